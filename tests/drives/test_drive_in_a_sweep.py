"""A drive with state defined in this file alone, entered in the table of drives by
:func:`impactbar.drives.register_drive`, reaches ``simulate``, ``find_orbit``, ``continue_orbit`` and a
sweep (a ``[drive]`` table in place of ``[load]``), its own parameter ``lag`` continued and swept
with no line in continuation/, sweeps/ or cli/ for it.

``Lag`` is the first-order lag of ``tests/drives/test_new_drive.py``: the force ``z`` follows the level
``P`` of its mode, ``z' = (P - z) / lag``, ``P = +stroke`` from the crossing of ``x1`` to the impact
and ``-ret`` after it. Each point is checked against a fresh :func:`impactbar.find_orbit` at that
value and against the fixed point of the Poincare map integrated here (scipy's DOP853 at
``rtol = 1e-12``: the drive's flights are ``solve_ivp``'s at ``1e-10``, so ``1e-8``), and the run from
an orbit's state against the orbit (the impacts repeat)."""

import dataclasses
from dataclasses import dataclass, field

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from impactbar import (
    BarModel,
    Drive,
    DriveState,
    DriveTraits,
    InitialState,
    continue_orbit,
    find_orbit,
    simulate,
)
from impactbar.drives import DRIVES, GapCrossing, register_drive

STROKE, RETURN = 0, 1


@dataclass(frozen=True)
class Lag(Drive):
    """The force lags behind the level of its mode: ``p = z``, ``z' = (P - z) / lag``; ``z0``, the
    force at the start of a run (default the level of the first mode), is not a parameter."""

    stroke: float
    ret: float
    x1: float
    lag: float = 0.2
    z0: float | None = field(default=None, compare=False, repr=False)

    traits = DriveTraits(kind="lag", parameters=("stroke", "ret", "x1", "lag"), state_size=1,
                         parameter_ranges={"lag": {"low": 0.0, "low_open": True,
                                                   "description": "time constant of the force"}})

    def __post_init__(self):
        if not self.lag > 0.0:
            raise ValueError(f"lag must be > 0; got {self.lag!r}")

    def level(self, mode):
        return self.stroke if mode == STROKE else -self.ret

    def start(self, model, q, v):
        mode = RETURN if -q[0] < self.x1 else STROKE
        return DriveState(mode, np.array([self.level(mode) if self.z0 is None else self.z0]))

    def mode_name(self, mode):
        return ("stroke", "return")[mode]

    def force(self, mode, z, q, v):
        return float(z[0])

    def rate(self, mode, z, q, v, model=None):
        return np.array([(self.level(mode) - z[0]) / self.lag])

    def events(self, mode):
        return (GapCrossing("x1", level=self.x1, direction=1),) if mode == RETURN else ()

    def jump(self, mode, z, event, t, q, v):
        return DriveState(STROKE, z)

    def impact(self, mode, z, t, q, v):
        return DriveState(RETURN, z)


MODEL = BarModel(s=10.0, d=0.1, R=0.3, n_modes=0)


def lag_map(drive, x):
    """The rigid piston's Poincare map just after an impact, ``(w, z) -> (w, z)``, and the period:
    ``q' = w, w' = z - d w, z' = (P - z) / lag`` integrated here, switching to stroke where ``-q``
    rises through ``x1``, the impact ``w -> -R w`` where ``q`` rises through 0."""
    d, R = MODEL.d, MODEL.R
    t, y, mode = 0.0, np.array([0.0, x[0], x[1]]), RETURN
    while True:
        P = drive.stroke if mode == STROKE else -drive.ret

        def f(_, y, P=P):
            return [y[1], y[2] - d * y[1], (P - y[2]) / drive.lag]

        def hit(_, y):
            return y[0]

        def out(_, y):
            return -y[0] - drive.x1

        hit.terminal, hit.direction, out.terminal, out.direction = True, 1, True, 1
        sol = solve_ivp(f, (t, t + 200.0), y, method="DOP853", rtol=1e-12, atol=1e-14,
                        events=[hit, out] if mode == RETURN else [hit])
        t, y = sol.t[-1], sol.y[:, -1]
        if sol.t_events[0].size:
            return np.array([-R * y[1], y[2]]), t
        mode = STROKE


def _check_against_the_map(orbit):
    x = np.array([orbit.state[1], orbit.drive_states[0, 0]])
    image, T = lag_map(orbit.drive, x)
    np.testing.assert_allclose(image, x, rtol=0, atol=1e-8)
    assert orbit.period == pytest.approx(T, abs=1e-8)


@pytest.fixture
def registered():
    register_drive(Lag)
    yield
    DRIVES.pop(Lag.traits.kind, None)


def test_simulate_from_the_orbit_repeats_it():
    o = find_orbit(MODEL, Lag(1.0, 1.0, 1.0, lag=0.5))
    assert o.stable and o.admissible
    _check_against_the_map(o)
    start = dataclasses.replace(o.drive, z0=float(o.drive_states[0, 0]))  # the orbit's force after impact
    assert start == o.drive
    run = simulate(MODEL, start, InitialState(o.state[:1], o.state[1:]), 5.5 * o.period)
    assert run.n_impacts == 5
    np.testing.assert_allclose(run.impact_times, o.period * np.arange(1, 6), rtol=0, atol=1e-8)
    np.testing.assert_allclose(run.impact_velocities, o.impact_velocity, rtol=1e-8)


