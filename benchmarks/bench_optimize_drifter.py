"""Benchmark: ``optimize_drifter`` on the example rock drifter with its piston given by its shape
(examples/circuit_drifter_rock_piston.toml, the piston and circuit of examples/circuit_drifter_rock.toml)
over six variables (collar, front rod and rear rod diameters, rear chamber volume, switch point,
pre-charge) for drilling rate per hydraulic kilowatt, beside one baseline evaluation (a fresh ``orbit()``
of the start) in the same run.

Run: ``python benchmarks/bench_optimize_drifter.py [--max-evaluations N] [--out result.json]
[--cache cache.json] [--keys K1,K2,...] [--method cobyla|slsqp|differential_evolution|multistart]
[--sample N] [--local-starts K] [--workers W] [--quick]``; ``--keys four`` is the four variables of the
speed goal (the three diameters and the switch point). Prints the wall times, the number of
evaluations and the design table; nothing is asserted. A stopped run resumes from ``--cache``.

With ``--method multistart`` (a Sobol sample of ``--sample`` designs, COBYLA from the
``--local-starts`` best feasible ones) it prints too the designs evaluated, those without an operating
point and the seconds they cost, the certificate's verdict, the gain and each local search's best
design. ``--quick``: two variables (switch point, pre-charge), a sample of 8, one local search, 16
designs at most (a check that it runs, in minutes).

``--against REF`` runs the same search on the git ref ``REF`` (its ``src`` exported by ``git archive``,
or a tree's ``src`` folder, its numba caches kept) and on this tree, each in a fresh process, and
prints side by side the designs evaluated (and continued from a neighbour), those without an operating
point and the CPU seconds they cost (the evaluations that raised and their records' classification,
timed in the search's process; a sample's designs on workers by their records' seconds), apart the
classification after the search of the designs the result lists (a tree that classifies none in
the search), all designs' CPU seconds, the wall and CPU time of the call, the certificate's verdict
and KKT residual (``none`` on a tree without one) and the gain, e.g. ``--against 15d5b20`` (before
the certificate, the stall test and the failures' classification). With ``--cache FILE`` each tree
writes its own cache file, started empty (``FILE`` with the tree's tag before its suffix), and the
rows add the seconds of the cache's writes, of the certificate, and the file's bytes.
"""

from __future__ import annotations

import argparse
import contextlib
import hashlib
import inspect
import json
import sys
import time
from pathlib import Path

from impactbar.physical import build, optimize_drifter, read_config
from impactbar.physical.optimize_drifter import OBJECTIVES

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "circuit_drifter_rock_piston.toml"

#: The problem of docs/optimising_a_drifter.md.
VARY = {
    "piston.collar_diameter": ("47 mm", "52 mm"),
    "piston.front_rod_diameter": ("43 mm", "47 mm"),
    "piston.rear_rod_diameter": ("38 mm", "43 mm"),
    "chambers.rear_volume": ("0.06 L", "0.2 L"),
    "valve.switch_out": ("18 mm", "25 mm"),
    "accumulator.precharge": ("8 MPa", "14 MPa"),
}
#: The four variables of the speed goal: the piston's three diameters and the switch point.
FOUR = ("piston.collar_diameter", "piston.front_rod_diameter", "piston.rear_rod_diameter", "valve.switch_out")
#: ``--quick``: the switch point and the pre-charge.
QUICK = ("valve.switch_out", "accumulator.precharge")
CONSTRAINTS = {"peak_rod_stress": "250 MPa", "min_drilling_rate": "2.5 m/min"}


@contextlib.contextmanager
def _phases():
    """The wall seconds of the multistart's phases: the sample's designs computed together
    (``compute_new``, on the workers) and the polish (``polish_search``); the local searches and the
    rest (the fresh re-evaluation, the certificate) are the call's wall time less those. Under
    ``"<phase> CPU"`` the CPU seconds this process spent in each (the workers' not counted). Apart,
    the certificate (``certify_search``, its gradient on the workers on a tree that keeps them open)
    and the cache file's writes (a tree's ``write_cache``, the whole file, or its log's lines)."""
    import impactbar.physical.optimize_cache as cache
    import impactbar.physical.optimize_multistart as multistart

    module = inspect.getmodule(optimize_drifter)
    walls = {f"{phase}{cpu}": 0.0 for phase in ("sample", "polish", "certificate", "cache writes")
             for cpu in ("", " CPU")}
    saved = [(multistart, "compute_new", "sample"), (module, "polish_search", "polish"),
             (module, "certify_search", "certificate"), (module, "write_cache", "cache writes"),
             *((getattr(cache, "DesignCache", None), n, "cache writes") for n in ("_write", "rewrite"))]

    def timed(fn, phase):
        def wrapper(*args, **kwargs):
            t0, c0 = time.perf_counter(), time.process_time()
            try:
                return fn(*args, **kwargs)
            finally:
                walls[phase] += time.perf_counter() - t0
                walls[f"{phase} CPU"] += time.process_time() - c0
        return wrapper

    kept = [(m, n, phase, getattr(m, n)) for m, n, phase in saved if m is not None and hasattr(m, n)]
    for m, n, phase, fn in kept:
        setattr(m, n, timed(fn, phase))
    try:
        yield walls
    finally:
        for m, n, _, fn in kept:
            setattr(m, n, fn)


