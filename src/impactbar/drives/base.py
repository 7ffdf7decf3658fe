r"""The drive interface: what the solvers ask of a drive that is not a function of time (theory §10).

A *drive* takes the place of a periodic :class:`~impactbar.Load` at the driven end ``x = 0``, but
its force is not a function of time: it is a function of the drive's own state, which changes with
the bar's motion. The bar and the drive together are autonomous (the blow frequency is an output).
Each drive is a hybrid system (a *switched* system) with

- a discrete ``mode`` (any hashable value: the valve's position, pending delayed switches, ...) and a
  continuous state ``z`` of ``state_size`` numbers (empty for a force that is piecewise constant; the
  chamber pressures of an oil circuit), together a :class:`DriveState`;
- between events, the force :meth:`Drive.force` on the piston and the rate :meth:`Drive.rate` of
  ``z``, coupled to the modes of the bar, :math:`q_n'' + d q_n' + (s n \pi)^2 q_n = p` (eq. 6);
- events, :meth:`Drive.events`: crossings of a position or velocity by the piston, scheduled times
  (a valve's delay, a ramp's end) or any surface ``g(t, q, q', z) = 0`` crossed in a direction
  (:class:`DriveEvent`), each with its map :meth:`Drive.jump`, and the map at an impact,
  :meth:`Drive.impact`;
- its parameters for continuation, :attr:`Drive.parameters`, and their copies :meth:`Drive.with_`.

The solvers dispatch on this interface, never on a drive's class: :func:`impactbar.simulate`
(:mod:`impactbar.simulation.switched`), :func:`impactbar.find_orbit`
(:mod:`impactbar.orbits.switched`) and :func:`impactbar.continue_orbit`
(:mod:`impactbar.continuation.switched`). A drive without state (``state_size == 0``) has a force
that is constant between events: its flights are the closed-form flights of the modes (eq. 8), run by
the simulator's certified event search, and its events in closed form where they are crossings of
the piston's position or velocity or scheduled times (:meth:`DriveEvent.first_time`). A drive with
state is integrated with scipy's ``solve_ivp`` (stiff methods) and its events located to the
integrator's tolerance. A drive may add numerics of its own where they pay: a compiled event loop
(:meth:`Drive.compiled_loop`), as the valve of :class:`~impactbar.PositionSwitchedDrive` does, and
a closed-form periodic-orbit problem with an exact Jacobian (:meth:`Drive.orbit_problem`; the
valve's sits with the orbit solvers, :data:`impactbar.orbits.switched.ORBIT_PROBLEMS`); otherwise
the generic paths run.

The design follows three well-kept codes: the event functions of scipy's ``solve_ivp`` (a scalar
function of the state whose zero is crossed in a ``direction``, +1 rising, -1 falling, 0 either, and
that ends the step: :class:`DriveEvent`), Siconos' event-driven simulation of nonsmooth dynamical
systems (a vector field between events, ``computeF``, and a map at each event, its non-smooth law:
:meth:`Drive.rate` and :meth:`Drive.jump`; scheduled events beside state events), and Hopsan's
components (parameters registered by name, read by the solver and copied with new values:
:attr:`Drive.parameters`, :meth:`Drive.with_`). The saltation matrices of the multipliers follow
Hiskens and Pai (2000).

References
----------
I. A. Hiskens, M. A. Pai, "Trajectory sensitivity analysis of hybrid systems", IEEE Trans. Circuits
Syst. I 47(2) (2000) 204-220.
V. Acary, B. Brogliato, *Numerical Methods for Nonsmooth Dynamical Systems*, Springer (2008), ch. 7
(event-driven schemes, the basis of Siconos' ``EventDriven`` simulation).
"""

from __future__ import annotations

import dataclasses
import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, NamedTuple

import numpy as np

from .._shared.parameters import NamedParameters
from .._shared.registry import register

if TYPE_CHECKING:
    from .orbitproblem import OrbitProblem

__all__ = ["Drive", "DriveState", "FlightSettings", "DriveEvent", "GapCrossing", "RateCrossing", "TimedEvent",
           "SurfaceEvent", "FlightKernel", "KernelRun"]


