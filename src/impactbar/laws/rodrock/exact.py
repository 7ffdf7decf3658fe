r"""The exact blow: a piston of uniform segments strikes a rod of uniform segments whose bit loads a
bilinear rock (theory §4d), every wave carried exactly (:mod:`impactbar.laws.rodrock._exactloop`).

**What is exact.** Each segment is a delay line: a force wave leaving one end arrives at the other
its travel time later, unchanged, so the state of the chain is the set of waves that left each end
in the last travel time. Every such wave is a chain of *pieces*, each a finite sum
``Re sum c tau^d e^{lam tau}`` over a table of exponents: constants (a rigid piston's waves), the
characteristic roots of the bit on each branch of the rock (``-k/Z``, ``-k_u/Z`` and 0 for a
massless bit; the roots of ``m r^2 + Z r + b`` with a mass), and those of the data (a drive, a
piston's modal fields). Every operation maps such pieces to such pieces exactly:

- a welded junction between impedances ``Z_L`` and ``Z_R`` transmits and reflects,
  ``f_out = (2 Z_R f_in + (Z_L - Z_R) g_in)/(Z_L + Z_R)``,
  ``g_out = ((Z_R - Z_L) f_in + 2 Z_L g_in)/(Z_L + Z_R)``;
- the piston's free far end reflects ``f_out = -g_in`` (``N = p(t)`` under a drive);
- the piston-shank interface is welded while its force ``N = 2 (Z_R f_in + Z_L g_in)/(Z_L + Z_R)`` is
  compressive and free (``N = 0``) otherwise; the gap is the exact integral of ``v_s - v_p``, and
  contact resumes where it closes;
- at the bit, ``m p'' + Z p' + R(p) = 2 F + f`` (``F`` the arriving wave, ``f`` the feed) is linear on
  each branch of Lundberg's law (loading ``R = k p``, unloading and reloading
  ``R = k_u (p - p_perm)``, lift-off ``R = 0``) and is solved in closed form: polynomial times
  exponential terms where the forcing shares an exponent with the branch (one degree more);
  the reflected wave is ``G = F - Z p'``.

Every switch (separation, re-contact, unloading, reloading, lift-off, landing) is the first zero of
an exact piece, located by a certified branch-and-bound search and refined by safeguarded Newton
steps to rounding; arrivals that differ only by the rounding of sums of travel times are one break
point. Nothing is averaged over cells; segment lengths need not be commensurate.
Exponents closer than ``0.05 / h`` (``h`` the shortest travel time) are handled as one, the
difference carried by the Taylor series of ``e^{delta tau}`` over at most ``h`` (to ``1e-18``), so a
soft rock (``k -> 0``), a light bit (``m -> 0``: below ``1e-18`` of the bit's time scales the
massless bit itself) or ``k_u -> k`` change nothing abruptly. Terms below ``1e-19`` of the blow's
force scale on its time scale are dropped.

**When the blow ends** (:attr:`ExactBlow.ended_by`), from bounds that hold for all later time:

- ``"separated"``: the piston has left the shank for good (its mean velocity ``<= 0`` and its struck
  end, within ``2 sqrt(2 C_p E_int)`` of where it is, behind the lowest point the shank can reach:
  with a feed, the static position less what the rod's energy ``Psi`` above the static state can
  lift it; without one, the rod's mean velocity bounded by ``sqrt(2 Psi / M_r)``) and the rock
  can no longer yield (``Psi < (R_max - f)^2/(2 k_u)``, the energy that loading past ``p_max`` needs);
  the rod may go on ringing on the rock without loss;
- ``"lifted"``: the same, the rod having left the rock for good (no feed, the bit off the rock,
  the rod moving back, its waves unable to bring the bit back);
- ``"spent"``: the energy that could still reach the rock (the rod's, the bit's and the rock's above
  the static state, and the piston's while it may strike again) is below ``1e-17`` of the available
  energy: no result can move by more;
- ``"may_yield"`` (with a feed, no ``t_max``): the piston has gone for good and the rock is not
  loading, but ``Psi`` could still load it past ``R_max``: under the feed a lossless rod ringing on
  the rock may make it yield again at any later time, so no end is certain. The loading episodes so
  far are reported, and ``uncertainty`` bounds the rock work still possible: each new yield lowers
  ``Psi`` by its dissipation less the feed's work on the permanent advance, at least
  ``1 - f / R_max`` of the dissipation, so the rock can still take at most
  ``Psi R_max / (R_max - f)``. The efficiency is that of the instant the blow ended: its
  denominator holds the feed's work to then, which the ringing rod moves either way (theory §4d);
- under a drive (``drive`` given, no ``fixed_horizon``) the piston counts as gone once out of
  contact with its mean velocity ``<= 0`` (what it does next is the drive's: the coupled blow's end,
  :mod:`~impactbar.laws.rodrock.coupled_exact`), and ``"may_yield"`` ends the blow with a ``t_max``
  too;
- ``"t_max"``: the horizon the caller gave;
- ``"rings"``: the cost bound reached with the rock unable to yield but the piston's return not
  excluded (a lossless rod and piston touching again and again);
- ``"budget"``: the cost bound reached otherwise (``uncertainty`` bounds what the rock could still
  take; with a feed, times ``R_max / (R_max - f)`` as for ``"may_yield"``).

A semi-infinite rod (Lundberg's idealisation: the wave the bit reflects never returns) is the
option ``semi_infinite=True``: the bit's reflected wave leaves the chain (its energy booked as
``radiated``).
"""