def _multistart_summary(res) -> None:
    """The multistart's designs, its failures and their cost, the certificate, the gain, each local
    search's best design."""
    failed = [r for r in res.history if not r.get("ok")]
    cert, lost = res.certificate, sum(r.get("seconds", 0.0) for r in failed)
    print(f"multistart: {len(res.history)} designs evaluated ({res.evaluations} new, {res.cached} cached), "
          f"{len(failed)} without an operating point costing {lost:.1f} s of the designs' "
          f"{sum(r.get('seconds', 0.0) for r in res.history):.1f} s (each design's own time); certificate "
          f"{cert.verdict if cert is not None else 'none'}"
          f"{f' (KKT residual {cert.residual:.3g})' if cert is not None else ''}; gain {res.gain:+.2%}")
    scored = [r["border"] for r in failed if "border" in r]  # (the border model's; none on a tree without)
    print(f"border model: {len(scored)} of the {len(failed)} scored by their nearest success's "
          f"extrapolation ({sum(b['located'] == 'margin' for b in scored)} located by the multiplier's "
          f"margin, the others at a border radius), from {len({b['nearest'] for b in scored})} successes' "
          "gradients")
    from impactbar.physical.optimize_multistart import found_table

    print(found_table(res.found, res.vary, OBJECTIVES[res.objective][0]))


@contextlib.contextmanager
def _timed_designs():
    """The CPU seconds of the search's evaluations in this process: ``evaluate_design``'s calls (each
    whether it raised), the failed records' (their motion classified, on a tree that classifies it
    there) and, after the search, the classification of the designs the result lists
    (``classify_listed``, on a tree that leaves it to then), as the search module looks them up (on
    any tree: a name missing there is not timed)."""
    module = inspect.getmodule(optimize_drifter)
    calls = {"ok": 0.0, "failed": 0.0, "n_failed": 0, "classified": 0.0}
    bucket = {"evaluate_design": "ok", "failed_record": "failed", "classify_listed": "classified"}

    def timed(fn, name: str):
        def wrapper(*args, **kwargs):
            c0 = time.process_time()
            try:
                out = fn(*args, **kwargs)
            except Exception:
                calls["failed"] += time.process_time() - c0
                raise
            calls[bucket[name]] += time.process_time() - c0
            calls["n_failed"] += name == "failed_record"
            return out
        return wrapper

    saved = {n: getattr(module, n) for n in bucket if hasattr(module, n)}
    for name, fn in saved.items():
        setattr(module, name, timed(fn, name))
    try:
        yield calls
    finally:
        for name, fn in saved.items():
            setattr(module, name, fn)


def summary(res, wall: float, cpu: float, calls: dict, walls: dict | None = None) -> dict:
    """The figures ``--against`` compares: designs, failures and their cost, certificate, gain, and
    with ``walls`` (:func:`_phases`') the multistart's phases' wall and CPU seconds."""
    failed = [r for r in res.history if not r.get("ok")]
    cert = getattr(res, "certificate", None)
    return {"designs evaluated": res.evaluations, "continued from a neighbour": sum(
                r.get("continued", False) for r in res.history),
            "without an operating point": len(failed),
            "their CPU s": calls["failed"],
            "the listed classified CPU s": calls["classified"],
            "their recorded s": sum(r.get("seconds", 0.0) + r.get("motion_seconds", 0.0) for r in failed),
            "all designs CPU s": calls["ok"] + calls["failed"], "wall s": wall, "CPU s": cpu,
            **({} if walls is None else {"sample wall s": walls["sample"], "polish wall s": walls["polish"],
                                         "polish CPU s": walls["polish CPU"], "the rest wall s": wall
                                         - walls["sample"] - walls["polish"], "the rest CPU s": cpu
                                         - walls["sample CPU"] - walls["polish CPU"],
                                         "certificate wall s": walls["certificate"],
                                         "certificate CPU s": walls["certificate CPU"],
                                         "cache writes wall s": walls["cache writes"],
                                         "cache writes CPU s": walls["cache writes CPU"]}),
            "certificate": cert.verdict if cert is not None else "none",
            "KKT residual": cert.residual if cert is not None else None,
            "gain %": 100.0 * res.gain, OBJECTIVES[res.objective][0]: res.optimum["objectives"][
                OBJECTIVES[res.objective][0]],
            "optimum (its changes' digest)": hashlib.sha1(json.dumps(res.optimum["changes"], sort_keys=True)
                                                          .encode()).hexdigest()[:12]}


