"""One-line errors from every subcommand, checked before any computing: output
locations that cannot be written, sizes too large to draw, missing extras, Ctrl-C, a closed or full
stdout, unhashable values in a sweep spec. Exit status 2 for bad input, 1 for a failed write or a
missing extra, 141 for a closed pipe, 130 for Ctrl-C."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import impactbar.paper
import impactbar.simulation.experiments
from impactbar.cli import main
from impactbar.cli._common import MAX_DPI, UsageError, check_dpi, output_file, output_folder

ROOT = Path(__file__).resolve().parents[2]
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "MPLBACKEND": "Agg"}


def _never(*args, **kwargs):
    raise AssertionError("computed before the inputs were checked")


@pytest.fixture
def no_computing(monkeypatch):
    """Any of the subcommands' computations fails the test: the error must come before them."""
    monkeypatch.setattr(impactbar.paper, "reproduce", _never)
    monkeypatch.setattr(impactbar.simulation.experiments, "run_experiment", _never)
    monkeypatch.setattr("impactbar.physical.simulate", _never)
    monkeypatch.setattr("impactbar.continuation.doubling_cascade", _never)
    monkeypatch.setattr("impactbar.sweeps.plot.plot_sweep", _never)


def _one_line_error(capsys, command):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith(f"impactbar {command}: error: ")
    return err[0]


@pytest.fixture
def a_file(tmp_path):
    path = tmp_path / "a_file.txt"
    path.write_text("not a folder")
    return path


def _bad_outs(tmp_path, a_file):
    """Output locations that cannot be written: a virtual file system, under a file, a file."""
    bad = [str(a_file / "sub"), str(a_file)]
    if Path("/proc").is_dir():
        bad.append("/proc/forbidden")
    return bad


@pytest.mark.parametrize("command", [
    ["paper", "--quick"],
    ["simulate", "--preset", "pneumatic-drill"],
    ["continue", "--parameter", "p0", "--to", "0.8"],
    ["experiment", "pneumatic", "--starts", "2"],
])
def test_an_output_folder_that_cannot_be_written_is_one_line_before_computing(
        command, tmp_path, a_file, no_computing, capsys):
    for out in _bad_outs(tmp_path, a_file):
        assert main([*command, "--out", out]) == 2
        line = _one_line_error(capsys, command[0])
        assert f"--out {out}: " in line and ("cannot write there" in line or "is not a folder" in line)


def test_plot_refuses_an_output_file_it_cannot_write(tmp_path, a_file, no_computing, capsys):
    store = str(tmp_path / "missing.zarr")
    cases = [str(a_file / "fig.png"), str(tmp_path)]  # under a file; a folder
    if Path("/proc").is_dir():
        cases.append("/proc/forbidden/fig.png")
    for out in cases:
        assert main(["plot", store, "--out", out]) == 2
        assert f"--out {out}: " in _one_line_error(capsys, "plot")


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0,
                    reason="permissions do not stop the superuser")
