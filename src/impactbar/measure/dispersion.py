r"""The first longitudinal mode of a round bar: its phase velocity (Pochhammer and Chree's frequency
equation, as Bancroft tabulated it) and a wave carried along the bar with it.

A one-dimensional bar carries every frequency at :math:`c_0 = \sqrt{E/\rho}`. A round bar of radius
:math:`a` carries its first longitudinal mode slower as the wavelength :math:`\Lambda` shrinks toward
the diameter: the phase velocity :math:`c` of a wave :math:`e^{i(kz - \omega t)}` solves the
Pochhammer-Chree frequency equation (Graff, *Wave Motion in Elastic Solids*, eq. 8.1.25),

.. math::

    \frac{2\alpha}{a}(\beta^2 + k^2)\,J_1(\alpha a)J_1(\beta a)
    - (\beta^2 - k^2)^2\,J_0(\alpha a)J_1(\beta a)
    - 4k^2\alpha\beta\,J_1(\alpha a)J_0(\beta a) = 0,

with :math:`\alpha^2 = \omega^2/c_1^2 - k^2`, :math:`\beta^2 = \omega^2/c_2^2 - k^2`, the dilatational
and shear speeds :math:`c_1^2 = c_0^2 (1-\nu)/((1+\nu)(1-2\nu))`, :math:`c_2^2 = c_0^2 / (2(1+\nu))`
(:math:`\nu` Poisson's ratio). Divided by :math:`\beta` it is a real function of
:math:`\alpha^2` and :math:`\beta^2` on either side of zero (:math:`x J_1(x)`, :math:`J_1(x)/x` and
:math:`J_0(x)` are even; for :math:`x = ip` they are :math:`-p I_1(p)`, :math:`I_1(p)/p` and
:math:`I_0(p)`), so the first
mode's :math:`c/c_0` for a given :math:`a/\Lambda` is its largest root below :math:`c_0`, found by a
scan and Brent's method (Bancroft, 1941, tabulated these roots). It falls from 1 as
:math:`1 - \nu^2\pi^2(a/\Lambda)^2` (Rayleigh's correction, Love) toward the Rayleigh surface wave's
speed at short wavelengths.

A wave recorded at one station is carried a distance :math:`\Delta z` along the bar by shifting the
phase of each of its Fourier components by :math:`\omega\,\Delta z / c(\omega)` (Follansbee and Frantz,
1983; Tyas and Watson, 2001): :func:`disperse`. At low frequencies this is the plain delay
:math:`\Delta z / c_0`; toward the specimen (:math:`\Delta z > 0` in the wave's direction) the
high-frequency ripple of a step runs behind its front. The radial variation of strain and stress
across the section (Tyas and Wilson's factors :math:`M_1`, :math:`M_2`) is not corrected: the
gauge's surface strain is taken for the section's mean.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .._shared.validate import check_real
from .recording import Bar

__all__ = ["phase_velocity", "disperse"]


def _even(x2: np.ndarray, kind: str) -> np.ndarray:
    """``J0(x)`` (``"J0"``), ``x J1(x)`` (``"xJ1"``) or ``J1(x) / x`` (``"J1/x"``) as functions of
    ``x2 = x^2`` of either sign (``x = i p``: ``I0(p)``, ``-p I1(p)``, ``I1(p) / p``)."""
    from scipy.special import i0, i1, j0, j1

    x = np.sqrt(np.abs(x2))
    if kind == "J0":
        return np.where(x2 >= 0.0, j0(x), i0(x))
    if kind == "xJ1":
        return np.where(x2 >= 0.0, x * j1(x), -x * i1(x))
    safe = np.where(x > 0.0, x, 1.0)
    return np.where(x > 0.0, np.where(x2 >= 0.0, j1(safe), i1(safe)) / safe, 0.5)


def _frequency_equation(c: np.ndarray, k: float, nu: float) -> np.ndarray:
    """The Pochhammer-Chree equation over ``beta`` (the module's, radius 1, ``c0`` 1; divided by
    ``beta``, which multiplies each term, so that ``beta = 0`` is no root), at phase velocities ``c``
    and wavenumber ``k``."""
    c1sq = (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))
    c2sq = 1.0 / (2.0 * (1.0 + nu))
    w2 = (c * k) ** 2
    a2, b2 = w2 / c1sq - k * k, w2 / c2sq - k * k
    sa, tb = _even(a2, "xJ1"), _even(b2, "J1/x")  # alpha J1(alpha), J1(beta) / beta (radius 1)
    ca, cb = _even(a2, "J0"), _even(b2, "J0")
    return 2.0 * (b2 + k * k) * sa * tb - (b2 - k * k) ** 2 * ca * tb - 4.0 * k * k * sa * cb


def _first_mode(k: float, nu: float) -> float:
    """The first mode's phase velocity over ``c0`` at wavenumber ``k`` (radius 1)."""
    from scipy.optimize import brentq

    if k < 1e-6:
        return 1.0 - nu * nu * k * k / 4.0  # (Rayleigh's correction; exact to O(k^4))
    grid = np.linspace(0.3, 1.0, 281)  # (the first mode is the slowest: above the Rayleigh wave's)
    g = _frequency_equation(grid, k, nu)
    s = np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]
    if s.size == 0:
        raise ValueError(f"no first-mode root at k a = {k:g} (Poisson's ratio {nu:g})")
    i = int(s[0])
    return float(brentq(lambda c: float(_frequency_equation(np.array([c]), k, nu)[0]), grid[i], grid[i + 1],
                        xtol=1e-15, rtol=4 * np.finfo(float).eps))


