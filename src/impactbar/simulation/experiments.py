"""The paper's numerical experiments (Section 5, theory §8): many random starts, the
long-run motion of each classified.

The paper follows the bar "from arbitrary initial values" and reports that the pneumatic hammer
(eq. 33) settles into the one-impact motion, or into permanent contact ``U(L, t) = 0``, reaching the
smallest possible ``k`` (one impact per ``k`` load periods) in more than 99 % of the starts, while
the hydraulic hammer (eq. 34) never settles: its impact interval fluctuates around the load period
with a standard deviation of 5-10 %.

:func:`run_experiment` repeats :func:`impactbar.simulate` from seeded random starts (threads: the
compiled core releases the GIL) and :func:`classify` sorts the last part of each run into

- ``"k=1"``, ``"k=2"``, ...: one impact every ``k`` load periods, periodic;
- ``"permanent contact"``: the end stays on the stop to the end of the run;
- ``"stick-impact"``: contact intervals keep recurring between impacts;
- ``"periodic, several impacts"``: ``m >= 2`` impacts per cycle of whole load periods;
- ``"not periodic"``: none of these (or no impact at all).

Figures of a result are drawn by :func:`impactbar.plotting.plot_experiment` (matplotlib is not
imported here).
"""

from __future__ import annotations

import math
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from .._shared import tables as _tables
from .._shared.columns import IV_HI
from .._shared.validate import check_int, check_real
from ..loads import CosineLoad, Load, SquareWaveLoad
from ..model import BarModel
from .simulate import InitialState, Trajectory, simulate

__all__ = [
    "Classification",
    "ExperimentResult",
    "classify",
    "load_period",
    "random_start",
    "run_experiment",
    "pneumatic_setup",
    "hydraulic_setup",
]

TWO_PI = 2.0 * math.pi

#: the order in which the classes are reported
CLASS_ORDER = ("k=1", "k=2", "k=3", "k=4", "k=5", "k=6", "k=7", "k=8", "permanent contact",
               "stick-impact", "periodic, several impacts", "not periodic")


@dataclass(frozen=True)
class Classification:
    """The long-run motion of one run.

    Attributes
    ----------
    kind : str
        One of :data:`CLASS_ORDER` (``"k=<n>"`` for larger ``n`` too).
    k : int or None
        Load periods per impact cycle for the periodic kinds, else ``None``.
    impacts_per_cycle : int
        Impacts per cycle for the periodic kinds (1 for ``"k=..."``), else 0.
    mismatch : float
        How far the window is from the periodic pattern found (time, load-period units); for
        ``"not periodic"`` the best candidate's.
    """

    kind: str
    k: int | None
    impacts_per_cycle: int
    mismatch: float


def load_period(load: Load) -> float:
    """The fundamental period of the load (dimensionless time): ``2 pi / k`` for a
    :class:`CosineLoad` of order ``k``, ``2 pi / gcd(orders)`` for a :class:`FourierLoad`, ``2 pi``
    otherwise."""
    return load.abilities.period


def classify(tr: Trajectory, *, window: float = 0.25, tol: float = 1e-4,
             max_impacts_per_cycle: int = 8) -> Classification:
    """Classify the last ``window`` fraction of a run (see the module docstring).

    Parameters
    ----------
    tr : Trajectory
    window : float, optional
        Fraction of the run, at its end, that is classified; ``0 < window <= 1``. Default 0.25.
    tol : float, optional
        Tolerance on the periodicity of the last impact times of the window (the last
        ``max(4 m, 8)`` intervals for ``m`` impacts per cycle), in load periods. Default ``1e-4``:
        orbits with a multiplier near -1 converge slowly, and a genuinely different motion misses
        the pattern by far more.
    max_impacts_per_cycle : int, optional
        Largest number of impacts per cycle tried. Default 8.

    Returns
    -------
    Classification
    """
    window = check_real("window", window, lo=0.0, hi=1.0, lo_open=True)
    tol = check_real("tol", tol, lo=0.0, lo_open=True)
    max_impacts_per_cycle = check_int("max_impacts_per_cycle", max_impacts_per_cycle, lo=1)
    T = load_period(tr.load)
    t_start = tr.t_end - window * (tr.t_end - tr.t0)
    ci = tr.contact_intervals
    in_window = int(np.sum(ci[:, IV_HI] > t_start)) if ci.size else 0
    if tr.in_contact_at_end and in_window == 1:
        return Classification("permanent contact", None, 0, 0.0)
    if in_window >= 2:
        return Classification("stick-impact", None, 0, 0.0)
    times = tr.impact_times[tr.impact_times >= t_start] / T
    best = math.inf
    for m in range(1, max_impacts_per_cycle + 1):
        if times.size < 3 * m + 1:
            break
        lag = (times[m:] - times[:-m])[-max(4 * m, 8):]  # the end of the window: converged
        k = int(round(float(np.median(lag))))
        mismatch = float(np.max(np.abs(lag - k))) if k >= 1 else math.inf
        best = min(best, mismatch)
        if k >= 1 and mismatch <= tol:
            if m == 1:
                return Classification(f"k={k}", k, 1, mismatch)
            return Classification("periodic, several impacts", k, m, mismatch)
    return Classification("not periodic", None, 0, best)


