"""The exact blow as a :class:`~impactbar.laws.rodrock.blow.Blow` (theory §4d): the record
:func:`~impactbar.single_blow` and the simulator's exact blows return, its force and penetration
histories sampled from the exact pieces of :mod:`impactbar.laws.rodrock.exact` (the numbers and the
force methods exact whatever the sampling)."""

from __future__ import annotations

import math

import numpy as np

from ._records import (
    CHI_HEAD,  # the channels' lists
    JUNC_SHANK,
)
from .exact import MAX_PIECES, MAX_WINDOWS, exact_blow
from .exactresult import _eval_channel

__all__ = ["blow_from_exact", "exact_rod_rock_blow"]


def exact_rod_rock_blow(s, V, lengths, impedances, speeds, k, k_u, bit_mass, feed, *, t_max=None,
                        semi_infinite=False, samples_per_piston=32, record_field=False,
                        max_pieces=MAX_PIECES, max_windows=MAX_WINDOWS, piston=None, max_pool_bytes=None):
    r"""One blow of a rigid, unstressed piston (uniform or stepped) on a stepped rod, every wave
    exact (:func:`exact_blow`), as the :class:`~impactbar.laws.rodrock.blow.Blow` of
    :func:`single_blow`.

    Parameters
    ----------
    s, V, lengths, impedances, speeds, k, k_u, bit_mass, feed
        As :func:`impactbar.laws.rodrock.blow.rod_rock_blow`: the piston's impedance (the model's
        ``s``; its crossing time ``1/s``), the impact velocity, the segments (shape ``(J,)`` each;
        piston lengths, impedances and wave speeds relative to the piston's), the rock's loading and
        unloading stiffness, the bit's mass (piston masses) and the feed force (model units).
    t_max : float, optional
        Stop there (``ended_by = "t_max"``); by default the blow runs until its end is certified.
    semi_infinite : bool
        Lundberg's idealisation: the wave the bit reflects leaves the rod and never returns.
    samples_per_piston : int
        Samples per piston crossing time ``1/s`` in the recorded arrays (``times``, the force
        histories, ``field``); the numbers and the methods ``shank_force``, ``junction_force``,
        ``bit_force`` are exact whatever it is.
    record_field : bool
        Sample the force in piston and rod on a grid of cells (``samples_per_piston`` along the
        piston, each segment as many as its travel time holds, at least 1) at the sample times.
    max_pieces, max_windows : int
        Bounds of the cost (then ``ended_by = "budget"`` or ``"rings"``, with ``uncertainty``).
    max_pool_bytes : int, optional
        The most memory the wave pieces may take (:func:`exact_blow`).
    piston : SteppedPiston, optional
        A stepped piston of the model's mass and length (theory §12): each segment a delay line of
        travel time ``l_j / s`` and impedance ``s mu_j`` (``mu_j`` its mass per length), welded to
        the next; its boundaries need not fall on the samples. Default None: the uniform piston.

    Returns
    -------
    Blow
        ``method = "exact"``; ``grid_loss = 0``, ``cell_time`` the sampling step; ``cell_edges``
        (with ``record_field``) the sampled cells' edges, piston then rod.

    Raises
    ------
    ValueError
        As :func:`exact_blow`.

    Notes
    -----
    Theory §4d, "exact blows". As the lattice's, ``work_on_rock`` is the work done on the rock:
    what it dissipated (Lundberg's ``k (1 - 1/gamma)`` times the growth of ``p^2/2`` on every
    loading, ``rock_dissipated``) plus its recoverable elastic energy at the end
    (``rock_stored_energy``, 0 once the bit has lifted off).
    """
    s = float(s)
    lengths = np.asarray(lengths, float)
    imps = np.asarray(impedances, float)
    travel = lengths / (np.asarray(speeds, float) * s)
    from ._piston import piston_segments

    p_len, p_mu = piston_segments(piston)
    ex = exact_blow(p_len / s, s * p_mu, travel, s * imps, k=k, k_u=k_u, bit_mass=bit_mass, feed=feed,
                    impact_velocity=V, semi_infinite=semi_infinite, t_max=t_max, record=True,
                    max_pieces=max_pieces, max_windows=max_windows, max_pool_bytes=max_pool_bytes)
    return blow_from_exact(ex, s, lengths, travel, p_len, samples_per_piston, record_field)


