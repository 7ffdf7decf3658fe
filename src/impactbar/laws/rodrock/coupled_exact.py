r"""The rod-rock law's blow with a drive that has state, on the exact scheme (theory §11, "The
coupled blow"; §4d): every wave of the piston and the rod carried exactly
(:func:`~impactbar.laws.rodrock.exact.exact_blow`), the drive's force on the piston's far end
iterated to the drive's own accuracy.

**The wave the drive meets.** At the piston's driven end (segment 0, impedance :math:`Z_0`, travel
time :math:`T_0`) the force is the drive's, :math:`N(0, t) = F + G = p(t)`, and the end moves at
:math:`u_t(0, t) = (F - G)/Z_0 = a(t) + p(t)/Z_0` with :math:`a = -2 G_0 / Z_0`, :math:`G_0(t)`
the left-going wave arriving there. It left the far end of segment 0 (the first step of a stepped
piston, else the struck end) :math:`T_0` earlier, where the force :math:`N_1` is the exact blow's
recorded junction force and the right-going wave arriving there is the one the driven end sent
:math:`T_0` before:

.. math::

    G_0(t) = N_1(t - T_0) - p(t - 2T_0) + G_0(t - 2T_0) \quad (t \ge T_0),

and, for :math:`t < T_0` and the right-going wave before :math:`T_0`, the piston's waves at impact
(:func:`~impactbar.laws.rodrock.exactmap.initial_waves`). :math:`a` over :math:`[0, t]` depends on
:math:`p` over :math:`[0, t - 2T_0]` only.

**The iteration.** Start from the force held at its value at impact; solve the exact blow with it;
integrate the drive over the blow with the driven end moved by that blow's :math:`a`
(its ability ``end_flight``; :math:`a` as a cubic spline through its exact values
``T_0 / SAMPLES`` apart, cut where the far end's force jumps); take the force it gives, its
integrator's cubic Hermite pieces exactly, as the next blow's drive; repeat until the force changes
by less than :data:`FORCE_TOL` of its size. By causality the :math:`k`-th iterate is right over
:math:`[0, 2kT_0]` whatever the coupling, so the iteration ends after at most
``duration / (2 T_0) + 1`` steps (six to eight rounds on the example). What is left is the
integrator's tolerance, the spline's and :data:`FORCE_TOL`: nothing is averaged over cells and the
rod's lengths are as they are.

**Marching** (the default). As the :math:`k`-th iterate is right over :math:`[0, 2kT_0]` only, its
blow is solved to :math:`(2k + 1) T_0` (all that :math:`a` over :math:`[0, 2(k + 1) T_0]` needs) and
the drive integrated to :math:`2(k + 1) T_0`, its force held after. The first iterate that took a
force right over the whole blow (by causality) is the answer, the force it gives within
:data:`MARCH_TOL` of the one it took (the drive's flights' noise: 1.4e-9 of the force's size on the
example; a larger change, causality broken, iterates on). The blows
and the drive's flights before the drive's force matters are the shorter, and no blow is solved twice
with one force: about half the plain iteration's work, the same blow (on the example to the bit: the
drive's integration restarts at every break, and the exact solver is causal, so that an iterate's
early part is its predecessor's). So each blow goes on from a snapshot of its predecessor's solver
(its state at the last window before where their forces part; the snapshots taken a travel time
apart up to where the predecessor's force is held), not from the impact: the same blow to the bit,
its windows before there not solved again (:func:`~impactbar.laws.rodrock.exact.exact_blow`'s
``_keep``). ``march=False`` runs the plain iteration.

**When the blow ends.** Not at the law's window (:meth:`~impactbar.RodRock.window`, where the
simulator's blows under a load on the exact scheme end) but when it is certified over, as a single
exact blow is (:mod:`~impactbar.laws.rodrock.exact`, "when the blow ends";
:func:`~impactbar.laws.rodrock._exactend.certify`), so that its numbers do not depend on a window.
Under a drive the piston's driven end is pushed on after the contact opens, and no bound on the
piston's later course holds without the drive's own; the blow is over at the first of the solver's
windows where the contact piston-shank is open and the piston's mean velocity is ``<= 0`` (moving
back, or standing), the rod unable to make the rock yield again (``"separated"``; ``"lifted"``
where the rod has left the rock for good; ``"spent"``), or with a feed the rock merely not loading
(``"may_yield"``: the record's ``uncertainty`` bounds what a ringing rod could still make the rock
take). From then on the piston's course is the drive's: it returns to the modal flight under the
drive, whose arrival event catches a later touch of the shank as a new impact, not as part of this
blow. While the piston still moves towards the shank, the blow goes on (a touch then is the exact
solver's re-contact). The iteration marches to the end of the last iterate's blow (each blow solved
with the certificate on, to its end or the part the iterate is right on) and goes on whole over it
until the force settles; the blow's history before its end depends on the force before it only, so
the end moves only while that force does. A blow not certified over within :data:`HORIZONS` of
the law's window ends there (``ended_by = "t_max"``, the former fixed window). The rock is loaded by
the feed at each blow and the piston returns to the modal flight with the state the exact solution
projects (theory §11 says what these choices assume).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..base import DrivenContact, LawNotSupported

__all__ = ["driven_exact_contact", "Coupling", "FORCE_TOL", "MARCH_TOL", "HORIZONS", "MAX_ITERATIONS",
           "SAMPLES"]

#: The iteration ends when the force changes by less than this fraction of its size.
FORCE_TOL = 1e-9
#: Marching: the first iterate over the whole blow took a force right over all of it (causality), so
#: that what its force still changes is the drive's flights' noise (1.4e-9 of the force on the
#: example, against the 1e-10 of their tolerance: they restart at other breaks); it is the answer where
#: that change is below this fraction of the force's size (a check that causality held).
MARCH_TOL = 1e-6
#: The most iterations beyond the causal bound (``duration / (2 T_0) + 1``).
MAX_ITERATIONS = 64
#: The end is searched for up to this many of the law's window (:meth:`~impactbar.RodRock.window`);
#: a blow not certified over by then ends there.
HORIZONS = 2.0
#: The solver's ends that certify the coupled blow over (module docstring).
ENDS = ("separated", "lifted", "spent", "may_yield")
#: Samples of the arriving wave per travel time of the piston's first segment.
SAMPLES = 400
#: How far inside its interval (in ``T_0``) the spline's end values are taken: beyond the model time's
#: rounding of a break (``1e-13`` of ``T_0`` on the example), within what moves a value by rounding.
INSIDE = 1e-10


class Coupling(NamedTuple):
    """What the drive met over a coupled exact blow's last flight (its tangent's data,
    :mod:`~impactbar.laws.rodrock.coupled_tangent`).

    Attributes
    ----------
    breaks : numpy.ndarray
        The flight's breaks (model times).
    splines : list of tuple
        The wave ``a`` on each interval, its callable's ``spline`` ``(x, c, t0)``
        (:meth:`_Incoming.callables`; the arrays kept, not the callables' lists).
    impedance : float
        ``Z_0`` of the piston's driven end (model units).
    """

    breaks: np.ndarray
    splines: list
    impedance: float


def _piece_value(piece, tau):
    """An exact piece ``Re sum c tau^d e^{lam tau}`` at ``tau`` (array)."""
    exps, degs, coefs = piece
    tau = np.asarray(tau, dtype=float)[..., None]
    return np.real(np.sum(np.asarray(coefs) * tau ** np.asarray(degs) * np.exp(np.asarray(exps) * tau),
                          axis=-1))


def _hermite(piece, j):
    """The cubic Hermite interpolant of column ``j`` of a piece's steps (``y``, rates ``f`` at the
    times ``t``), shape ``(intervals, 4)``, ``(x - x_i)^3`` first: the coefficients of scipy's
    ``CubicHermiteSpline(t, y, f).c[:, :, j].T`` by its own arithmetic (to the bit), without the
    spline of all the columns."""
    t, y, f = piece.t, piece.y[:, j], piece.f[:, j]
    dx = np.diff(t)
    slope = np.diff(y) / dx
    tt = (f[:-1] + f[1:] - 2 * slope) / dx
    return np.stack((tt / dx, (slope - f[:-1]) / dx - tt, f[:-1], y[:-1]), axis=1)


class _Force:
    """The drive's force over the blow (time from the impact): held at its value at impact before a
    first iterate, then the cubic pieces of an :meth:`end_flight`'s steps (its integrator's Hermite
    interpolant, exactly: ``p = p_r - alpha p_f``, each state a cubic between two steps)."""

    def __init__(self, p0, pieces=(), t0=0.0):
        self.p0 = float(p0)
        starts, coefs = [0.0], [np.array([0.0, 0.0, 0.0, self.p0])]
        if pieces:
            starts, coefs = [], []
            for piece in pieces:
                if piece.t.size < 2:
                    continue
                coefs.append(_hermite(piece, 2) - piece.alpha * _hermite(piece, 1))
                starts.append(piece.t[:-1] - float(t0))
            starts, coefs = np.concatenate(starts), np.concatenate(coefs)
        self.starts = np.atleast_1d(np.asarray(starts, dtype=float))
        self.coefs = np.atleast_2d(np.asarray(coefs, dtype=float))

    def __call__(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        j = np.clip(np.searchsorted(self.starts, t, side="right") - 1, 0, self.starts.size - 1)
        x = np.maximum(t - self.starts[j], 0.0)
        c = self.coefs[j]
        out = ((c[:, 0] * x + c[:, 1]) * x + c[:, 2]) * x + c[:, 3]
        return np.where(t < 0.0, self.p0, out)

    def pieces(self, lead, horizon):
        """The force as the exact solver's ``drive``: a piece held at the force at impact from
        ``-lead`` (at least the chain's shortest travel time), one cubic per step, and the force at
        ``horizon`` held after it.

        A step shorter than ``1e-9`` of the horizon (the integrator's first step after a restart,
        some ``1e-13``) is taken over by the step after it, whose cubic is continued back over it
        (re-expanded about the short step's start): the short step's own cubic continued forward
        over the next step would miss that step's end by up to a fifth of the force (a spurious step
        of the drive, which moves with the data)."""
        starts, coefs = self.starts, self.coefs
        short = np.append(np.diff(starts) <= 1e-9 * horizon, False)
        # each kept step starts where the run of short steps just before it starts
        run = np.concatenate(([True], ~short[:-1]))  # (a step that starts a run)
        origin = starts[np.maximum.accumulate(np.where(run, np.arange(starts.size), 0))]
        keep = ~short & (origin < horizon)
        new_starts, cubics = origin[keep], coefs[keep].copy()
        shift = (starts - origin)[keep]
        moved = shift > 0.0
        if np.any(moved):  # P(x - d), P's coefficients x^3 first
            d = shift[moved]
            c3, c2, c1, c0 = cubics[moved].T
            cubics[moved] = np.column_stack((c3, c2 - 3.0 * c3 * d, c1 - 2.0 * c2 * d + 3.0 * c3 * d * d,
                                             c0 - c1 * d + c2 * d * d - c3 * d * d * d))
        starts = np.concatenate(([-lead], new_starts, [horizon]))
        degs, zero = np.arange(4), np.zeros(1, dtype=np.int64)
        held = (np.zeros(1), zero, np.array([self.p0], dtype=complex))
        zeros = np.zeros(4)  # (one array for all: read only)
        cubics = [(zeros, degs, c) for c in cubics[:, ::-1].astype(complex)]
        last = (np.zeros(1), zero, np.array([float(self(horizon)[0])], dtype=complex))
        return starts, [held, *cubics, last]


class _Incoming:
    """``a(t) = -2 G_0(t) / Z_0`` of an exact blow (module docstring), ``t`` the model time."""

    def __init__(self, ex, waves, force, T0, Z0, t0):
        self.ex, (self.F, self.G) = ex, waves
        self.force, self.T0, self.Z0, self.t0 = force, T0, Z0, t0

    def arriving(self, t):
        """``G_0`` at times ``t`` from the impact (array)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.zeros(t.shape)
        T0 = self.T0
        cur = t.copy()
        live = np.ones(t.shape, dtype=bool)
        while np.any(live):
            early = live & (cur < T0)
            out[early] += _piece_value(self.G, np.maximum(cur[early], 0.0))
            live &= ~early
            if not np.any(live):
                break
            idx = np.flatnonzero(live)
            s = cur[idx] - T0  # when G_0 left the far end of segment 0
            n1 = self.ex.junction_force(1, s)
            # the right-going wave arriving there at s: the start's, or F(0, s - T0) = p - G_0
            first = s < T0
            f_in = np.where(first, _piece_value(self.F, np.minimum(s, T0)), self.force(s - T0))
            out[idx] += n1 - f_in
            live[:] = False
            live[idx[~first]] = True  # G_0(s - T0) enters with a plus sign: on with it
            cur[idx[~first]] -= 2.0 * T0
        return out

    def callables(self, breaks, memo=None):
        """``a`` on each interval of ``breaks`` (model times, where ``a`` may jump) as a callable of
        the model time: a cubic spline through its exact values ``T_0 / SAMPLES`` apart (its error
        ``O(h^4)`` where ``a`` is smooth, ``O(h)`` over a step at a kink: ``O(h^2)`` in what the
        drive integrates). ``memo`` (a dict, the blow's iterates'): an interval's callable kept by
        its ends and taken again where its values are the same to the bit (the march's iterates: an
        iterate's early waves are its predecessor's)."""
        from scipy.interpolate import CubicSpline

        xs, xvs = [], []
        for a, b in zip(breaks[:-1], breaks[1:], strict=True):
            x = np.linspace(a - self.t0, b - self.t0, max(8, math.ceil((b - a) * SAMPLES / self.T0)) + 1)
            # the ends' values a hair inside (INSIDE of T_0): the break, rounded through the model time,
            # may fall on the far side of the jump it marks, and a spline through the value beyond a
            # jump is wrong over a whole sample
            xv = x.copy()
            xv[0] += INSIDE * self.T0
            xv[-1] -= INSIDE * self.T0
            xs.append(x)
            xvs.append(xv)
        # (the wave at all the samples at once: each value the one it has alone)
        values = np.split(-2.0 * self.arriving(np.concatenate(xvs)) / self.Z0,
                          np.cumsum([x.size for x in xs])[:-1])
        memo = {} if memo is None else memo
        out = []
        for key, x, y in zip(zip(breaks[:-1], breaks[1:], strict=True), xs, values, strict=True):
            seen, a = memo.get(key, (None, None))
            if seen is None or not np.array_equal(seen, y):
                a = _spline_callable(CubicSpline(x, y), self.t0)
                memo[key] = (y, a)
            out.append(a)
        return out


def _spline_callable(spline, t0):
    """``spline(t - t0)`` as a float, for the integrator's many scalar calls: the spline's interval
    and its power sum in scipy's own order (its values to the last bit), without the array call's
    overhead; its ``spline`` attribute ``(x, c, t0)``, which the circuit's compiled flight evaluates
    the same way (:mod:`impactbar.drives.circuit._endcvode`)."""
    from bisect import bisect_right

    xs = spline.x.tolist()
    k3, k2, k1, k0 = (row.tolist() for row in spline.c)
    last = len(xs) - 2

    def a(t):
        tt = t - t0
        i = min(max(bisect_right(xs, tt) - 1, 0), last)
        s = tt - xs[i]
        s2 = s * s
        return ((k0[i] + k1[i] * s) + k2[i] * s2) + k3[i] * (s2 * s)

    a.spline = (np.asarray(spline.x, dtype=float), np.asarray(spline.c, dtype=float), float(t0))
    return a


def _breaks(ex, T0, D, t0, upto=None):
    """Where ``a`` may jump: the multiples of ``T0`` (the start's waves end) and the far
    junction's jumps (a contact resumed) carried to the driven end (``T0`` later, and every
    ``2 T0`` after); with ``upto`` (a blow run only to ``upto - T0``) those before ``upto``, and
    ``upto`` the last."""
    end = D if upto is None else upto
    cuts = list(np.arange(0.0, end, T0))
    b = ex.junction_breaks(1)
    b = b[(b > 0.0) & (b < end)]
    if b.size:
        eps = 1e-9 * T0
        jump = np.abs(ex.junction_force(1, b + eps) - ex.junction_force(1, b - eps))
        size = max(float(np.max(np.abs(ex.junction_force(1, np.linspace(0.0, ex.duration if upto else D,
                                                                          65))))), 1e-300)
        for c in b[jump > 1e-6 * size] + T0:
            while c < end:
                cuts.append(c)
                c += 2.0 * T0
    cuts = np.unique(np.append(np.asarray(cuts), end))
    keep = np.concatenate(([True], np.diff(cuts) > 1e-9 * T0))
    return t0 + cuts[keep]


def driven_exact_contact(model, drive, state, t0: float, q, v, settings=None, *, march=True) -> DrivenContact:
    """The blow of a piston arriving at the shank in modal state ``(q, q')`` at ``t0`` with the drive
    in ``state``, on the exact scheme, the drive's force iterated (module docstring; theory §11,
    "The coupled blow").

    Parameters
    ----------
    model : BarModel
        Under :class:`~impactbar.RodRock` with exact blows (:meth:`~impactbar.RodRock.blow_method`).
    drive : Drive
        A drive with state that follows a blow (its ability ``end_flight``).
    state : DriveState
        The drive's state at the arrival.
    t0, q, v : float, array_like
        The arrival: its time (model units) and the piston's modal state, each of shape
        ``(N + 1,)``, positions from the shank (``u(1) = 0``).
    settings : FlightSettings, optional
        The integrator of the drive's flight beside each iterate (default the drive's).
    march : bool
        Iterate over the part of the blow each iterate can be right on (module docstring, "Marching":
        the iterates' blows and flights the shorter, the last iterate's blow the answer); ``False``:
        every iterate over the whole blow, and the blow solved once more with the last force.

    Returns
    -------
    DrivenContact
        Its ``record`` an :class:`~impactbar.laws.rodrock.exactmap.ExactRockContact` whose blow took
        the drive's force as the last iterate gave it.

    Raises
    ------
    ValueError
        A drive that cannot follow a blow, the drive's integration failing, or the iteration not
        settling within its bound (the force's change then named).

    Examples
    --------
    >>> import inspect
    >>> inspect.signature(driven_exact_contact).parameters["march"].default
    True
    """
    from ...loads import FourierLoad
    from .exactjac import LOG_ROWS, kept_primal
    from .exactmap import ExactBlowMap, ExactRockContact, initial_waves

    q = np.array(q, dtype=float)
    v = np.array(v, dtype=float)
    t0 = float(t0)
    p0 = float(drive.force(state.mode, state.z, q, v))
    bmap = ExactBlowMap(model, FourierLoad(p0, []), t0)
    basis = bmap.basis
    T0, Z0 = float(basis.travel[0]), float(basis.impedance[0])
    cap = HORIZONS * bmap.duration  # (the law's window: the end searched for up to HORIZONS of it)
    D = cap  # the blow's end: the certified end of the last blow solved past it, else the cap
    waves = initial_waves(basis, q, v, p0)
    w0 = -float(model.drive_weights @ q)
    scale = max(abs(p0), 1e-300)
    force = _Force(p0)
    bound = math.ceil(cap / (2.0 * T0)) + 1 + MAX_ITERATIONS
    change = math.inf
    reach = 0.0  # marching: the iterate is right on [0, reach]
    keep: dict = {}  # marching: the blow's snapshots (module docstring, "Marching")
    splines: dict = {}  # the iterates' splines of a (_Incoming.callables)
    for _ in range(bound):
        upto = min(reach + 2.0 * T0, D) if march else D
        # (the blow is needed to upto - T0 only, but to its end where its change decides)
        cut = march and not (upto >= D and reach >= D)
        if march:  # (snapshots where the next force may part from this one: the breaks T0 apart
            # up to where this force is held; the next blow goes on from the last it shares)
            keep = {"resume": keep.get("snapshots"), "stops": T0 * np.arange(1, math.floor(reach / T0) + 2)}
        ex, finish = bmap.solve(q, v, record=True, t_max=upto - T0 if cut and upto > T0 else cap,
                                certified=True, defer=True, keep=keep if march else None,
                                log=LOG_ROWS if march else 0)  # (each iterate's: the last one's
        # is its tangent's schedule, coupled_tangent; a log that overflows is dropped, the tangent then
        # solving the blow again for its own)
        # (the last one's energies and copies: finish)
        if ex.ended_by in ENDS:  # certified over at ex.duration with this force
            D = float(ex.duration)
            upto = min(upto, D)
        elif not cut:
            D = cap
        whole = upto >= D and reach >= D  # (the iterate over the whole blow: its change decides)
        breaks = _breaks(ex, T0, D, t0, upto if not whole else None)
        incoming = _Incoming(ex, waves, force, T0, Z0, t0).callables(breaks, splines)
        follow = drive.abilities.end_flight
        if follow is None:
            raise LawNotSupported(f"the drive {type(drive).__name__} has state but cannot follow a blow "
                                  "(no end_flight in its abilities); it runs under an instantaneous impact "
                                  "law only")
        fl = follow(model, state, breaks, w0, incoming, Z0, settings)
        new = _Force(p0, fl.pieces, t0)
        grid = np.union1d(new.starts, np.linspace(0.0, upto, 257))
        scale = max(scale, float(np.max(np.abs(new(grid)))))
        change = float(np.max(np.abs(new(grid) - force(grid))))
        if march and whole and change <= MARCH_TOL * scale:
            break  # (ex took force, right over the whole blow: the blow; fl the force it gives)
        force, reach = new, upto
        bmap.drive = force.pieces(T0, upto)
        if not march and change <= FORCE_TOL * scale:
            break
    else:
        raise ValueError(f"the coupled exact blow at t = {t0:.6g} did not settle: the drive's force still "
                         f"changed by {change / scale:.2e} of its size after {bound} iterations")
    if not march:
        ex = bmap.solve(q, v, record=True, t_max=cap, certified=True)
    else:
        ex = finish()
    bmap.duration = float(ex.duration)
    q_after, v_after, on_stop = bmap.state_after(ex, on_stop=True)
    rec = ExactRockContact(bmap, q, v, ex, q_after, v_after)
    # (marching: the last iterate's switch log, logged from the impact on, the tangent's schedule)
    rec.switch_log = None if not march else (kept_primal(*keep["workspace"], float(ex.duration)), on_stop)
    rec.stored_apart()  # the work on rock the dissipated work (theory §11; when it is sampled)
    rec.coupling = Coupling(breaks, [a.spline for a in incoming], Z0)  # (the blow's tangent: coupled_tangent)
    work = float(sum(p.piston_work() for p in fl.pieces))
    gaps = _rigid_gaps(ex, force, q, v, t0, breaks.size - 1)
    return DrivenContact(q_after.copy(), v_after.copy(), t0 + ex.duration, rec, fl.state, fl.pieces,
                         fl.events, work, gaps)


def _rigid_gaps(ex, force, q, v, t0, n):
    """The piston's rigid coordinate ``-q_0`` during the blow (mass 1: ``q_0'' = p - N_c``, ``N_c``
    the shank's force), by the trapezoidal rule on the contact junction's breaks and a grid of
    ``64 n`` steps (where the drive's position switches would be crossed; the positions to the
    grid's second order)."""
    D = ex.duration
    t = np.union1d(np.linspace(0.0, D, 64 * n + 1), np.clip(ex.junction_breaks(ex.contact_junction), 0.0, D))
    acc = force(t) - ex.shank_force(t)
    dt = np.diff(t)
    vel = float(v[0]) + np.concatenate(([0.0], np.cumsum(0.5 * dt * (acc[:-1] + acc[1:]))))
    pos = float(q[0]) + np.concatenate(([0.0], np.cumsum(0.5 * dt * (vel[:-1] + vel[1:]))))
    return np.vstack((t0 + t, -pos))
