"""The fuzz campaign's categories of the oil circuit, the exact blow and the stepped piston
(imported by ``fuzz_campaign.py``, whose ``case`` runs each in a forked child with a time limit).

- ``circuit``: the oil-circuit drifter's configs (the preset, the example files, a stepped piston and
  a drill string), one or two keys mutated (scaled over decades, weird strings, None, negative, no
  unit, the wrong dimension, left out); per case ``build``, ``orbit()`` and, where it returns, the
  orbit restarted in ``simulate`` from its state after the impact repeating itself over 3 periods
  to 1e-6, the energy account closing, ``0 <= hydraulic_efficiency <= 1``, finite pressures, a
  positive period and a finite blow frequency, ``summary()``; a refusal at ``build`` one line naming
  the mutated key (``section.key``).
- ``exact_blow``: ``single_blow(method="exact")`` with a bit mass and a feed (and without), with and
  without a ``t_max``: the account closing, no NaN, an end (``ended_by``; an uncertain one,
  ``"budget"``, ``"rings"``, ``"may_yield"`` or ``"t_max"``, with an ``uncertainty`` in [0, inf]) within
  the case's time limit.
- ``stepped``: stepped pistons (``SteppedBar`` configs of the hammer, the drifter and the circuit)
  and ``optimize_piston`` with random valid and invalid inputs.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections import Counter
from pathlib import Path

import numpy as np

import impactbar as ib

ROOT = Path(__file__).resolve().parents[1]

#: Values put into a key in place of its own (strings without a unit or of the wrong dimension,
#: None, negative, not finite, the wrong type).
WEIRD_VALUES = [None, "", "abc", "1", 1.0, 0, -1, "-1 MPa", "nan MPa", "inf L", "1e400 MPa", "5 kg",
                "20 MPa", "0.1 L", "1 ms", "21.5 mm", "70 L/min", "6e-6 m^3/s/Pa^0.5", "2,5 mm", "1 MPa)",
                "10 MPa # x", True, [1.0], {"a": 1}, math.nan, math.inf, -0.5, "0 L", "-0.5 L", "1e-300 Pa",
                "1e300 Pa"]

_NUMBER = re.compile(r"^\s*([-+]?[0-9.]+(?:[eE][-+]?[0-9]+)?)\s*(.*)$")


def _scaled(value, factor):
    """``value`` (a number or ``"70 L/min"``) times ``factor``, its unit kept; lists each entry."""
    if isinstance(value, list):
        return [_scaled(v, factor) for v in value]
    if isinstance(value, bool):
        return value
    if isinstance(value, int | float):
        return type(value)(value * factor) if isinstance(value, float) else max(0, round(value * factor))
    if isinstance(value, str):
        m = _NUMBER.match(value)
        if m:
            return f"{float(m.group(1)) * factor:.6g} {m.group(2)}".strip()
    return value


def _flat_keys(config):
    """The config's dotted keys (``section.key``; the rod's segments as ``rod.segments.<i>.<key>``)."""
    out = []
    for sec, body in config.items():
        if not isinstance(body, dict):
            continue
        for key, value in body.items():
            if sec == "rod" and key == "segments":
                out += [f"rod.segments.{i}.{k}" for i, seg in enumerate(value) for k in seg]
            else:
                out.append(f"{sec}.{key}")
    return out


def _circuit_bases():
    from impactbar import physical as ph

    preset, _ = ph.read_config("circuit-drifter")
    toml, _ = ph.read_config(str(ROOT / "examples" / "circuit_drifter.toml"))
    rock, _ = ph.read_config(str(ROOT / "examples" / "circuit_drifter_rock.toml"))
    stepped = ph.with_values(preset, {"bar.length": ["150 mm", "298.54236 mm"],
                                      "bar.diameter": ["56 mm", "38.3 mm"], "model.n_modes": 2})
    flexible = ph.with_values(preset, {"model.n_modes": 2})
    no_extras = {k: v for k, v in preset.items() if k != "accumulator"}
    no_extras["supply"] = {k: v for k, v in preset["supply"].items() if not k.startswith("relief")}
    # (an orbit of the rigid piston costs about 0.5 s, of two modes 7 s, on the drill string 17 s: the
    # flexible, stepped and rock bases one case in 50 to 120, the stepped category has more)
    return [("preset", preset, 50), ("toml", toml, 40), ("stepped", stepped, 2), ("flexible", flexible, 1),
            ("bare", no_extras, 25), ("rock", rock, 1)]


def _mutate(rng, config, key):
    """A copy of ``config`` with ``key`` mutated, and what was done (for the report)."""
    from impactbar import physical as ph

    value = ph.config_value(config, key)
    r = rng.random()
    if r < 0.45:  # a moderate change: the orbit is likely to exist
        f = float(10 ** rng.uniform(-0.6, 0.6))
        new, how = _scaled(value, f), f"x{f:.3g}"
    elif r < 0.65:  # decades
        f = float(10 ** rng.uniform(-4, 4))
        new, how = _scaled(value, f), f"x{f:.3g}"
    elif r < 0.72:
        new, how = _scaled(value, -1.0), "negated"
    elif r < 0.95:
        new = WEIRD_VALUES[rng.integers(len(WEIRD_VALUES))]
        how = f"= {new!r}"
    else:
        holder = config
        parts = key.split(".")
        if parts[0] == "rod":
            new, how = _scaled(value, 0.5), "x0.5"
        else:
            cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in config.items()}
            cfg[parts[0]] = {k: v for k, v in holder[parts[0]].items() if k != parts[1]}
            return cfg, "left out"
    return ph.with_values(config, {key: new}), how


def _repeats(o, periods=3):
    """The orbit ``o`` (a CircuitDrifterOrbit with one impact) restarted in ``simulate`` from its state
    after the impact: the largest relative deviation of the next ``periods`` impact times and
    velocities from the orbit's (``inf`` if fewer impacts)."""
    from impactbar.simulation import InitialState, simulate

    orbit = o.orbit
    M = orbit.model.n_modes + 1
    y = np.asarray(orbit.states_after_impact[0], dtype=float)
    drive = dataclasses.replace(orbit.drive, start_pressures=tuple(orbit.drive_states[0]))
    T = orbit.period
    run = simulate(orbit.model, drive, InitialState(y[:M], y[M:]), periods * T * (1.0 + 1e-3),
                   max_impacts=periods)
    t, v = np.asarray(run.impact_times), np.asarray(run.impact_velocities)
    if t.size < periods:
        return math.inf
    return max(float(np.max(np.abs(t - T * np.arange(1, periods + 1)))) / T,
               float(np.max(np.abs(v - orbit.impact_velocity))) / abs(orbit.impact_velocity))


