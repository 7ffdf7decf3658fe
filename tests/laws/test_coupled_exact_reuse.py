"""What makes the coupled exact blow cheap changes none of its numbers: a map's blow started on the
pool its last blow filled is the blow started on the default pool (grown by runs again), to the
bit; a blow gone on from the snapshot of one whose drive was the same up to there is the blow from
its start, to the bit; the force's cubics are scipy's Hermite spline's, to the bit; the arriving
wave's scalar callable is scipy's cubic spline, to the bit; the marching iteration's blow is the
plain fixed-point iteration's, within the iteration's tolerance; a record's histories sampled when first
read are those sampled at once, to the bit."""

import dataclasses

import numpy as np
import pytest
import test_coupled_exact_blow as blow_tests
from scipy.interpolate import CubicSpline

from impactbar.drives.circuit import CircuitFlightSettings
from impactbar.laws.rodrock.coupled_exact import _Force, _spline_callable
from impactbar.laws.rodrock.exactmap import ExactBlowMap
from impactbar.loads import FourierLoad
from impactbar.physical import build, read_config

arrival = blow_tests.arrival  # (the fixture: the drifter's second arrival, on a rod of whole piston lengths)


@pytest.fixture(scope="module")
def driven_map():
    """The drifter's exact map under a drive of 600 cubic pieces (a circuit's force, as the coupled
    blow's iterates give it), and an arrival ``(q, v)``."""
    cfg, _ = read_config("examples/circuit_drifter_rock.toml")
    del cfg["rock"]["cells_per_piston"]
    cfg["rock"].pop("contact_events", None)  # (the lattice's plain events: the arrival as measured)
    model = build(cfg).model()
    model = model.with_(impact=dataclasses.replace(model.law, method="exact"))
    p0 = 0.3
    bmap = ExactBlowMap(model, FourierLoad(p0, []), 0.0)
    T0, D = float(bmap.basis.travel[0]), bmap.duration
    force = _Force(p0)
    force.starts = np.linspace(0.0, D, 601)[:-1]
    x = force.starts / D
    slope = 0.2 * np.cos(7.0 * x)
    force.coefs = np.column_stack((0.01 * np.sin(x), -0.05 * x, slope, p0 * (1.0 + 0.3 * np.sin(7.0 * x))))
    bmap.drive = force.pieces(T0, D)
    q = np.zeros(model.n_modes + 1)
    v = np.zeros(model.n_modes + 1)
    v[0] = 0.8
    return bmap, q, v


def _numbers(ex):
    return (ex.work_on_rock, ex.duration, ex.pieces, ex.diagnostics["terms"], ex.shank_displacement, ex.gap,
            ex.drive_work, ex.piston_energy, ex.permanent_penetration, ex.loadings.tobytes())


def test_a_blow_on_the_last_blows_pool_is_the_blow_on_a_grown_one(driven_map):
    bmap, q, v = driven_map
    bmap._pool = None
    first = bmap.solve(q, v, record=True)
    assert first.pieces > 256  # (the default pool's: the first blow grew it, running again)
    kept = bmap._pool
    hint = bmap._pool_for(bmap.duration)
    assert hint[0] > first.pieces and hint[1] > first.diagnostics["terms"]
    again = bmap.solve(q, v, record=True)
    assert _numbers(again) == _numbers(first)
    assert np.array_equal(np.concatenate(bmap.state_after(again)), np.concatenate(bmap.state_after(first)))
    t = np.linspace(0.0, first.duration, 97)
    assert np.array_equal(again.shank_force(t), first.shank_force(t))
    # the lean blow (the impact map's) on the same pool
    bmap._pool = None
    ws_default, _ = bmap.solve(q, v, lean=True)
    bmap._pool = kept
    ws_hinted, _ = bmap.solve(q, v, lean=True)
    for a, b in zip(ws_default, ws_hinted, strict=True):
        if isinstance(a, np.ndarray) and a.ndim <= 1 and a.size < 64:  # the counts and the state
            assert np.array_equal(a, b, equal_nan=True)


def _same_blow(a, b, bmap):
    """The two blows' numbers and histories, to the bit (but the pool's counts: a blow gone on from a
    snapshot keeps the drive's pieces it no longer reads)."""
    assert _numbers(a)[:2] == _numbers(b)[:2] and _numbers(a)[4:] == _numbers(b)[4:]
    assert a.ended_by == b.ended_by and a.energy_error == b.energy_error
    assert np.array_equal(np.concatenate(bmap.state_after(a)), np.concatenate(bmap.state_after(b)))
    t = np.linspace(0.0, a.duration, 197)
    for j in range(1, a._hist[2]):  # (the interfaces)
        assert np.array_equal(a.junction_force(j, t), b.junction_force(j, t))
    assert np.array_equal(a.shank_force(t), b.shank_force(t))


