"""``impactbar sweep SPEC.toml --out RESULTS.zarr``: a parameter sweep or Monte Carlo study on
``dask.distributed``, stored chunk by chunk in zarr; rerunning resumes."""

from __future__ import annotations

import sys
from pathlib import Path

from ._common import UsageError, add_deprecated_alias, add_quiet_argument, docs_page, output_folder


def add_parser(sub) -> None:
    p = sub.add_parser(
        "sweep",
        help="parameter sweep / Monte Carlo on dask.distributed into a resumable zarr store",
        description="Compute the task of SPEC.toml (orbits, montecarlo or bifurcation; "
        "operating_point for a design map of a drifter, a spec with config = a drifter's TOML or preset, "
        "its edges recorded after it) at every "
        "point of its grid on a dask.distributed cluster (a sweep in the rigid bar's closed forms: "
        "in threads of this process, which is faster than starting a cluster) and store each chunk "
        "in RESULTS.zarr as it finishes. Rerunning the same command resumes: finished chunks are "
        "kept. The spec is checked before any work starts (its keys: "
        + docs_page("Sweeps and Monte Carlo on a cluster") + ").",
    )
    p.add_argument("spec", help="the sweep spec (TOML)")
    p.add_argument("--out", required=True, help="the zarr store to create or resume (a folder)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None,
                       help="chunks computed at once: processes of the local dask cluster started, or "
                       "threads of this process for a sweep in the rigid closed forms (default: the cores)")
    where.add_argument("--scheduler", default=None,
                       help="address of a running dask scheduler, e.g. tcp://host:8786, instead")
    p.add_argument("--overwrite", action="store_true",
                   help="replace a store that holds a different sweep")
    p.add_argument("--worker-timeout", type=float, default=60.0, metavar="SECONDS",
                   help="on a dask cluster, say so on stderr when it has had no worker for this "
                   "long while chunks remain (default 60; 0: never)")
    p.add_argument("--no-workers", choices=("wait", "stop"), default="wait",
                   help="then keep waiting for workers to join (wait, default) or stop, keeping "
                   "the chunks finished (stop; exit status 1; rerunning resumes)")
    p.add_argument("--numba-cache", default=None, metavar="FOLDER",
                   help="a numba cache folder the dask workers share, filled once by "
                   "NUMBA_CACHE_DIR=FOLDER impactbar warmup: the workers load the kernels from it "
                   "instead of each compiling them")
    add_quiet_argument(p)
    add_deprecated_alias(p, "--no-progress", "--quiet", "quiet", flag=True)
    p.set_defaults(func=run)


def run(args) -> int:
    from ..sweeps import load_spec, run_sweep

    spec = load_spec(args.spec)  # refused here, before any cluster starts
    from ..sweeps.run import max_workers

    if args.workers is not None and not 1 <= args.workers <= max_workers():
        raise ValueError(f"--workers must be in [1, {max_workers()}] (four per core); got {args.workers}")
    store = Path(args.out)  # the store itself is made by run_sweep; its folder must be writable
    if store.exists() and not store.is_dir():
        raise UsageError(f"--out {args.out}: exists and is not a folder (a zarr store is one)")
    output_folder(store.resolve().parent, option=f"--out {args.out}: the folder")
    print(f"{spec.task}: {spec.n_points} points in {spec.n_chunks} chunks of up to "
          f"{spec.chunk_points} -> {args.out}", file=sys.stderr)
    if not args.worker_timeout >= 0:
        raise ValueError(f"--worker-timeout must be >= 0 (0: never); got {args.worker_timeout}")
    from ..sweeps import NoWorkersError

    try:
        res = run_sweep(spec, args.out, scheduler=args.scheduler, n_workers=args.workers,
                        overwrite=args.overwrite,
                        progress=not args.quiet and sys.stderr.isatty(),
                        worker_timeout=args.worker_timeout or None, no_workers=args.no_workers,
                        numba_cache=args.numba_cache)
    except NoWorkersError as exc:
        print(f"impactbar sweep: error: {exc}", file=sys.stderr)
        return 1
    rate = (f", {res.computed * spec.n_points / spec.n_chunks / res.seconds:.1f} points/s"
            if res.computed and res.seconds > 0 else "")
    print(f"{args.out}: {res.already_done + res.computed}/{res.n_chunks} chunks stored "
          f"({res.already_done} found, {res.computed} computed in {res.seconds:.1f} s{rate})")
    from ..sweeps.maps import sweep_edges

    edges = sweep_edges(spec, args.out) if res.complete else []  # a design map's, refined on request
    for e in edges:  # in the unit the config writes the key in (the store keeps SI)
        low, high, value = (spec.axis_text(e["axis"], e[k], digits)
                            for k, digits in (("low", 6), ("high", 6), ("value", 7)))
        where = f", refined to {value}" if e["value"] == e["value"] else ""
        print(f"edge: {e['flag']} changes along {e['axis']} between {low} and {high}{where} "
              f"(at grid index {list(e['index'])})")
    return 0
