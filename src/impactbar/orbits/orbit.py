"""The periodic orbit: ``m`` impacts in ``n`` load periods, with its stability (paper Sections 2, 3;
theory §4, §5, §7).

One type for every periodic motion the library finds: :func:`~impactbar.periodic_orbits` gives the
one-impact orbits (``m = n = 1``, with the phase equation's multiplicity and the paper's Schur
criterion), :func:`~impactbar.find_orbit` and the continuation any ``m`` and ``n``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from .._shared import tables as _tables
from .._shared.schema import END_MOTION, SI, Field, Schema
from ..laws.abilities import BlowRecords, require

if TYPE_CHECKING:
    from .._shared.status import Admissibility
    from ..laws.wave.impact import WaveImpact
    from ..loads import Load
    from ..model import BarModel

__all__ = ["PeriodicOrbit", "MultiImpactOrbit", "ORBIT_FIELDS"]

TWO_PI = 2.0 * math.pi

_ONE = "dict_one_impact"  # the view of a one-impact orbit's to_dict (module impactbar._shared.schema)
_DRIFTER = "drifter_branch"  # the columns of a drifter's branch.csv (impactbar.physical.branch_table)

#: The declared fields of a periodic orbit, in order: every view of an orbit is generated from them
#: (:meth:`PeriodicOrbit.to_dict`, :meth:`OrbitList.to_dataframe`, the branch tables, a sweep's
#: variables, the SI results, the CLI's table, the repr). A new field of an orbit is declared here,
#: with the views that show it.
ORBIT_FIELDS = Schema(
    Field("impacts", "impacts per period of the motion, m", "", dtype="i8", views={"dict"}),
    Field("periods", "load periods per period of the motion, n", "", dtype="i8", views={"dict"}),
    Field("period", "duration of one period of the motion (2 pi n; under a drive found with the orbit, "
                    "theory §10)", views={_DRIFTER}),
    Field("impact_times", "load time of each impact", per="impact", element="impact_time",
          views={"dict", "branch"}),
    Field("phase", "phase lag between load and impact cycle, a root of eq. 14", "rad",
          views={_ONE, "table", "sweep", "cli"}, fmt=".5f",
          si=SI("phase_rad", "rad", None, "phase of the load at impact", "phase/rad", ".4f")),
    Field("phases", "load phase of each impact", "rad", per="impact", element="phase",
          views={"dict", "branch", "repr"}, fmt=".4f"),
    Field("multiplicity", "multiplicity of the root (2 at a fold)", "", dtype="i8",
          views={_ONE, "table"}),
    Field("impact_velocity", "velocity of the struck end before impact", views={
          _ONE, "table", "sweep", "si", "cli", _DRIFTER}, label="impact vel.", fmt=".6f",
          si=SI("impact_velocity_m_s", "m/s", "velocity_m_s", None, "v/(m/s)", ".3f")),
    Field("impact_velocities", "velocity of the struck end before each impact", per="impact",
          element="impact_velocity", views={"dict", "branch", "repr"}, fmt=".6g"),
    Field("admissible", "the end stays off the stop between impacts (theory §5)", "", dtype="b1",
          views={"dict", _ONE, "table", "sweep", "si", "branch"}),
    Field("admissibility", "admissible, or why not", "", dtype="U",
          views={"dict", _ONE, "table", "branch", "cli", "repr"}),
    Field("clearance", "largest u(1, t) at a stationary point between impacts",
          views={"dict", _ONE, "table", "branch", "cli"}, fmt=".3e"),
    Field("clearance_error", "bound on the error of clearance", views={"table"}),
    Field("stable", "admissible and every non-trivial |Floquet multiplier| below 1, theory §7", "",
          dtype="b1",
          views={"dict", _ONE, "table", "sweep", "si", "branch", "cli", "repr", _DRIFTER}),
    Field("max_abs_multiplier", "largest non-trivial |Floquet multiplier|", views={
          "dict", _ONE, "table", "sweep", "si", "branch", "cli", "repr", _DRIFTER}, label="max|mu|",
          fmt=".5f"),
    Field("multipliers", "Floquet multipliers, by decreasing modulus", dtype="c16", per="multiplier",
          element="multiplier", views={"dict", _ONE, "branch"}),
    Field("schur_stable", "the paper's Schur criterion, eqs. 27-31 (theory §6)", "", dtype="b1",
          views={_ONE, "table", "sweep", "cli"}, label="paper"),
    Field("schur_roots", "roots of the paper's quadratic blocks, eqs. 27-31", dtype="c16",
          per="multiplier", views={_ONE}),
    Field("impact_law", "the impact law", "", dtype="U", attr="model.impact", views={_ONE}),
    Field("rod_energy", "energy carried into the rod per blow (theory §4b)", attr="impact.rod_energy",
          views={_ONE}, optional=True),
    Field("peak_force", "peak contact force", attr="impact.peak_force", views={_ONE}, optional=True),
    Field("peak_rod_stress", "peak compressive stress of the transmitted wave",
          attr="impact.peak_rod_stress", views={_ONE}, optional=True),
    Field("efficiency", "energy the blow delivers over the energy available to it: work on the rock with "
                        "one, else the energy carried into the rod", attr="impact.efficiency", views={_ONE},
          optional=True),
    Field("advance", "advance of the rod end per blow", attr="impact.advance", views={_ONE},
          optional=True),
)


@dataclass(frozen=True, eq=False, init=False)
class PeriodicOrbit:
    """A periodic motion with ``impacts`` impacts in ``periods`` load periods, with its stability.

    Orbit time ``t`` is counted from the first impact, which happens at load time
    ``impact_times[0]``; the motion repeats after ``2 pi periods``, and the load acting at orbit time
    ``t`` is ``p(t + impact_times[0])`` (eq. 7). The one-impact orbits of :func:`periodic_orbits`
    (paper Section 2) are the case ``impacts = periods = 1``, ``impact_times[0] = phase``, a root of
    the phase equation (eq. 14); they also carry the root's ``multiplicity`` and the paper's Schur
    criterion (``schur_roots``, ``schur_stable``), which are defined for them only.

    Attributes
    ----------
    model : BarModel
    load : Load
    impacts : int
        ``m``, impacts per period of the motion.
    periods : int
        ``n``, load periods per period of the motion.
    impact_times : numpy.ndarray, shape (m,)
        Load times of the impacts, increasing, the first in ``[0, 2 pi)``, all within
        ``2 pi n`` of it.
    phases : numpy.ndarray, shape (m,)
        ``impact_times mod 2 pi`` (rad): the load phase at each impact (eq. 7).
    impact_velocities : numpy.ndarray, shape (m,)
        ``u_t(1, t-)`` just before the impact at each of ``impact_times`` (dimensionless); > 0 for
        a physical motion.
    admissible : bool
        Every flight stays off the stop (``u(1, t) < 0`` between impacts), the end leaves the stop
        after each impact (for ``R = 0``: its acceleration just after impact points away from the
        stop) and every impact arrives moving forward (theory §5). Decided with certified bounds,
        not sampling.
    admissibility : Admissibility
        ``"admissible"``, or the first reason found on a flight in the order of
        :class:`~impactbar.Admissibility` (``"penetrates"``, ``"backward impact"``, ``"grazing"``,
        ``"sticks"``, ``"separates"``; ``"unchecked"`` where it was not decided); a string.
    clearance : float
        Largest value of ``u(1, t)`` at its stationary points between impacts, over all flights
        (dimensionless): < 0 for an admissible orbit, > 0 where the end swings through the stop,
        ~0 at grazing; may be ``-inf`` where a flight has none.
    clearance_error : float
        Bound on the error of ``clearance`` from the enclosure of the stationary points.
    multipliers : numpy.ndarray of complex, shape (2 N + 2,)
        Exact Floquet multipliers: eigenvalues of the product of the ``m`` impact-map Jacobians,
        each with its saltation term (theory §7), sorted by decreasing modulus.
    stable : bool
        ``admissible`` and every ``|multiplier| < 1 - MARGINAL`` (``1e-9``): a multiplier on the
        unit circle to rounding (e.g. ``R = 1``, ``d = 0``, a conservative map) is marginal, not
        stable, whatever its last bits.
    states_after_impact, states_before_impact : numpy.ndarray, shape (m, 2 N + 2)
        Modal states ``(q_0..q_N, q_0'..q_N')`` just after and just before the impact at each of
        ``impact_times`` (the state before the first impact is the end of the last flight). Under
        the wave law, "after" is at the end of the contact window, where the flight starts.
    contacts : tuple of WaveImpact or None
        Under the wave law (theory §4b): each impact's contact with the rod solved by
        characteristics (force wave ``F(t)``, rod energy, peak stresses, efficiency, advance per
        blow); ``None`` under eq. 10 (an instant impact has no force history), and when
        admissibility was not checked or an impact velocity is not positive.
    multiplicity : int
        Of a one-impact orbit's phase: 1, or 2 for a double root of the phase equation (a fold,
        where two orbits merge); 0 for the orbit that stands for a degenerate family (the phase
        equation holds on an interval, :attr:`OrbitList.families`); 1 for the orbits of
        :func:`find_orbit`.
    schur_roots : numpy.ndarray of complex, shape (2 N + 2,), or None
        One-impact orbits of :func:`periodic_orbits`: roots of the paper's quadratic blocks
        (eqs. 27, 29-31), rigid block first; ``None`` otherwise.
    schur_stable : bool or None
        The paper's criterion (Schur's conditions, eq. 28) on every block; ignores admissibility.
        ``None`` where ``schur_roots`` is.

    Notes
    -----
    Under the wave law (``model.impact == "wave"``) impact ``j`` starts at ``impact_times[j]`` and
    lasts :attr:`window` ``= 2/s``; the flight after it lasts the interval to the next impact less
    ``2/s``. Positions are measured from the rod end, which each blow advances. The multipliers are
    those of the wave law's impact map (theory §7, §4b); ``schur_roots`` and ``schur_stable`` remain
    the paper's criterion for its eq. 10.

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, periodic_orbits
    >>> orbit = periodic_orbits(BarModel(s=3.0, d=0.0, R=0.6, n_modes=0), CosineLoad(0.9, 1.0))[1]
    >>> orbit.impacts, orbit.periods
    (1, 1)
    >>> round(orbit.phase, 4), str(orbit.admissibility), orbit.stable
    (2.3565, 'admissible', True)
    >>> orbit  # a short repr: the motion, its impacts, admissibility and stability
    PeriodicOrbit(1 impact in 1 load period, phase 2.3565, impact velocity 3.53429, admissible,
                  stable, max|mu| 0.60000)
    """

    #: the declared fields (:data:`ORBIT_FIELDS`), from which every view of the orbit is generated
    fields: ClassVar[Schema] = ORBIT_FIELDS

    def __init__(self, model: BarModel, load: Load, impacts: int, periods: int, impact_times: np.ndarray,
                 phases: np.ndarray, impact_velocities: np.ndarray, admissible: bool,
                 admissibility: Admissibility | str, clearance: float, clearance_error: float,
                 multipliers: np.ndarray, stable: bool, states_after_impact: np.ndarray,
                 states_before_impact: np.ndarray, contacts: tuple | None = None,
                 multiplicity: int = 1, schur_roots: np.ndarray | None = None,
                 schur_stable: bool | None = None) -> None:
        # every attribute set at once: the generated __init__ of a frozen dataclass sets them one
        # by one through object.__setattr__, 3 us more per orbit (measured; 6 % of periodic_orbits
        # on a rigid bar, whose closed forms take some 100 us)
        vars(self).update(
            model=model, load=load, impacts=impacts, periods=periods, impact_times=impact_times,
            phases=phases, impact_velocities=impact_velocities, admissible=admissible,
            admissibility=admissibility, clearance=clearance, clearance_error=clearance_error,
            multipliers=multipliers, stable=stable, states_after_impact=states_after_impact,
            states_before_impact=states_before_impact, contacts=contacts, multiplicity=multiplicity,
            schur_roots=schur_roots, schur_stable=schur_stable)

    model: BarModel
    load: Load
    impacts: int
    periods: int
    impact_times: np.ndarray = field(repr=False)
    phases: np.ndarray
    impact_velocities: np.ndarray
    admissible: bool
    admissibility: Admissibility | str
    clearance: float
    clearance_error: float
    multipliers: np.ndarray = field(repr=False)
    stable: bool
    states_after_impact: np.ndarray = field(repr=False)
    states_before_impact: np.ndarray = field(repr=False)
    contacts: tuple[WaveImpact, ...] | None = field(default=None, repr=False)
    multiplicity: int = 1
    schur_roots: np.ndarray | None = field(default=None, repr=False)
    schur_stable: bool | None = None

    @classmethod
    def one_impact(cls, *, model: BarModel, load: Load, phase: float, multiplicity: int,
                   impact_velocity: float, admissible: bool, admissibility: str, clearance: float,
                   clearance_error: float, multipliers: np.ndarray, stable: bool,
                   schur_roots: np.ndarray, schur_stable: bool, state_after_impact: np.ndarray,
                   state_before_impact: np.ndarray, impact: WaveImpact | None = None) -> PeriodicOrbit:
        """The one-impact orbit (``m = n = 1``) from its scalar description (paper Section 2).

        Parameters
        ----------
        phase : float
            The root of the phase equation (eq. 14) in ``[0, 2 pi)`` (rad).
        impact_velocity : float
            ``u_t(1, 2 pi-)``.
        state_after_impact, state_before_impact : numpy.ndarray, shape (2 N + 2,)
            Modal states at ``t = 0+`` (wave law: at the end of the window) and ``t = 2 pi-``.
        impact : WaveImpact or None
            The contact under the wave law.
        model, load, multiplicity, admissible, admissibility, clearance, clearance_error, \