def random_start(model: BarModel, load: Load, rng: np.random.Generator) -> tuple[float, InitialState]:
    """An arbitrary start: load phase uniform in ``[0, 2 pi)``; the end at a distance up to
    ``pi V`` from the stop moving at up to ``V`` either way, ``V = 2 pi |p0| / (1 + R)`` the
    impact velocity of a one-impact orbit; flexible modes with random deflections up to the static
    ones, ``|p| / (s n pi)^2``, and velocities up to ``|p| / (s n pi)``.

    Returns
    -------
    t0, InitialState
    """
    V = TWO_PI * max(abs(load.p0), 0.1) / (1.0 + model.R)
    P = max(abs(load.p0), 1e-3) + getattr(load, "sup_oscillation", 0.0)
    N = model.n_modes
    q = np.zeros(N + 1)
    v = np.zeros(N + 1)
    if N:
        w = model.frequencies[1:]
        q[1:] = rng.uniform(-1, 1, N) * P / w**2
        v[1:] = rng.uniform(-1, 1, N) * P / w
    end = -rng.uniform(0.0, math.pi * V) - 1e-6
    q[0] = end - model.end_weights[1:] @ q[1:]
    v[0] = rng.uniform(-V, V)
    return float(rng.uniform(0.0, TWO_PI)), InitialState(q, v)


