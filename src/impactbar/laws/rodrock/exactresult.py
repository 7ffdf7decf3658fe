"""The result of an exact blow (theory §4d): :class:`ExactBlow`, its numbers and the histories it
reads from the wave pieces, built from the solver's workspace at the blow's end (:func:`_result`;
the solver, :func:`~impactbar.laws.rodrock.exact.exact_blow`, is in
:mod:`impactbar.laws.rodrock.exact`), and how it ended (``ended_by``; :data:`CERTIFIED`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import _exacthistory as H
from . import _exactpieces as P
from . import _records as S
from ._bit import feed_gain
from ._exactresume import run_kernel
from ._records import (  # columns by name
    CHI_HEAD,
    EP_DISS,
    EP_PEND,
    EP_PSTART,
    NSF_GAP,
    NSF_SHANK,
    PF_START,
    PI_COUNT,
    PI_NEXT,
)

__all__ = ["CERTIFIED", "ExactBlow"]

_END_NAMES = {P.SEPARATED: "separated", P.LIFTED: "lifted", P.SPENT: "spent", P.TMAX: "t_max",
              P.BUDGET: "budget", P.RINGS: "rings", P.FAILED: "failed", P.MAY_YIELD: "may_yield"}


@dataclass(frozen=True)
class ExactBlow:
    """One blow of the exact solver (:func:`exact_blow`; theory §4d), in the model's units.

    Attributes
    ----------
    efficiency : float
        ``work_on_rock / available_energy`` (``<= 1``).
    efficiency_with_rebound : float
        ``work_on_rock / (available_energy - piston_energy)`` (the rebound credited; ``<= 1``).
    work_on_rock : float
        The work the rock dissipated (``k (1 - 1/gamma) (p_b^2 - p_a^2)/2`` summed over the loadings):
        final once the blow has ended.
    rock_energy : float
        The rock's stored elastic energy at the end, ``R^2/(2 k_u)``.
    available_energy : float
        ``energy_at_impact + feed_work + drive_work`` plus the energy stored under the feed at
        impact (``f^2 C_rod / 2 + f^2/(2 k_u)``).
    energy_at_impact, feed_work, drive_work : float
        The piston's energy at impact, the feed's work on the shank, the drive's on the piston.
    piston_energy, rod_energy, radiated : float
        The piston's energy at the end; the rod's (its waves, its strain under the feed, the bit's
        kinetic energy); the energy the bit's reflected wave carried away on a semi-infinite rod.
    bit_energy : float
        The bit's kinetic energy ``m w^2/2`` at the end (its part of ``rod_energy``).
    energy_error : float
        ``|available - (work_on_rock + rock_energy + piston_energy + rod_energy + radiated)| /
        available``: rounding.
    rebound_velocity : float
        The piston's mean velocity at the end (negative: moving back).
    max_penetration, permanent_penetration, advance : float
        ``p_max`` (the bit's largest penetration, from the rock's surface), ``p_max - R_max/k_u``
        (where the rock's force vanishes on the last unloading line), the bit's displacement over
        the blow. Updated continuously: a blow stopped while the bit advances has them at its end.
    peak_bit_force, peak_bit_time : float
        ``R_max = k p_max`` and the time it was reached.
    duration : float
        The time at which the end was established.
    ended_by : str
        ``"separated"``, ``"lifted"``, ``"spent"``, ``"may_yield"``, ``"t_max"``, ``"rings"`` or
        ``"budget"`` (see :mod:`impactbar.laws.rodrock.exact`).
    uncertainty : float
        Zero when the end is certified; otherwise a bound on the rock work still possible, over
        the available energy (the energy that could still reach the rock, with a feed times
        ``R_max / (R_max - f)``): how much the efficiency could still grow by the rock's work. With
        a feed the efficiency also follows the feed's work in its denominator, which a rod ringing
        on the rock moves either way without any new yield (theory §4d).
    loadings : numpy.ndarray, shape (n, 5)
        One row per loading episode (the rock yielding): start and end time, penetration at start
        and end, the work dissipated.
    separations, recontacts : int
        How often the piston left the shank and struck it again.
    bit_velocity, gap, shank_displacement : float
        At the end.
    pieces, windows : int
        The cost: pieces stored, windows of the shortest travel time.
    diagnostics : dict
        ``searches_abandoned`` (crossing searches that hit their work bound: 0 in a sound run),
        ``degree_limit`` (series that reached the degree limit: 0), ``terms`` (stored).
    """

    efficiency: float
    efficiency_with_rebound: float
    work_on_rock: float
    rock_energy: float
    available_energy: float
    energy_at_impact: float
    feed_work: float
    drive_work: float
    piston_energy: float
    rod_energy: float
    radiated: float
    energy_error: float
    rebound_velocity: float
    max_penetration: float
    permanent_penetration: float
    advance: float
    peak_bit_force: float
    peak_bit_time: float
    duration: float
    ended_by: str
    uncertainty: float
    loadings: np.ndarray
    separations: int
    recontacts: int
    bit_velocity: float
    gap: float
    shank_displacement: float
    pieces: int
    windows: int
    bit_energy: float = 0.0
    diagnostics: dict = field(default_factory=dict)
    _hist: tuple = field(repr=False, default=())

    # -- histories ------------------------------------------------------------------------------
    def junction_force(self, j: int, t) -> np.ndarray:
        """Force at junction ``j`` at times ``t`` (``j`` counts the interfaces from the piston's far
        end: 1 .. J - 1; the shank is ``contact_junction``), 0 before the blow."""
        scale, pools, nodes, _ = self._hist
        if not 1 <= j < nodes:
            raise ValueError(f"j must be an interface 1 .. {nodes - 1}; got {j}")
        return scale * _eval_channel(pools, 2 * nodes + 1 + j, t, kind=0)

    def junction_breaks(self, j: int) -> np.ndarray:
        """The break points of junction ``j``'s force history (numbered as in
        :meth:`junction_force`): the times in ``[0, duration]`` where one of its pieces starts, so
        that between two of them the force is one analytic piece (to integrate it, for instance).

        Returns
        -------
        numpy.ndarray, shape (n,)
            Sorted, with 0 and ``duration``.
        """
        _, pools, nodes, _ = self._hist
        if not 1 <= j < nodes:
            raise ValueError(f"j must be an interface 1 .. {nodes - 1}; got {j}")
        PF, PI, _, _, CHI, _, _ = pools
        p, out = int(CHI[2 * nodes + 1 + j, CHI_HEAD]), [0.0, self.duration]
        while p >= 0:
            out.append(float(PF[p, PF_START]))
            p = int(PI[p, PI_NEXT])
        return np.unique(np.clip(out, 0.0, self.duration))

    def junction_impulse(self, j: int) -> float:
        """The impulse ``int N dt`` of junction ``j``'s force (numbered as in :meth:`junction_force`)
        over the blow, in closed form piece by piece (the blow kept with ``record=True``)."""
        scale, pools, nodes, _ = self._hist
        if not 1 <= j < nodes:
            raise ValueError(f"j must be an interface 1 .. {nodes - 1}; got {j}")
        PF, PI, TK, TC, CHI, lam = pools[:6]
        head = int(CHI[2 * nodes + 1 + j, CHI_HEAD])
        return scale * H.history_integral(PF, PI, TK, TC, lam, head, float(self.duration))

    @property
    def contact_junction(self) -> int:
        """The index of the piston-shank interface among the junctions."""
        *_, junction = self._hist  # (scale, pools, nodes, junction)
        return junction

    def shank_force(self, t) -> np.ndarray:
        """The piston-shank force at times ``t``."""
        return self.junction_force(self.contact_junction, t)

    def shank_peak(self, t_end: float) -> tuple[float, float]:
        """The largest piston-shank force up to ``t_end`` and when first reached (exact)."""
        scale, pools, nodes, junction = self._hist
        v, t = _channel_max(pools, 2 * nodes + 1 + junction, min(t_end, self.duration))
        return scale * v, t

    @property
    def first_separation(self) -> float:
        """When the piston first left the shank (the start of the shank force's first zero
        piece); ``duration`` where it never did."""
        _, pools, nodes, _ = self._hist
        PF, PI, _, _, CHI, _, _ = pools
        p = int(CHI[2 * nodes + 1 + self.contact_junction, CHI_HEAD])
        while p >= 0 and PF[p, PF_START] < self.duration:
            if PI[p, PI_COUNT] == 0 and PF[p, PF_START] > 0.0:
                return float(PF[p, PF_START])
            p = int(PI[p, PI_NEXT])
        return self.duration

    def penetration(self, t) -> np.ndarray:
        """The bit's penetration at times ``t``."""
        scale, pools, nodes, _ = self._hist
        return scale * _eval_channel(pools, 3 * nodes + 1, t, kind=1)

    def bit_force(self, t) -> np.ndarray:
        """The rock's force on the bit at times ``t``."""
        scale, pools, nodes, _ = self._hist
        return scale * _eval_channel(pools, 3 * nodes + 1, t, kind=2)

    def peak_forces(self):
        """The largest compressive force at every junction and at the bit, and when each is first
        reached (exact maxima of the pieces).

        Returns
        -------
        values, times : numpy.ndarray, shape (J,)
            Junctions ``1 .. J - 1`` then the bit (its ``R_max``).
        """
        scale, pools, nodes, _ = self._hist
        vals, times = [], []
        for j in range(1, nodes):
            v, t = _channel_max(pools, 2 * nodes + 1 + j, self.duration)
            vals.append(scale * v)
            times.append(t)
        vals.append(self.peak_bit_force)
        times.append(self.peak_bit_time)
        return np.array(vals), np.array(times)


