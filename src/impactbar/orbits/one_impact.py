"""One-impact periodic orbits from the law's phase equation (paper Section 2, theory §4, §5, §7).

``phase_equation_orbits(model, load)`` finds every root ``phase`` of the law's phase equation
(eq. 14 under the paper's law), takes the orbit's modal states and exact Floquet multipliers from
the law, decides admissibility rigorously, and adds the paper's Schur criterion.
:func:`~impactbar.periodic_orbits` (:mod:`impactbar.orbits.find`) calls it for a law with a
phase equation, and Newton's method from guesses for one without.
"""

from __future__ import annotations

import math

import numpy as np

from .._shared import tables as _tables
from .._shared.schema import Field, Schema
from .._shared.status import Admissibility
from .._shared.threads import single_threaded_blas
from ..dynamics.implementations import use_fast
from ..laws.abilities import PhaseEquation, require
from ..loads import Load
from ..model import BarModel
from .admissibility import _admissibility, _window_departure
from .orbit import PeriodicOrbit
from .phase import _check_inputs
from .rigid import STATUS, rigid_cosine_orbits, rigid_square_orbits
from .stability import quadratic_roots, schur_blocks, schur_test, stable_verdict

__all__ = ["PeriodicOrbit", "phase_equation_orbits", "orbit_multipliers"]

TWO_PI = 2.0 * math.pi

#: the columns of :meth:`OrbitList.to_dataframe`: the orbit's fields in the view ``"table"``
#: (:data:`impactbar.orbits.orbit.ORBIT_FIELDS`), then the model's numbers (and the load, as text)
ORBIT_COLUMNS = PeriodicOrbit.fields.select("table") + Schema(
    *(Field(f.name, f.long_name, f.units, f.dtype, attr=f"model.{f.name}") for f in BarModel.parameters))


class OrbitList(list):
    """The list of :class:`PeriodicOrbit` that :func:`periodic_orbits` returns: a plain ``list``
    (indexing, iteration, ``len``, comparison with lists) with conversions to tables.

    Attributes
    ----------
    families : tuple of (float, float)
        Intervals of phases on which the phase equation holds identically (a degenerate family:
        a continuum of orbits, e.g. under the wave law,
        :func:`impactbar.laws.wave.periodic.wave_phase_families`); each is stood for in the list by one
        orbit at the interval's middle, with ``multiplicity = 0``. Empty for isolated orbits only.
    window : (float, float) or None
        Under a drive (:func:`~impactbar.orbits.drive_orbits`): the window of periods
        searched; ``None`` under a load (the load's period is given).
    certified : tuple of bool
        Under a drive: per orbit, whether the search proved it the only root in a box around it
        (empty under a load, whose search is certified throughout).
    unresolved : tuple of (float, float, str)
        Under a drive: the intervals of periods the search could not decide, with the reason
        (empty: every root in the window is listed).

    Methods
    -------
    to_dataframe()
        One row per orbit.
    to_xarray()
        The same as an ``xarray.Dataset`` along the dimension ``orbit``.
    """

    __slots__ = ("_families", "_window", "_certified", "_unresolved")

    @property
    def families(self) -> tuple:
        """``((start, end), ...)``: the degenerate families' phase intervals (rad); empty when the
        list holds isolated orbits only."""
        return getattr(self, "_families", ())

    @property
    def window(self) -> tuple | None:
        """The window of periods searched under a drive (``None`` under a load)."""
        return getattr(self, "_window", None)

    @property
    def certified(self) -> tuple:
        """Per orbit under a drive, whether it is certified the only root in a box around it."""
        return getattr(self, "_certified", ())

    @property
    def unresolved(self) -> tuple:
        """Under a drive, the period intervals the search could not decide, with the reason."""
        return getattr(self, "_unresolved", ())

    @property
    def degenerate(self) -> bool:
        """Whether the list holds a degenerate family (:attr:`families` not empty)."""
        return bool(self.families)

    def __repr__(self) -> str:
        """A line for the list, then one per orbit (the orbits' short reprs; at most 12)."""
        if not self:
            return "OrbitList([])"
        fam = f", {len(self.families)} degenerate famil{'ies' if len(self.families) > 1 else 'y'}" \
            if self.families else ""
        lines = [f"OrbitList of {len(self)} orbit{'s' if len(self) > 1 else ''}{fam}:"]
        lines += [f"  {o!r}" for o in self[:12]]
        if len(self) > 12:
            lines.append(f"  ... and {len(self) - 12} more")
        return "\n".join(lines)

    def to_dataframe(self):
        """One row per orbit: phase, impact velocity, admissibility, clearance, stability.

        Returns
        -------
        pandas.DataFrame
            Index ``orbit`` (0, 1, ... in order of phase), the columns of :data:`ORBIT_COLUMNS`:
            the orbit's, the model's ``s``, ``d``, ``R``, ``n_modes`` and the ``load`` (as text), so
            frames of several models concatenate; ``attrs["columns"]`` gives each column's
            ``long_name`` and ``units`` (dimensionless numbers have units ``"1"``, eq. 2).
        """
        loads = [repr(o.load) for o in self] or np.zeros(0, dtype=object)
        return ORBIT_COLUMNS.frame(self, index="orbit", index_meta=("orbit number, in order of phase", "1"),
                                   extra={"load": loads}, extra_meta={"load": ("the load", "")})

    def to_xarray(self):
        """:meth:`to_dataframe` as an ``xarray.Dataset`` along ``orbit``, every variable with
        ``long_name`` and ``units``.

        Raises
        ------
        ModuleNotFoundError
            xarray is not installed (extra ``data``).
        """
        return _tables.to_xarray(self.to_dataframe())


