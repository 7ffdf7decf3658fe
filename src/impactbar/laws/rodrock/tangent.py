r"""Exact derivatives of the lattice's blow with respect to the piston's cell impedances
(theory §12): the tangent-linear blow.

The lattice's blow (:func:`~impactbar.laws.rodrock.blow.rod_rock_blow`) is a discrete-time
recursion: per step every junction gives :math:`N = 2 (Z_R F + Z_L G)/(Z_L + Z_R)` and the waves
move one cell, the piston-shank contact is on or off, and the bit on the rock is solved exactly
over the cell on each branch of the bilinear law. Its work on the rock and its piston-shank force
on every step are therefore smooth functions of the cells' impedances wherever the switching
schedule stays the same: the contact on or off per step, the rock's branch on each of the bit's
sub-steps, the step that ends the blow. :func:`rod_rock_blow_tangent` runs that recursion with its
forward-mode (tangent-linear) derivative beside it (compiled, ``_rocktangent``; the rod's uniform
segments carried as delay lines, where the lattice's junctions pass the waves on): the schedule held
as the primal run decides it, the times of the branch changes inside a step moving with the state
(a massless bit's closed-form switch time differentiated; a bit with mass crosses every switch with
a continuous vector field, so that its switch time's derivative drops out). The derivatives are
exact to rounding for the discrete blow; across a change of the schedule the blow has a kink and
the derivative is that of the piece the primal run is on. Checked against central finite differences
of :func:`~impactbar.laws.rodrock.blow.rod_rock_blow` (tests/laws/test_rock_tangent.py).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from ..._shared.validate import check_real
from . import _records as S
from ._bit import _LOAD
from .blow import _bit_params, _loop_controls
from .grid import _check_blow_size, blow_grid, whole_steps

__all__ = ["BlowTangent", "rod_rock_blow_tangent"]


@dataclass(frozen=True)
class BlowTangent:
    """A lattice blow's work on the rock and piston-shank forces with their derivatives along
    ``nv`` directions of the piston's cell impedances (theory §12; the model's units of
    :class:`~impactbar.laws.rodrock.blow.Blow`).

    Attributes
    ----------
    work_on_rock : float
        ``int R dp`` over the blow plus the rock's elastic energy under the feed at the start
        (:attr:`Blow.work_on_rock`).
    work_tangent : numpy.ndarray, shape (nv,)
        Its derivative along each direction.
    energy_at_impact : float
        The piston's energy at impact, ``V^2/2`` times its mass ``dt sum(Z)/s``.
    energy_tangent : numpy.ndarray, shape (nv,)
        Its derivative along each direction.
    shank_forces : numpy.ndarray, shape (n,)
        The piston-shank force on each step (:attr:`Blow.shank_forces`).
    shank_tangents : numpy.ndarray, shape (n, nv)
        Their derivatives.
    cell_time : float
        The step ``dt``.
    ended_by : str
        ``"energy"`` or ``"t_max"`` (:attr:`Blow.ended_by`).
    """

    work_on_rock: float
    work_tangent: np.ndarray = field(repr=False)
    energy_at_impact: float
    energy_tangent: np.ndarray = field(repr=False)
    shank_forces: np.ndarray = field(repr=False)
    shank_tangents: np.ndarray = field(repr=False)
    cell_time: float
    ended_by: str

    def __repr__(self) -> str:
        return (f"BlowTangent(work on rock {self.work_on_rock:.6g}, {self.work_tangent.size} directions, "
                f"{self.shank_forces.size} steps, ended by {self.ended_by})")


def rod_rock_blow_tangent(s, V, lengths, impedances, speeds, k, k_u, bit_mass, feed, piston_impedances,
                          directions, *, t_max=None, energy_fraction=1e-9) -> BlowTangent:
    r"""The lattice's blow of a piston given by its cells, and the derivatives of its work on the rock
    and of its shank forces along directions of those cells' impedances (theory §12).

    The piston is ``n_p = len(piston_impedances)`` cells of one travel time ``dt = 1/(s n_p)``, from
    its driven (free) end to the struck end, moving rigidly at ``V`` and unstressed at impact; the
    rod, the rock, the bit and the feed as in :func:`~impactbar.laws.rodrock.blow.rod_rock_blow`
    with ``cells_per_piston = n_p``, whose blow this is, to rounding, when the cells'
    impedances have the mean ``s`` (a piston of mass 1; ``rod_rock_blow(...,
    piston=SteppedPiston(np.ones(n_p), piston_impedances))`` builds the same cells).

    Parameters
    ----------
    s, V, lengths, impedances, speeds, k, k_u, bit_mass, feed
        As :func:`~impactbar.laws.rodrock.blow.rod_rock_blow` (dimensionless; the rod's
        ``lengths``, ``impedances``, ``speeds`` of shape ``(J,)``).
    piston_impedances : array_like, shape (n_p,)
        The piston's cells' impedances (``> 0``, finite; model units, ``s`` times the mass per
        length), ``n_p >= 1``.
    directions : array_like, shape (n_p, nv) or (n_p,)
        The derivatives of the cells' impedances along ``nv >= 1`` directions (finite).
    t_max : float, optional
        Longest blow (model time, ``> 0``); default as ``rod_rock_blow``'s.
    energy_fraction : float
        As ``rod_rock_blow``'s (``>= 0``).

    Returns
    -------
    BlowTangent
        The work on the rock, the piston's energy at impact and the shank force per step, each
        with its derivatives: exact (to rounding) on the piece of the blow where the switching
        schedule of this run holds; there the blow is smooth in the impedances.

    Raises
    ------
    ValueError
        ``piston_impedances`` not positive and finite or empty, ``directions`` of another length or
        not finite, ``V``, ``t_max`` or ``energy_fraction`` out of range, or the blow too large
        (as ``rod_rock_blow``).

    Examples
    --------
    A uniform piston of 16 cells on a matched long rod and Lundberg's rock (``alpha = 2 k/s^2``):
    the derivative of the work as mass moves from the driven end's cell to the struck end's (the
    piston's mass held, as ``rod_rock_blow`` holds it), against a central difference.

    >>> import numpy as np
    >>> from impactbar import SteppedPiston
    >>> from impactbar.laws.rodrock.blow import rod_rock_blow
    >>> from impactbar.laws.rodrock.tangent import rod_rock_blow_tangent
    >>> rod = ([20.0], [1.0], [1.0])
    >>> Z, dZ = np.ones(16), np.zeros(16)
    >>> dZ[0], dZ[-1] = -1.0, 1.0
    >>> tb = rod_rock_blow_tangent(1.0, 1.0, *rod, 0.6, 6e11, 0.0, 0.0, Z, dZ, t_max=44.0)
    >>> tb  # Lundberg's efficiency 0.8138825 at alpha = 1.2 times the impact energy 1/2
    BlowTangent(work on rock 0.406941, 1 directions, 704 steps, ended by t_max)
    >>> work = lambda z: rod_rock_blow(1.0, 1.0, *rod, 0.6, 6e11, 0.0, 0.0, cells_per_piston=16,
    ...     t_max=44.0, piston=SteppedPiston(np.ones(16), z)).work_on_rock
    >>> h = 1e-5
    >>> fd = (work(Z + h * dZ) - work(Z - h * dZ)) / (2 * h)
    >>> bool(abs(tb.work_tangent[0] - fd) < 1e-7 * abs(fd))
    True
    """
    from ._rocktangent import blow_loop_tangent

    Zp = np.asarray(piston_impedances, dtype=float)
    if Zp.ndim != 1 or Zp.size < 1 or not np.all(np.isfinite(Zp)) or not np.all(Zp > 0.0):
        raise ValueError("piston_impedances must be a non-empty 1-D array of positive finite numbers; "
                         f"got {piston_impedances!r}")
    D = np.asarray(directions, dtype=float)
    if D.ndim == 1:
        D = D[:, None]
    if D.ndim != 2 or D.shape[0] != Zp.size or D.shape[1] < 1 or not np.all(np.isfinite(D)):
        raise ValueError(f"directions must be finite, of shape ({Zp.size}, nv) with nv >= 1 or "
                         f"({Zp.size},); got shape {np.shape(directions)}")
    V = check_real("V", V, lo=0.0, lo_open=True)
    energy_fraction = check_real("energy_fraction", energy_fraction, lo=0.0)
    n_p, nv = Zp.size, D.shape[1]
    grid = blow_grid(s, lengths, impedances, speeds, n_p, None)
    Z = grid.Z.copy()
    Z[:n_p] = Zp
    grid = dataclasses.replace(grid, Z=Z)
    dt = grid.cell_time
    if t_max is None:
        t_max = 20.0 * (dt * n_p + float(np.sum(grid.travel)))
    t_max = check_real("t_max", t_max, lo=0.0, lo_open=True)
    _check_blow_size(Z.size, t_max / dt, False)
    n_max = whole_steps(t_max, dt)
    Fp = 0.5 * Zp * V
    Gp = -Fp
    dZ = np.ascontiguousarray(D.T)
    dFp = 0.5 * V * dZ
    dGp = -dFp
    E0 = float(np.sum((Fp ** 2 + Gp ** 2) / Zp)) * dt
    dE0 = 0.5 * V * V * dt * D.sum(axis=0)
    seg_len = np.array(grid.segment_cells, dtype=np.int64)
    seg_z = Z[n_p + np.concatenate(([0], np.cumsum(seg_len)[:-1]))]
    bs = np.zeros(S.BIT_SIZE)  # fresh rock loaded to the feed (blow._Bit)
    bs[S.BIT_P] = feed / k
    bs[S.BIT_BRANCH] = float(_LOAD)
    bs[S.BIT_PMAX], bs[S.BIT_RMAX] = bs[S.BIT_P], feed
    bs[S.BIT_PPERM] = bs[S.BIT_PMAX] - bs[S.BIT_RMAX] / k_u
    bp = _bit_params(Z[-1], k, k_u, bit_mass, feed)
    dbs = np.zeros((S.BIT_SIZE, nv))
    shank = np.zeros(n_max)
    dshank = np.zeros((n_max, nv))
    acc = np.zeros(S.ACC_SIZE)
    P = np.empty((S.CELL_SIZE, n_p))
    P[S.CELL_F], P[S.CELL_G], P[S.CELL_Z] = Fp, Gp, Zp
    dP = np.empty((S.CELL_SIZE, nv, n_p))
    dP[S.CELL_F], dP[S.CELL_G], dP[S.CELL_Z] = dFp, dGp, dZ
    blow_loop_tangent(P, dP, seg_len, seg_z, bs, dbs, bp, _loop_controls(dt, energy_fraction * E0, 0, 0.0),
                      shank, dshank, acc)
    n = int(acc[S.ACC_STEPS])
    rock0 = feed * feed / (2.0 * k_u)
    return BlowTangent(work_on_rock=float(bs[S.BIT_WORK] + rock0), work_tangent=dbs[S.BIT_WORK].copy(),
                       energy_at_impact=E0, energy_tangent=dE0, shank_forces=shank[:n],
                       shank_tangents=dshank[:n], cell_time=dt,
                       ended_by=("t_max", "energy")[int(acc[S.ACC_ENDED])])
