"""The drifter's oil circuit in SI (``impactbar.physical.circuit``) where its relief valve opens, and
toward the ideal limit of theory §11.

- The relief set below the supply pressure the circuit reaches without it: the orbit is the one with
  the relief open (checked against the run from rest, the restarted orbit and the orbit without
  relief; the relief's flow from the orbit's own supply-pressure history).
- The oil ``k`` times stiffer, the openings ``k`` times wider, the spool ``k`` times faster
  (k = 10, 100, 1000, 10000): the operating point converges at first order in ``1/k``, its
  Richardson limit from two members predicting the next.
"""

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import trapezoid

from impactbar import InitialState, simulate
from impactbar.physical.circuit import circuit_preset

#: the relief set 2 MPa below the preset's mean supply pressure without it (21.94 MPa), 30 L/min per
#: 0.1 MPa above its setting
RELIEF = {"relief_pressure": "20 MPa", "relief_coefficient": "5e-9 m^3/s/Pa"}


def _restarted(orbit, periods):
    """The impact times and velocities of ``simulate`` restarted from the orbit's state after its
    impact (pressures and valve as the start's), over ``periods`` periods."""
    M = orbit.model.n_modes + 1
    y = np.asarray(orbit.states_after_impact[0], dtype=float)
    drive = dataclasses.replace(orbit.drive, start_pressures=tuple(orbit.drive_states[0]))
    run = simulate(orbit.model, drive, InitialState(y[:M], y[M:]), periods * orbit.period * (1 + 1e-3),
                   max_impacts=periods)
    return np.asarray(run.impact_times), np.asarray(run.impact_velocities)


def test_the_orbit_with_the_relief_open_is_the_motion_from_rest():
    """The relief's discrete state opens only where the supply pressure crosses its setting upward;
    along the orbit without relief it never did, and ``orbit()`` returned that orbit (period 21.735
    ms, 10.016 m/s, a mean supply pressure of 21.94 MPa above the 20 MPa setting) while the run from
    rest settled onto another (22.806 ms, 9.421 m/s)."""
    plain = circuit_preset("circuit-drifter").orbit()
    d = circuit_preset("circuit-drifter", supply=RELIEF)
    point = d.orbit()
    p_rel, k_rel = 20e6, 5e-9
    # not the orbit without relief
    assert plain.mean_supply_pressure_Pa > p_rel + 1.5e6
    assert abs(point.period_s / plain.period_s - 1) > 0.04
    # the relief open over part of the period: its flow from the supply pressure's history
    h = point.histories(4001)
    above = np.maximum(h["p_s_Pa"] - p_rel, 0.0)
    assert np.any(above == 0.0) and h["p_s_Pa"].max() > p_rel + 5e4  # it opens and closes
    relief_flow = k_rel * trapezoid(above, h["t_s"]) / point.period_s
    pump = 70e-3 / 60
    assert 0.02 * pump < relief_flow < pump
    # the oil the pump delivers over a period leaves to the tank (the tank's term p_t V; to within
    # the linear oil's p / beta, 1.4 %, which does not conserve the oil's volume exactly)
    assert point.energy_account["tank"] / 0.3e6 == pytest.approx(pump * point.period_s, rel=0.014)
    assert abs(point.mean_supply_pressure_Pa - p_rel) < 0.5e6
    # the run from rest settles onto it
    run = d.simulate(2.0)
    t, v = run["impact_times_s"], run["impact_velocities_m_s"]
    assert t.size > 80
    assert np.diff(t)[-1] == pytest.approx(point.period_s, rel=1e-6)
    assert v[-1] == pytest.approx(point.impact_velocity_m_s, rel=1e-6)
    # and the run restarted from the orbit's state repeats it over three periods
    o = point.orbit
    times, speeds = _restarted(o, 3)
    assert times.size == 3
    assert np.max(np.abs(times - o.period * np.arange(1, 4))) < 1e-6 * o.period
    assert np.max(np.abs(speeds - o.impact_velocity)) < 1e-6 * abs(o.impact_velocity)