from __future__ import annotations

import functools
import math
import threading
from typing import NamedTuple

import numpy as np

from . import _exactpieces as P
from . import _records as S
from ._exactdata import _Data
from ._exactresume import _resumed, _run, pool_bytes, run_kernel
from ._records import (  # the pool's columns and the channels' lists
    CHI_HEAD,
    CHI_TAIL,
    NSI_CONTACT,
    PF_INT,
    PF_REF,
    PF_START,
    PF_VALID,
    PI_COUNT,
    PI_NEXT,
    PI_TERMS,
)
from .exactresult import CERTIFIED as CERTIFIED
from .exactresult import ExactBlow as ExactBlow
from .exactresult import _result

__all__ = ["CERTIFIED", "ExactBlow", "PoolOverflow", "exact_blow"]

_SPENT = 1e-17
_TOL = 1e-19
#: cost bounds of one blow (pieces stored, windows of the shortest travel time)
MAX_PIECES = 2_000_000
MAX_WINDOWS = 2_000_000
#: the wave-piece pool is enlarged 4-fold while it overflows, never past this many bytes
MAX_POOL_BYTES = 2 ** 31


class PoolOverflow(ValueError):
    """The exact blow's wave pieces would need more memory than its bound (a light bit's fast
    branches make long series; waves broken into very many pieces): the lattice is the method for
    such a blow."""


def _roots(m, Z, b):
    """Roots of ``m r^2 + Z r + b`` (fast first), or of ``Z r + b`` for ``m = 0``; without
    cancellation."""
    if m == 0.0:
        return [complex(-b / Z)]
    disc = Z * Z - 4.0 * m * b
    if disc >= 0.0:
        q = -0.5 * (Z + math.sqrt(disc))
        return [complex(q / m), complex(b / q) if b != 0.0 else 0j]
    om = math.sqrt(-disc) / (2.0 * m)
    re = -Z / (2.0 * m)
    return [complex(re, om), complex(re, -om)]


def _table(data, roots):
    """The exponent table: 0, the data's exponents and the roots, each once; the roots' indices."""
    lam, index = _table_of(tuple(complex(x) for x in data), tuple(complex(r) for r in roots))
    return np.array(lam, dtype=complex), list(index)


@functools.lru_cache(maxsize=256)
def _table_of(data, roots):
    lam = [0j]
    for x in (*data, *roots):
        if all(x != y for y in lam):
            lam.append(x)
    return tuple(lam), tuple(lam.index(r) for r in roots)


