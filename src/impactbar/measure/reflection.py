r"""A bar's wave speed from a reflection time: the delay between a pulse and its echo at one gauge,
fitted by least squares, with its standard error from the fit's Jacobian.

A gauge at the distance :math:`d` from a bar's end sees the pulse going toward the end, and then
its reflection :math:`\tau = 2 d / c` later; at a free end the reflection is the pulse inverted
(:math:`r = -1`), at a fixed end the pulse itself (:math:`r = 1`), at the specimen of a Kolsky bar
something between. The echo is modelled as the pulse read at the gauge (its window, zero outside),
delayed and scaled,

.. math:: \varepsilon(t) \approx r\,\varepsilon_I(t - \tau)

on the samples that the delayed pulse covers, widened by a quarter of its length on each side. The
delay between samples is the band-limited one (the pulse's Fourier series on a zero-padded record,
each component turned by :math:`e^{-2\pi i f \tau}`), exact for a pulse sampled above its Nyquist
rate. The start is the cross-correlation's peak over the delays where the pulse overlaps the echo's
window, refined by a parabola; ``scipy.optimize.least_squares`` then fits :math:`\tau` and
:math:`r` with the analytic Jacobian :math:`J`, and their covariance is
:math:`(1 + r^2)\,s^2 (J^\mathsf{T} J)^{-1}`, :math:`s^2` the residuals' sum of squares over the
degrees of freedom (the linearised model's, the noise taken white and alike on every sample), the
factor :math:`1 + r^2` counting the pulse's own noise, which enters the delay as the echo's does,
mirrored and scaled by :math:`r`. Where the record is noisy the pulse is band-limited first (its
components above a ``cutoff`` dropped, the echo's kept): the noise's steep slopes would otherwise
fill the Jacobian and the delay would fall among the cost's sample-scale ripples (with 1 % noise
the errors then come out at twice the standard errors; band-limited, within them).
The wave speed is :math:`c = 2 d / \tau`, its standard error
:math:`c\,\sigma_\tau / \tau` (the distance taken as exact).

A shape the echo does not share with the pulse (a specimen that yields, dispersion over :math:`2 d`)
biases :math:`\tau` by more than its standard error counts: the misfit says how far the echo is a
copy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._shared.validate import check_real
from .waves import Window

__all__ = ["ReflectionFit", "fit_reflection"]


@dataclass(frozen=True)
class ReflectionFit:
    r"""A wave speed fitted from a reflection time (:func:`fit_reflection`).

    Attributes
    ----------
    wave_speed, wave_speed_error : float (m/s)
        :math:`c = 2 d / \tau` and its standard error.
    delay, delay_error : float (s)
        The echo's delay :math:`\tau` after the pulse, and its standard error.
    ratio, ratio_error : float
        The echo's amplitude over the pulse's, :math:`r` (-1 at a free end), and its standard error.
    distance : float (m)
        The gauge's distance :math:`d` from the reflecting end.
    misfit : float
        The residuals' root mean square over the echo's, on the samples fitted (0: an exact copy).
    samples : int
        The samples fitted.
    """

    wave_speed: float
    wave_speed_error: float
    delay: float
    delay_error: float
    ratio: float
    ratio_error: float
    distance: float
    misfit: float
    samples: int

    def to_dict(self) -> dict:
        """The fit as plain numbers (the delay in microseconds), JSON-ready."""
        return {"wave_speed_m_s": self.wave_speed, "wave_speed_std_m_s": self.wave_speed_error,
                "delay_us": self.delay * 1e6, "delay_std_us": self.delay_error * 1e6, "ratio": self.ratio,
                "ratio_std": self.ratio_error, "distance_m": self.distance, "misfit": self.misfit,
                "samples": self.samples}


def _delayed(template: np.ndarray, dt: float, cutoff: float | None):
    """The template's band-limited delay and its derivative in the delay, on its own sample grid
    (its components above ``cutoff`` (Hz) dropped)."""
    n = template.size
    spectrum = np.fft.rfft(template)
    f = np.fft.rfftfreq(n, dt)
    if cutoff is not None:
        spectrum[f > cutoff] = 0.0

    def at(tau: float) -> tuple[np.ndarray, np.ndarray]:
        turned = spectrum * np.exp(-2j * np.pi * f * tau)
        return np.fft.irfft(turned, n), np.fft.irfft(-2j * np.pi * f * turned, n)

    return at


def fit_reflection(time, strain, distance: float, incident: Window, reflected: Window, *,
                   cutoff: float | None = None) -> ReflectionFit:
    r"""Fit the delay of a pulse's reflection at one gauge, and the wave speed :math:`2 d / \tau`
    (the module's least squares and standard errors).

    Parameters
    ----------
    time : array_like, shape (n,)
        The record's times (s), evenly spaced.
    strain : array_like, shape (n,)
        The gauge's strain (its offset removed), holding the pulse and its reflection apart.
    distance : float (m)
        The gauge's distance :math:`d` from the reflecting end, ``> 0``.
    incident, reflected : Window
        The pulse's window and its reflection's (:func:`~impactbar.measure.find_pulses`), the
        reflection's after the pulse's end.
    cutoff : float (Hz), optional
        The pulse's band: its components above it dropped (the echo's not), so that its noise's
        steep slopes do not enter the Jacobian; above the pulse's own band it changes no clean
        pulse. None keeps every component (for a clean record).

    Returns
    -------
    ReflectionFit

    Raises
    ------
    ValueError
        Times not evenly spaced or of another shape than the strain, a distance not finite and
        positive, windows outside the record, a reflection not after the pulse, a pulse of zeros,
        or a fitted delay that leaves the record (each named).

    Examples
    --------
    A Gaussian pulse 0.2 m from a free end of a bar of 5000 m/s, its echo inverted 80 us later:

    >>> from impactbar.measure import find_pulses
    >>> t = np.arange(4000) * 1e-7
    >>> pulse = lambda s: -np.exp(-((s - 60e-6) / 4e-6) ** 2)
    >>> eps = pulse(t) - pulse(t - 2 * 0.2 / 5000.0)
    >>> w = find_pulses(t, eps)
    >>> fit = fit_reflection(t, eps, 0.2, w[0], w[1])
    >>> round(fit.wave_speed, 6), round(fit.ratio, 9)
    (5000.0, -1.0)
    """
    from scipy.optimize import least_squares

    t = np.asarray(time, dtype=float)
    y = np.asarray(strain, dtype=float)
    if t.ndim != 1 or y.shape != t.shape or t.size < 8:
        raise ValueError(f"strain must have the shape of time (8 samples at least); got {y.shape} and "
                         f"{t.shape}")
    dt = float(t[1] - t[0])
    steps = np.diff(t)
    if not (dt > 0.0 and np.all(np.abs(steps - dt) <= 1e-6 * dt)):
        raise ValueError("time must be evenly spaced and increasing")
    d = check_real("distance", distance, lo=0.0, lo_open=True)
    if cutoff is not None:
        cutoff = check_real("cutoff", cutoff, lo=0.0, lo_open=True)
    n = t.size
    for name, w in (("incident", incident), ("reflected", reflected)):
        if not isinstance(w, Window) or not 0 <= w.start < w.stop <= n:
            raise ValueError(f"{name} must be a Window inside the record's {n} samples; got {w!r}")
    if reflected.start < incident.stop:
        raise ValueError(f"reflected must start after the incident pulse ends (sample {incident.stop}); it "
                         f"starts at sample {reflected.start}")
    m = incident.stop - incident.start
    pulse = y[incident.start:incident.stop]
    energy = float(pulse @ pulse)
    if not energy > 0.0:
        raise ValueError("the incident window holds no pulse (all zeros)")
    # the start: the cross-correlation's peak over the delays (whole samples) where the pulse overlaps
    # the reflection's window, refined by a parabola through its neighbours
    lags = np.arange(max(m, reflected.start - incident.stop + 1), reflected.stop - incident.start)
    lags = lags[incident.stop + lags <= n]
    if lags.size == 0:
        raise ValueError("the record ends before the incident pulse, delayed onto its reflection, does")
    corr = np.array([pulse @ y[incident.start + k:incident.stop + k] for k in lags])
    i = int(np.argmax(np.abs(corr)))
    frac = 0.0
    if 0 < i < lags.size - 1:
        a, b, c = np.abs(corr[i - 1:i + 2])
        if a - 2 * b + c < 0.0:
            frac = 0.5 * (a - c) / (a - 2 * b + c)
    lag = float(lags[i]) + frac
    # the samples fitted: those the delayed pulse covers, a quarter of its length wider each side
    margin = max(4, m // 4)
    lo = max(incident.stop, incident.start + int(lags[i]) - margin)
    hi = min(n, incident.stop + int(lags[i]) + margin)
    # the pulse alone on a zero-padded grid long enough that its delay does not wrap onto the samples
    size = 1 << int(math.ceil(math.log2(hi - incident.start + m + 2 * margin)))
    template = np.zeros(size)
    template[:m] = pulse
    delayed = _delayed(template, dt, cutoff)
    data = y[lo:hi]
    k = np.arange(lo, hi) - incident.start

    def residual(p):
        g, _ = delayed(p[0] * dt)
        return p[1] * g[k] - data

    def jacobian(p):
        g, dg = delayed(p[0] * dt)
        return np.column_stack([p[1] * dg[k] * dt, g[k]])

    p0 = np.array([lag, float(corr[i]) / energy])
    res = least_squares(residual, p0, jac=jacobian, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    tau_samples, ratio = (float(v) for v in res.x)
    if not (0.0 < tau_samples and incident.stop + tau_samples <= n):
        raise ValueError(f"the fitted delay ({tau_samples * dt * 1e6:.6g} us) leaves the record: no echo of "
                         "the pulse in the reflected window")
    dof = max(1, data.size - 2)
    r = res.fun
    # the pulse's noise enters the delay as the echo's does, mirrored and scaled by the ratio: both
    # counted, (1 + ratio^2) times the echo's alone
    cov = (1.0 + ratio * ratio) * float(r @ r) / dof * np.linalg.pinv(res.jac.T @ res.jac)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    tau, tau_sd = tau_samples * dt, float(sd[0]) * dt
    speed = 2.0 * d / tau
    scale = float(np.sqrt(np.mean(data * data)))
    return ReflectionFit(speed, speed * tau_sd / tau, tau, tau_sd, ratio, float(sd[1]), d,
                         float(np.sqrt(np.mean(r * r))) / scale if scale > 0.0 else math.inf, int(data.size))
