"""A pilot-operated spool valve (``SpoolValve``, theory §11, *Parts of a drill's circuit*) in the place
of the preset's ramped valve: a spool of mass ``m_s`` and stroke ``h_s`` between inelastic stops,
``m_s x_s'' = p_c A_c - p_s A_0 - b_s x_s'``, its main ports opened by its position with a lap, its
control chamber switched to the supply or the return by ports the piston uncovers.

- A spool of a few tenths of a kilogram (in the preset's scales): its orbit crosses every kink and both
  stops, it repeats when ``simulate`` restarts it (20 periods), its energy account closes over a
  period, its kinetic integrand over the period is the kinetic energy lost at its arrivals, and the
  circuit's equations written out with numpy (the openings clipped: no mode; the stops from the run's
  pieces), integrated by scipy's ``solve_ivp``, reproduce one period.
- A light fast spool tends to the ramped valve with an instant switch (``switch_out = y_open - d_y``,
  ``switch_in = y_close + d_y``), at first order in its mass (the stroke, the damping and the control
  volume with it, the pilot's coefficient as its inverse).
- On the drill string and rock: an admissible orbit whose account closes.
"""

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from circuit_parts_reference import check_repeats, check_rock, restart, with_parts
from scipy.integrate import solve_ivp

from impactbar import find_orbit
from impactbar.drives.circuit import SpoolValve
from impactbar.drives.circuit.spool_valve import port_openings

#: the preset's scales: 0.2 kg, 8 mm, 1.7 cm^2 and 0.84 cm^2, 5 cm^3 (theory §11's typical spool)
Y_OPEN, Y_CLOSE, D_Y = 0.052, 0.002, 0.004


def spool(e=1.0, **changes):
    """The spool at the scale ``e`` of its mass, stroke, damping and control volume (the pilot's
    coefficient as ``1 / e``)."""
    sv = SpoolValve(mass=0.036 * e, stroke=0.018 * e, damping=0.1 * e, large_area=0.3, small_area=0.15,
                    control_volume=0.02 * e, coefficient=1.599784529568825, pilot_coefficient=0.5 / e,
                    lap=0.1, open_gap=Y_OPEN, close_gap=Y_CLOSE, port_span=D_Y)
    return dataclasses.replace(sv, **changes)


@pytest.fixture(scope="module")
def orbit(preset):
    model, drive, _ = preset
    return with_parts(model, drive, spool())


def field(drive, model, held, acc, rel, y):
    """``y'`` of ``(q, q', p_f, p_r, p_s, p_c, v_s, x, ports, pilot, damping)`` (the last three the
    losses), the spool resting (``held``) or free: the equations of theory §11 written out."""
    ch, su, oil, ac = drive.chambers, drive.supply, drive.oil, drive.accumulator
    (sv,) = drive.extra_parts
    M = model.n_modes + 1
    q, qd = y[:M], y[M:2 * M]
    pf, pr, ps, pc, vs, x = y[2 * M:2 * M + 6]
    pt, beta, ptr2 = su.tank_pressure, oil.bulk_modulus, oil.transition_pressure ** 2
    w, wd = -model.drive_weights @ q, -model.drive_weights @ qd
    gap = -q[0]

    def phi(d):
        return d * (d * d + ptr2) ** -0.25

    o_p, o_t = port_openings(x, sv.lap)
    a_p = np.clip((gap - sv.open_gap) / sv.port_span + 1.0, 0.0, 1.0)
    a_t = np.clip((sv.close_gap - gap) / sv.port_span + 1.0, 0.0, 1.0)
    qf = su.front_coefficient * phi(ps - pf)
    qp, qt = sv.coefficient * o_p * phi(ps - pr), sv.coefficient * o_t * phi(pr - pt)
    cp, ct = sv.pilot_coefficient * a_p * phi(ps - pc), sv.pilot_coefficient * a_t * phi(pc - pt)
    qrel = su.relief_coefficient * (ps - su.relief_pressure) if rel else 0.0
    a = ch.area_ratio
    dpf = beta / (ch.front_volume + a * w) * (qf - a * wd)
    dpr = beta / (ch.rear_volume - w) * (qp - qt + wd)
    cs = (su.hose_volume - sv.small_area * sv.stroke * x) / beta
    if acc:
        n = ac.polytropic_exponent
        cs += ac.volume / n * ac.precharge ** (1 / n) * ps ** (-1 / n - 1)
    dps = (su.pump_flow - qf - qp - cp - qrel + sv.small_area * vs) / cs
    dpc = beta / (sv.control_volume + sv.large_area * sv.stroke * x) * (cp - ct - sv.large_area * vs)
    dvs = 0.0 if held else (sv.large_area * pc - sv.small_area * ps - sv.damping * vs) / sv.mass
    dx = 0.0 if held else vs / sv.stroke
    qdd = (pr - a * pf) - model.d * qd - model.frequencies ** 2 * q
    losses = [qp * (ps - pr) + qt * (pr - pt), cp * (ps - pc) + ct * (pc - pt), sv.damping * vs * vs]
    return np.concatenate((qd, qdd, [dpf, dpr, dps, dpc, dvs, dx], losses))