def _eval_channel(pools, c, t, kind, head=None):
    """Channel ``c``'s history at times ``t`` (from its first piece, or ``head``: a wave channel's
    ``CHI[c, CHI_HEAD]`` is its receiver's cursor, its first piece the ``c``-th of the pool)."""
    PF, PI, TK, TC, CHI, lam, lamk = pools
    t = np.atleast_1d(np.asarray(t, dtype=float))
    flat = t.ravel()
    order = np.argsort(flat, kind="stable")
    out = np.zeros(flat.size)
    head = int(CHI[c, CHI_HEAD]) if head is None else int(head)
    H.eval_history(PF, PI, TK, TC, lam, head, np.ascontiguousarray(flat[order]), out, kind, lamk)
    res = np.empty(flat.size)
    res[order] = out
    return res.reshape(t.shape)


def _channel_max(pools, c, t_end):
    PF, PI, TK, TC, CHI, lam, lamk = pools
    res = np.zeros(S.HMAX_SIZE)
    H.history_max(PF, PI, TK, TC, lam, int(CHI[c, CHI_HEAD]), float(t_end), res)
    return res[S.HMAX_V], res[S.HMAX_T]



def _result(ws, scale, Tp, Zp, Tr, Zr, k, k_u, m, fn, Vn, Mp, C_rod, lam, record, final=True):
    """The :class:`ExactBlow` of a run's workspace ``ws``; ``final=False``: its histories alone (the
    energies those of the last account, not the end's; the histories on the pool's own arrays, not
    copies: valid until the thread's next blow reuses them), for a blow read only through its
    histories (the coupled blow's iterates, :mod:`~impactbar.laws.rodrock.coupled_exact`)."""
    (PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam, BIN, WB, WN, STK, PR, SZ, ST, NSF, NSI, BS, BI,
     RT, RC, RD, EP, CI, CT) = ws
    J = SZ.size
    n_p = Tp.size
    t_end = float(CT[S.CT_T])
    if final and CT[S.CT_TACC] != t_end:  # (the energies at the end, unless the run's last pass was there)
        run_kernel(ws, t_end)  # (account, through run)
    Pp, Ep, Er = CT[S.CT_PP], CT[S.CT_EP], CT[S.CT_ER]
    br = int(BI[S.BI_BRANCH])
    p = BS[S.BS_P]
    R = k * BS[S.BS_X] if br == P.LOAD else (k_u * BS[S.BS_X] if br == P.ELASTIC else 0.0)
    xs = NSF[n_p, NSF_SHANK]
    gap = NSF[n_p, NSF_GAP]
    E0 = PR[S.PR_E0]  # the piston's energy at impact (0.5 Mp Vn^2 for a rigid piston)
    drive_work = BS[S.BS_DRIVEW]
    feed_work = fn * xs
    static = 0.5 * fn * fn * C_rod
    available = E0 + drive_work + feed_work + static + 0.5 * fn * fn / k_u
    dissipated = BS[S.BS_DISS]
    rock_e = R * R / (2.0 * k_u)
    rod_e = Er + 0.5 * m * BS[S.BS_W] ** 2 + fn * (xs - (p - BS[S.BS_PSTART])) + static
    radiated = BS[S.BS_ABS]
    err = abs(available - (dissipated + rock_e + Ep + rod_e + radiated)) / abs(available)
    if not (available > 0.0 and err == err):  # (pieces gone wrong: never an account that closes)
        err = math.inf
    nep = int(BI[S.BI_NEP])
    loads = EP[:nep].copy()
    if br == P.LOAD and p > BS[S.BS_EPP]:  # a loading under way at the end
        loads = np.vstack((loads, [[BS[S.BS_EPT], t_end, BS[S.BS_EPP], p,
                                    0.5 * (1.0 - k / k_u) * k * (p - BS[S.BS_EPP]) * (p + BS[S.BS_EPP])]]))
    ended = _END_NAMES.get(int(CI[S.CI_END]), "failed")
    unc = 0.0
    if ended in ("budget", "t_max", "may_yield"):
        rem = CT[S.CT_PSI] + (Ep if ended != "may_yield" else 0.0)
        unc = rem * feed_gain(BS[S.BS_RMAX], fn) / available
    s2 = scale * scale
    loads[:, EP_PSTART:EP_PEND + 1] *= scale
    loads[:, EP_DISS] *= s2
    lamk = np.array([k, k_u, 0.0])
    # the pieces kept, not the pool's capacity (megabytes)
    npc, nt = int(CNT[S.CNT_PIECES]), int(CNT[S.CNT_TERMS])
    keep = (lambda x: x.copy()) if final else (lambda x: x)
    hist = (scale, (keep(PF[:npc]), keep(PI[:npc]), keep(TK[:nt]), keep(TC[:nt]), CHI, lam, lamk), J,
            n_p)  # (the junctions' only with record)
    return ExactBlow(
        efficiency=dissipated / available,
        efficiency_with_rebound=dissipated / (available - Ep),
        work_on_rock=s2 * dissipated, rock_energy=s2 * rock_e, available_energy=s2 * available,
        energy_at_impact=s2 * E0, feed_work=s2 * feed_work, drive_work=s2 * drive_work,
        piston_energy=s2 * Ep,
        rod_energy=s2 * rod_e, radiated=s2 * radiated, energy_error=err,
        rebound_velocity=scale * Pp / Mp, max_penetration=scale * BS[S.BS_PMAX],
        permanent_penetration=scale * BS[S.BS_PPERM], advance=scale * (p - BS[S.BS_PSTART]),
        peak_bit_force=scale * BS[S.BS_RMAX], peak_bit_time=float(BS[S.BS_TPMAX]), duration=t_end,
        ended_by=ended,
        uncertainty=unc, loadings=loads, separations=int(CI[S.CI_SEP]), recontacts=int(CI[S.CI_RECON]),
        bit_velocity=scale * BS[S.BS_W], gap=scale * gap, shank_displacement=scale * xs,
        pieces=int(CNT[S.CNT_PIECES]), windows=int(CI[S.CI_WIN]), bit_energy=s2 * (0.5 * m * BS[S.BS_W] ** 2),
        diagnostics={"searches_abandoned": int(CI[S.CI_GIVEUP]), "degree_limit": int(CI[S.CI_DEG]),
                     "terms": int(CNT[S.CNT_TERMS])},
        _hist=hist)


#: ``ended_by`` of a certified end (the blow's numbers are final): no contact, and no yield of the
#: rock, can happen again, or no energy that could still reach the rock is left
CERTIFIED = ("separated", "lifted", "spent")

