"""The map of the drill on the preset's ramped valve (``examples/circuit_drill_parts.toml``) over its
cushion's volume and full-open coefficient, 15 x 15 operating points on a local dask cluster
(``impactbar.sweeps.run_map``, as ``impactbar sweep`` runs a design map), stored as
``docs/data/drill_cushion_map.csv`` for the tutorial page ``docs/drill_parts.md``, whose test recomputes
a sample of its points from the config.

Run: ``python benchmarks/make_drill_cushion_map.py [--workers 2]`` (some minutes of CPU; it prints
the map's CPU time: this process' and its finished children's, the dask workers, together).
"""

from __future__ import annotations

import argparse
import csv
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
CONFIG = HERE.parent / "examples" / "circuit_drill_parts.toml"
OUT = HERE.parent / "docs" / "data" / "drill_cushion_map.csv"
#: the map's axes: the cushion's oil volume and its port's full-open coefficient
AXES = {"parts.cushion.volume": {"start": "5 mL", "stop": "40 mL", "num": 15},
        "parts.cushion.coefficient": {"start": "2.5e-6 m^3/s/Pa^0.5", "stop": "1.5e-5 m^3/s/Pa^0.5",
                                      "num": 15}}
#: the stored columns: the axes (SI), then the map's outputs (SI)
OUTPUTS = ("status", "blow_frequency", "impact_energy", "hydraulic_efficiency", "max_abs_multiplier",
           "stable", "mean_supply_pressure", "min_rear_pressure")


def spec(config=CONFIG, axes=None):
    """The map's spec (:class:`impactbar.sweeps.SweepSpec`) over ``axes`` (:data:`AXES`) of
    ``config``."""
    from impactbar.sweeps import parse_spec

    return parse_spec({"task": "operating_point", "config": str(config), "axes": axes or AXES})


def main(workers: int = 2, store=None, config=CONFIG, axes=None, out=OUT) -> None:
    """Run the map of ``config`` over ``axes`` (default the drill's cushion's, :data:`AXES`) on
    ``workers`` dask workers and write it as a CSV to ``out``."""
    from impactbar.sweeps import open_sweep
    from impactbar.sweeps.maps import run_map

    axes = axes or AXES
    with tempfile.TemporaryDirectory() as tmp:
        store = Path(tmp) / "map.zarr" if store is None else Path(store)
        wall, cpu = time.perf_counter(), _cpu()
        run_map(spec(config, axes), store, executor="dask", n_workers=workers, progress=False)
        wall, cpu = time.perf_counter() - wall, _cpu() - cpu
        ds = open_sweep(store)
        names = list(axes)
        grid = np.meshgrid(*(ds[n].values for n in names), indexing="ij")
        rows = [[*(g.ravel()[k] for g in grid), *(ds[o].values.ravel()[k] for o in OUTPUTS)]
                for k in range(grid[0].size)]
    out.parent.mkdir(parents=True, exist_ok=True)
    with out.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow([*names, *OUTPUTS])
        for r in rows:
            w.writerow([repr(float(x)) if isinstance(x, float | np.floating) else int(x) for x in r])
    print(f"{len(rows)} points on {workers} dask workers: {wall:.1f} s of wall time, {cpu:.0f} s of CPU; "
          f"written to {out.relative_to(HERE.parent)}")


def _cpu() -> float:
    """CPU seconds of this process and its finished children (the dask workers, once the cluster
    closes)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def command_line(doc: str, **where) -> None:
    """Read ``--workers`` and ``--store`` from the command line (``doc`` its help) and run
    :func:`main` with them and ``where`` (``config``, ``axes``, ``out``)."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--store", default=None,
                        help="the zarr store to keep (a rerun resumes it); default a temporary one")
    a = parser.parse_args()
    main(a.workers, a.store, **where)


if __name__ == "__main__":
    command_line(__doc__)
