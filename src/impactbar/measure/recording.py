r"""Recordings in: oscilloscope channels, their bridges and the bars they sit on.

A strain-gauge channel records the output voltage of a Wheatstone bridge, amplified. With the
bridge's excitation :math:`V_{ex}`, the amplifier's gain :math:`G` and the gauges' gauge factor
:math:`GF`, the bridge ratio :math:`V_r = V_{out} / (G\,V_{ex})` gives the axial strain

.. math:: \varepsilon = \frac{4\,V_r}{GF\,n},

where :math:`n` counts the bridge's active arms: 1 for a quarter bridge, 2 for a half bridge of two
axial gauges (on opposite faces, in opposite arms, which cancels bending), :math:`1 + \nu` for a half
bridge of one axial and one transverse (Poisson) gauge, 4 for a full bridge of four axial gauges and
:math:`2 (1 + \nu)` for a full bridge of two axial and two transverse gauges (Vishay Precision Group,
*Tech Note TN-514*, "Shunt calibration of strain gage instrumentation", and *TN-507*, "Errors due to
Wheatstone bridge nonlinearity"). The linear form drops the quarter bridge's nonlinearity, a relative
error of about :math:`2 V_r` (:math:`3 \times 10^{-3}` at a strain of :math:`1.3 \times 10^{-3}`). The
half-bridge form is HopPyBar's (LANL), ``strain = V (2 / GF) / (gain excitation)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._shared.columns import IV_HI, IV_LO

__all__ = ["BRIDGES", "Bar", "Gauge", "Recording", "read_tektronix_csv"]

#: the bridges and their number of active arms (a function of Poisson's ratio)
BRIDGES = {
    "quarter": lambda nu: 1.0,
    "half": lambda nu: 2.0,
    "half-poisson": lambda nu: 1.0 + nu,
    "full": lambda nu: 4.0,
    "full-poisson": lambda nu: 2.0 * (1.0 + nu),
}


def _positive(name: str, value) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return value


@dataclass(frozen=True)
class Bar:
    r"""An elastic bar (or rod) of one cross-section, as the gauges see it.

    Parameters
    ----------
    young_modulus : float (Pa)
        Young's modulus :math:`E`.
    density : float (kg/m^3)
        Density :math:`\rho`.
    area : float (m^2)
        Cross-section :math:`A`.
    wave_speed : float (m/s), optional
        The bar wave speed :math:`c`; by default :math:`\sqrt{E/\rho}` (a measured one, from a
        reflection time, may be given instead).

    Examples
    --------
    >>> bar = Bar(71.7e9, 2810.0, 2.11e-3 ** 2)
    >>> round(bar.wave_speed, 1), round(bar.impedance, 3)
    (5051.3, 63.194)
    """

    young_modulus: float
    density: float
    area: float
    wave_speed: float | None = None

    def __post_init__(self) -> None:
        for name in ("young_modulus", "density", "area"):
            object.__setattr__(self, name, _positive(name, getattr(self, name)))
        c = math.sqrt(self.young_modulus / self.density) if self.wave_speed is None else \
            _positive("wave_speed", self.wave_speed)
        object.__setattr__(self, "wave_speed", c)

    @property
    def impedance(self) -> float:
        """The mechanical impedance :math:`Z = E A / c` (N s/m): a wave's force over its particle
        velocity."""
        return self.young_modulus * self.area / self.wave_speed

    @property
    def stiffness(self) -> float:
        """:math:`E A` (N): a strain's force."""
        return self.young_modulus * self.area