def _compliance(T, Z, lead_mass):
    """``int N^2 dx / EA`` for the chain (segments' travel times ``T`` and impedances ``Z`` in order
    from the loaded end's far side to the loaded end) under a unit force at its end balanced by
    uniform acceleration, ``lead_mass`` a point mass at the far side: the compliance of the end
    relative to the centre of mass."""
    masses = np.asarray(Z) * np.asarray(T)
    M = lead_mass + float(masses.sum())
    n0 = lead_mass / M
    c = 0.0
    for Ti, Zi, mi in zip(np.asarray(T).tolist(), np.asarray(Z).tolist(), masses.tolist(), strict=True):
        n1 = n0 + mi / M
        c += Ti / Zi * (n0 * n0 + n0 * n1 + n1 * n1) / 3.0
        n0 = n1
    return c


def _check_chain(name, times, imps):
    T = np.asarray(times, dtype=float)
    Z = np.asarray(imps, dtype=float)
    if T.ndim != 1 or T.size == 0 or T.shape != Z.shape:
        raise ValueError(f"{name}: travel times and impedances must be 1-d, non-empty, of one length; "
                         f"got shapes {T.shape} and {Z.shape}")
    for what, a in (("travel times", T), ("impedances", Z)):
        if not (0.0 < float(a.min()) and float(a.max()) < math.inf):  # (a NaN fails both)
            raise ValueError(f"{name}: {what} must be finite and > 0; got {a}")
    return T, Z


