"""The map of the spool drill (``examples/circuit_drill_spool.toml``) over its spool's mass and control
end (the large area, whose pressure opens it), 15 x 15 operating points on a local dask cluster, run
and stored as the drill's cushion map is (``make_drill_cushion_map.main``) in
``docs/data/drill_spool_map.csv``, whose test recomputes a sample of its points from the config.

Run: ``python benchmarks/make_drill_spool_map.py [--workers 2]`` (some minutes of CPU).
"""

from __future__ import annotations

from pathlib import Path

from make_drill_cushion_map import command_line

HERE = Path(__file__).resolve().parent
CONFIG = HERE.parent / "examples" / "circuit_drill_spool.toml"
OUT = HERE.parent / "docs" / "data" / "drill_spool_map.csv"
#: the map's axes: the spool's mass and its control end's area
AXES = {"parts.main_spool.mass": {"start": "0.1 kg", "stop": "0.3 kg", "num": 15},
        "parts.main_spool.large_area": {"start": "1.4 cm^2", "stop": "2.2 cm^2", "num": 15}}

if __name__ == "__main__":
    command_line(__doc__, config=CONFIG, axes=AXES, out=OUT)
