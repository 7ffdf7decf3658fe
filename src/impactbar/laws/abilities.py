"""What only some impact laws can do, each ability a small class of hooks (theory §4, §4b, §4d, §11).

The base :class:`~impactbar.laws.ContactLaw` holds what every solver calls; a law that can do more
derives from the abilities here as well (``class WaveLaw(ContactLaw, PhaseEquation, BlowRecords,
CoupledBlow)``), and a solver looks each up once, where it chooses its path, by
``law.ability(kind)``: the ability's object, or ``None`` where the law does not have it (as scipy's
``OdeSolver`` asks two methods and leaves the rest to the method).

- :class:`PhaseEquation`: the one-impact orbits from the law's phase equation
  (:func:`~impactbar.periodic_orbits`; without it, Newton's method from guesses), their
  multipliers, the charts' existence edge.
- :class:`BlowRecords`: each contact leaves a blow with a record of its own (a force history, the
  rod's energy), which a periodic orbit lists as its ``contacts`` and the SI results read.
- :class:`CoupledBlow`: the contact step solved together with a drive that has state (theory §11).
- :class:`NewtonStart`: what Newton's method for the law's orbits starts from, and a cheaper
  residual than the impact map with its Jacobian (:func:`newton_start` gives the defaults to a law
  without it).

Examples
--------
>>> from impactbar.laws import get_law
>>> from impactbar.laws.abilities import BlowRecords, PhaseEquation
>>> [get_law(name).ability(BlowRecords) is not None for name in ("paper", "wave")]
[False, True]
"""

from __future__ import annotations

from .base import ContactLaw, DrivenContact, LawNotSupported, OrbitState, not_provided

__all__ = ["PhaseEquation", "BlowRecords", "CoupledBlow", "NewtonStart", "newton_start", "require"]