@pytest.mark.parametrize("n_modes", [0, 2])
def test_the_spool_valves_kinds_give_their_equations_and_the_generated_code_their_numbers(preset, n_modes):
    """At random states (the gap across the pilot's ports, the spool free or resting at a stop, the
    mode's flags those of the state): the interpreted network against :func:`field`, its Jacobian
    against central differences, its events against the levels, the account closing at each point,
    and the code generated for its topology the interpreted network's numbers to the bit."""
    from circuit_parts_reference import both_ways, network_jacobian_fd, random_state


    model, drive = preset[0].with_(n_modes=n_modes), dataclasses.replace(preset[1], extra_parts=(spool(),))
    L, M = drive.layout, n_modes + 1
    n, ne = L.size(M), L.n_energy
    sv = drive.extra_parts[0]
    events = drive._composition.events
    rng = np.random.default_rng(5)
    gen = None
    for _ in range(60):
        q, z = random_state(rng, L, M, 0.07, "spool_valve")
        z[L["spool_valve_v"]] = 0.0 if z[L["spool"]] in (0.0, 1.0) else rng.normal(0.0, 0.5)
        mode = drive._mode(0, 0, z[L["supply"]], z, q)
        held = mode[1 + events.index("spool_valve_stop")]
        y = np.concatenate((q, rng.normal(0.0, 0.3, M), z, np.zeros(ne)))
        par = drive._network_par(model, mode)
        out, g, A, gen = both_ways(y, -q[0], par, M, n, ne, len(events), gen)
        want = field(drive, model, held, *drive._flags(mode), y[:n])
        assert np.allclose(out[:n], want[:n], rtol=1e-12, atol=1e-12 * np.max(np.abs(want[:n])))
        losses = [out[n + L.energy[f"spool_valve_{k}"]] for k in ("ports", "pilot", "damping")]
        assert np.allclose(losses, want[n:], rtol=1e-12, atol=1e-15)
        assert abs(out[n] - np.sum(out[n + 1:])) <= 1e-12 * np.sum(np.abs(out[n:]))
        x, gap = z[L["spool"]], -q[0]
        force = sv.large_area * z[L["spool_valve"]] - sv.small_area * z[L["supply"]]
        stop = (force if x == 1.0 else -force) if held else -x * (1 - x)
        levels = [stop, x - 0.55, x - 0.45, gap - 0.048, gap - 0.052, gap - 0.002, gap - 0.006]
        at = [events.index(f"spool_valve_{e}") for e in ("stop", "open_p", "open_t", "pilot0", "pilot1",
                                                              "pilot2", "pilot3")]
        assert np.allclose(g[at], levels, rtol=0, atol=1e-15)
        fd = network_jacobian_fd(y, par, M, n, ne)
        scale = np.max(np.abs(A), axis=1, keepdims=True)
        assert np.allclose(A, fd, rtol=1e-6, atol=1e-7 * scale), np.max(np.abs(A - fd))


def test_a_spool_valves_orbit_repeats_and_its_account_closes(orbit):
    one, account = check_repeats(orbit)
    drive, model = orbit.drive, orbit.model
    L, M = drive.layout, model.n_modes + 1
    pieces = [p for p in one.pieces if hasattr(p, "energies") and p.t_end > p.t0]
    X, V = 2 * M + L["spool"], 2 * M + L["spool_valve_v"]
    # every kink and both stops: the spool rests at each stop, and crosses both ports' kinks
    rests = [p for p in pieces if np.all(p.y[:, V] == 0.0)]
    assert {float(p.y[0, X]) for p in rests} == {0.0, 1.0}
    x = np.concatenate([p.y[:, X] for p in pieces])
    gap = -np.concatenate([p.y[:, 0] for p in pieces])
    assert -1e-9 < x.min() <= 0.0 and 1.0 <= x.max() < 1.0 + 1e-9  # (to the arrivals' location)
    assert gap.max() > Y_OPEN and gap.min() < Y_CLOSE
    # the kinetic integrand over a period: the kinetic energy lost at the stops (their arrivals: the end
    # of each flight after which the spool rests)
    sv = drive.extra_parts[0]
    lost = sum(0.5 * sv.mass * a.y[-1, V] ** 2 for a, b in zip(pieces, pieces[1:], strict=False)
               if a.y[-1, V] != 0.0 and b.y[0, V] == 0.0)
    total = sum(p.energies() for p in pieces)
    assert lost > 0.0
    assert total[L.energy["spool_valve_kinetic"]] == pytest.approx(lost, rel=1e-6)
    spool_terms = total[L.energy["spool_valve_kinetic"]] + total[L.energy["spool_valve_damping"]]
    assert account["spool"] == pytest.approx(spool_terms, rel=1e-12)
    assert 0.0 < total[L.energy["spool_valve_damping"]] < account["spool"]