class DriveState(NamedTuple):
    """A drive's state: its discrete ``mode`` and its continuous state ``z``.

    Attributes
    ----------
    mode : hashable
        The drive's discrete state (chosen by the drive; the solvers only hand it back).
    z : numpy.ndarray, shape (k,)
        The continuous state, ``k = Drive.state_size`` (shape ``(0,)`` for a drive without state).

    Examples
    --------
    >>> import numpy as np
    >>> from impactbar import DriveState
    >>> state = DriveState(mode="stroke", z=np.array([2.0e7]))  # e.g. a chamber pressure
    >>> state.mode, state.z.shape
    ('stroke', (1,))
    """

    mode: Hashable
    z: np.ndarray


# --------------------------------------------------------------------------------------------------
# events
# --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class DriveEvent:
    """An event of a drive: the zero of an event function crossed in a direction (scipy's
    ``solve_ivp`` convention). A base class; the solvers use :meth:`value` and, under a constant
    force, :meth:`first_time`.

    Attributes
    ----------
    name : str
        What the drive calls it (handed back to :meth:`Drive.jump`).
    direction : int
        ``+1``: the function rises through 0; ``-1``: it falls; ``0``: either.
    """

    name: str
    direction: int = 0

    def value(self, t: float, q: np.ndarray, v: np.ndarray, z: np.ndarray) -> float:
        """The event function ``g(t, q, q', z)`` (its zero is the event)."""
        raise NotImplementedError  # pragma: no cover - every event kind defines it

    def first_time(self, d: float, p: float, t: float, q: np.ndarray, v: np.ndarray) -> float:
        """The first time after ``t`` at which the event happens on the flight under the constant
        force ``p`` from the modal state ``(q, v)`` at ``t`` (damping ``d``): in closed form,
        ``inf`` if never; ``nan`` where the event has no closed form (the solver then locates it
        numerically)."""
        return math.nan

    def crossing_speed(self, q: np.ndarray, v: np.ndarray) -> float:
        """At a crossing of a switch position, the gap's rate in the crossing's direction (0 where
        the motion grazes the switching surface); ``nan`` for other events."""
        return math.nan


@dataclass(frozen=True)
class GapCrossing(DriveEvent):
    """The piston's gap ``y = -q_0`` (its rigid coordinate measured from the stop, bar lengths)
    crossing ``level`` (theory §10): ``g = -q_0 - level``. Under a constant force the rigid
    coordinate obeys ``q_0'' + d q_0' = p`` alone, its rate is monotone, and the first crossing is
    found in closed form and refined to rounding
    (:func:`~impactbar.drives._crossing.first_rising_crossing`): none is missed."""

    level: float = 0.0
    direction: int = 1

    def value(self, t, q, v, z):
        return -float(q[0]) - self.level

    def crossing_speed(self, q, v):
        return -float(v[0]) if self.direction >= 0 else float(v[0])

    def first_time(self, d, p, t, q, v):
        from ._crossing import first_rising_crossing

        up = t + first_rising_crossing(d, -float(q[0]), -float(v[0]), -p, self.level) \
            if self.direction >= 0 else math.inf
        down = t + first_rising_crossing(d, float(q[0]), float(v[0]), p, -self.level) \
            if self.direction <= 0 else math.inf
        return min(up, down)


@dataclass(frozen=True)
class RateCrossing(DriveEvent):
    """The gap's rate ``y' = -q_0'`` (the piston's velocity away from the stop) crossing ``level``:
    ``g = -q_0' - level``. Under a constant force the rate is monotone: at most one crossing, in
    closed form (:func:`~impactbar.drives._crossing.first_rate_crossing`)."""

    level: float = 0.0

    def value(self, t, q, v, z):
        return -float(v[0]) - self.level

    def first_time(self, d, p, t, q, v):
        from ._crossing import first_rate_crossing

        w0 = -float(v[0])
        dt = first_rate_crossing(d, w0, -p, self.level)
        if self.direction and math.isfinite(dt) and (-p - d * w0) * self.direction <= 0.0:
            return math.inf  # it crosses the other way
        return t + dt


@dataclass(frozen=True)
class TimedEvent(DriveEvent):
    """An event at a scheduled time (a valve's delay after its trigger, the end of a ramp):
    ``g = t - time``, rising."""

    time: float = math.inf
    direction: int = 1

    def value(self, t, q, v, z):
        return t - self.time

    def first_time(self, d, p, t, q, v):
        return max(self.time, t)  # (one due already: at once)