def circuit_orbit_labels(o):
    """The invariants of a returned circuit orbit ``o`` as outcome labels."""
    out = []
    T = o.period_s
    if not (math.isfinite(T) and T > 0.0):
        return [f"BAD period {T!r}"]
    if not math.isfinite(o.blow_frequency_Hz):
        out.append("BAD blow frequency not finite")
    if not (math.isfinite(o.impact_velocity_m_s) and o.impact_velocity_m_s > 0.0):
        out.append("BAD impact velocity not positive")
    acc = o.energy_account
    if not all(math.isfinite(v) for v in acc.values()):
        out.append("BAD energy account not finite")
    elif not acc["relative_residual"] < 1e-6:
        out.append(f"BAD energy account ({acc['relative_residual']:.2g})")
    eta = o.hydraulic_efficiency
    if not 0.0 <= eta <= 1.0:
        out.append(f"BAD hydraulic efficiency {eta:.4g}")
    low = o.minimum_pressures_Pa
    if not all(math.isfinite(p) for p in low.values()) or not math.isfinite(o.mean_supply_pressure_Pa):
        out.append("BAD pressure not finite")
    h = o.histories(50)
    if not all(np.all(np.isfinite(h[k])) for k in ("p_f_Pa", "p_r_Pa", "p_s_Pa", "x_v")):
        out.append("BAD pressure history not finite")
    s = o.summary()
    if any(isinstance(v, float) and not math.isfinite(v) for v in s.values()):
        out.append("BAD summary not finite")
    if o.drifter.drill is None and o.orbit.impacts == 1:
        dev = _repeats(o)
        if not dev <= 1e-6:
            out.append(f"BAD restarted orbit does not repeat ({dev:.2g})")
    return out or ["ok"]


def _names(msg, key):
    """Whether the refusal ``msg`` names ``key`` (a rod segment's as ``rod.segments``, a section's
    own refusal as ``[section]``)."""
    section = key.split(".")[0]
    return key in msg or (key.startswith("rod.") and "rod" in msg) or f"[{section}]" in msg


def _one_line_naming(fn, keys):
    """``fn`` with a refusal at ``build`` that is not one line naming one of ``keys`` (the mutated
    ones) counted as bad."""
    def run():
        try:
            return fn()
        except ValueError as exc:
            msg = str(exc).strip()
            if "\n" in msg:
                return [f"BAD multi-line error: {msg[:80]!r}"]
            if getattr(exc, "at_build", False) and not any(_names(msg, key) for key in keys):
                return [f"BAD refusal does not name {' or '.join(keys)}: {msg[-100:]!r}"]
            raise
    run.__defaults__ = getattr(fn, "__defaults__", None)
    return run