@dataclass(frozen=True)
class Gauge:
    """A strain-gauge channel: its bridge, its amplifier and where it sits on which bar.

    Parameters
    ----------
    bar : str
        The name of the bar it is glued to.
    station : float (m)
        Its distance from the bar's end of interest (the specimen's face, the bit), >= 0.
    bridge : {'quarter', 'half', 'half-poisson', 'full', 'full-poisson'}
        The bridge (see the module's formula).
    gauge_factor : float
        The gauges' gauge factor :math:`GF`.
    excitation : float (V)
        The bridge's excitation :math:`V_{ex}`.
    gain : float
        The amplifier's gain :math:`G`.
    poisson : float
        The bar's Poisson ratio, for the Poisson bridges.
    polarity : {1, -1}
        -1 where the wiring gives a positive voltage in compression (the strain is then tension
        positive whatever the wiring).

    Examples
    --------
    >>> g = Gauge("incident", 0.10202, bridge="half", gauge_factor=2.1, excitation=10.0, gain=100.0)
    >>> float(g.strain(np.array([-1.35]))[0])  # volts to strain: 4 V / (G Vex GF n)
    -0.0012857142857142859
    """

    bar: str
    station: float
    bridge: str = "quarter"
    gauge_factor: float = 2.0
    excitation: float = 1.0
    gain: float = 1.0
    poisson: float = 0.3
    polarity: int = 1

    def __post_init__(self) -> None:
        if self.bridge not in BRIDGES:
            raise ValueError(f"bridge must be one of {sorted(BRIDGES)}, got {self.bridge!r}")
        station = float(self.station)
        if not (math.isfinite(station) and station >= 0):
            raise ValueError(f"station must be a finite distance >= 0 (m), got {self.station!r}")
        object.__setattr__(self, "station", station)
        for name in ("gauge_factor", "excitation", "gain"):
            object.__setattr__(self, name, _positive(name, getattr(self, name)))
        if not 0 <= float(self.poisson) < 0.5:
            raise ValueError(f"poisson must lie in [0, 0.5), got {self.poisson!r}")
        if self.polarity not in (1, -1):
            raise ValueError(f"polarity must be 1 or -1, got {self.polarity!r}")

    @property
    def strain_per_volt(self) -> float:
        r""":math:`4 / (G\,V_{ex}\,GF\,n)`, the strain of one volt at the recorder."""
        arms = BRIDGES[self.bridge](float(self.poisson))
        return self.polarity * 4.0 / (self.gain * self.excitation * self.gauge_factor * arms)

    def strain(self, volts) -> np.ndarray:
        """The axial strain (tension positive) of recorded voltages (V)."""
        return np.asarray(volts, dtype=float) * self.strain_per_volt


#: the window of :meth:`Recording.from_channels`' polyphase filter (``scipy.signal.resample_poly``): a
#: Kaiser window of beta 10 (measured: a sinusoid up to 0.6 of the coarser channel's Nyquist frequency
#: resampled within 2e-5 of its amplitude; the default beta 5 leaves 1e-3)
RESAMPLE_WINDOW = ("kaiser", 10.0)
#: the samples at each end of a resampled channel left out, per unit of ``max(up, down)``: the
#: filter's half length, where it meets the record's ends (measured: within 15 of the 20 at 2:1)
RESAMPLE_EDGE = 10


