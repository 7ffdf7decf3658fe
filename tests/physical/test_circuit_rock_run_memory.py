"""A run of the drifter with its oil circuit on the rock without histories
(``CircuitDrifter.simulate(histories=False)``, what the settle task and the optimiser's failed designs
run for up to 16 s): each blow keeps a bounded summary, not the circuit's pieces over it, and every
figure of the run is the one with histories (theory §11, "The coupled blow")."""

from pathlib import Path

import numpy as np
import pytest

from impactbar.physical import CircuitDrifter, build, read_config, with_values
from impactbar.physical.circuit import PRESSURE_SCALE, _least_pressures
from impactbar.simulation.blows import BlowPiece

EXAMPLE = Path(__file__).parents[2] / "examples" / "circuit_drifter_rock.toml"
#: the run: its first blows from rest (some 30 a second at first)
SPAN_S = 0.2
#: what a blow of a run without histories may hold (bytes of arrays): its law's record (the blow's
#: forces and waves at its steps, some 6 kB on the example's grid of 8 cells a piston), not the
#: circuit's pieces over it (about 1.5 MB a blow)
BLOW_BYTES = 32_000


def _array_bytes(obj, seen=None) -> int:
    """The bytes of the distinct numpy arrays reachable from ``obj`` (through lists, tuples, dicts,
    ``__dict__`` and ``__slots__``), each array's memory counted once (views by their base)."""
    seen = set() if seen is None else seen
    stack, total = [obj], 0
    while stack:
        o = stack.pop()
        if isinstance(o, np.ndarray):
            while isinstance(o.base, np.ndarray):
                o = o.base
            if id(o) not in seen:
                seen.add(id(o))
                total += o.nbytes
            continue
        if id(o) in seen or isinstance(o, (int, float, str, bytes, bool, type(None), type)):
            continue
        seen.add(id(o))
        if isinstance(o, dict):
            stack.extend(o.values())
        elif isinstance(o, (list, tuple, set, frozenset)):
            stack.extend(o)
        else:
            stack.extend(getattr(o, "__dict__", {}).values())
            for cls in type(o).__mro__:
                slots = getattr(cls, "__slots__", ())
                for name in (slots,) if isinstance(slots, str) else slots:
                    if hasattr(o, name):
                        stack.append(getattr(o, name))
    return total


#: the example's rock, and a softer one on which the piston strikes the shank again after each blow:
#: a chatter impact of some 0.9 m/s after a blow of some 7 m/s where the blow ended at the law's
#: window; ended where the piston is free for good (the default) that touch is inside the blow,
#: which lasts longer than the window (theory §11, "The coupled blow")
ROCKS = {"example": {}, "soft": {"rock.k": "100 kN/mm", "rock.k_u": "1000 kN/mm"}}


@pytest.fixture(scope="module", params=list(ROCKS))
def runs(request):
    cfg, folder = read_config(EXAMPLE)
    drifter = build(with_values(cfg, ROCKS[request.param]), folder)
    assert isinstance(drifter, CircuitDrifter) and drifter.drill is not None
    full, bare = drifter.simulate(SPAN_S, histories=True), drifter.simulate(SPAN_S, histories=False)
    v = bare["impact_velocities_m_s"]
    assert np.count_nonzero(v < 0.25 * v.max()) == 0  # (no chatter impact: every blow a blow)
    if request.param == "soft":  # (the re-contact in the blow, which ends past the window)
        model = drifter.model()
        assert all(b.ended_by == "separated" and b.duration > model.law.window(model)
                   for b in bare["run"].impacts)
    return drifter, full, bare


def _blows(run):
    return [p for p in run["run"].pieces if isinstance(p, BlowPiece)]


def test_a_run_without_histories_keeps_a_bounded_summary_of_each_blow(runs):
    """Each blow of the run without histories (on the soft rock each with its re-contact) holds at
    most ``BLOW_BYTES`` of arrays, the blows together no more than the sum; with histories the same
    blows hold the circuit's pieces, over 20 times more (what a 16 s run of a chattering design
    kept, past 6.5 GB)."""
    _, full, bare = runs
    blows, kept = _blows(bare), _blows(full)
    assert len(blows) == len(kept) == bare["impact_times_s"].size >= 4
    sizes = [_array_bytes(b) for b in blows]
    assert max(sizes) <= BLOW_BYTES, sizes
    assert all(type(b).__name__ == "BlowSummary" and b.drive_pieces == () for b in blows)
    # the blows together: no more than the sum of each (nothing that grows with the run behind them)
    assert _array_bytes(blows) <= sum(sizes)
    assert _array_bytes(kept) > 20 * _array_bytes(blows)


def test_a_run_without_histories_gives_the_same_figures(runs):
    """The impacts, the work on the rock and the penetration of each blow, the circuit's least
    pressures (its pieces' extremes), its energy account and the bar's: those of the run with
    histories, to the bit."""
    drifter, full, bare = runs
    for key in ("impact_times_s", "impact_velocities_m_s", "work_on_rock_J", "penetration_mm"):
        np.testing.assert_array_equal(bare[key], full[key])
    assert _least_pressures(bare["run"].pieces) == _least_pressures(full["run"].pieces)
    # (the flights' taken together: the least of each piece's own)
    pieces = [p for p in full["run"].pieces if hasattr(p, "extremes")]
    assert _least_pressures(full["run"].pieces) == {
        n: min(p.extremes(n)[0] for p in pieces) * PRESSURE_SCALE for n in ("front", "rear", "supply")}
    drive = bare["run"].load
    assert drive.energy(bare["run"]) == drive.energy(full["run"])
    a, b = bare["run"].energy, full["run"].energy
    assert (a.work, a.impact_loss, a.damping_loss, a.final) == \
        (b.work, b.impact_loss, b.damping_loss, b.final)
    for s, p in zip(_blows(bare), _blows(full), strict=True):
        assert (s.t0, s.t_end) == (p.t0, p.t_end) and s.piston_work() == p.piston_work()
        for name in ("front", "rear", "supply", 0, 3):  # (3: the valve's x_v)
            np.testing.assert_array_equal(s.extremes(name), p.extremes(name))


def test_the_histories_inside_a_summarised_blow_are_refused(runs):
    """Inside a blow of the run without histories the circuit's state is refused in one line (the
    run with histories has it)."""
    _, full, bare = runs
    (s, p) = (_blows(bare)[0], _blows(full)[0])
    t = 0.5 * (s.t0 + s.t_end)
    assert np.all(np.isfinite(full["run"].drive_state([t])))
    assert p.drive_state([t]).shape[1] == 1
    with pytest.raises(ValueError, match="histories=False"):
        bare["run"].drive_state([t])
    with pytest.raises(ValueError, match="histories=False"):
        s.force([t])


def test_histories_must_be_a_bool():
    from impactbar import BarModel, CosineLoad, InitialState, simulate

    model = BarModel(s=10.0, d=0.05, R=0.5, n_modes=2)
    with pytest.raises(ValueError, match="histories must be True or False"):
        simulate(model, CosineLoad(0.3, 1.0), InitialState.rigid(-0.01, 0.0, n_modes=2), 1.0, histories="no")
