r"""Probe: the documented drifter search (docs/optimising_a_drifter.md) on a finer lattice blow.

The page's search (``bench_optimize_drifter.py``'s problem: six variables of
``examples/circuit_drifter_rock_piston.toml``, drilling rate per kW, peak rod stress at most 250 MPa,
drilling rate at least 2.5 m/min, COBYLA, 30 designs) stops next to a border of the one-impact orbit
that is the 8-cell lattice blow's: the piston's re-contact with the shank moves by one step. This
probe runs the same search on a copy of the example (written to ``--dir``) with ``[rock]
cells_per_piston = --cells`` and, with ``--inside``, the rod-rock law's ``contact_events="inside"``
(the re-contact located inside its step; not a config key, so the law is patched in this process).

It prints: the designs evaluated, those without an operating point, the gain over the same config's
baseline, the certificate (verdict, KKT residual, active set, bounds, multipliers, border), the
search's CPU and wall seconds, the reported design and a fresh ``evaluate_design`` of it (feasible,
the objective, each constraint's scaled margin). With ``--along S1,S2,...``, where the certificate
is not converged: fresh orbits (each continued from the previous) along the projected gradient
:math:`p = g + \sum_i \lambda_i \nabla m_i` of the certificate (the active margins held to first
order; steps in units of the scaled variables' spans), the objective against its first-order rise
and the drilling rate, or the error where the design has no one-impact orbit; with ``--at-cells``
the same designs on copies of the config at those cell counts (is a jump the lattice's?).

Run: ``python benchmarks/probes/optimize_cells16.py [--cells 16] [--inside] [--max-evaluations 30]
[--along 0.002,0.004,...] [--at-cells 32] [--dir /tmp/...] [--out result.json]
[--from result.json]``; ``--compare page,result.json --at-cells 8,16,64``: designs on a common
lattice, no search.

Measured on 5bc09748 (benchmarks/HISTORY.md, "the documented search on a finer lattice blow"): at 16
cells 30 designs, none without an orbit, +13.22 %, "stopped at a budget" (KKT residual 0.107, the
drilling rate active, multiplier 0.326), feasible by a fresh orbit; along the projected gradient a
border at 0.0024 to 0.0025 of the spans, at 0.0006 to 0.0008 on 32 cells, none to 0.006 on 64;
``--cells 64``: +14.40 %, budget (KKT residual 0.128), a border of its own at 0.0018 to 0.002.
"""

from __future__ import annotations

import argparse
import functools
import json
import re
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench_optimize_drifter import CONSTRAINTS, EXAMPLE, VARY  # noqa: E402

from impactbar.physical import build, optimize_drifter, read_config, with_values  # noqa: E402


def _config(cells: int, folder: Path) -> Path:
    """The example with ``cells_per_piston = cells``, written under ``folder``, without its
    ``contact_events`` (the lattice's ``"step"``, where this probe measured; ``--inside`` patches the law)."""
    text = re.sub(r'(?m)^contact_events = "[a-z]+"\n', "", EXAMPLE.read_text())
    new, n = re.subn(r"(?m)^cells_per_piston = \d+$", f"cells_per_piston = {cells}", text)
    if n != 1:
        raise ValueError(f"the example must set rock.cells_per_piston once; found {n}")
    path = folder / f"circuit_drifter_rock_piston_cells{cells}.toml"
    path.write_text(new)
    return path


def _fresh(path: Path, changes: dict, guess=None):
    """A fresh ``evaluate_design`` of ``changes`` on ``path`` under the search's constraints."""
    from impactbar.physical.optimize_problem import DEFAULT_CONSTRAINTS, _limits, evaluate_design

    cfg, folder = read_config(path)
    kept = dict.fromkeys(DEFAULT_CONSTRAINTS) | _limits(CONSTRAINTS, build(cfg, folder), ideal=False)
    return evaluate_design(build(with_values(cfg, changes), folder), kept, guess=guess)


def _along(path: Path, res, steps: list, at_cells: list) -> None:
    """Fresh orbits along the certificate's projected gradient from the reported design, on the
    search's config and on copies of it at each of ``at_cells`` cells a piston."""
    from impactbar.physical.design_keys import design_bounds

    cert, fkey = res.certificate, "drilling_rate_per_kW"
    cfg, folder = read_config(path)
    spec = design_bounds(cfg, VARY, folder)
    keys = list(spec)
    lo = np.array([spec[k]["low"] for k in keys])
    span = np.array([spec[k]["high"] - spec[k]["low"] for k in keys])
    u0 = (np.array([res.optimum["values"][k] for k in keys]) - lo) / span
    p = np.array(cert.objective_gradient, dtype=float)
    for name, lam in cert.multipliers.items():
        if name in cert.constraint_gradients:
            p = p + lam * np.array(cert.constraint_gradients[name], dtype=float)
    for key, side in cert.bounds.items():  # (a bound's margin u_j or 1 - u_j; held, not crossed)
        j = keys.index(key)
        p[j] += cert.multipliers.get(f"{key} {side}", 0.0) * (1.0 if side == "low" else -1.0)
        if (p[j] < 0.0) == (side == "low"):
            p[j] = 0.0
    norm = float(np.linalg.norm(p))
    print(f"projected gradient: norm {norm:.5g} per span, direction "
          + ", ".join(f"{k.split('.')[-1]} {x:+.3f}" for k, x in zip(keys, p / norm, strict=True)))
    for where in [path, *(_config(n, path.parent) for n in at_cells)]:
        print(f"along it on {where.name}:")
        prev, base = None, res.optimum["objectives"][fkey]
        for s in [0.0, *steps]:
            u = u0 + s * p / norm
            changes = {k: f"{float(x)!r} {spec[k]['unit']}" for k, x in zip(keys, lo + span * u, strict=True)}
            c0 = time.process_time()
            try:
                rec, prev = _fresh(where, changes, guess=prev)
            except ValueError as e:
                print(f"  s {s:.4f}: no orbit ({str(e)[:110]})", flush=True)
                continue
            f = rec["objectives"][fkey]
            if s == 0.0:  # (the rise on each lattice from its own figure at the design)
                base = f
            rise = f"{(f - base) / (s * norm):.4f}" if s else "-"
            print(f"  s {s:.4f}: {fkey} {f:.7f} (first-order {base + s * norm:.7f}, ratio of rises "
                  f"{rise}), drilling rate {rec['objectives']['drilling_rate_m_min']:.6f} m/min, "
                  f"feasible {rec['feasible']}, {time.process_time() - c0:.1f} s CPU", flush=True)


