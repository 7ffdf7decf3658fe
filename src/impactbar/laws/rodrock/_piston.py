"""A stepped piston's cells on the blow's grid (theory §12): the piston's segments, from the driven
end to the struck end, become cells of impedances ``s mu_j`` (``mu_j`` the segments' masses per
length, the piston's mass 1 and length 1, one material), welded to each other like the rod's cells
and joined to the shank by the blow's unilateral contact
(:mod:`impactbar.laws.rodrock.blow`). As elwaspatid builds a stepped striker: ``Barhete`` of the
segments' lengths and diameters on one travel-time lattice, given its velocity, in contact with the
bar (``WP2``; D. Brizard, github.com/dbrizard/elwaspatid, after Bacon, Int. J. Impact Eng. 13
(1993) 527-539)."""

from __future__ import annotations

import numpy as np


def piston_segments(piston):
    """``(lengths, masses per length)`` of the piston's segments, each shape ``(n,)``, from the driven
    end; ``((1,), (1,))`` for None, the uniform piston.

    Raises
    ------
    ValueError
        If ``piston`` is neither None nor a :class:`~impactbar.dynamics.stepped.SteppedPiston`.
    """
    if piston is None:
        return np.ones(1), np.ones(1)
    from ...dynamics.stepped import SteppedPiston

    if not isinstance(piston, SteppedPiston):
        raise ValueError("piston must be a SteppedPiston or None (the uniform piston); "
                         f"got piston={piston!r}")
    return piston.lengths, piston.mass_per_length


def piston_cells(s, lengths, mass_per_length, n_p):
    """The segments' cells (int, shape ``(n,)``: the boundaries rounded to whole cells from the
    driven end, so that the piston keeps ``n_p`` cells) and every cell's impedance (shape
    ``(n_p,)``: ``s mu_j``, scaled so that the rounded piston's mass is 1). One segment: ``s`` in
    every cell, exactly the uniform piston's."""
    cells = np.diff(np.round(np.concatenate(([0.0], np.cumsum(lengths))) * n_p)).astype(np.int64)
    z = np.repeat(mass_per_length, cells)
    return cells, s * z / (np.sum(z) / n_p)
