"""The fuzz campaign's categories of a designer's changes and searches (imported by
``fuzz_campaign.py``, whose ``case`` runs each in a forked child with a time limit).

- ``change_sets``: one to four of a problem's parameters (the rod-rock law under a cosine load, the
  oil circuit's drive of the preset) changed together by ``with_parameters``, to multiples of their
  values or weird values, in one order and in the reverse: both orders must agree (the same problem,
  or both refused), the result must equal the changes applied one by one where each of those is
  accepted, and a refusal must be one ``ValueError`` line naming one of the changed parameters.
- ``optimizer_args``: ``optimize_drifter`` on the circuit preset with weird ``rhobeg``, ``tol``,
  ``max_evaluations``, ``method``, ``popsize``, ``seed``, ``workers``, bounds, objectives and
  constraint limits; the orbit solver replaced by one that stops the case where it is reached, so
  that a case is either refused before any solve in one ``ValueError`` line naming an argument, or
  reaches the solve ("ok").
"""

from __future__ import annotations

import math
from collections import Counter

#: Weird values of a parameter or an argument.
ODD = [0, -1, 0.5, 5e-324, 1e-300, 1e308, math.nan, math.inf, -math.inf, True, "1", None, 2**63, 1 + 1j,
       [1.0], 10**400]


def _problems():
    from impactbar import BarModel, BilinearRock, CosineLoad, RodRock, RodSegment
    from impactbar.physical import circuit_preset

    law = RodRock(segments=[RodSegment(length=2.0, impedance=2.0)], rock=BilinearRock(k=20.0, k_u=200.0))
    d = circuit_preset("circuit-drifter")
    return [(BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=law), CosineLoad(0.3, 1.0)),
            (d.model(), d.drive())]


def _outcome(fn):
    """``("ok", result)`` or ``("refused", message)``; other exceptions propagate."""
    try:
        return "ok", fn()
    except ValueError as exc:
        return "refused", str(exc)


def change_set_calls(rng, n, slow, case):
    from impactbar.parameters import parameters, with_parameter, with_parameters

    c = Counter()
    problems = _problems()
    for _ in range(n):
        model, forcing = problems[rng.integers(len(problems))]
        table = parameters(model, forcing)
        names = list(table)
        chosen = [names[i] for i in rng.choice(len(names), size=min(len(names), int(rng.integers(1, 5))),
                                               replace=False)]
        changes = {}
        for name in chosen:
            value = table[name].value
            if rng.random() < 0.15 or value is None:
                changes[name] = ODD[rng.integers(len(ODD))]
            else:
                changes[name] = type(value)(value * float(2.0 ** rng.uniform(-3, 3))) \
                    if isinstance(value, float) else value

        def one(model=model, forcing=forcing, changes=changes):
            forward = _outcome(lambda: with_parameters(model, forcing, changes))
            backward = _outcome(lambda: with_parameters(model, forcing, dict(reversed(changes.items()))))
            if forward[0] != backward[0]:
                return [f"BAD order matters: {forward[0]} one way, {backward[0]} the other, {changes!r}"]
            if forward[0] == "refused":
                msg = forward[1].strip()
                if "\n" in msg:
                    return [f"BAD multi-line error: {msg[:80]!r}"]
                if not any(name.split(".")[-1] in msg for name in changes):
                    return [f"BAD refusal names none of {list(changes)}: {msg[:100]!r}"]
                return ["ValueError"]
            if forward[1] != backward[1]:
                return [f"BAD the orders give different problems: {changes!r}"]
            m, f = model, forcing  # one by one, where each step is accepted: the same problem
            for name, value in changes.items():
                step = _outcome(lambda m=m, f=f, name=name, value=value: with_parameter(m, f, name, value))
                if step[0] == "refused":
                    return ["ok"]
                m, f = step[1]
            return ["ok"] if (m, f) == forward[1] else [f"BAD the set differs from the steps: {changes!r}"]

        case(c, one, slow)
    return c


class _Solved(Exception):
    """Raised where an accepted case reaches the orbit solver."""


def _arguments(rng) -> dict:
    """Keyword arguments of ``optimize_drifter``, each weird with some probability."""
    def maybe(good, p=0.3):
        return ODD[rng.integers(len(ODD))] if rng.random() < p else good

    lo, hi = float(rng.uniform(50, 70)), float(rng.uniform(70, 100))
    vary = {"supply.pump_flow": (maybe(f"{lo:.3g} L/min", 0.15), maybe(f"{hi:.3g} L/min", 0.15))}
    if rng.random() < 0.4:
        key = ["accumulator.precharge", "chambers.rear_area", "stop.restitution", "model.n_modes",
               "valve.switch_out", "oil.colour"][rng.integers(6)]
        vary[key] = {"accumulator.precharge": ("7 MPa", "13 MPa"), "chambers.rear_area": ("5 cm^2", "6 cm^2"),
                     "stop.restitution": (0.1, 0.3), "model.n_modes": (0, 2),
                     "valve.switch_out": ("20 mm", "23 mm"), "oil.colour": (1, 2)}[key]
    limit = maybe(["23.7 MPa", "2.4e7 Pa", "18", "inf", "nan", "24 L"][rng.integers(6)], 0.1)
    return dict(vary=vary, objective=maybe("impact_power", 0.1),
                constraints=maybe({"mean_supply_pressure": limit}, 0.1) if rng.random() < 0.5 else None,
                max_evaluations=maybe(int(rng.integers(1, 20))), rhobeg=maybe(float(rng.uniform(0.01, 0.5))),
                tol=maybe(float(10 ** rng.uniform(-6, -1))),
                method=maybe(["cobyla", "slsqp", "population"][rng.integers(3)], 0.1),
                popsize=maybe(int(rng.integers(2, 8)), 0.1), seed=maybe(int(rng.integers(100)), 0.1),
                workers=maybe(None, 0.1))


def optimizer_calls(rng, n, slow, case):
    c = Counter()
    for _ in range(n):
        kwargs = _arguments(rng)

        def one(kwargs=kwargs):
            from impactbar import physical
            from impactbar.physical import optimize_drifter

            def solved(*args, **kw):
                raise _Solved

            physical.CircuitDrifter.orbit = solved  # (in the forked child only)
            try:
                optimize_drifter("circuit-drifter", progress=False, **kwargs)
            except _Solved:
                return ["ok"]
            except ValueError as exc:
                msg = str(exc).strip()
                if "\n" in msg:
                    return [f"BAD multi-line error: {msg[:80]!r}"]
                named = [*kwargs, *kwargs["vary"], "constraint", "mean_supply_pressure", "bound", "vary"]
                if not any(name in msg for name in named):
                    return [f"BAD refusal names no argument: {msg[:100]!r}"]
                return ["ValueError"]
            return ["BAD finished without a solve"]

        case(c, one, slow)
    return c
