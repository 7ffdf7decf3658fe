"""
Fig. 5: the stable band of the pneumatic hammer
===============================================

The band of ``p0/p1`` in which the one-impact orbit exists and is stable (``k = 1``, rigid bar), for
``2πd = 0`` and ``2πd = 0.03`` (theory §6). Damping moves the edges by under 2 % except near
``R = 1``, so the lower panel shows the shift. At ``R = 0`` the upper part of the band
(``0.303314 < p0/p1 < 0.318310``) is stable by the paper's criterion but not a motion: the end
sticks (theory §5, Findings).
"""

from impactbar import paper

data = paper.fig5_data(n=12)
paper.fig5_plot(data)
print(f"R = 0, 2πd = 0: stable {data['stability_exact_2pid=0'][0]:.6f} .. "
      f"{data['existence_2pid=0'][0]:.6f}, sticks from {data['sticks_from_2pid=0'][0]:.6f}")
