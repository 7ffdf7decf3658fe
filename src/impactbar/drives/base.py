r"""The drive interface: what the solvers ask of a drive that is not a function of time (theory §10).

A *drive* takes the place of a periodic :class:`~impactbar.Load` at the driven end ``x = 0``, but
its force is not a function of time: it is a function of the drive's own state, which changes with
the bar's motion. The bar and the drive together are autonomous (the blow frequency is an output).
Each drive is a hybrid system (a *switched* system) with

- a discrete ``mode`` (any hashable value: the valve's position, pending delayed switches, ...) and a
  continuous state ``z`` of ``traits.state_size`` numbers (empty for a force that is piecewise constant; the
  chamber pressures of an oil circuit), together a :class:`DriveState`;
- between events, the force :meth:`Drive.force` on the piston and the rate :meth:`Drive.rate` of
  ``z``, coupled to the modes of the bar, :math:`q_n'' + d q_n' + (s n \pi)^2 q_n = p` (eq. 6);
- events, :meth:`Drive.events`: crossings of a position or velocity by the piston, scheduled times
  (a valve's delay, a ramp's end) or any surface ``g(t, q, q', z) = 0`` crossed in a direction
  (:class:`DriveEvent`), each with its map :meth:`Drive.jump`, and the map at an impact,
  :meth:`Drive.impact`;
- what its class declares, :attr:`Drive.traits` (a :class:`DriveTraits`: its parameters for
  continuation, its state's size, its integrator), and copies with new parameter values,
  :meth:`Drive.with_`.

The solvers dispatch on this interface, never on a drive's class: :func:`impactbar.simulate`
(:mod:`impactbar.simulation.driven`), :func:`impactbar.find_orbit`
(:mod:`impactbar.orbits.driven`) and :func:`impactbar.continue_orbit`
(:mod:`impactbar.continuation.driven`). A drive without state (``traits.state_size == 0``) has a force
that is constant between events: its flights are the closed-form flights of the modes (eq. 8), run by
the simulator's certified event search, and its events in closed form where they are crossings of
the piston's position or velocity or scheduled times (:meth:`DriveEvent.first_time`). A drive with
state is integrated with scipy's ``solve_ivp`` (stiff methods) and its events located to the
integrator's tolerance. A drive may add numerics of its own where they pay, as abilities
(:attr:`Drive.abilities`, :mod:`impactbar.drives.abilities`, each asked once where a solver
dispatches on it): a compiled event loop, as the valve of :class:`~impactbar.PositionSwitchedDrive`
has, its own flights, as the oil circuit's, or a periodic-orbit problem of its own (the valve's
closed-form problem sits with the orbit solvers, :data:`impactbar.orbits.driven.ORBIT_PROBLEMS`);
otherwise the generic paths run.

The design follows three well-kept codes: the event functions of scipy's ``solve_ivp`` (a scalar
function of the state whose zero is crossed in a ``direction``, +1 rising, -1 falling, 0 either, and
that ends the step: :class:`DriveEvent`), Siconos' event-driven simulation of nonsmooth dynamical
systems (a vector field between events, ``computeF``, and a map at each event, its non-smooth law:
:meth:`Drive.rate` and :meth:`Drive.jump`; scheduled events beside state events), and Hopsan's
components (parameters registered by name, read by the solver and copied with new values:
:attr:`Drive.traits`, :meth:`Drive.with_`). The saltation matrices of the multipliers follow
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
from collections.abc import Callable, Hashable, Mapping
from dataclasses import dataclass
from typing import ClassVar, NamedTuple

import numpy as np

from .._shared.registry import register
from .abilities import NONE, DriveAbilities
from .params import DriveParameters

__all__ = ["Drive", "DriveTraits", "DriveState", "FlightSettings", "DriveEvent", "GapCrossing",
           "RateCrossing", "TimedEvent", "SurfaceEvent", "FlightKernel", "KernelRun"]


class DriveState(NamedTuple):
    """A drive's state: its discrete ``mode`` and its continuous state ``z``.

    Attributes
    ----------
    mode : hashable
        The drive's discrete state (chosen by the drive; the solvers only hand it back).
    z : numpy.ndarray, shape (k,)
        The continuous state, ``k = traits.state_size`` (shape ``(0,)`` for a drive without state).

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
    drive (its ``traits.integrator``, :class:`DriveTraits`).

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
    """What the simulator hands a drive's compiled event loop (its ability
    :class:`~impactbar.drives.abilities.CompiledLoop`): the compiled driver's data for the loop's
    constant forces, ``levels``.

    Attributes
    ----------
    loads : tuple
        The plain tuples of the :class:`~impactbar.dynamics.compiled_views.LoadKernelView` of each level.
    basis : tuple
        The plain tuple of the free-free :class:`~impactbar.dynamics.compiled_views.ModalBasisView`.
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
        in the loop's ``levels`` plus ``len(levels)`` where the rigid piston rests on the stop.
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


@dataclass(frozen=True)
class DriveTraits:
    """What a drive class declares once, in its body (``traits = DriveTraits(...)``): its entry in the
    table of drives, its parameters, its continuous state and the integrator of its flights; read by
    the solvers, the sweeps and the parameter protocol (:attr:`Drive.params`).

    Parameters
    ----------
    kind : str, optional
        Its name in the table :data:`DRIVES` (a sweep spec's ``[drive] kind``,
        :func:`register_drive`); empty (default) for a drive not in the table.
    parameters : tuple of str, optional
        The names of the drive's attributes that :func:`~impactbar.continue_orbit` and the sweeps
        may change (each a float), copies made by :meth:`Drive.with_`.
    parameter_ranges : mapping, optional
        Name -> keyword arguments of :class:`~impactbar.parameters.Parameter` (``low``, ``high``,
        ``low_open``, ``description``, ...), the ranges the parameters' records state; the
        constructor checks them again.
    state_size : int, optional
        ``k``, the size of the continuous state ``z`` (default 0: a force constant between events,
        whose flights are closed forms).
    state_names : tuple of str, optional
        The names of the ``k`` variables (logged with a run's drive state).
    integrator : FlightSettings, optional
        ``solve_ivp``'s method and tolerances for the flights of a drive with state.

    Raises
    ------
    ValueError
        A ``kind`` that is not a string, names that are not strings, a negative ``state_size``, or
        ``state_names`` neither empty nor ``state_size`` of them.

    Examples
    --------
    >>> from impactbar import PositionSwitchedDrive
    >>> traits = PositionSwitchedDrive.traits
    >>> traits.kind, traits.parameters[:3], traits.piecewise_constant
    ('position-switched', ('stroke', 'ret', 'switch_out'), True)
    """

    kind: str = ""
    parameters: tuple[str, ...] = ()
    parameter_ranges: Mapping[str, dict] = dataclasses.field(default_factory=dict)
    state_size: int = 0
    state_names: tuple[str, ...] = ()
    integrator: FlightSettings = FlightSettings()

    def __post_init__(self) -> None:
        if not isinstance(self.kind, str):
            raise ValueError(f"kind must be a string (the drive's name in DRIVES); got {self.kind!r}")
        for name in ("parameters", "state_names"):
            names = getattr(self, name)
            if isinstance(names, str) or not all(isinstance(n, str) for n in names):
                raise ValueError(f"{name} must be a sequence of strings; got {names!r}")
            object.__setattr__(self, name, tuple(names))
        size = self.state_size
        if isinstance(size, bool) or not isinstance(size, (int, np.integer)) or size < 0:
            raise ValueError(f"state_size must be an integer >= 0; got {size!r}")
        if self.state_names and len(self.state_names) != size:
            raise ValueError(f"state_names must name the {size} states (or none); got {self.state_names!r}")

    @property
    def piecewise_constant(self) -> bool:
        """Whether the force is constant between events (no continuous state): flights in closed
        form."""
        return self.state_size == 0


#: What a drive declared in its class body before its traits, params and abilities: a class that
#: declares one of them with no ``traits`` (or ``params``, ``abilities``) of its own is refused, since
#: no solver would read it.
_MOVED = {
    **dict.fromkeys(("kind", "parameters", "parameter_ranges", "state_size", "state_names", "integrator"),
                    "traits"),
    **dict.fromkeys(("parameter_table", "with_parameter", "with_parameters", "_parameter_value"), "params"),
    **dict.fromkeys(("levels", "compiled_loop", "flight", "variational", "variational_state_settings",
                     "n_quadratures", "piston_work_quadrature", "quadratures", "end_flight", "border_tests",
                     "orbit_problem"), "abilities"),
}
_HOMES = {"traits": "traits = DriveTraits(...)", "params": "a params property returning DriveParameters",
          "abilities": "an abilities property returning DriveAbilities"}


# --------------------------------------------------------------------------------------------------
# the drive
# --------------------------------------------------------------------------------------------------
class Drive(ABC):
    r"""A drive of the piston that is not a function of time: autonomous, with state of its own
    (theory §10). A base class: subclasses declare the force, the events and their maps.

    The solvers (:func:`impactbar.simulate`, :func:`impactbar.find_orbit`,
    :func:`impactbar.continue_orbit`) take a drive wherever they take a load and call only the
    members below; a new drive needs nothing else (``tests/drives/test_new_drive.py`` defines some in
    the test file alone). Subclasses are frozen dataclasses (validated once, hashable, compared by
    value).

    ==================================  ===============================================================
    member                              what it gives
    ==================================  ===============================================================
    :meth:`start`                       the state at the start of a run, from the bar's
    :meth:`force`                       ``p`` on the piston, from the state (and the bar's, ``k > 0``)
    :meth:`events`                      the events that can end a flight in a mode
    :meth:`jump`                        the state after an event
    :meth:`impact`                      the state after an impact
    :meth:`rate`                        ``z'`` between events (``k > 0``)
    :meth:`mode_name`                   a mode's name, logged at each switch
    :meth:`with_`                       a copy with new parameter values (validated again)
    :attr:`traits`                      what the class declares (:class:`DriveTraits`): its ``kind``,
                                        ``parameters`` and their ranges, ``state_size`` ``k`` (0: a
                                        force constant between events), ``integrator``
    :attr:`params`                      its parameters' records and copies (the parameter protocol,
                                        :class:`~impactbar.drives.params.DriveParameters`)
    :attr:`abilities`                   optional numerics of its own
                                        (:class:`~impactbar.drives.abilities.DriveAbilities`): a
                                        compiled event loop, its own flights, quadratures, coupled
                                        blows, border tests, a periodic-orbit problem
    :attr:`family`                      ``"drive"``: the forcing family, by which each entry point
                                        chooses its solver once (``impactbar._shared.forcing``)
    ==================================  ===============================================================

    The first five are abstract: with them alone (and ``traits`` for parameters or state) a drive runs
    in every solver. The example below is a force of constant size pushing the piston onto the stop
    (no event, no state): the bounces of a rigid piston dropped from the gap :math:`y_0` arrive at
    :math:`v_1 = \sqrt{2 p y_0}`, then :math:`R v_1`, :math:`R^2 v_1` (eq. 10, energy).

    Raises
    ------
    ValueError
        On defining a subclass that declares in its body a member that now lives in ``traits``,
        ``params`` or ``abilities`` (``state_size``, ``parameters``, ``compiled_loop``, ...) without
        declaring that home.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> from impactbar import BarModel, Drive, DriveState, DriveTraits, InitialState, simulate
    >>> import numpy as np
    >>> @dataclass(frozen=True)
    ... class Push(Drive):
    ...     p: float
    ...     traits = DriveTraits(parameters=("p",))
    ...     def start(self, model, q, v): return DriveState(0, np.zeros(0))
    ...     def force(self, mode, z, q, v): return self.p
    ...     def events(self, mode): return ()
    ...     def jump(self, mode, z, event, t, q, v): return DriveState(mode, z)
    ...     def impact(self, mode, z, t, q, v): return DriveState(mode, z)
    >>> run = simulate(BarModel(s=10, d=0, R=0.5, n_modes=0), Push(2.0), InitialState.rigid(-1.0, 0.0),
    ...                5.0, max_impacts=3)
    >>> [round(float(v), 12) for v in run.impact_velocities]
    [2.0, 1.0, 0.5]
    >>> Push(2.0).with_(p=3.0), Push(2.0).abilities.compiled_loop
    (Push(p=3.0), None)
    """

    #: the forcing family, by which each entry point chooses its solver once (a load's is ``"load"``)
    family: ClassVar[str] = "drive"
    #: what the class declares: its kind, parameters, continuous state and integrator
    traits: ClassVar[DriveTraits] = DriveTraits()

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        for name, home in _MOVED.items():
            if name in vars(cls) and getattr(cls, home) is getattr(Drive, home):
                raise ValueError(f"{cls.__name__}.{name}: a drive declares it in {_HOMES[home]} now "
                                 f"(impactbar.Drive), not as a member of its own")

    @property
    def abilities(self) -> DriveAbilities:
        """What the drive can do beyond its required hooks (:class:`DriveAbilities`): none here."""
        return NONE

    @property
    def params(self) -> DriveParameters:
        """The drive's parameters, their records and copies with some changed, from its
        :attr:`traits` (:class:`~impactbar.drives.params.DriveParameters`)."""
        return DriveParameters(self)

    def with_(self, **changes) -> Drive:
        """A copy with the given parameters changed (validated again by the constructor).

        Raises
        ------
        ValueError
            For a name not in ``traits.parameters`` (named) or a value the constructor refuses.
        """
        names = self.traits.parameters
        bad = sorted(set(changes) - set(names))
        if bad:
            raise ValueError(f"parameter must be one of {names} for a {type(self).__name__}; got {bad[0]!r}")
        return dataclasses.replace(self, **changes)

    # -- state ------------------------------------------------------------------------------------
    @abstractmethod
    def start(self, model, q: np.ndarray, v: np.ndarray) -> DriveState:
        """The drive's state at the start of a run from the bar's modal state ``(q, q')``."""

    def mode_name(self, mode) -> str:
        """The name of a mode, logged at each switch (``DrivenTrajectory.switch_kinds``)."""
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


#: The table of drives by their ``traits.kind``, as :data:`impactbar.loads.LOADS` is of the loads: a
#: sweep spec's ``[drive] kind`` names one, its other keys the constructor's (or the factory's)
#: arguments. A value is a drive class or a function returning a drive (:func:`register_drive`).
DRIVES: dict[str, Callable[..., Drive]] = {}


def register_drive(cls: type[Drive] | Callable[..., Drive], *, kind: str | None = None):
    """Enter a drive class in the table :data:`DRIVES` by its ``traits.kind``, so that a sweep
    spec's ``[drive] kind`` knows it (usable as a class decorator); or, with ``kind`` given, a
    factory: a function whose keyword arguments are the table's keys and that returns a drive (a drive
    whose constructor takes objects rather than a table's numbers, such as
    :class:`~impactbar.drives.circuit.HydraulicCircuitDrive` with its ``extra_parts``). An axis of
    the sweep then takes any of the built drive's ``traits.parameters`` (changed by its
    ``with_``), not only the factory's arguments.

    Parameters
    ----------
    cls : type or callable
        A subclass of :class:`Drive` with a non-empty ``traits.kind`` (``kind`` not given); or a function,
        not a class, returning a :class:`Drive` (``kind`` given).
    kind : str, optional
        The factory's name in :data:`DRIVES`; ``None`` (default): a class, entered by its own
        ``traits.kind``.

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
        return register(DRIVES, cls, Drive, "traits.kind", "drive")
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
