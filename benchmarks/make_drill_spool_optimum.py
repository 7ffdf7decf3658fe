"""The optimiser on the spool drill (``examples/circuit_drill_spool.toml``) over its spool's mass and
control end and its cushion's volume and coefficient, by their dotted keys: ``optimize_drifter`` with
``method="multistart"`` (a Sobol sample of 16 designs evaluated together on a local dask cluster, then
COBYLA from the best feasible one), 28 designs at most, the impact power maximised, the mean supply
pressure's cap raised to 26 MPa. Stored as ``docs/data/drill_spool_optimum.json``
(:meth:`DrifterOptimum.to_json`) for the tutorial, whose test recomputes the optimum's orbit from the
config and the stored changes.

Run: ``python benchmarks/make_drill_spool_optimum.py [--workers 2]`` (a few minutes of CPU).
"""

from __future__ import annotations

import argparse
from pathlib import Path

HERE = Path(__file__).resolve().parent
CONFIG = HERE.parent / "examples" / "circuit_drill_spool.toml"
OUT = HERE.parent / "docs" / "data" / "drill_spool_optimum.json"
#: the variables: two of the spool's (its mass, the control end that opens it) and two of the cushion's
VARY = {"parts.main_spool.mass": ("0.1 kg", "0.3 kg"),
        "parts.main_spool.large_area": ("1.4 cm^2", "2.2 cm^2"),
        "parts.cushion.volume": ("5 mL", "40 mL"),
        "parts.cushion.coefficient": ("2.5e-6 m^3/s/Pa^0.5", "1.5e-5 m^3/s/Pa^0.5")}
#: the search: 16 sampled designs, then one local search of the rest
SEARCH = {"objective": "impact_power", "method": "multistart", "sample": 16, "local_starts": 1,
          "max_evaluations": 28, "seed": 0}
#: the default limits but the mean supply pressure's: the drill runs on its relief valve (25 MPa; the
#: spool drill's mean 25.7 MPa), so its cap is raised to 26 MPa, the relief's setting plus 1 MPa
CONSTRAINTS = {"mean_supply_pressure": "26 MPa"}


def main(workers: int = 2) -> None:
    from impactbar.physical import optimize_drifter

    res = optimize_drifter(CONFIG, VARY, constraints=CONSTRAINTS, workers=workers, progress=False, **SEARCH)
    res.to_json(OUT)
    print(res.table())
    print(f"{res.evaluations} designs on {workers} dask workers in {res.seconds:.1f} s; written to "
          f"{OUT.relative_to(HERE.parent)}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--workers", type=int, default=2)
    main(parser.parse_args().workers)