def circuit_calls(rng, n, slow, case):
    """Mutated circuit configs: build, orbit and the orbit's invariants."""
    from impactbar import physical as ph

    c = Counter()
    bases = _circuit_bases()
    weights = np.array([w for *_, w in bases], dtype=float)
    for _ in range(n):
        name, base, _w = bases[rng.choice(len(bases), p=weights / weights.sum())]
        keys = [k for k in _flat_keys(base)]
        cfg, hows = base, []
        mutated = []
        for _ in range(int(rng.integers(1, 3))):
            key = keys[rng.integers(len(keys))]
            mutated.append(key)
            try:
                cfg, how = _mutate(rng, cfg, key)
            except ValueError:  # (a key left out before)
                continue
            hows.append(f"{key} {how}")

        def one(hows=tuple(hows), name=name, cfg=cfg):
            try:
                d = ph.build(cfg)
            except ValueError as exc:
                exc.at_build = True
                raise
            return circuit_orbit_labels(d.orbit())

        case(c, _one_line_naming(one, mutated), slow)
    return c


def exact_blow_calls(rng, n, slow, case):
    """single_blow(method="exact") with a bit mass and a feed."""
    c = Counter()
    for _ in range(n):
        k = float(10 ** rng.uniform(-1, 1.5))
        a = {"segs": [(float(10 ** rng.uniform(-0.5, 1.3)), float(10 ** rng.uniform(-0.3, 0.3)))
                      for _ in range(int(rng.integers(1, 4)))],
             "k": k, "k_u": k * float(10 ** rng.uniform(0, 1.5)),
             "bit": [0.0, float(10 ** rng.uniform(-2, 0.5))][int(rng.random() < 0.8)],
             "feed": [0.0, float(10 ** rng.uniform(-2.5, -0.3))][int(rng.random() < 0.7)],
             "s": float(10 ** rng.uniform(0, 1.2)), "v": float(10 ** rng.uniform(-1, 1)),
             "t_max": [None, None, float(rng.uniform(2, 30))][rng.integers(3)]}

        def one(a=a):
            law = ib.RodRock(segments=[ib.RodSegment(*g) for g in a["segs"]],
                             rock=ib.BilinearRock(k=a["k"], k_u=a["k_u"]), bit_mass=a["bit"], feed=a["feed"])
            m = ib.BarModel(a["s"], 0.0, 0.0, 0, impact=law)
            b = ib.single_blow(m, a["v"], method="exact", t_max=a["t_max"])
            nums = [b.efficiency, b.work_on_rock, b.max_penetration, b.permanent_penetration,
                    b.rebound_velocity, b.energy_error, b.times[-1]]
            if not np.all(np.isfinite(nums)):
                return ["BAD not finite"]
            out = []
            if not b.energy_error <= 1e-9:
                out.append(f"BAD exact blow's account ({b.energy_error:.2g})")
            if b.ended_by == "failed":
                out.append("BAD no end (failed)")
            # (+inf where the rock has not been loaded past the feed yet, R_max = f: feed_gain)
            if b.ended_by in ("budget", "rings", "may_yield", "t_max") and not b.uncertainty >= 0.0:
                out.append(f"BAD {b.ended_by} without an uncertainty")
            if not -1e-9 <= b.efficiency <= 1.0 + 1e-9:
                out.append("BAD efficiency outside [0, 1]")
            return out or [f"ok ({b.ended_by})"]

        case(c, one, slow)
    return c


def _stepped_config(rng):
    """A config of a hammer, a drifter or a circuit with a stepped piston: lengths and diameters drawn
    (one in five of them weird)."""
    from impactbar import physical as ph

    kind = ["hydraulic-drill", "hydraulic-drifter", "circuit-drifter"][rng.integers(3)]
    cfg, _ = ph.read_config(kind)
    k = int(rng.integers(1, 5))
    total = 448.54236 if kind != "hydraulic-drill" else 450.0
    cuts = np.sort(rng.uniform(0, 1, k - 1))
    lengths = np.diff(np.concatenate(([0.0], cuts, [1.0]))) * total
    lengths = [f"{x:.6g} mm" for x in lengths]
    diam = [f"{45.0 * 10 ** rng.uniform(-0.3, 0.2):.4g} mm" for _ in range(k)]
    if rng.random() < 0.2:
        j = int(rng.integers(k))
        (lengths if rng.random() < 0.5 else diam)[j] = WEIRD_VALUES[rng.integers(len(WEIRD_VALUES))]
    if rng.random() < 0.1:
        diam = diam[:-1] or ["45 mm", "40 mm"]
    # (the hammer's periodic_orbits on a stepped piston of 4 modes take a minute: fewer modes there)
    modes = {"hydraulic-drill": (0, 1, 2), "hydraulic-drifter": (0, 2, 4, 8),
             "circuit-drifter": (0, 0, 2)}[kind]
    changes = {"bar.length": lengths, "bar.diameter": diam,
               "model.n_modes": int(modes[rng.integers(len(modes))])}
    return kind, ph.with_values(cfg, changes)