def exact_blow(piston_times, piston_impedances, rod_times, rod_impedances, *, k, k_u, bit_mass=0.0,
               feed=0.0, impact_velocity=None, semi_infinite=False, t_max=None, record=True,
               max_pieces=MAX_PIECES, max_windows=MAX_WINDOWS, max_pool_bytes=None, initial=None,
               drive=None, fixed_horizon=False, lean=False, _trusted=False, _log=0, _pool=None,
               _energies=True, _defer=False, _keep=None) -> ExactBlow:
    r"""The blow of a rigidly moving, unstressed piston (or of a piston in any state given by its
    waves, under a drive) on a rod resting on the rock under the feed, every wave exact (theory §4d;
    the module's text says what is exact and how the end is decided).

    Parameters
    ----------
    piston_times, piston_impedances : array_like, shape (P,)
        The piston's segments from its far (driven) end to its struck end: travel times (model time)
        and impedances (model units; a uniform piston of the model is ``[1/s]``, ``[s]``).
    rod_times, rod_impedances : array_like, shape (R,)
        The rod's segments from the shank to the bit.
    k, k_u : float
        The rock's loading and unloading stiffness, ``0 < k <= k_u``.
    bit_mass : float
        ``>= 0`` (model masses; the piston of the model has mass 1).
    feed : float
        The static feed force on the shank, ``>= 0``.
    impact_velocity : float, optional
        ``> 0``: the piston moves rigidly, unstressed, at this velocity. Exactly one of it and
        ``initial``.
    semi_infinite : bool
        Lundberg's idealisation: the wave the bit reflects leaves the chain and never returns.
    t_max : float, optional
        Stop there (``ended_by = "t_max"``); by default the blow runs until its end is certified.
    record : bool
        Keep the force and penetration histories (for :meth:`ExactBlow.junction_force` and the
        peaks).
    max_pieces, max_windows : int
        Bounds of the cost (``ended_by = "budget"`` or ``"rings"`` past them).
    max_pool_bytes : int, optional
        The most memory the wave pieces may take; default ``MAX_POOL_BYTES`` (2 GiB).
    initial : sequence of 2 P tuples, optional
        The piston's waves at impact (instead of ``impact_velocity``): for each piston segment, in
        order, the right-going wave that left its driven-side end and the left-going one that left
        its struck-side end over the last travel time, each a piece ``(exps, degs, coefs)`` (arrays
        of one length: ``Re sum coefs tau^degs e^{exps tau}`` for ``0 <= tau < T_i``, ``tau`` from
        the emission time ``-T_i``; conjugate-complete, so that the sum is real). Built from a
        modal state by :func:`impactbar.laws.rodrock.exactmap.initial_waves`.
    drive : tuple, optional
        The force ``p(t)`` on the piston's far end, ``(starts, pieces)``: pieces as ``initial``'s,
        the ``j``-th valid from ``starts[j]`` (increasing, ``starts[0] <= 0``; ``tau`` from it) to
        the next start.
    fixed_horizon : bool
        Run to ``t_max`` (required) without deciding the end (a drive can bring the piston back):
        the simulator's blow of a fixed duration. Without it under a drive the end is decided as
        the module's text says for a drive (the coupled blow's).
    lean : bool
        Return only ``(ws, scale)``, the solver's workspace after the run and the forces' scale,
        without the energies (the impact map's many blows: :mod:`~impactbar.laws.rodrock.exactmap`).

    Returns
    -------
    ExactBlow

    Raises
    ------
    ValueError
        An argument outside its range (named), a blow whose energies the float range cannot hold,
        or one whose wave pieces would need more than ``max_pool_bytes`` of memory
        (:class:`PoolOverflow`, a ``ValueError``).
    """
    Tp, Zp = _check_chain("piston", piston_times, piston_impedances)
    Tr, Zr = _check_chain("rod", rod_times, rod_impedances)
    from ..._shared.validate import check_int, check_real

    k = check_real("k", k, lo=0.0, lo_open=True)
    k_u = check_real("k_u", k_u, lo=k)
    m = check_real("bit_mass", bit_mass, lo=0.0)
    f = check_real("feed", feed, lo=0.0)
    if (impact_velocity is None) == (initial is None):
        raise ValueError("give exactly one of impact_velocity and initial")
    V = 0.0
    if impact_velocity is not None:
        V = check_real("impact_velocity", impact_velocity, lo=0.0, lo_open=True)
    if t_max is not None:
        t_max = check_real("t_max", t_max, lo=0.0, lo_open=True)
    if fixed_horizon and t_max is None:
        raise ValueError("fixed_horizon needs a t_max")
    max_pieces = check_int("max_pieces", max_pieces, lo=16)
    max_windows = check_int("max_windows", max_windows, lo=1)
    if not isinstance(semi_infinite, bool | np.bool_):
        raise ValueError(f"semi_infinite must be True or False; got {semi_infinite!r}")
    T = np.concatenate((Tp, Tr))
    Z = np.concatenate((Zp, Zr))
    h = float(T.min())
    Tsum = float(T.sum())
    if not (Tsum / h <= 1e9):
        raise ValueError(f"the travel times span {T.min():.3g} to {T.max():.3g}: the shortest would "
                         "need more than 1e9 windows to cross the chain once")
    if 2.0 * Tp.sum() / h > max_windows:
        raise ValueError(f"max_windows = {max_windows} cannot hold even the piston's contact "
                         f"({2.0 * Tp.sum() / h:.3g} windows of the shortest travel time {h:.3g})")
    Zb = float(Zr[-1])
    data = _Data(initial, drive, Tp, trusted=_trusted) if initial is not None else None
    # scale: the largest of the impact force (the data's waves and drive) and the feed is 1
    scale = max(float(Zp[-1]) * V if data is None else data.scale, f)
    if scale == 0.0:
        scale = 1.0
    Vn, fn = V / scale * 1.0, f / scale
    C_rod = float((Tr / Zr).sum())
    e_scale = 0.5 * float((Zp * Tp).sum()) * (Vn * Vn if data is None else 1.0) \
        + fn * fn * (0.5 * C_rod + 0.5 / k_u)
    if not (1e-290 < scale * scale * e_scale < 1e290):
        raise ValueError(f"impact_velocity = {V:g} and feed = {f:g} give a blow whose energy "
                         f"(~{scale * scale * e_scale:.3g}) the float range cannot hold; choose units that "
                         "keep it within 1e-290 .. 1e290")
    # a bit lighter than 1e-18 of its time scales is the massless bit
    if m > 0.0 and m * max(k_u / (Zb * Zb), 1.0 / (Zb * h)) < 1e-18:
        m = 0.0
    branches = [k, k_u, 0.0]
    roots = []
    for b in branches:
        if m == 0.0:
            roots.append([complex(-b / Zb)])
        elif b == 0.0:
            roots.append([complex(-Zb / m), 0j])
        else:
            roots.append(_roots(m, Zb, b))
    flat = [r for rs in roots for r in rs]
    lam, index = _table([] if data is None else data.exponents, flat)
    nr = 2 if m > 0.0 else 1
    RT = np.zeros((3, 2), dtype=complex)
    RC = np.zeros((3, 2), dtype=np.int64)
    RD = np.zeros((1 + _log, S.RD_COLS), dtype=complex)  # the switch log (_exactloop), _log rows
    i = 0
    for br in range(3):
        for q in range(nr):
            RT[br, q] = flat[i]
            RC[br, q] = index[i]
            i += 1
    Mp = float((Zp * Tp).sum())
    Mr = float((Zr * Tr).sum()) + m
    Lb = max(2.0 * Tsum, h)
    PR = np.zeros(S.PR_SIZE)
    PR[S.PR_K], PR[S.PR_KU], PR[S.PR_MASS], PR[S.PR_FEED], PR[S.PR_ZBIT], PR[S.PR_H] = k, k_u, m, fn, Zb, h
    PR[S.PR_SEMI] = 1.0 if semi_infinite else 0.0
    PR[S.PR_LB], PR[S.PR_SPENT], PR[S.PR_E0], PR[S.PR_CROD] = Lb, _SPENT, 0.5 * Mp * Vn * Vn, C_rod
    PR[S.PR_CP] = _compliance(Tp, Zp, 0.0)
    PR[S.PR_CSHANK] = _compliance(Tr[::-1], Zr[::-1], m)
    PR[S.PR_CBIT] = _compliance(Tr, Zr, 0.0)
    PR[S.PR_MP], PR[S.PR_MR], PR[S.PR_WINDOW] = Mp, Mr, h
    PR[S.PR_TMAX] = math.inf if t_max is None else t_max
    PR[S.PR_MAXWIN] = max_windows
    PR[S.PR_P0], PR[S.PR_NP] = fn / k, Tp.size
    PR[S.PR_RECORD], PR[S.PR_MAXP] = 1.0 if record else 0.0, max_pieces
    PR[S.PR_DRIVEN] = 1.0 if data is not None and data.drive is not None else 0.0
    PR[S.PR_FIXED] = 1.0 if fixed_horizon else 0.0
    bound = MAX_POOL_BYTES if max_pool_bytes is None else max_pool_bytes
    # 4 MB, of which a blow touches what it uses (a pool too small runs the blow again, larger); the
    # simulator's blows (data given, a fixed horizon of a few round trips) need tens of pieces: 40 kB
    pcap, tcap, ecap = (16384, 131072, 256) if data is None else (256, 2048, 64)
    if _pool is not None:  # (the pool a like blow filled: no runs again to grow it)
        pcap, tcap, ecap = (max(c, int(u)) for c, u in zip((pcap, tcap, ecap), _pool[:3], strict=True))
    while pcap > 1024 and pool_bytes(pcap, tcap) > bound:
        pcap, tcap, ecap = pcap // 4, tcap // 4, ecap // 4
    # (_keep: the coupled blow's iterates, each going on from where the last one's drive was its own:
    # _keep["resume"] the last run's snapshots, _keep["stops"] the times this one takes its own at,
    # given back as _keep["snapshots"], and the run's (ws, scale) as _keep["workspace"]: its switch
    # log; :func:`_resumed`)
    stops = () if _keep is None else _keep.get("stops", ())
    snaps: list = []
    ws = None
    if _keep is not None and _keep.get("resume") and data is not None and data.drive is not None:
        drive_terms = data.terms(lam, scale).drive
        rows, terms, larger = pcap, tcap, False
        for _ in range(3):  # (the pool full: on from the snapshot again, on a pool 4 times larger)
            ws = _resumed(_keep["resume"], drive_terms, scale, lam, PR, rows, terms, larger,
                           bound=MAX_POOL_BYTES)
            if ws is None:
                break
            _run(ws, t_max, stops, h, snaps, scale)
            if ws[S.WS_CI][S.CI_STATUS] == 0:
                PR, RD = ws[S.WS_PR], ws[S.WS_RD]
                break
            rows, terms, larger = 4 * ws[S.WS_PF].shape[0], 4 * ws[S.WS_TK].size, True
            ws, snaps = None, []
    while ws is None:
        RD[S.RD_HEAD] = 0.0  # (a run again with a larger pool logs afresh)
        ws = _workspace(T, Z, Tp.size, Vn, fn, k, k_u, lam, PR, RT, RC, RD, pcap, tcap, ecap, h, Lb, Zb,
                        None if data is None else data.terms(lam, scale), reuse=not lean)
        if data is not None and not lean and _energies:  # the piston's energy at impact: its waves'
            run_kernel(ws, 0.0)  # (kinetic and strain: account, through run)
            PR[S.PR_E0] = ws[S.WS_CT][S.CT_EP]
        snaps = []
        _run(ws, t_max, stops, h, snaps, scale)
        if ws[S.WS_CI][S.CI_STATUS] == 0:
            break
        # what overflowed grows 4-fold: the pieces, the loading episodes, or else the terms (the
        # pieces hold 5 to 40 terms each: the terms' array fills first)
        npc, nterms = int(ws[S.WS_CNT][S.CNT_PIECES]), int(ws[S.WS_CNT][S.CNT_TERMS])
        full_p, full_e = npc >= ws[S.WS_PF].shape[0], int(ws[S.WS_BI][S.BI_NEP]) > ws[S.WS_EP].shape[0]
        pcap, ecap = 4 * pcap if full_p else pcap, 4 * ecap if full_e else ecap
        tcap = tcap if full_p or full_e else 4 * tcap
        reached = float(ws[S.WS_CT][S.CT_T])
        if fixed_horizon and 0.0 < reached < t_max:  # as many pieces to the horizon as the square of
            # the time gives (the waves' breaks multiply), terms as its cube (each piece's terms grow
            # too): one run again, not one per 4-fold growth
            grow = t_max / reached
            more = max(pcap, int(1.25 * grow ** 2 * npc)), max(tcap, int(1.25 * grow ** 3 * nterms))
            if pool_bytes(*more) <= bound:
                pcap, tcap = more
        if pool_bytes(pcap, tcap) > bound:
            per = nterms / max(npc, 1)
            raise PoolOverflow(
                f"the exact blow needs more than {bound / 2 ** 30:.3g} GiB of wave pieces (the waves broke "
                f"into more pieces than that by t = {ws[S.WS_CT][S.CT_T]:.6g}: {npc} pieces of {per:.3g} "
                "terms on average; each sum of the segments' travel times is a break point, so that many or "
                "incommensurate segments multiply them, and exponents close together, a bit's mass or a soft "
                "rock, lengthen their series); "
                + ("give a t_max" if t_max is None else f"give a t_max below {ws[S.WS_CT][S.CT_T]:.6g}")
                + ", or use method='lattice'")
        ws = None
    if _keep is not None:  # (and the run's workspace and scale: its switch log, the tangent's schedule)
        _keep["snapshots"], _keep["workspace"] = snaps, (ws, scale)
    if lean:
        return ws, scale
    if not _energies:  # (a fixed horizon's run reads no energy: its pieces are the same without them)
        PR[S.PR_E0] = math.nan
        ws[S.WS_CT][[S.CT_PP, S.CT_EP, S.CT_PR, S.CT_ER, S.CT_PSI]] = math.nan
        ws[S.WS_CT][S.CT_TACC] = ws[S.WS_CT][S.CT_T]
    args = (ws, scale, Tp, Zp, Tr, Zr, k, k_u, m, fn, Vn, Mp, C_rod, lam, record)
    if _defer:  # (the histories now, without the energies at the end and on the pool's arrays; the
        # whole blow, its energies and copies, from the second: until this thread's next blow)
        return _result(*args, final=False), functools.partial(_result, *args)
    return _result(*args)