def blow_from_exact(ex, s, lengths, travel, piston_lengths, samples_per_piston=32, record_field=False):
    """The :class:`~impactbar.laws.rodrock.blow.Blow` of an :class:`ExactBlow` (kept with
    ``record=True``): its force and penetration histories sampled ``samples_per_piston`` times per
    piston crossing time ``1/s`` (the numbers and the methods ``shank_force``, ``junction_force``,
    ``bit_force`` exact whatever it is), the field with ``record_field``.

    Parameters
    ----------
    ex : ExactBlow
    s : float
        The model's wave-speed ratio.
    lengths, travel : numpy.ndarray, shape (J,)
        The rod's segments' lengths (piston lengths) and travel times.
    piston_lengths : numpy.ndarray, shape (P,)
        The piston's segments' lengths (piston lengths).
    samples_per_piston : int
    record_field : bool

    Returns
    -------
    Blow
    """
    from .blow import Blow

    p_len = np.asarray(piston_lengths, dtype=float)
    dt = 1.0 / (s * samples_per_piston)
    T = ex.duration
    n = max(1, math.ceil(T / dt * (1.0 - 1e-12)))
    seg_cells = tuple(max(1, round(Ti / dt)) for Ti in travel)
    p_cells = _piston_samples(p_len, samples_per_piston)
    _check_samples(n, J=lengths.size, cells=(sum(p_cells) + sum(seg_cells)) if record_field else 0)
    times = np.minimum(dt * np.arange(n + 1), T)
    mid = 0.5 * (times[:-1] + times[1:])
    J = lengths.size
    junc, bit, pen = _sampled(ex, mid, times, J)
    fld = edges = None
    if record_field:
        fld, edges = _field(ex, np.concatenate((p_len / s, travel)), np.concatenate((p_len, lengths)),
                            (*p_cells, *seg_cells), mid)
    return Blow(
        times=times, shank_forces=junc[:, JUNC_SHANK].copy(), junction_forces=junc,
        bit_forces=bit, penetrations=pen, field=fld,
        energy_at_impact=ex.energy_at_impact, feed_work=ex.feed_work,
        available_energy=ex.available_energy, work_on_rock=ex.work_on_rock + ex.rock_energy,
        piston_energy=ex.piston_energy, rebound_velocity=ex.rebound_velocity,
        rod_energy=ex.rod_energy + ex.radiated, grid_loss=0.0, rock_stored_energy=ex.rock_energy,
        max_penetration=ex.max_penetration, permanent_penetration=ex.permanent_penetration,
        advance=ex.advance, ended_by=ex.ended_by, cell_time=dt, piston_cells=sum(p_cells),
        segment_cells=seg_cells, cell_edges=edges, length_error=0.0, drive_work=ex.drive_work, gap=ex.gap,
        shank_displacement=ex.shank_displacement, piston_waves=None, rod_waves=None,
        bit_velocity=ex.bit_velocity, method="exact", uncertainty=ex.uncertainty, loadings=ex.loadings,
        radiated=ex.radiated, exact=ex, bit_energy=ex.bit_energy)


def _sampled(ex, mid, times, J):
    """The forces at the rod's ``J`` junctions (the shank first) at the sorted times ``mid``, shape
    ``(mid.size, J)``, and the rock's force and the penetration at the sorted ``times``: the values
    of :meth:`ExactBlow.junction_force`, ``bit_force`` and ``penetration``, each piece loaded once.

    A process's first records take the evaluators' interpreted twins, which give their machine
    code's bits (:func:`~impactbar.dynamics.compiled.interpreted_first`): the README's blow samples
    its histories in some 0.01 s of CPU time there, against about 1 s to compile them."""
    from ...dynamics.compiled import interpreted_first
    from . import _exacthistory as H

    scale, (PF, PI, TK, TC, CHI, lam, lamk), nodes, n_p = ex._hist
    first = 2 * nodes + 1 + n_p
    junc = np.empty((mid.size, J))
    heads = np.ascontiguousarray(CHI[first:first + J, CHI_HEAD])  # (the junctions' histories)
    interpreted_first(H.eval_histories, scratch=(7,))(PF, PI, TK, TC, lam, heads, mid, junc, 0, lamk)
    bit = np.empty(times.size)
    pen = np.empty(times.size)
    head = int(CHI[3 * nodes + 1, CHI_HEAD])
    interpreted_first(H.eval_bit, scratch=(7, 8))(PF, PI, TK, TC, lam, head, times, pen, bit, lamk)
    return scale * junc, scale * bit, scale * pen


#: Most values the recorded arrays of one exact blow may hold (1 GiB as float64)
MAX_SAMPLES = 2**27


def _check_samples(n, J, cells):
    """Refuse recorded arrays of ``n`` samples of ``J + 1`` histories and ``cells`` field values
    beyond ``MAX_SAMPLES``."""
    total = float(n) * (J + 3 + cells)
    if total > MAX_SAMPLES:
        what = "record_field would keep" if cells else "the recorded histories would keep"
        raise ValueError(f"single blow: {what} {total:.3g} values (more than {MAX_SAMPLES}) over "
                         f"{n} samples; use a shorter t_max or fewer cells_per_piston")


def _piston_samples(lengths, n):
    """The sampled cells of each piston segment (shape ``(P,)``, each at least 1): ``n`` along the
    piston shared out by the segments' lengths (Hamilton's largest remainders)."""
    if lengths.size == 1:
        return (int(n),)
    share = lengths / lengths.sum() * n
    cells = np.maximum(np.floor(share).astype(np.int64), 1)
    while cells.sum() < n:
        cells[np.argmax(share - cells)] += 1
    return tuple(int(c) for c in cells)


def _field(ex, travel, lengths, cells, t):
    """The force ``F + G`` at the centres of ``cells[i]`` cells of every segment (piston first) at
    the times ``t``: the right-going wave that left the segment's left end ``u T`` earlier and the
    left-going one that left its right end ``(1 - u) T`` earlier (``u`` the cell's fraction)."""
    scale, pools, *_ = ex._hist
    cols, edges = [], [np.array([-1.0])]
    x0 = -1.0
    for i, (Ti, Li, n) in enumerate(zip(travel, lengths, cells, strict=True)):
        u = (np.arange(n) + 0.5) / n
        for ui in u:
            F = _eval_channel(pools, 2 * i, t - ui * Ti, kind=0, head=2 * i)
            G = _eval_channel(pools, 2 * i + 1, t - (1.0 - ui) * Ti, kind=0, head=2 * i + 1)
            cols.append(scale * (F + G))
        edges.append(x0 + Li * np.arange(1, n + 1) / n)
        x0 += Li
    return np.column_stack(cols), np.concatenate(edges)
