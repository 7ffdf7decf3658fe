"""One-impact periodic orbits (paper Section 2, theory §4, §5, §7).

``periodic_orbits(model, load)`` finds every root ``phase`` of the phase equation (eq. 14),
builds the orbit's modal state, decides admissibility rigorously, and computes the exact Floquet
multipliers and the paper's Schur criterion.
"""

from __future__ import annotations

import math

import numpy as np

from .._shared import tables as _tables
from .._shared.schema import Field, Schema
from .._shared.status import Admissibility
from .._shared.threads import single_threaded_blas
from ..dynamics.implementations import use_fast
from ..loads import FourierLoad, Load
from ..model import BarModel
from .admissibility import _admissibility, _window_departure
from .orbit import PeriodicOrbit
from .phase import _check_inputs
from .rigid import STATUS, rigid_cosine_orbits, rigid_multipliers, rigid_square_orbits
from .stability import (
    floquet_multipliers,
    period_fundamental,
    quadratic_roots,
    schur_blocks,
    schur_test,
    sort_multipliers,
    stable_verdict,
)

__all__ = ["PeriodicOrbit", "periodic_orbits", "orbit_multipliers"]

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
        :func:`impactbar.orbits.wave.wave_phase_families`); each is stood for in the list by one
        orbit at the interval's middle, with ``multiplicity = 0``. Empty for isolated orbits only.

    Methods
    -------
    to_dataframe()
        One row per orbit.
    to_xarray()
        The same as an ``xarray.Dataset`` along the dimension ``orbit``.
    """

    __slots__ = ("_families",)

    @property
    def families(self) -> tuple:
        """``((start, end), ...)``: the degenerate families' phase intervals (rad); empty when the
        list holds isolated orbits only."""
        return getattr(self, "_families", ())

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


def periodic_orbits(model: BarModel, load: Load) -> OrbitList:
    """Every one-impact-per-period steady state of the bar under the load (paper Section 2).

    Each root ``phase`` of the phase equation (eq. 14) in ``[0, 2 pi)`` gives one orbit: the flexible
    modes' start state solves the periodicity and impact conditions (eqs. 10-13) exactly, mode by
    mode; the rigid mode strikes at ``2 pi p0 / (1 + R)`` and its constant is fixed by contact
    ``u(1, 0) = 0``.

    Parameters
    ----------
    model : BarModel
    load : Load
        Any load of period ``2 pi``: ``CosineLoad``, ``SquareWaveLoad``, ``FourierLoad``, ...

    Returns
    -------
    OrbitList
        A ``list`` of :class:`PeriodicOrbit` sorted by phase, empty when none exists (e.g. above the
        fold, eq. 38); ``.to_dataframe()`` and ``.to_xarray()`` make it a table. Where the phase
        equation holds on a whole interval (a degenerate family, wave law), ``.families`` holds
        the interval and one orbit with ``multiplicity = 0`` stands for it, at its middle.

    Raises
    ------
    ValueError
        For inputs of the wrong type, or at an undamped resonance ``s n pi = k`` (eq. 16).

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, periodic_orbits
    >>> orbits = periodic_orbits(BarModel(s=10, d=0, R=0.5, n_modes=4), CosineLoad(0.5, 1.0))
    >>> [round(o.phase, 4) for o in orbits]
    [0.5511, 2.5905]
    """
    _check_inputs(model, load)
    _check_modes(model)
    by_newton = getattr(model.law, "periodic_orbits", None)  # a law without a phase equation
    if by_newton is not None:
        return by_newton(model, load)
    fast = _rigid_orbits(model, load)
    if fast is not None:
        return fast
    return _periodic_orbits_general(model, load)


def _periodic_orbits_general(model: BarModel, load: Load) -> OrbitList:
    """:func:`periodic_orbits` by the general path (certified searches, any model and load): the
    reference every fast path is tested against."""
    _check_inputs(model, load)
    law = model.law
    families = tuple(law.phase_families(model, load))
    with single_threaded_blas():
        roots = list(law.phase_roots(model, load))
        roots += [((0.5 * (lo + hi)) % TWO_PI, 0) for lo, hi in families]  # one orbit each
        out = OrbitList(law.orbit(model, load, ph, mult) for ph, mult in sorted(roots))
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
    if model.n_modes != 0 or not model.law.rigid_closed_forms:
        return None
    square, cosine = load.square_form(), load.cosine_form()
    if square is not None and square[1] < 2.0:  # kappa = 2: a constant load, the general path
        args, square = (model.d, model.R, *square), True
    elif cosine is not None and cosine[1] != 0.0:  # pk = 0: a constant load, the general path
        args, square = (model.d, model.R, *cosine), False
    else:
        return None
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


def _start_state(model: BarModel, load: Load, phase: float) -> np.ndarray:
    """Modal state just after the impact of the orbit with this phase (eqs. 10-13)."""
    N = model.n_modes
    R, d = model.R, model.d
    q = np.zeros(N + 1)
    v = np.zeros(N + 1)
    if N > 0:
        w2 = model.frequencies[1:] ** 2
        p11, p12, p21, p22 = (a[1:] for a in period_fundamental(model))
        if isinstance(load, FourierLoad):  # fast-path guard: the closed-form periodic response
            # the response from rest over one period, (I - Phi(2 pi)) y_p(phase) with y_p the
            # periodic response (what the flow from rest computes, without building it; it also
            # fixes the orbit's last bits, which the general path's propagation would change)
            qp, vp = load.periodic_state(w2, d, [phase])
            qp, vp = qp[:, 0], vp[:, 0]
            fq = qp - (p11 * qp + p12 * vp)
            fv = vp - (p21 * qp + p22 * vp)
        else:
            zeros = np.zeros(N)
            fq, fv = load.propagate(w2, d, phase, zeros, zeros, [phase + TWO_PI])
            fq, fv = fq[:, 0], fv[:, 0]
        # y = J_R (Phi y + f),  J_R = diag(1, -R)
        a11, a12, a21, a22 = 1.0 - p11, -p12, R * p21, 1.0 + R * p22
        det = a11 * a22 - a12 * a21
        if np.any(np.abs(det) < 1e-13):
            if R == 1.0 and d == 0.0:
                raise ValueError("R = 1 with d = 0 and flexible modes: a conservative bar with elastic "
                                 "impacts has a continuum of one-impact orbits, not isolated ones; "
                                 "use d > 0, R < 1 or n_modes = 0")
            raise ValueError("the periodicity conditions are singular (undamped resonance, eq. 16)")
        r1, r2 = fq, -R * fv
        q[1:] = (a22 * r1 - a12 * r2) / det
        v[1:] = (a11 * r2 - a21 * r1) / det
    v[0] = -R * TWO_PI * load.p0 / (1.0 + R)
    q[0] = -float(model.end_weights[1:] @ q[1:])
    return np.concatenate((q, v))


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
    return model.law.multipliers(model, load, phase)


def _paper_multipliers(model: BarModel, load: Load, phase: float) -> np.ndarray:
    """:func:`orbit_multipliers` under the paper's law (eq. 10)."""
    y_plus, y_minus = _impact_states(model, load, phase)
    if model.n_modes == 0:  # the 2 x 2 Jacobian in closed form
        mu = rigid_multipliers(model.d, model.R, float(load(phase)), float(load.left_limit(phase)),
                               y_plus[1], y_minus[1])
        if not np.all(np.isfinite(mu)):
            raise ValueError("grazing impact (zero arrival velocity): the saltation term is infinite")
        return mu
    with single_threaded_blas():
        return floquet_multipliers(model, load, phase, y_plus, y_minus)


