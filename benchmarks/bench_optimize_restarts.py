"""Benchmark: ``optimize_drifter(method="multistart")`` against the best of restarted COBYLA searches
on the problem of docs/optimising_a_drifter.md (examples/circuit_drifter_rock_piston.toml, its six
variables, the peak incident stress at most 250 MPa, the drilling rate at least 2.5 m/min, drilling
rate per hydraulic kilowatt).

On a local dask cluster of ``--workers`` processes (one thread each), first the multistart: a scrambled
Sobol sample of ``--sample`` designs (seed ``--seed``) evaluated on the cluster, then COBYLA from its
``--local-starts`` best feasible designs, ``--evaluations`` designs each, one after another in this
process; its optimum is re-solved by a fresh orbit and certified (first order, KKT). Then the
restarted searches: COBYLA (``optimize_drifter``'s default, ``--search-evaluations`` designs, 30 by
default) started from each of the ``--searches`` first designs of the same sample ranked (those with
an operating point: the feasible ones first, the objective largest first, then the infeasible ones,
the least missed first, by their smallest scaled margin; on the six variables 7 of 256 are feasible,
so most searches start infeasible, ``optimize_drifter(start="any")``), the searches run side by side
on the cluster's workers, each one's result confirmed feasible by a fresh ``orbit()`` of its design
(:func:`~impactbar.physical.optimize_drifter.evaluate_design` without a guess). Prints each search's
start per kilowatt and its smallest scaled margin, its result per kilowatt, the multistart's table,
certificate and local searches, the wall times
(the multistart's on ``--workers`` and what 4 workers would make of it: its sample's design seconds
over 4 instead of over the workers, the rest serial) and whether the multistart's design is at least
as good per kilowatt as the best search's (less :data:`RELATIVE`, the orbits' accuracy): met or
missed. Nothing is asserted.

Run: ``python benchmarks/bench_optimize_restarts.py [--workers W] [--sample N] [--local-starts K]
[--searches S] [--evaluations E] [--search-evaluations E] [--seed S] [--out result.json] [--cache DIR]
[--only K] [--polish N] [--contact-events {step,inside}] [--quick]``; ``--polish N`` the multistart's
polish's designs (12 by default); ``--contact-events step`` the example with ``rock.contact_events =
"step"`` (the lattice blow's re-contact at a whole step: the lattice's border along the drilling rate's
limit; the example's own is ``"inside"``, the re-contact inside its step), for the multistart and the
searches alike; ``--only K`` runs the ``K``-th restarted
search alone (1 to ``--searches``;
with ``--cache`` the multistart read from it: a search reproduced without the others); ``--cache DIR``
makes a run resumable: the multistart's designs in ``DIR/multistart.json``
(``optimize_drifter(cache=...)``, read first: a killed run's designs are not computed again) and each
finished restarted search's result in ``DIR/search-NN.json`` (read first: a search stored with the same
start and budget is not run again), so that a killed run, run again with the same arguments, finishes
where it stopped and prints the final comparison line;
``--evaluations`` is each of the multistart's local searches' designs (40 by default); ``--quick`` is
two variables (switch point, pre-charge), a sample of 8, one local start, two searches of 8 designs
(a check that it runs).

Measured (``--workers 2``, the 2-core development machine shared with other sessions, load about 6):
the multistart, 373 designs in 1211 s, 0.10988 m/min/kW (+13.27 %), feasible by a fresh orbit, its
certificate "stopped at a border" (KKT residual 1: the drilling rate and the pre-charge's low bound
active, a design of its last step without an orbit). The twenty searches (seven from the sample's
feasible designs, thirteen from its least infeasible; each of the nineteen that reported ended
feasible by a fresh orbit, at its budget of 30 designs): the best 0.109880 (search 1, from the best
feasible sample design), then
0.109846, 0.109758, 0.109505; the multistart's design is as good per kilowatt as the best to the
printed digits (the final comparison line of the run that recorded this was not reached before the
session's deadline when 19 of the 20 searches had reported). A second run (``--cache``, load about
10, the code before the polish) reproduced the multistart's design and figures to the digits in 1434 s
of wall time; its first four searches took 200-290 s each and reached 0.109880, 0.107181, 0.109846 and
0.107491, then fifteen more (the twentieth still running at the session's deadline; the best of the
nineteen 0.109880, from the sample's best feasible design).
The multistart again from that run's cache with the polish (12 designs, 3 refined gradients, 1295 s):
0.109881, feasible by a fresh orbit, its certificate "stopped at a budget" (the polish's 12 designs;
KKT residual 0.085, the drilling rate active with multiplier 0.282, the pre-charge at its low bound,
a design of its last steps without an orbit).
The twentieth search never reported in three runs: its tenth design (``BUZZING`` in
tests/physical/drifter_optimum.py) has no orbit from rest on the stop (``orbit()``'s default chain;
it has a stable one from rest at the switch point, ``orbit(switch_start=True)``), and the
classification of its motion after the
search ran from rest a piston buzzing on the shank (700 impacts a second) for more than 16 minutes.
With the settle runs bounded by their impacts (``--only 20 --cache``, the multistart read from the
cache, 1 worker, load about 5): 74 s, 30 designs (2 without an orbit), 0.107945 m/min/kW feasible
by a fresh orbit ("stopped at a budget", KKT residual 1), below the multistart's 0.109881 (+1.79 %).
With the blows ended where the piston is free for good (the default since), all of it in one run
(``--workers 2 --cache``, load 2 to 3.5): the multistart, 385 designs in 291 s (about 125 s on 4
workers), 0.110703 m/min/kW (+14.12 %) after the polish, feasible by a fresh orbit, "stopped at a
budget" (KKT residual 0.054); all twenty searches reported (497 s on the 2 workers, 24-81 s each),
the best 0.110561; the multistart at least as good, +0.128 %: met.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import time

from bench_optimize_drifter import CONSTRAINTS, EXAMPLE, QUICK, VARY

from impactbar.physical import optimize_drifter, read_config, with_values
from impactbar.physical.design_keys import design_bounds
from impactbar.physical.optimize_drifter import OBJECTIVES
from impactbar.physical.optimize_multistart import found_table, sobol_sample
from impactbar.physical.optimize_problem import least_margin

#: How much below the best search's objective the multistart's may lie and still count as at least as
#: good: the operating point's accuracy (a continued and a fresh orbit of one design differ by some 1e-9).
RELATIVE = 1e-8
OBJECTIVE = "drilling_rate_per_kW"


def restarted_search(changes: dict, config: dict, vary: dict, constraints: dict, evaluations: int) -> dict:
    """COBYLA from the design ``changes`` of ``config`` (a worker's task): its result, and the result
    confirmed by a fresh orbit."""
    from impactbar.physical import build, with_values
    from impactbar.physical.optimize_drifter import OBJECTIVES, evaluate_design

    t0 = time.perf_counter()
    try:
        res = optimize_drifter(with_values(config, changes), vary, objective=OBJECTIVE,
                               constraints=constraints, max_evaluations=evaluations, progress=False,
                               start="any")
    except ValueError as exc:  # (a start without an operating point, when solved again)
        return {"error": str(exc), "feasible": False, "seconds": time.perf_counter() - t0}
    fkey = OBJECTIVES[OBJECTIVE][0]
    fresh, _ = evaluate_design(build(with_values(config, res.optimum["changes"])), constraints)
    return {"start": res.baseline["objectives"][fkey], "start_feasible": res.baseline["feasible"],
            "result": res.optimum["objectives"][fkey],
            "fresh": fresh["objectives"][fkey], "feasible": fresh["feasible"],
            "values": res.optimum["values"], "changes": res.optimum["changes"],
            "evaluations": res.evaluations, "failed": sum(not r.get("ok") for r in res.history),
            "verdict": res.certificate.verdict, "residual": res.certificate.residual,
            "message": res.message, "seconds": time.perf_counter() - t0}


def search_result(future) -> dict:
    """A restarted search's result from its dask ``future``, or, where its task failed (a design that
    killed its worker: distributed's ``KilledWorker`` after the retries, or any other exception), the
    failure as a result: ``error`` (the exception's type and text), not feasible, ``lost`` (the run goes
    on, and the search is not stored: a run again tries it again)."""
    try:
        return future.result()
    except Exception as exc:
        return {"error": f"{type(exc).__name__}: {exc}", "feasible": False, "seconds": math.nan, "lost": True}


def _search_file(cache: str | None, i: int, changes: dict, evaluations: int) -> tuple:
    """The stored result of restarted search ``i`` (``None`` where none, or stored for another start or
    budget) and its file (``None`` without a cache)."""
    if cache is None:
        return None, None
    path = os.path.join(cache, f"search-{i:02d}.json")
    if os.path.exists(path):
        with open(path) as fh:
            stored = json.load(fh)
        if stored.get("start_changes") == json.loads(json.dumps(changes, default=str)) and \
                stored.get("budget") == evaluations:
            return stored, path
    return None, path


def ranked_starts(recs: list, fkey: str) -> list:
    """The sample's designs with an operating point as starts: the feasible ones first, the objective
    largest first, then the infeasible ones, the least missed first (the largest
    :func:`~impactbar.physical.optimize_problem.least_margin`)."""
    feasible = sorted((r for r in recs if r.get("feasible")), key=lambda r: r["objectives"][fkey],
                      reverse=True)
    missed = sorted((r for r in recs if r.get("ok") and not r.get("feasible")), key=least_margin,
                    reverse=True)
    return feasible + missed


def sample_records(history: list, vary: dict, sample: int, seed: int) -> list:
    """The records of the multistart's Sobol sample among ``history``, in the sample's order (each
    found by its id, the repr of its SI values, as the search keys it)."""
    config, folder = read_config(EXAMPLE)
    spec = design_bounds(config, vary, folder)
    keys = list(spec)
    by_id = {r["id"]: r for r in history}
    out = []
    for u in sobol_sample(len(keys), sample, seed):
        values = [spec[k]["low"] + (spec[k]["high"] - spec[k]["low"]) * float(x) for k, x in zip(keys, u,
                                                                                                   strict=True)]
        out.append(by_id[json.dumps([repr(float(v)) for v in values])])
    return out


def design_seconds(record: dict) -> float:
    """A design's own seconds: its operating point's, and the settle task's where it had none."""
    return record.get("seconds", 0.0) + record.get("motion_seconds", 0.0)


def four_worker_estimate(history: list, sample: list) -> float:
    """What 4 workers would make of the multistart, from its designs' own recorded seconds (those
    read from a cache too: their seconds are the run's that computed them): the sample's designs side
    by side, over 4, the local searches' and the polish's one after another. Never negative, and the
    same whether the designs were computed in this run or read from its cache."""
    sampled = {id(r) for r in sample}
    return sum(design_seconds(r) for r in sample) / 4.0 + sum(design_seconds(r) for r in history
                                                               if id(r) not in sampled)


def _multistart_summary(ms, recs: list, wall: float, workers: int) -> None:
    """The multistart's table, message and local searches, its designs, failures and wall time (and
    on 4 workers: :func:`four_worker_estimate`)."""
    fkey = OBJECTIVES[OBJECTIVE][0]
    print(ms.table())
    print(ms.message)
    print(found_table(ms.found, ms.vary, fkey))
    sample_s = sum(design_seconds(r) for r in recs)
    failed = [r for r in ms.history if not r.get("ok")]
    feasible = sum(r.get("feasible", False) for r in recs)
    lost = sum(design_seconds(r) for r in failed)
    read = f", {ms.cached} of them read from the cache" if ms.cached else ""
    print(f"multistart: {len(ms.history)} designs{read} ({len(recs)} sampled, {feasible} of them feasible, "
          f"{sum(not r.get('ok') for r in recs)} without an operating point), "
          f"{len(failed)} without an operating point in all costing {lost:.0f} s; "
          f"{wall:.0f} s wall on {workers} workers (the sample's designs {sample_s:.0f} s), "
          f"on 4 workers about {four_worker_estimate(ms.history, recs):.0f} s (the designs' own seconds: "
          "the sample's over 4, the rest one after another)", flush=True)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--sample", type=int, default=256)
    p.add_argument("--local-starts", type=int, default=3)
    p.add_argument("--searches", type=int, default=20)
    p.add_argument("--evaluations", type=int, default=40,
                   help="each of the multistart's local searches' designs")
    p.add_argument("--search-evaluations", type=int, default=30, help="each restarted search's designs")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default=None)
    p.add_argument("--cache", default=None, help="a folder: the designs and the finished searches stored "
                   "there, read first (a killed run resumes)")
    p.add_argument("--only", type=int, default=None, help="run the K-th restarted search alone")
    p.add_argument("--polish", type=int, default=12, help="the multistart's polish's most designs")
    p.add_argument("--contact-events", choices=("step", "inside"), default=None,
                   help="the example's rock.contact_events (the lattice blow's re-contact; its own, "
                   "'inside', where not given)")
    p.add_argument("--quick", action="store_true")
    args = p.parse_args()
    if args.only is not None and not 1 <= args.only <= args.searches:
        p.error(f"--only must be 1 to --searches ({args.searches}); got {args.only}")
    vary = VARY
    if args.quick:
        vary = {k: VARY[k] for k in QUICK}
        args.sample, args.local_starts, args.searches, args.evaluations = 8, 1, 2, 8
        args.search_evaluations = 8
    import dask
    from distributed import Client, LocalCluster, as_completed

    config, _ = read_config(EXAMPLE)
    if args.contact_events is not None:  # (else the example's own setting, "inside")
        config = with_values(config, {"rock.contact_events": args.contact_events})
    if args.cache is not None:
        os.makedirs(args.cache, exist_ok=True)
    fkey = OBJECTIVES[OBJECTIVE][0]
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; {args.workers} workers")
    # (one retry of a task whose worker died: a search that kills its worker by its memory is tried
    # twice, some 10 minutes each, not four times)
    with (dask.config.set({"distributed.scheduler.http.routes": [], "distributed.worker.http.routes": [],
                           "distributed.scheduler.allowed-failures": 1}),
          LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                       dashboard_address="127.0.0.1:0", scheduler_kwargs={"dashboard": False},
                       worker_dashboard_address=None, silence_logs=logging.ERROR) as cluster,
          Client(cluster) as client):
        t0 = time.perf_counter()
        ms = optimize_drifter(EXAMPLE if args.contact_events is None else config, vary, objective=OBJECTIVE,
                              constraints=CONSTRAINTS,
                              method="multistart", sample=args.sample, local_starts=args.local_starts,
                              seed=args.seed, polish=args.polish,
                              max_evaluations=args.sample + args.local_starts * args.evaluations,
                              workers=client, progress=False, cache=None if args.cache is None
                              else os.path.join(args.cache, "multistart.json"))
        ms_wall = time.perf_counter() - t0
        recs = sample_records(ms.history, vary, args.sample, args.seed)
        _multistart_summary(ms, recs, ms_wall, args.workers)
        starts = ranked_starts(recs, fkey)[:args.searches]
        t0 = time.perf_counter()
        stored = {i: _search_file(args.cache, i, r["changes"], args.search_evaluations)
                  for i, r in enumerate(starts, 1)}
        futures = {client.submit(restarted_search, r["changes"], config, vary, CONSTRAINTS,
                                 args.search_evaluations, pure=False): i for i, r in enumerate(starts, 1)
                   if stored[i][0] is None and args.only in (None, i)}
        print(f"{'search':>6s} {'start':>10s} {'margin':>9s} {'result':>10s} {'fresh':>10s} {'feasible':>8s} "
              f"{'designs':>7s} {'failed':>6s} {'seconds':>7s}  certificate", flush=True)
        searches = []

        def report(i: int, s: dict, how: str = "") -> None:
            searches.append(s)
            if "error" in s:
                print(f"{i:6d} failed: {s['error']}{how}", flush=True)
                return
            print(f"{i:6d} {s['start']:10.6f} {least_margin(starts[i - 1]):9.3g} "
                  f"{s['result']:10.6f} {s['fresh']:10.6f} "
                  f"{s['feasible']!s:>8s} {s['evaluations']:7d} {s['failed']:6d} {s['seconds']:7.0f}  "
                  f"{s['verdict']} (KKT residual {s['residual']:.2g}){how}", flush=True)

        for i, (s, _) in stored.items():
            if s is not None and args.only in (None, i):
                report(i, s, " (stored)")
        for future in as_completed(futures):
            i = futures[future]
            s = search_result(future)
            if "lost" in s:  # (not stored: a run again tries it again)
                report(i, s)
                continue
            path = stored[i][1]
            if path is not None:
                with open(path + ".part", "w") as fh:
                    json.dump(dict(s, start_changes=starts[i - 1]["changes"], budget=args.search_evaluations),
                              fh, default=str)
                os.replace(path + ".part", path)
            report(i, s)
        cobyla_wall = time.perf_counter() - t0
    failed = sum("error" in s for s in searches)
    own = sum(s["seconds"] for s in searches if math.isfinite(s["seconds"]))
    print(f"the {len(searches)} searches ({args.search_evaluations} designs at most each; {failed} failed): "
          f"{cobyla_wall:.0f} s wall on {args.workers} workers, {own:.0f} s of the searches' own time")
    ok = [s for s in searches if s["feasible"]]
    best = max(ok, key=lambda s: s["fresh"]) if ok else None
    base = ms.baseline["objectives"][fkey]
    mine = ms.optimum["objectives"][fkey]
    if best is None:
        print("no search's result was feasible by a fresh orbit")
        return
    met = ms.optimum["feasible"] and mine >= best["fresh"] * (1.0 - RELATIVE)
    print(f"baseline {base:.6f}; best search {best['fresh']:.6f} ({best['fresh'] / base - 1:+.2%}), "
          f"multistart {mine:.6f} ({mine / base - 1:+.2%}, feasible by a fresh orbit: "
          f"{ms.optimum['feasible']}), "
          f"certificate: {ms.certificate}")
    print(f"multistart {mine:.6f} vs best of {len(ok)} feasible of {len(searches)} searches "
          f"{best['fresh']:.6f} ({fkey}): "
          f"at least as good: {'yes' if met else 'no'} ({mine / best['fresh'] - 1:+.3%}); certificate: "
          f"{ms.certificate.verdict} (KKT residual {ms.certificate.residual:.2g}, tolerance "
          f"{ms.certificate.tolerance:g})", flush=True)
    if args.out:
        with open(args.out, "w") as fh:
            json.dump({"multistart": {"objective": mine, "values": ms.optimum["values"],
                                      "changes": ms.optimum["changes"], "wall_s": ms_wall,
                                      "certificate": ms.certificate.to_dict(), "found": ms.found,
                                      "message": ms.message},
                       "searches": searches, "search_evaluations": args.search_evaluations,
                       "sample": args.sample, "seed": args.seed, "cobyla_wall_s": cobyla_wall,
                       "met": bool(met)}, fh, default=str)


if __name__ == "__main__":
    main()
