"""Continuation of periodic motions under a position-switched drive (theory §10).

The augmented problem for the engine (:mod:`impactbar.continuation.engine`) is the segment problem
of :func:`impactbar.orbits.find_switched_orbit` (unknowns: the state after the impact and the free
flight times ``h1``, ``h3``; conditions: the impact law, the switch crossing and the contact) with
the continued parameter appended: a field of the drive (``stroke``, ``ret``, ``switch_out``,
``delay``) or of the bar (``R``, ``d``, ``s``). The events are those of
:func:`impactbar.continue_orbit` (fold, period doubling, Neimark-Sacker, an impact velocity through
0, a change of admissibility), confirmed by the multipliers of the autonomous map (the trivial one
along the flow set apart), and the grazing of the switching surface: the gap's rate at the switch
crossing going through 0.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
from scipy.optimize import brentq

from .._shared.status import BranchStatus, EventKind
from .._shared.validate import check_real
from ..drives.switched import PositionSwitchedDrive
from ..model import BarModel
from ..orbits.switched import SwitchedOrbit, _constants, _residual, orbit_at
from .branch import Branch, BranchEvent
from .engine import ContinuationSettings, _Engine, _settings
from .parameters import _target

__all__ = ["SWITCHED_PARAMETERS", "continue_switched"]

EVENT_KINDS = tuple(EventKind)

#: Parameters a switched orbit can be continued in: the drive's fields and the bar's.
SWITCHED_PARAMETERS = ("stroke", "ret", "switch_out", "delay", "R", "d", "s")


def _with(model: BarModel, drive: PositionSwitchedDrive, name: str, value: float):
    """The model and drive with one parameter changed (validated again by their constructors)."""
    if name in ("R", "d", "s"):
        return model.with_(**{name: value}), drive
    return model, dataclasses.replace(drive, **{name: value})


class _SwitchedProblem:
    """The segment problem of a switched orbit in ``U = (state, h1, h3, lambda)``, for the engine."""

    def __init__(self, model, drive, name, detect, *, events=True, stop_on=(), xtol=1e-10):
        self.model0, self.drive0, self.name, self.detect = model, drive, name, detect
        self.events, self.stop_on, self.xtol = events, stop_on, xtol
        size = 2 * (model.n_modes + 1) + 2
        self.W = np.append(np.full(size, 1.0 / size), 1.0)
        self.pair = functools.lru_cache(maxsize=16)(self._pair)

    def _pair(self, lam: float):
        """The model, drive and residual constants at the parameter value ``lam``."""
        model, drive = _with(self.model0, self.drive0, self.name, lam)
        if model.R >= 1.0:
            raise ValueError("R must be < 1 for a switched orbit")
        return model, drive, _constants(model)

    def F(self, U):
        model, drive, consts = self.pair(float(U[-1]))
        return _residual(model, drive, U[:-1], consts)[0]

    def FJ(self, U, F_lam=None):
        """Residual, the Jacobian ``[F_u, F_lam]`` (``F_u`` exact, ``F_lam`` by central
        differences unless given, one-sided at the edge of the parameter's range) and ``F_lam``."""
        model, drive, consts = self.pair(float(U[-1]))
        F, DF = _residual(model, drive, U[:-1], consts)
        if F_lam is None:
            h = 1e-6 * max(1.0, abs(U[-1]))
            sides = []
            for sign in (1.0, -1.0):
                try:
                    sides.append(self.F(np.append(U[:-1], U[-1] + sign * h)))
                except ValueError:
                    sides.append(None)
            up, down = sides
            if up is None and down is None:
                raise ValueError(f"{self.name}: no admissible value within {h:g} of {U[-1]}")
            F_lam = ((up if up is not None else F) - (down if down is not None else F)) / (
                h * ((up is not None) + (down is not None)))
        return F, np.column_stack((DF, F_lam)), F_lam

    def orbit(self, U, admissibility=True):
        model, drive, _ = self.pair(U[-1])
        return orbit_at(model, drive, U[:-1])

    def acceptable(self, U):
        return bool(U[-3] > 0.0 and U[-2] > 0.0)  # positive flight times

    def after_point(self, engine, points, tangents, orbits):
        if not self.events:
            return [], None
        new = self.detect(engine, points, tangents, [_tests(o) for o in orbits[-2:]], orbits, self.xtol)
        graze = _switch_grazing(engine, points, tangents, orbits, self.xtol)
        if graze is not None:
            new.append(graze)
            Ua = points[-2]
            ta = tangents[-2] if tangents[-2] is not None else points[-1] - Ua
            new.sort(key=lambda e: engine.dot(ta, e._point - Ua))
        hit = [e for e in new if e.kind in self.stop_on]
        return new, (BranchStatus.stopped_at(hit[0].kind) if hit else None)

    def corner(self, engine, U, index):
        return None


def _tests(o: SwitchedOrbit) -> dict:
    """The test functions of :func:`impactbar.continuation.core._detect` at a switched orbit (no
    clearance: the grazing of the stop between impacts shows in the admissibility flag)."""
    mu = o.multipliers
    cpx = mu[mu.imag > 1e-10 * np.maximum(1.0, np.abs(mu))]
    ns = float(np.prod(np.abs(cpx) ** 2 - 1.0)) if cpx.size else 1.0
    return {"fold": float(np.prod(1.0 - mu).real), "period-doubling": float(np.prod(1.0 + mu).real),
            "neimark-sacker": ns, "pairs": int(cpx.size),
            "grazing": math.nan, "impact": o.impact_velocity, "admissible": o.admissible}


def _switch_grazing(engine, points, tangents, orbits, xtol):
    """A grazing of the switching surface between the last two points: the gap's rate at the
    switch crossing changes sign; located by Brent's method along the chord (as the other events)."""
    a, b = orbits[-2].switch_velocity, orbits[-1].switch_velocity
    if not a * b < 0.0:
        return None
    Ua, Ub = points[-2], points[-1]
    ta = tangents[-2] if tangents[-2] is not None else (Ub - Ua) / engine.norm(Ub - Ua)
    hb = engine.dot(ta, Ub - Ua)
    found = {}

    def g(hh):
        pred = Ua + hh * ta
        U, _ = engine.correct(pred, ta, pred)
        if U is None:
            raise ValueError("no point")
        found[hh] = U
        return engine.orbit(U).switch_velocity

    try:
        hh = brentq(g, 0.0, hb, xtol=xtol, rtol=4 * np.finfo(float).eps, maxiter=200) if hb else None
    except (ValueError, RuntimeError):
        return None
    if hh is None:
        return None
    U = found.get(hh)
    if U is None:
        g(hh)
        U = found[hh]
    return BranchEvent(kind=EventKind.GRAZING, parameter=engine.problem.name, value=float(U[-1]),
                       index=len(points) - 1, orbit=engine.orbit(U), multiplier=complex(math.nan, math.nan),
                       _point=U)


def checked_events(stop_on, xtol: float) -> tuple[tuple, float]:
    """``stop_on`` as a tuple of event kinds and ``xtol`` in ``(0, 1e-2]``, checked (a ValueError
    names the argument)."""
    xtol = check_real("xtol", xtol, lo=0.0, lo_open=True, hi=1e-2)
    stop_on = tuple(stop_on)
    for k in stop_on:
        if k not in EVENT_KINDS:
            raise ValueError(f"stop_on must hold event kinds from {EVENT_KINDS}; got {k!r}")
    return stop_on, xtol


def continue_switched(orbit: SwitchedOrbit, parameter: str, to: float, detect, *,
                      settings: ContinuationSettings | None = None, events: bool = True, stop_on=(),
                      xtol: float = 1e-10) -> Branch:
    """Follow a periodic motion under a position-switched drive as one parameter changes, by
    pseudo-arclength continuation (theory §7, §10). Called by :func:`impactbar.continue_orbit`
    when its start is a :class:`~impactbar.SwitchedOrbit`.

    Parameters
    ----------
    orbit : SwitchedOrbit
        The start (from :func:`impactbar.find_orbit` with the drive).
    parameter : str
        One of :data:`SWITCHED_PARAMETERS`: ``"stroke"``, ``"ret"`` (force levels, dimensionless,
        eq. 2), ``"switch_out"`` (bar lengths), ``"delay"`` (dimensionless time), ``"R"``, ``"d"``,
        ``"s"``.
    to : float
        Target value; the branch stops there or where it leaves the range between start and ``to``.
    detect : callable
        The event detection of :func:`impactbar.continue_orbit`
        (``impactbar.continuation.core._detect``, handed in: this module sits below that one).
    settings : ContinuationSettings, optional
        Steps, point limit and Newton tolerance.
    events : bool
        Detect and locate events: ``"fold"``, ``"period-doubling"``, ``"neimark-sacker"`` (from the
        non-trivial multipliers), ``"grazing"`` (an impact velocity, or the gap's rate at the switch
        crossing, through 0), ``"admissibility"``.
    stop_on : iterable of str
        Event kinds at which to stop.
    xtol : float
        Tolerance of the event location along the chord.

    Returns
    -------
    Branch
        Its ``orbits`` are :class:`~impactbar.SwitchedOrbit` (``period``, ``blow_frequency``,
        multipliers); ``impacts = periods = 1``.

    Raises
    ------
    ValueError
        For a bad argument (named), or a start that is not a solution.
    """
    if not isinstance(orbit, SwitchedOrbit):
        raise ValueError(f"orbit must be a SwitchedOrbit; got {type(orbit).__name__}")
    if parameter not in SWITCHED_PARAMETERS:
        raise ValueError(f"parameter must be one of {SWITCHED_PARAMETERS} for a switched orbit; "
                         f"got {parameter!r}")
    model, drive = orbit.model, orbit.drive
    lam0 = float(getattr(model if parameter in ("R", "d", "s") else drive, parameter))
    to = _target(parameter, lam0, to)
    settings = _settings(settings)
    steps = settings.steps(abs(to - lam0))
    stop_on, xtol = checked_events(stop_on, xtol)
    direction = 1.0 if to > lam0 else -1.0
    problem = _SwitchedProblem(model, drive, parameter, detect, events=events, stop_on=stop_on, xtol=xtol)
    engine = _Engine(problem, settings.tol)
    U0 = np.concatenate((orbit.state, orbit.durations[[1, 3]], [lam0]))
    F0, J0, _ = problem.FJ(U0)
    if float(np.max(np.abs(F0))) > 1e-9 * max(1.0, float(np.max(np.abs(U0)))):
        raise ValueError("orbit: not a solution of the segment problem at the start value")
    t0 = np.linalg.svd(J0)[2][-1]
    t0 /= engine.norm(t0)
    if t0[-1] * direction < 0:
        t0 = -t0
    lo, hi = min(lam0, to), max(lam0, to)
    P, orbits, found, status = engine.march(U0, t0, to, direction, lo, hi, steps, settings.max_points)
    return Branch(parameter=parameter, values=P[:, -1].copy(), orbits=orbits, events=tuple(found),
                  status=status, impacts=1, periods=1, _points=P)
