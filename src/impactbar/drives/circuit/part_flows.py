r"""The flows of the parts added to a drifter's oil circuit along a run (theory §11): each extra part's
flow records (a turbulent orifice's :math:`K \phi(\Delta p)`, a laminar leak's, a cushion's, a check
valve's, :mod:`.kinds`) evaluated at sampled states, for the histories of
:meth:`HydraulicCircuitDrive.histories <impactbar.drives.circuit.HydraulicCircuitDrive.histories>` and
:meth:`impactbar.physical.CircuitOrbitResult.histories`.

A part's records depend on the drive's mode only through its watched levels' flags (the piece of a
cushion's or a check valve's piecewise linear opening); at each sample a flag is the level's quantity
(the gap, or a pressure drop) at or above its level, the piece the state lies on. The opening is
continuous across its kinks, so that the flow does not depend on which side a sample on a kink takes.
"""

from __future__ import annotations

import numpy as np

from . import _network as NW
from . import kinds as KD
from .kinds._flow import phi

__all__ = ["part_flows"]


def part_flows(drive, z, gap) -> dict:
    r"""Each extra part's flow from its source node to its target at the given states.

    Parameters
    ----------
    drive : HydraulicCircuitDrive
        The drive with its extra parts.
    z : numpy.ndarray, shape (n_states, n)
        The circuit's states (its layout's order) at ``n`` samples.
    gap : numpy.ndarray, shape (n,)
        The piston's gap ``y`` there (bar lengths).

    Returns
    -------
    dict of numpy.ndarray
        ``q_<name>`` for each part with one flow record (``q_<name>_<i>`` for its ``i``-th of
        several), each of shape ``(n,)``, in the model's flow unit :math:`A_r L \Omega`; none for the
        preset circuit.

    Examples
    --------
    >>> import numpy as np
    >>> from dataclasses import replace
    >>> from impactbar.drives.circuit import LaminarLeak
    >>> from impactbar.physical import circuit_preset
    >>> drive = replace(circuit_preset("circuit-drifter").drive(),
    ...                 extra_parts=(LaminarLeak(source="rear", target="front", conductance=0.5),))
    >>> z = np.array([[1.0], [3.0], [2.0], [0.0]])  # p_f, p_r, p_s, x_v
    >>> part_flows(drive, z, np.array([0.1]))["q_leak"]  # G (p_r - p_f)
    array([1.])
    """
    comp = drive._composition
    z = np.atleast_2d(np.asarray(z, dtype=float))
    gap = np.asarray(gap, dtype=float)
    tank = np.full(gap.shape, drive.supply.tank_pressure)

    def pressure(j):
        return z[j] if j < comp.n_states else tank

    kinds = {NW.ORIFICE, *(m.CODE for m in KD.FLOWS)}
    out: dict = {}
    for part in drive.extra_parts:
        rest = part.records(comp.slots(part, (0, 0) + (0,) * len(comp.events)), drive.oil)
        flags = np.zeros((len(comp.events), gap.size), dtype=bool)
        for r in rest:
            if int(r[NW.KIND]) == NW.LEVEL:
                x = KD.level.quantity(r, pressure, gap)
                flags[int(r[KD.level.EVENT]) - 1] = x >= r[KD.level.LEVEL]
        flows = [np.empty(gap.size) for r in rest if int(r[NW.KIND]) in kinds]
        combos, which = np.unique(flags.T, axis=0, return_inverse=True)
        for c, combo in enumerate(combos):
            sel = np.flatnonzero(which.ravel() == c)
            recs = [r for r in part.records(comp.slots(part, (0, 0, *combo.tolist())), drive.oil)
                    if int(r[NW.KIND]) in kinds]
            for f, r in zip(flows, recs, strict=True):
                pa, pb = pressure(int(r[NW.O_FROM]))[sel], pressure(int(r[NW.O_TO]))[sel]
                if int(r[NW.KIND]) == NW.ORIFICE:
                    f[sel] = r[NW.O_K] * phi.py_func(pa - pb, r[NW.O_PTR2])  # (the law on arrays)
                else:
                    f[sel] = [q for q, *_ in (KD.law(int(r[NW.KIND]), r, 0, a, b, y)
                                              for a, b, y in zip(pa, pb, gap[sel], strict=True))]
        name = getattr(part, "name", type(part).__name__)
        out.update({f"q_{name}": flows[0]} if len(flows) == 1 else
                   {f"q_{name}_{i}": f for i, f in enumerate(flows)})
    return out
