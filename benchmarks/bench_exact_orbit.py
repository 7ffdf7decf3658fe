"""The circuit on rock's orbit with the default lattice blows against the exact blows: the cost of each
and how far the default is from the exact orbit.

On ``examples/circuit_drifter_rock.toml``: the orbit as the example gives it (the lattice's blows at its
``cells_per_piston``, the default) and with the exact blows (``RodRock(method="exact")``, the rod as
given), each after one untimed solve (compilation, caches), in CPU seconds (the best of ``--reps``);
then the relative differences of the blow frequency, the impact velocity, the work dissipated in the
rock, the penetration and the mean supply pressure between the two.

The rows the goals read (``bench_circuit.py --goals``): ``exact / default cost (x)`` (the goal at most
10) and ``default's distance from the exact orbit`` (the largest of the relative differences; the goal
at most 1e-5).

Run: ``python benchmarks/bench_exact_orbit.py [--reps N]``. ``--against SRC`` runs the same in fresh
processes on the package tree ``SRC`` (e.g. ``git worktree add /tmp/old <commit>`` then ``--against
/tmp/old/src``) and on this one, alternately (``--rounds`` each), and prints both trees' rows side by
side, the baseline's first, with the largest relative difference of the exact orbit's compared
figures between the trees, and of its multipliers' moduli relative to the largest.
"""

from __future__ import annotations

import dataclasses
import json
import time
from pathlib import Path

from _timing import against_parser, example_drifter, fresh_runs  # this folder's shared runner of two trees

EXAMPLE = Path(__file__).parents[1] / "examples" / "circuit_drifter_rock.toml"


def figures(point) -> dict:
    """The compared numbers of an operating point."""
    rock = point.rock()
    return {"blow frequency": point.blow_frequency_Hz, "impact velocity": point.impact_velocity_m_s,
            "work on rock": rock["work_on_rock_J"], "penetration": rock["penetration_mm"],
            "mean supply pressure": point.mean_supply_pressure_Pa}


def solve(drifter, model, reps: int):
    """The operating point with ``model``'s blows, and the best CPU seconds of its orbit."""
    from impactbar import find_orbit
    from impactbar.physical.circuit import CircuitDrifterOrbit

    find_orbit(model, drifter.drive())  # (untimed: compilation, caches)
    best = float("inf")
    for _ in range(reps):
        t = time.process_time()
        orbit = find_orbit(model, drifter.drive())
        best = min(best, time.process_time() - t)
    return CircuitDrifterOrbit(drifter, orbit), best


def measure(reps: int) -> dict:
    """Both orbits' CPU seconds and figures, and the exact orbit's multipliers' moduli."""

    drifter = example_drifter(EXAMPLE)
    model = drifter.model()
    exact = model.with_(impact=dataclasses.replace(model.law, method="exact"))
    default, t_default = solve(drifter, model, reps)
    precise, t_exact = solve(drifter, exact, reps)
    return {"t_default": t_default, "t_exact": t_exact, "default": figures(default),
            "exact": figures(precise), "moduli": [abs(complex(m)) for m in precise.orbit.multipliers]}


def against(src, rounds: int, reps: int) -> None:
    """Both trees' rows side by side (module docstring), each the best of ``rounds`` processes."""
    runs = fresh_runs(__file__, src, rounds, args=("--reps", str(reps)))
    rows = {}
    for name, outs in runs.items():
        t_d = min(r["t_default"] for r in outs)
        t_e = min(r["t_exact"] for r in outs)
        d, e = outs[0]["default"], outs[0]["exact"]
        rows[name] = (t_d, t_e, t_e / t_d, max(abs(d[k] - e[k]) / abs(e[k]) for k in e))
    old, new = runs["baseline"][0], runs["new"][0]
    moved = max(abs(old["exact"][k] - new["exact"][k]) / abs(old["exact"][k]) for k in old["exact"])
    # (the multipliers relative to the largest: those at rounding, 1e-17, differ by their whole size)
    radius = max(old["moduli"])
    turned = max(abs(x - y) / radius for x, y in zip(old["moduli"], new["moduli"], strict=True))
    b, n = rows["baseline"], rows["new"]
    print(f"the circuit on rock ({EXAMPLE.name})")
    print(f"{'(best of ' + str(rounds) + ' processes each)':46s} {'baseline':>12s} {'new':>12s}")
    print(f"{'default orbit CPU s':46s} {b[0]:12.3f} {n[0]:12.3f}")
    print(f"{'exact orbit CPU s':46s} {b[1]:12.3f} {n[1]:12.3f}")
    print(f"exact / default cost (x) {b[2]:.1f} {n[2]:.1f}")
    print(f"default's distance from the exact orbit {b[3]:.3g} {n[3]:.3g}")
    print(f"the exact orbit's figures between the trees (largest rel. diff) {moved:.2e}")
    print(f"the exact orbit's multipliers between the trees (of the largest) {turned:.2e}")


def main(argv=None) -> int:
    args = against_parser(__doc__, "orbits", rounds=1).parse_args(argv)
    if args.json:
        print(json.dumps(measure(args.reps)))
        return 0
    if args.against:
        against(args.against, args.rounds, args.reps)
        return 0
    out = measure(args.reps)
    t_default, t_exact, a, b = out["t_default"], out["t_exact"], out["default"], out["exact"]
    head = f"the circuit on rock ({EXAMPLE.name})"
    print(f"{head:46s} {'default':>12s} {'exact':>12s} {'rel. diff':>10s}")
    worst = 0.0
    for key in a:
        diff = abs(a[key] - b[key]) / abs(b[key])
        worst = max(worst, diff)
        print(f"{key:46s} {a[key]:12.6g} {b[key]:12.6g} {diff:10.2e}")
    print(f"{'orbit CPU s (best of ' + str(args.reps) + ')':46s} {t_default:12.3f} {t_exact:12.3f}")
    print(f"exact / default cost (x) {t_exact / t_default:.1f}")
    print(f"default's distance from the exact orbit {worst:.3g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
