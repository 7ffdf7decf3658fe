"""The one-line note on stderr while numba compiles impactbar's kernels:
``impactbar._shared.compiling``. The command line prints it under the subcommand's name
(``compile_note``), the Python API through the process-wide watch the kernels' module starts
(``watch_compiles``); one line per process, only while kernels compile, never breaking a tqdm
progress bar. The process-wide watch is checked in fresh processes with an empty numba cache."""

import io
import os
import subprocess
import sys

import numba
import pytest

from impactbar._shared import compiling
from impactbar._shared.compiling import NOTE, compile_note


@pytest.fixture
def fresh(monkeypatch):
    """This process as if it had printed no note yet, and the test's own kernels counted as
    impactbar's (the watch ignores a user's numba code)."""
    monkeypatch.setattr(compiling._PROCESS, "said", False)
    monkeypatch.setattr(compiling, "_ours", lambda ev: True)


def _fresh_kernel():
    @numba.njit(cache=False)
    def f(x):
        s = 0.0
        for i in range(x.size):
            s += x[i] * x[i]
        return s

    return f


def test_a_long_compile_prints_one_line_once(fresh):
    import numpy as np

    out = io.StringIO()
    with compile_note("impactbar test", after=1e-4, stream=out):
        _fresh_kernel()(np.ones(3))  # a compile of far more than 0.1 ms
        _fresh_kernel()(np.ones(3))  # another: no second line
    lines = out.getvalue().splitlines()
    assert lines == [f"impactbar test: {NOTE}"]
    assert "first run with this cache" in NOTE and "this machine" not in NOTE


def test_no_compile_or_a_short_one_prints_nothing(fresh):
    import numpy as np

    f = _fresh_kernel()
    f(np.ones(3))  # compiled before the block
    out = io.StringIO()
    with compile_note(after=60.0, stream=out):
        f(np.ones(4))  # no compile
        _fresh_kernel()(np.ones(3))  # a compile far shorter than a minute
    assert out.getvalue() == ""
    # and the listener is gone after the block: a compile there prints nothing either
    _fresh_kernel()(np.ones(3))
    assert out.getvalue() == ""


def test_a_user_s_own_numba_code_prints_nothing(monkeypatch):
    import numpy as np

    monkeypatch.setattr(compiling._PROCESS, "said", False)
    out = io.StringIO()
    with compile_note(after=1e-4, stream=out):
        _fresh_kernel()(np.ones(3))  # this module's kernel, not impactbar's
    assert out.getvalue() == ""


def test_the_note_does_not_break_a_progress_bar(fresh):
    import numpy as np
    from tqdm import tqdm

    out = io.StringIO()
    with compile_note("impactbar test", after=1e-4, stream=out), \
            tqdm(total=5, file=out, ascii=True, mininterval=0) as bar:
        bar.update(1)
        _fresh_kernel()(np.ones(3))
        bar.update(1)
    # the bar is cleared before the note (tqdm.write): the note stands alone on its line, where a
    # plain print would have run on after the bar's "1/5"
    rows = [row.split("\r")[-1] for row in out.getvalue().split("\n")]
    assert f"impactbar test: {NOTE}" in rows


def test_after_must_be_positive():
    with pytest.raises(ValueError, match="after"), compile_note(after=0.0):
        pass
    with pytest.raises(ValueError, match="after"):
        compiling.watch_compiles(after=-1.0)


def test_the_kernels_start_the_process_wide_watch():
    import impactbar.dynamics._event_loop  # noqa: F401  (any kernel module; imported by every solver)

    assert compiling._PROCESS.watching


#: a first call in a fresh process: the watch started with a short threshold before the kernels'
#: module does (its own call is then a no-op), then a small kernel of impactbar compiled
_SCRIPT = """
from impactbar._shared.compiling import watch_compiles
watch_compiles(after=0.02)
from impactbar.dynamics._flight import _bc
import numba
numba.njit(lambda x: x + 1)(1.0)   # a user's own kernel: no note for it
_bc(0.1, 1.0)
_bc(0.2, 2.0)
print("done")
"""


def test_the_python_api_notes_a_compile_once_and_only_when_it_compiles(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    first = subprocess.run([sys.executable, "-c", _SCRIPT], env=env, capture_output=True, text=True,
                           check=True)
    assert first.stdout.strip() == "done"
    assert first.stderr.splitlines() == [f"impactbar: {NOTE}"]
    # the same cache: nothing compiles, nothing is said
    again = subprocess.run([sys.executable, "-c", _SCRIPT], env=env, capture_output=True, text=True,
                           check=True)
    assert again.stderr == ""


@pytest.mark.slow
def test_a_first_call_in_python_prints_the_note_before_a_long_compile(tmp_path):
    """A first rigid ``simulate`` with an empty cache, the watch as the package starts it: its event
    loop compiles for some seconds, well past the note's 2 s (the README's first example, whose
    admissibility search starts as its interpreted twin, now compiles for about 2 s, too near them
    to say whether the note comes)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    script = ("from impactbar import BarModel, CosineLoad, InitialState, simulate\n"
              "simulate(BarModel(s=5.0, d=0.1, R=0.5, n_modes=0), CosineLoad(0.6, 1.0),\n"
              "         InitialState.rigid(-0.1, 0.0), 20.0)\n")
    first = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True,
                           check=True)
    assert first.stderr.splitlines() == [f"impactbar: {NOTE}"]
    again = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True,
                           check=True)
    assert again.stderr == ""


def test_the_garbage_collector_pauses_while_a_kernel_compiles(fresh):
    """Off while one of impactbar's kernels compiles (the collector's state seen from inside the
    compile, by the kernel's compile-time callee), on again after, and left off where the program
    had turned it off."""
    import gc

    from numba.core import event

    seen = []

    class Probe(event.Listener):
        def on_start(self, ev):
            seen.append(gc.isenabled())

        def on_end(self, ev):
            pass

    pause = type("Pause", (compiling._GcPause, event.Listener), {})()
    probe = Probe()
    event.register("numba:compile", pause)
    event.register("numba:compile", probe)  # (after the pause: sees its state)
    was = gc.isenabled()
    try:
        gc.enable()
        _fresh_kernel()(__import__("numpy").ones(3))
        assert seen == [False] and gc.isenabled()
        gc.disable()
        _fresh_kernel()(__import__("numpy").ones(3))
        assert seen == [False, False] and not gc.isenabled()
    finally:
        event.unregister("numba:compile", probe)
        event.unregister("numba:compile", pause)
        if was:
            gc.enable()

