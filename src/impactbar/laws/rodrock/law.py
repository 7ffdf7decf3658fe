"""The rod-and-rock law (theory §4d): the piston strikes a finite, possibly stepped rod whose bit
loads a rock with Lundberg's bilinear force-penetration law, under a static feed force.

Dimensionless as the model (theory §1): lengths in piston lengths ``L``, impedances and wave speeds
relative to the piston's (``Z = E A / C``, ``C``), so that a segment of relative length ``l`` and wave
speed ``c`` takes ``l / (c s)`` to cross; forces in ``m L Omega^2`` (the model's ``p``), so a rock
stiffness ``K`` (N/m) is ``k = K / (m Omega^2)``; masses in piston masses ``m``. The piston's
impedance in these units is ``s`` and its crossing time ``1/s``, so Lundberg's
``alpha = K (2 L / C) / Z`` is ``2 k / s^2``.

The law gives single blows (:func:`single_blow`) and the simulator's contact step
(:meth:`RodRock.contact`: ``simulate`` runs under it, one :class:`~impactbar.dynamics.rockcontact.RockContact`
per blow in ``Trajectory.impacts``) and its impact map (:meth:`RodRock.impact_map`, the contact step
with a finite-difference Jacobian: ``find_orbit`` runs under it from a guess, e.g. a simulation, and
``continue_orbit`` in the drive's and the rock's parameters); ``periodic_orbits`` finds the
one-impact orbits by Newton's method from guesses (:func:`~impactbar.laws.rock_periodic_orbits`): there is no
phase equation (the law's ``phase_roots`` and ``orbit`` raise ``LawNotSupported``, a
``ValueError``, naming them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._shared.threads import single_threaded_blas
from .._shared.validate import check_real
from .base import ContactLaw

__all__ = ["BilinearRock", "RodRock", "RodSegment", "rock_periodic_orbits", "single_blow"]


@dataclass(frozen=True)
class RodSegment:
    """A uniform piece of the rod (theory §4d).

    Parameters
    ----------
    length : float
        In piston lengths, ``> 0``.
    impedance : float
        ``E A / C`` relative to the piston's, ``> 0``.
    wave_speed : float
        Relative to the piston's, ``> 0``; default 1 (the same material).

    Examples
    --------
    >>> from impactbar import RodSegment
    >>> RodSegment(length=40.0, impedance=1.0)  # the wave speed defaults to the piston's
    RodSegment(length=40.0, impedance=1.0, wave_speed=1.0)
    """

    length: float
    impedance: float
    wave_speed: float = 1.0

    def __post_init__(self) -> None:
        for name in ("length", "impedance", "wave_speed"):
            object.__setattr__(self, name, check_real(name, getattr(self, name), lo=0.0, lo_open=True))

    def travel_time(self, model) -> float:
        """Time a wave takes to cross the segment (model time): ``length / (wave_speed s)``."""
        return self.length / (self.wave_speed * model.s)


@dataclass(frozen=True)
class BilinearRock:
    """Lundberg's bilinear bit-rock law (Lundberg 1982; Karlsson, Lundberg and Sundin 1989): the force
    grows as ``k p`` with the penetration ``p`` while it grows past its largest value, and follows
    ``k_u (p - p_perm)`` on unloading and reloading below it, with ``p_perm = p_max - R_max / k_u``;
    the force is compressive only (the bit lifts off for ``p < p_perm``).

    Parameters
    ----------
    k : float
        Loading stiffness (model units of force per length, ``K / (m Omega^2)``), ``> 0``.
    k_u : float
        Unloading stiffness, ``k_u >= k`` (``gamma = k_u / k``).

    Examples
    --------
    >>> from impactbar import BilinearRock
    >>> BilinearRock(k=2.5, k_u=25.0)
    BilinearRock(k=2.5, k_u=25.0)
    """

    k: float
    k_u: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "k", check_real("k", self.k, lo=0.0, lo_open=True))
        object.__setattr__(self, "k_u", check_real("k_u", self.k_u, lo=self.k))

    @property
    def gamma(self) -> float:
        """``k_u / k >= 1``."""
        return self.k_u / self.k


@dataclass(frozen=True)
class RodRock(ContactLaw):
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
        trip of a wave through piston and rod after it.

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

    name = "rodrock"
    instantaneous = False
    rigid_closed_forms = False
    supports_schur = False
    flight_starts_on_stop = False
    uses_restitution = False

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
        if self.blow_time is not None:
            object.__setattr__(self, "blow_time",
                               check_real("blow_time", self.blow_time, lo=0.0, lo_open=True))

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
            A bar under this law.

        Returns
        -------
        BarModel
            ``model`` with ``impact="paper"`` and that ``R``.
        """
        return model.with_(impact="paper", R=_equivalent_restitution(model))

    def window(self, model) -> float:
        """Duration of the blow in the simulator and in periodic orbits (model time): ``blow_time``,
        by default ``4/s + 2 sum of the segments' travel times``, rounded up to whole steps of the
        blow's cell grid (the simulator's blow lasts whole steps, so the orbits' flights start
        where its flights do)."""
        from ..dynamics.rockcontact import _grid_for
        from ..dynamics.rodrock import whole_steps

        T = self.blow_time
        if T is None:
            T = 4.0 / model.s + 2.0 * sum(g.travel_time(model) for g in self.segments)
        segs = self.segments
        dt = _grid_for(float(model.s), tuple(g.length for g in segs), tuple(g.impedance for g in segs),
                       tuple(g.wave_speed for g in segs), None).cell_time
        return whole_steps(T, dt) * dt

    def impact_map(self, model, load, t, y_minus):
        """The contact step as a map of the arrival state (theory §4d): ``y_plus`` the state
        :meth:`window` after the impact (positions from the advanced shank), with its Jacobians by
        **central finite differences** (the blow on the cell grid is piecewise smooth in the state:
        smooth while the piston does not hit the shank again inside the blow): steps
        ``h = 1e-6 max(1, |y_minus|_inf)`` in every state component and ``h_t = 1e-6`` in ``t``
        (truncation ``O(h^2)``, rounding ``O(eps/h)``: about 1e-10 relative), ``4 N + 6`` blows.

        Returns
        -------
        y_plus : numpy.ndarray, shape (2 N + 2,)
        jac_y : numpy.ndarray, shape (2 N + 2, 2 N + 2)
        jac_t : numpy.ndarray, shape (2 N + 2,)
        """
        from ..dynamics.rockcontact import BlowMap

        y = np.array(y_minus, dtype=float)
        t = float(t)
        step = BlowMap(model, load, t)
        y_plus = step(y)
        h = 1e-6 * max(1.0, float(np.max(np.abs(y))))
        jac = np.empty((y.size, y.size))
        for j in range(y.size):
            e = np.zeros(y.size)
            e[j] = h
            jac[:, j] = (step(y + e) - step(y - e)) / (2.0 * h)
        ht = 1e-6
        jt = (BlowMap(model, load, t + ht)(y) - BlowMap(model, load, t - ht)(y)) / (2.0 * ht)
        return y_plus, jac, jt

    def periodic_orbits(self, model, load):
        """The one-impact orbits, by :func:`find_orbit` from the paper law's orbits and a settled
        simulation as guesses (:func:`~impactbar.laws.rock_periodic_orbits`; there is no
        phase equation: the blow map is numerical). :func:`~impactbar.periodic_orbits` calls it.

        Returns
        -------
        OrbitList
        """
        return rock_periodic_orbits(model, load)

    def blow(self, model, load, t, y_minus):
        """The blow of an arrival at load time ``t`` in state ``y_minus`` (shape ``(2 N + 2,)``)
        with the drive acting: the record of :meth:`contact`."""
        M = model.n_modes + 1
        c = model.end_weights
        qm = np.array(y_minus[:M], dtype=float)
        qm[0] -= float(c @ qm)  # the end exactly on the shank (rounding)
        return self.contact(model, load, t, qm, np.array(y_minus[M:], dtype=float))[3]

    def contact(self, model, load, t, q_minus, v_minus, *, kernel=None):
        """The simulator's contact step (theory §4d): the piston's modal state at impact -> the blow
        by characteristics on the piston and the rod with the drive's force, averaged over each
        cell step, on the piston's far end (the compiled rock kernel) -> the piston's fields at the
        blow's end projected on the modes; the rod then rests on the rock (its residual waves
        discarded, counted in the energy the piston lost), the shank advanced by the blow's
        permanent penetration, from which the next flight's positions are measured
        (:func:`impactbar.dynamics.rockcontact.rock_contact`; ``kernel`` is not used).

        Returns
        -------
        q_after, v_after : numpy.ndarray, shape (N + 1,)
        t_release : float
            ``t + duration`` of the blow.
        record : RockContact
            Work on rock, penetrations, efficiencies (those of its :class:`Blow`), the piston's
            energy balance.
        """
        from ..dynamics.rockcontact import rock_contact

        rec = rock_contact(model, load, float(t), q_minus, v_minus)
        return rec.q_after.copy(), rec.v_after.copy(), float(t) + rec.duration, rec


