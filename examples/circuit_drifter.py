"""A hydraulic drifter with its oil circuit (theory §11): its operating point, the pressures and the
valve over one period, and the p-V (indicator) diagram of each chamber.

    python examples/circuit_drifter.py [figure.png] [config.toml]
"""

import sys
import tomllib
from pathlib import Path

import matplotlib.pyplot as plt

from impactbar.physical import CircuitDrifter

CONFIG = Path(__file__).with_name("circuit_drifter.toml")


def main(out="circuit_drifter.png", config=CONFIG):
    with open(config, "rb") as f:
        drifter = CircuitDrifter.from_config(tomllib.load(f))
    point = drifter.orbit()
    for key, value in point.summary().items():
        print(f"{key:26s} {value:.6g}" if isinstance(value, float) else f"{key:26s} {value}")
    h = point.histories(800)
    fig, ax = plt.subplots(1, 3, figsize=(13, 4), layout="constrained")
    t = 1e3 * h["t_s"]
    for key, label in (("p_r_Pa", "rear"), ("p_f_Pa", "front"), ("p_s_Pa", "supply")):
        ax[0].plot(t, h[key] / 1e6, label=label)
    ax[0].set(xlabel="time from the impact (ms)", ylabel="pressure (MPa, absolute)")
    ax[0].legend()
    ax[1].plot(t, h["x_v"], label="valve opening")
    ax[1].plot(t, 1e3 * h["gap_m"] / 50.0, label="gap / 50 mm")
    ax[1].set(xlabel="time from the impact (ms)")
    ax[1].legend()
    for key, vol, label in (("p_r_Pa", "V_r_m3", "rear"), ("p_f_Pa", "V_f_m3", "front")):
        ax[2].plot(1e6 * h[vol], h[key] / 1e6, label=label)
    ax[2].set(xlabel="chamber volume (cm^3)", ylabel="pressure (MPa)", title="indicator diagrams")
    ax[2].legend()
    fig.savefig(out, dpi=120)
    return point


if __name__ == "__main__":
    main(*sys.argv[1:])
