"""The contact-law interface: everything that differs between impact laws (theory §4, §4b, §4d).

A law is a frozen, hashable object; :class:`~impactbar.BarModel` holds one (``BarModel(impact=...)``
takes its name or the object) and every solver asks ``model.law`` instead of comparing names. The
laws sit below the solvers (the layer contract in ``pyproject.toml``): a law returns plain data,
numbers, arrays, its own records (:class:`OrbitState`, a blow's record), and the solvers build their
results from them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple, Protocol

import numpy as np

from .._shared.parameters import Parameter

__all__ = ["ContactLaw", "LawNotSupported", "OrbitState", "DrivenContact", "BarModelLike"]


class BarModelLike(Protocol):
    """The bar model as a law's numerics read it: what their annotations name, since the laws sit
    below :class:`~impactbar.BarModel` (which holds one) and never import it. A ``BarModel`` is one.

    Attributes
    ----------
    s, d, R : float
        The bar's slenderness, damping and restitution (paper eqs. 2, 10).
    n_modes : int
        ``N``, the number of flexible modes.
    frequencies : numpy.ndarray, shape (N + 1,)
        The modes' circular frequencies (0 for the rigid mode).
    end_weights : numpy.ndarray, shape (N + 1,)
        ``c``, the struck end's displacement ``u(1, t) = c . q``.
    """

    s: float
    d: float
    R: float
    n_modes: int

    @property
    def frequencies(self) -> np.ndarray: ...

    @property
    def end_weights(self) -> np.ndarray: ...


class LawNotSupported(ValueError, NotImplementedError):
    """A computation asked of an impact law that does not provide it: a ``ValueError`` for the user
    (the model's ``impact`` does not allow it), a ``NotImplementedError`` for whoever writes the law."""


@dataclass(frozen=True, eq=False)
class OrbitState:
    """What a law computes of its one-impact orbit at a root of its phase equation
    (:meth:`ContactLaw.orbit_state`); the orbit solver decides the orbit's admissibility from it
    (theory §5) and builds the :class:`~impactbar.PeriodicOrbit`.

    Attributes
    ----------
    state_after_impact : numpy.ndarray, shape (2 N + 2,)
        Modal state ``(q_0..q_N, q_0'..q_N')`` where the flight starts: at load time ``phase +
        window(model)`` (the impact's end), the end on the stop (or the advanced rod end).
    state_before_impact : numpy.ndarray, shape (2 N + 2,)
        Modal state at the arrival (load time ``phase``, one period after the impact).
    multipliers : numpy.ndarray of complex, shape (2 N + 2,)
        Exact Floquet multipliers, sorted by decreasing modulus (``inf`` at exact grazing).
    impact : object, optional
        The impact's record (for example :class:`~impactbar.WaveImpact`), ``None`` for an
        instantaneous impact or an arrival that does not move into the stop.
    separates : bool
        Contact is lost inside the law's window (theory §4b): the orbit is not admissible as a held
        contact.
    flow : callable, optional
        The flight's flow from ``state_after_impact`` (the load's own exact flow), where the law built it:
        the admissibility search reuses it.
    """

    state_after_impact: np.ndarray
    state_before_impact: np.ndarray
    multipliers: np.ndarray
    impact: Any = None
    separates: bool = False
    flow: Any = None


class DrivenContact(NamedTuple):
    """A contact step solved together with a drive that has state of its own
    (:meth:`ContactLaw.driven_contact`, theory §11, "The coupled blow").

    Attributes
    ----------
    q_after, v_after : numpy.ndarray, shape (N + 1,)
        Modal state where the flight resumes (positions from the stop where it is then), as
        :meth:`ContactLaw.contact` returns it.
    t_release : float
        Where the flight resumes.
    record
        The law's record of the blow (:class:`~impactbar.WaveImpact`,
        :class:`~impactbar.laws.rodrock.contact.RockContact`), solved with the drive's force as it
        evolved during the blow.
    drive_state : DriveState
        The drive's state at ``t_release``.
    pieces : list
        The drive's pieces over the blow (their histories and energy quadratures,
        ``impactbar.drives.circuit.endflight.EndPiece``).
    events : list
        The drive's events inside the blow, ``(t, event, mode after)``.
    drive_work : float
        The drive's work on the piston over the blow, ``int p u_t(0, t) dt`` along its integration;
        the law's record books the work of the force as its blow takes it (the lattice's step
        averages), and the difference, ``>= 0`` on the lattice, is energy its grid drops.
    gaps : numpy.ndarray, shape (2, P)
        Times and the piston's rigid coordinate ``-q_0`` (from the stop where it was at impact)
        during the blow: where the drive's position switches would be crossed.
    """

    q_after: np.ndarray
    v_after: np.ndarray
    t_release: float
    record: Any
    drive_state: Any
    pieces: list
    events: list
    drive_work: float
    gaps: np.ndarray


@dataclass(frozen=True)
class ContactLaw:
    """Base class of the impact laws, in the style of scipy's ``OdeSolver``: a subclass sets
    :attr:`name` and implements the methods below; :data:`impactbar.laws.LAWS` maps names to
    classes.

    Attributes
    ----------
    name : str
        The law's name in :data:`~impactbar.laws.LAWS` and in ``BarModel.impact``.
    instantaneous : bool
        The law's own declaration, read inside the laws only: the impact takes no time and is the
        velocity map that :meth:`kernel_restitution` gives, applied by the compiled free-flight
        kernel (with chatter and sustained contact handled by the simulator). The defaults of
        :meth:`restitution_in_kernel` and :meth:`has_blow_records` follow from it; the solvers ask
        those (and :meth:`window` for the impact's duration), never this flag.
    rigid_closed_forms : bool
        The rigid bar's closed forms (:mod:`impactbar.orbits.rigid`, eq. 14 with eq. 10) give this
        law's orbits.
    supports_schur : bool
        The paper's Schur criterion (eqs. 27-31) and eq. 14's charts (existence edges) belong to
        this law.
    open_ended : bool
        The contact step may last until the run's end (a sustained contact): the simulator passes
        its ``t_end`` to :meth:`contact` as a keyword.
    flight_starts_on_stop : bool
        Every flight starts with the end on the stop (``c . q = 0`` after :meth:`impact_map`), so
        that periodic orbits leave ``q_0`` out of their unknowns; ``False`` for a law whose piston
        may leave the contact step off the stop (the rod-rock law), whose orbits keep it.
    uses_restitution : bool
        The model's restitution ``R`` enters the contact (``False`` for the rod-rock law, whose rod
        and rock replace it).
    has_phase_equation : bool
        :func:`~impactbar.periodic_orbits` finds the one-impact orbits from the law's phase
        equation (:meth:`phase_roots`, :meth:`phase_families`, :meth:`orbit_state`). ``False``: the
        law has none (its blow is a numerical map), and ``periodic_orbits`` finds them by Newton's
        method from guesses (:func:`impactbar.orbits.periodic_orbits_by_newton`: the orbits of
        :meth:`paper_equivalent` and a settled simulation), which needs :meth:`window`,
        :meth:`impact_map` and :meth:`contact` only.
    stepped_piston : bool
        The law acts on the modal state alone (no characteristics on a uniform piston), so that a
        stepped piston's modes (``BarModel(..., piston=...)``, theory §12) serve it; ``False``
        (the default) refuses a stepped piston.
    parameters : tuple of str
        The law's own continuation parameters (:func:`~impactbar.continue_orbit`, the sweeps' axes),
        read by :meth:`parameter_value` and changed by :meth:`with_parameter`; none by default.
    """

    #: The hooks a law must implement (the base raises :class:`LawNotSupported`): with them alone it
    #: runs in :func:`~impactbar.simulate`, :func:`~impactbar.find_orbit`, the continuation and the
    #: sweeps (``tests/laws/test_custom_law.py``'s ``VelocityRestitution``).
    REQUIRED_HOOKS: ClassVar[tuple[str, ...]] = ("window", "impact_map", "contact")
    #: Every other member the solvers call: declarations and hooks with a default, or whose absence
    #: (:class:`LawNotSupported`) refuses only the computation that needs them (the phase equation's,
    #: the charts', the coupled blow's).
    OPTIONAL_HOOKS: ClassVar[tuple[str, ...]] = (
        "name", "instantaneous", "rigid_closed_forms", "supports_schur", "open_ended",
        "flight_starts_on_stop", "uses_restitution", "has_phase_equation", "stepped_piston", "parameters",
        "restitution_in_kernel", "kernel_restitution", "has_blow_records", "blow", "impact_state",
        "paper_equivalent", "check_model", "coarse_model", "phase_roots", "phase_families", "orbit_state",
        "multipliers", "existence_edge", "driven_contact", "parameter_table", "has_parameter",
        "parameter_value", "with_parameter", "with_parameters", "check_continuable")

    name: ClassVar[str] = ""
    instantaneous: ClassVar[bool] = True
    rigid_closed_forms: ClassVar[bool] = False
    supports_schur: ClassVar[bool] = False
    open_ended: ClassVar[bool] = False
    flight_starts_on_stop: ClassVar[bool] = True
    uses_restitution: ClassVar[bool] = True
    has_phase_equation: ClassVar[bool] = True
    stepped_piston: ClassVar[bool] = False
    parameters: ClassVar[tuple[str, ...]] = ()

    def paper_equivalent(self, model):
        """The same bar under the paper's law (eq. 10) with the restitution this law's contact
        gives: the model's ``R`` (clipped to ``0.95``), unless a law says otherwise. Newton's
        method for this law's orbits starts from that bar's orbits (theory §10).

        Parameters
        ----------
        model : BarModel
            A bar under this law.

        Returns
        -------
        BarModel
            ``model`` with ``impact="paper"`` and the equivalent ``R``.
        """
        return model.with_(impact="paper", R=min(model.R, 0.95))

    def check_model(self, model) -> None:
        """Refuse a model this law cannot take (called by :class:`~impactbar.BarModel` once its
        piston is set); every model is accepted by default.

        Parameters
        ----------
        model : BarModel

        Raises
        ------
        ValueError
            Naming the parameter out of the law's range.
        """

    def coarse_model(self, model):
        """A cheaper model of the same motion, whose orbits Newton's method reaches from farther
        guesses, to start this law's Newton from (:func:`~impactbar.find_orbit`), or ``None`` (the
        default): e.g. the rod-rock law's blows on the lattice for its exact blows.

        Parameters
        ----------
        model : BarModel
            The model to coarsen (under this law).

        Returns
        -------
        BarModel or None
        """
        return None

    def window(self, model) -> float:
        """Duration of one impact (dimensionless time): 0 for an instantaneous law.

        Parameters
        ----------
        model : BarModel
            The bar that strikes (its wave speed ``s`` sets a window's length).

        Returns
        -------
        float
            ``>= 0``; each flight of a periodic orbit starts this long after its impact.
        """
        raise LawNotSupported(self._missing("window"))

    def impact_state(self, model, load, t: float, y_minus):
        """The state where the next flight starts, ``y_plus`` of :meth:`impact_map` without its
        derivatives (a residual of the orbit solver; a law whose Jacobian costs more than its map,
        such as the rod-rock law's finite differences, gives it alone).

        Parameters
        ----------
        model, load, t, y_minus
            As :meth:`impact_map`.

        Returns
        -------
        numpy.ndarray, shape (2 N + 2,)
        """
        return self.impact_map(model, load, t, y_minus)[0]

    def impact_map(self, model, load, t: float, y_minus):
        """State where the next flight starts from the state at arrival, with its derivatives
        (the seam of the multi-segment orbit solver, theory §7).

        Parameters
        ----------
        model : BarModel
        load : Load
        t : float
            Load time of the arrival.
        y_minus : numpy.ndarray, shape (2 N + 2,)
            Modal state ``(q_0..q_N, q_0'..q_N')`` at arrival (the end on the stop).

        Returns
        -------
        y_plus : numpy.ndarray, shape (2 N + 2,)
            State at load time ``t + window(model)``, where the next flight starts, with ``q_0`` set
            so that the end touches the stop.
        jac_y : numpy.ndarray, shape (2 N + 2, 2 N + 2)
            ``d y_plus / d y_minus``.
        jac_t : numpy.ndarray, shape (2 N + 2,)
            ``d y_plus / d t`` at fixed ``y_minus``.
        """
        raise LawNotSupported(self._missing("impact_map"))

    def phase_roots(self, model, load) -> list[tuple[float, int]]:
        """Roots of the law's one-impact phase equation in ``[0, 2 pi)`` (for a law with
        :attr:`has_phase_equation`).

        Parameters
        ----------
        model : BarModel
        load : Load

        Returns
        -------
        list of (float, int)
            ``(phase, multiplicity)`` sorted by phase; ``phase`` is the load time of the arrival.
        """
        raise LawNotSupported(self._missing("phase_roots"))

    def phase_families(self, model, load) -> list[tuple[float, float]]:
        """Intervals of phases on which the phase equation holds identically (a continuum of
        one-impact orbits, which :meth:`phase_roots` leaves out); none by default.

        Returns
        -------
        list of (float, float)
            ``(start, end)`` phases (rad), ``end > start``.
        """
        return []

    def orbit_state(self, model, load, phase: float) -> OrbitState:
        """The one-impact orbit whose arrival is at this root of :meth:`phase_roots`: its states at
        the impact's end and at the arrival, its multipliers, the impact's record. The orbit solver
        decides admissibility from them (theory §5) and builds the
        :class:`~impactbar.PeriodicOrbit`.

        Parameters
        ----------
        model : BarModel
        load : Load
        phase : float
            Load time of the arrival (rad), a root of the phase equation.

        Returns
        -------
        OrbitState
        """
        raise LawNotSupported(self._missing("orbit_state"))

    def multipliers(self, model, load, phase: float):
        """Exact Floquet multipliers of the one-impact orbit with this phase (theory §7),
        without the admissibility check (:func:`~impactbar.orbits.orbit_multipliers`).

        Parameters
        ----------
        model : BarModel
        load : Load
        phase : float
            A root of :meth:`phase_roots` (rad).

        Returns
        -------
        numpy.ndarray of complex, shape (2 N + 2,)
            Sorted by decreasing modulus.
        """
        raise LawNotSupported(self._missing("multipliers"))

    def existence_edge(self, model, k: int = 1) -> float:
        """Largest load factor ``k p0 / pk`` of the pneumatic load (eq. 33) with one-impact orbits
        (the stability charts, :mod:`impactbar.orbits.charts`).

        Parameters
        ----------
        model : BarModel
        k : int
            Order of the harmonic, ``>= 1``.

        Returns
        -------
        float
            ``inf`` when orbits exist at every load factor, ``nan`` when none exist.
        """
        raise LawNotSupported(self._missing("existence_edge"))

    def blow(self, model, load, t: float, y_minus):
        """Per-blow output of a periodic orbit's impact (the ``contacts`` of
        :func:`~impactbar.find_orbit`'s orbits).

        Parameters
        ----------
        model, load : BarModel, Load
            The orbit's bar and load.
        t : float
            Load time of the arrival.
        y_minus : numpy.ndarray, shape (2 N + 2,)
            Modal state at the arrival.

        Returns
        -------
        object or None
            The blow's record (as :meth:`contact` returns it), or ``None`` where the law has none
            to add (an instantaneous impact on an orbit).
        """
        return None

    def kernel_restitution(self, model) -> float:
        """Factor ``r`` of the compiled free-flight kernel's velocity map ``v -> -r v`` at an
        arrival (the simulator's flight kernel, theory §8).

        Parameters
        ----------
        model : BarModel

        Returns
        -------
        float
            ``R`` for an instantaneous law that the kernel applies itself (eq. 10); ``-1``
            (``v -> v``, nothing applied) for a law the simulator resolves by :meth:`contact`.
        """
        return model.R if self.restitution_in_kernel(model) else -1.0

    def restitution_in_kernel(self, model) -> bool:
        """Whether the impact is the velocity map ``v -> -r v`` at the arrival's instant, ``r =``
        :meth:`kernel_restitution`, which the solvers apply themselves: the compiled flight kernel
        (chatter and sustained contact the simulator's), the drives' loops, the closed forms of eq. 10
        of the position-switched orbits. ``False``: they call the law's :meth:`contact`,
        :meth:`impact_map` and :meth:`driven_contact` at each arrival instead (a contact that takes
        time, or one of no duration whose map the kernel cannot apply). By default the law's
        declaration :attr:`instantaneous`.

        Parameters
        ----------
        model : BarModel

        Returns
        -------
        bool

        Examples
        --------
        >>> from impactbar import BarModel
        >>> paper = BarModel(s=10.0, d=0.0, R=0.5, n_modes=0)
        >>> wave = paper.with_(impact="wave")
        >>> paper.law.restitution_in_kernel(paper), wave.law.restitution_in_kernel(wave)
        (True, False)
        """
        return self.instantaneous

    def has_blow_records(self, model) -> bool:
        """Whether the law's contact step leaves a blow with a record of its own (a force history,
        the rod's energy, the contact's separations: :class:`~impactbar.WaveImpact`, a rock's
        blow), which a periodic orbit lists as its ``contacts`` (:meth:`blow`), checks for
        separation, and the SI results read per impact. ``False``: an impact with nothing to add
        (eq. 10's :class:`~impactbar.laws.InstantImpact`). By default ``not`` :attr:`instantaneous`.

        Parameters
        ----------
        model : BarModel
            The bar under this law.

        Returns
        -------
        bool
            ``True`` where :meth:`blow` and :meth:`contact` give such a record.

        Examples
        --------
        >>> from impactbar import BarModel
        >>> models = [BarModel(s=10.0, d=0.0, R=0.5, n_modes=0, impact=name) for name in ("paper", "wave")]
        >>> [m.law.has_blow_records(m) for m in models]
        [False, True]
        """
        return not self.instantaneous

    def contact(self, model, load, t: float, q_minus, v_minus, *, kernel=None):
        """The simulator's contact step: from the arrival at the stop to the start of the next flight.

        Parameters
        ----------
        model : BarModel
        load : Load
        t : float
            Load time of the arrival at the stop.
        q_minus, v_minus : numpy.ndarray, shape (N + 1,)
            Free-free modal state at arrival, the end exactly on the stop (``c . q = 0``).
        kernel : object, optional
            The simulator's compiled view of the model and load (``impactbar.simulation``'s
            ``_Core``), for a law with a compiled contact solver; a law may ignore it.
        t_end : float, optional
            Only for a law with :attr:`open_ended`: the run's end, where a contact that lasts so
            long stops (``t_release = t_end``).

        Returns
        -------
        q_after, v_after : numpy.ndarray, shape (N + 1,)
            Modal state where the flight resumes, positions from the (possibly advanced) stop.
        t_release : float
            Load time where the flight resumes, ``>= t``.
        record
            The blow's output: an object with ``t0``, ``duration`` (``t_release - t``),
            ``q_after``, ``v_after``, ``state_at(tau) -> (q, v)`` for ``0 <= tau <= duration``,
            ``account(tau) -> (drive_work, energy_out, field_energy)`` (the energy balance up to
            ``tau``: ``energy_before + drive_work = field_energy + energy_out``, plus
            ``damping(tau)`` where the record has it: a sustained contact) and ``resolve()``
            (the full record, for one solved lazily): :class:`~impactbar.WaveImpact`,
            :class:`~impactbar.laws.InstantImpact`.
        """
        raise LawNotSupported(self._missing("contact"))

    def driven_contact(self, model, drive, state, t: float, q_minus, v_minus, *,
                       settings=None) -> DrivenContact:
        """The contact step with a drive that has state of its own, solved together with it (theory
        §11, "The coupled blow"): the drive's force is not held during the blow but follows its
        state, which the piston's driven end moves (:meth:`~impactbar.Drive.end_flight`). Not
        provided by default (an instantaneous law needs none: its impact takes no time).

        Parameters
        ----------
        model : BarModel
        drive : Drive
            A drive with state that provides :meth:`~impactbar.Drive.end_flight`.
        state : DriveState
            The drive's state at the arrival, after its map at the impact.
        t : float
            Time of the arrival.
        q_minus, v_minus : numpy.ndarray, shape (N + 1,)
            Modal state at arrival, the end on the stop.
        settings : FlightSettings, optional
            The drive's integrator.

        Returns
        -------
        DrivenContact

        Raises
        ------
        ValueError
            Where the law or the drive cannot (:class:`LawNotSupported`), or the blow cannot be
            solved (the message says why).
        """
        raise LawNotSupported(self._missing("driven_contact"))

    def parameter_table(self, model=None) -> tuple[Parameter, ...]:
        """The law's own parameters as records (:func:`impactbar.parameters.parameters` lists them
        beside the bar's): by default one unbounded, continuable record for each of
        :attr:`parameters`, with its :meth:`parameter_value`. A law with bounds, units,
        descriptions or a parameter it is not smooth in overrides this, its one declaration.

        Parameters
        ----------
        model : BarModel, optional
            The model under this law.

        Returns
        -------
        tuple of Parameter

        Examples
        --------
        >>> from impactbar.laws import get_law
        >>> get_law("paper").parameter_table()
        ()
        """
        return tuple(Parameter(name, self.parameter_value(name)) for name in self.parameters)

    def has_parameter(self, name: str) -> bool:
        """Whether ``name`` is one of the law's own continuation parameters (:attr:`parameters`).

        Parameters
        ----------
        name : str
            A parameter's name, as a continuation's ``parameter`` names it.

        Returns
        -------
        bool
        """
        return name in self.parameters

    def parameter_value(self, name: str) -> float:
        """The value of one of the law's own continuation parameters.

        Parameters
        ----------
        name : str
            One of :attr:`parameters`.

        Returns
        -------
        float

        Raises
        ------
        ValueError
            For a name that is not one of the law's parameters (the message lists them).
        """
        self._check_parameter(name)
        return float(getattr(self, name))

    def with_parameter(self, name: str, value: float) -> ContactLaw:
        """A copy of the law with one of its own continuation parameters changed (validated again
        by the constructor).

        Parameters
        ----------
        name : str
            One of :attr:`parameters`.
        value : float

        Returns
        -------
        ContactLaw

        Raises
        ------
        ValueError
            For a name that is not one of the law's parameters, or a value the law refuses.
        """
        return self.with_parameters({name: value})

    def with_parameters(self, changes: dict) -> ContactLaw:
        """A copy of the law with several of its own continuation parameters changed at once:
        ``changes`` (dict of name to float) applied together, the result validated once by the
        constructor whatever their order (a ``ValueError`` as :meth:`with_parameter`)."""
        import dataclasses

        for name in changes:
            self._check_parameter(name)
        return dataclasses.replace(self, **changes)

    def check_continuable(self, name: str, model=None) -> None:
        """Refuse a parameter in which the law's impact map is not smooth, so that a branch cannot
        be continued in it (:func:`~impactbar.continue_orbit`): one whose record in
        :meth:`parameter_table` is not ``continuable`` (its ``reason`` given).

        Parameters
        ----------
        name : str
            One of :attr:`parameters`.
        model : BarModel, optional
            The model under this law (a law whose smoothness depends on it).

        Raises
        ------
        ValueError
            Saying why the parameter cannot be continued.
        """
        self._check_parameter(name)
        for p in self.parameter_table(model):
            if p.name == name and not p.continuable:
                raise ValueError(f"parameter {name!r} cannot be continued: {p.reason}")

    def _check_parameter(self, name: str) -> None:
        if not self.has_parameter(name):
            raise ValueError(f"parameter {name!r} is not one of the impact law {self.name!r}'s "
                             f"parameters {self.parameters}")

    def _missing(self, method: str) -> str:
        """The message of the :class:`LawNotSupported` raised where a solver needs ``method`` and
        this law does not provide it (the solvers check a hook before any work: ``find_orbit``'s
        check of the law)."""
        return (f"model.impact: the impact law {self.name!r} ({type(self).__name__}) does not provide "
                f"{method}(), so this computation is not available under it; use impact='paper' or "
                f"impact='wave'")

    def __str__(self) -> str:
        return self.name