multipliers, stable, schur_roots, schur_stable
            As the attributes.
        """
        return cls(model, load, 1, 1, np.array([phase]), np.array([phase]), np.array([impact_velocity]),
                   admissible, admissibility, clearance, clearance_error, multipliers, stable,
                   np.asarray(state_after_impact)[None, :], np.asarray(state_before_impact)[None, :],
                   None if impact is None else (impact,), multiplicity, schur_roots, schur_stable)

    # -- the short repr -------------------------------------------------------------------------------
    def __repr__(self) -> str:
        """One line: the motion (impacts in load periods), the impacts' phases and velocities, the
        admissibility, the stability and the largest multiplier; the arrays are
        :meth:`to_dict`'s."""
        return f"{type(self).__name__}({', '.join(self._repr_items())})"

    def _repr_items(self) -> list[str]:
        """The items of the repr, in order; a subclass extends the list (its own numbers)."""
        m, n = self.impacts, self.periods
        return [f"{m} impact{'s' if m != 1 else ''} in {n} load period{'s' if n != 1 else ''}",
                *self.fields.select("repr").summary(self)]

    # -- the first impact, and the one-impact conveniences -------------------------------------------
    @property
    def phase(self) -> float:
        """Load phase of the first impact, ``phases[0]`` (rad); for a one-impact orbit the root of
        the phase equation (eq. 14)."""
        return float(self.phases[0])

    @property
    def impact_velocity(self) -> float:
        """Velocity of the struck end before the first impact, ``impact_velocities[0]``."""
        return float(self.impact_velocities[0])

    @property
    def state_after_impact(self) -> np.ndarray:
        """Modal state just after the first impact, shape ``(2 N + 2,)``."""
        return self.states_after_impact[0].copy()

    @property
    def state_before_impact(self) -> np.ndarray:
        """Modal state just before the first impact (the end of the last flight), shape
        ``(2 N + 2,)``."""
        return self.states_before_impact[0].copy()

    @property
    def impact(self) -> WaveImpact | None:
        """The first impact's contact with the rod under the wave law (``contacts[0]``), ``None``
        under eq. 10."""
        return None if self.contacts is None else self.contacts[0]

    @property
    def window(self) -> float:
        """Duration of each impact, the law's window: ``2/s`` under the wave law (theory §4b), 0
        under eq. 10."""
        return self.model.law.window(self.model)

    @property
    def period(self) -> float:
        """Duration of one period of the motion, ``2 pi n``."""
        return TWO_PI * self.periods

    @property
    def max_abs_multiplier(self) -> float:
        """Largest ``|multiplier|`` (spectral radius of the impact map's Jacobian)."""
        return float(np.max(np.abs(self.multipliers)))

    @property
    def modal_state_after_impact(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q, q')`` just after the first impact, each shape ``(N + 1,)``: start
        ``simulate(model, load, InitialState(*orbit.modal_state_after_impact), t_end,
        t0=orbit.impact_times[0])`` on the orbit."""
        M = self.model.n_modes + 1
        return self.states_after_impact[0, :M].copy(), self.states_after_impact[0, M:].copy()

    def plot(self, ax=None, n: int = 2000):
        """Draw the end displacement over one period, on ``ax`` (a new figure's axes if omitted)
        at ``n`` times: :func:`impactbar.plotting.plot_orbit`, which returns the axes."""
        from ..plotting.orbits import plot_orbit

        return plot_orbit(self, ax, n)

    # -- the motion ---------------------------------------------------------------------------------
    def modal_state(self, t):
        """Modal displacements and velocities at orbit times ``t`` (from the first impact).

        Parameters
        ----------
        t : array_like, shape (T,)
            Orbit times (dimensionless), taken modulo ``2 pi n``; at an impact time the state just
            after the impact (under the wave law: at the start of contact; inside a window, the
            characteristics solution projected on the modes).

        Returns
        -------
        q, v : numpy.ndarray, shape (N + 1, T)
        """
        t = np.atleast_1d(np.asarray(t, dtype=float)).ravel()
        return self._state_in_period(np.mod(t, self.period))

    def _state_in_period(self, t):
        """State at orbit times ``0 <= t <= 2 pi n`` without wrapping (``2 pi n`` is just before the
        first impact again)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        M = self.model.n_modes + 1
        rel = self.impact_times - self.impact_times[0]
        j = np.clip(np.searchsorted(rel, t, side="right") - 1, 0, self.impacts - 1)
        q = np.empty((M, t.size))
        v = np.empty((M, t.size))
        w2 = self.model.frequencies**2
        Tw = self.window
        inside = (t - rel[j]) < Tw
        if np.any(inside):  # within a wave-law contact window: the characteristics solution
            contacts = self.contacts
            if contacts is None:
                blows = require(self.model.law, BlowRecords, "blow")
                contacts = tuple(blows.blow(self.model, self.load, float(ta), ym) for ta, ym in
                                 zip(self.impact_times, self.states_before_impact, strict=True))
            for i in np.flatnonzero(inside):
                q[:, i], v[:, i] = contacts[j[i]].state_at(t[i] - rel[j[i]])
        for jj in np.unique(j[~inside]):
            sel = (j == jj) & ~inside
            y = self.states_after_impact[jj]
            q[:, sel], v[:, sel] = self.load.propagate(w2, self.model.d, self.impact_times[jj] + Tw,
                                                       y[:M], y[M:], self.impact_times[0] + t[sel])
        return q, v

    def _field(self, x, t, velocity):
        xb, tb = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(t, dtype=float))
        shapes = self.model.shape_functions(xb.ravel())  # (P, M)
        tt, inv = np.unique(tb.ravel(), return_inverse=True)
        q, v = self.modal_state(tt)
        modal = (v if velocity else q)[:, inv]  # (M, P)
        return np.einsum("pm,mp->p", shapes, modal).reshape(xb.shape)

    def displacement(self, x, t) -> np.ndarray:
        """Displacement ``u(x, t)`` (eq. 15), dimensionless.

        Parameters
        ----------
        x : array_like
            Positions in ``[0, 1]``; broadcast against ``t``.
        t : array_like
            Orbit times (periodic with period ``2 pi n``).

        Returns
        -------
        numpy.ndarray, shape ``broadcast(x, t).shape``
        """
        return self._field(x, t, velocity=False)

    def velocity(self, x, t) -> np.ndarray:
        """Velocity ``u_t(x, t)``, same conventions as :meth:`displacement`; at impact times the
        velocity just after the impact."""
        return self._field(x, t, velocity=True)

    def end_displacement(self, t) -> np.ndarray:
        """Displacement of the struck end ``u(1, t)`` at orbit times ``t``, shape of ``t``."""
        t = np.asarray(t, dtype=float)
        q, _ = self.modal_state(t.ravel())
        return (self.model.end_weights @ q).reshape(t.shape)

    # -- conversions --------------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """A JSON-ready summary (floats, lists; multipliers as ``[re, im]``; ``clearance`` may be
        ``-inf``): the fields of :data:`ORBIT_FIELDS` in the view ``"dict_one_impact"`` or
        ``"dict"``.

        A one-impact orbit of :func:`periodic_orbits` (one with ``schur_roots``) gives its scalar
        description (``phase``, ``multiplicity``, ``impact_velocity``, the Schur criterion, the
        impact law and, under the wave law, the contact's rod energy, peak force and stress,
        efficiency and advance); any other orbit ``impacts``, ``periods`` and the arrays
        ``impact_times``, ``phases``, ``impact_velocities``.
        """
        return self.fields.select("dict" if self.schur_roots is None else _ONE).record(self)

    def to_dataframe(self, n: int = 256):
        """The struck end's motion over one period of the motion as a table.

        Parameters
        ----------
        n : int, optional
            Number of orbit times, ``t = 2 pi periods j / n`` for ``j = 0..n`` (the last one just
            before the first impact again). Default 256.

        Returns
        -------
        pandas.DataFrame
            Index ``t`` (orbit time since the first impact), columns ``end_displacement``
            ``u(1, t)`` and ``end_velocity`` ``u_t(1, t)``, all dimensionless (eq. 2); ``attrs``
            holds the model, the load, the phase and each column's ``long_name`` and ``units``.
        """
        n = int(n)
        if n < 1:
            raise ValueError(f"n must be an integer >= 1; got {n}")
        t = np.linspace(0.0, self.period, n + 1)
        q, v = self._state_in_period(t)
        c = self.model.end_weights
        return _tables.frame(
            {"t": t, "end_displacement": c @ q, "end_velocity": c @ v},
            {"t": ("orbit time since the impact", "1"), **END_MOTION.meta()}, index="t",
            attrs=self._attrs())

    def to_xarray(self, nx: int = 51, nt: int = 256):
        """The displacement and velocity fields over one period of the motion as an
        ``xarray.Dataset``.

        Parameters
        ----------
        nx, nt : int, optional
            Grid points along the bar (``x`` in ``[0, 1]``, driven end 0) and in orbit time
            (``t`` in ``[0, 2 pi periods]``). Defaults 51 and 256.

        Returns
        -------
        xarray.Dataset
            ``displacement`` and ``velocity`` with dims ``(t, x)``, dimensionless (eq. 2), each with
            ``long_name`` and ``units``; the model, load and phase in ``attrs``.

        Raises
        ------
        ModuleNotFoundError
            xarray is not installed (extra ``data``).
        """
        nx, nt = int(nx), int(nt)
        if nx < 2 or nt < 2:
            raise ValueError(f"nx and nt must be integers >= 2; got {nx}, {nt}")
        x = np.linspace(0.0, 1.0, nx)
        t = np.linspace(0.0, self.period, nt)
        q, v = self._state_in_period(t)
        shapes = self.model.shape_functions(x)  # (X, M)
        tt, xx = np.meshgrid(t, x, indexing="ij")  # rows in (t, x) order, as the fields below
        df = _tables.frame(
            {"t": tt.ravel(), "x": xx.ravel(), "displacement": (q.T @ shapes.T).ravel(),
             "velocity": (v.T @ shapes.T).ravel()},
            {"t": ("orbit time since the impact", "1"), "x": ("position along the bar", "1"),
             "displacement": ("displacement u(x, t)", "1"), "velocity": ("velocity u_t(x, t)", "1")},
            index=["t", "x"], attrs=self._attrs())
        return _tables.to_xarray(df)

    def _attrs(self) -> dict:
        m = self.model
        return {"model": repr(m), "load": repr(self.load), "phase": self.phase, "s": m.s, "d": m.d,
                "R": m.R, "n_modes": m.n_modes}


#: The name :func:`find_orbit` results had before the two orbit types were one: the same class.
MultiImpactOrbit = PeriodicOrbit