def against(ref: str, args: list) -> None:
    """This script's search on the tree of ``ref`` and on this one, fresh processes, side by side."""
    from _timing import fresh_runs, ref_tree

    src = ref if Path(ref).is_dir() else ref_tree(ref)
    runs = fresh_runs(__file__, src, 1, args)
    base, new = runs["baseline"][0], runs["new"][0]
    print(f"{'':30s} {ref[:12]:>14s} {'this tree':>14s}")
    for key in new:
        row = []
        for r in (base, new):
            v = r.get(key)
            row.append(f"{v:14.4g}" if isinstance(v, float) else f"{'-' if v is None else v!s:>14s}")
        print(f"{key:30s} {' '.join(row)}")


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--max-evaluations", type=int, default=30)
    p.add_argument("--out", default=None)
    p.add_argument("--cache", default=None)
    p.add_argument("--any-rate", action="store_true",
                   help="drop the constraint on the drilling rate (the per-kW optimum then drills slower)")
    p.add_argument("--keys", default=None, help="a comma-separated subset of the variables, or 'four'")
    p.add_argument("--method", default="cobyla")
    p.add_argument("--popsize", type=int, default=5)
    p.add_argument("--sample", type=int, default=256)
    p.add_argument("--local-starts", type=int, default=3)
    p.add_argument("--workers", type=int, default=None)
    p.add_argument("--polish", type=int, default=12, help="multistart: the polish's most designs (0: none)")
    p.add_argument("--seed", type=int, default=0, help="multistart: the sample's seed")
    p.add_argument("--quick", action="store_true", help="multistart on two variables, a sample of 8")
    p.add_argument("--against", metavar="REF", help="the same search on the git ref REF (e.g. 15d5b20) or a "
                   "tree's src folder, side by side")
    p.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # (--against's child)
    args = p.parse_args(argv)
    if args.against:
        rest = list(argv if argv is not None else sys.argv[1:])
        i = rest.index("--against")
        against(args.against, rest[:i] + rest[i + 2:])
        return
    if args.quick:
        args.method, args.keys, args.sample, args.local_starts = "multistart", ",".join(QUICK), 8, 1
        args.max_evaluations = 16
    if args.json and args.cache:  # (--against's child: each tree its own cache file, started empty)
        import impactbar

        tree = hashlib.sha1(str(Path(impactbar.__file__).parent).encode()).hexdigest()[:8]
        args.cache = str(Path(args.cache).with_suffix(f".{tree}{Path(args.cache).suffix}"))
        Path(args.cache).unlink(missing_ok=True)
    keys = FOUR if args.keys == "four" else (args.keys.split(",") if args.keys else tuple(VARY))
    vary = {k: VARY[k] for k in keys}
    config, folder = read_config(EXAMPLE)
    drifter = build(config, folder)
    drifter.orbit()  # compiles (numba cache) outside the timing
    t = time.perf_counter()
    drifter.orbit()
    one = time.perf_counter() - t
    t = time.perf_counter()
    constraints = {**CONSTRAINTS, "min_drilling_rate": None} if args.any_rate else CONSTRAINTS
    c0 = time.process_time()
    with _timed_designs() as calls, _phases() as walls:
        res = optimize_drifter(EXAMPLE, vary, objective="drilling_rate_per_kW", constraints=constraints,
                               max_evaluations=args.max_evaluations, cache=args.cache, method=args.method,
                               popsize=args.popsize, progress=False, workers=args.workers,
                               **({"sample": args.sample, "local_starts": args.local_starts,
                                   "seed": args.seed, "polish": args.polish}
                                  if args.method == "multistart" else {}))
    cpu = time.process_time() - c0
    wall = time.perf_counter() - t
    if args.json:
        done = summary(res, wall, cpu, calls, walls if args.method == "multistart" else None)
        print(json.dumps(dict(done, **({"cache file bytes": Path(args.cache).stat().st_size} if args.cache
                                       else {}))))
        return
    print(res.table())
    print(f"one baseline evaluation (fresh orbit): {one:.1f} s; optimize_drifter ({args.method}, "
          f"{len(vary)} variables): {wall:.0f} s wall, {cpu:.0f} s CPU, "
          f"{res.evaluations} evaluations ({res.cached} cached), {res.gradients} gradients, "
          f"{sum(r.get('continued', False) for r in res.history)} continued from a neighbour; {res.message}")
    done = summary(res, wall, cpu, calls)
    print(f"designs evaluated {done['designs evaluated']} ({done['continued from a neighbour']} continued), "
          f"{done['without an operating point']} without an operating point costing "
          f"{done['their CPU s']:.1f} s of CPU of the designs' {done['all designs CPU s']:.1f} s; "
          f"certificate {done['certificate']}"
          + ("" if done["KKT residual"] is None else f" (KKT residual {done['KKT residual']:.3g})")
          + f"; gain {done['gain %']:+.2f} %")
    if args.method == "multistart":
        _multistart_summary(res)
        print(f"wall time by phase ({args.workers or 'no'} workers): the sample {walls['sample']:.0f} s, the "
              f"polish {walls['polish']:.0f} s, the local searches and the rest "
              f"{wall - walls['sample'] - walls['polish']:.0f} s; CPU time of this process: the polish "
              f"{walls['polish CPU']:.0f} s, the local searches and the rest "
              f"{cpu - walls['sample CPU'] - walls['polish CPU']:.0f} s")
    if args.out:
        res.to_json(args.out)


if __name__ == "__main__":
    main()