@dataclass(frozen=True)
class SurfaceEvent(DriveEvent):
    """Any event surface ``g(t, q, q', z) = 0`` (``function``, a callable of the time, the modal
    displacements and velocities and the drive's continuous state) crossed in ``direction``; located
    numerically (to the integrator's tolerance on a flight of a drive with state; by bracketing on a
    grid finer than the stiffest mode's period and Brent's method on a closed-form flight)."""

    function: Callable[..., float] | None = None

    def value(self, t, q, v, z):
        return float(self.function(t, q, v, z))


@dataclass(frozen=True)
class FlightSettings:
    """The integrator of the flights of a drive with state (scipy's ``solve_ivp``), chosen by the
    drive (:attr:`Drive.integrator`).

    Attributes
    ----------
    method : str
        A method of ``solve_ivp``: ``"LSODA"`` (default: ODEPACK's, switching between Adams and BDF
        as the problem turns stiff, as an oil column against the piston's inertia does), ``"Radau"``
        or ``"BDF"`` (stiff), ``"DOP853"`` (not stiff, high order).
    rtol, atol : float
        Relative and absolute tolerances (defaults ``1e-10`` and ``1e-12``): the flights and the
        event times are accurate to about these.
    max_step : float
        Largest step (default ``inf``).
    magnus_theta : float or None
        The size of the Magnus steps of a variational flight that takes its fundamental matrix over
        the plain flight's steps (the oil circuit's flexible piston,
        :mod:`impactbar.drives.circuit._magnus`: ``h ||A|| = theta``); ``None`` (default): the
        drive's own (0.5). A coarser one serves a Jacobian that only steers Newton's method.

    Raises
    ------
    ValueError
        ``magnus_theta`` neither ``None`` nor positive and finite.
    """

    method: str = "LSODA"
    rtol: float = 1e-10
    atol: float = 1e-12
    max_step: float = math.inf
    magnus_theta: float | None = None

    def __post_init__(self) -> None:
        t = self.magnus_theta
        if t is not None and not (math.isfinite(t) and t > 0.0):
            raise ValueError(f"magnus_theta must be None or positive and finite; got {t!r}")


# --------------------------------------------------------------------------------------------------
# optional compiled event loop
# --------------------------------------------------------------------------------------------------
class FlightKernel(NamedTuple):
    """What the simulator hands a drive's compiled event loop (:meth:`Drive.compiled_loop`): the
    compiled driver's data for the constant forces :attr:`Drive.levels`.

    Attributes
    ----------
    loads : tuple
        The plain tuples of the :class:`~impactbar.dynamics.kernelview.LoadKernelView` of each level.
    basis : tuple
        The plain tuple of the free-free :class:`~impactbar.dynamics.kernelview.ModalBasisView`.
    R : float
        The impact law's restitution as the kernel applies it (``kernel_restitution``).
    c : numpy.ndarray, shape (N + 1,)
        Weights of the struck end's displacement, ``u(1, t) = c . q``.
    tail : float
        The driver's chatter tolerance.
    rigid : bool
        Whether the rigid bar's flights take the scalar closed forms.
    fast_search : bool
        Whether the driver's specialised impact searches run.
    """

    loads: tuple
    basis: tuple
    R: float
    c: np.ndarray
    tail: float
    rigid: bool
    fast_search: bool


class KernelRun(NamedTuple):
    """What a drive's compiled event loop hands back to the simulator after a call.

    Attributes
    ----------
    status : int
        :attr:`DONE` (``t_end`` reached), :attr:`MAX_IMPACTS` or :attr:`PYTHON` (the next flight is
        the simulator's: a touch without an impact, a start through the stop, ...).
    state : DriveState
        The drive's state where the loop stopped.
    t : float
        Where it stopped; ``q``, ``v`` the modal state there (arrays of the call, overwritten).
    n_impacts : int
        Impacts so far (the run's count).
    impact_times, impact_velocities : numpy.ndarray
        The impacts of this call.
    switch_times, switch_gaps : numpy.ndarray
        The drive's switches of this call and the gap ``-q_0`` at each.
    switch_names : list of str
        The name of the mode entered at each switch (:meth:`Drive.mode_name`).
    pieces : tuple or None
        The flights of this call: ``(starts, ends, codes, q, v)``, ``codes`` the index of the level
        in :attr:`Drive.levels` plus ``len(levels)`` where the rigid piston rests on the stop.
    """

    status: int
    state: DriveState
    t: float
    q: np.ndarray
    v: np.ndarray
    n_impacts: int
    impact_times: np.ndarray
    impact_velocities: np.ndarray
    switch_times: np.ndarray
    switch_gaps: np.ndarray
    switch_names: list
    pieces: tuple | None

    DONE = 0
    MAX_IMPACTS = 1
    PYTHON = 3