def single_blow(model, impact_velocity: float, *, cells_per_piston: int | None = None,
                t_max: float | None = None, energy_fraction: float = 1e-9, record_field: bool = False):
    """One blow of the piston on the rod and rock of ``model.law`` (theory §4d).

    Assumed: the piston (the model's bar: length 1, impedance ``s``, mass 1) moves rigidly and
    unstressed at ``impact_velocity`` when it touches the shank; no drive acts during the blow (the
    feed force acts on the shank); the rod is at rest, compressed by the feed, the bit resting on
    fresh rock loaded to the feed force. The model's ``R`` and ``d`` play no part (the rod replaces
    the restitution; the blow is undamped), nor its flexible modes (the piston is unstressed at
    impact). Solved by characteristics on a common cell grid, exact for commensurate segments
    (:mod:`impactbar.dynamics.rodrock`; a compiled loop, ``"rock.blow"`` in
    :mod:`impactbar.dynamics.implementations`).

    Parameters
    ----------
    model : BarModel
        With ``impact=RodRock(...)``.
    impact_velocity : float
        ``> 0``, in the model's velocity unit ``L Omega``.
    cells_per_piston, t_max, energy_fraction, record_field
        See :func:`impactbar.dynamics.rodrock.rod_rock_blow`: the grid, the longest blow, the end
        criterion (piston separated and the rod's wave energy below this fraction of the impact
        energy) and whether to keep the force field for the Lagrange diagram.

    Returns
    -------
    Blow
        Work on rock, efficiencies, penetrations, force histories, the energy account.

    Examples
    --------
    >>> from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow
    >>> law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)],
    ...               rock=BilinearRock(k=2.5, k_u=25.0))
    >>> blow = single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law), 1.0, t_max=39.0)
    >>> round(blow.efficiency, 6), round(blow.work_on_rock, 6)  # of the impact energy 1/2
    (0.733069, 0.366534)
    """
    from ..dynamics.rodrock import rod_rock_blow

    law = model.law
    if not isinstance(law, RodRock):
        raise ValueError(f"single_blow needs a model with impact=RodRock(...); got impact={model.impact!r}")
    V = check_real("impact_velocity", impact_velocity, lo=0.0, lo_open=True)
    if t_max is None:
        t_max = 20.0 * (1.0 / model.s + sum(g.travel_time(model) for g in law.segments))
    segs = law.segments
    return rod_rock_blow(
        model.s, V, [g.length for g in segs], [g.impedance for g in segs], [g.wave_speed for g in segs],
        law.rock.k, law.rock.k_u, law.bit_mass, law.feed, cells_per_piston=cells_per_piston,
        t_max=float(t_max), energy_fraction=check_real("energy_fraction", energy_fraction, lo=0.0),
        record_field=record_field)


