"""Existence and stability boundaries of one-impact orbits (the paper's Figs. 5, 6, 8).

Each boundary is a curve found by root-finding in the load factor: the existence edge (a fold of
the phase equation, a double root), the edge of stability on a branch (a multiplier crossing the
unit circle: ``-1`` for period doubling, ``+1`` for a fold), and the edge of admissibility
(theory §5). The root is bracketed by a coarse scan and refined by Brent's method to
``xtol``; nothing is read off a shaded grid.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..laws.abilities import PhaseEquation, require
from ..laws.paper.phase import pneumatic_existence_edge as pneumatic_existence_edge
from ..loads import CosineLoad, Load, SquareWaveLoad
from ..model import BarModel
from .find import periodic_orbits
from .one_impact import orbit_multipliers
from .phase import phase_G, phase_residual

__all__ = [
    "Boundary",
    "pneumatic_existence_edge",
    "pneumatic_stability_edges",
    "pneumatic_stability_curve",
    "admissibility_edges",
    "hydraulic_existence_edge",
    "find_sign_changes",
    "max_phase_residual",
]

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class Boundary:
    """A boundary curve in a chart.

    Attributes
    ----------
    x : numpy.ndarray, shape (n,)
        The abscissa (restitution coefficient ``R``).
    y : numpy.ndarray, shape (n,)
        The load factor on the boundary; NaN where the curve does not exist at that ``x``.
    kind : str
        ``"existence"``, ``"period-doubling"``, ``"fold"``, ``"stability"`` or ``"admissibility"``.
    criterion : str
        ``"exact"`` (multipliers of the impact map), ``"paper"`` (Schur blocks, eqs. 27-31) or
        ``"closed form"``.
    label : str
        A legend label.
    """

    x: np.ndarray
    y: np.ndarray
    kind: str
    criterion: str
    label: str


def find_sign_changes(h: Callable[[float], float], lo: float, hi: float, *, n_scan: int = 24,
                      xtol: float = 1e-12, last: bool = False) -> list[float]:
    """Roots of a continuous scalar function on ``[lo, hi]``: scan, then Brent on each bracket.

    Parameters
    ----------
    h : callable
        ``h(x) -> float``; NaN marks points where it is undefined (they break brackets).
    lo, hi : float
        The interval (the units of ``x``).
    n_scan : int
        Scan points.
    xtol : float
        Absolute tolerance of each root (the units of ``x``).
    last : bool
        Only the highest root (the last of the list): the scan then runs from ``hi`` down and stops
        at the first bracket that holds one, evaluating ``h`` nowhere below it.

    Returns
    -------
    list of float
        Increasing; with ``last``, that list's last root alone (or none), the same float.

    Notes
    -----
    Brent's method starts by evaluating ``h`` at the bracket's ends: those are the scan's values,
    read back instead of computed again (the same numbers, so the same iterates).
    """
    xs = np.linspace(lo, hi, n_scan)
    scanned = {}

    def f(x):
        v = scanned.get(x)
        return h(x) if v is None else v

    if last:
        return _last_sign_change(h, f, xs, scanned, xtol)
    hs = np.array([h(x) for x in xs])
    scanned.update(zip(xs.tolist(), hs.tolist(), strict=True))
    out = []
    for a, b, ha, hb in zip(xs[:-1], xs[1:], hs[:-1], hs[1:], strict=True):
        root = _bracket_root(f, a, b, ha, hb, xtol)
        if root is not None:
            out.append(root)
    if np.isfinite(hs[-1]) and hs[-1] == 0.0:
        out.append(float(xs[-1]))
    return out


def _last_sign_change(h, f, xs, scanned: dict, xtol: float) -> list[float]:
    """:func:`find_sign_changes`' last root over the scan ``xs``, the scan taken from the top down
    (``scanned`` filled for Brent's ``f``): the same tests on the same values, bracket by bracket."""
    hb = scanned[float(xs[-1])] = float(h(xs[-1]))
    if math.isfinite(hb) and hb == 0.0:
        return [float(xs[-1])]
    for i in range(xs.size - 2, -1, -1):
        ha = scanned[float(xs[i])] = float(h(xs[i]))
        root = _bracket_root(f, xs[i], xs[i + 1], ha, hb, xtol)
        if root is not None:
            return [root]
        hb = ha
    return []


def _bracket_root(f, a, b, ha: float, hb: float, xtol: float) -> float | None:
    """The root :func:`find_sign_changes` takes from the scan's bracket ``[a, b]`` (``ha``, ``hb``
    the values there): ``a`` where ``ha`` is 0, Brent's root where the signs differ, else ``None``
    (and where either value is not finite: NaN breaks a bracket)."""
    if not (math.isfinite(ha) and math.isfinite(hb)):
        return None
    if ha == 0.0:
        return float(a)
    if ha * hb < 0.0:
        return brentq(f, a, b, xtol=xtol, rtol=8.9e-16)
    return None


def max_phase_residual(model: BarModel, load: Load) -> float:
    """``max over phase`` of the phase-equation residual (eq. 14); solutions exist iff it is ``>= 0``
    (the residual is periodic with zero-mean oscillating part, so it also takes negative values).

    For a piecewise-constant load the rigid velocity ``V`` is monotone on each piece, so the maximum
    is at a jump; otherwise it is found among the zeros of the residual's derivative.

    Raises
    ------
    ValueError
        Under a law other than the paper's (e.g. the wave impact law), whose phase equation is
        another (theory §4b): its existence edges come from the law's ``existence_edge``
        (:func:`impactbar.laws.wave.periodic.wave_existence_edge`, pneumatic) or from the orbits themselves.
    """
    if not model.law.traits.supports_schur:
        raise ValueError("max_phase_residual is eq. 14's, the paper's impact law; model.impact must "
                         f"be 'paper' (got {model.impact!r})")
    own = load.abilities
    if own.pieces is not None:  # V is monotone on each piece: the largest residual is at a jump
        return float(np.max(phase_residual(model, load, own.pieces[0])))
    orders = own.orders
    if orders is not None and len(orders) == 1:
        k = int(orders[0])
        amp = (1.0 + model.R) * abs(own.amplitudes[0]) / math.hypot(model.d, k)
        return amp - load.p0 * phase_G(model.d, model.R)
    t = np.linspace(0.0, TWO_PI, 4097)
    F = phase_residual(model, load, t)
    i = int(np.argmax(F))
    from scipy.optimize import minimize_scalar

    res = minimize_scalar(lambda x: -float(phase_residual(model, load, x)),
                          bounds=(t[max(i - 1, 0)], t[min(i + 1, t.size - 1)]), method="bounded",
                          options={"xatol": 1e-14})
    return max(float(F[i]), -float(res.fun))


# ------------------------------------------------------------------ pneumatic (Figs. 5, 6) --------
def _stable_branch_phase(model: BarModel, load: CosineLoad) -> float | None:
    """Phase of the orbit on the paper's stable branch: ``cos(k phase)`` of opposite sign to ``pk``
    (load decreasing through the mean at impact), the first of its ``k`` copies. Under the wave law
    the impact is taken at the middle of its contact window, ``phase + 1/s``."""
    law = model.law
    roots = require(law, PhaseEquation, "phase_roots").phase_roots(model, load)
    shift = 0.5 * law.window(model)
    for ph, _ in roots:
        if math.cos(load.k * (ph + shift)) * load.pk < 0.0:
            return ph
    return None


def pneumatic_stability_edges(model: BarModel, k: int = 1, *, criterion: str = "exact",
                              lf_min: float = 1e-3, n_scan: int = 24,
                              xtol: float = 1e-12, bracket: tuple[float, float] | None = None,
                              last: bool = False) -> list[tuple[float, str]]:
    """Load factors ``k p0 / pk`` where the stable-branch orbit of the pneumatic load gains or loses
    stability, below the existence edge.

    The test function is ``max |multiplier| - 1`` on the branch where ``cos(k phase) pk < 0``; each
    sign change is refined by Brent's method, and classified by the crossing multiplier.

    Parameters
    ----------
    model : BarModel
    k : int
        Order of the harmonic (``pk = 1``).
    criterion : {"exact", "paper"}
        Exact multipliers (theory §7; under the wave law those of the wave
        law's impact map, theory §4b), or the roots of the paper's rigid block (eqs. 29,
        30, with the flexible modes in ``sigma``), which is what the paper's bounds (eq. 39) use: its
        flexible blocks (eq. 31) do not depend on the load, and at ``d = 0`` they put a root exactly
        on the unit circle whenever ``cos(2 pi lambda_n) = +-1``. The paper's criterion belongs to
        its eq. 10 and is refused under the wave law.
    lf_min : float
        Smallest load factor searched.
    n_scan, xtol
        As in :func:`find_sign_changes`.
    bracket : (float, float), optional
        Search only this range of load factors (clipped to the existence edge).
    last : bool
        Only the highest edge (the one closest to the existence edge), as
        :func:`find_sign_changes`' ``last``: the load factors below its bracket are not evaluated.

    Returns
    -------
    list of (float, str)
        ``(load factor, kind)`` with kind ``"period-doubling"``, ``"fold"`` or ``"neimark-sacker"``,
        in increasing load factor.

    Raises
    ------
    ValueError
        For an unknown ``criterion``, or ``criterion="paper"`` under the wave law.
    """
    if criterion not in ("exact", "paper"):
        raise ValueError(f"criterion must be 'exact' or 'paper'; got {criterion!r}")
    law = model.law
    if criterion == "paper" and not law.traits.supports_schur:
        raise ValueError("criterion 'paper' is the paper's Schur test for its impact law (eq. 10); "
                         f"use criterion='exact' with impact={model.impact!r}")
    edge = require(law, PhaseEquation, "existence_edge").existence_edge(model, k)
    if not edge > 0.0:  # e.g. the wave law's window does not fit in the period: no orbit
        return []
    hi = min(edge, 50.0) * (1.0 - 1e-9)

    @functools.cache  # each load factor's multipliers once: the root Brent returns is one it evaluated
    def mu(lf):
        load = CosineLoad(lf / k, 1.0, k)
        ph = _stable_branch_phase(model, load)
        if ph is None:
            return None
        if criterion == "paper":  # the paper's bounds (eq. 39) come from its rigid block (eqs. 29, 30)
            return orbit_multipliers(model, load, ph, paper=True)[:2]
        return orbit_multipliers(model, load, ph)

    def h(lf):
        m = mu(lf)
        return math.nan if m is None else float(np.max(np.abs(m))) - 1.0

    lo = lf_min
    if bracket is not None:
        b_lo, b_hi = bracket
        lo, hi = max(lf_min, b_lo), min(hi, b_hi)
        if not lo < hi:
            return []
    out = []
    for lf in find_sign_changes(h, lo, hi, n_scan=n_scan, xtol=xtol, last=last):
        m = mu(lf)
        crit = m[np.argmax(np.abs(m))]
        if abs(crit.imag) > 1e-6:
            kind = "neimark-sacker"
        else:
            kind = "period-doubling" if crit.real < 0 else "fold"
        out.append((lf, kind))
    return out


# ------------------------------------------------------------------ hydraulic (Fig. 8) ------------
def hydraulic_existence_edge(model: BarModel, *, xtol: float = 1e-12) -> float:
    """The ``kappa`` above which the hydraulic load (eq. 34) has no one-impact orbit (Fig. 8).

    Root of ``max over phase of F(phase; kappa) = 0``; the maximum is at a jump of the square wave.

    Returns
    -------
    float
        ``kappa`` in ``(1, 2]``; ``2.0`` when orbits exist up to ``kappa = 2``, ``nan`` if none exist
        for any ``kappa > 1``.

    Raises
    ------
    ValueError
        Under a law other than the paper's (e.g. ``impact="wave"``): this edge is eq. 14's (theory §4).
    """
    if not model.law.traits.supports_schur:
        raise ValueError("hydraulic_existence_edge is the paper's impact law's (eq. 14); model.impact "
                         f"must be 'paper' (got {model.impact!r})")

    def h(kappa):
        return max_phase_residual(model, SquareWaveLoad(1.0, kappa))

    roots = find_sign_changes(h, 1.0 + 1e-9, 2.0, n_scan=24, xtol=xtol)
    if roots:
        return roots[-1]
    return 2.0 if h(2.0) >= 0 else math.nan


def admissibility_edges(model: BarModel, make_load: Callable[[float], Load], lo: float, hi: float,
                        select: Callable[[list], object], *, n_scan: int = 24,
                        xtol: float = 1e-10) -> list[float]:
    """Load factors where the selected orbit changes admissibility (theory §5), by a scan
    and bisection on the admissibility flag.

    Parameters
    ----------
    model : BarModel
    make_load : callable
        ``make_load(load_factor) -> Load``.
    lo, hi : float
        Range of the load factor.
    select : callable
        Picks one orbit from ``periodic_orbits``' list (or returns ``None``).
    n_scan, xtol
        Scan points and bisection tolerance.

    Returns
    -------
    list of float
    """
    def adm(x):
        o = select(periodic_orbits(model, make_load(x)))
        return None if o is None else bool(o.admissible)

    xs = np.linspace(lo, hi, n_scan)
    flags = [adm(x) for x in xs]
    out = []
    for a, b, fa, fb in zip(xs[:-1], xs[1:], flags[:-1], flags[1:], strict=True):
        if fa is None or fb is None or fa == fb:
            continue
        while b - a > xtol:
            m = 0.5 * (a + b)
            fm = adm(m)
            if fm is None:
                break
            if fm == fa:
                a = m
            else:
                b = m
        out.append(0.5 * (a + b))
    return out


def pneumatic_stability_curve(model: BarModel, R_values, k: int = 1, *, criterion: str = "exact",
                              xtol: float = 1e-11) -> Boundary:
    """The lowest stability edge of the pneumatic stable branch as a curve over ``R`` (Figs. 5, 6).

    For each ``R`` the edge is bracketed near the previous one (continuation) or by a scan, then
    refined by Brent's method to ``xtol`` in the load factor ``k p0 / pk``.

    Parameters
    ----------
    model : BarModel
        Its ``R`` is replaced by each value of ``R_values``.
    R_values : array_like, shape (n,)
        Restitution coefficients in ``[0, 1)``.
    k : int
        Order of the harmonic.
    criterion : {"exact", "paper"}
        See :func:`pneumatic_stability_edges`.
    xtol : float
        Tolerance in the load factor.

    Returns
    -------
    Boundary
        ``y`` is NaN where the branch has no stability edge below the existence edge.
    """
    R_values = np.asarray(R_values, dtype=float)
    ys = np.full(R_values.shape, np.nan)
    kinds = []
    prev = None
    for i, R in enumerate(R_values):
        m = model.with_(R=float(R))
        edges = []
        if prev is not None:  # continuation: a narrow bracket around the previous edge
            edges = pneumatic_stability_edges(m, k, criterion=criterion, n_scan=2, xtol=xtol,
                                              bracket=(prev * 0.85, prev * 1.15), last=True)
        if not edges:
            edges = pneumatic_stability_edges(m, k, criterion=criterion, n_scan=16, xtol=xtol, last=True)
        prev = None
        if edges:
            *_, (prev, edge_kind) = edges
            ys[i] = prev  # the edge closest to the existence edge bounds the stable band
            kinds.append(edge_kind)
    kind = kinds[0] if kinds and all(x == kinds[0] for x in kinds) else "stability"
    return Boundary(R_values, ys, kind, criterion, f"{criterion} stability edge")