def stepped_calls(rng, n, slow, case):
    """Stepped pistons in every kind of machine; optimize_piston with random inputs."""
    from impactbar import physical as ph
    from impactbar.physical.rock import RodPiece

    c = Counter()
    for _ in range(n):
        if rng.random() < 0.6:
            kind, cfg = _stepped_config(rng)

            def one(cfg=cfg, kind=kind):
                m = ph.build(cfg)
                if kind == "hydraulic-drill":
                    res = ph.orbits(m)
                    bad = [o for o in res if not (math.isfinite(o.blow_frequency_Hz))]
                    return ["BAD not finite"] if bad else ["ok"]
                o = m.orbit()
                if kind == "circuit-drifter":
                    return circuit_orbit_labels(o)
                s = o.summary()
                finite = all(math.isfinite(v) for v in s.values() if isinstance(v, float))
                if not finite or not o.period_s > 0:
                    return ["BAD drifter orbit not finite"]
                return ["ok"]
        else:
            def u(lo, hi, weird=0.08):
                if rng.random() < weird:
                    return [None, -1.0, 0.0, math.nan, math.inf, "x", 1e300][rng.integers(7)]
                return float(10 ** rng.uniform(lo, hi))

            rod_len = u(-0.3, 1.0, 0.03)
            a = {"rod": [(rod_len, u(-3.3, -2.7, 0.03)) for _ in range(int(rng.integers(1, 3)))],
                 "rock": (3e8, 3e8 * float(10 ** rng.uniform(0, 1.3))) if rng.random() > 0.05 else (3e8, 1e8),
                 "mass": u(0.0, 0.7), "length": u(-0.8, -0.3), "max_stress": [math.inf, u(8.0, 8.7)][
                     rng.integers(2)],
                 "v": u(0.5, 1.2), "segments": [2, 2, 3, 1, 0, 9][rng.integers(6)],
                 "bit": [0.0, u(-0.5, 0.5)][rng.integers(2)],
                 "method": ["slsqp", "nelder-mead"][int(rng.random() < 0.2)],
                 "max_evaluations": [None, 10, 30][rng.integers(3)]}

            def one(a=a):
                rod = [RodPiece(length_m=L, area_m2=A, E_Pa=2.1e11, density_kg_m3=7850.0)
                       for L, A in a["rod"]]
                best = ph.optimize_piston(rod, a["rock"], mass=a["mass"], length=a["length"],
                                          max_stress=a["max_stress"], impact_velocity=a["v"],
                                          segments=a["segments"], bit_mass=a["bit"], method=a["method"],
                                          max_evaluations=a["max_evaluations"], cells=16)
                nums = [best.work_on_rock_J, best.uniform_work_on_rock_J, best.bar.mass_kg]
                if not all(math.isfinite(x) for x in nums):
                    return ["BAD not finite"]
                out = []
                if abs(best.bar.mass_kg - a["mass"]) > 1e-9 * a["mass"]:
                    out.append("BAD piston's mass not kept")
                if abs(best.bar.length_m - a["length"]) > 1e-9 * a["length"]:
                    out.append("BAD piston's length not kept")
                if best.feasible and best.work_on_rock_J < best.uniform_work_on_rock_J * (1 - 1e-6) \
                        and best.uniform_peak_rod_stress_Pa <= best.max_stress_Pa:
                    out.append("BAD optimum below the uniform piston")
                return out or ["ok"]

        case(c, one, slow)
    return c


def warm_up():
    """Compile (or load) the circuit's and the exact blow's kernels once in the parent, so that the
    forked cases do not each do it."""
    from impactbar import physical as ph
    from impactbar.physical.rock import RodPiece

    ph.circuit_preset("circuit-drifter").orbit()
    stepped = {"bar.length": ["150 mm", "298.54236 mm"], "bar.diameter": ["56 mm", "38.3 mm"],
               "model.n_modes": 2}
    ph.build(ph.with_values(ph.read_config("hydraulic-drifter")[0], stepped)).orbit()
    stepped["bar.length"] = ["150 mm", "300 mm"]
    ph.orbits(ph.build(ph.with_values(ph.read_config("hydraulic-drill")[0], stepped)))
    ph.optimize_piston([RodPiece(length_m=3.0, area_m2=1e-3, E_Pa=2.1e11, density_kg_m3=7850.0)], (3e8, 3e9),
                       mass=2.355, length=0.3, max_stress=2.5e8, impact_velocity=10.0, segments=2,
                       max_evaluations=4, cells=16)
    law = ib.RodRock(segments=[ib.RodSegment(4.0, 1.0)], rock=ib.BilinearRock(k=2.0, k_u=20.0), bit_mass=0.3,
                     feed=0.05)
    ib.single_blow(ib.BarModel(2.0, 0.0, 0.0, 0, impact=law), 1.0, method="exact")