# --------------------------------------------------------------------------------------------------
# the drive
# --------------------------------------------------------------------------------------------------
class Drive(NamedParameters, ABC):
    r"""A drive of the piston that is not a function of time: autonomous, with state of its own
    (theory §10). A base class: subclasses declare the force, the events and their maps.

    The solvers (:func:`impactbar.simulate`, :func:`impactbar.find_orbit`,
    :func:`impactbar.continue_orbit`) take a drive wherever they take a load and call only the
    members below; a new drive needs nothing else (``tests/drives/test_new_drive.py`` defines two in
    the test file alone). Subclasses are frozen dataclasses (validated once, hashable, compared by
    value).

    ==================================  ===============================================================
    member                              what it gives
    ==================================  ===============================================================
    ``state_size``                      ``k``, size of the continuous state ``z`` (0: a force constant
                                        between events)
    ``parameters``                      names of the fields :func:`~impactbar.continue_orbit` may follow
    ``parameter_ranges``                optional: their ranges and descriptions (the records of
                                        :meth:`parameter_table`, :mod:`impactbar.parameters`)
    :meth:`with_`                       a copy with new parameter values (validated again)
    :meth:`start`                       the state at the start of a run, from the bar's
    :meth:`force`                       ``p`` on the piston, from the state (and the bar's, ``k > 0``)
    :meth:`rate`                        ``z'`` between events (``k > 0``)
    :meth:`events`                      the events that can end a flight in a mode
    :meth:`jump`                        the state after an event
    :meth:`impact`                      the state after an impact
    :meth:`mode_name`                   a mode's name, logged at each switch
    ``integrator``                      ``solve_ivp``'s method and tolerances for ``z``
    ``levels``, :meth:`compiled_loop`   optional: a compiled event loop
    :meth:`orbit_problem`               optional: a periodic-orbit problem of the drive's own
    ==================================  ===============================================================

    Attributes
    ----------
    family : str
        ``"drive"``: the forcing family, by which each entry point chooses its solver once
        (``impactbar._shared.forcing``).
    state_size : int
        ``k``, the number of continuous state variables ``z`` (0 for a force that is constant between
        events, whose flights are then closed forms).
    state_names : tuple of str
        Names of the ``k`` variables (logged with the run's drive state).
    integrator : FlightSettings
        The integrator of a drive with state (method and tolerances of ``solve_ivp``).
    parameters : tuple of str
        The fields :func:`impactbar.continue_orbit` can follow (each a float).
    levels : tuple of float or None
        For a drive with a compiled event loop, the constant forces it takes (the valve:
        ``(+stroke, -ret)``); ``None`` otherwise.

    The example below is a force of constant size pushing the piston onto the stop (no event, no
    state): the bounces of a rigid piston dropped from the gap :math:`y_0` arrive at
    :math:`v_1 = \sqrt{2 p y_0}`, then :math:`R v_1`, :math:`R^2 v_1` (eq. 10, energy).

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> from impactbar import BarModel, Drive, DriveState, InitialState, simulate
    >>> import numpy as np
    >>> @dataclass(frozen=True)
    ... class Push(Drive):
    ...     p: float
    ...     parameters = ("p",)
    ...     def start(self, model, q, v): return DriveState(0, np.zeros(0))
    ...     def force(self, mode, z, q, v): return self.p
    ...     def events(self, mode): return ()
    ...     def jump(self, mode, z, event, t, q, v): return DriveState(mode, z)
    ...     def impact(self, mode, z, t, q, v): return DriveState(mode, z)
    >>> run = simulate(BarModel(s=10, d=0, R=0.5, n_modes=0), Push(2.0), InitialState.rigid(-1.0, 0.0),
    ...                5.0, max_impacts=3)
    >>> [round(float(v), 12) for v in run.impact_velocities]
    [2.0, 1.0, 0.5]
    """

    #: The members a drive must implement (abstract here): with them alone it runs in
    #: :func:`~impactbar.simulate` and :func:`~impactbar.find_orbit` (``tests/drives/test_new_drive.py``).
    REQUIRED_HOOKS: ClassVar[tuple[str, ...]] = ("start", "force", "events", "jump", "impact")
    #: Every other member the solvers call: declarations and hooks with a default (``rate`` is needed
    #: with ``state_size > 0``, ``end_flight`` for a drive with state under a law whose contact takes
    #: time).
    OPTIONAL_HOOKS: ClassVar[tuple[str, ...]] = (
        "family", "kind", "integrator", "state_size", "state_names", "parameters", "parameter_ranges",
        "n_quadratures", "piston_work_quadrature", "variational", "variational_state_settings", "with_",
        "parameter_table", "with_parameter", "with_parameters",
        "mode_name", "rate", "quadratures", "piecewise_constant", "levels",
        "compiled_loop", "flight", "end_flight", "border_tests", "orbit_problem")

    family: ClassVar[str] = "drive"
    #: the drive's name in :data:`DRIVES` (a sweep spec's ``[drive] kind``, :func:`register_drive`)
    kind: ClassVar[str] = ""
    integrator: ClassVar[FlightSettings] = FlightSettings()
    state_size: ClassVar[int] = 0
    state_names: ClassVar[tuple[str, ...]] = ()
    parameters: ClassVar[tuple[str, ...]] = ()
    # (their records, changed by with_parameter: NamedParameters, the parameter protocol)

    # -- parameters -------------------------------------------------------------------------------
    def with_(self, **changes) -> Drive:
        """A copy with the given parameters changed (validated again by the constructor).

        Raises
        ------
        ValueError
            For a name not in :attr:`parameters` (named) or a value the constructor refuses.
        """
        bad = sorted(set(changes) - set(self.parameters))
        if bad:
            raise ValueError(f"parameter must be one of {self.parameters} for a {type(self).__name__}; "
                             f"got {bad[0]!r}")
        return dataclasses.replace(self, **changes)

    # -- state ------------------------------------------------------------------------------------
    @abstractmethod
    def start(self, model, q: np.ndarray, v: np.ndarray) -> DriveState:
        """The drive's state at the start of a run from the bar's modal state ``(q, q')``."""

    def mode_name(self, mode) -> str:
        """The name of a mode, logged at each switch (``SwitchedTrajectory.switch_kinds``)."""
        return str(mode)

    # -- between events ---------------------------------------------------------------------------
    @abstractmethod
    def force(self, mode, z: np.ndarray, q: np.ndarray, v: np.ndarray) -> float:
        """The force ``p`` on the piston at ``x = 0`` (dimensionless, eq. 2) in ``mode`` with the
        continuous state ``z`` and the bar's modal state ``(q, q')``. With ``state_size == 0`` it
        depends on the mode alone (constant between events)."""

    def rate(self, mode, z: np.ndarray, q: np.ndarray, v: np.ndarray, model=None) -> np.ndarray:
        r"""``z'``, the rate of the continuous state between events, shape ``(state_size,)``.
        ``model`` (a :class:`~impactbar.BarModel`) is passed only for a stepped piston, whose driven
        end moves as ``model.drive_weights @ q`` (the uniform bar's :math:`q_0 + 2 \sum_n q_n` otherwise;
        a drive written without the argument serves uniform bars)."""
        return np.zeros(0)

    #: The number of quadratures the drive keeps of its own along a run (the oil circuit's energy
    #: account: 8), whose integrands :meth:`quadratures` gives; 0: none.
    n_quadratures: ClassVar[int] = 0
    #: Which of the drive's quadratures (an index into :meth:`quadratures`) is its work on the piston,
    #: ``int p u_t(0, t) dt`` (the oil circuit's: its layout's ``energy["piston"]``); ``None``: none
    #: (the solvers then integrate the force against the driven end's velocity). The pieces of a run
    #: give it over their span as ``piston_work()``; no solver reads a quadrature by its index.
    piston_work_quadrature: ClassVar[int | None] = None

    def quadratures(self, mode, z: np.ndarray, q: np.ndarray, v: np.ndarray, model=None) -> np.ndarray:
        """The integrands of the drive's own quadratures, shape ``(n_quadratures,)`` (the oil circuit's
        energy terms), for the rigid piston resting on the stop; ``model`` as in :meth:`rate`."""
        return np.zeros(0)

    @property
    def piecewise_constant(self) -> bool:
        """Whether the force is constant between events (no continuous state): flights in closed
        form."""
        return self.state_size == 0

    # -- events -----------------------------------------------------------------------------------
    @abstractmethod
    def events(self, mode) -> tuple[DriveEvent, ...]:
        """The events that can end a flight in ``mode``, in the order their maps apply when two
        happen at once."""

    @abstractmethod
    def jump(self, mode, z: np.ndarray, event: DriveEvent, t: float, q: np.ndarray,
             v: np.ndarray) -> DriveState:
        """The drive's state after ``event`` at time ``t`` (the bar's state ``(q, q')`` there is
        continuous across it)."""

    @abstractmethod
    def impact(self, mode, z: np.ndarray, t: float, q: np.ndarray, v: np.ndarray) -> DriveState:
        """The drive's state after an impact, ``(q, q')`` the bar's state just after it (after the
        impact law; under a law whose contact takes time, where the contact ends, at ``t``)."""

    # -- optional numerics of the drive's own ----------------------------------------------------
    @property
    def levels(self) -> tuple[float, ...] | None:
        """The constant forces of a compiled event loop (:meth:`compiled_loop`), ``None`` without
        one."""
        return None

    def compiled_loop(self, model, kernel: FlightKernel):
        """A compiled event loop for a run (``None``: the simulator's loop in Python).

        Returns an object whose ``run(state, t, q, v, t_end, n_impacts, max_impacts)`` follows the
        drive through many flights and returns a :class:`KernelRun`; ``piece(t0, t1, code, q, v)``
        is then asked for nothing (the simulator builds the flights from the codes)."""
        return None

    def flight(self, model, state: DriveState, t: float, q: np.ndarray, v: np.ndarray, t_stop: float,
               settings: FlightSettings | None = None, variational: bool = False):
        """The drive's own integration of one flight (``None``: the generic flight of
        :func:`impactbar.drives.flight.fly`, ``solve_ivp`` over :meth:`force` and :meth:`rate`).

        A drive with stiff state of its own (the oil circuit) integrates its flights with its own
        compiled vector field; it returns a :class:`~impactbar.drives.flight.Flight` ending at the
        first of the arrival at the stop, one of its :meth:`events` or ``t_stop``, and with
        ``variational`` (when :attr:`variational` is true) the flight's fundamental matrix of
        ``(q, q', z)`` in ``Flight.sensitivity``."""
        return None

    #: Whether :meth:`flight` integrates the variational equations when asked (the generic
    #: periodic orbits then take the shooting Jacobian and the multipliers from them).
    variational: ClassVar[bool] = False

    def variational_state_settings(self, model, settings: FlightSettings | None = None):
        """The integrator of a plain flight (:meth:`flight` without ``variational``) whose state is
        that of the variational flight with ``settings``, bit for bit, where the drive has one (a
        variational flight that integrates the plain flight and then takes its fundamental matrix
        over its steps, the oil circuit's flexible piston); ``None`` where the variational flight's
        state is its own (the default).

        Parameters
        ----------
        model : BarModel
        settings : FlightSettings, optional
            The variational flight's integrator (default: the drive's, :attr:`integrator`).

        Returns
        -------
        FlightSettings or None
        """
        return None

    def end_flight(self, model, state: DriveState, breaks, w0: float, incoming, impedance: float,
                   settings: FlightSettings | None = None):
        r"""The drive's state over a stretch of a blow under a law whose contact takes time (theory
        §11, "The coupled blow"), or ``None`` where the drive cannot follow one (a drive with state
        is then refused under such a law; a drive without state needs none: its force is held).

        Over the stretch the law gives the wave ``a(t)`` arriving at the piston's driven end from
        inside it, and the driven end answers the drive's force ``p`` as a semi-infinite bar of
        impedance ``Z``: :math:`u_t(0, t) = a(t) + p/Z`, ``w = -u(0, t)``.

        Parameters
        ----------
        model : BarModel
        state : DriveState
            At ``breaks[0]``.
        breaks : numpy.ndarray, shape (n + 1,)
            Increasing times (model units); ``a`` is constant or smooth between them.
        w0 : float
            ``w`` at ``breaks[0]`` (bar lengths, from the stop where it was at impact).
        incoming : sequence, length n
            ``a`` on each interval: a float, or a callable of the time.
        impedance : float
            ``Z`` (model units: ``s`` for a uniform piston).
        settings : FlightSettings, optional

        Returns
        -------
        object or None
            With ``state`` (the :class:`DriveState` at ``breaks[-1]``), ``w``, ``impulses`` (``int p
            dt`` over each interval, shape ``(n,)``), ``pieces`` (with ``drive_state(t)``,
            ``force(t)``, ``energies()``, ``piston_work()``, the drive's work on the piston over the
            piece, and ``piston_work_at(t)``, that work to the time ``t`` in it) and ``events``
            (``(t, event, mode after)``): the oil circuit's ``EndFlight``
            (``impactbar.drives.circuit.endflight``).
        """
        return None

    def border_tests(self, pieces) -> dict:
        """Test functions of the drive's own border collisions over one period of an orbit
        (``{surface: value}``, each changing sign where the drive's state touches that switching
        surface during the period: the return map changes its formula there); ``pieces`` are the
        period's flights as the drive's :meth:`flight` gives them. The continuation of switched
        orbits locates each change of sign as a ``"border-collision"`` event. Default: none."""
        return {}

    def orbit_problem(self, model, impacts: int,
                      constant_load: Callable[[float], Any]) -> OrbitProblem | None:
        """The drive's own periodic-orbit problem (closed-form flights, exact Jacobian), or ``None``
        for the generic shooting problem of :mod:`impactbar.orbits.switched`. ``constant_load(p)``
        gives the load of a constant force ``p`` (for a contact law's map)."""
        return None