@pytest.mark.parametrize("part", [0.5, 0.02])
def test_a_blow_gone_on_from_a_snapshot_is_the_blow_from_its_start(driven_map, monkeypatch, part):
    """The force held from half the blow, then the whole force: the second blow goes on from the
    first one's last snapshot before half the blow. A force changed near the start: no snapshot
    shares it, and the blow is solved from its start."""
    import impactbar.laws.rodrock.exact as E

    bmap, q, v = driven_map
    T0, D = float(bmap.basis.travel[0]), bmap.duration
    full = bmap.drive
    force = _Force(0.3)
    force.starts, force.coefs = np.array(full[0][1:-1]), np.array([c[::-1].real for _, _, c in full[1][1:-1]])
    if part < 0.1:  # (a force parting from the first one's before its first snapshot)
        force.coefs = force.coefs.copy()
        force.coefs[3, 3] *= 1.0 + 1e-12
    resumed = []
    real = E._resumed
    monkeypatch.setattr(E, "_resumed", lambda *a, **k: resumed.append(real(*a, **k)) or resumed[-1])
    keep = {"stops": T0 * np.arange(1, 9)}
    held = _Force(0.3)
    held.starts, held.coefs = np.array(full[0][1:-1]), np.array([c[::-1].real for _, _, c in full[1][1:-1]])
    bmap.drive = held.pieces(T0, 0.5 * D)
    bmap.solve(q, v, record=True, keep=keep)
    assert len(keep["snapshots"]) >= 2
    bmap.drive = force.pieces(T0, D)
    keep = {"resume": keep["snapshots"]}
    on = bmap.solve(q, v, record=True, keep=keep)
    assert (resumed[-1] is not None) == (part > 0.1)
    fresh = bmap.solve(q, v, record=True)
    _same_blow(on, fresh, bmap)
    bmap.drive = full


def test_the_forces_cubics_are_scipys_hermite_spline_to_the_bit():
    from scipy.interpolate import CubicHermiteSpline

    from impactbar.laws.rodrock.coupled_exact import _hermite

    rng = np.random.default_rng(5)
    t = np.sort(rng.uniform(0.0, 2.0, 40))
    piece = type("Steps", (), {"t": t, "y": rng.normal(size=(40, 4)), "f": rng.normal(size=(40, 4))})()
    c = CubicHermiteSpline(piece.t, piece.y, piece.f, axis=0).c
    for j in range(4):
        assert np.array_equal(_hermite(piece, j), c[:, :, j].T)


def test_the_scalar_spline_is_scipys_to_the_bit():
    rng = np.random.default_rng(3)
    x = np.sort(rng.uniform(0.2, 3.0, 30))
    spline = CubicSpline(x, np.sin(4.0 * x) + rng.normal(size=30))
    t0 = 1.7
    a = _spline_callable(spline, t0)
    ts = t0 + np.concatenate((rng.uniform(-0.5, 3.5, 500), x))  # (outside: the end pieces extended)
    assert [a(float(t)) for t in ts] == [float(spline(t - t0)) for t in ts]


def test_the_compiled_flights_are_scikit_sundaes_to_the_bit(arrival, monkeypatch):
    """The circuit under the arriving wave's splines flown by the compiled CVODE loop (the splines in
    its callbacks' data) takes scikit-sundae's Python interface's steps: the same blow to the bit."""
    import impactbar.drives.circuit.endflight as EF
    from impactbar.laws.rodrock.coupled_exact import driven_exact_contact

    if EF._compiled_end(CircuitFlightSettings()) is None:
        pytest.skip("no compiled CVODE here")
    flights = []
    real = EF._compiled_stretches
    monkeypatch.setattr(EF, "_compiled_stretches", lambda *a: flights.append(len(a)) or real(*a))
    fast = driven_exact_contact(*arrival)
    assert flights and min(flights) == 10  # (every flight compiled, with its splines)
    compiled = len(flights)
    monkeypatch.setattr(EF, "_compiled_end", lambda settings: None)
    python = driven_exact_contact(*arrival)
    assert len(flights) == compiled  # (scikit-sundae's: none compiled)
    assert fast.t_release == python.t_release and fast.drive_state.mode == python.drive_state.mode
    for a, b in ((fast.v_after, python.v_after), (fast.q_after, python.q_after),
                 (fast.drive_state.z, python.drive_state.z), (fast.gaps, python.gaps)):
        assert np.array_equal(np.asarray(a), np.asarray(b))
    assert fast.record.work_on_rock == python.record.work_on_rock and fast.drive_work == python.drive_work
    for x, y in zip(fast.pieces, python.pieces, strict=True):
        assert np.array_equal(x.t, y.t) and np.array_equal(x.y, y.y) and np.array_equal(x.f, y.f)