class PhaseEquation:
    """The ability of a law with a one-impact phase equation (eq. 14 for the paper's law, theory
    §4b for the wave law): :func:`~impactbar.periodic_orbits` finds the one-impact orbits from its
    roots (:meth:`phase_roots`, :meth:`phase_families`, :meth:`orbit_state`). A law without it has
    its orbits found by Newton's method from guesses
    (:func:`~impactbar.orbits.periodic_orbits_by_newton`), which needs the base's hooks alone.
    """

    def phase_roots(self, model, load) -> list[tuple[float, int]]:
        """Roots of the law's one-impact phase equation in ``[0, 2 pi)``.

        Parameters
        ----------
        model : BarModel
        load : Load

        Returns
        -------
        list of (float, int)
            ``(phase, multiplicity)`` sorted by phase; ``phase`` is the load time of the arrival.
        """
        raise LawNotSupported(not_provided(self, "phase_roots"))

    def phase_families(self, model, load) -> list[tuple[float, float]]:
        """Intervals of phases on which the phase equation holds identically (a continuum of
        one-impact orbits, which :meth:`phase_roots` leaves out); none by default.

        Parameters
        ----------
        model, load : BarModel, Load
            As :meth:`phase_roots`.

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
        raise LawNotSupported(not_provided(self, "orbit_state"))

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
        raise LawNotSupported(not_provided(self, "multipliers"))

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
        raise LawNotSupported(not_provided(self, "existence_edge"))


class BlowRecords:
    """The ability of a law whose contact step leaves a blow with a record of its own (a force
    history, the rod's energy, the contact's separations: :class:`~impactbar.WaveImpact`, a rock's
    blow), which a periodic orbit lists as its ``contacts`` and checks for separation, and the SI
    results read per impact. A law without it (eq. 10's :class:`~impactbar.laws.InstantImpact`) has
    nothing to add to its impacts.
    """

    def blow(self, model, load, t: float, y_minus):
        """The blow of a periodic orbit's arrival (the ``contacts`` of
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
        object
            The blow's record, as :meth:`~impactbar.laws.ContactLaw.contact` returns it.
        """
        raise LawNotSupported(not_provided(self, "blow"))


class CoupledBlow:
    """The ability of a law whose contact step can be solved together with a drive that has state
    of its own (theory §11, "The coupled blow"): the drive's force is not held during the blow but
    follows its state, which the piston's driven end moves (:meth:`~impactbar.Drive.end_flight`).
    An instantaneous law needs none: its impact takes no time.
    """

    def driven_contact(self, model, drive, state, t: float, q_minus, v_minus, *,
                       settings=None) -> DrivenContact:
        """The contact step with a drive that has state, solved together with it.

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
            Where the drive cannot (:class:`~impactbar.laws.LawNotSupported`), or the blow cannot be
            solved (the message says why).
        """
        raise LawNotSupported(not_provided(self, "driven_contact"))

    def driven_tangent(self, model, drive, res, after, state):
        """The Jacobian of a coupled blow's map ``(q, q', z)`` at the arrival ``->`` after the blow and
        the drive's map, from a tangent of the blow (theory §11, "The coupled blow"), or ``None``
        where the law has none for this blow (the default): the caller differences the blow.

        Parameters
        ----------
        model : BarModel
        drive : Drive
        res : DrivenContact
            The blow (:meth:`driven_contact`'s).
        after : DriveState
            The drive's state after its map at the blow's end.
        state : DriveState
            The drive's state at the arrival.

        Returns
        -------
        numpy.ndarray, shape (2 N + 2 + k, 2 N + 2 + k), or None
        """
        return None


class NewtonStart:
    """The ability of a law whose orbits Newton's method reaches better from its own starts (the
    rod-rock law's): the bar under the paper's law whose orbits are the guesses, a cheaper model of
    the same motion, and the impact map's state without its Jacobian. Every law has the defaults
    here (:func:`newton_start`).
    """

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

    def coarse_start(self, model):
        """A cheaper model still, whose orbit starts the chord to :meth:`coarse_model`'s orbit (in
        place of that model's settling from rest), or ``None`` (the default): e.g. the rod-rock law's
        lattice at 8 cells a piston for the exact blows' lattice at its own grid.

        Parameters
        ----------
        model : BarModel
            The model whose :meth:`coarse_model` this one starts (under this law).

        Returns
        -------
        BarModel or None
            The model at the chain's cheap end; ``None``: that model settles from rest itself.
        """
        return None

    def impact_state(self, model, load, t: float, y_minus):
        """The state where the next flight starts, ``y_plus`` of
        :meth:`~impactbar.laws.ContactLaw.impact_map` without its derivatives (a residual of the
        orbit solver; a law whose Jacobian costs more than its map, such as the rod-rock law's,
        gives it alone).

        Parameters
        ----------
        model, load, t, y_minus
            As :meth:`~impactbar.laws.ContactLaw.impact_map`.

        Returns
        -------
        numpy.ndarray, shape (2 N + 2,)
        """
        y_plus, *_ = self.impact_map(model, load, t, y_minus)
        return y_plus


class _Defaults(NewtonStart):
    """:class:`NewtonStart`'s defaults for a law without the ability."""

    def __init__(self, law: ContactLaw):
        self.impact_map = law.impact_map


def newton_start(law: ContactLaw) -> NewtonStart:
    """The law's :class:`NewtonStart`, or the defaults for a law without it (every law has them).

    Parameters
    ----------
    law : ContactLaw

    Returns
    -------
    NewtonStart

    Examples
    --------
    >>> from impactbar import BarModel
    >>> model = BarModel(s=10.0, d=0.0, R=0.99, n_modes=0, impact="wave")
    >>> newton_start(model.law).paper_equivalent(model).R
    0.95
    """
    found = law.ability(NewtonStart)
    return _Defaults(law) if found is None else found


def require(law: ContactLaw, kind: type, hook: str):
    """The law's ability ``kind``, for a computation that needs its ``hook``.

    Parameters
    ----------
    law : ContactLaw
    kind : type
        One of the abilities here.
    hook : str
        The method the computation calls, named in the message.

    Returns
    -------
    object
        ``law.ability(kind)``.

    Raises
    ------
    LawNotSupported
        Where the law does not have the ability (a ``ValueError`` naming ``model.impact`` and the
        hook).
    """
    found = law.ability(kind)
    if found is None:
        raise LawNotSupported(not_provided(law, hook))
    return found