def lundberg_efficiency(alpha: float, gamma: float) -> float:
    """Lundberg's efficiency of a rectangular incident wave on a massless bit and bilinear rock:
    ``(2/alpha)(1 - e^-alpha)^2 (1 - 1/gamma)`` (theory §4d)."""
    return 2.0 / alpha * (-math.expm1(-alpha)) ** 2 * (1.0 - 1.0 / gamma)


# ------------------------------------------------------------------------------------------------
# one-impact orbits by Newton from guesses (periodic_orbits under this law)
# ------------------------------------------------------------------------------------------------
_TWO_PI = 2.0 * math.pi
_SETTLE_PERIODS = 60  # load periods of the simulation guess


def _equivalent_restitution(model) -> float:
    """``-rebound_velocity / V`` of a rigid piston's blow at ``V = 1`` on the model's rod and rock,
    clipped to ``[0, 0.95]``: the restitution of the paper-law guesses."""
    blow = single_blow(model, 1.0)
    return min(0.95, max(0.0, -float(blow.rebound_velocity)))


def _paper_guesses(model, load):
    from ..orbits import periodic_orbits

    law = model.law
    paper = law.paper_equivalent(model)
    T = law.window(model)
    guesses = []
    for o in sorted(periodic_orbits(paper, load), key=lambda o: (not o.stable, o.phase)):
        if not np.isfinite(o.phase):
            continue
        q, v = o.modal_state(np.array([T]))
        guesses.append((np.array([o.phase]), np.concatenate((q[:, 0], v[:, 0]))[None, :]))
    return guesses