def _impact_states(model: BarModel, load: Load, phase: float, return_flow: bool = False):
    """Modal states just after (``t = 0+``) and just before (``t = 2 pi-``) the orbit's impact;
    with ``return_flow``, also the flight's flow (``load.flow`` from ``y_plus``) where it is the
    one that gave ``y_minus`` (a Fourier load; else ``None``), for the admissibility search."""
    M = model.n_modes + 1
    y_plus = _start_state(model, load, phase)
    w2 = model.frequencies**2
    flow = None
    if isinstance(load, FourierLoad):  # fast-path guard: its propagate is this flow, built once, used
        # twice (here and by the admissibility search, which would build it again)
        flow = load.flow(w2, model.d, phase, y_plus[:M], y_plus[M:])
        qm, vm = flow([phase + TWO_PI])
    else:
        qm, vm = load.propagate(w2, model.d, phase, y_plus[:M], y_plus[M:], [phase + TWO_PI])
    y_minus = np.concatenate((qm[:, 0], vm[:, 0]))
    return (y_plus, y_minus, flow) if return_flow else (y_plus, y_minus)


def _build_orbit(model: BarModel, load: Load, phase: float, mult: int) -> PeriodicOrbit:
    M = model.n_modes + 1
    y_plus, y_minus, flow = _impact_states(model, load, phase, return_flow=True)
    c = model.end_weights
    v_imp = float(c @ y_minus[M:])

    status, clearance, cerr = _admissibility(model, load, phase, y_plus, v_imp, flow=flow)
    admissible = status == Admissibility.ADMISSIBLE

    try:
        mu = floquet_multipliers(model, load, phase, y_plus, y_minus)
    except ValueError:  # exact grazing: a multiplier is infinite
        mu = np.full(2 * M, np.inf + 0j)
    blocks = schur_blocks(model, load, phase)
    return PeriodicOrbit.one_impact(
        model=model,
        load=load,
        phase=float(phase),
        multiplicity=int(mult),
        impact_velocity=v_imp,
        admissible=admissible,
        admissibility=status,
        clearance=clearance,
        clearance_error=cerr,
        multipliers=mu,
        stable=stable_verdict(admissible, mu),
        schur_roots=quadratic_roots(blocks),
        schur_stable=schur_test(blocks),
        state_after_impact=y_plus,
        state_before_impact=y_minus,
    )




