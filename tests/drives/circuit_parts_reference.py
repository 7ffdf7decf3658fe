"""The drifter's circuit with the parts of a drill's circuit (``LaminarLeak``, ``Cushion``,
``CheckValve``) written out with numpy, for the tests of those parts: the vector field of
``(q, q', p_f, p_r, p_s, [p_cushion], x_v)`` and each part's loss, with the parts' own laws (``g``
by ``np.interp``, the check valve's opening clipped: no mode of theirs), and one period of an orbit
integrated by scipy's ``solve_ivp`` flight by flight (each flight's mode of the preset read from its
states, the circuit's state carried from flight to flight, the bar's taken from the run at each
flight's start: its impact map is not the circuit's)."""

import dataclasses
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from impactbar import InitialState, find_orbit, simulate
from impactbar.drives.circuit import CheckValve, Cushion, LaminarLeak
from impactbar.physical import circuit_preset

#: the drifter on the drill string and rock (the ``rock_drifter`` fixture of this folder's conftest)
ROCK_EXAMPLE = Path(__file__).parents[2] / "examples" / "circuit_drifter_rock.toml"


def preset_orbit():
    """``(model, drive, orbit)``: the preset drifter's rigid piston, its circuit and its orbit."""
    d = circuit_preset("circuit-drifter")
    model, drive = d.model().with_(n_modes=0), d.drive()
    return model, drive, find_orbit(model, drive)


def with_parts(model, drive, *parts):
    """``find_orbit`` of ``drive`` with ``parts`` added to its circuit (its ``extra_parts``)."""
    return find_orbit(model, dataclasses.replace(drive, extra_parts=parts))


def check_repeats(orbit):
    """The orbit is admissible, repeats when ``simulate`` restarts it (20 periods, to 1e-6) and its
    energy account closes over a period (1e-8 of the pump's work); returns the run of one period and
    its account."""
    assert orbit.admissible
    run = restart(orbit, 20.5)
    assert run.n_impacts == 20
    assert np.allclose(np.diff(run.impact_times), orbit.period, rtol=1e-6, atol=0.0)
    assert np.allclose(run.impact_velocities, orbit.impact_velocity, rtol=1e-6, atol=0.0)
    one = restart(orbit, 1.0)
    account = orbit.drive.energy(one)
    assert abs(account["relative_residual"]) < 1e-8
    return one, account


def check_orbit(orbit):
    """:func:`check_repeats`, and the numpy equations reproduce that period (the circuit's state and
    the parts' losses, 1e-6); returns the run of one period."""
    one, _ = check_repeats(orbit)
    z, want_z, losses, want_losses = one_period(orbit)
    assert np.allclose(z, want_z, rtol=1e-6, atol=1e-8), z - want_z
    assert np.allclose(losses, want_losses, rtol=1e-6), (losses, want_losses)
    return one


def check_rock(model, drive, part):
    """``find_orbit`` on the drill string and rock with ``part``: admissible, one blow a period
    when restarted, its account closing over it; returns the orbit."""
    orbit = with_parts(model, drive, part)
    assert orbit.admissible
    run = restart(orbit, 1.0)
    assert run.n_impacts == 1
    assert abs(orbit.drive.energy(run)["relative_residual"]) < 1e-8
    return orbit


def random_state(rng, layout, M, gap, node):
    """A random point of the drifter's state for the kinds' tests: the bar's modal positions ``q``
    (the piston's gap up to ``gap``) and the circuit's state ``z``: the supply, the front near it, the
    rear and the part's own ``node`` anywhere, the main valve at a stop or between."""
    q = rng.normal(0.0, 0.005, M)
    q[0] = -rng.uniform(0.0, gap)
    z = np.empty(layout.n_states)
    z[layout["supply"]] = rng.uniform(0.8, 2.6)
    z[layout["front"]] = z[layout["supply"]] + rng.uniform(-0.02, 0.03)
    z[layout["rear"]], z[layout[node]] = rng.uniform(0.05, 2.4, 2)
    z[layout["spool"]] = rng.choice([0.0, 1.0, rng.uniform()])
    return q, z


