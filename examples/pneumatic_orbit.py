"""A pneumatic hammer's one-impact orbits: end displacement, the field, and the multipliers.

Equations: theory §4-§7 (paper eqs. 8-14, 27-31). ``python examples/pneumatic_orbit.py [OUT.png]``
takes about 4 s of CPU time once numba's kernels are cached (3.8 s measured on a 2-core AMD EPYC
machine, most of it importing matplotlib and drawing); the first run with an empty cache compiles
the kernels first, some 12-23 s more.
"""

import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from impactbar import BarModel, CosineLoad, periodic_orbits  # noqa: E402
from impactbar.plotting import plot_multipliers, plot_orbit, plot_orbit_field  # noqa: E402

bar = BarModel(s=5.0, d=0.1, R=0.5, n_modes=16)
load = CosineLoad(p0=0.6, pk=1.0)
orbits = periodic_orbits(bar, load)
fig, axes = plt.subplots(len(orbits), 3, figsize=(15, 3.6 * len(orbits)), squeeze=False)
for row, orbit in zip(axes, orbits, strict=True):
    print(f"phase {orbit.phase:.5f}  v {orbit.impact_velocity:.5f}  {orbit.admissibility:<11} "
          f"max|mu| {orbit.max_abs_multiplier:.4f}  stable {orbit.stable}  paper {orbit.schur_stable}")
    plot_orbit(orbit, row[0])
    plot_orbit_field(orbit, row[1])
    plot_multipliers(orbit, row[2])
fig.tight_layout()
fig.savefig(sys.argv[1] if len(sys.argv) > 1 else "pneumatic_orbit.png", dpi=110)
