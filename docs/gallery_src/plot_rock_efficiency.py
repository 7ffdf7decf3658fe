"""
Efficiency against rock stiffness, as a branch of periodic orbits
=================================================================

A rigid piston (``s = 10``) strikes a rod twice as stiff (impedance ratio ``r = 2``, 10 piston
lengths) over a rock with ``k_u = 10^6``; the drive pulls back, pushes and rests while the piston
blows (theory §4d). The one-impact orbit is followed by ``continue_orbit`` in the rock's loading
stiffness ``"rock.k"``, and each point's efficiency (work on rock over the energy available to the
blow) lies on Lundberg's curve ``4r/(1+r)^2 eta(alpha_r, gamma)``, ``alpha_r = k (2/s)/(r s)``
(tests/continuation/test_rock_continuation.py checks every point to 1e-10).
"""

import matplotlib.pyplot as plt
import numpy as np

import impactbar as ib
from impactbar.laws.rodrock import lundberg_efficiency

s, r, k_u = 10.0, 2.0, 1e6
law = ib.RodRock(segments=[ib.RodSegment(length=10.0, impedance=r)],
                 rock=ib.BilinearRock(k=20.0, k_u=k_u), blow_time=2.0)
model = ib.BarModel(s=s, d=0.3, R=0.0, n_modes=0, impact=law)
load = ib.PiecewiseConstantLoad([0.0, 1.0, 3.0], [-1.0, 2.0, 0.0])
start = [o for o in ib.periodic_orbits(model, load) if o.stable][0]
branch = ib.continue_orbit(start, "rock.k", 300.0)

k = branch.values
eff = [o.contacts[0].efficiency for o in branch.orbits]
kk = np.linspace(k[0], k[-1], 400)
closed = [4 * r / (1 + r) ** 2 * lundberg_efficiency(2 * x / (r * s * s), k_u / x) for x in kk]
fig, ax = plt.subplots()
ax.plot(2 * kk / (r * s * s), closed, color="0.6", label="Lundberg, closed form")
ax.plot(2 * k / (r * s * s), eff, "o", label="branch of periodic orbits")
ax.set_xlabel(r"$\alpha_r = k\,(2/s)/(r s)$")
ax.set_ylabel("work on rock / energy available to the blow")
ax.legend()
print(f"{len(k)} points; largest efficiency {max(eff):.4f}")