def _compare(folder: Path, designs: list, cells: list) -> None:
    """Each design (a result written by ``--out``, or ``page``: the page's design,
    ``tests/physical/drifter_optimum.py``) by a fresh ``evaluate_design`` at each cell count."""
    for name in designs:
        if name == "page":
            sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "physical"))
            from drifter_optimum import OPTIMUM as changes
        else:
            changes = json.loads(Path(name).read_text())["optimum"]["changes"]
        for n in cells:
            c0 = time.process_time()
            try:
                rec, _ = _fresh(_config(n, folder), changes)
            except ValueError as e:
                print(f"{name} at {n} cells: no orbit ({str(e)[:100]})", flush=True)
                continue
            f = rec["objectives"]
            print(f"{name} at {n} cells: drilling_rate_per_kW {f['drilling_rate_per_kW']:.7f}, "
                  f"drilling rate {f['drilling_rate_m_min']:.6f} m/min, feasible "
                  f"{rec['feasible']}, {time.process_time() - c0:.1f} s CPU", flush=True)


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cells", type=int, default=16)
    p.add_argument("--inside", action="store_true", help='the law\'s contact_events="inside"')
    p.add_argument("--max-evaluations", type=int, default=30)
    p.add_argument("--along", default="", help="comma-separated steps along the projected gradient")
    p.add_argument("--at-cells", default="", help="comma-separated cell counts to repeat --along on")
    p.add_argument("--compare", default="", help="comma-separated results (--out) or 'page': each "
                   "design's fresh orbit at each of --at-cells; no search")
    p.add_argument("--dir", default=None, help="where the config's copy is written (a temporary folder)")
    p.add_argument("--out", default=None)
    p.add_argument("--from", dest="read", default=None,
                   help="a result written by --out: no search, only --along from its design")
    args = p.parse_args(argv)
    if args.inside:
        import impactbar.physical.rock as rock

        rock.RodRock = functools.partial(rock.RodRock, contact_events="inside")
    folder = Path(args.dir) if args.dir else Path(tempfile.mkdtemp())
    folder.mkdir(parents=True, exist_ok=True)
    path = _config(args.cells, folder)
    steps = [float(s) for s in args.along.split(",") if s]
    at_cells = [int(n) for n in args.at_cells.split(",") if n]
    if args.compare:
        _compare(folder, args.compare.split(","), at_cells)
        return
    if args.read:  # (the search's result read back)
        done = json.loads(Path(args.read).read_text())
        res = SimpleNamespace(optimum=done["optimum"], certificate=SimpleNamespace(**done["certificate"]))
        _along(path, res, steps, at_cells)
        return
    build(*read_config(path)).orbit()  # compiles (numba cache) outside the timing
    t, c0 = time.perf_counter(), time.process_time()
    res = optimize_drifter(path, VARY, objective="drilling_rate_per_kW", constraints=CONSTRAINTS,
                           max_evaluations=args.max_evaluations, method="cobyla", progress=False)
    cpu, wall = time.process_time() - c0, time.perf_counter() - t
    print(res.table())
    failed = [r for r in res.history if not r.get("ok")]
    cert = res.certificate
    print(f"cells {args.cells}{' inside' if args.inside else ''}: {res.evaluations} designs evaluated, "
          f"{len(failed)} without an operating point, gain {res.gain:+.3%}, {wall:.0f} s wall, "
          f"{cpu:.0f} s CPU; {res.message}")
    print(f"certificate: {cert.verdict}, KKT residual {cert.residual:.4g}, active {cert.active}, "
          f"bounds {cert.bounds}, multipliers {cert.multipliers}, border {cert.border!r}")
    print(f"design: {res.optimum['changes']}")
    c1 = time.process_time()
    rec, _ = _fresh(path, res.optimum["changes"])
    print(f"fresh orbit: feasible {rec['feasible']}, drilling_rate_per_kW "
          f"{rec['objectives']['drilling_rate_per_kW']:.7f} (the search's "
          f"{res.optimum['objectives']['drilling_rate_per_kW']:.7f}), scaled margins "
          + ", ".join(f"{k} {c['scaled']:.3g}" for k, c in rec["constraints"].items())
          + f"; {time.process_time() - c1:.1f} s CPU")
    if args.out:
        res.to_json(args.out)
    if steps:
        _along(path, res, steps, at_cells)


if __name__ == "__main__":
    main()