def restart(orbit, periods, **changes):
    """:func:`impactbar.simulate` from the orbit's state after its impact for ``periods`` periods."""
    z, y = orbit.drive_states[0], np.asarray(orbit.states_after_impact[0])
    M = orbit.model.n_modes + 1
    drive = dataclasses.replace(orbit.drive, start_pressures=tuple(z), **changes)
    return simulate(orbit.model, drive, InitialState(y[:M], y[M:]), periods * orbit.period)


def field(drive, model, mode, y):
    """``y'`` of ``(q, q', pressures in the layout's order, x_v, L_0..L_{k-1})``, ``L_i`` the loss of
    the ``i``-th extra part."""
    target, moving, acc, rel = mode[:4]
    ch, va, su, oil, ac = drive.chambers, drive.valve, drive.supply, drive.oil, drive.accumulator
    L = drive.layout
    M = model.n_modes + 1
    q, qd = y[:M], y[M:2 * M]
    names = L.states[:-1]
    p = {name: y[2 * M + i] for i, name in enumerate(names)}
    p["tank"] = su.tank_pressure
    xv = y[2 * M + len(names)]
    beta, ptr2 = oil.bulk_modulus, oil.transition_pressure ** 2
    w, wd = -model.drive_weights @ q, -model.drive_weights @ qd
    gap = -q[0]

    def phi(x):
        return x * (x * x + ptr2) ** -0.25

    net = dict.fromkeys(p, 0.0)

    def flow(a, b, value):
        net[a] -= value
        net[b] += value
        return value

    ret = next((c.name for c in drive.extra_parts if isinstance(c, Cushion)), "tank")
    flow("supply", "front", su.front_coefficient * phi(p["supply"] - p["front"]))
    flow("supply", "rear", va.coefficient * xv * phi(p["supply"] - p["rear"]))
    flow("rear", ret, va.coefficient * (1 - xv) * phi(p["rear"] - p[ret]))
    if rel:
        flow("supply", "tank", su.relief_coefficient * (p["supply"] - su.relief_pressure))
    net["supply"] += su.pump_flow
    losses = []
    for part in drive.extra_parts:
        if isinstance(part, LaminarLeak):
            dp = p[part.source] - p[part.target]
            losses.append(flow(part.source, part.target, part.conductance * dp) * dp)
        elif isinstance(part, Cushion):
            dp = p[part.name] - p[part.target]
            g = np.interp(gap, part.gaps, part.openings)
            losses.append(flow(part.name, part.target, part.coefficient * g * phi(dp)) * dp)
        elif isinstance(part, CheckValve):
            dp = p[part.source] - p[part.target]
            o = np.clip((dp - part.cracking_pressure) / part.opening_span, 0.0, 1.0)
            losses.append(flow(part.source, part.target, part.coefficient * o * phi(dp)) * dp)
    a = ch.area_ratio
    rates = {"front": beta / (ch.front_volume + a * w) * (net["front"] - a * wd),
             "rear": beta / (ch.rear_volume - w) * (net["rear"] + wd)}
    cs = su.hose_volume / beta
    if acc:
        n = ac.polytropic_exponent
        cs += ac.volume / n * ac.precharge ** (1 / n) * p["supply"] ** (-1 / n - 1)
    rates["supply"] = net["supply"] / cs
    for part in drive.extra_parts:
        if isinstance(part, Cushion):
            rates[part.name] = beta / part.volume * net[part.name]
    force = p["rear"] - a * p["front"]
    qdd = force - model.d * qd - model.frequencies ** 2 * q
    rate = ((1.0 if target else -1.0) / va.switching_time) if moving else 0.0
    return np.concatenate((qd, qdd, [rates[name] for name in names], [rate], losses))