def _stiff(k):
    """The preset with the oil and the openings ``k`` times stiffer and the spool ``k`` times faster
    (theory §11's ideal limit; the transition pressure and the relief as the preset's)."""
    return circuit_preset("circuit-drifter",
                          valve={"flow_coefficient": f"{6e-6 * k!r} m^3/s/Pa^0.5",
                                 "switching_time": f"{1 / k!r} ms"},
                          supply={"front_flow_coefficient": f"{6e-6 * k!r} m^3/s/Pa^0.5"},
                          oil={"bulk_modulus": f"{1.4 * k!r} GPa"})


@pytest.fixture(scope="module")
def stiff_points():
    return {k: _stiff(k).orbit() for k in (10.0, 100.0, 1000.0, 10000.0)}


def test_the_ideal_limit_sequence_converges_at_first_order(stiff_points):
    """find_orbit's default start (the run from rest followed until it settles, then Newton) finds
    each orbit; the period and the impact velocity move ten times less per decade of ``k`` (measured
    order 1.00), and the Richardson limit of k = 100 and 1000 predicts k = 10000 to within 1 % of
    their difference. The pump-fed circuit's limit is not the ideal valve's of theory §10: the
    valve's crossflow during each ramp (a volume ~ K_v tau_v) stays, about half the pump's oil."""
    ks = (10.0, 100.0, 1000.0, 10000.0)
    for name in ("period_s", "impact_velocity_m_s"):
        x = [getattr(stiff_points[k], name) for k in ks]
        d = np.diff(x)
        order = [math.log10(d[j] / d[j + 1]) for j in range(2)]
        assert all(0.95 < p < 1.05 for p in order), (name, order)
        limit = (10.0 * x[2] - x[1]) / 9.0  # first order in 1/k
        predicted = limit + (x[2] - limit) / 10.0
        assert abs(x[3] - predicted) < 0.01 * abs(x[2] - x[1]), (name, x, predicted)
    for k in ks:
        p = stiff_points[k]
        assert p.stable and not p.cavitates
        acc = p.energy_account
        assert abs(acc["relative_residual"]) < 1e-10
        # the crossflow: the tank takes the pump's oil, the piston's strokes only A_r x_s of it
        to_tank = acc["tank"] / 0.3e6
        assert to_tank == pytest.approx(70e-3 / 60 * p.period_s, rel=0.014 / k)
        assert 0.4 < 1 - 5.6e-4 * 21.5e-3 / to_tank < 0.6


@pytest.mark.parametrize("k", [100.0, 1000.0])
def test_a_stiff_circuit_runs_from_rest_toward_its_orbit(k, stiff_points):
    """The run from rest on the stop integrates through the stiff transients (CVODE) and its blows
    approach the operating point."""
    out = _stiff(k).simulate(1.0)
    t, v = out["impact_times_s"], out["impact_velocities_m_s"]
    p = stiff_points[k]
    assert t.size > 40
    assert np.diff(t)[-1] == pytest.approx(p.period_s, rel=0.03)
    assert v[-1] == pytest.approx(p.impact_velocity_m_s, rel=0.03)


#: the front chamber fed through an opening 30 times narrower than the preset's: its pressure falls
#: to -0.53 MPa absolute as the piston leaves the stop
STARVED = {"front_flow_coefficient": "2e-7 m^3/s/Pa^0.5"}


def test_a_cavitating_motion_is_refused_by_orbit_simulate_and_a_restart():
    """``orbit()`` returned this orbit flagged ``cavitates`` (the front chamber's least pressure
    -0.526 MPa, a motion the model does not represent); now the orbit, the run from rest and a start
    below 0 are all refused, naming the volume."""
    d = circuit_preset("circuit-drifter", supply=STARVED)
    with pytest.raises(ValueError, match=r"front pressure to -0\.5\d+ MPa absolute, below 0: the oil would "
                                         r"cavitate"):
        d.orbit()
    with pytest.raises(ValueError, match=r"the run of 1 s takes the front pressure to -\d.*cavitate"):
        d.simulate(1.0)
    drive = d.drive()
    with pytest.raises(ValueError, match="start_pressures"):
        dataclasses.replace(drive, start_pressures=(-0.01, 2.0, 2.0, 1.0))
    # a shorter run, before the accumulator has charged, stays above 0 and is kept
    assert d.simulate(0.02)["histories"]["p_f_Pa"].min() > 0.0
    # the preset's orbit and runs are untouched
    assert not circuit_preset("circuit-drifter").orbit().cavitates