@dataclass(frozen=True)
class Recording:
    """Channels sampled together on one uniform time base.

    Parameters
    ----------
    time : array_like, shape (n,) (s)
        Uniformly spaced sample times.
    channels : dict of str to array_like, shape (n,) (V)
        The channels' voltages, by name.
    full_scale : float (V), optional
        The recorder's range: a channel that reaches it is saturated.

    Raises
    ------
    ValueError
        A channel of another length than the time, a time base that is not uniform, a value that
        is not finite, a saturated channel (one line naming it).

    Examples
    --------
    >>> rec = Recording.from_arrays(np.arange(8) * 1e-6, a=[0.0, 1.0, 0.5, 0.0, 0.0, 0.1, 0.0, 0.0])
    >>> rec.dt, sorted(rec.channels)
    (1e-06, ['a'])
    """

    time: np.ndarray
    channels: dict = field(default_factory=dict)
    full_scale: float | None = None

    def __post_init__(self) -> None:
        time = np.asarray(self.time, dtype=float)
        if time.ndim != 1 or time.size < 8:
            raise ValueError(f"time must be a 1-d array of >= 8 samples, got shape {time.shape}")
        steps = np.diff(time)
        dt = float(np.mean(steps))
        if not (np.all(np.isfinite(time)) and dt > 0 and np.max(np.abs(steps - dt)) <= 1e-6 * dt):
            raise ValueError("time must be finite, increasing and uniformly spaced (one sample interval)")
        if not self.channels:
            raise ValueError("channels must name at least one channel")
        channels = {}
        for name, values in self.channels.items():
            v = np.asarray(values, dtype=float)
            if v.shape != time.shape:
                raise ValueError(f"channel {name!r} has {v.size} samples where the time has {time.size}")
            if not np.all(np.isfinite(v)):
                raise ValueError(f"channel {name!r} holds values that are not finite")
            _check_saturation(name, v, self.full_scale)
            channels[name] = v
        object.__setattr__(self, "time", time)
        object.__setattr__(self, "channels", channels)

    @property
    def dt(self) -> float:
        """The sample interval (s)."""
        return float((self.time[-1] - self.time[0]) / (self.time.size - 1))

    @classmethod
    def from_arrays(cls, time, *, full_scale=None, **channels) -> Recording:
        """A recording of NumPy arrays: ``Recording.from_arrays(t, ch1=v1, ch2=v2)``."""
        return cls(time, dict(channels), full_scale)

    @classmethod
    def from_frame(cls, frame, *, time: str = "time", full_scale=None) -> Recording:
        """A recording of a pandas DataFrame's columns: the column ``time`` and every other."""
        if time not in frame.columns:
            raise ValueError(f"time must name a column of the frame, got {time!r}")
        return cls(frame[time].to_numpy(), {str(c): frame[c].to_numpy() for c in frame.columns if c != time},
                   full_scale)

    @classmethod
    def from_channels(cls, channels: dict, *, dt: float | None = None, full_scale=None) -> Recording:
        r"""A recording of channels each sampled on its own uniform time base (another rate, another
        start), resampled onto one: the times all channels cover, at the interval ``dt``.

        Each channel is brought to the new rate by ``scipy.signal.resample_poly`` (a polyphase
        filter: zero-stuffing by ``up``, a Kaiser-windowed low-pass at the lower of the two Nyquist
        frequencies, keeping every ``down``-th sample; ``up / down`` the ratio of the rates as a
        fraction of terms up to 1000; a Kaiser window of beta 10, :data:`RESAMPLE_WINDOW`: a
        sinusoid up to 0.6 of the coarser Nyquist frequency within 2e-5 of its amplitude), its
        first and last :data:`RESAMPLE_EDGE` ``max(up, down)`` samples left out (where the filter
        meets the record's ends), then read at the common times by linear interpolation
        (``numpy.interp``) where its resampled times fall between them: no interpolation where a
        channel's start lies on the common grid (a sample rate's multiple, the usual case of one
        oscilloscope), else an error of :math:`\Delta t^2 |\ddot v| / 8` at most. A channel already
        on the common times is taken as it is.

        Parameters
        ----------
        channels : dict of str to (array_like, array_like)
            Each channel's ``(time, volts)``, shapes ``(n_i,)``, its times uniformly spaced (s).
        dt : float, optional
            The common sample interval (s), ``> 0``; default the smallest of the channels'.
        full_scale : float (V), optional
            As :class:`Recording`'s (each channel checked on its own samples).

        Returns
        -------
        Recording
            The channels on ``t_0 + k\,dt``, :math:`t_0` the latest start, up to the earliest end.

        Raises
        ------
        ValueError
            A channel's time base that is not uniform, a saturated channel (as :class:`Recording`),
            ``dt`` not positive, or a channel whose times overlap the others' by fewer than 8
            common samples (naming it).

        Examples
        --------
        >>> t = np.arange(64) * 1e-6
        >>> rec = Recording.from_channels({"a": (t, np.sin(2e4 * t)), "b": (t[::2], np.sin(2e4 * t[::2]))})
        >>> round(rec.dt * 1e6, 9), rec.time.size  # (1 us; the 2:1 filter's 20 samples left out at each end)
        (1.0, 24)
        >>> float(np.max(np.abs(rec.channels["b"] - rec.channels["a"]))) < 1e-5
        True
        """
        from fractions import Fraction

        from scipy.signal import resample_poly

        if not isinstance(channels, dict) or not channels:
            raise ValueError("channels must be a non-empty dict of name to (time, volts)")
        own = {}
        for name, pair in channels.items():
            try:
                t, v = pair
            except (TypeError, ValueError):
                raise ValueError(f"channels[{name!r}] must be a pair (time, volts)") from None
            own[name] = cls(t, {name: v}, full_scale)  # (each time base and channel checked)
        if dt is None:
            dt = min(r.dt for r in own.values())
        elif not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a positive sample interval (s); got {dt!r}")
        # each channel at the new rate: its times and samples, the filter's ends left out
        fine = {}
        for name, r in own.items():
            v = r.channels[name]
            ratio = Fraction(r.dt / dt).limit_denominator(1000)
            up, down = ratio.numerator, ratio.denominator
            if up == down == 1:
                fine[name] = (r.time, v)
                continue
            w = resample_poly(v, up, down, window=RESAMPLE_WINDOW, padtype="line")
            t = r.time[0] + r.dt * down / up * np.arange(w.size)
            h = RESAMPLE_EDGE * max(up, down)  # (the filter's half length at each end)
            fine[name] = (t[h:w.size - h], w[h:w.size - h])
        start = max(float(t[0]) if t.size else math.inf for t, _ in fine.values())
        end = min(float(t[-1]) if t.size else -math.inf for t, _ in fine.values())
        n = int(math.floor((end - start) / dt * (1.0 + 1e-12))) + 1 if end >= start else 0
        if n < 8:
            name = min(own, key=lambda k: float(own[k].time[-1])) if end >= start else \
                max(own, key=lambda k: float(own[k].time[0]))
            r = own[name]
            raise ValueError(f"channel {name!r} ({r.time[0]:.6g} to {r.time[-1]:.6g} s) overlaps the other "
                             f"channels' times by fewer than 8 samples of {dt:.6g} s")
        time = start + dt * np.arange(n)
        out = {}
        for name, (t, w) in fine.items():
            k = (start - t[0]) / dt
            if t.size >= n and math.isclose(t[1] - t[0], dt, rel_tol=1e-9) and abs(k - round(k)) <= 1e-6 \
                    and round(k) + n <= t.size:  # (on the common times already)
                out[name] = w[int(round(k)):int(round(k)) + n]
            else:
                out[name] = np.interp(time, t, w)
        return cls(time, out, full_scale)

    @classmethod
    def from_tektronix(cls, files: dict, *, full_scale=None) -> Recording:
        """A recording of Tektronix CSV files, one a channel (``{"ch1": path, ...}``); files on
        another time base than the first's (another rate or start) are resampled onto the times all
        cover (:meth:`from_channels`)."""
        time, channels, pairs, same = None, {}, {}, True
        for name, path in files.items():
            t, v = read_tektronix_csv(path)
            tol = 1e-3 * (t[1] - t[0])
            same = same and (time is None or (t.size == time.size and np.allclose(t, time, rtol=0, atol=tol)))
            time = t if time is None else time
            channels[name], pairs[name] = v, (t, v)
        if not same:
            return cls.from_channels(pairs, full_scale=full_scale)
        return cls(time, channels, full_scale)

    @classmethod
    def from_npz(cls, path, *, full_scale=None) -> Recording:
        """A recording stored as ``.npz``: either ``time`` and one array a channel, or ``t0``, ``dt``,
        ``volts_per_code`` and integer channels (a compact copy of an oscilloscope's record)."""
        with np.load(Path(path)) as data:
            arrays = {k: data[k] for k in data.files}
        if "time" in arrays:
            time = arrays.pop("time")
            scale = 1.0
        else:
            try:
                t0, dt, scale = (float(arrays.pop(k)) for k in ("t0", "dt", "volts_per_code"))
            except KeyError as exc:
                raise ValueError(f"{path}: an .npz recording holds 'time' or 't0', 'dt' and "
                                 f"'volts_per_code'; {exc.args[0]!r} is missing") from None
            n = len(next(iter(arrays.values())))
            time = t0 + dt * np.arange(n)
        return cls(time, {k: np.asarray(v, dtype=float) * scale for k, v in arrays.items()}, full_scale)