def test_marching_gives_the_plain_iterations_blow(arrival):
    """The iterates over the part of the blow each can be right on, the first over the whole of it
    the answer, give the blow of the plain iteration (every iterate over the whole blow until the
    force settles, the blow solved once more with the last force): within the iteration's tolerance
    (the flights' noise, which the answer's force carries, 1.4e-9 of its size)."""
    from impactbar.laws.rodrock.coupled_exact import FORCE_TOL, driven_exact_contact

    fast = driven_exact_contact(*arrival)
    plain = driven_exact_contact(*arrival, march=False)
    assert fast.t_release == plain.t_release
    for a, b in ((fast.v_after, plain.v_after), (fast.q_after, plain.q_after),
                 (fast.drive_state.z, plain.drive_state.z),
                 ([fast.record.work_on_rock, fast.drive_work],
                  [plain.record.work_on_rock, plain.drive_work])):
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        assert np.all(np.abs(a - b) <= FORCE_TOL * np.maximum(np.abs(b), np.max(np.abs(b)) * 1e-3)), (a, b)
    assert fast.drive_state.mode == plain.drive_state.mode
    # the gap's history: its samples 1.5e-8 apart at most (measured; the same to the bit while the blow
    # ended at the law's window and the arriving wave's spline took its ends on the breaks: the two
    # iterations now restart the drive's integration at other breaks)
    assert np.allclose(fast.gaps, plain.gaps, rtol=1e-7, atol=0.0)


def test_the_iterates_take_their_predecessors_splines_where_a_is_the_same(arrival, monkeypatch):
    """The march's iterates take again the arriving wave's spline of an interval whose values are
    their predecessor's to the bit (an iterate's early waves are its predecessor's): fewer splines
    made (measured on this arrival: 14 of 71), the same blow to the bit as with every spline made
    afresh."""
    import impactbar.laws.rodrock.coupled_exact as CE

    made = []
    real = CE._spline_callable
    monkeypatch.setattr(CE, "_spline_callable", lambda *a: made.append(1) or real(*a))
    fast = CE.driven_exact_contact(*arrival)
    kept = len(made)
    made.clear()
    callables = CE._Incoming.callables
    monkeypatch.setattr(CE._Incoming, "callables", lambda self, breaks, memo=None: callables(self, breaks))
    fresh = CE.driven_exact_contact(*arrival)
    assert 0 < kept < len(made), (kept, len(made))
    assert fast.t_release == fresh.t_release and fast.drive_state.mode == fresh.drive_state.mode
    for a, b in ((fast.v_after, fresh.v_after), (fast.q_after, fresh.q_after),
                 (fast.drive_state.z, fresh.drive_state.z), (fast.gaps, fresh.gaps)):
        assert np.array_equal(np.asarray(a), np.asarray(b))
    assert fast.record.work_on_rock == fresh.record.work_on_rock and fast.drive_work == fresh.drive_work


def _same_record(a, b):
    """Two :class:`Blow` records field by field, to the bit (arrays by their values and shapes)."""
    for f in dataclasses.fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            assert np.array_equal(x, y) and np.shape(x) == np.shape(y), f.name
        elif f.name == "exact":
            assert x is y
        else:
            assert x == y or (x != x and y != y), f.name


def test_a_records_blow_sampled_when_first_read_is_the_one_sampled_at_once(driven_map):
    """The record's histories are sampled when first read, after the thread's next blows reused the
    solver's pool: the same record, to the bit, as the one sampled at once; with ``stored_apart``
    (the coupled blow's) its work on rock the work dissipated in the rock, as the eager record's."""
    from impactbar.laws.rodrock.exactrecord import blow_from_exact

    bmap, q, v = driven_map
    rec = bmap.contact(q, v)
    assert rec._blow is None  # (nothing sampled yet)
    eager = blow_from_exact(rec.exact, *rec._blow_of)
    other = v.copy()
    other[0] *= 1.3
    later = bmap.contact(q, other)  # (a blow on the reused pool: its pieces overwrite the solver's arrays)
    assert later.blow.times.size > 1
    assert later.exact.work_on_rock != rec.exact.work_on_rock
    rec.stored_apart()
    assert rec._blow is None
    _same_record(rec.blow, eager.with_stored_apart())
    assert rec.work_on_rock == eager.rock_dissipated and rec.blow.stored_apart  # (read through the record)
    assert rec.blow is rec.blow  # (sampled once)
