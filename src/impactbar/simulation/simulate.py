"""Event-driven simulation from any start, impact after impact (paper Section 5, theory §8).

Between impacts the bar moves in closed form (theory §2, eq. 8), so there is no
time-stepping error; a piecewise-constant load (the hydraulic square wave, eq. 34) is integrated
exactly piece by piece. The next impact, the first ``t`` with ``u(1,t) = c . q(t) = 0`` and
``u_t(1,t) > 0``, is found with a guaranteed search (bounds on ``|u_tt(1,t)|`` and
``|u_ttt(1,t)|`` from the modal energies exclude every step it takes), then refined to rounding;
after an impact the rigid bar under one harmonic and flexible bars under a Fourier load take
specialised searches with the same guarantee (switch ``"simulate.impact_search"`` of
:mod:`impactbar.dynamics.implementations`).
At an impact the model's law acts (:attr:`impactbar.BarModel.law`): the paper's
``u_t(x) -> -R u_t(x)`` (eqs. 10, 11) is applied inside the compiled flight kernel; a law that is
not instantaneous (the wave law, ``BarModel(impact="wave")``, theory §4b: a contact window of length
``2/s`` with the long rod, solved by characteristics) makes the kernel stop at the arrival, and its
contact step (:meth:`impactbar.laws.ContactLaw.contact`) gives the state where the flight resumes
(under the wave law after a sustained contact where the window ends with the end still driven into
the rod: :mod:`impactbar.laws.wave.sustained`).

With ``R < 1`` and a load pressing the end on the stop the bounces shrink geometrically and
accumulate in finite time; the simulation jumps to the accumulation point, where the velocity field
has gone to zero, and follows the bar fixed at ``x = 1`` (fixed-free modes
``r_m = int_0^1 u cos((m - 1/2) pi x) dx``, theory §8) until the stop's reaction
``F_stop = p - q_0'' - d q_0'`` would turn tensile; then the state is projected back on the
free-free modes and the free motion resumes.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .._shared.forcing import dispatch
from .._shared.status import RunStatus
from .._shared.validate import check_int, check_real
from ..drives.base import Drive, FlightSettings
from ..drives.flight import solver_settings
from ..dynamics import compiled as K
from ..dynamics.implementations import use_fast
from ..loads import Load
from ..model import BarModel
from ._core import CHATTER_TAIL, _Core, _core_for
from ._interrupt import SimulationInterrupted as SimulationInterrupted
from ._interrupt import _CtrlC
from ._shortrun import FIRST_BLOCK, SHORT_RUN_IMPACTS, run_short
from .driven import Driver, run_drive
from .initial import InitialState as InitialState
from .trajectory import _CONTACT as _CONTACT
from .trajectory import _ENTRIES as _ENTRIES
from .trajectory import _FREE as _FREE
from .trajectory import _WINDOW as _WINDOW
from .trajectory import MAX_ENERGY_WORK as MAX_ENERGY_WORK
from .trajectory import EnergyAccount as EnergyAccount
from .trajectory import Trajectory as Trajectory
from .trajectory import _energy_account as _energy_account
from .trajectory import _energy_nodes as _energy_nodes
from .trajectory import _Segment as _Segment
from .trajectory import _SegmentLog as _SegmentLog
from .trajectory import _Segments as _Segments

__all__ = ["InitialState", "Trajectory", "EnergyAccount", "SimulationInterrupted", "simulate"]

TWO_PI = 2.0 * math.pi

#: First extra dwell in contact when the free and the fixed-free bases disagree at a release.
DWELL_START = 1e-9
#: Largest such dwell (it grows fourfold while the disagreement lasts).
DWELL_MAX = 1e-2
#: A flight after a release that ends back on the stop within this time (bounces included) is a
#: disagreement between the truncated bases, not a motion: the release is undone.
MICRO_FLIGHT = 1e-6


@dataclass(slots=True)
class _Contact:
    """A contact interval of the run: its start and end (NaN while it lasts)."""
    start: float
    end: float = math.nan


class _Release(NamedTuple):
    """A release, as the run keeps it to undo it: its time, the contact segment's index in the log,
    and how many impact entries and impacts there were."""
    time: float
    segment: int
    entries: int
    impacts: int

# Implementations (impactbar.dynamics.implementations): "simulate.impact_search" searches the
# impacts after an impact by the kernel's specialised certified searches (the rigid bar under one
# harmonic in scalars, ``rigid1_crossing``; flexible modes under a Fourier load in folded form,
# ``modal_crossing``), the reference being the general search ``find_crossing`` (the same impacts, to
# rounding).

#: Largest ``|t0|``, ``|t_end|`` and ``t_end - t0`` accepted by :func:`simulate` (about 1.6e7 periods).
MAX_TIME = 1e8
#: Largest ``s * n_modes`` :func:`simulate` accepts: the guaranteed event search steps on the
#: scale of the stiffest mode's period, so beyond it a run does not finish in bounded time.
MAX_SIMULATE_STIFFNESS = 1e5
#: A run at least this long (dimensionless time, 1,000 load periods) catches Ctrl-C between
#: blocks of impacts and keeps what it computed (:class:`SimulationInterrupted`), as does any run
#: with a ``progress`` callback; not a run of at most ``SHORT_RUN_IMPACTS`` (256) impacts, done in
#: one compiled call or a few blocks (the handler's system calls were a tenth of a 1-impact run).
LONG_RUN = 2000.0 * math.pi
#: Least wall time (s) between two calls of a run's ``progress`` callback.
PROGRESS_EVERY = 0.1
_NO_LIMIT = int(np.iinfo(np.int64).max)  # max_impacts=None (np.iinfo per call: 2 us)


# --------------------------------------------------------------------------------------------------
# the driver
# --------------------------------------------------------------------------------------------------
def simulate(model: BarModel, load: Load | Drive, initial: InitialState, t_end, *, t0=0.0,
             max_impacts=None, progress=None, settings: FlightSettings | None = None,
             histories: bool = True) -> Trajectory:
    r"""Follow the bar from ``initial`` through impact after impact (paper Section 5).

    Between impacts every mode obeys :math:`q_n'' + d q_n' + (s n \pi)^2 q_n = p(t)` (eq. 6) and is
    advanced in closed form; at an impact (:math:`u(1,t) = 0`, :math:`u_t(1,t) > 0`)
    :math:`u_t(x, t^+) = -R\,u_t(x, t^-)` (eqs. 10, 11). Chatter is jumped over to its accumulation point,
    after which the bar stays on the stop (fixed at :math:`x = 1`, theory §8) until the stop's
    reaction would turn tensile.

    Parameters
    ----------
    model : BarModel
        The bar: ``s``, ``d``, ``R`` and ``N`` flexible modes.
    load : FourierLoad or PiecewiseConstantLoad or Drive
        The load at ``x = 0``, evaluated at absolute time (an impact at ``t`` has load phase
        :math:`t \bmod 2\pi`); or a :class:`~impactbar.Drive` (theory §10: autonomous, with state of its
        own, e.g. the valve of :class:`~impactbar.PositionSwitchedDrive`, which starts in return when
        the gap :math:`-q_0` is below ``switch_out`` and in stroke beyond it): the result is then a
        :class:`~impactbar.DrivenTrajectory` (a :class:`Trajectory`) with the drive's switches
        logged (:mod:`impactbar.simulation.driven`).
    initial : InitialState
        Free-free modal state at ``t0``, ``N + 1`` modes (a one-mode state is padded with zeros).
    t_end : float
        End of the run (dimensionless time), :math:`t_0 < t_{end} \le t_0 + 10^8` and
        :math:`|t_{end}| \le 10^8`
        (``MAX_TIME``: beyond, impact times are not resolved in double precision, and the run would
        not end in bounded time).
    t0 : float, optional
        Start time, :math:`|t_0| \le 10^8`. Default 0.
    max_impacts : int, optional
        Stop at this many impacts (at least 1); ``t_end`` of the result is then the last impact (under
        the wave law the end of its window; where its bounces accumulate, their accumulation point).
    progress : callable, optional
        Called as ``progress(fraction)`` with the fraction of ``[t0, t_end]`` done, in ``[0, 1]``,
        between blocks of impacts (at most every 0.1 s of wall time) and once at the end: e.g. to
        drive a progress bar with an estimate of the time left. Not with a
        :class:`~impactbar.Drive`.
    settings : FlightSettings, optional
        With a :class:`~impactbar.Drive` whose state is integrated, how its flights are
        (:class:`~impactbar.drives.FlightSettings`; the oil circuit's
        :class:`~impactbar.drives.circuit.CircuitFlightSettings`, its tolerances and options);
        default the drive's :attr:`~impactbar.Drive.integrator`. Not with a load (its flights are
        closed forms).
    histories : bool, optional
        ``False``: with a drive with state under a law whose contact takes time (theory §11, "The
        coupled blow"), each blow of the result keeps what is read of it once it ended, not the drive's
        pieces over it (a :class:`~impactbar.simulation.blows.BlowSummary`: its record, the drive's
        energies, work and extremes; a few kilobytes a blow against about 1.5 MB); the drive's histories
        inside the blows are then refused. The impacts and every other figure are the same. Default
        ``True``; no effect otherwise.

    Returns
    -------
    Trajectory
        A :class:`~impactbar.DrivenTrajectory` under a drive.

    Raises
    ------
    ValueError
        On a bad parameter (named in the message), a start that penetrates the stop
        (:math:`u(1, t_0) > 0`), an undamped resonance between a mode and a load harmonic, or a bar too
        stiff for the guaranteed event search, ``s * n_modes > 1e5`` (``MAX_SIMULATE_STIFFNESS``: the
        search steps on the scale of the stiffest mode's period).
    SimulationInterrupted
        On Ctrl-C during a run with ``progress``, or of at least 1,000 load periods (``LONG_RUN``)
        and more than 256 ``max_impacts``, in the main thread: a :class:`KeyboardInterrupt` whose
        ``trajectory`` holds the run up to the last block of impacts it finished (in a run of at most
        256 impacts Ctrl-C is an ordinary :class:`KeyboardInterrupt`).

    Examples
    --------
    >>> import math
    >>> from impactbar import BarModel, CosineLoad, InitialState, simulate
    >>> model = BarModel(s=10.0, d=0.05, R=0.5, n_modes=2)
    >>> run = simulate(model, CosineLoad(0.3, 1.0), InitialState.rigid(-0.01, 0.0, n_modes=2),
    ...                2 * math.pi * 20)
    >>> str(run.status), run.n_impacts > 10
    ('t_end', True)
    >>> run.energy.relative_residual < 1e-8  # the energy account closes
    True
    """
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be a callable of the fraction done; got "
                         f"{type(progress).__name__}")
    if not isinstance(model, BarModel):
        raise ValueError(f"model must be a BarModel; got {type(model).__name__}")
    if not isinstance(initial, InitialState):
        raise ValueError(f"initial must be an InitialState; got {type(initial).__name__}")
    # beyond |t| = 1e8 an impact time is resolved to worse than 1e-8 in double precision, and a run
    # of that many periods does not finish in bounded time: refused
    t0 = check_real("t0", t0, lo=-MAX_TIME, hi=MAX_TIME)
    t_end = check_real("t_end", t_end, lo=t0, hi=t0 + MAX_TIME, lo_open=True)
    if abs(t_end) > MAX_TIME:
        raise ValueError(f"t_end must be in [-{MAX_TIME:g}, {MAX_TIME:g}]; got {t_end}")
    max_imp = _NO_LIMIT if max_impacts is None else check_int("max_impacts", max_impacts, lo=1)
    if not isinstance(histories, bool | np.bool_):
        raise ValueError(f"histories must be True or False; got {histories!r}")
    N = model.n_modes
    if N and model.s * N > MAX_SIMULATE_STIFFNESS:
        raise ValueError(
            f"model: s * n_modes must be at most {MAX_SIMULATE_STIFFNESS:g} for simulate (the event search "
            f"resolves the stiffest mode, frequency s n_modes pi); got s = {model.s:g}, "
            f"n_modes = {N}: use fewer modes (a stiff bar moves as a rigid one, n_modes = 0)"
        )
    q = initial.modal_displacement.copy()  # (contiguous floats, as InitialState makes them)
    v = initial.modal_velocity.copy()
    if q.size == 1 and N > 0:
        q = np.concatenate((q, np.zeros(N)))
        v = np.concatenate((v, np.zeros(N)))
    if q.size != N + 1:
        raise ValueError(
            f"initial must have n_modes + 1 = {N + 1} modal coordinates; got {q.size}"
        )
    solver = dispatch(SIMULATORS, load)
    keep = {} if histories or solver is not _simulate_drive else {"histories": False}
    return solver(model, load, q, v, t0, t_end, max_imp, progress,
                  **solver_settings(settings, load, solver is _simulate_drive), **keep)


def _simulate_drive(model, drive, q, v, t0, t_end, max_imp, progress, settings=None,
                    histories=True) -> Trajectory:
    """:func:`simulate` under a drive (theory §10): the drive's own event loop over pieces of this
    driver, a drive with state's flights by ``settings`` (default its integrator), its blows'
    ``histories`` kept or summarised (:func:`simulate`)."""
    _push_off(model.end_weights, q)
    return run_drive(model, drive, q, v, t0, t_end, max_imp, _DRIVER, settings, bool(histories))


def _simulate_load(model, load, q, v, t0, t_end, max_imp, progress) -> Trajectory:
    """:func:`simulate` under a periodic load: the compiled flights and impacts (Section 5)."""
    core = _core_for(model, load)
    _push_off(core.c, q)
    if progress is None and (t_end - t0 < LONG_RUN or max_imp <= SHORT_RUN_IMPACTS):
        # (no Ctrl-C handler: a short run's cost)
        if core.instant and use_fast("simulate.short_run"):  # the first block: it may end the run
            traj, first = run_short(core, q, v, t0, t_end, max_imp, InitialState._trusted)
            return traj if traj is not None else _run(core, q, v, t0, t_end, max_imp, first=first)
        return _run(core, q, v, t0, t_end, max_imp)
    with _CtrlC() as ctrl_c:
        traj = _run(core, q, v, t0, t_end, max_imp, progress=progress, stop=ctrl_c)
    if ctrl_c.pressed:  # (also when the run ended in the block where Ctrl-C came)
        raise SimulationInterrupted(traj)
    return traj


def _push_off(c, q) -> None:
    """Refuse a start through the stop; a penetration within rounding is shifted off (in place)."""
    # (the bits of c @ q: c.dot(q) at less than half its cost on small arrays; one product for the
    # rigid bar, at a fifth of it)
    g = c.item(0) * q.item(0) if q.size == 1 else float(c.dot(q))
    if g > 0.0 and g > 1e-12 * max(1.0, float(np.sum(np.abs(c * q)))):
        raise ValueError(f"initial penetrates the stop: u(1, t0) = {g:.3e} > 0")
    if g > 0.0:
        q[0] -= g


def _run(core: _Core, q, v, t0, t_end, max_imp, progress=None, stop=False, first=None) -> Trajectory:
    """The driver, for every law: free flight by the compiled kernel (which applies an
    instantaneous law itself, with chatter), sustained contact until the stop's reaction turns
    tensile, and the law's contact step at each arrival the kernel stops at without resolving it.

    Between blocks of impacts (where the state is a flight's start) it calls ``progress`` and
    stops there (status ``"t_end"``, ``t_end`` the time reached) when ``stop`` has turned true.
    ``first``: the first block, done by :func:`run_short`, which ``q, v`` are the end of."""
    instant = core.instant
    if first is None and instant and progress is None and use_fast("simulate.short_run"):
        traj, first = run_short(core, q, v, t0, t_end, max_imp, InitialState._trusted)
        if traj is not None:  # the kernel's first call ended the run in flight, with no contact
            return traj
    segs = _SegmentLog(core.N, min(max_imp, FIRST_BLOCK) + 1)  # a short run's pieces without a resize
    if first is None:
        segs.add(t0, _FREE, q, v, "start")
    else:  # run_short's first block: the log goes on from it (q, v are where its kernel stopped)
        segs.add(t0, _FREE, first.q[0], first.v[0], "start")
    times: list = []  # blocks of the kernel's impacts (arrays), or the law's contact steps (floats)
    vels: list = []
    contacts: list[_Contact] = []
    n_imp = 0
    t = t0
    mode = _FREE
    status = RunStatus.T_END
    dwell = 0.0
    retries = 0
    last_release = None  # the last release, for undoing
    cap = FIRST_BLOCK
    in_flight = False  # the run ended at t_end in a flight of the kernel's: q, v its state there
    if not instant:  # the kernel's state at the arrival it stops at
        aq, av = np.empty((1, q.size)), np.empty((1, q.size))
    shown = time.monotonic()
    while True:
        if progress is not None and time.monotonic() - shown >= PROGRESS_EVERY:
            progress(min(1.0, (t - t0) / (t_end - t0)))
            shown = time.monotonic()
        if stop:  # (at a flight's start: the log is consistent)
            break
        if mode == _FREE:
            left = max_imp - n_imp
            if left <= 0:  # pragma: no cover - run_free stops at max_imp itself
                status = RunStatus.MAX_IMPACTS
                break
            if not instant:  # the kernel stops at the next arrival, applying nothing
                qa, va = q.copy(), v.copy()
                n, st, tn, ot, _ = core.run_free(t, q, v, t_end, 1, aq, av)
                if st == K.MAXIMP or st == K.CONTACT:  # an impact, or a touch at zero speed
                    q, v, t = _contact_step(core, segs, t, qa, va, n, tn, ot, aq, av, times, vels,
                                            t_end, contacts)
                    n_imp += 1
                    if t >= t_end:  # the run ends inside the contact
                        t = t_end
                        break
                    segs.add(t, _FREE, q, v, "release")
                    if n_imp >= max_imp:
                        status = RunStatus.MAX_IMPACTS
                        break
                    continue
            elif first is not None:  # the first block, done by run_short: its rows into the log
                n, st, tn, ot, ov = first.n, first.status, first.t, first.times, first.velocities
                oq, ovv = segs.impact_rows(n)
                oq[...] = first.q[1:]
                ovv[...] = first.v[1:]
                del oq, ovv
                first = None
                cap = min(cap * 2, 1 << 16)
            else:
                # the kernel writes into the log's next rows; at most an eighth more than the log
                # holds, so the run's peak memory stays near its stored trajectory
                oq, ovv = segs.impact_rows(min(cap, left, max(FIRST_BLOCK, segs.count // 8)))
                n, st, tn, ot, ov = core.run_free(t, q, v, t_end, left, oq, ovv)
                del oq, ovv  # no view of the log may outlive the call (it is resized in place)
                cap = min(cap * 2, 1 << 16)
            if n:  # (views of the kernel's fresh output, copied where it is mostly unused)
                times.append(ot if 2 * n >= ot.base.size else ot.copy())
                vels.append(ov if 2 * n >= ov.base.size else ov.copy())
                segs.add_impacts(ot)
                n_imp += n
            if st == K.FAILED:  # pragma: no cover - defensive
                raise ValueError(f"impact search did not converge at t = {tn}: the model is too "
                                 f"stiff for the event search (s = {core.model.s:g}, n_modes = "
                                 f"{core.N}); use fewer modes")
            if st == K.END:
                t = t_end
                in_flight = True
                break
            if st == K.MAXIMP:
                t = tn
                status = RunStatus.MAX_IMPACTS
                break
            if st == K.FULL:
                t = tn
                continue
            # CHATTER or CONTACT: the end stays on the stop from tn
            micro = last_release is not None and tn - last_release.time <= MICRO_FLIGHT
            if micro:
                # the free motion presses straight back (at once, or after a few bounces too
                # small to matter): the bases disagree on the sign of the reaction here. Undo
                # the release and stay in contact a little longer (fourfold) before asking again.
                t_rel, seg_index, k_times, n_saved = last_release
                segs.truncate(seg_index + 1)
                del times[k_times:], vels[k_times:]
                n_imp = n_saved
                contacts[-1].end = math.nan
                dwell = min(max(4.0 * dwell, DWELL_START), DWELL_MAX)
                retries += 1
                cseg = segs.last()
                t = t_rel
                mode = _CONTACT
                r, rv = _contact_at(core, cseg, t_rel + dwell, t_end)
                if r is None:
                    contacts[-1].end = t_end
                    t = t_end
                    break
                t = t_rel + dwell
                last_release = None
            else:
                dwell = 0.0
                if st == K.CHATTER:
                    frozen = q.copy()
                    r, rv = core.contact_state(q, np.zeros_like(v))
                    t = min(tn, t_end)
                    segs.add(t, _CONTACT, r, rv, "chatter", frozen)
                else:
                    r, rv = core.contact_state(q, v)
                    t = tn
                    segs.add(t, _CONTACT, r, rv, "touch")
                contacts.append(_Contact(t))
                mode = _CONTACT
                if t >= t_end or (st == K.CHATTER and n_imp >= max_imp):  # (the last impact's bounces)
                    contacts[-1].end = min(t, t_end)
                    status = RunStatus.T_END if t >= t_end else RunStatus.MAX_IMPACTS
                    break
        # ---- in contact: from (t, r, rv) find the release ----
        st, tr, rr, rrv = core.find_release(t, r, rv, t_end)
        if st == K.FAIL:  # pragma: no cover - defensive
            raise ValueError(f"release search did not converge at t = {tr}: the model is too "
                             f"stiff for the event search (s = {core.model.s:g}, n_modes = "
                             f"{core.N}); use fewer modes")
        if st == K.NONE:
            contacts[-1].end = t_end
            t = t_end
            break
        contacts[-1].end = tr
        q, v = core.release_state(rr, rrv)
        last_release = _Release(tr, segs.count - 1, len(times), n_imp)
        segs.add(tr, _FREE, q, v, "release")
        t = tr
        mode = _FREE
    # ---- final state ----
    i = segs.count - 1
    if t == segs.t[i] and segs.basis[i] == _FREE:  # the run ended on a piece's start (max_impacts)
        qe, ve = segs.q[i].copy(), segs.v[i].copy()
        last = None
    elif segs.basis[i] == _WINDOW:  # the run ended inside a law's contact step
        last = segs.last()
        qe, ve = last.frozen.state_at(min(t - last.t, last.frozen.duration))
    elif in_flight:  # the kernel's state at t_end: the flow from the last piece's start, to the bit
        qe, ve = q, v
    else:
        last = segs.last()
        qe, ve = core.propagate(last.basis, last.t, last.q, last.v, [t])
        qe, ve = qe[:, 0], ve[:, 0]
        if last.basis == _CONTACT:
            qe, ve = core.release_state(qe, ve)
    if progress is not None:
        progress(min(1.0, (t - t0) / (t_end - t0)))
    imp_t = _joined(times) if instant else np.array(times, dtype=float)
    imp_v = _joined(vels) if instant else np.array(vels, dtype=float)
    ci = np.array([(c.start, c.end) for c in contacts], dtype=float).reshape(-1, 2)
    return Trajectory(model=core.model, load=core.load, t0=t0, t_end=t,
                      impact_times=imp_t, impact_velocities=imp_v, contact_intervals=ci,
                      final_state=InitialState._trusted(qe, ve), status=status, _core=core,
                      _segments=segs.finish(), n_release_retries=retries)


def _joined(blocks: list) -> np.ndarray:
    """The blocks of a run's impact data as one array (the block itself when there is one)."""
    if len(blocks) == 1:
        return blocks[0]
    return np.concatenate(blocks) if blocks else np.zeros(0)


def _contact_at(core: _Core, seg: _Segment, t: float, t_end: float):
    """Contact state at ``t`` on the contact segment ``seg`` (None when ``t >= t_end``)."""
    if t >= t_end:
        return None, None
    r, rv = core.propagate(_CONTACT, seg.t, seg.q, seg.v, [t])
    return r[:, 0], rv[:, 0]


def _contact_step(core: _Core, segs: _SegmentLog, t, qa, va, n, tn, ot, aq, av, times, vels, t_end,
                  contacts):
    """The law's contact step at the arrival the kernel stopped at (an impact, ``n = 1``, its state
    in ``aq, av``; or a touch at zero speed at ``tn``, the state then from the flight's start
    ``(t, qa, va)``): logs the contact segment and the impact; returns the state and time where the
    flight resumes (positions from the stop, which the contact may have advanced). A sustained
    contact after the law's window (:attr:`~impactbar.laws.LawTraits.open_ended`) goes into
    ``contacts``."""
    model = core.model
    c = core.c
    ti = float(ot[0]) if n else float(tn)
    if n:
        qm, vm = aq[0].copy(), av[0].copy()
    else:
        qm, vm = (a[:, 0] for a in core.propagate(_FREE, t, qa, va, [ti]))
    qm[0] -= float(c @ qm)  # the end exactly on the stop
    arrival = float(c @ vm)
    if arrival < 0.0:  # a touch whose speed rounded below zero
        vm[0] -= arrival
        arrival = 0.0
    law = model.law
    kw = {"t_end": t_end} if law.traits.open_ended else {}
    q, v, t_release, record = law.contact(model, core.load, ti, qm, vm, kernel=core, **kw)
    sustained = getattr(record, "sustained", None)
    if sustained is not None:
        contacts.append(_Contact(sustained.t0, min(t_release, t_end)))
    times.append(ti)  # floats: the run's impacts are all the law's (no kernel blocks)
    vels.append(arrival)
    segs.add(ti, _WINDOW, qm, vm, "impact", record)
    return q, v, t_release


#: the solver of :func:`simulate` for each forcing family (the one place it is chosen)
SIMULATORS = {"load": _simulate_load, "drive": _simulate_drive}

#: the driver as a drive's run takes it (:func:`impactbar.simulation.driven.run_drive`)
_DRIVER = Driver(core_for=_core_for, run=_run, push_off=_push_off, make_state=InitialState, tail=CHATTER_TAIL)
