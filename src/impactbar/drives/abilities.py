"""What a drive can do beyond the hooks every drive implements: :class:`DriveAbilities`, the object
:attr:`impactbar.Drive.abilities` returns, and the abilities it holds.

A solver asks a drive its abilities where it dispatches on them (the simulator its compiled loop, a
flight its own integration, the orbit solvers its own problem) and takes what is there; an ability
that is ``None`` leaves the generic path (:mod:`impactbar.drives.flight`, the simulator's loop in
Python, the shooting problem), so that a drive with the required hooks alone runs everywhere. As
scipy's ``OdeSolver`` asks two methods of a solver, each ability asks a few of the drive.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

__all__ = ["DriveAbilities", "CompiledLoop", "OwnFlight", "Quadratures", "NONE"]


@dataclass(frozen=True)
class CompiledLoop:
    """A compiled event loop of the drive's own, for a force constant between events.

    Parameters
    ----------
    levels : tuple of float
        The constant forces it takes (the valve's ``(+stroke, -ret)``); the simulator hands the loop
        the compiled driver's data of each (:class:`~impactbar.drives.base.FlightKernel`).
    build : callable
        ``build(model, kernel)``: an object whose ``run(state, t, q, v, t_end, n_impacts,
        max_impacts)`` follows the drive through many flights and returns a
        :class:`~impactbar.drives.base.KernelRun` (``None``: the simulator's loop in Python).
    """

    levels: tuple[float, ...]
    build: Callable[..., Any]


@dataclass(frozen=True)
class OwnFlight:
    """The drive's own integration of its flights (in place of the generic flight of
    :func:`impactbar.drives.flight.fly`, ``solve_ivp`` over the drive's ``force`` and ``rate``).

    Parameters
    ----------
    fly : callable
        ``fly(model, state, t, q, v, t_stop, settings=None, variational=False)``: a
        :class:`~impactbar.drives.flight.Flight` ending at the first of the arrival at the stop, one
        of the drive's events or ``t_stop``; with ``variational`` the flight's fundamental matrix of
        ``(q, q', z)`` in ``Flight.sensitivity``.
    variational : bool, optional
        Whether ``fly`` integrates the variational equations when asked (the generic periodic orbits
        then take the shooting Jacobian and the multipliers from them). Default ``False``.
    state_settings : callable or None, optional
        ``state_settings(model, settings=None)``: the integrator of a plain flight whose state is that
        of the variational flight with ``settings``, bit for bit, or ``None`` where the variational
        flight's state is its own (the oil circuit's flexible piston has one). Default ``None``.
    carried : callable or None, optional
        ``carried(model, settings) -> bool``: whether ``fly`` takes ``start=D``, the Jacobian so far
        (an ``(n, n)`` array), its variational equations started there, so that its
        ``Flight.sensitivity`` is the Jacobian carried through the flight (the shooting problem then
        composes the events' saltations alone, theory §11); ``None`` (default) or ``False``: each
        flight's fundamental matrix from the identity, composed after.
    root_settings : callable or None, optional
        ``root_settings(model, settings) -> FlightSettings or None``: the integrator of plain flights
        whose root is the orbit itself, as accurate as the variational flights' state, so that the
        chord's root needs no closing step by a variational flight (theory §11, *The integrator*);
        ``None`` (default), or a ``None`` returned: the orbit is the variational flights' root.
    charged_start : callable or None, optional
        ``charged_start(model, q, v) -> DriveState or None``: a state of the drive nearer the orbit
        than its ``start`` from rest (the oil circuit's supply charged to its relief valve's
        setting), from which the periodic orbits whose chord's root is ``root_settings``' follow the
        motion to Newton's start (:func:`impactbar.orbits._closing.settle_start`); ``None`` (default),
        or a ``None`` returned: ``start``.
    """

    fly: Callable[..., Any]
    variational: bool = False
    state_settings: Callable[..., Any] | None = None
    carried: Callable[..., Any] | None = None
    root_settings: Callable[..., Any] | None = None
    charged_start: Callable[..., Any] | None = None


@dataclass(frozen=True)
class Quadratures:
    """Quadratures the drive keeps of its own along a run (the oil circuit's energy account), for
    the rigid piston resting on the stop.

    Parameters
    ----------
    count : int
        How many (the oil circuit's: 8).
    integrands : callable
        ``integrands(mode, z, q, v, model=None)``: their integrands, shape ``(count,)`` (``model``
        passed for a stepped piston only, as to the drive's ``rate``).
    piston_work : int or None, optional
        Which of them is the drive's work on the piston, ``int p u_t(0, t) dt``; ``None`` (default):
        none (the solvers then integrate the force against the driven end's velocity).
    """

    count: int
    integrands: Callable[..., Any]
    piston_work: int | None = None


@dataclass(frozen=True)
class DriveAbilities:
    """What a drive can do beyond its required hooks, each ``None`` where it cannot (the generic path
    then runs): returned by :attr:`impactbar.Drive.abilities`.

    Parameters
    ----------
    compiled_loop : CompiledLoop or None
        A compiled event loop (the valve's, :mod:`impactbar.drives.valve.loop`).
    flight : OwnFlight or None
        Its own integration of its flights (the oil circuit's CVODE).
    quadratures : Quadratures or None
        Quadratures it keeps of its own (the oil circuit's energy account).
    end_flight : callable or None
        ``end_flight(model, state, breaks, w0, incoming, impedance, settings=None)``: the drive's
        state over a stretch of a blow under a law whose contact takes time (theory §11, "The coupled
        blow"), the driven end answering the drive's force ``p`` as a semi-infinite bar of impedance
        ``Z``, :math:`u_t(0, t) = a(t) + p/Z`, ``incoming`` the wave ``a`` on each interval between
        ``breaks`` (a float or a callable of the time), ``w0`` the end's ``w = -u(0, t)`` at
        ``breaks[0]``. It returns an object with ``state`` (at ``breaks[-1]``), ``w``, ``impulses``
        (``int p dt`` over each interval), ``pieces`` and ``events`` (the oil circuit's
        ``EndFlight``). A drive with state without it runs under an instantaneous law only.
    end_tangent : callable or None
        ``end_tangent(pieces, events, mode, breaks, splines, impedance, t0)``: the variational
        equations of the drive's state along the blow's flight (``pieces`` and ``events`` of an
        ``end_flight``, ``splines`` its wave ``a`` as a cubic spline ``(x, c, t0)`` on each interval,
        ``t0`` the impact's time), for the coupled blow's tangent (the oil circuit's
        :class:`~impactbar.drives.circuit.endtangent.EndTangent`); ``None``: the coupled blow's
        Jacobian by differences.
    border_tests : callable or None
        ``border_tests(pieces)``: ``{surface: value}`` over one period of an orbit whose flights are
        ``pieces``, each value changing sign where the drive's state touches that switching surface
        during the period (a border collision, located by the continuation of driven orbits).
    orbit_problem : callable or None
        ``orbit_problem(model, impacts, constant_load)``: the drive's own periodic-orbit problem
        (:class:`~impactbar.drives.OrbitProblem`), in place of the generic shooting problem of
        :mod:`impactbar.orbits.driven`; ``constant_load(p)`` gives the load of a constant force
        ``p`` (for a contact law's map).
    start_mode : callable or None
        ``start_mode(mode, q, v, z)``: the mode a flight of a periodic orbit's block starts in from
        the state ``(q, v, z)``, given the block's mode (fixed from the guess): the flags that the
        state decides set by it where they disagree (the oil circuit's watched levels: its module
        ``watch``'s ``consistent_mode``); ``mode`` itself where they agree.
        ``None``: the block's mode.

    Examples
    --------
    >>> from impactbar import PositionSwitchedDrive
    >>> abilities = PositionSwitchedDrive(stroke=2.0, ret=1.0, switch_out=0.5).abilities
    >>> abilities.compiled_loop.levels, abilities.flight
    ((2.0, -1.0), None)
    """

    compiled_loop: CompiledLoop | None = None
    flight: OwnFlight | None = None
    quadratures: Quadratures | None = None
    end_flight: Callable[..., Any] | None = None
    end_tangent: Callable[..., Any] | None = None
    border_tests: Callable[..., dict] | None = None
    orbit_problem: Callable[..., Any] | None = None
    start_mode: Callable[..., Any] | None = None


#: the abilities of a drive that has none (the default of :attr:`impactbar.Drive.abilities`)
NONE = DriveAbilities()