def phase_equation_orbits(model: BarModel, load: Load) -> OrbitList:
    """The one-impact orbits from the law's phase equation (:func:`~impactbar.periodic_orbits` for a
    law with the ability :class:`~impactbar.laws.abilities.PhaseEquation`): each root ``phase`` of
    the phase equation (eq. 14 under the paper's law) in ``[0, 2 pi)`` gives one orbit, whose states
    and multipliers the law computes (:meth:`~impactbar.laws.abilities.PhaseEquation.orbit_state`)
    and whose admissibility is decided here; the rigid bar under the paper's law in closed form.

    Parameters
    ----------
    model : BarModel
    load : Load
        Any load of period ``2 pi``.

    Returns
    -------
    OrbitList
        As :func:`~impactbar.periodic_orbits`.

    Raises
    ------
    ValueError
        For inputs of the wrong type, at an undamped resonance ``s n pi = k`` (eq. 16), or under a
        law without a phase equation (``LawNotSupported``).
    """
    _check_inputs(model, load)
    _check_modes(model)
    fast = _rigid_orbits(model, load)
    if fast is not None:
        return fast
    return _periodic_orbits_general(model, load)


def _periodic_orbits_general(model: BarModel, load: Load) -> OrbitList:
    """:func:`periodic_orbits` by the general path (certified searches, any model and load): the
    reference every fast path is tested against."""
    _check_inputs(model, load)
    phase = require(model.law, PhaseEquation, "phase_roots")
    families = tuple(phase.phase_families(model, load))
    with single_threaded_blas():
        roots = list(phase.phase_roots(model, load))
        roots += [((0.5 * (lo + hi)) % TWO_PI, 0) for lo, hi in families]  # one orbit each
        out = OrbitList(_one_impact_orbit(model, load, ph, mult) for ph, mult in sorted(roots))
    out._families = families
    return out


#: Largest ``n_modes`` for the orbit functions: the multipliers are the eigenvalues of a dense
#: ``(2 N + 2)``-square Jacobian, O(N^3); beyond this they do not come in bounded time.
MAX_ORBIT_MODES = 1024


def _check_modes(model: BarModel) -> None:
    if model.n_modes > MAX_ORBIT_MODES:
        raise ValueError(f"model.n_modes must be at most {MAX_ORBIT_MODES} for one-impact orbits "
                         f"(dense Floquet multipliers, O(n_modes^3)); got {model.n_modes}")


# single points of the rigid bar take the closed forms in plain floats (``orbits/_rigid_scalar.py``);
# the reference of "orbits.rigid_scalar" (dynamics.implementations) is the vectorised numpy closed forms


def _rigid_orbits(model: BarModel, load: Load) -> OrbitList | None:
    """The rigid bar under one cosine harmonic or the square wave in closed form
    (:mod:`impactbar.orbits.rigid`), or ``None`` where that does not apply (flexible modes, another
    load, a degenerate orbit)."""
    if model.n_modes != 0 or not model.law.traits.rigid_closed_forms:
        return None
    form = load.abilities.square
    if form is not None:
        _, kappa, *_ = form
        if not kappa < 2.0:  # kappa = 2: a constant load, the general path
            return None
        args, square = (model.d, model.R, *form), True
    else:
        form = load.abilities.cosine
        if form is None:
            return None
        _, pk, *_ = form
        if pk == 0.0:  # pk = 0: a constant load, the general path
            return None
        args, square = (model.d, model.R, *form), False
    if use_fast("orbits.rigid_scalar"):
        from . import _rigid_scalar

        found = (_rigid_scalar.square_orbits if square else _rigid_scalar.cosine_orbits)(*args)
        if found is None:
            return None
        return OrbitList(_rigid_orbit(model, load, o.phase, o.multiplicity, o.impact_velocity, o.status,
                                      o.clearance, o.clearance_error, np.array(o.multipliers),
                                      o.stable, np.array(o.schur_roots), o.schur_stable, o.v_plus,
                                      o.q_minus) for o in found)
    res = (rigid_square_orbits if square else rigid_cosine_orbits)(*args)
    if res.fallback[0]:
        return None
    return OrbitList(_rigid_orbit(
        model, load, float(res.phase[0, j]), int(res.multiplicity[0, j]),
        float(res.impact_velocity[0, j]), int(res.status[0, j]), float(res.clearance[0, j]),
        float(res.clearance_error[0, j]), res.multipliers[0, j].copy(), bool(res.stable[0, j]),
        res.schur_roots[0, j].copy(), bool(res.schur_stable[0, j]), float(res.v_plus[0, j]),
        float(res.q_minus[0, j])) for j in range(int(res.n_orbits[0])))