def one_period(orbit):
    """The orbit's circuit state after one period and each extra part's loss over it by the numpy
    equations, against the run's (the state, the parts' loss integrands): ``(z, want_z, losses,
    want_losses)``."""
    drive, model = orbit.drive, orbit.model
    L = drive.layout
    run = restart(orbit, 1.0)
    pieces = [p for p in run.pieces if hasattr(p, "energies") and p.t_end > p.t0]
    M = model.n_modes + 1
    n = L.size(M)
    k = len(drive.extra_parts)
    z = np.array(orbit.drive_states[0], dtype=float)
    losses = np.zeros(k)
    for p in pieces:
        xv0, xv1 = p.y[0, 2 * M + L["spool"]], p.y[-1, 2 * M + L["spool"]]
        moving = int(xv1 != xv0)
        target = int(xv1 > xv0) if moving else int(round(xv0))
        ps = p.drive_state(0.5 * (p.t0 + p.t_end))[L["supply"], 0]
        mode = (target, moving, int(ps >= drive.accumulator.precharge),
                int(ps > drive.supply.relief_pressure))
        y0 = np.concatenate((p.y[0, :2 * M], z, np.zeros(k)))
        sol = solve_ivp(lambda t, y, mode=mode: field(drive, model, mode, y), (p.t0, p.t_end), y0,
                        method="Radau", rtol=1e-11, atol=1e-13)
        assert sol.success
        z = sol.y[2 * M:n, -1]
        losses += sol.y[n:, -1]
    total = sum(p.energies() for p in pieces)
    want = [total[L.energy[name]] for part in drive.extra_parts for name, _ in part.energies
            if _is_loss(part, name)]
    return z, np.asarray(orbit.drive_states[0]), losses, np.asarray(want)


def _is_loss(part, name):
    """Whether the integrand ``name`` of ``part`` is its flow's loss (a cushion's port, not its node)."""
    return not (isinstance(part, Cushion) and name == part.name)


def network_jacobian_fd(y, par, M, n, n_energy):
    """The central differences (step ``1e-6 max(1, |y_j|)``) of the interpreted network's vector
    field (``network_interpreter.base``, its first ``n`` rows) at ``y``: the reference of its
    Jacobian."""
    import network_interpreter as NI

    fd = np.empty((n, n))
    for j in range(n):
        h = 1e-6 * max(1.0, abs(y[j]))
        up, dn = y.copy(), y.copy()
        up[j] += h
        dn[j] -= h
        fu, fl = np.empty(n + n_energy), np.empty(n + n_energy)
        NI.base(up, par, M, fu)
        NI.base(dn, par, M, fl)
        fd[:, j] = (fu[:n] - fl[:n]) / (2 * h)
    return fd


def both_ways(y, gap, par, M, n, n_energy, n_events, gen=None):
    """The network's vector field, event functions and Jacobian at ``y`` (``gap`` the piston's gap,
    ``-q_0``) by the interpreter (:mod:`network_interpreter`) and by the code generated for its
    topology (``gen``, generated from ``par`` where ``None``; its ``rates`` too, the field and the
    Jacobian from one pass), asserted the same to the bit:
    ``(out, g, A, gen)``, the interpreter's three and the generated module."""
    import network_interpreter as NI

    from impactbar.drives.circuit import _bar as K
    from impactbar.drives.circuit import _netgen as NG

    if gen is None:
        gen = NG.generate(par[K.HEAD + 3 * M:])
    bits = lambda a: np.asarray(a, dtype=float).view(np.int64)  # noqa: E731
    out, out2 = np.full(n + n_energy, np.nan), np.full(n + n_energy, np.nan)
    NI.base(y, par, M, out)
    gen.base(y, par, M, out2)
    assert np.array_equal(bits(out2), bits(out))
    g, g2 = np.full(n_events, np.nan), np.full(n_events, np.nan)
    NI.events(y[2 * M:n], par, M, g, 0, gap)
    gen.events(y[2 * M:n], par, M, g2, 0, gap)
    assert np.array_equal(bits(g2), bits(g))
    A, A2 = np.full((n, n), np.nan), np.full((n, n), np.nan)
    NI.jac_base(y, par, M, A)
    gen.jac_base(y, par, M, A2)
    assert np.array_equal(bits(A2), bits(A))
    out3, A3 = np.full_like(out, np.nan), np.full_like(A, np.nan)
    gen.rates(y, par, M, out3, A3)  # (both at once: the variational equations' right-hand side's)
    assert np.array_equal(bits(out3), bits(out)) and np.array_equal(bits(A3), bits(A))
    return out, g, A, gen
