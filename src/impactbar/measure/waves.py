r"""Waves from gauges: pulses found in a channel, and the two waves of a bar separated.

In a bar of wave speed :math:`c`, with the station :math:`x` measured from the end of interest into
the bar, the axial strain is the sum of a wave travelling toward the end and one travelling away,

.. math:: \varepsilon(x, t) = a(t + x/c) + b(t - x/c),

:math:`a(t)` and :math:`b(t)` being the two waves at the end (:math:`x = 0`). A gauge at :math:`x`
sees the wave toward the end :math:`x/c` before the end does, and the wave away from it :math:`x/c`
after.

*One-point separation* reads each wave in a time window of one gauge where it is alone (the
incident and reflected pulses of a Kolsky bar, Kolsky 1949) and shifts it to the end. *Two-point
separation* (Lundberg and Henchoz 1977, "Analysis of elastic waves from two-point strain
measurement", *Experimental Mechanics* 17, 213-218) needs no such window: from two gauges at
:math:`x_A < x_B`, :math:`\tau = (x_B - x_A)/c` apart, the wave toward the end at :math:`A`,
:math:`p(t) = a(t + x_A/c)`, obeys

.. math:: p(t) = \varepsilon_B(t - \tau) - \varepsilon_A(t - 2\tau) + p(t - 2\tau),

marched from a quiet start (:math:`p = 0` before the first wave), and the other is
:math:`q = \varepsilon_A - p`. Its frequency-domain form :math:`P = (E_B - E_A e^{-i\omega\tau}) /
(2 i \sin\omega\tau)` (Yanagihara 1978; Park and Zhou 1999) shows the method's ill-conditioning: at
the frequencies :math:`f = n c / (2 (x_B - x_A))` (the spacing a multiple of half a wavelength,
:math:`n = 0` the mean included) the two gauges see the same thing and the waves cannot be told apart.
In the recursion these are its poles: an offset of the channels grows linearly, noise at those
frequencies as a random walk, :math:`\sqrt{t / 2\tau}`. It is handled by removing each channel's
pre-trigger mean and, optionally, by a leak :math:`\lambda < 1` in :math:`\lambda\,p(t - 2\tau)`,
which bounds the gain at the poles by :math:`1/(1 - \lambda)` and biases the waves' slowest parts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._shared.columns import IV_HI, IV_LO
from .recording import Bar

__all__ = ["Waves", "Window", "find_pulses", "noise_level", "shift", "separate_one_point",
           "separate_two_point"]


@dataclass(frozen=True)
class Window:
    """A pulse found in a channel: the samples ``start`` to ``stop`` (exclusive) and their times.

    Attributes
    ----------
    start, stop : int
        The sample indices (``stop`` exclusive).
    t_start, t_stop : float (s)
        The window's first and last times (the pulse's foot and tail).
    sign : int
        +1 for a pulse of positive values, -1 for negative.
    peak : float
        The (low-passed) signal's largest magnitude in the window, signed.
    """

    start: int
    stop: int
    t_start: float
    t_stop: float
    sign: int
    peak: float

    @property
    def duration(self) -> float:
        """``t_stop - t_start`` (s)."""
        return self.t_stop - self.t_start

    def to_dict(self) -> dict:
        """The window in microseconds, for printing."""
        return {"start_us": round(self.t_start * 1e6, 3), "stop_us": round(self.t_stop * 1e6, 3),
                "sign": self.sign, "peak": self.peak}


@dataclass(frozen=True)
class Waves:
    """The two waves at a bar's end: ``toward`` it (:math:`a`) and ``away`` from it (:math:`b`), as
    strains (tension positive) on the time base ``time`` (s)."""

    time: np.ndarray
    toward: np.ndarray
    away: np.ndarray


def noise_level(signal, baseline: slice | None = None) -> tuple[float, float]:
    """The offset and the noise (a robust standard deviation, 1.4826 times the median absolute
    deviation) of a channel's quiet part, by default its first tenth."""
    signal = np.asarray(signal, dtype=float)
    quiet = signal[baseline if baseline is not None else slice(0, max(8, signal.size // 10))]
    offset = float(np.median(quiet))
    return offset, float(1.4826 * np.median(np.abs(quiet - offset)))


def lowpass(signal, dt: float, cutoff: float) -> np.ndarray:
    """A zero-phase fourth-order Butterworth low-pass (``scipy.signal.sosfiltfilt``)."""
    from scipy.signal import butter, sosfiltfilt

    nyquist = 0.5 / dt
    if not 0 < cutoff < nyquist:
        raise ValueError(f"cutoff must lie in (0, {nyquist:g}) Hz (the Nyquist frequency), got {cutoff!r}")
    return sosfiltfilt(butter(4, cutoff / nyquist, output="sos"), np.asarray(signal, dtype=float))


def find_pulses(time, signal, *, threshold: float = 10.0, cutoff: float | None = None,
                baseline: slice | None = None, min_duration: float = 0.0, name: str = "signal"
                ) -> list[Window]:
    """The pulses of a channel, found where it leaves its noise band.

    The channel, low-passed at ``cutoff`` (Hz) when given, is a pulse where it stays beyond
    ``threshold`` times its noise (:func:`noise_level`) on one side of its offset; each such run is
    widened to the last sample before it and the first after it where the signal comes back
    within twice the noise (the pulse's foot and tail), and runs closer than that are one pulse.

    Parameters
    ----------
    time, signal : array_like, shape (n,)
    threshold : float
        The detection level in noise standard deviations (> 2).
    cutoff : float (Hz), optional
    baseline : slice, optional
        The quiet samples (default: the first tenth).
    min_duration : float (s)
        Shorter pulses are dropped.
    name : str
        The channel's name, for the error.

    Returns
    -------
    list of Window
        In time order.

    Raises
    ------
    ValueError
        No pulse: the channel never leaves its noise band.

    Examples
    --------
    >>> t = np.arange(1000) * 1e-7
    >>> s = np.where((t > 30e-6) & (t < 40e-6), -1.0, 0.0) + 1e-3 * np.sin(1e6 * t)
    >>> [w.to_dict()["start_us"] for w in find_pulses(t, s)]
    [30.0]
    """
    time = np.asarray(time, dtype=float)
    if not threshold > 2:
        raise ValueError(f"threshold must be > 2 (noise standard deviations), got {threshold!r}")
    raw = np.asarray(signal, dtype=float)
    smooth = lowpass(raw, time[1] - time[0], cutoff) if cutoff is not None else raw
    offset, noise = noise_level(smooth, baseline)
    s = smooth - offset
    noise = max(noise, 1e-12 * max(1.0, float(np.max(np.abs(s)))))
    windows = []
    for sign in (1, -1):
        above = sign * s > threshold * noise
        quiet = sign * s <= 2 * noise
        runs = np.flatnonzero(np.diff(np.concatenate(([0], above.astype(np.int8), [0])))).reshape(-1, 2)
        for i0, i1 in zip(runs[:, IV_LO], runs[:, IV_HI], strict=True):  # each run above: first, after last
            before = np.flatnonzero(quiet[:i0])
            after = np.flatnonzero(quiet[i1:])
            start = int(before[-1]) if before.size else 0
            stop = int(i1 + after[0] + 1) if after.size else s.size
            w_start, w_stop, w_sign = windows[-1] if windows else (0, 0, 0)
            if windows and w_sign == sign and start <= w_stop:
                windows[-1] = (w_start, max(stop, w_stop), sign)
            else:
                windows.append((start, stop, sign))
    if not windows:
        raise ValueError(f"no pulse in {name}: it never leaves its noise band ({threshold:g} x "
                         f"{noise:.3g} about {offset:.3g})")
    found = []
    for start, stop, sign in sorted(windows):
        seg = s[start:stop]
        w = Window(start, stop, float(time[start]), float(time[stop - 1]), sign,
                   float(seg[np.argmax(sign * seg)]))
        if w.duration >= min_duration:
            found.append(w)
    return found


def shift(time, wave, delay: float) -> np.ndarray:
    """``wave(t - delay)`` on the same time base, linearly interpolated, zero outside the record
    (exact for a delay of whole samples)."""
    time = np.asarray(time, dtype=float)
    return np.interp(time - delay, time, np.asarray(wave, dtype=float), left=0.0, right=0.0)


def separate_one_point(time, strain, toward: Window, away: Window, station: float, bar: Bar) -> Waves:
    """The waves at a bar's end from one gauge, each read in its own window.

    ``a(t) = s_toward(t - x/c)``, ``b(t) = s_away(t + x/c)``: the gauge's strain inside each window
    (zero outside), shifted by the gauge's travel time :math:`x/c` to the end.

    Raises
    ------
    ValueError
        The two windows overlap at the gauge (the waves are not apart there: use
        :func:`separate_two_point`).
    """
    if toward.start < away.stop and away.start < toward.stop:
        raise ValueError(f"the pulses overlap at the gauge ({toward.t_start * 1e6:.2f}-"
                         f"{toward.t_stop * 1e6:.2f} us and {away.t_start * 1e6:.2f}-"
                         f"{away.t_stop * 1e6:.2f} us): one-point separation needs them apart; use "
                         "two-point separation")
    strain = np.asarray(strain, dtype=float)
    delay = station / bar.wave_speed
    parts = []
    for w, d in ((toward, delay), (away, -delay)):
        alone = np.zeros_like(strain)
        alone[w.start:w.stop] = strain[w.start:w.stop]
        parts.append(shift(time, alone, d))
    return Waves(np.asarray(time, dtype=float), parts[0], parts[1])


def separate_two_point(time, near, far, station_near: float, station_far: float, bar: Bar, *,
                       leak: float = 1.0, baseline: slice | None = None, cutoff: float | None = None
                       ) -> Waves:
    r"""The waves at a bar's end from two gauges (Lundberg and Henchoz 1977), pulses overlapping or not.

    Parameters
    ----------
    time : array_like, shape (n,) (s)
        The record's time base, which must start before any wave reaches either gauge.
    near, far : array_like, shape (n,)
        The strains of the gauge nearer the end and the one farther.
    station_near, station_far : float (m)
        Their distances from the end, ``station_far - station_near`` at least one sample's travel.
    bar : Bar
    leak : float
        :math:`\lambda` in (0, 1]: 1 is the exact recursion; below 1 it bounds the gain at the
        frequencies where the method fails by :math:`1/(1-\lambda)` (see the module).
    baseline : slice, optional
        The quiet samples whose median is removed from each channel; None removes nothing.
    cutoff : float (Hz), optional
        Both channels low-passed (:func:`lowpass`) first, below the first failing frequency
        :math:`c / (2 (x_B - x_A))`, so that no noise reaches the poles above it (the waves then are
        those low-passed alike).

    Returns
    -------
    Waves
        At the end, on the record's time base up to the last time the wave away from the end is
        known there (``x_near / c`` before the record's end).

    Examples
    --------
    >>> bar = Bar(200e9, 7850.0, 1e-3, wave_speed=5000.0)
    >>> t = np.arange(400) * 1e-6
    >>> a = lambda t: np.exp(-((t - 100e-6) / 10e-6) ** 2)  # a long pulse: it overlaps its echo
    >>> b = lambda t: -0.5 * a(t - 10e-6)
    >>> gauge = lambda x: a(t + x / 5000.0) + b(t - x / 5000.0)
    >>> w = separate_two_point(t, gauge(0.1), gauge(0.15), 0.1, 0.15, bar)
    >>> bool(np.max(np.abs(w.toward - a(w.time))) < 1e-12)
    True
    """
    time = np.asarray(time, dtype=float)
    eA, eB = (np.asarray(v, dtype=float).copy() for v in (near, far))
    if eA.shape != time.shape or eB.shape != time.shape:
        raise ValueError(f"near and far must have the time's {time.size} samples, got {eA.size} and "
                         f"{eB.size}")
    if baseline is not None:
        eA -= np.median(eA[baseline])
        eB -= np.median(eB[baseline])
    dt = time[1] - time[0]
    tau = (station_far - station_near) / bar.wave_speed
    if not (math.isfinite(tau) and tau >= dt / 2 and station_near >= 0):
        raise ValueError(f"station_far - station_near must be >= 0 and the gauges at least half a "
                         f"sample's travel ({0.5 * dt * bar.wave_speed:.3g} m) apart, got {station_near!r} "
                         f"and {station_far!r}")
    if not 0 < leak <= 1:
        raise ValueError(f"leak must lie in (0, 1], got {leak!r}")
    if cutoff is not None:
        eA, eB = lowpass(eA, dt, cutoff), lowpass(eB, dt, cutoff)
    drive = shift(time, eB, tau) - shift(time, eA, 2 * tau)
    p = _march(drive, 2 * tau / dt, leak)
    q = eA - p
    lead = station_near / bar.wave_speed
    keep = time + lead <= time[-1] - 1e-6 * dt
    return Waves(time[keep], shift(time, p, lead)[keep], shift(time, q, -lead)[keep])


def _march(drive: np.ndarray, lag: float, leak: float) -> np.ndarray:
    """``p[k] = drive[k] + leak * p(k - lag)``, ``p`` zero before the record, linear between samples."""
    p = np.zeros_like(drive)
    whole = int(math.floor(lag + 1e-9))
    frac = lag - whole
    if frac < 1e-9:  # whole samples: one first-order recursion on each residue class
        from scipy.signal import lfilter

        for r in range(min(whole, drive.size)):
            p[r::whole] = lfilter([1.0], [1.0, -leak], drive[r::whole])
        return p
    for k in range(drive.size):  # p(k - lag) between p[k - whole - 1] and p[k - whole]
        j = k - whole
        hi = p[j] if j >= 0 else 0.0
        lo = p[j - 1] if j >= 1 else 0.0
        p[k] = drive[k] + leak * ((1 - frac) * hi + frac * lo)
    return p
