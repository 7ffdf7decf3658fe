"""The contact-law interface: everything that differs between impact laws (theory §4, §4b, §4d).

A law is a frozen, hashable object; :class:`~impactbar.BarModel` holds one (``BarModel(impact=...)``
takes its name or the object) and every solver asks ``model.law`` instead of comparing names. The
base (:class:`ContactLaw`) holds what every solver calls; what only some laws can do is an ability
(:mod:`impactbar.laws.abilities`), looked up by :meth:`ContactLaw.ability`. The laws sit below the
solvers (the layer contract in ``pyproject.toml``): a law returns plain data, numbers, arrays, its
own records (:class:`OrbitState`, a blow's record), and the solvers build their results from them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple, Protocol

import numpy as np

from .._shared.parameters import Parameter

__all__ = ["ContactLaw", "LawTraits", "LawNotSupported", "OrbitState", "DrivenContact", "BarModelLike",
           "not_provided"]


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
    (:meth:`PhaseEquation.orbit_state <impactbar.laws.abilities.PhaseEquation.orbit_state>`); the
    orbit solver decides the orbit's admissibility from it (theory §5) and builds the
    :class:`~impactbar.PeriodicOrbit`.

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
    (:meth:`CoupledBlow.driven_contact <impactbar.laws.abilities.CoupledBlow.driven_contact>`,
    theory §11, "The coupled blow").

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
class LawTraits:
    """What a law declares about its contact, read by the solvers (:attr:`ContactLaw.traits`); each
    field's default is the paper's law's (eq. 10).

    Parameters
    ----------
    restitution_in_kernel : bool
        The impact is the velocity map ``v -> -r v`` at the arrival's instant, ``r =``
        :meth:`kernel_restitution`, which the solvers apply themselves: the compiled flight kernel
        (chatter and sustained contact the simulator's), the drives' loops, the closed forms of
        eq. 10 of the valve drive's orbits. ``False``: they call the law's
        :meth:`~ContactLaw.contact` and :meth:`~ContactLaw.impact_map` (and its
        :class:`~impactbar.laws.abilities.CoupledBlow`) at each arrival instead (a contact that takes
        time, or one of no duration whose map the kernel cannot apply).
    open_ended : bool
        The contact step may last until the run's end (a sustained contact): the simulator passes
        its ``t_end`` to :meth:`~ContactLaw.contact` as a keyword.
    flight_starts_on_stop : bool
        Every flight starts with the end on the stop (``c . q = 0`` after
        :meth:`~ContactLaw.impact_map`), so that periodic orbits leave ``q_0`` out of their
        unknowns; ``False`` for a law whose piston may leave the contact step off the stop (the
        rod-rock law), whose orbits keep it.
    uses_restitution : bool
        The model's restitution ``R`` enters the contact (``False`` for the rod-rock law, whose rod
        and rock replace it).
    rigid_closed_forms : bool
        The rigid bar's closed forms (:mod:`impactbar.orbits.rigid`, eq. 14 with eq. 10) give this
        law's orbits.
    supports_schur : bool
        The paper's Schur criterion (eqs. 27-31) and eq. 14's charts (existence edges) belong to
        this law.
    stepped_piston : bool
        The law acts on the modal state alone (no characteristics on a uniform piston), so that a
        stepped piston's modes (``BarModel(..., piston=...)``, theory §12) serve it; ``False``
        refuses a stepped piston.

    Examples
    --------
    >>> from impactbar import BarModel
    >>> paper = BarModel(s=10.0, d=0.0, R=0.5, n_modes=0)
    >>> wave = paper.with_(impact="wave")
    >>> paper.law.traits.restitution_in_kernel, wave.law.traits.restitution_in_kernel
    (True, False)
    """

    restitution_in_kernel: bool = True
    open_ended: bool = False
    flight_starts_on_stop: bool = True
    uses_restitution: bool = True
    rigid_closed_forms: bool = False
    supports_schur: bool = False
    stepped_piston: bool = False

    def kernel_restitution(self, model) -> float:
        """Factor ``r`` of the compiled free-flight kernel's velocity map ``v -> -r v`` at an
        arrival (the simulator's flight kernel, theory §8).

        Parameters
        ----------
        model : BarModel

        Returns
        -------
        float
            ``R`` for a law that the kernel applies itself (eq. 10, :attr:`restitution_in_kernel`);
            ``-1`` (``v -> v``, nothing applied) for a law the simulator resolves by its contact.
        """
        return model.R if self.restitution_in_kernel else -1.0


#: the flags a law declared before its :class:`LawTraits` (refused on a subclass, with what replaces each)
_FORMER_DECLARATIONS = {
    "instantaneous": "traits = LawTraits(restitution_in_kernel=...), and the ability BlowRecords for a "
                     "blow with a record of its own",
    "has_phase_equation": "the ability PhaseEquation (a law without it has none)",
    **{flag: f"traits = LawTraits({flag}=...)" for flag in (
        "rigid_closed_forms", "supports_schur", "open_ended", "flight_starts_on_stop", "uses_restitution",
        "stepped_piston")},
}


@dataclass(frozen=True)
class ContactLaw:
    """Base class of the impact laws, in the style of scipy's ``OdeSolver``: a subclass sets
    :attr:`name` (and :attr:`traits` where they differ from the paper's law's) and implements the
    three required hooks; :data:`impactbar.laws.LAWS` maps names to classes. What only some laws can
    do is an ability (:mod:`impactbar.laws.abilities`): a law derives from it, and a solver looks it
    up once by :meth:`ability`.

    Attributes
    ----------
    name : str
        The law's name in :data:`~impactbar.laws.LAWS` and in ``BarModel.impact``.
    traits : LawTraits
        What the law declares about its contact (the kernel applies its restitution, its flights
        start on the stop, ...); by default the paper's law's.
    parameters : tuple of str
        The law's own continuation parameters (:func:`~impactbar.continue_orbit`, the sweeps' axes),
        each a field of the law: the names of :meth:`parameter_table`'s default records; none by
        default.
    """

    #: The hooks a law must implement (the base raises :class:`LawNotSupported`): with them alone it
    #: runs in :func:`~impactbar.simulate`, :func:`~impactbar.find_orbit`, the continuation and the
    #: sweeps (``tests/laws/test_custom_law.py``'s ``VelocityRestitution``).
    REQUIRED_HOOKS: ClassVar[tuple[str, ...]] = ("window", "impact_map", "contact")
    #: Every other member the solvers read: declarations, the ability lookup, and hooks with a default.
    OPTIONAL_HOOKS: ClassVar[tuple[str, ...]] = (
        "name", "traits", "parameters", "ability", "check_model", "parameter_table", "with_parameters")

    name: ClassVar[str] = ""
    traits: ClassVar[LawTraits] = LawTraits()
    parameters: ClassVar[tuple[str, ...]] = ()

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        for flag, instead in _FORMER_DECLARATIONS.items():
            if flag in vars(cls):
                raise TypeError(f"{cls.__name__}.{flag}: a law no longer declares {flag}; use {instead} "
                                "(impactbar.laws.abilities)")

    def ability(self, kind: type):
        """The law's ability ``kind`` (a class of :mod:`impactbar.laws.abilities`: its phase
        equation, its blows' records, its blow coupled to a drive, its help to Newton's method), or
        ``None`` where the law does not have it. A law has an ability by deriving from it, and
        then is that object; a law may override this to return another object with the ability's
        methods.

        Parameters
        ----------
        kind : type
            The ability asked for, e.g. :class:`~impactbar.laws.abilities.PhaseEquation`.

        Returns
        -------
        object or None

        Examples
        --------
        >>> from impactbar.laws import get_law
        >>> from impactbar.laws.abilities import CoupledBlow, PhaseEquation
        >>> paper = get_law("paper")
        >>> paper.ability(PhaseEquation) is paper, paper.ability(CoupledBlow)
        (True, None)
        """
        return self if isinstance(self, kind) else None

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
        raise LawNotSupported(not_provided(self, "window"))

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
        raise LawNotSupported(not_provided(self, "impact_map"))

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
            Only for a law whose traits are ``open_ended``: the run's end, where a contact that lasts
            so long stops (``t_release = t_end``).

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
        raise LawNotSupported(not_provided(self, "contact"))

    def parameter_table(self, model=None) -> tuple[Parameter, ...]:
        """The law's own parameters as records (:func:`impactbar.parameters.parameters` lists them
        beside the bar's): by default one unbounded, continuable record for each of
        :attr:`parameters`, its value the field of that name. A law with bounds, units,
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
        return tuple(Parameter(name, float(getattr(self, name))) for name in self.parameters)

    def with_parameters(self, changes: dict) -> ContactLaw:
        """A copy of the law with several of its own parameters (:meth:`parameter_table`) changed at
        once, the result validated once by the constructor whatever their order.

        Parameters
        ----------
        changes : dict of str to float

        Returns
        -------
        ContactLaw

        Raises
        ------
        ValueError
            For a name that is not one of the law's parameters (the message lists them), or a value
            the law refuses.
        """
        import dataclasses

        names = tuple(p.name for p in self.parameter_table())
        for name in changes:
            if name not in names:
                raise ValueError(f"parameter {name!r} is not one of the impact law {self.name!r}'s "
                                 f"parameters {names}")
        return dataclasses.replace(self, **changes)

    def __str__(self) -> str:
        return self.name


def not_provided(law: ContactLaw, hook: str) -> str:
    """The message of the :class:`LawNotSupported` raised where a solver needs ``hook`` and ``law``
    does not provide it (the solvers check a hook before any work: ``find_orbit``'s check of the
    law).

    Parameters
    ----------
    law : ContactLaw
    hook : str
        The method's name.

    Returns
    -------
    str
    """
    return (f"model.impact: the impact law {law.name!r} ({type(law).__name__}) does not provide "
            f"{hook}(), so this computation is not available under it; use impact='paper' or "
            f"impact='wave'")
