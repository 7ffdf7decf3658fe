"""Long simulate runs: a progress callback with the fraction done, and Ctrl-C that
keeps what the run computed (SimulationInterrupted carries the trajectory up to its last finished
block of impacts, identical to a run that ends there)."""

import importlib
import math
import os
import signal
import threading
import time

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, InitialState, simulate
from impactbar.simulation import SimulationInterrupted

MODEL = BarModel(10.0, 0.05, 0.6, 4)
LOAD = CosineLoad(0.6, 1.0)
START = InitialState.rigid(-0.1, 0.0, 4)


def test_progress_reports_fractions_up_to_one(monkeypatch):
    mod = importlib.import_module("impactbar.simulation.simulate")  # (the package's name is the function)
    monkeypatch.setattr(mod, "PROGRESS_EVERY", 0.0)
    seen = []
    tr = simulate(MODEL, LOAD, START, 2 * math.pi * 50, progress=seen.append)
    assert len(seen) >= 2 and seen[-1] == 1.0
    assert all(0.0 <= a <= b <= 1.0 for a, b in zip(seen, seen[1:], strict=False))
    ref = simulate(MODEL, LOAD, START, 2 * math.pi * 50)  # the callback changes nothing
    np.testing.assert_array_equal(tr.impact_times, ref.impact_times)
    with pytest.raises(ValueError, match="progress must be a callable"):
        simulate(MODEL, LOAD, START, 10.0, progress=5)


@pytest.mark.skipif(not hasattr(signal, "SIGINT") or os.name == "nt", reason="POSIX signals")
def test_ctrl_c_keeps_the_finished_part():
    simulate(MODEL, LOAD, START, 10.0)  # compiled before the clock starts
    before = signal.getsignal(signal.SIGINT)

    def press():  # Ctrl-C once the run's handler is in place, and a little later
        deadline = time.monotonic() + 60.0
        while signal.getsignal(signal.SIGINT) is before:
            if time.monotonic() > deadline:
                return
            time.sleep(0.01)
        time.sleep(0.2)
        os.kill(os.getpid(), signal.SIGINT)

    presser = threading.Thread(target=press)
    presser.start()
    try:
        with pytest.raises(SimulationInterrupted) as info:
            simulate(MODEL, LOAD, START, 2 * math.pi * 1e6)  # some seconds at least
    finally:
        presser.join()
    assert isinstance(info.value, KeyboardInterrupt)
    tr = info.value.trajectory
    assert tr.status == "t_end" and 0.0 < tr.t_end < 2 * math.pi * 1e6
    assert tr.impact_times.size > 0 and tr.impact_times[-1] <= tr.t_end
    # the same run, ended at the same impact (or time, when the block ended without one)
    if tr.t_end == tr.impact_times[-1]:
        ref = simulate(MODEL, LOAD, START, 2 * math.pi * 1e6, max_impacts=tr.impact_times.size)
    else:
        ref = simulate(MODEL, LOAD, START, tr.t_end)
    assert ref.t_end == tr.t_end
    np.testing.assert_allclose(tr.impact_times, ref.impact_times, rtol=0, atol=1e-9)
    np.testing.assert_allclose(tr.final_state.modal_velocity, ref.final_state.modal_velocity,
                               atol=1e-9)
    # the handler is gone: a later Ctrl-C is an ordinary KeyboardInterrupt again
    assert signal.getsignal(signal.SIGINT) is before


def test_a_run_of_few_impacts_sets_no_ctrl_c_handler(monkeypatch):
    """A run that asks for at most 256 impacts takes no Ctrl-C handler however long its span (the
    handler's two system calls were a tenth of a 1-impact run's cost); one that asks for more does."""
    mod = importlib.import_module("impactbar.simulation.simulate")
    entered = []

    class Spy(mod._CtrlC):
        def __enter__(self):
            entered.append(True)
            return super().__enter__()

    monkeypatch.setattr(mod, "_CtrlC", Spy)
    span = 2.0 * mod.LONG_RUN
    assert simulate(MODEL, LOAD, START, span, max_impacts=mod.SHORT_RUN_IMPACTS).n_impacts == 256
    assert entered == []
    assert simulate(MODEL, LOAD, START, span, max_impacts=mod.SHORT_RUN_IMPACTS + 1).n_impacts == 257
    assert entered == [True]
