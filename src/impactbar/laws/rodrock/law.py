"""The rod-and-rock law (theory §4d): the piston strikes a finite, possibly stepped rod whose bit
loads a rock with Lundberg's bilinear force-penetration law, under a static feed force.

Dimensionless as the model (theory §1): lengths in piston lengths ``L``, impedances and wave speeds
relative to the piston's (``Z = E A / C``, ``C``), so that a segment of relative length ``l`` and wave
speed ``c`` takes ``l / (c s)`` to cross; forces in ``m L Omega^2`` (the model's ``p``), so a rock
stiffness ``K`` (N/m) is ``k = K / (m Omega^2)``; masses in piston masses ``m``. The piston's
impedance in these units is ``s`` and its crossing time ``1/s``, so Lundberg's
``alpha = K (2 L / C) / Z`` is ``2 k / s^2``.

The law gives single blows (:func:`single_blow`) and the simulator's contact step
(:meth:`RodRock.contact`: ``simulate`` runs under it, one
:class:`~impactbar.laws.rodrock.contact.RockContact` per blow in ``Trajectory.impacts``) and its
impact map (:meth:`RodRock.impact_map`, the contact step with a finite-difference Jacobian:
``find_orbit`` runs under it from a guess, e.g. a simulation, and ``continue_orbit`` in the drive's
and the rock's parameters, :attr:`RodRock.parameters`). It has no phase equation
(not the ability :class:`~impactbar.laws.abilities.PhaseEquation`: what needs it raises
``LawNotSupported``, a ``ValueError``, naming it): ``periodic_orbits`` finds the one-impact orbits by
Newton's method from guesses
(:func:`~impactbar.orbits.periodic_orbits_by_newton`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import warnings
from dataclasses import dataclass

import numpy as np

from ..._shared.parameters import Parameter
from ..._shared.validate import check_int, check_real
from ..abilities import BlowRecords, CoupledBlow, NewtonStart
from ..base import ContactLaw, LawTraits
from ._choice import (  # noqa: F401  (the choices' bounds, as before)
    MAX_EXACT_LOADING_EXPONENT,
    MAX_EXACT_PASS_WINDOWS,
    NEGLIGIBLE_BIT,
    _bit_is_negligible,
    _exact_is_cheap,
)
from ._parameters import _NAMES, _SEGMENT, OWN, changed
from .checks import _check_blow_call, _check_force_scale
from .rod import BilinearRock as BilinearRock
from .rod import RodSegment as RodSegment

__all__ = ["BilinearRock", "RodRock", "RodSegment", "single_blow"]


@dataclass(frozen=True)
class RodRock(ContactLaw, BlowRecords, CoupledBlow, NewtonStart):
    """The piston strikes a rod of uniform segments; the bit (optional mass) loads a bilinear rock
    under a static feed force (theory §4d; Lundberg 1982, Chiang and Elias 2000).

    Parameters
    ----------
    segments : sequence of RodSegment
        From the shank to the bit, at least one (stored as a tuple).
    rock : BilinearRock
    bit_mass : float
        In piston masses, ``>= 0``; 0 is Lundberg's massless bit.
    feed : float
        Static feed force on the shank (model force units), ``>= 0``.
    blow_time : float, optional
        Duration of the blow in the simulator and in periodic orbits (model time, ``> 0``; the next
        flight starts this long after the impact, :meth:`window`). Default
        ``4/s + 2 sum of the segments' travel times``: the piston's contact of ``2/s`` and a round
        trip of a wave through piston and rod after it. Under a drive with state the blow ends
        where the piston is free for good instead (theory §11, "The coupled blow"; searched for up
        to twice the window), the exact blow's at the first of its solver's windows so, the
        lattice's so by default (``driven_end``).
    cells_per_piston : int, optional
        Cells along the piston of the simulator's blows on the lattice (``method="lattice"``, or
        ``"auto"`` with this given: :mod:`impactbar.laws.rodrock.blow`), ``1 <= n <= 4096``.
        Default: the smallest count making the piston's and every segment's travel times whole
        numbers of cells, at least 8 (else 64, the lengths rounded). The lattice's error is of first
        order in the cell time at most (the bit's exponential response stored as cell averages,
        switches inside a cell); on whole cells twice the cells estimates it (theory §4d), but a
        segment rounded to whole cells (``Blow.length_error``) sets an error that does not shrink as
        the cells double (theory §11: 2.2e-6 of the work on the circuit's rock example); ``"exact"``
        has none. :func:`single_blow` takes its own ``cells_per_piston``.
    method : {"auto", "exact", "lattice"}
        The simulator's blows (``simulate``, ``find_orbit``, ``continue_orbit``): ``"exact"`` every
        wave of piston and rod carried exactly, the piston's modal state and the drive as exact
        pieces, the state after the blow projected on the modes in closed form
        (:mod:`impactbar.laws.rodrock.exactmap`); ``"lattice"`` the cell grid; ``"auto"`` (default)
        exact unless ``cells_per_piston`` is given.
    driven_end : {"free", "window"}
        Where the lattice's blow under a drive with state ends (no other blow reads it): ``"free"``
        (default) where the piston is free for good (out of contact, its momentum ``<= 0``, the rock
        not loading: the exact blow's argument under a drive, theory §11), tested where the exact
        blow tests it, at the first step end at or after each multiple of the shortest travel time
        of piston and rod (the two end at the same instant to a step), searched for up to twice the
        window (``contact_events="slots"``: at that multiple itself); ``"window"`` at :meth:`window` (a
        fixed end, named by the user: on the circuit's rock example, 8 cells, ``"step"``, its orbit is
        4.3e-3 from the exact blows' in the work on the rock, the default's 1.4e-3; theory §11).
    contact_events : {"step", "inside", "slots"}
        Where the lattice's piston-shank separation and re-contact fall: ``"step"`` (default) at
        step ends (a re-contact from the first step that starts with the gap closed); ``"inside"``
        inside their steps, each wave arriving at the contact read as its value on the step before
        up to a front and on the next after it (:mod:`impactbar.laws.rodrock.blow`). On the circuit's
        rock example (its rod rounded to whole cells) ``"inside"`` puts the orbit farther from the
        exact blows' at 8, 16 and 32 cells (the work on the rock 2.6e-3, 4.1e-3, 2.6e-3 off against
        1.4e-3, 8.1e-4, 1.8e-3 at the steps' ends; theory §11, "The coupled blow"); its re-contact
        does not jump a whole step as a design changes, as the steps' ends' does (the border of the
        whole-drifter search, docs/optimising_a_drifter.md), so ``"inside"`` is the choice for a
        search that needs the operating point smooth in the design. ``"slots"``: every event of the
        blow at its own instant inside its step, the steps cut into slots every cell carries, and the
        rod's segments exact (:mod:`~impactbar.laws.rodrock._rockslots`): on the circuit's rock example,
        which names it, the orbit 2.0e-6 from the exact blows' on 8 cells at 3 times the cost of
        ``"step"`` (theory §11, "The coupled blow").

    Examples
    --------
    >>> from impactbar import BarModel, RodRock, RodSegment, BilinearRock, single_blow
    >>> law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)],
    ...               rock=BilinearRock(k=2.5, k_u=25.0))
    >>> model = BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law)
    >>> law.alpha(model)
    1.25
    >>> round(single_blow(model, 1.0, t_max=39.0).efficiency, 6)  # Lundberg's (2/a)(1-e^-a)^2(1-1/g)
    0.733069
    """

    segments: tuple = ()
    rock: BilinearRock | None = None
    bit_mass: float = 0.0
    feed: float = 0.0
    blow_time: float | None = None
    cells_per_piston: int | None = None
    method: str = "auto"
    driven_end: str = "free"
    contact_events: str = "step"

    # the declarations where the law differs from ContactLaw's defaults
    name = "rodrock"
    #: its piston may leave the blow off the shank, the rod and rock replace ``R``; a stepped piston
    #: (``BarModel(..., piston=...)``, theory §12): its modal state becomes the cells of its segments'
    #: impedances at impact and is projected back on its modes after the blow
    #: (:func:`~impactbar.laws.rodrock.contact._stepped_maps`)
    traits = LawTraits(restitution_in_kernel=False, flight_starts_on_stop=False, uses_restitution=False,
                       stepped_piston=True)
    #: the law's continuation parameters, in its units: the rock's loading and unloading stiffnesses
    #: (``"rock.k"`` alone, ``k_u`` kept, so ``k <= k_u``), the bit's mass, the feed force, and
    #: ``"segment<i>.length"`` (``i`` from 0 at the shank; the default ``blow_time`` follows the
    #: lengths), continued on the exact blows only (the lattice's cell grid rounds them to whole
    #: cells: :meth:`parameter_table`)
    parameters = (*_NAMES, "segment<i>.length")

    def __post_init__(self) -> None:
        segs = tuple(self.segments)
        if not segs or not all(isinstance(g, RodSegment) for g in segs):
            raise ValueError("segments must be a non-empty sequence of RodSegment; "
                             f"got segments={self.segments!r}")
        object.__setattr__(self, "segments", segs)
        if not isinstance(self.rock, BilinearRock):
            raise ValueError(f"rock must be a BilinearRock; got rock={self.rock!r}")
        object.__setattr__(self, "bit_mass", check_real("bit_mass", self.bit_mass, lo=0.0))
        object.__setattr__(self, "feed", check_real("feed", self.feed, lo=0.0))
        if self.driven_end not in DRIVEN_ENDS:
            raise ValueError(f"driven_end must be 'window' or 'free'; got driven_end={self.driven_end!r}")
        if self.contact_events not in CONTACT_EVENTS:
            raise ValueError("contact_events must be 'step', 'inside' or 'slots'; "
                             f"got contact_events={self.contact_events!r}")
        if self.blow_time is not None:
            object.__setattr__(self, "blow_time",
                               check_real("blow_time", self.blow_time, lo=0.0, lo_open=True))
        if self.cells_per_piston is not None:
            object.__setattr__(self, "cells_per_piston",
                               check_int("cells_per_piston", self.cells_per_piston, lo=1, hi=4096))
        if self.method not in ("auto", "exact", "lattice"):
            raise ValueError(f"method must be 'auto', 'exact' or 'lattice'; got method={self.method!r}")

    def blow_method(self, model) -> str:
        """The method of the simulator's blows of ``model`` under this law: ``"exact"`` for
        ``method="exact"``, or ``"auto"`` without ``cells_per_piston`` where a round trip of a wave
        through piston and rod takes at most ``MAX_EXACT_PASS_WINDOWS`` (2000) of the shortest travel
        time and the rock's loading exponent over it is at most ``MAX_EXACT_LOADING_EXPONENT`` (the
        exact solver's cost grows with the windows; :func:`single_blow`'s choice); else
        ``"lattice"``. It depends on the law and the model's geometry only, so that every blow of a
        run, and :meth:`window`, take one method.

        Parameters
        ----------
        model : BarModel

        Returns
        -------
        str
        """
        return _blow_method(self, model)

    def alpha(self, model) -> float:
        """Lundberg's ``alpha = K (2 L / C) / Z`` of the piston, ``2 k / s^2`` in the model's units."""
        return 2.0 * self.rock.k / model.s ** 2

    def paper_equivalent(self, model):
        """The same bar under the paper's law with the restitution of a rigid piston's blow on this
        rod and rock, ``R = -rebound_velocity / V`` at ``V = 1`` (:func:`single_blow`, clipped to
        ``[0, 0.95]``): whose orbits start Newton's method for this law's (theory §4d, §10).

        Parameters
        ----------
        model : BarModel
            A bar under the rod-rock law.

        Returns
        -------
        BarModel
            ``model`` with ``impact="paper"`` and that ``R``.
        """
        return model.with_(impact="paper", R=_equivalent_restitution(model))

    def coarse_model(self, model):
        """``model`` with its blows on the lattice where they are exact (:meth:`blow_method`), else
        ``None``: Newton's method for the exact blows' orbits starts from the lattice's orbit
        (:func:`~impactbar.find_orbit`), which it reaches from farther guesses (its blows are
        smoothed over the cells) at a fraction of the cost, and which lies within the lattice's
        second-order error of the exact one. With ``method="exact"`` the lattice's blows under a
        drive with state end where the exact ones do, where the piston is free for good
        (``driven_end="free"``, theory §11, "The coupled blow"): on
        ``examples/circuit_drifter_rock.toml`` the polish then starts 2.6e-4 from the exact orbit, not
        8.8e-3 (at the law's window), and its chord gains three digits a step, not two: 4 exact blows
        an orbit, not 6.

        Parameters
        ----------
        model : BarModel

        Returns
        -------
        BarModel or None
        """
        if self.blow_method(model) != "exact":
            return None
        # ("auto": the lattice with the law's own end under a drive; its plain events, the cheapest)
        end = "free" if self.method == "exact" else self.driven_end
        return model.with_(impact=dataclasses.replace(self, method="lattice", cells_per_piston=None,
                                                      driven_end=end, contact_events="step"))

    def coarse_start(self, model):
        """:meth:`coarse_model` on a lattice of ``COARSE_START_CELLS`` (8) cells a piston, else
        ``None``: its orbit starts the chord to the coarse model's (:func:`~impactbar.find_orbit`), the
        settling from rest then on blows some 8 times cheaper. On
        ``examples/circuit_drifter_rock.toml`` the chord from 8 cells to the lattice's own grid takes 3
        steps (6.5e-3, 3.4e-5, 1.3e-7) where the settling took 14 blows and a steering Jacobian: the
        lattice's part of the exact orbit 1.20 s to 0.88 s (measured), the same 4 exact blows (theory
        §11, "The coupled blow").

        Parameters
        ----------
        model : BarModel
            Its blows exact (:meth:`blow_method`), else the answer is ``None``.

        Returns
        -------
        BarModel or None
            ``model`` under this law on the 8 cells' lattice, its blows ended as :meth:`coarse_model`'s.
        """
        coarse = self.coarse_model(model)
        return None if coarse is None else coarse.with_(
            impact=dataclasses.replace(coarse.law, cells_per_piston=COARSE_START_CELLS))

    def window(self, model) -> float:
        """Duration of the blow in the simulator and in periodic orbits (model time): ``blow_time``,
        by default ``4/s + 2 sum of the segments' travel times``; on the lattice rounded up to whole
        steps of the blow's cell grid (the simulator's blow lasts whole steps, so the orbits' flights
        start where its flights do)."""
        from .contact import _grid_for
        from .grid import whole_steps

        T = self.blow_time
        if T is None:
            T = 4.0 / model.s + 2.0 * sum(g.travel_time(model) for g in self.segments)
        if self.blow_method(model) == "exact":
            return float(T)
        segs = self.segments
        dt = _grid_for(float(model.s), tuple(g.length for g in segs), tuple(g.impedance for g in segs),
                       tuple(g.wave_speed for g in segs), self.cells_per_piston,
                       model.piston).cell_time
        return whole_steps(T, dt) * dt

    def impact_map(self, model, load, t, y_minus):
        """The contact step as a map of the arrival state (theory §4d): ``y_plus`` the state
        :meth:`window` after the impact (positions from the advanced shank; the exact blow's, or
        the lattice's, :meth:`blow_method`), with its Jacobians. For exact blows the Jacobians are
        exact (theory §4d, "the exact blow's Jacobian": tangent runs of the blow along each state
        direction and the impact time, the switches held, a re-contact's move carried as impulses;
        :func:`~impactbar.laws.rodrock.exactjac.exact_impact_map`); on the lattice, and where the
        exact map has no derivative (a re-contact at zero closing speed), **central finite
        differences**: steps ``h = 1e-6 |y_minus|_inf`` (relative, so that the map's Jacobian is the
        same at every scale of the load) in every state component and ``h_t = 1e-6`` in ``t``
        (truncation ``O(h^2)``, rounding ``O(eps/h)``: about 1e-10 relative where the map is smooth
        on that scale), ``4 N + 6`` blows.

        Returns
        -------
        y_plus : numpy.ndarray, shape (2 N + 2,)
        jac_y : numpy.ndarray, shape (2 N + 2, 2 N + 2)
        jac_t : numpy.ndarray, shape (2 N + 2,)
        """
        from .step import blow_map, map_with_jacobians

        return map_with_jacobians(blow_map(model, load, float(t)), y_minus, t)

    def impact_state(self, model, load, t, y_minus):
        """``y_plus`` of :meth:`impact_map` alone: one blow, no finite differences."""
        from .step import blow_map

        return blow_map(model, load, float(t))(np.asarray(y_minus, dtype=float))

    def blow(self, model, load, t, y_minus):
        """The blow of an arrival at load time ``t`` in state ``y_minus`` (shape ``(2 N + 2,)``)
        with the drive acting: the record of :meth:`contact`."""
        M = model.n_modes + 1
        c = model.end_weights
        qm = np.array(y_minus[:M], dtype=float)
        qm[0] -= float(c @ qm)  # the end exactly on the shank (rounding)
        _, _, _, record = self.contact(model, load, t, qm, np.array(y_minus[M:], dtype=float))
        return record

    def contact(self, model, load, t, q_minus, v_minus, *, kernel=None):
        """The simulator's contact step (theory §4d): the piston's modal state at impact -> the blow
        by characteristics on the piston and the rod with the drive's force on the piston's far
        end, every wave exact (:mod:`impactbar.laws.rodrock.exactmap`; on the lattice,
        :meth:`blow_method`, the drive averaged over each cell step) -> the piston's waves at the
        blow's end projected on the modes; the rod then rests on the rock (its residual waves
        discarded, counted in the energy the piston lost), the shank advanced by the blow's
        permanent penetration, from which the next flight's positions are measured
        (:func:`impactbar.laws.rodrock.step.rock_contact`; ``kernel`` is not used).

        Returns
        -------
        q_after, v_after : numpy.ndarray, shape (N + 1,)
        t_release : float
            ``t + duration`` of the blow.
        record : RockContact
            Work on rock, penetrations, efficiencies (those of its :class:`Blow`), the piston's
            energy balance (an :class:`~impactbar.laws.rodrock.exactmap.ExactRockContact` for the
            exact blows).
        """
        from .step import rock_contact

        rec = rock_contact(model, load, float(t), q_minus, v_minus)
        return rec.q_after.copy(), rec.v_after.copy(), float(t) + rec.duration, rec

    def driven_contact(self, model, drive, state, t, q_minus, v_minus, *, settings=None):
        """The contact step with a drive that has state (theory §11, "The coupled blow"): the
        lattice's blow by a method of steps (:func:`~impactbar.laws.rodrock.coupled.driven_rock_contact`),
        or with ``method="exact"`` (not ``"auto"``) the exact blow, the drive's force iterated
        (:func:`~impactbar.laws.rodrock.coupled_exact.driven_exact_contact`).

        Returns
        -------
        DrivenContact
        """
        if self.method == "exact":
            from .coupled_exact import driven_exact_contact

            return driven_exact_contact(model, drive, state, float(t), q_minus, v_minus, settings)
        from .coupled import driven_rock_contact

        return driven_rock_contact(model, drive, state, float(t), q_minus, v_minus, settings)

    def driven_tangent(self, model, drive, res, after, state):
        """With ``method="exact"`` the coupled exact blow's tangent
        (:func:`~impactbar.laws.rodrock.coupled_tangent.coupled_blow_tangent`, ``None`` where it
        does not cover the blow); the lattice's blows: ``None`` (differenced by the caller).

        Returns
        -------
        numpy.ndarray or None
        """
        if self.method != "exact":
            return None
        from .coupled_tangent import coupled_blow_tangent

        return coupled_blow_tangent(model, drive, res, after, state)

    def parameter_table(self, model=None) -> tuple[Parameter, ...]:
        """The law's parameters, in its units (:attr:`parameters`), for
        :func:`impactbar.parameters.parameters`: a segment's length is not continuable where the blows
        are the lattice's (its cell grid rounds them to whole cells).

        Parameters
        ----------
        model : BarModel, optional
            The model under this law (which blows it takes: :meth:`blow_method`).

        Returns
        -------
        tuple of Parameter
            ``rock.k``, ``rock.k_u``, ``bit_mass``, ``feed``, ``segment0.length``, ...

        Examples
        --------
        >>> law = RodRock(segments=[RodSegment(length=2.0, impedance=2.0)],
        ...               rock=BilinearRock(k=20.0, k_u=200.0))
        >>> [(p.name, p.value) for p in law.parameter_table()][:2]
        [('rock.k', 20.0), ('rock.k_u', 200.0)]
        """
        exact = self.method == "exact" if model is None else self.blow_method(model) == "exact"
        lattice = ("" if exact else "on the lattice its cell grid rounds the segments' travel times to whole "
                   "cells, so the orbit changes in steps with a length: use RodRock(method='exact' or "
                   "'auto', without cells_per_piston), or follow it with simulated_diagram or find_orbit "
                   "at each length")
        return (
            *(dataclasses.replace(p, value=self.parameter_value(p.name),  # (k_u at least this law's k)
                                  low=float(self.rock.k) if p.name == "rock.k_u" else p.low) for p in OWN),
            *(Parameter(f"segment{i}.length", float(g.length), low=1e-100, high=1e100, continuable=exact,
                        description=f"length of rod segment {i} (piston lengths)", reason=lattice)
              for i, g in enumerate(self.segments)),
        )

    @classmethod
    def has_parameter(cls, name: str) -> bool:
        """Whether ``name`` is one of :attr:`parameters` (``"segment<i>.length"`` for any ``i``).

        Parameters
        ----------
        name : str
            Any name; the segment's index is not checked against a rod (a class method).

        Returns
        -------
        bool
        """
        return name in _NAMES or bool(_SEGMENT.fullmatch(str(name)))

    def parameter_value(self, name: str) -> float:
        """The value of one of :attr:`parameters` (``"rock.k"``, ``"segment0.length"``, ...).

        Parameters
        ----------
        name : str
            One of :attr:`parameters`, a segment's index below the rod's number of segments.

        Returns
        -------
        float
            In the model's units.

        Raises
        ------
        ValueError
            For another name, or a segment the rod does not have.
        """
        self._check_parameter(name)
        if name.startswith("rock."):
            return float(getattr(self.rock, name[5:]))
        match = _SEGMENT.fullmatch(name)
        if match:
            return float(self.segments[int(match.group(1))].length)
        return float(getattr(self, name))

    def with_parameter(self, name: str, value: float) -> RodRock:
        """A copy with one of :attr:`parameters` changed (validated again by the constructors).

        Parameters
        ----------
        name : str
        value : float

        Returns
        -------
        RodRock

        Raises
        ------
        ValueError
            For another name, a segment the rod does not have, or a value the constructors refuse
            (for example ``rock.k`` above ``rock.k_u``).
        """
        return self.with_parameters({name: value})

    def with_parameters(self, changes: dict) -> RodRock:
        """A copy with several of :attr:`parameters` changed at once, the result validated once
        whatever their order (``impactbar.laws.rodrock._parameters.changed``)."""
        return changed(self, changes)

    def _check_parameter(self, name: str) -> None:
        if not self.has_parameter(name):
            raise ValueError(f"parameter {name!r} is not one of the rod-rock law's {self.parameters}")
        match = _SEGMENT.fullmatch(str(name))
        if match and int(match.group(1)) >= len(self.segments):
            raise ValueError(f"parameter {name!r}: the rod has {len(self.segments)} segment(s), "
                             f"segment0 to segment{len(self.segments) - 1}")


@functools.lru_cache(maxsize=256)
def _blow_method(law, model) -> str:
    """:meth:`RodRock.blow_method`, cached per (frozen, hashable) law and model: every blow of a run
    or an orbit asks it."""
    if law.method == "exact":
        return "exact"
    if law.method == "auto" and law.cells_per_piston is None and _exact_is_cheap(model, law, model.piston):
        return "exact"
    return "lattice"


def single_blow(model, impact_velocity: float, *, cells_per_piston: int | None = None,
                t_max: float | None = None, energy_fraction: float = 1e-9, record_field: bool = False,
                piston=None, method: str = "auto", semi_infinite: bool = False):
    """One blow of the piston on the rod and rock of ``model.law`` (theory §4d).

    Assumed: the piston (the model's bar: length 1, impedance ``s``, mass 1) moves rigidly and
    unstressed at ``impact_velocity`` when it touches the shank; no drive acts during the blow (the
    feed force acts on the shank); the rod is at rest, compressed by the feed, the bit resting on
    fresh rock loaded to the feed force. The model's ``R`` and ``d`` play no part (the rod replaces
    the restitution; the blow is undamped), nor its flexible modes (the piston is unstressed at
    impact). Without a feed (a bit with or without mass), every wave is carried exactly (``method="exact"``,
    ``impactbar.laws.rodrock.exact``: pieces of constants and exponentials between break points,
    every switch a located root) and the blow runs until its end is certified (``ended_by``:
    ``"separated"``, the piston gone for good and the rock unable to yield again, the rod perhaps
    ringing on it; ``"lifted"``, the rod off the rock for good too; ``"spent"``, the energy that
    could still reach the rock below 1e-17 of the available), no ``t_max`` needed. With a feed,
    ``method="exact"`` ends once the piston has gone for good and the rock is not loading, if the
    rod's ringing could still make the rock yield (``"may_yield"``: under the feed a lossless rod
    may load it again at any later time; the loading episodes so far in ``Blow.loadings`` and
    ``uncertainty`` bounding the rock work still possible are the answer there: the efficiency's
    denominator holds the feed's work up to that instant, which the ringing rod moves either way),
    unless a ``t_max`` asks to go on. Without a ``t_max`` the cost of ``method="exact"`` is bounded by
    ``EXACT_MAX_PIECES`` (1e5) wave pieces, past which the blow ends as ``"budget"`` (``uncertainty``
    bounding the rock work still possible); a ``t_max`` is the caller's horizon. By
    default, with a feed or a ``cells_per_piston``, the lattice of
    :mod:`impactbar.laws.rodrock.blow` (``method="lattice"``: first order in the cell time,
    the bit's reflected wave stored as cell averages; to
    ``t_max``, default 20 travel times through piston and rod, or until the rod's wave energy is
    spent). The lattice certifies no end: stopped at ``t_max`` it reports in ``uncertainty`` the
    rock work still possible by the energy left in piston, rod, bit and rock (the exact blow's bound,
    the piston's energy included since the lattice does not prove it gone) over the available
    energy; with a feed that is seldom small.

    Parameters
    ----------
    model : BarModel
        With ``impact=RodRock(...)``.
    impact_velocity : float
        ``> 0``, in the model's velocity unit ``L Omega``.
    cells_per_piston, t_max, energy_fraction, record_field
        See :func:`impactbar.laws.rodrock.blow.rod_rock_blow`: the grid, the longest blow, the end
        criterion (piston separated and the rod's wave energy below this fraction of the impact
        energy) and whether to keep the force field for the Lagrange diagram. For the exact method
        ``t_max`` is an optional horizon (``ended_by = "t_max"``, ``uncertainty`` bounding what the
        efficiency could still gain), ``cells_per_piston`` (given with ``method="exact"``) the
        samples per piston crossing time of the recorded arrays (default 32), ``energy_fraction``
        unused.
    piston : SteppedPiston, optional
        A stepped piston of the model's mass and length (theory §12): its segments, from the driven
        end to the struck end, each of impedance ``s mu_j`` (``mu_j`` its mass per length, the
        piston's mass 1), carried by characteristics like the rod's, so that on a long rod it sends
        the staircase wave its impedances give: exactly by the exact method, each segment a delay
        line of travel time ``l_j / s`` (its boundaries anywhere), or by the lattice as cells of its
        grid (boundaries rounded to whole cells, ``length_error``). The rod's impedances stay
        relative to ``s`` (a uniform piston of the same mass and length). Default None: the uniform
        piston, whose results a one-segment ``SteppedPiston`` reproduces to the bit.
    method : {"auto", "exact", "lattice"}
        ``"auto"``: exact for a uniform or stepped piston, a bit with or without mass, no feed and
        no ``cells_per_piston`` (and
        where a wave's round trip takes at most ``MAX_EXACT_PASS_WINDOWS`` (2000) of the shortest
        travel time, ``k / Z_b`` times the shortest travel time is at most ``1e6`` and its waves
        need at most ``AUTO_MAX_PIECES`` (1e5) pieces in at most ``AUTO_MAX_POOL_BYTES`` (64 MiB;
        exponents close together, a bit's mass or a soft rock, make long series)), else the
        lattice; an exact blow whose energy account does not close to ``1e-9`` is not taken
        either (auto: the lattice's instead; ``"exact"``: a ``RuntimeWarning``). A bit whose time
        constant ``m / Z_b`` (``Z_b`` the last rod segment's impedance) is at most ``1e-10`` of the
        shortest travel time, and overdamped on the rock (``4 m k_u <= Z_b^2``), counts as massless
        for both the choice and the exact solver: its effect on every result is of that relative
        order.
    semi_infinite : bool
        Lundberg's idealisation (exact method): the wave the bit reflects leaves the rod and never
        returns (its energy in ``radiated``); the blow ends when the energy is spent.

    Returns
    -------
    Blow
        Work on rock, efficiencies, penetrations, force histories, the energy account.

    Raises
    ------
    ValueError
        Before any array is built: ``model`` not a ``BarModel`` under ``RodRock``; ``impact_velocity``
        not finite and ``> 0`` or its wave force ``s V`` outside ``[1e-100, 1e100]``; the law's
        ``feed`` above ``1e100`` or its ``bit_mass`` in ``(0, 1e-100)`` (the wave energies would
        overflow); ``t_max`` not finite and ``> 0``; ``cells_per_piston`` not an integer ``>= 1``; a
        grid of more than ``5e9`` cell updates (a rod far longer, in travel time, than the piston, or
        too fine a grid); a bit ringing on the rock more than ``1e6`` radians a lattice step; ``piston``
        neither None nor a ``SteppedPiston``; ``method`` not one of those above; ``semi_infinite`` not
        a bool, or with the lattice.

    Examples
    --------
    >>> from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow
    >>> law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)],
    ...               rock=BilinearRock(k=2.5, k_u=25.0))
    >>> blow = single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law), 1.0, t_max=39.0)
    >>> round(blow.efficiency, 6), round(blow.work_on_rock, 6)  # of the impact energy 1/2
    (0.733069, 0.366534)
    >>> ib = single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law), 1.0, semi_infinite=True)
    >>> ib.ended_by, round(ib.efficiency, 12)  # Lundberg's idealisation, no horizon
    ('spent', 0.733068583061)

    A piston with a heavy head (the struck end) and a light tail, on a rod of the head's impedance,
    sends a two-step wave: ``Z_h V/2`` for the head's round trip, then ``(1 + R)`` times it for the
    tail's, ``R = (Z_t - Z_h)/(Z_t + Z_h) = -1/3`` (theory §12; the shank's force on each step):

    >>> from impactbar import SteppedPiston
    >>> head = SteppedPiston([0.75, 0.25], [1.0, 2.0])  # tail, head: areas 1 and 2
    >>> head.mass_per_length  # the rod of the head's impedance: 1.6 s
    array([0.8, 1.6])
    >>> rod = RodRock(segments=[RodSegment(length=40.0, impedance=1.6)], rock=BilinearRock(k=2.5, k_u=25.0))
    >>> b = single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=rod), 1.0, piston=head)
    >>> b.method, b.ended_by  # every wave exact, the end certified
    ('exact', 'lifted')
    >>> b.shank_force([0.1, 0.3, 0.9, 1.1]).round(6)  # the head's round trip 0.25, the tail's 0.75
    array([1.6     , 1.066667, 1.066667, 0.      ])
    """
    from .blow import rod_rock_blow

    law = getattr(model, "law", None)
    if not isinstance(law, RodRock):
        got = f"impact={model.impact!r}" if hasattr(model, "impact") else f"model={model!r}"
        raise ValueError(f"single_blow needs a BarModel with impact=RodRock(...); got {got}")
    if method not in ("auto", "exact", "lattice"):
        raise ValueError(f"method must be 'auto', 'exact' or 'lattice'; got method={method!r}")
    if not isinstance(semi_infinite, bool | np.bool_):
        raise ValueError(f"semi_infinite must be True or False; got semi_infinite={semi_infinite!r}")
    if piston is not None:
        from ._piston import piston_segments

        piston_segments(piston)  # (checked before any choice is made)
        if model.piston is not None and piston != model.piston:
            raise ValueError(f"piston: the model's is {model.piston!r}, the call's {piston!r}; give one "
                             "(or the same)")
    piston = model.piston if piston is None else piston
    massless = law.bit_mass == 0.0 or _bit_is_negligible(model, law)
    exact = method == "exact" or (method == "auto" and (semi_infinite or (
        law.feed == 0.0 and cells_per_piston is None and _exact_is_cheap(model, law, piston))))
    if semi_infinite and not exact:
        raise ValueError("semi_infinite=True needs method='exact' (or 'auto'); the lattice carries "
                         "the rod's finite length")
    segs = law.segments
    if exact:
        from .exact import PoolOverflow

        auto = method == "auto" and not semi_infinite
        try:
            blow = _exact_single_blow(model, law, impact_velocity, t_max, cells_per_piston, record_field,
                                      semi_infinite, 0.0 if massless else law.bit_mass,
                                      AUTO_MAX_PIECES if auto else
                                      (EXACT_MAX_PIECES if t_max is None else None), piston,
                                      AUTO_MAX_POOL_BYTES if auto else None)
        except PoolOverflow:
            if not auto:
                raise
            blow = None  # a light bit's long series: the lattice
        bad = blow is None or not blow.energy_error <= EXACT_ACCOUNT_TOLERANCE
        if not auto and (blow.ended_by == "failed" or not math.isfinite(blow.efficiency)):
            raise ValueError("method='exact': the blow's pieces overflowed (a rock far stiffer than the "
                             f"rod: k / Z_b = {law.rock.k / (model.s * law.segments[-1].impedance):.3g}); "
                             "use method='lattice' (or 'auto')")
        if bad and not auto:
            warnings.warn(f"the exact blow's energy account is off by {blow.energy_error:.2g} of the "
                          "available energy (a switch of the rock's branches it could not resolve); "
                          "method='lattice' gives the first-order solution", RuntimeWarning, stacklevel=2)
        if not (auto and (bad or blow.ended_by == "budget")):
            return blow
        try:  # waves broken into too many pieces (incommensurate segments, a slow soft rock)
            V, t_max, cells_per_piston = _check_blow_call(model, law, impact_velocity, t_max,
                                                          cells_per_piston, record_field, piston)
        except ValueError:  # the lattice too costly: the exact blow's budget end stands (a failed
            if bad:  # or unbalanced one never does: the lattice's reason is the answer)
                raise
            return blow
    else:
        V, t_max, cells_per_piston = _check_blow_call(model, law, impact_velocity, t_max,
                                                      cells_per_piston, record_field, piston)
    return rod_rock_blow(
        model.s, V, [g.length for g in segs], [g.impedance for g in segs], [g.wave_speed for g in segs],
        law.rock.k, law.rock.k_u, law.bit_mass, law.feed, cells_per_piston=cells_per_piston,
        t_max=t_max, energy_fraction=check_real("energy_fraction", energy_fraction, lo=0.0),
        record_field=record_field, piston=piston)


def _exact_single_blow(model, law, impact_velocity, t_max, samples, record_field, semi_infinite,
                       bit_mass, max_pieces=None, piston=None, max_pool_bytes=None):
    """:func:`single_blow` by the exact solver (checked arguments; ``cells_per_piston`` the samples
    per piston crossing time of the recorded arrays, default 32; ``bit_mass`` 0 for a negligible
    bit)."""
    from .exactrecord import exact_rod_rock_blow

    V = _check_force_scale(model, law, impact_velocity)
    if t_max is not None:
        t_max = check_real("t_max", t_max, lo=0.0, lo_open=True)
    samples = 32 if samples is None else check_int("cells_per_piston", samples, lo=1)
    segs = law.segments
    return exact_rod_rock_blow(model.s, V, [g.length for g in segs], [g.impedance for g in segs],
                               [g.wave_speed for g in segs], law.rock.k, law.rock.k_u, bit_mass,
                               law.feed, t_max=t_max, semi_infinite=semi_infinite,
                               **({} if max_pieces is None else {"max_pieces": max_pieces}),
                               samples_per_piston=samples, record_field=bool(record_field),
                               piston=piston, max_pool_bytes=max_pool_bytes)


#: The values of :class:`RodRock`'s ``driven_end`` and ``contact_events`` (a config's ``[rock]`` keys too)
DRIVEN_ENDS = ("free", "window")
CONTACT_EVENTS = ("step", "inside", "slots")

#: The cells a piston of the lattice whose orbit starts the exact blows' coarse orbit
#: (:meth:`RodRock.coarse_start`; the example's default grid, its orbit within 1.4e-3 of the exact one)
COARSE_START_CELLS = 8

#: The exact blow's energy account (relative to the available energy) closes to rounding, about
#: 1e-15; past this its answer is not taken (``method="auto"``: the lattice's instead) or is warned
#: of (``method="exact"``)
EXACT_ACCOUNT_TOLERANCE = 1e-9

#: The most wave pieces ``method="exact"`` stores without a ``t_max`` (some seconds; a blow under a
#: feed waiting for the piston to go for good ran to 2 million in a minute); past it the blow ends as
#: ``"budget"``, its ``uncertainty`` bounding what the rock could still take
EXACT_MAX_PIECES = 100_000

#: The most wave pieces ``method="auto"`` lets the exact solver store (about a second; the blows
#: tried need 60 to 700) before it gives the blow to the lattice: incommensurate segments and a slow,
#: soft rock multiply the break points (each sum of travel times is one) until they cost more than
#: the lattice's cells.
AUTO_MAX_PIECES = 100_000

#: The most memory ``method="auto"`` lets the exact solver's pieces take (their terms: 5 to 40 a
#: piece, long series where exponents lie close together; the blows tried need a few MiB) before it
#: gives the blow to the lattice. (128 MiB, when the pool grew its pieces and terms together, held
#: about the terms 64 MiB holds now.)
AUTO_MAX_POOL_BYTES = 2 ** 26


def lundberg_efficiency(alpha: float, gamma: float) -> float:
    """Lundberg's efficiency of a rectangular incident wave on a massless bit and bilinear rock:
    ``(2/alpha)(1 - e^-alpha)^2 (1 - 1/gamma)`` (theory §4d)."""
    return 2.0 / alpha * (-math.expm1(-alpha)) ** 2 * (1.0 - 1.0 / gamma)


def _equivalent_restitution(model) -> float:
    """``-rebound_velocity / V`` of a rigid piston's blow at ``V = 1`` on the model's rod and rock,
    clipped to ``[0, 0.95]``: the restitution of the paper-law guesses."""
    blow = single_blow(model, 1.0)
    return min(0.95, max(0.0, -float(blow.rebound_velocity)))

