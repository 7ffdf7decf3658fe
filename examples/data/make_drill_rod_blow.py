"""Write drill_rod_blow.npz: the strains the library's own exact blow puts at two gauges of a drill
rod, with noise, as a bridge amplifier records them (``examples/drill_rod.toml`` reads it).

A uniform steel piston 0.3 m long (1.0e-3 m^2) strikes at 10 m/s a rod of a 0.5 m shank (1.2e-3 m^2)
and 3.0 m of rod (0.8e-3 m^2), E = 200 GPa, 8000 kg/m^3 (c = 5000 m/s), on a bilinear rock of
k = 3e8 N/m and k_u = 3e9 N/m (:func:`impactbar.measure.gauge_strains`, exact). Two half bridges
(gauge factor 2.0, 5 V, gain 200) sit 0.15 m and 0.20 m from the bit; the record runs from 0.4 ms
after the impact for 2400 samples at 2 MHz (the wave reaches the gauges at 0.66 ms), with white
noise of 0.2 % of the larger gauge's peak strain (3.2 microstrain) added to each channel (seed 7),
stored as counts of 0.1 mV. Run ``python examples/data/make_drill_rod_blow.py`` to write it again.
"""

from pathlib import Path

import numpy as np

from impactbar.measure import Gauge, gauge_strains
from impactbar.physical.rock import RodPiece

STEEL = {"E_Pa": 2.0e11, "density_kg_m3": 8000.0}
ROD = [RodPiece(length_m=0.5, area_m2=1.2e-3, **STEEL), RodPiece(length_m=3.0, area_m2=0.8e-3, **STEEL)]
PISTON = {"piston_lengths": [0.3], "piston_areas": [1.0e-3]}
TRUE = {"impact_velocity": 10.0, "rock.k": 3e8, "rock.k_u": 3e9}
STATIONS = {"near": 0.15, "far": 0.20}  # m from the bit
GAUGE = {"bridge": "half", "gauge_factor": 2.0, "excitation": 5.0, "gain": 200.0}
T0, DT, N = 0.4e-3, 0.5e-6, 2400
NOISE, SEED, VOLTS_PER_CODE = 0.002, 7, 1e-4


def make() -> dict:
    """The arrays of the .npz (``t0``, ``dt``, ``volts_per_code``, int16 ``near`` and ``far``)."""
    t = T0 + DT * np.arange(N)
    length = sum(p.length_m for p in ROD)
    eps = gauge_strains(ROD, **PISTON, values=TRUE, stations=[length - x for x in STATIONS.values()], time=t)
    strains = dict(zip(STATIONS, eps.values(), strict=True))
    peak = max(float(np.max(np.abs(e))) for e in strains.values())
    rng = np.random.default_rng(SEED)
    out = {"t0": T0, "dt": DT, "volts_per_code": VOLTS_PER_CODE}
    for name, e in strains.items():
        volts = (e + NOISE * peak * rng.standard_normal(N)) / Gauge("rod", STATIONS[name], **GAUGE).strain_per_volt
        out[name] = np.round(volts / VOLTS_PER_CODE).astype(np.int16)
    return out


if __name__ == "__main__":
    np.savez(Path(__file__).with_name("drill_rod_blow.npz"), **make())