@dataclass(frozen=True, eq=False)
class ExperimentResult:
    """Result of :func:`run_experiment`.

    Attributes
    ----------
    model : BarModel
    load : Load
    periods : float
        Length of each run in load periods.
    classes : tuple of Classification
        One per start, in start order.
    interval_mean, interval_std : float
        Mean and standard deviation of the intervals between successive *main* impacts over the
        classified windows of all runs pooled, in load periods. A main impact ends a free flight
        of at least 5 % of the load period (since the last impact or the end of the last
        contact) and is not a bounce of the previous one (flight under half a period, arrival
        under ``1.5 R`` times the previous arrival velocity): the bounces of a chatter sequence
        and the rattling around a contact belong to the main impact that started them.
    run_spread : float
        Median over the runs (with at least 5 main impacts in the window) of the relative
        standard deviation ``std / mean`` of that run's main-impact intervals: the spread "not
        depending on the initial conditions" the paper reports for the hydraulic hammer.
    all_interval_mean, all_interval_std : float
        The same over every impact.
    trajectories : tuple of Trajectory
        The first few runs, kept for plotting.
    intervals : numpy.ndarray
        Every main-impact interval in the windows (load periods), for the histogram.
    impact_pairs : numpy.ndarray, shape (P, 2)
        ``(v_i, v_{i+1})`` of successive main impacts in the windows, for the impact map.
    """

    model: BarModel
    load: Load
    periods: float
    classes: tuple
    interval_mean: float
    interval_std: float
    all_interval_mean: float
    all_interval_std: float
    run_spread: float
    trajectories: tuple = field(repr=False)
    intervals: np.ndarray = field(repr=False)
    impact_pairs: np.ndarray = field(repr=False)

    @property
    def load_period(self) -> float:
        """The load's fundamental period (dimensionless time, :func:`load_period`)."""
        return load_period(self.load)

    @property
    def fractions(self) -> dict[str, float]:
        """Fraction of the starts in each class, in :data:`CLASS_ORDER` order (present ones)."""
        counts = Counter(c.kind for c in self.classes)
        n = len(self.classes)
        keys = [k for k in CLASS_ORDER if k in counts] + sorted(set(counts) - set(CLASS_ORDER))
        return {k: counts[k] / n for k in keys}

    def to_dataframe(self):
        """One row per random start: its long-run motion.

        Returns
        -------
        pandas.DataFrame
            Index ``start`` (in start order), columns ``kind`` (the class, theory §8), ``k``
            (load periods per impact cycle, NaN when not periodic), ``impacts_per_cycle`` and
            ``mismatch`` (load periods); ``attrs`` holds the model, the load, the run length and
            the pooled impact-interval statistics (``interval_mean``, ``interval_std``,
            ``run_spread``, in load periods).
        """
        cl = self.classes
        return _tables.frame(
            {"start": np.arange(len(cl)), "kind": [c.kind for c in cl],
             "k": [math.nan if c.k is None else float(c.k) for c in cl],
             "impacts_per_cycle": [c.impacts_per_cycle for c in cl],
             "mismatch": [c.mismatch for c in cl]},
            {"start": ("random start number", "1"), "kind": ("long-run motion", ""),
             "k": ("load periods per impact cycle", "1"),
             "impacts_per_cycle": ("impacts per cycle", "1"),
             "mismatch": ("distance from the periodic pattern", "load periods")},
            index="start",
            attrs={"model": repr(self.model), "load": repr(self.load), "periods": self.periods,
                   "interval_mean": self.interval_mean, "interval_std": self.interval_std,
                   "run_spread": self.run_spread})

    def to_xarray(self):
        """:meth:`to_dataframe` as an ``xarray.Dataset`` along ``start``, with the class fractions
        (``fraction`` along ``motion``) and the main-impact intervals (``interval`` along
        ``main_impact``); every variable with ``long_name`` and ``units``.

        Raises
        ------
        ModuleNotFoundError
            xarray is not installed (extra ``data``).
        """
        ds = _tables.to_xarray(self.to_dataframe())
        fr = self.fractions
        ds = ds.assign_coords(motion=list(fr))
        ds["fraction"] = ("motion", np.array(list(fr.values()), dtype=float),
                          {"long_name": "fraction of the starts in each long-run motion", "units": "1"})
        ds["interval"] = ("main_impact", np.asarray(self.intervals, dtype=float),
                          {"long_name": "interval between successive main impacts",
                           "units": "load periods"})
        return ds

    def summary(self) -> str:
        """A plain-text report: parameters, class fractions, impact-interval statistics."""
        m = self.model
        lines = [
            f"model: s={m.s:g} d={m.d:g} R={m.R:g} n_modes={m.n_modes}; load: {self.load!r}",
            f"{len(self.classes)} random starts, {self.periods:g} load periods each "
            f"(last 25 % classified)",
            "long-run motion:",
        ]
        for k, f in self.fractions.items():
            lines.append(f"  {k:<28s} {100 * f:6.2f} %")
        lines.append(
            f"impact interval (main impacts): mean {self.interval_mean:.6f}, std "
            f"{self.interval_std:.6f} load periods ({100 * self.interval_std / self.interval_mean:.2f} %)"
            if self.intervals.size else "impact interval: no impacts in the windows"
        )
        if self.intervals.size:
            lines.append(
                f"impact interval (all impacts):  mean {self.all_interval_mean:.6f}, std "
                f"{self.all_interval_std:.6f} load periods"
            )
            lines.append(f"median over runs of each run's interval std/mean (main impacts): "
                         f"{100 * self.run_spread:.2f} %")
        return "\n".join(lines)


