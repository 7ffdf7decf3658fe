"""A hydraulic drifter with its oil circuit (theory §11): its operating point, the pressures and the
valve over one period, and the p-V (indicator) diagram of each chamber.

    python examples/circuit_drifter.py [figure.png] [config.toml]
"""

import sys
from pathlib import Path

from impactbar.physical import load

CONFIG = Path(__file__).with_name("circuit_drifter.toml")


def main(out="circuit_drifter.png", config=CONFIG):
    drifter = load(config)  # a CircuitDrifter: the file has a [chambers] section
    point = drifter.orbit()
    for key, value in point.summary().items():
        print(f"{key:26s} {value:.6g}" if isinstance(value, float) else f"{key:26s} {value}")
    for chamber, work in point.indicator_work_J().items():
        print(f"{'indicator work, ' + chamber:26s} {work:.6g} J")
    axes = point.plot(points=800)  # pressures, valve, and the rear and front p-V loops
    fig = axes[0].figure
    fig.savefig(out, dpi=120)
    return point


if __name__ == "__main__":
    main(*sys.argv[1:])