def _build_wave_orbit(model: BarModel, load: Load, phase: float, mult: int) -> PeriodicOrbit:
    """An orbit of the wave law (theory §4b): contact over ``[0, 2/s]``, flight over ``[2/s, 2 pi]``."""
    from ..dynamics.impact import _wave_impact
    from .wave import _orbit_states, wave_floquet_multipliers

    M = model.n_modes + 1
    _, y_end, y_minus, rate, drive = _orbit_states(model, load, phase)
    c = model.end_weights
    v_imp = float(c @ y_minus[M:])
    T = 2.0 / model.s
    impact = None
    if v_imp > 0.0:
        qm = y_minus[:M].copy()
        qm[0] -= float(c @ qm)  # the end exactly on the rod end (rounding)
        impact = _wave_impact(model, load, float(phase), qm, y_minus[M:], drive)
    # the departure: the end must leave the rod end when the window closes
    v_dep = float(c @ y_end[M:])
    scale = max(abs(v_imp), load.sup_abs, 1e-300)
    at_rest = abs(v_dep) <= 1e-12 * scale
    status, clearance, cerr = _admissibility(model, load, phase + T, y_end, v_imp,
                                             horizon=TWO_PI - T, at_rest=at_rest)
    status = _window_departure(status, at_rest, v_dep, impact is not None and bool(impact.separations))
    admissible = status == Admissibility.ADMISSIBLE
    mu = wave_floquet_multipliers(model, load, phase, y_end, y_minus, rate)
    blocks = schur_blocks(model, load, phase)
    return PeriodicOrbit.one_impact(
        model=model, load=load, phase=float(phase), multiplicity=int(mult), impact_velocity=v_imp,
        admissible=admissible, admissibility=status, clearance=clearance, clearance_error=cerr,
        multipliers=mu, stable=stable_verdict(admissible, mu),
        schur_roots=quadratic_roots(blocks), schur_stable=schur_test(blocks),
        state_after_impact=y_end, state_before_impact=y_minus, impact=impact,
    )


def _sorted_multipliers(jacobian, size, *args) -> np.ndarray:
    """Eigenvalues of ``jacobian(*args)`` in the order of :func:`sort_multipliers`; infinite at exact
    grazing."""
    try:
        DP = jacobian(*args)
    except ValueError:  # exact grazing: a multiplier is infinite
        return np.full(size, np.inf + 0j)
    return sort_multipliers(np.linalg.eigvals(DP))