def test_a_read_only_folder_is_refused(tmp_path, no_computing, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        assert main(["plot", "x.zarr", "--out", str(ro / "fig.png")]) == 2
        assert "cannot write there" in _one_line_error(capsys, "plot")
        assert main(["paper", "--out", str(ro / "figs")]) == 2
        _one_line_error(capsys, "paper")
    finally:
        ro.chmod(0o755)


def test_output_locations_are_created_when_missing(tmp_path):
    assert output_folder(tmp_path / "a" / "b").is_dir()
    assert output_file(tmp_path / "c" / "fig.png").parent.is_dir()
    with pytest.raises(UsageError, match="is a folder"):
        output_file(tmp_path)


@pytest.mark.parametrize("command", [["plot", "x.zarr", "--out", "fig.png"], ["paper", "--quick"]])
@pytest.mark.parametrize("dpi", [0, -5, MAX_DPI + 1, 100000])
def test_a_dpi_too_large_to_draw_is_refused_up_front(command, dpi, tmp_path, no_computing, capsys,
                                                    monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main([*command, "--dpi", str(dpi)]) == 2
    assert f"--dpi must be in [1, {MAX_DPI}]" in _one_line_error(capsys, command[0])
    assert check_dpi(MAX_DPI) == MAX_DPI and check_dpi(1) == 1


def test_the_library_reproduce_refuses_bad_dpi_and_format(tmp_path):
    from impactbar.paper import reproduce

    with pytest.raises(ValueError, match=r"dpi must be in \[1, 1200\]"):
        reproduce(tmp_path, quick=True, dpi=100000)
    with pytest.raises(ValueError, match="format must be one of"):
        reproduce(tmp_path, quick=True, format="jpg")
    assert not any(tmp_path.iterdir())


def test_experiment_without_matplotlib_fails_before_computing(monkeypatch, tmp_path, no_computing,
                                                              capsys):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # find_spec then reports it missing
    assert main(["experiment", "pneumatic", "--out", str(tmp_path / "x")]) == 1
    line = _one_line_error(capsys, "experiment")
    assert "pip install 'impactbar[plot]'" in line


def test_ctrl_c_is_one_line_and_exit_130(monkeypatch, tmp_path, capsys):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(impactbar.paper, "reproduce", interrupted)
    assert main(["paper", "--quick", "--out", str(tmp_path / "figs")]) == 130
    assert capsys.readouterr().err.strip() == "impactbar paper: interrupted"


def test_ctrl_c_inside_a_c_callback_is_not_reported(monkeypatch):
    """A Ctrl-C that lands in a ctypes callback (numba compiling through llvmlite on a first run)
    cannot propagate and CPython reports it to ``sys.unraisablehook`` ("Exception ignored ...");
    after a Ctrl-C the command drops that report, and passes every other one on as before; and
    after a Ctrl-C, to the process's end, the failure of a ``__del__`` (an object the interrupt left
    half built: pyparsing's ``Forward`` when matplotlib's import is cut short)."""
    import ctypes

    from impactbar import cli

    reported = []
    monkeypatch.setattr(sys, "unraisablehook", lambda u: reported.append(type(u.exc_value).__name__))
    callback_type = ctypes.CFUNCTYPE(None)

    def interrupt():
        raise KeyboardInterrupt

    def fail():
        raise RuntimeError("a real error in a callback")

    interrupting, failing = callback_type(interrupt), callback_type(fail)

    class HalfBuilt:  # (an object whose construction a Ctrl-C cut short, collected later)
        def __del__(self):
            raise AttributeError("expr")

    # (Python's own SIGINT handler, as in a terminal: a test run started in the background of a
    # non-interactive shell ignores SIGINT, and the command then leaves Ctrl-C alone)
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with cli._CtrlC() as ctrl_c:
            assert ctrl_c._hook is not None  # installed (pytest's main thread, Python's SIGINT handler)
            interrupting()  # before any Ctrl-C: reported
            HalfBuilt()  # (as is a __del__'s failure)
            ctrl_c.pressed = True  # as the handler sets it
            interrupting()  # dropped
            HalfBuilt()  # dropped
            failing()
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # restored
    finally:
        signal.signal(signal.SIGINT, before)
    interrupting()  # outside a command: reported
    HalfBuilt()  # after the Ctrl-C, to the process's end: dropped
    assert reported == ["KeyboardInterrupt", "AttributeError", "RuntimeError", "KeyboardInterrupt"]


def test_ctrl_c_during_paper_in_a_real_process(tmp_path):
    out = tmp_path / "figs"
    # (the child's SIGINT at its default: a test run started in the background of a non-interactive
    # shell ignores SIGINT, the child inherits that, and Python then never raises KeyboardInterrupt)
    proc = subprocess.Popen([sys.executable, "-m", "impactbar", "paper", "--out", str(out)], env=ENV,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 120
    while not out.exists() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)  # the folder is made by the check before the computing starts
    time.sleep(2.0)  # (past the imports: in the computing, or in numba's compiling on a first run)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=120)
    # Under ``python -m`` an interrupt that lands early (while the paper's first worker threads start)
    # can make CPython end the process by SIGINT itself after our handler ran: the shell then shows 130
    # (128 + 2) as well. The message is the same, once, and no traceback.
    assert proc.returncode in (130, -signal.SIGINT), stderr
    assert stderr.strip() == "impactbar paper: interrupted"


def test_a_closed_stdout_ends_quietly_with_141():
    proc = subprocess.run([sys.executable, "-c", "import os, sys; os.close(1); sys.stdout = None;"
                           "from impactbar.cli import main; sys.exit(main(['orbits', '--n-modes', '0']))"],
                          env=ENV, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 141, proc.stderr
    assert proc.stderr == ""


def test_a_closed_stdout_from_the_shell(tmp_path):
    proc = subprocess.run(f"'{sys.executable}' -m impactbar orbits --n-modes 0 >&-", shell=True,
                          env=ENV, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 141, proc.stderr
    assert proc.stderr == ""


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_a_full_disk_on_stdout_is_one_line_and_exit_1():
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "impactbar", "orbits", "--n-modes", "0"], env=ENV,
                              stdout=full, stderr=subprocess.PIPE, text=True, timeout=300)
    assert proc.returncode == 1
    lines = proc.stderr.strip().splitlines()
    assert lines == ["impactbar orbits: error: No space left on device"]


@pytest.mark.parametrize("kind", ['["cosine"]', '{ a = 1 }'])
def test_a_sweep_spec_with_an_unhashable_load_kind_is_one_line(kind, tmp_path, capsys):
    spec = (ROOT / "examples" / "sweep_orbits.toml").read_text()
    assert 'kind = "cosine"' in spec
    path = tmp_path / "spec.toml"
    path.write_text(spec.replace('kind = "cosine"', f"kind = {kind}"))
    assert main(["sweep", str(path), "--out", str(tmp_path / "out.zarr")]) == 2
    assert "[load] kind must be one of" in _one_line_error(capsys, "sweep")


def test_sweep_refuses_a_store_it_cannot_write_before_any_cluster(tmp_path, a_file, monkeypatch, capsys):
    monkeypatch.setattr("impactbar.sweeps.run_sweep", _never)
    spec = str(ROOT / "examples" / "sweep_orbits.toml")
    for out in [str(a_file), str(a_file / "out.zarr")]:
        assert main(["sweep", spec, "--out", out]) == 2
        assert f"--out {out}: " in _one_line_error(capsys, "sweep")


def test_paper_writes_the_format_and_dpi_asked(tmp_path, monkeypatch, capsys):
    seen = {}

    def fake(out, **kwargs):
        seen.update(kwargs)
        return [("4", "x", "1")]

    monkeypatch.setattr(impactbar.paper, "reproduce", fake)
    assert main(["paper", "--quick", "--out", str(tmp_path), "--dpi", "300", "--format", "svg"]) == 0
    assert seen["dpi"] == 300 and seen["format"] == "svg"
    assert "(.svg, .csv)" in capsys.readouterr().out


def test_simulate_drives_a_progress_bar_on_a_terminal_only(monkeypatch, capsys, tmp_path):
    """``impactbar simulate`` hands the library a progress callback (a bar on stderr with an
    estimate) only on a terminal and without --quiet."""
    seen = {}

    def fake(hammer, *, periods, gap_m, progress=None):
        seen["periods"], seen["progress"] = periods, progress
        if progress is not None:
            progress(0.5)
            progress(1.0)
        raise RuntimeError("stopped by the test")

    monkeypatch.setattr("impactbar.physical.simulate", fake)
    for tty, extra, given in ((False, [], False), (True, ["--quiet"], False), (True, [], True)):
        monkeypatch.setattr(sys.stderr, "isatty", lambda tty=tty: tty, raising=False)
        assert main(["simulate", "--preset", "pneumatic-drill", "--out", str(tmp_path / "o"),
                     "--periods", "1e6", *extra]) == 1
        assert seen["periods"] == 1e6 and (seen["progress"] is not None) == given
        assert capsys.readouterr().err.strip().splitlines()[-1].endswith("stopped by the test")


@pytest.mark.parametrize("command", [["simulate", "--preset", "pneumatic-drill", "--quiet"],
                                     ["paper", "--quiet"]])
def test_an_empty_out_is_refused(command, tmp_path, monkeypatch, capsys, no_computing):
    """``--out ''`` wrote the outputs into the working directory (found by the fuzz campaign)."""
    monkeypatch.chdir(tmp_path)
    assert main([*command, "--out", ""]) == 2
    assert "--out: an empty path" in _one_line_error(capsys, command[0])
    assert not any(tmp_path.iterdir())


def test_an_interrupt_wrapped_by_an_import_is_still_an_interrupt(monkeypatch, capsys):
    """Python 3.11 wraps an exception raised inside ``__set_name__`` (Ctrl-C while matplotlib
    imports, say) in a RuntimeError; the command still ends with one line and 130. Any other
    RuntimeError is not caught."""
    import impactbar.cli.paper as paper_cli

    def interrupted(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise RuntimeError("Error calling __set_name__ on '_deprecate_privatize_attribute'") from exc

    monkeypatch.setattr(paper_cli, "run", interrupted)
    assert main(["paper", "--quiet"]) == 130
    assert capsys.readouterr().err.strip() == "impactbar paper: interrupted"

    def broken(args):
        raise RuntimeError("a bug")

    monkeypatch.setattr(paper_cli, "run", broken)
    with pytest.raises(RuntimeError, match="a bug"):
        main(["paper", "--quiet"])