@functools.cache
def _binomials():
    """``C(a, b)`` for ``a, b < P.DC`` (read only: shared by every blow)."""
    out = np.zeros((P.DC, P.DC))
    for a in range(P.DC):
        for b in range(a + 1):
            out[a, b] = math.comb(a, b)
    out.flags.writeable = False
    return out


class _PoolArrays(NamedTuple):
    """The wave-piece pool's arrays: the pieces' floats ``PF`` and integers ``PI``, the terms' keys
    ``TK`` and coefficients ``TC``."""
    PF: np.ndarray
    PI: np.ndarray
    TK: np.ndarray
    TC: np.ndarray


#: a thread's pool arrays, reused by its next blow (``_pool_arrays``)
_POOLS = threading.local()
#: the largest pool kept for reuse (the default one: 4 MB)
_REUSED_POOL_BYTES = 2 ** 23


def _pool_arrays(rows, terms, reuse):
    """The pool's arrays ``PF``, ``PI`` (``rows`` pieces) and ``TK``, ``TC`` (``terms``), uninitialised:
    the kernel reads only the pieces and terms it has written (and the first ones, which
    :func:`_workspace` sets), so that their megabytes cost no zeroing, and ``reuse``: the calling
    thread's arrays of the last such call (their pages mapped once; a record keeps copies of what
    it holds, :func:`_result`), up to ``_REUSED_POOL_BYTES``."""
    if reuse:
        kept = getattr(_POOLS, "arrays", None)
        if kept is not None and kept.PF.shape[0] == rows and kept.TK.size == terms:
            return kept
    arrays = _PoolArrays(np.empty((rows, S.PF_COLS)), np.empty((rows, S.PI_COLS), dtype=np.int64),
                         np.empty(terms, dtype=np.int64), np.empty(terms, dtype=complex))
    if reuse and pool_bytes(rows, terms) <= _REUSED_POOL_BYTES:
        _POOLS.arrays = arrays
    return arrays