@pytest.mark.slow
def test_numpy_reproduces_a_spool_valves_period(orbit):
    """The numpy equations over the period, flight by flight from the run's bar (its impacts are the
    bar's), the circuit's state carried; at an arrival the spool put on its stop at rest."""
    drive, model = orbit.drive, orbit.model
    L, M = drive.layout, model.n_modes + 1
    pieces = [p for p in restart(orbit, 1.0).pieces if hasattr(p, "energies") and p.t_end > p.t0]
    X, V = 2 * M + L["spool"], 2 * M + L["spool_valve_v"]
    total = sum(p.energies() for p in pieces)
    z = np.array(orbit.drive_states[0], dtype=float)
    losses = np.zeros(3)
    for p in pieces:
        held = bool(np.all(p.y[:, V] == 0.0) and np.all(p.y[:, X] == p.y[0, X]) and p.y[0, X] in (0.0, 1.0))
        if p.y[0, V] == 0.0 and p.y[0, X] in (0.0, 1.0):  # (an arrival: the inelastic stop)
            z[L["spool_valve_v"]], z[L["spool"]] = 0.0, round(z[L["spool"]])
        ps = p.drive_state(0.5 * (p.t0 + p.t_end))[L["supply"], 0]
        acc, rel = ps >= drive.accumulator.precharge, ps > drive.supply.relief_pressure
        y0 = np.concatenate((p.y[0, :2 * M], z, np.zeros(3)))
        sol = solve_ivp(lambda t, y, h=held, a=acc, r=rel: field(drive, model, h, a, r, y), (p.t0, p.t_end),
                        y0, method="Radau", rtol=1e-11, atol=1e-13)
        assert sol.success
        z = sol.y[2 * M:2 * M + L.n_states, -1]
        losses += sol.y[2 * M + L.n_states:, -1]
    want = np.asarray(orbit.drive_states[0])
    assert np.allclose(z, want, rtol=1e-6, atol=1e-8), z - want
    run_losses = [total[L.energy[f"spool_valve_{k}"]] for k in ("ports", "pilot", "damping")]
    assert np.allclose(losses, run_losses, rtol=1e-6), (losses, run_losses)


def test_a_spool_valve_refuses_bad_input():
    with pytest.raises(ValueError, match="small_area must be below large_area"):
        spool(small_area=0.3)
    with pytest.raises(ValueError, match="spool_valve.lap must be"):
        spool(lap=1.0)
    with pytest.raises(ValueError, match="pilot's ports must not overlap"):
        spool(open_gap=0.01)
    with pytest.raises(ValueError, match="spool_valve.mass must be"):
        spool(mass=0.0)


@pytest.mark.slow
def test_a_light_fast_spool_tends_to_the_instant_valve_at_first_order(preset):
    """Over a decade of the spool's mass (its stroke, damping and control volume with it, the pilot's
    coefficient as its inverse; the pilot's ports 1 mm wide): the period, the impact velocity and the
    pressures after impact (over the supply's) against the ramped valve's with ``tau_v = 0``. Measured
    orders 1.005 (period), 0.98 (impact velocity), 1.06 (the largest, the rear pressure's); errors at
    the lightest spool 1.8e-4, 3.8e-4, 8.1e-3."""
    model, drive, _ = preset
    y_open, y_close, d_y = Y_OPEN, 0.0005, 0.001
    instant = drive.with_(switching_time=0.0, switch_out=y_open - d_y, switch_in=y_close + d_y)
    want = find_orbit(model, instant)
    z0 = np.asarray(want.drive_states[0])
    err = []
    for e in (0.01, 0.001):
        o = with_parts(model, drive, spool(e, open_gap=y_open, close_gap=y_close, port_span=d_y))
        z = np.asarray(o.drive_states[0])
        err.append([abs(o.period / want.period - 1), abs(o.impact_velocity / want.impact_velocity - 1),
                    np.max(np.abs(z[:3] - z0[:3])) / z0[2]])
    order = np.log10(np.asarray(err[0]) / np.asarray(err[1]))
    assert np.all((0.9 < order) & (order < 1.2)), order
    assert np.max(err[1]) < 1e-2


