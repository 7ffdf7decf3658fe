r"""The model beside the measurement: the strains a blow puts at gauge stations of the drill rod,
their misfit to a recording, and the blow's parameters fitted to it.

The strain at a gauge station :math:`x` of the rod (measured from the rod's struck end, the shank's
face) is the normal force there over the piece's stiffness, :math:`\varepsilon(x, t) = -N(x, t) /
(E A)` (tension positive, as :mod:`~impactbar.measure.waves` reads a gauge; :math:`N` compression
positive). The library's blow of a piston on the rod, bit and rock (theory §12, "Stepped rods, the
bit and the rock") gives :math:`N` at its segments' boundaries; a station inside a segment is made
one by splitting the segment there into two of the same material and area, which changes no wave
(equal impedances reflect nothing). The blow is the exact one (every wave a sum of closed-form
pieces) where the exact solver's bounds allow, else the lattice's (:func:`impactbar.physical.piston
.piston_blow`), whose force is piecewise constant on the cell time.

A fit (:func:`fit_blow`) varies named parameters of the blow, by the configuration's dotted names
(``impact_velocity``, ``rock.k``, ``rock.k_u``, ``bit.mass``, ``rock.feed``), to the least squares of
the model's strains against the recorded ones at each station (``scipy.optimize.least_squares``); the
parameters' standard errors come from the fit's Jacobian :math:`J` at the optimum,
:math:`\operatorname{cov} = s^2 (J^\mathsf{T} J)^{-1}`, :math:`s^2` the residuals' sum of squares over
the degrees of freedom (the linearised model's covariance; the noise taken white and alike on every
sample).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .._shared.validate import check_real
from ..physical import tree

__all__ = ["gauge_strains", "model_rod", "Comparison", "compare", "BlowFit", "fit_blow", "FIT_PARAMETERS"]

#: the blow's parameters a fit can vary, each with its SI unit: the impact velocity, and the rock's and
#: the bit's keys of the configuration (:data:`impactbar.physical.tree.FIELDS`, those of a drill string)
FIT_PARAMETERS = {"impact_velocity": "m/s", **{k: f.unit for k, f in tree.FIELDS.items()
                                             if f.needs == "rock" and f.holder == "law"}}
#: the parameters a blow cannot go without (the others are 0 where not given: no bit mass, no feed)
_REQUIRED = ("impact_velocity", "rock.k", "rock.k_u")


def _split(pieces, stations):
    """The rod's pieces split at each station, and the boundary number (0 the shank's face, ``i``
    below the ``i``-th piece) and the piece of each station."""
    from ..physical.rock import RodPiece

    ends = np.cumsum([p.length_m for p in pieces])
    total = float(ends[-1])
    cuts = sorted(set(stations))
    out, where, start = [], {}, 0.0
    for p, end in zip(pieces, ends, strict=True):
        inner = [x for x in cuts if start < x < end and not math.isclose(x, end, rel_tol=1e-12)]
        a = start
        for x in inner:
            out.append(RodPiece(x - a, p.area_m2, p.E_Pa, p.density_kg_m3))
            where[x] = (len(out), p)
            a = x
        out.append(RodPiece(end - a, p.area_m2, p.E_Pa, p.density_kg_m3))
        for x in cuts:
            if math.isclose(x, end, rel_tol=1e-12) and x < total:
                where[x] = (len(out), p)  # (on the boundary: the piece above it read)
        start = end
    return tuple(out), where, total


def gauge_strains(rod, *, piston_lengths, piston_areas, values: dict, stations, time,
                  E=None, density=None) -> dict:
    r"""The strains a blow puts at gauge stations of the drill rod (the module's formula).

    Parameters
    ----------
    rod : sequence of RodPiece, or dict
        The drill string from its struck end (:class:`~impactbar.physical.rock.RodPiece`, SI), or
        the model's ``[rod]`` table (``{"segments": [...]}``, or a configuration or spec holding it),
        read as a configuration's (:func:`model_rod`).
    piston_lengths, piston_areas : sequence of float, shape (n,)
        The piston's segments (m, m^2), driven end first (one segment: a uniform piston).
    values : dict
        The blow's parameters by :data:`FIT_PARAMETERS`' names: ``impact_velocity`` (m/s, > 0),
        ``rock.k`` and ``rock.k_u`` (N/m, ``0 < k <= k_u``) required; ``bit.mass`` (kg) and
        ``rock.feed`` (N) optional (0).
    stations : sequence of float, shape (s,)
        Gauge stations (m) from the rod's struck end, each inside the rod (``0 < x < length``).
    time : array_like, shape (t,)
        Times (s) from the impact.
    E, density : float, optional
        The piston's Young's modulus (Pa) and density (kg/m^3); the rod's first piece's by default.

    Returns
    -------
    dict
        Each station (float) to its strain history, shape (t,), tension positive.

    Raises
    ------
    ValueError
        A station outside the rod, a parameter missing, unknown or out of its range (named).

    Notes
    -----
    Source: the blow of theory §12 ("Stepped rods, the bit and the rock"); paper eq. (2) for the
    waves in each segment.

    Examples
    --------
    >>> from impactbar.physical.rock import RodPiece
    >>> rod = [RodPiece(length_m=3.0, area_m2=1.0e-3, E_Pa=2.1e11, density_kg_m3=7850.0)]
    >>> t = np.array([0.2e-3, 0.5e-3])  # the wave front passes 1 m at 0.19 ms
    >>> eps = gauge_strains(rod, piston_lengths=[0.3], piston_areas=[1.0e-3], stations=[1.0], time=t,
    ...                     values={"impact_velocity": 10.0, "rock.k": 3e8, "rock.k_u": 3e9})
    >>> round(float(eps[1.0][0]) * 1e6, 1)  # -V / (2 c): the piston and rod of one impedance
    -966.7
    """
    from ..physical.piston import _model_units, piston_blow

    pieces = model_rod(rod)
    v = _values(values)
    try:
        xs = [check_real(f"stations[{j}]", x) for j, x in enumerate(stations)]
    except TypeError:
        raise ValueError("stations must be a sequence of numbers (m)") from None
    split, where, total = _split(pieces, xs)
    for j, x in enumerate(xs):
        if not 0.0 < x < total:
            raise ValueError(f"stations[{j}] must lie inside the rod, 0 < x < {total:g} m; got {x!r}")
    t = np.asarray(time, dtype=float)
    if t.ndim != 1 or not np.all(np.isfinite(t)):
        raise ValueError("time must be a one-dimensional array of finite times (s)")
    b = piston_blow(split, (v["rock.k"], v["rock.k_u"]), lengths=piston_lengths, areas=piston_areas,
                    impact_velocity=v["impact_velocity"], E=E, density=density, bit_mass=v["bit.mass"],
                    feed=v["rock.feed"])
    E0 = pieces[0].E_Pa if E is None else E
    rho = pieces[0].density_kg_m3 if density is None else density
    c, force_N, _, time_s, *_ = _model_units(split, v["rock.k"], v["rock.k_u"], b["mass_kg"], b["length_m"],
                                             E0, rho, None)
    blow = b["blow"]
    out = {}
    for x in xs:
        j, piece = where[x]
        out[x] = -blow.junction_force(j, t / time_s) * force_N / (piece.E_Pa * piece.area_m2)
    return out


def model_rod(rod) -> tuple:
    """The model's rod: RodPieces as given, or read from the model's ``[rod]`` table.

    Parameters
    ----------
    rod : RodPiece, sequence of RodPiece, or dict
        A dict is the ``[rod]`` table of a hammer's or a drifter's configuration (``{"segments":
        [...]}``, SI quantities with units) or a configuration or measurement spec holding one,
        read by :func:`impactbar.physical.rock.rod_from_config`, each segment with its own ``E`` and
        ``density``.

    Returns
    -------
    tuple of RodPiece
        From the struck end.

    Raises
    ------
    ValueError
        The reader's refusals (a missing, unknown or invalid key, named), or a rod that is none of
        these.

    Examples
    --------
    >>> steel = {"E": "210 GPa", "density": "7850 kg/m^3"}  # quantities with units (pint)
    >>> rod = model_rod({"segments": [{"length": "3 m", "diameter": "32 mm", **steel}]})
    >>> round(rod[0].area_m2 * 1e6, 2), round(rod[0].wave_speed_m_s, 1)
    (804.25, 5172.2)
    """
    from ..physical.piston import _pieces

    if isinstance(rod, dict):
        from ..physical.rock import rod_from_config

        return rod_from_config(rod if "rod" in rod else {"rod": rod})
    return _pieces(rod)


def _values(values) -> dict:
    """``values`` checked against :data:`FIT_PARAMETERS`, with the optional ones' zeros."""
    if not isinstance(values, dict):
        raise ValueError(f"values must be a dict of {', '.join(FIT_PARAMETERS)}; got {values!r}")
    unknown = sorted(set(values) - set(FIT_PARAMETERS))
    missing = [k for k in _REQUIRED if k not in values]
    if unknown or missing:
        names = ", ".join(FIT_PARAMETERS)
        raise ValueError(f"values: unknown parameter {unknown[0]!r}; the blow's are {names}"
                         if unknown else f"values needs {missing[0]!r} ({FIT_PARAMETERS[missing[0]]})")
    out = dict.fromkeys(FIT_PARAMETERS, 0.0)
    for k, x in values.items():
        out[k] = check_real(k, x, lo=0.0, lo_open=k in _REQUIRED)
    if out["rock.k_u"] < out["rock.k"]:
        raise ValueError(f"rock.k_u must be at least rock.k ({out['rock.k']:g} N/m); got {out['rock.k_u']:g}")
    return out


@dataclass(frozen=True)
class Comparison:
    r"""A measured history beside the model's, on the measurement's times.

    Attributes
    ----------
    time : numpy.ndarray, shape (t,)
        Times (s).
    measured, model : numpy.ndarray, shape (t,)
        The two histories (the model's shifted by ``shift``).
    shift : float
        The model's delay (s) that best overlays it on the measurement (0 where not sought).
    residual : numpy.ndarray, shape (t,)
        ``model - measured``.
    misfit : float
        The residual's root mean square over the measurement's (0: identical).
    peak_ratio : float
        The model's largest magnitude over the measurement's.
    """

    time: np.ndarray
    measured: np.ndarray
    model: np.ndarray
    shift: float
    residual: np.ndarray = field(repr=False)
    misfit: float
    peak_ratio: float

    def plot(self, ax=None, *, label: str = "strain"):
        """The two histories and their residual on one axis (matplotlib); returns the axis."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(7, 3.5))
        ms = 1e3 * self.time
        ax.plot(ms, self.measured, color="0.3", lw=1.2, label="measured")
        ax.plot(ms, self.model, color="C3", lw=1.0, ls="--",
                label=f"model (shifted {1e6 * self.shift:+.2f} µs)" if self.shift else "model")
        ax.plot(ms, self.residual, color="C0", lw=0.8, alpha=0.7,
                label=f"residual (misfit {self.misfit:.2%})")
        ax.set_xlabel("time (ms)")
        ax.set_ylabel(label)
        ax.legend(fontsize=8)
        return ax


def compare(time, measured, model, *, max_shift: float = 0.0) -> Comparison:
    r"""A measured history against the model's, with the misfit.

    Parameters
    ----------
    time : array_like, shape (t,)
        The measurement's times (s), increasing.
    measured : array_like, shape (t,)
        The measured history.
    model : callable or array_like
        The model's history: a function of the times (s) returning shape (t,), or its values on
        ``time`` (then no shift is sought).
    max_shift : float, optional
        The largest delay (s) of the model sought to overlay it best (a trigger's offset): the
        least-squares delay on a grid of a twentieth of the sampling step, within ``±max_shift``;
        0 (default) compares as given.

    Returns
    -------
    Comparison

    Raises
    ------
    ValueError
        Histories of other lengths, times not increasing, a measurement of zeros, a negative
        ``max_shift`` or a shift asked of values.

    Examples
    --------
    >>> t = np.linspace(0.0, 1e-3, 201)
    >>> pulse = lambda s: np.exp(-((s - 4e-4) / 1e-4) ** 2)
    >>> c = compare(t, pulse(t - 2e-6), pulse, max_shift=1e-5)
    >>> round(c.shift * 1e6, 3), c.misfit < 1e-3
    (2.0, True)
    """
    t = np.asarray(time, dtype=float)
    y = np.asarray(measured, dtype=float)
    if t.ndim != 1 or y.shape != t.shape:
        raise ValueError(f"measured must have the shape of time {t.shape}; got {y.shape}")
    if t.size < 2 or not np.all(np.diff(t) > 0):
        raise ValueError("time must increase, with two samples at least")
    scale = float(np.sqrt(np.mean(y * y)))
    if not scale > 0.0 or not math.isfinite(scale):
        raise ValueError("measured must be finite and not all zero")
    max_shift = check_real("max_shift", max_shift, lo=0.0)
    if callable(model):
        def at(s):
            m = np.asarray(model(t - s), dtype=float)
            if m.shape != t.shape:
                raise ValueError(f"model(time) must return shape {t.shape}; got {m.shape}")
            return m
        shift = 0.0
        if max_shift > 0.0:
            step = float(np.median(np.diff(t))) / 20.0
            grid = np.arange(-max_shift, max_shift + 0.5 * step, step)
            shift = float(grid[int(np.argmin([np.sum((at(s) - y) ** 2) for s in grid]))])
        m = at(shift)
    else:
        if max_shift > 0.0:
            raise ValueError("max_shift needs the model as a function of time, not its values")
        m, shift = np.asarray(model, dtype=float), 0.0
        if m.shape != t.shape:
            raise ValueError(f"model must have the shape of time {t.shape}; got {m.shape}")
    r = m - y
    return Comparison(t, y, m, shift, r, float(np.sqrt(np.mean(r * r))) / scale,
                      float(np.max(np.abs(m)) / np.max(np.abs(y))))


@dataclass(frozen=True)
class BlowFit:
    """The blow's parameters fitted to gauge recordings (:func:`fit_blow`).

    Attributes
    ----------
    values : dict
        Every parameter of the blow (:data:`FIT_PARAMETERS`' names), the varied ones at the fit.
    errors : dict
        Each varied parameter's standard error (its unit), from the fit's Jacobian.
    comparisons : dict
        Each station (m) to its :class:`Comparison` at the fit.
    misfit : float
        The residuals' root mean square over the measurements', all stations together.
    evaluations : int
        Blows computed.
    """

    values: dict
    errors: dict
    comparisons: dict = field(repr=False)
    misfit: float
    evaluations: int


def fit_blow(time, strains: dict, rod, *, piston_lengths, piston_areas, values: dict, vary, E=None,
             density=None) -> BlowFit:
    r"""Fit the blow's named parameters to the strains recorded at gauge stations (the module's
    least squares and standard errors).

    Parameters
    ----------
    time : array_like, shape (t,)
        The recording's times (s) from the impact.
    strains : dict
        Each gauge station (m from the rod's struck end) to its strain history, shape (t,), tension
        positive.
    rod, piston_lengths, piston_areas, E, density
        As :func:`gauge_strains`'.
    values : dict
        The start of the varied parameters and the values of the others (:func:`gauge_strains`).
    vary : sequence of str
        The parameters to fit, from :data:`FIT_PARAMETERS` (at least one; ``rock.k_u >= rock.k``
        is kept by fitting ``rock.k_u`` as ``rock.k`` times a factor of at least 1 where both vary).

    Returns
    -------
    BlowFit

    Raises
    ------
    ValueError
        An unknown or repeated name in ``vary``, a start out of its range, strains of another
        shape, no station (each named).

    Examples
    --------
    >>> from impactbar.physical.rock import RodPiece
    >>> rod = [RodPiece(length_m=3.0, area_m2=1.0e-3, E_Pa=2.1e11, density_kg_m3=7850.0)]
    >>> t = np.linspace(0.0, 2.5e-3, 500)
    >>> true = {"impact_velocity": 10.0, "rock.k": 3e8, "rock.k_u": 3e9}
    >>> piston = {"piston_lengths": [0.3], "piston_areas": [1.0e-3]}
    >>> eps = gauge_strains(rod, **piston, values=true, stations=[1.0, 1.4], time=t)
    >>> fit = fit_blow(t, eps, rod, **piston, values={**true, "impact_velocity": 8.0, "rock.k": 2e8},
    ...                vary=["impact_velocity", "rock.k"])
    >>> round(fit.values["impact_velocity"], 6), round(fit.values["rock.k"] / 1e8, 6)
    (10.0, 3.0)
    """
    from scipy.optimize import least_squares

    names = list(vary) if not isinstance(vary, str) else [vary]
    if not names:
        raise ValueError(f"vary must name at least one of {', '.join(FIT_PARAMETERS)}")
    for n in names:
        if n not in FIT_PARAMETERS:
            raise ValueError(f"vary: unknown parameter {n!r}; the blow's are {', '.join(FIT_PARAMETERS)}")
    if len(set(names)) != len(names):
        raise ValueError(f"vary names a parameter twice: {names}")
    start = _values(values)
    rod = model_rod(rod)
    t = np.asarray(time, dtype=float)
    if not isinstance(strains, dict) or not strains:
        raise ValueError("strains must be a dict of gauge stations (m) to strain histories")
    stations = list(strains)
    data = {}
    for x in stations:
        y = np.asarray(strains[x], dtype=float)
        if y.shape != t.shape:
            raise ValueError(f"strains[{x!r}] must have the shape of time {t.shape}; got {y.shape}")
        data[x] = y
    measured = np.concatenate([data[x] for x in stations])
    scale = float(np.sqrt(np.mean(measured ** 2)))
    if not scale > 0.0:
        raise ValueError("strains are all zero: no blow to fit")
    ratio = "rock.k" in names and "rock.k_u" in names  # (k_u = k * (1 + u), u >= 0)
    x0 = np.array([start["rock.k_u"] / start["rock.k"] - 1.0 if (ratio and n == "rock.k_u") else start[n]
                   for n in names])
    typ = np.where(x0 > 0.0, x0, 1.0)
    count = [0]

    def unpack(z):
        out = dict(start)
        for n, zi, s in zip(names, z, typ, strict=True):
            out[n] = float(zi * s)
        if ratio:
            out["rock.k_u"] = out["rock.k"] * (1.0 + out["rock.k_u"])
        return out

    def strains_of(z):
        count[0] += 1
        return gauge_strains(rod, piston_lengths=piston_lengths, piston_areas=piston_areas, values=unpack(z),
                             stations=stations, time=t, E=E, density=density)

    def residual(z):
        eps = strains_of(z)
        return np.concatenate([eps[x] - data[x] for x in stations]) / scale

    lower = np.array([0.0 if (ratio and n == "rock.k_u") or n not in _REQUIRED else 1e-9 for n in names])
    res = least_squares(residual, x0 / typ, bounds=(lower, np.inf), x_scale="jac", xtol=1e-12, ftol=1e-12,
                        gtol=1e-12)
    best = unpack(res.x)
    dof = max(1, measured.size - len(names))
    # the residuals' variance and the covariance of z, both in the residual's scale (it cancels)
    cov = 2.0 * res.cost / dof * np.linalg.pinv(res.jac.T @ res.jac)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0)) * typ
    errors = {}
    for i, n in enumerate(names):
        if ratio and n == "rock.k_u":  # k_u = k (1 + u): first order in both
            jk = names.index("rock.k")
            g = np.zeros(len(names))
            g[jk], g[i] = (1.0 + res.x[i] * typ[i]) * typ[jk], best["rock.k"] * typ[i]
            errors[n] = float(math.sqrt(max(g @ cov @ g, 0.0)))
        else:
            errors[n] = float(sd[i])
    eps = strains_of(res.x)
    comparisons = {x: compare(t, data[x], eps[x]) for x in stations}
    misfit = float(np.sqrt(np.mean(np.concatenate([eps[x] - data[x] for x in stations]) ** 2))) / scale
    return BlowFit(best, errors, comparisons, misfit, count[0])