def _simulated_guess(model, load):
    from ..simulation import InitialState, simulate

    try:
        tr = simulate(model, load, InitialState.rigid(-0.1, 0.0, n_modes=model.n_modes),
                      _TWO_PI * _SETTLE_PERIODS)
    except ValueError:
        return None
    ti = np.asarray(tr.impact_times)
    if ti.size < 4 or not np.allclose(np.diff(ti[-4:]), _TWO_PI, atol=1e-3):
        return None
    return tr


def rock_periodic_orbits(model, load):
    """The one-impact orbits under the rod-rock law, by Newton's method from guesses (theory §4d):
    :func:`~impactbar.periodic_orbits` for a model with ``impact=RodRock(...)``.

    The blow is a numerical map (characteristics on the cell grid,
    :meth:`~impactbar.RodRock.impact_map`), so there is no closed-form phase equation to search:
    each orbit is found by :func:`~impactbar.find_orbit` (one impact in one period, the flight's
    start ``q_0`` among the unknowns) from two kinds of guesses:

    1. the paper law's one-impact orbits of the same bar and load (``periodic_orbits`` with
       ``impact="paper"``) with the restitution of a rigid piston's blow on this rod and rock,
       ``R = -rebound_velocity / V`` at ``V = 1`` (clipped to ``[0, 0.95]``), each taken at its
       phase with the state it has ``blow_time`` after the impact (where this law's flight starts);
    2. where none of those gives a stable orbit, the end of a simulation from rest (60 load
       periods), if it has settled to one blow per period.

    Orbits found twice (phases within ``1e-7``) are kept once. Guesses from which Newton does not
    converge give nothing: the list holds the orbits found, not a certified set of all of them.

    Parameters
    ----------
    model : BarModel
        With ``impact=RodRock(...)``.
    load : Load
        Of period ``2 pi``.

    Returns
    -------
    OrbitList
        Sorted by phase; each a :class:`~impactbar.PeriodicOrbit` of :func:`~impactbar.find_orbit`
        (multipliers of the finite-difference impact map, admissibility, one ``RockContact`` per
        blow in ``contacts``). Empty when no guess converges.

    Examples
    --------
    >>> import impactbar as ib
    >>> law = ib.RodRock(segments=[ib.RodSegment(length=10.0, impedance=2.0)],
    ...                  rock=ib.BilinearRock(k=60.0, k_u=1e6), blow_time=2.0)
    >>> model = ib.BarModel(s=10.0, d=0.3, R=0.0, n_modes=0, impact=law)
    >>> load = ib.PiecewiseConstantLoad([0.0, 1.0, 3.0], [-1.0, 2.0, 0.0])
    >>> orbits = ib.periodic_orbits(model, load)  # calls rock_periodic_orbits
    >>> [(round(o.phase, 4), o.stable) for o in orbits]
    [(2.6008, False), (3.5461, True)]
    """
    from ..orbits import find_orbit
    from ..orbits.one_impact import OrbitList

    found = []
    starts = _paper_guesses(model, load)
    with single_threaded_blas():
        for guess in [*starts, None]:
            if guess is None:
                if any(o.stable for o in found):
                    break
                guess = _simulated_guess(model, load)
                if guess is None:
                    break
            try:
                orbit = find_orbit(model, load, 1, 1, guess=guess)
            except ValueError:
                continue
            if all(abs(math.remainder(orbit.phase - o.phase, _TWO_PI)) > 1e-7 for o in found):
                found.append(orbit)
    out = OrbitList(sorted(found, key=lambda o: o.phase))
    out._families = ()
    return out