def test_a_spool_valve_on_the_rock(rock_drifter):
    orbit = check_rock(*rock_drifter, spool())
    x = orbit.drive.layout["spool"]
    assert 0.0 <= orbit.drive_states[0][x] <= 1.0


#: a spool valve's table on the preset's circuit, in SI
SPOOL_TABLE = {"kind": "spool_valve", "mass": "0.2 kg", "stroke": "8 mm", "damping": "50 N*s/m",
               "large_area": "1.7 cm^2", "small_area": "0.85 cm^2", "control_volume": "5 cm^3",
               "coefficient": "6e-6 m^3/s/Pa^0.5", "pilot_coefficient": "2e-6 m^3/s/Pa^0.5", "lap": 0.1,
               "open_gap": "23 mm", "close_gap": "1 mm", "port_span": "1.5 mm"}


def test_a_spool_valve_table_builds_the_part_in_si():
    from impactbar.physical import build, read_config

    cfg = read_config("circuit-drifter")[0]
    table = SPOOL_TABLE
    d = build({**cfg, "parts": {"sv": table}})
    (got,) = d.drive().extra_parts
    m, L, ar = d.bar.mass_kg, d.bar.length_m, d.si["rear_area_m2"]
    orifice = math.sqrt(1e7) / d.flow_scale_m3_s
    want = SpoolValve(mass=0.2 / m, stroke=0.008 / L, damping=50.0 / (m * d.omega_rad_s),
                      large_area=1.7e-4 / ar, small_area=0.85e-4 / ar,
                      control_volume=5e-6 / d.volume_scale_m3, coefficient=6e-6 * orifice,
                      pilot_coefficient=2e-6 * orifice, lap=0.1, open_gap=0.023 / L, close_gap=0.001 / L,
                      port_span=0.0015 / L, name="sv")
    assert (got.name, got.port) == (want.name, want.port)
    for f in got.si_fields:
        assert getattr(got, f.name) == pytest.approx(getattr(want, f.name), rel=1e-14), f.name
    with pytest.raises(ValueError, match=r"sv\.lap"):
        build({**cfg, "parts": {"sv": {**table, "lap": 1.5}}})


def test_a_spool_valve_takes_the_place_of_the_valve_table():
    """A config whose spool valve stands in for the valve needs no ``[valve]`` table (its keys then
    refused, naming the part); one without either gets one error naming both."""
    from impactbar.physical import build, read_config

    cfg = {k: v for k, v in read_config("circuit-drifter")[0].items() if k != "valve"}
    table = SPOOL_TABLE
    d = build({**cfg, "parts": {"sv": table}})
    (got,) = d.drive().extra_parts
    assert isinstance(got, SpoolValve) and d.drive()._stand_in
    assert d.to_dimensionless("parts.sv.mass", "0.2 kg")[1] == pytest.approx(0.2 / d.bar.mass_kg, rel=1e-14)
    with pytest.raises(ValueError, match=r"valve\.switch_out: this drifter has no \[valve\]: the part sv"):
        d.to_dimensionless("valve.switch_out", "20 mm")
    with pytest.raises(ValueError, match=r"needs a valve: a \[valve\] table .* spool_valve\); got neither"):
        build(cfg)


def test_a_used_drive_pickles_and_its_copy_finds_the_same_orbit():
    """A drive that has run (its composed network and its spool's watched events cached: closures)
    pickles without its caches, every one of them, and the copy finds the same orbit to the bit."""
    import functools
    import pickle

    from impactbar.drives.circuit import drive as D
    from impactbar.physical import load

    cached = {n for n, v in vars(D.HydraulicCircuitDrive).items() if isinstance(v, functools.cached_property)}
    assert cached == set(D._CACHED)
    drifter = load(Path(__file__).resolve().parents[2] / "examples" / "circuit_drill_spool.toml")
    drive, model = drifter.drive(), drifter.model()
    first = find_orbit(model, drive)
    assert cached <= set(vars(drive))  # (used: every cache computed)
    copy = pickle.loads(pickle.dumps(drive))
    assert copy == drive and not cached & set(vars(copy))
    again = find_orbit(model, copy)
    assert (again.period, again.impact_velocity) == (first.period, first.impact_velocity)
    assert np.array_equal(again.multipliers, first.multipliers)