def _workspace(T, Z, n_p, Vn, fn, k, k_u, lam, PR, RT, RC, RD, pcap, tcap, ecap, h, Lb, Zb, data=None,
               reuse=False):
    J = T.size
    nch = 3 * J + 2
    init, drive = (None, None) if data is None else data
    ndrive = 0 if drive is None else drive.starts.size
    extra = 0
    if init is not None:
        extra = sum(x.keys.size for x in init) + (0 if drive is None else drive.keys.size)
    PF, PI, TK, TC = _pool_arrays(pcap + 2 * J + 1 + ndrive + 16, tcap + extra, reuse)  # (room for the
    # data's pieces besides the pieces the run adds)
    CNT = np.zeros(S.CNT_SIZE, dtype=np.int64)
    CHI = np.full((nch, 2), -1, dtype=np.int64)
    CH_T = np.zeros(nch)
    CH_TOL = np.full(nch, _TOL)
    CH_TOL[3 * J + 1] = _TOL * max(1.0 / k, Lb / Zb)
    n = 0
    nt = 0

    def put(n, nt, keys, coefs):
        nz = coefs != 0.0
        count = int(np.count_nonzero(nz))
        TK[nt:nt + count], TC[nt:nt + count] = keys[nz], coefs[nz]
        PI[n, PI_TERMS], PI[n, PI_COUNT] = nt, count
        return nt + count

    for i in range(1, J + 1):
        for side, (c, val) in enumerate(((2 * (i - 1), 0.5 * Z[i - 1] * Vn),
                                         (2 * i - 1, -0.5 * Z[i - 1] * Vn))):
            CH_T[c] = T[i - 1]
            # (the columns in order: start, valid, ref, the integrals NaN until cached; next, first term,
            # count, flag)
            PF[n] = (-T[i - 1], math.inf, 0.0, math.nan, math.nan)
            PI[n] = (-1, nt, 0, 0)
            if i <= n_p and init is not None:
                nt = put(n, nt, *init[2 * (i - 1) + side])
            elif i <= n_p and val != 0.0:
                TK[nt] = 0
                TC[nt] = val
                nt += 1
                PI[n, PI_COUNT] = 1
            CHI[c, CHI_TAIL] = n
            CHI[c, CHI_HEAD] = n
            n += 1
    # the drive channel (no drive: one empty piece), its pieces linked in order, their nonzero terms
    c = 2 * J
    starts = np.array([-1.0]) if drive is None else np.asarray(drive.starts, dtype=float)
    m = starts.size
    rows = slice(n, n + m)
    PF[rows, PF_START], PF[rows, PF_VALID], PF[rows, PF_REF] = starts, math.inf, 0.0
    PF[rows, PF_INT:] = math.nan
    PI[rows, PI_NEXT] = np.arange(n + 1, n + m + 1)
    PI[n + m - 1, PI_NEXT] = -1
    PI[rows, PI_TERMS:] = 0
    PI[rows, PI_TERMS] = nt
    if drive is not None:
        _, keys, coefs, sizes = drive
        nz = coefs != 0.0
        count = int(np.count_nonzero(nz))
        TK[nt:nt + count], TC[nt:nt + count] = keys[nz], coefs[nz]
        before = np.concatenate(([0], np.cumsum(nz)))  # nonzero terms before each term
        ends = np.cumsum(sizes)
        PI[rows, PI_TERMS] = nt + before[ends - sizes]
        PI[rows, PI_COUNT] = before[ends] - before[ends - sizes]
        nt += count
    CHI[c, CHI_HEAD], CHI[c, CHI_TAIL] = n, n + m - 1
    n += m
    CNT[S.CNT_PIECES], CNT[S.CNT_TERMS] = n, nt
    BIN = _binomials()
    WB = np.zeros((S.BLOCKS, lam.size, P.DC), dtype=complex)
    WN = np.zeros((S.BLOCKS, lam.size), dtype=np.int64)
    STK = np.zeros((256, S.STK_COLS))
    SZ = Z.astype(float)
    ST = T.astype(float)
    NSF = np.zeros((J + 1, S.NSF_COLS))
    NSI = np.full((J + 1, S.NSI_COLS), -1, dtype=np.int64)
    NSI[:, NSI_CONTACT] = 0
    NSI[n_p, NSI_CONTACT] = 1  # in contact at impact
    BS = np.zeros(S.BS_SIZE)
    p0 = fn / k
    BS[S.BS_P], BS[S.BS_X], BS[S.BS_W] = p0, p0, 0.0
    BS[S.BS_PMAX], BS[S.BS_RMAX], BS[S.BS_PPERM] = p0, fn, p0 - fn / k_u
    BS[S.BS_PSTART], BS[S.BS_TPMAX], BS[S.BS_EPT], BS[S.BS_EPP] = p0, 0.0, 0.0, p0
    BI = np.zeros(S.BI_SIZE, dtype=np.int64)
    EP = np.zeros((ecap, S.EP_COLS))
    CI = np.zeros(S.CI_SIZE, dtype=np.int64)
    CT = np.zeros(S.CT_SIZE)
    CT[S.CT_TACC] = math.nan  # (no energy pass yet)
    return (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
            RT, RC, RD, EP, CI, CT)