def run_experiment(model: BarModel, load: Load, *, starts: int = 200, periods: float = 200.0,
                   seed: int = 0, workers: int = 2, keep: int = 4, window: float = 0.25,
                   progress=None) -> ExperimentResult:
    """Simulate ``starts`` random starts for ``periods`` load periods each and classify them.

    Parameters
    ----------
    model : BarModel
    load : Load
        A :class:`FourierLoad` (e.g. :class:`CosineLoad`) or :class:`PiecewiseConstantLoad`.
    starts : int, optional
        Number of random starts, in ``[1, 1e6]`` (each start is held in memory). Default 200.
    periods : float, optional
        Length of each run in load periods, ``> 0``. Default 200.
    seed : int, optional
        Seed of the random starts (:func:`numpy.random.default_rng`). Default 0.
    workers : int, optional
        Threads, in ``[1, 1024]``. Default 2.
    keep : int, optional
        Trajectories kept for plotting. Default 4.
    window : float, optional
        Fraction of each run classified, at its end. Default 0.25.
    progress : callable, optional
        Called with the number of finished runs.

    Returns
    -------
    ExperimentResult
    """
    starts = check_int("starts", starts, lo=1, hi=1_000_000)
    periods = check_real("periods", periods, lo=0.0, lo_open=True)
    seed = check_int("seed", seed, lo=0)
    workers = check_int("workers", workers, lo=1, hi=1024)
    keep = check_int("keep", keep, lo=0)
    rng = np.random.default_rng(seed)
    T = load_period(load)
    jobs = [random_start(model, load, rng) for _ in range(starts)]

    def one(job):
        t0, st = job
        tr = simulate(model, load, st, t0 + periods * T, t0=t0)
        return tr, classify(tr, window=window)

    results = []
    with ThreadPoolExecutor(max_workers=workers) as pool:
        for i, res in enumerate(pool.map(one, jobs)):
            results.append(res)
            if progress is not None:
                progress(i + 1)
    intervals, all_intervals, pairs, spreads = [], [], [], []
    for tr, _ in results:
        t_start = tr.t_end - window * (tr.t_end - tr.t0)
        sel = tr.impact_times >= t_start
        t = tr.impact_times[sel] / T
        vel = tr.impact_velocities[sel]
        if t.size >= 2:
            all_intervals.append(np.diff(t))
        if vel.size:
            main = _main_impacts(tr, sel, T)
            tm, vm = t[main], vel[main]
            if tm.size >= 2:
                dt = np.diff(tm)
                intervals.append(dt)
                pairs.append(np.column_stack((vm[:-1], vm[1:])))
                if dt.size >= 4:
                    spreads.append(float(np.std(dt) / np.mean(dt)))
    iv = np.concatenate(intervals) if intervals else np.zeros(0)
    ia = np.concatenate(all_intervals) if all_intervals else np.zeros(0)
    return ExperimentResult(
        model=model, load=load, periods=periods, classes=tuple(c for _, c in results),
        interval_mean=float(np.mean(iv)) if iv.size else math.nan,
        interval_std=float(np.std(iv)) if iv.size else math.nan,
        all_interval_mean=float(np.mean(ia)) if ia.size else math.nan,
        all_interval_std=float(np.std(ia)) if ia.size else math.nan,
        run_spread=float(np.median(spreads)) if spreads else math.nan,
        trajectories=tuple(tr for tr, _ in results[:keep]), intervals=iv,
        impact_pairs=np.concatenate(pairs) if pairs else np.zeros((0, 2)),
    )


def _main_impacts(tr: Trajectory, sel: np.ndarray, period: float) -> np.ndarray:
    """Mask over ``tr.impact_times[sel]`` of the main impacts: those that end a free flight of at
    least 5 % of the load period (since the last impact or the end of the last contact) and are
    not a bounce of the previous impact (a flight shorter than half a period arriving at less
    than ``1.5 R`` times the previous arrival velocity)."""
    t = tr.impact_times
    v = tr.impact_velocities
    prev = np.concatenate(([tr.t0], t[:-1]))
    v_prev = np.concatenate(([np.inf], v[:-1]))
    after_release = np.zeros(t.size, dtype=bool)
    ci = tr.contact_intervals
    if ci.size:
        j = np.searchsorted(ci[:, IV_HI], t, side="right") - 1
        last_release = np.where(j >= 0, ci[np.clip(j, 0, None), IV_HI], -np.inf)
        after_release = last_release > prev
        prev = np.maximum(prev, last_release)
    flight = t - prev
    with np.errstate(invalid="ignore"):  # R = 0 times the first impact's v_prev = inf: no bounce
        bounce = ~after_release & (flight < 0.5 * period) & (v < 1.5 * tr.model.R * v_prev)
    return ((flight >= 0.05 * period) & ~bounce)[sel]


def pneumatic_setup(*, p0: float = 1.2, pk: float = 1.0, k: int = 1, s: float = 10.0,
                    d: float = 0.03 / TWO_PI, R: float = 0.8, n_modes: int = 4):
    """The pneumatic hammer (eq. 33): ``p0 + pk cos(k t)``. The defaults put ``p0/pk`` where the
    rigid theory (theory §6) has both the one-impact-per-period (``k = 1``) and the
    one-impact-per-two-periods motion stable, so the 'smallest k' claim is tested.

    Returns
    -------
    BarModel, CosineLoad
    """
    return BarModel(s=s, d=d, R=R, n_modes=n_modes), CosineLoad(p0, pk, k)


def hydraulic_setup(*, q: float = 1.0, kappa: float = 1.5, s: float = 10.0,
                    d: float = 0.03 / TWO_PI, R: float = 0.5, n_modes: int = 4):
    """The hydraulic hammer (eq. 34): a square wave ``+q`` for ``kappa pi``, ``-q`` for the rest.

    Returns
    -------
    BarModel, SquareWaveLoad
    """
    return BarModel(s=s, d=d, R=R, n_modes=n_modes), SquareWaveLoad(q, kappa)