#: The table of drives by :attr:`~Drive.kind`, as :data:`impactbar.loads.LOADS` is of the loads: a
#: sweep spec's ``[drive] kind`` names one, its other keys the constructor's (or the factory's)
#: arguments. A value is a drive class or a function returning a drive (:func:`register_drive`).
DRIVES: dict[str, Callable[..., Drive]] = {}


def register_drive(cls: type[Drive] | Callable[..., Drive], *, kind: str | None = None):
    """Enter a drive class in the table :data:`DRIVES` by its :attr:`~Drive.kind`, so that a sweep
    spec's ``[drive] kind`` knows it (usable as a class decorator); or, with ``kind`` given, a
    factory: a function whose keyword arguments are the table's keys and that returns a drive (a drive
    whose constructor takes objects rather than a table's numbers, such as
    :class:`~impactbar.drives.circuit.HydraulicCircuitDrive` with its ``extra_parts``). An axis of
    the sweep then takes any of the built drive's :attr:`~Drive.parameters` (changed by its
    ``with_``), not only the factory's arguments.

    Parameters
    ----------
    cls : type or callable
        A subclass of :class:`Drive` with a non-empty ``kind`` (``kind`` not given); or a function,
        not a class, returning a :class:`Drive` (``kind`` given).
    kind : str, optional
        The factory's name in :data:`DRIVES`; ``None`` (default): a class, entered by its own
        ``kind``.

    Returns
    -------
    type or callable
        ``cls``, unchanged (a decorator returns it).

    Raises
    ------
    ValueError
        For a class that is not a drive, without a ``kind``, or whose ``kind`` another class holds;
        with ``kind`` given, for a ``kind`` that is not a non-empty string or that another drive or
        factory holds, or a ``cls`` that is a class or not callable.

    Examples
    --------
    >>> from impactbar.drives import DRIVES, PositionSwitchedDrive, register_drive
    >>> register_drive(PositionSwitchedDrive) is PositionSwitchedDrive  # already there
    True
    >>> def valve(x1):  # a factory: the valve at equal forces, its switching gap an argument
    ...     return PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=x1)
    >>> register_drive(valve, kind="equal-valve") is valve
    True
    >>> DRIVES.pop("equal-valve") is valve
    True
    """
    if kind is None:
        return register(DRIVES, cls, Drive, "kind", "drive")
    if not isinstance(kind, str) or not kind:
        raise ValueError(f"kind must be a non-empty string (the factory's name in DRIVES); got {kind!r}")
    if isinstance(cls, type) or not callable(cls):
        raise ValueError(f"cls must be a function returning a Drive where kind is given (a drive class "
                         f"registers by its own kind); got {cls!r}")
    held = DRIVES.get(kind)
    if held is not None and held is not cls:
        raise ValueError(f"kind {kind!r} is already the drive {getattr(held, '__name__', repr(held))}; "
                         "choose another kind")
    DRIVES[kind] = cls
    return cls