@functools.lru_cache(maxsize=8)
def _table(nu: float) -> tuple[np.ndarray, np.ndarray]:
    """The first mode's ``omega a / c0`` and ``c / c0`` on a table of ``k a`` (``omega`` rises with
    ``k``: the mode's group velocity stays positive), to interpolate a frequency's velocity."""
    ka = np.concatenate(([0.0], np.geomspace(1e-4, 12.0, 400)))
    cr = np.array([_first_mode(k, nu) for k in ka])
    return ka * cr, cr


def phase_velocity(frequency, radius: float, bar: Bar, poisson: float) -> np.ndarray:
    r"""The first longitudinal mode's phase velocity in a round bar (the module's frequency equation).

    Parameters
    ----------
    frequency : array_like, shape (n,)
        Frequencies (Hz), ``>= 0``.
    radius : float
        The bar's radius :math:`a` (m), ``> 0``.
    bar : Bar
        The bar (its :attr:`~Bar.wave_speed` :math:`c_0`).
    poisson : float
        Poisson's ratio :math:`\nu`, in ``(0, 0.5)``.

    Returns
    -------
    numpy.ndarray, shape (n,)
        :math:`c(f)` (m/s), :math:`c_0` at 0.

    Raises
    ------
    ValueError
        A parameter out of its range (named), or a frequency beyond the table's reach
        (:math:`f a / c_0 > 1`, where the first mode's velocity is near the Rayleigh wave's).

    Examples
    --------
    >>> bar = Bar(200e9, 7850.0, math.pi * 0.01 ** 2)
    >>> c = phase_velocity([0.0, 50e3], 0.01, bar, 0.29)
    >>> round(float(c[0] / bar.wave_speed), 6), round(float(c[1] / bar.wave_speed), 4)
    (1.0, 0.9911)
    """
    a = check_real("radius", radius, lo=0.0, lo_open=True)
    nu = check_real("poisson", poisson, lo=0.0, hi=0.5, lo_open=True, hi_open=True)
    f = np.atleast_1d(np.asarray(frequency, dtype=float))
    if not np.all(np.isfinite(f)) or np.any(f < 0.0):
        raise ValueError("frequency must be finite and >= 0 (Hz)")
    c0 = bar.wave_speed
    fa = f * a / c0  # normalised frequency
    if np.any(fa > 1.0):
        raise ValueError(f"frequency: f a / c0 must be at most 1 (the first mode's reach here); got "
                         f"{float(fa.max()):.3g} at {float(f.max()):.4g} Hz")
    wa, cr = _table(nu)
    w = 2.0 * math.pi * fa
    if np.any(w > wa.max()):
        raise ValueError("frequency beyond the table of the first mode")
    return c0 * np.interp(w, wa, cr)


def disperse(time, wave, distance: float, radius: float, bar: Bar, poisson: float) -> np.ndarray:
    r"""A wave carried ``distance`` along a round bar in its first longitudinal mode (the module's
    phase shift), on the same times.

    Parameters
    ----------
    time : array_like, shape (n,)
        Equally spaced times (s).
    wave : array_like, shape (n,)
        The wave at the first station (a strain), zero at both ends of the record (it is padded
        to twice its length against wrap-around).
    distance : float
        How far it travels (m), in its own direction (negative: back, to undo a dispersion).
    radius, bar, poisson
        As :func:`phase_velocity`'s.

    Returns
    -------
    numpy.ndarray, shape (n,)
        The wave at the second station; components above the first mode's reach
        (:math:`f a / c_0 > 1`) are dropped.

    Raises
    ------
    ValueError
        Times not equally spaced, a wave of another length, a parameter out of its range.

    Examples
    --------
    A 20 mm steel bar: a step's front 40 cm on, its ripple running behind (the slower high
    frequencies), its plateau the same:

    >>> bar = Bar(200e9, 7850.0, math.pi * 0.01 ** 2)
    >>> t = np.arange(4096) * 1e-7
    >>> step = np.where((t > 20e-6) & (t < 200e-6), 1.0, 0.0)
    >>> moved = disperse(t, step, 0.4, 0.01, bar, 0.29)
    >>> delay = 0.4 / bar.wave_speed
    >>> plain = np.interp(t - delay, t, step)
    >>> round(float(moved[t.searchsorted(150e-6)]), 3), bool(np.max(np.abs(moved - plain)) > 0.1)
    (1.0, True)
    """
    t = np.asarray(time, dtype=float)
    y = np.asarray(wave, dtype=float)
    if t.ndim != 1 or y.shape != t.shape or t.size < 4:
        raise ValueError(f"wave must have the shape of time {t.shape} (4 samples at least); got {y.shape}")
    dt = float(t[1] - t[0])
    if not dt > 0.0 or np.max(np.abs(np.diff(t) - dt)) > 1e-6 * dt:
        raise ValueError("time must be equally spaced and increasing")
    dz = check_real("distance", distance)
    n = 2 * t.size
    f = np.fft.rfftfreq(n, dt)
    a = check_real("radius", radius, lo=0.0, lo_open=True)
    keep = f * a / bar.wave_speed <= 1.0
    c = np.full(f.shape, np.inf)
    c[keep] = phase_velocity(f[keep], a, bar, poisson)
    spectrum = np.fft.rfft(y, n)
    spectrum = np.where(keep, spectrum * np.exp(-2j * math.pi * f * dz / c), 0.0)
    return np.fft.irfft(spectrum, n)[: t.size]