def _check_saturation(name: str, v: np.ndarray, full_scale, run: int = 8) -> None:
    """A channel is saturated where it reaches the full scale, or, without one, where it stays at
    its extreme value (the recorder's rail) for ``run`` samples or more."""
    if full_scale is not None:
        peak = float(np.max(np.abs(v)))
        if peak >= full_scale:
            raise ValueError(f"channel {name!r} is saturated: it reaches {peak:g} V, the full scale "
                             f"{full_scale:g} V")
        return
    for extreme in (v.max(), v.min()):
        at = np.concatenate(([0], (v == extreme).astype(np.int8), [0]))
        runs = np.flatnonzero(np.diff(at)).reshape(-1, 2)  # each run's first sample and the one after it
        longest = int(np.max(runs[:, IV_HI] - runs[:, IV_LO]))
        if longest >= run and v.max() > v.min():
            raise ValueError(f"channel {name!r} is saturated: it stays at {extreme:g} V for {longest} "
                             f"samples (clipped at the recorder's range)")


def read_tektronix_csv(path) -> tuple[np.ndarray, np.ndarray]:
    """Time (s) and signal (V) of one Tektronix oscilloscope CSV.

    The format of the TDS/DPO series: six header rows in columns 1-3 (``Record Length``,
    ``Sample Interval``, ``Trigger Point``, ...), and the time and the signal in columns 4 and 5 on
    every row. Read with pandas.

    Raises
    ------
    ValueError
        A file that is not in this format.
    """
    import pandas as pd

    try:
        frame = pd.read_csv(Path(path), header=None, usecols=[3, 4], names=["time", "volts"], dtype=float)
    except (ValueError, pd.errors.ParserError) as exc:
        raise ValueError(f"{path}: not a Tektronix CSV (time and volts in columns 4 and 5): {exc}") from None
    return frame["time"].to_numpy(), frame["volts"].to_numpy()
