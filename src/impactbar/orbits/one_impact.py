"""One-impact periodic orbits (paper Section 2, MODEL.md sections 4, 5, 7).

``periodic_orbits(model, load)`` finds every root ``phase`` of the phase equation (eq. 14),
builds the orbit's modal state, decides admissibility rigorously, and computes the exact Floquet
multipliers and the paper's Schur criterion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import _tables
from .._threads import single_threaded_blas
from ..dynamics.modal import fundamental
from ..loads import Load
from ..model import BarModel
from .admissibility import _admissibility
from .phase import _check_inputs, phase_roots
from .stability import impact_map_jacobian, quadratic_roots, schur_blocks, schur_test

__all__ = ["PeriodicOrbit", "periodic_orbits", "orbit_multipliers"]

TWO_PI = 2.0 * math.pi

@dataclass(frozen=True, eq=False)
class PeriodicOrbit:
    """A one-impact-per-period steady state (paper Section 2) with its stability.

    Orbit time ``t`` is counted from an impact: the impacts are at ``t = 0, 2 pi, ...``, and the load
    acting at orbit time ``t`` is ``p(t + phase)`` (eq. 7).

    Attributes
    ----------
    model : BarModel
    load : Load
    phase : float
        Phase lag ``phase`` in ``[0, 2 pi)`` between load and impact cycle (rad), a root of eq. 14.
    multiplicity : int
        1, or 2 for a double root of the phase equation (a fold, where two orbits merge).
    impact_velocity : float
        ``u_t(1, 2 pi-)``, velocity of the struck end just before impact (dimensionless); > 0 for a
        physical orbit.
    admissible : bool
        The end stays off the stop between impacts (``u(1, t) < 0`` for ``0 < t < 2 pi``), leaves it
        (for ``R = 0``: the end's acceleration just after impact points away from the stop) and
        arrives moving forward (MODEL.md section 5). Decided with certified bounds, not sampling.
    admissibility : str
        ``"admissible"``, or why not: ``"penetrates"``, ``"grazing"``, ``"backward impact"``,
        ``"sticks"`` (R = 0 and the load presses the end on the stop after impact).
    clearance : float
        Largest value of ``u(1, t)`` at its stationary points between impacts (dimensionless): < 0
        for an admissible orbit, > 0 where the end swings through the stop, ~0 at grazing. By Rolle's
        theorem there is at least one stationary point.
    clearance_error : float
        Bound on the error of ``clearance`` from the enclosure of the stationary points.
    multipliers : numpy.ndarray of complex, shape (2 N + 2,)
        Exact Floquet multipliers (eigenvalues of the impact map's Jacobian, MODEL.md section 7),
        sorted by decreasing modulus.
    stable : bool
        ``admissible`` and every ``|multiplier| < 1``.
    schur_roots : numpy.ndarray of complex, shape (2 N + 2,)
        Roots of the paper's quadratic blocks (eqs. 27, 29-31), rigid block first.
    schur_stable : bool
        The paper's criterion (Schur's conditions, eq. 28) on every block; ignores admissibility.
    state_after_impact : numpy.ndarray, shape (2 N + 2,)
        Modal state ``(q_0..q_N, q_0'..q_N')`` at ``t = 0+``.
    state_before_impact : numpy.ndarray, shape (2 N + 2,)
        Modal state at ``t = 2 pi-``.
    """

    model: BarModel
    load: Load
    phase: float
    multiplicity: int
    impact_velocity: float
    admissible: bool
    admissibility: str
    clearance: float
    clearance_error: float
    multipliers: np.ndarray = field(repr=False)
    stable: bool
    schur_roots: np.ndarray = field(repr=False)
    schur_stable: bool
    state_after_impact: np.ndarray = field(repr=False)
    state_before_impact: np.ndarray = field(repr=False)

    @property
    def max_abs_multiplier(self) -> float:
        """Largest ``|multiplier|`` (spectral radius of the impact map's Jacobian)."""
        return float(np.max(np.abs(self.multipliers)))

    @property
    def modal_state_after_impact(self) -> tuple[np.ndarray, np.ndarray]:
        """``(q, q')`` just after the impact, each shape ``(N + 1,)``."""
        M = self.model.n_modes + 1
        return self.state_after_impact[:M].copy(), self.state_after_impact[M:].copy()

    def modal_state(self, t):
        """Modal displacements and velocities at orbit times ``t``.

        Parameters
        ----------
        t : array_like, shape (T,)
            Orbit times (dimensionless); taken modulo ``2 pi``, and a multiple of ``2 pi`` gives the
            state just after the impact.

        Returns
        -------
        q, v : numpy.ndarray, shape (N + 1, T)
        """
        t = np.atleast_1d(np.asarray(t, dtype=float)).ravel()
        return self._state_in_period(np.mod(t, TWO_PI))

    def _state_in_period(self, t):
        """State at orbit times ``0 <= t <= 2 pi`` without wrapping (``2 pi`` is before impact)."""
        M = self.model.n_modes + 1
        return self.load.propagate(self.model.frequencies**2, self.model.d, self.phase,
                                   self.state_after_impact[:M], self.state_after_impact[M:],
                                   self.phase + np.asarray(t, dtype=float))

    def _field(self, x, t, velocity):
        x = np.asarray(x, dtype=float)
        t = np.asarray(t, dtype=float)
        xb, tb = np.broadcast_arrays(x, t)
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
            Orbit times (periodic with period ``2 pi``).

        Returns
        -------
        numpy.ndarray, shape ``broadcast(x, t).shape``
        """
        return self._field(x, t, velocity=False)

    def velocity(self, x, t) -> np.ndarray:
        """Velocity ``u_t(x, t)``, same conventions as :meth:`displacement`; at multiples of
        ``2 pi`` the velocity just after the impact."""
        return self._field(x, t, velocity=True)

    def end_displacement(self, t) -> np.ndarray:
        """Displacement of the struck end ``u(1, t)``, shape of ``t``."""
        t = np.asarray(t, dtype=float)
        q, _ = self.modal_state(t.ravel())
        return (self.model.end_weights @ q).reshape(t.shape)

    def to_dict(self) -> dict:
        """A JSON-ready summary (floats, lists of ``[re, im]``; ``clearance`` may be ``-inf``)."""
        return {
            "phase": self.phase,
            "multiplicity": self.multiplicity,
            "impact_velocity": self.impact_velocity,
            "admissible": self.admissible,
            "admissibility": self.admissibility,
            "clearance": self.clearance,
            "stable": self.stable,
            "max_abs_multiplier": self.max_abs_multiplier,
            "multipliers": [[m.real, m.imag] for m in self.multipliers],
            "schur_stable": self.schur_stable,
            "schur_roots": [[m.real, m.imag] for m in self.schur_roots],
        }

    def to_dataframe(self, n: int = 256):
        """The struck end's motion over one period as a table.

        Parameters
        ----------
        n : int, optional
            Number of orbit times, ``t = 2 pi j / n`` for ``j = 0..n`` (the last one just before the
            next impact). Default 256.

        Returns
        -------
        pandas.DataFrame
            Index ``t`` (orbit time since the impact), columns ``end_displacement`` ``u(1, t)`` and
            ``end_velocity`` ``u_t(1, t)``, all dimensionless (eq. 2); ``attrs`` holds the model,
            the load, the phase and each column's ``long_name`` and ``units``.
        """
        n = int(n)
        if n < 1:
            raise ValueError(f"n must be an integer >= 1; got {n}")
        t = np.linspace(0.0, TWO_PI, n + 1)
        q, v = self._state_in_period(t)
        c = self.model.end_weights
        return _tables.frame(
            {"t": t, "end_displacement": c @ q, "end_velocity": c @ v},
            {"t": ("orbit time since the impact", "1"),
             "end_displacement": ("displacement u(1, t) of the struck end", "1"),
             "end_velocity": ("velocity u_t(1, t) of the struck end", "1")},
            index="t", attrs=self._attrs())

    def to_xarray(self, nx: int = 51, nt: int = 256):
        """The displacement and velocity fields over one period as an ``xarray.Dataset``.

        Parameters
        ----------
        nx, nt : int, optional
            Grid points along the bar (``x`` in ``[0, 1]``, driven end 0) and in orbit time
            (``t`` in ``[0, 2 pi]``). Defaults 51 and 256.

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
        t = np.linspace(0.0, TWO_PI, nt)
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


#: the columns of :meth:`OrbitList.to_dataframe`: name -> (long_name, units)
ORBIT_COLUMNS = {
    "orbit": ("orbit number, in order of phase", "1"),
    "phase": ("phase lag between load and impact cycle, a root of eq. 14", "rad"),
    "multiplicity": ("multiplicity of the root (2 at a fold)", "1"),
    "impact_velocity": ("velocity of the struck end before impact", "1"),
    "admissible": ("the end stays off the stop between impacts (theory §5)", ""),
    "admissibility": ("admissible, or why not", ""),
    "clearance": ("largest u(1, t) at a stationary point between impacts", "1"),
    "clearance_error": ("bound on the error of clearance", "1"),
    "stable": ("admissible and every |Floquet multiplier| < 1 (theory §7)", ""),
    "max_abs_multiplier": ("largest |Floquet multiplier|", "1"),
    "schur_stable": ("the paper's Schur criterion, eqs. 27-31 (theory §6)", ""),
}


class OrbitList(list):
    """The list of :class:`PeriodicOrbit` that :func:`periodic_orbits` returns: a plain ``list``
    (indexing, iteration, ``len``, comparison with lists) with conversions to tables.

    Methods
    -------
    to_dataframe()
        One row per orbit.
    to_xarray()
        The same as an ``xarray.Dataset`` along the dimension ``orbit``.
    """

    __slots__ = ()

    def to_dataframe(self):
        """One row per orbit: phase, impact velocity, admissibility, clearance, stability.

        Returns
        -------
        pandas.DataFrame
            Index ``orbit`` (0, 1, ... in order of phase), the columns of :data:`ORBIT_COLUMNS`
            plus the model's ``s``, ``d``, ``R``, ``n_modes`` and the ``load`` (as text), so frames
            of several models concatenate; ``attrs["columns"]`` gives each column's ``long_name``
            and ``units`` (dimensionless numbers have units ``"1"``, eq. 2).
        """
        keys = [k for k in ORBIT_COLUMNS if k != "orbit"]
        cols = {"orbit": np.arange(len(self))}
        for k in keys:
            cols[k] = [getattr(o, k) for o in self]
        for k in ("s", "d", "R", "n_modes"):
            cols[k] = [getattr(o.model, k) for o in self]
        cols["load"] = [repr(o.load) for o in self]
        meta = dict(ORBIT_COLUMNS, s=("wave-speed ratio C/(L Omega), eq. 2", "1"),
                    d=("damping D/(M Omega), eq. 2", "1"), R=("restitution coefficient", "1"),
                    n_modes=("flexible modes kept", "1"), load=("the load", ""))
        df = _tables.frame(cols, meta, index="orbit")
        if len(self) == 0:  # keep the dtypes of a non-empty table
            df = df.astype({"multiplicity": int, "admissible": bool, "admissibility": object,
                            "stable": bool, "schur_stable": bool, "n_modes": int, "load": object})
        return df

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
        fold, eq. 38); ``.to_dataframe()`` and ``.to_xarray()`` make it a table.

    Raises
    ------
    ValueError
        For inputs of the wrong type, or at an undamped resonance ``s n pi = k`` (eq. 16).

    Examples
    --------
    >>> from impactbar import BarModel, CosineLoad, periodic_orbits
    >>> orbits = periodic_orbits(BarModel(s=10, d=0, R=0.5, n_modes=4), CosineLoad(0.5, 1.0))
    >>> [round(o.phase, 4) for o in orbits]
    [0.5148, 2.6268]
    """
    _check_inputs(model, load)
    with single_threaded_blas():
        return OrbitList(_build_orbit(model, load, ph, mult) for ph, mult in phase_roots(model, load))


def _start_state(model: BarModel, load: Load, phase: float) -> np.ndarray:
    """Modal state just after the impact of the orbit with this phase (eqs. 10-13)."""
    N = model.n_modes
    R, d = model.R, model.d
    q = np.zeros(N + 1)
    v = np.zeros(N + 1)
    if N > 0:
        w2 = model.frequencies[1:] ** 2
        zeros = np.zeros(N)
        fq, fv = load.propagate(w2, d, phase, zeros, zeros, [phase + TWO_PI])
        fq, fv = fq[:, 0], fv[:, 0]
        p11, p12, p21, p22 = fundamental(w2, d, TWO_PI)
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
        multipliers (MODEL.md section 7).

    Returns
    -------
    numpy.ndarray of complex, shape (2 N + 2,)
    """
    if paper:
        return quadratic_roots(schur_blocks(model, load, phase))
    y_plus, y_minus = _impact_states(model, load, phase)
    with single_threaded_blas():
        return np.linalg.eigvals(impact_map_jacobian(model, load, phase, y_plus, y_minus))


def _impact_states(model: BarModel, load: Load, phase: float):
    """Modal states just after (``t = 0+``) and just before (``t = 2 pi-``) the orbit's impact."""
    M = model.n_modes + 1
    y_plus = _start_state(model, load, phase)
    qm, vm = load.propagate(model.frequencies**2, model.d, phase, y_plus[:M], y_plus[M:],
                            [phase + TWO_PI])
    return y_plus, np.concatenate((qm[:, 0], vm[:, 0]))


def _build_orbit(model: BarModel, load: Load, phase: float, mult: int) -> PeriodicOrbit:
    M = model.n_modes + 1
    y_plus, y_minus = _impact_states(model, load, phase)
    c = model.end_weights
    v_imp = float(c @ y_minus[M:])

    status, clearance, cerr = _admissibility(model, load, phase, y_plus, v_imp)
    admissible = status == "admissible"

    try:
        DP = impact_map_jacobian(model, load, phase, y_plus, y_minus)
    except ValueError:  # exact grazing: a multiplier is infinite
        mu = np.full(2 * M, np.inf + 0j)
    else:
        mu = np.linalg.eigvals(DP)
        mu = mu[np.argsort(-np.abs(mu), kind="stable")]
    blocks = schur_blocks(model, load, phase)
    return PeriodicOrbit(
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
        stable=bool(admissible and np.all(np.abs(mu) < 1.0)),
        schur_roots=quadratic_roots(blocks),
        schur_stable=schur_test(blocks),
        state_after_impact=y_plus,
        state_before_impact=y_minus,
    )