def test_the_drives_parameter_is_continued():
    branch = continue_orbit(find_orbit(MODEL, Lag(1.0, 1.0, 1.0, lag=0.5)), "lag", to=0.6)
    assert branch.parameter == "lag" and str(branch.status) == "reached" and len(branch) > 2
    for lag, o in zip(branch.values, branch.orbits, strict=True):
        assert o.drive == Lag(1.0, 1.0, 1.0, lag=lag)
        ref = find_orbit(MODEL, Lag(1.0, 1.0, 1.0, lag=lag))
        assert o.period == pytest.approx(ref.period, abs=1e-8)
        assert o.impact_velocity == pytest.approx(ref.impact_velocity, abs=1e-8)
    _check_against_the_map(branch.orbits[-1])


def test_the_drives_parameter_is_swept(registered, tmp_path):
    """A ``[drive]`` table in place of ``[load]``, an axis in ``lag``: each point's orbit against a
    fresh find_orbit and the map integrated here."""
    pytest.importorskip("xarray")
    pytest.importorskip("zarr")
    from impactbar.sweeps import open_sweep, parse_spec, run_sweep

    doc = {"task": "orbits", "model": {"s": 10.0, "d": 0.1, "R": 0.3, "n_modes": 0},
           "drive": {"kind": "lag", "stroke": 1.0, "ret": 1.0, "x1": 1.0, "lag": 0.5},
           "axes": {"lag": {"values": [0.4, 0.5, 0.6]}}}
    spec = parse_spec(doc)
    assert spec.load is None and spec.options["max_orbits"] == 8
    assert parse_spec(spec.to_dict()) == spec
    model, drive = spec.point((0,))
    assert model == MODEL and drive == Lag(1.0, 1.0, 1.0, lag=0.4)
    run_sweep(spec, tmp_path / "lag.zarr", executor="threads", n_workers=1, progress=False)
    ds = open_sweep(tmp_path / "lag.zarr")
    assert ds["lag"].values.tolist() == [0.4, 0.5, 0.6] and not ds["failed"].values.any()
    for i, lag in enumerate((0.4, 0.5, 0.6)):
        assert int(ds["n_orbits"].values[i]) == 1
        ref = find_orbit(MODEL, Lag(1.0, 1.0, 1.0, lag=lag))
        assert ds["impact_velocity"].values[i, 0] == pytest.approx(ref.impact_velocity, abs=1e-8)
        assert bool(ds["stable"].values[i, 0]) == ref.stable
        x = np.array([-MODEL.R * ref.impact_velocity, ref.drive_states[0, 0]])
        np.testing.assert_allclose(lag_map(ref.drive, x)[0], x, rtol=0, atol=1e-8)

    with pytest.raises(ValueError, match=r"\[axes\] lag = -1.0: lag must be in \(0, inf\)"):
        parse_spec({**doc, "axes": {"lag": {"values": [-1.0]}}})
    with pytest.raises(ValueError, match=r"^\[drive\] kind must be one of \[.*'lag'.*\] "
                                         r"\(impactbar.drives.register_drive adds one\); got 'nope'$"):
        parse_spec({**doc, "drive": {"kind": "nope"}})
    with pytest.raises(ValueError, match=r"^\[drive\] the drive 'lag' takes keys of Lag: .*'tau'"):
        parse_spec({**doc, "drive": {**doc["drive"], "tau": 1.0}})
    with pytest.raises(ValueError, match=r"give \[load\] or \[drive\]"):
        parse_spec({**doc, "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1}})
    with pytest.raises(ValueError, match="a \\[drive\\] sweeps the 'orbits' task only"):
        parse_spec({**doc, "task": "bifurcation"})


def test_register_drive_refuses_a_taken_kind_and_a_non_drive():
    class Other(Lag):
        traits = dataclasses.replace(Lag.traits, kind="position-switched")

    with pytest.raises(ValueError, match="kind .position-switched. is already the drive PositionSwitched"):
        register_drive(Other)
    with pytest.raises(ValueError, match="subclass of Drive"):
        register_drive(int)


def test_the_valve_is_swept_by_its_kind(tmp_path):
    """The valve is in the table as ``"position-switched"``: a ``[drive]`` table sweeps its
    ``switch_out``; on the rigid undamped piston each point's orbit is the closed form of energy and
    restitution (theory §10), ``v^2 (1 - R^2) = 2 x1 (stroke + ret)``."""
    pytest.importorskip("xarray")
    pytest.importorskip("zarr")
    from impactbar.sweeps import open_sweep, parse_spec, run_sweep

    spec = parse_spec({"task": "orbits", "model": {"s": 10.0, "d": 0.0, "R": 0.215, "n_modes": 0},
                       "drive": {"kind": "position-switched", "stroke": 1.0, "ret": 1.0, "switch_out": 1.0},
                       "axes": {"switch_out": {"values": [0.5, 1.0]}}})
    run_sweep(spec, tmp_path / "valve.zarr", executor="threads", n_workers=1, progress=False)
    ds = open_sweep(tmp_path / "valve.zarr")
    for i, x1 in enumerate((0.5, 1.0)):
        assert int(ds["n_orbits"].values[i]) == 1 and bool(ds["stable"].values[i, 0])
        v = np.sqrt(2.0 * x1 * 2.0 / (1.0 - 0.215**2))
        assert ds["impact_velocity"].values[i, 0] == pytest.approx(v, rel=1e-12)