def _rigid_orbit(model, load, phase, multiplicity, impact_velocity, status, clearance, clearance_error,
                 multipliers, stable, schur_roots, schur_stable, v_plus, q_minus) -> PeriodicOrbit:
    """A rigid bar's :class:`PeriodicOrbit` from the closed forms' numbers (``status`` indexes
    ``rigid.STATUS``)."""
    name = STATUS[status]
    return PeriodicOrbit.one_impact(
        model=model, load=load, phase=phase, multiplicity=multiplicity,
        impact_velocity=impact_velocity, admissible=name == Admissibility.ADMISSIBLE, admissibility=name,
        clearance=clearance, clearance_error=clearance_error, multipliers=multipliers,
        stable=stable, schur_roots=schur_roots, schur_stable=schur_stable,
        state_after_impact=np.array([-0.0, v_plus]),
        state_before_impact=np.array([q_minus, impact_velocity]),
    )


def orbit_multipliers(model: BarModel, load: Load, phase: float, *, paper: bool = False) -> np.ndarray:
    """Floquet multipliers of the orbit with this phase, without the admissibility check.

    Parameters
    ----------
    model : BarModel
    load : Load
    phase : float
        A root of the phase equation (rad).
    paper : bool
        Return the roots of the paper's quadratic blocks (eqs. 27-31) instead of the exact
        multipliers (theory §7).

    Returns
    -------
    numpy.ndarray of complex, shape (2 N + 2,)
    """
    _check_inputs(model, load)
    _check_modes(model)
    if paper:
        return quadratic_roots(schur_blocks(model, load, phase))
    return require(model.law, PhaseEquation, "multipliers").multipliers(model, load, phase)


def _one_impact_orbit(model: BarModel, load: Load, phase: float, mult: int) -> PeriodicOrbit:
    """The one-impact orbit at a root ``phase`` of the law's phase equation: the law's states and
    multipliers (:meth:`~impactbar.laws.abilities.PhaseEquation.orbit_state`), its admissibility
    decided here with certified bounds over the flight (theory §5; for a law whose impact lasts a
    window, the flight from the window's end, and the departure at the window's end), the paper's
    Schur criterion (eqs. 27-31)."""
    law = model.law
    st = require(law, PhaseEquation, "orbit_state").orbit_state(model, load, phase)
    M = model.n_modes + 1
    y_plus, y_minus = st.state_after_impact, st.state_before_impact
    c = model.end_weights
    v_imp = float(c @ y_minus[M:])
    T = law.window(model)
    if T == 0.0:  # the flight starts at the impact
        status, clearance, cerr = _admissibility(model, load, phase, y_plus, v_imp, flow=st.flow)
    else:  # the flight starts where the window closes: the end must leave the stop there
        v_dep = float(c @ y_plus[M:])
        scale = max(abs(v_imp), load.sup_abs, 1e-300)
        at_rest = abs(v_dep) <= 1e-12 * scale
        status, clearance, cerr = _admissibility(model, load, phase + T, y_plus, v_imp,
                                                 horizon=TWO_PI - T, at_rest=at_rest, flow=st.flow)
        status = _window_departure(status, at_rest, v_dep, st.separates)
    admissible = status == Admissibility.ADMISSIBLE
    mu = st.multipliers
    blocks = schur_blocks(model, load, phase)
    return PeriodicOrbit.one_impact(
        model=model, load=load, phase=float(phase), multiplicity=int(mult), impact_velocity=v_imp,
        admissible=admissible, admissibility=status, clearance=clearance, clearance_error=cerr,
        multipliers=mu, stable=stable_verdict(admissible, mu),
        schur_roots=quadratic_roots(blocks), schur_stable=schur_test(blocks),
        state_after_impact=y_plus, state_before_impact=y_minus, impact=st.impact,
    )
