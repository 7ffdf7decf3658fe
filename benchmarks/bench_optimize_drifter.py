"""Benchmark: ``optimize_drifter`` on the example rock drifter with its piston given by its shape
(examples/circuit_drifter_rock_piston.toml, the piston and circuit of examples/circuit_drifter_rock.toml)
over six variables (collar, front rod and rear rod diameters, rear chamber volume, switch point,
pre-charge) for drilling rate per hydraulic kilowatt, beside one baseline evaluation (a fresh ``orbit()``
of the start) in the same run.

Run: ``python benchmarks/bench_optimize_drifter.py [--max-evaluations N] [--out result.json]
[--cache cache.json] [--keys K1,K2,...] [--method cobyla|slsqp|differential_evolution|multistart]
[--sample N] [--local-starts K] [--workers W] [--project 2,4,8] [--quick]``; ``--keys four`` is the
four variables of the speed goal (the three diameters and the switch point). Prints the wall times,
the number of evaluations and the design table; nothing is asserted. A stopped run resumes from ``--cache``.

With ``--method multistart`` (a Sobol sample of ``--sample`` designs, COBYLA from the
``--local-starts`` best feasible ones) it prints too the designs evaluated, those without an operating
point and the seconds they cost, the certificate's verdict, the gain and each local search's best
design, and a table of its phases (the workers' start, the sample, the local searches, the polish,
the classification of the listed failures, the certificate, the workers' close, the rest): each
one's wall time, this process's CPU, the workers' CPU (``client.run(time.process_time)`` before and
after it), its tasks and flights on the workers, whether it is serial (in this process) or spread,
and a projection of its seconds on ``--project`` free workers (its CPU here, its workers' CPU over
N, the per-task and per-flight overheads of no-op tasks measured on the cluster before it closes);
then each local search's wall, CPU, COBYLA's evaluations and the designs it computed. ``--quick``:
two variables (switch point, pre-charge), a sample of 8, one local search, 16 designs at most (a
check that it runs, in minutes).

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
#: The summary's key of the optimum's changes' digest.
DIGEST = "optimum (its changes' digest)"
CONSTRAINTS = {"peak_rod_stress": "250 MPa", "min_drilling_rate": "2.5 m/min"}


#: The multistart's phases, in their order; each timed where it runs (its wall, this process's CPU, the
#: workers' CPU, its tasks and flights on the workers).
PHASES = ("cluster start", "sample", "local searches", "polish", "classification", "certificate",
          "cluster close")


def _noop(x):
    """A task that does nothing (the probe of a task's overhead on the workers)."""
    return x


class _Workers:
    """The search's dask client (caught where the search makes its map on the workers), its tasks and
    flights (``run`` calls), and its workers' CPU seconds (``client.run(time.process_time)``: each
    worker process's CPU, all its threads, summed over the workers)."""

    def __init__(self):
        self.client, self.tasks, self.flights, self.startup, self.probe = None, 0, 0, [], None

    def cpu(self) -> float:
        return 0.0 if self.client is None else float(sum(self.client.run(time.process_time).values()))

    def count(self, client, run):
        self.client = client

        def counted(fn, items, **common):
            items = list(items)
            self.flights += bool(items)
            self.tasks += len(items)
            return run(fn, items, **common)
        return counted

    def measure_overhead(self, rounds: int = 3) -> None:
        """``probe``: a flight's latency (one no-op task there and back) and a task's overhead on a
        worker (a flight of 16 no-op tasks a worker, its wall times the workers over the tasks), the
        least of ``rounds``."""
        client = self.client
        n = len(client.scheduler_info()["workers"])
        one = many = float("inf")
        for _ in range(rounds):
            t = time.perf_counter()
            client.gather(client.submit(_noop, 0, pure=False))
            one = min(one, time.perf_counter() - t)
            t = time.perf_counter()
            client.gather(client.map(_noop, range(16 * n), pure=False))
            many = min(many, (time.perf_counter() - t) * n / (16 * n))
        self.probe = {"workers": n, "flight s": one, "task s": many}


@contextlib.contextmanager
def _phases(calls: dict):
    """Each of the multistart's :data:`PHASES`: its wall seconds, under ``"<phase> CPU"`` this
    process's CPU seconds, ``"<phase> workers CPU"`` the workers' (read before and after the phase,
    outside its wall), ``"<phase> tasks"`` and ``"<phase> flights"`` its tasks and ``run`` calls on the
    workers: the cluster's start and close (``record_map``'s entry and exit), the sample's designs
    computed together (``compute_new``), the local searches (each COBYLA from a sample's design, in
    this process; ``"local"``: each one's wall, CPU, COBYLA's evaluations and the designs it computed,
    from ``calls``' count of :func:`_timed_designs`), the polish (``polish_search``), the
    classification of the listed failures (``classify_listed``) and the certificate
    (``certify_search``, its gradient's columns on the workers on a tree that keeps them open). Apart
    (inside the others), the cache file's writes (a tree's ``write_cache``, the whole file, or its
    log's lines). ``"workers"``: the :class:`_Workers`."""
    import impactbar.physical.optimize_cache as cache
    import impactbar.physical.optimize_multistart as multistart
    import impactbar.physical.optimize_population as population

    module = inspect.getmodule(optimize_drifter)
    walls = {f"{phase}{what}": 0 if what in (" tasks", " flights") else 0.0
             for phase in (*PHASES, "cache writes")
             for what in ("", " CPU", " workers CPU", " tasks", " flights")}
    workers = walls["workers"] = _Workers()
    walls["local"] = []

    def timed(fn, phase, on_workers=True):
        def wrapper(*args, **kwargs):
            w0 = workers.cpu() if on_workers else 0.0
            n0, f0 = workers.tasks, workers.flights
            t0, c0 = time.perf_counter(), time.process_time()
            try:
                return fn(*args, **kwargs)
            finally:
                walls[phase] += time.perf_counter() - t0
                walls[f"{phase} CPU"] += time.process_time() - c0
                walls[f"{phase} workers CPU"] += (workers.cpu() - w0) if on_workers else 0.0
                walls[f"{phase} tasks"] += workers.tasks - n0
                walls[f"{phase} flights"] += workers.flights - f0
        return wrapper

    def local_search(local):
        def one(u):
            t0, c0, d0 = time.perf_counter(), time.process_time(), calls["n"]
            res = local(u)
            walls["local"].append({"wall": time.perf_counter() - t0, "cpu": time.process_time() - c0,
                                   "evaluations": int(res.nfev), "designs": calls["n"] - d0})
            return res
        return timed(one, "local searches")

    def searched(fn):
        def wrapper(evaluate, design_of, stored, record, common, local, *args, **kwargs):
            return fn(evaluate, design_of, stored, record, common, local_search(local), *args, **kwargs)
        return wrapper

    def mapped(fn):
        @contextlib.contextmanager
        def wrapper(arg):
            t0, c0 = time.perf_counter(), time.process_time()
            with fn(arg) as run:
                walls["cluster start"] += time.perf_counter() - t0
                walls["cluster start CPU"] += time.process_time() - c0
                if workers.client is not None:  # (each worker's CPU since it started: its start's)
                    workers.startup = sorted(workers.client.run(time.process_time).values())
                    walls["cluster start workers CPU"] = sum(workers.startup)
                try:
                    yield run
                finally:
                    if workers.client is not None:
                        workers.measure_overhead()
                    t0, c0 = time.perf_counter(), time.process_time()
            walls["cluster close"] += time.perf_counter() - t0
            walls["cluster close CPU"] += time.process_time() - c0
        return wrapper

    saved = [(multistart, "compute_new", lambda fn: timed(fn, "sample")),
             (module, "multistart_search", searched),
             (module, "polish_search", lambda fn: timed(fn, "polish")),
             (module, "classify_listed", lambda fn: timed(fn, "classification")),
             (module, "certify_search", lambda fn: timed(fn, "certificate")),
             (module, "record_map", mapped),
             (population, "_client_map", lambda fn: lambda client: workers.count(client, fn(client))),
             (module, "write_cache", lambda fn: timed(fn, "cache writes", False)),
             *((getattr(cache, "DesignCache", None), n, lambda fn: timed(fn, "cache writes", False))
               for n in ("_write", "rewrite"))]
    kept = [(m, n, getattr(m, n), wrap) for m, n, wrap in saved if m is not None and hasattr(m, n)]
    for m, n, fn, wrap in kept:
        setattr(m, n, wrap(fn))
    try:
        yield walls
    finally:
        for m, n, fn, _ in kept:
            setattr(m, n, fn)


def projection(walls: dict, wall: float, cpu: float, n: int) -> list:
    """The rows of the phases' table and each phase's projection on ``n`` free workers: a phase's
    part in this process at its CPU seconds (a free core: wall = CPU), its workers' part at their CPU
    over ``n`` (its tasks shared evenly), each task's overhead (the probe's) over ``n`` and each
    flight's latency (a phase without tasks: its part here alone, the workers' CPU then their idle
    bookkeeping); the cluster's start at this process's CPU and the slowest worker's start (the
    workers start side by side), its close at its wall. The rest (the start's evaluation, the
    sample's designs read back, the fresh re-evaluations of the baseline and the optimum): its wall
    less the phases', at its CPU."""
    probe = walls["workers"].probe or {"flight s": 0.0, "task s": 0.0}
    rows = []
    for phase in PHASES:
        w, c, wc = walls[phase], walls[f"{phase} CPU"], walls[f"{phase} workers CPU"]
        tasks, flights = walls[f"{phase} tasks"], walls[f"{phase} flights"]
        if phase == "cluster start":
            at = c + max(walls["workers"].startup, default=0.0)
        elif phase == "cluster close":
            at = w
        else:  # (a serial phase's workers' CPU their idle bookkeeping: no work of the search's)
            at = c + (wc / n + tasks * probe["task s"] / n + flights * probe["flight s"] if tasks else 0.0)
        rows.append((phase, "spread" if tasks else "serial", w, c, wc, tasks, flights, at))
    rest_c = cpu - sum(r[3] for r in rows)
    rows.append(("the rest", "serial", wall - sum(r[2] for r in rows), rest_c, 0.0, 0, 0, rest_c))
    return rows


def _phase_table(walls: dict, wall: float, cpu: float, workers, project: list) -> None:
    """The phases' table (wall, CPU here and on the workers, tasks, flights) and the projections on
    ``project`` free workers."""
    w = walls["workers"]
    total_w = sum(w.startup) + sum(walls[f"{p} workers CPU"] for p in PHASES[1:-1])
    heads = "".join(f" {f'on {n}':>8s}" for n in project)
    print(f"the phases on {workers or 'no'} workers (wall and CPU seconds; the workers' CPU summed over "
          f"them; projection: seconds on N free workers)")
    print(f"{'phase':16s} {'where':>7s} {'wall':>8s} {'CPU':>8s} {'work. CPU':>9s} {'tasks':>6s} "
          f"{'flights':>7s}{heads}")
    tables = {n: projection(walls, wall, cpu, n) for n in project}
    for i, row in enumerate(tables[project[0]]):
        name, where, ww, c, wc, tasks, flights, _ = row
        print(f"{name:16s} {where:>7s} {ww:8.1f} {c:8.1f} {wc:9.1f} {tasks:6d} {flights:7d}"
              + "".join(f" {tables[n][i][-1]:8.1f}" for n in project))
    print(f"{'total':16s} {'':>7s} {wall:8.1f} {cpu:8.1f} {total_w:9.1f} {w.tasks:6d} {w.flights:7d}"
          + "".join(f" {sum(r[-1] for r in tables[n]):8.1f}" for n in project))
    if w.probe is not None:
        print(f"measured overhead ({w.probe['workers']} workers, no-op tasks, least of 3): a flight "
              f"{w.probe['flight s'] * 1e3:.1f} ms, a task {w.probe['task s'] * 1e3:.1f} ms on a worker; "
              f"the workers' starts (CPU s each): {', '.join(f'{x:.1f}' for x in w.startup)}")
    print("projection's assumptions: N free cores besides this process's; this process's work at its CPU "
          "seconds; the workers' at their CPU / N (the same CPU seconds a task as measured here, the tasks "
          "shared evenly, no straggler); plus the measured overheads; the workers' idle CPU counted as "
          "work in a spread phase, left out in a serial one")
    local = walls["local"]
    for j, one in enumerate(local):
        print(f"local search {j + 1}: {one['wall']:.1f} s wall, {one['cpu']:.1f} s CPU, {one['evaluations']} "
              f"COBYLA evaluations, {one['designs']} designs computed "
              f"({one['cpu'] / max(one['designs'], 1):.2f} s CPU a design)")
    if walls["local searches CPU"] > 300.0:
        print(f"the local searches alone (serial, in this process) take {walls['local searches CPU']:.0f} s "
              "of CPU: more than 5 minutes on any number of workers")


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
    any tree: a name missing there is not timed); under ``"n"`` the number of ``evaluate_design``'s
    calls (the designs computed here)."""
    module = inspect.getmodule(optimize_drifter)
    calls = {"ok": 0.0, "failed": 0.0, "n_failed": 0, "classified": 0.0, "n": 0}
    bucket = {"evaluate_design": "ok", "failed_record": "failed", "classify_listed": "classified"}

    def timed(fn, name: str):
        def wrapper(*args, **kwargs):
            c0 = time.process_time()
            calls["n"] += name == "evaluate_design"
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
                                         "cache writes CPU s": walls["cache writes CPU"],
                                         "local searches wall s": walls["local searches"],
                                         "local searches CPU s": walls["local searches CPU"],
                                         "workers CPU s": sum(walls[f"{p} workers CPU"] for p in PHASES),
                                         "projected on 4 workers s": sum(
                                             r[-1] for r in projection(walls, wall, cpu, 4))}),
            "certificate": cert.verdict if cert is not None else "none",
            "KKT residual": cert.residual if cert is not None else None,
            "gain %": 100.0 * res.gain, OBJECTIVES[res.objective][0]: res.optimum["objectives"][
                OBJECTIVES[res.objective][0]],
            DIGEST: hashlib.sha1(json.dumps(res.optimum["changes"], sort_keys=True)
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
    p.add_argument("--project", default="2,4,8", help="multistart: the numbers of free workers projected "
                   "(comma-separated)")
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
    with _timed_designs() as calls, _phases(calls) as walls:
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
          + f"; gain {done['gain %']:+.2f} %; the optimum's digest {done[DIGEST]}")
    if args.method == "multistart":
        _multistart_summary(res)
        _phase_table(walls, wall, cpu, args.workers, [int(n) for n in args.project.split(",")])
    if args.out:
        res.to_json(args.out)


if __name__ == "__main__":
    main()
