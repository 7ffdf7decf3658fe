"""Driving forces in SI units: pneumatic, hydraulic, and measured force curves (CSV) turned into
a Fourier load with a stated error (paper eqs. 33, 34)."""

from __future__ import annotations

import csv
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from .._shared.validate import check_int, check_real
from ..loads import CosineLoad, FourierLoad, Load, PiecewiseConstantLoad, SquareWaveLoad
from .bar import TWO_PI
from .units import to_si


# --------------------------------------------------------------------------------------------
# forces at the driven end
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PneumaticForce:
    r"""Pneumatic hammer force (eq. 33): :math:`F(T) = F_\mathrm{mean} + F_\mathrm{amp} \cos(2 \pi f T)`.

    With order ``k > 1`` the bar strikes once every ``k`` cycles of the force (a subharmonic
    motion): the impact cycle, and the dimensionless time, run at :math:`\Omega = 2 \pi f / k`.

    Parameters
    ----------
    mean_N : float
        Mean force (N), positive towards the stop.
    amplitude_N : float
        Amplitude of the oscillating part (N).
    k : int, optional
        Load cycles per impact, :math:`1 \le k \le 4096`. Default 1.
    """

    kind: ClassVar[str] = "pneumatic"
    mean_N: float
    amplitude_N: float
    k: int = 1

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean_N", check_real("force.mean", self.mean_N))
        object.__setattr__(self, "amplitude_N", check_real("force.amplitude", self.amplitude_N))
        object.__setattr__(self, "k", check_int("force.k", self.k, lo=1, hi=4096))

    @property
    def order(self) -> int:
        """Load cycles per impact cycle (``k``)."""
        return self.k

    @property
    def mean_force_N(self) -> float:
        """Mean force (N)."""
        return self.mean_N

    def load(self, force_scale_N: float) -> CosineLoad:
        r"""The dimensionless :class:`~impactbar.CosineLoad` ``p0 + pk cos(k t)`` for the force
        scale :math:`m L \Omega^2` (N)."""
        return CosineLoad(self.mean_N / force_scale_N, self.amplitude_N / force_scale_N, self.k)

    def to_dict(self) -> dict:
        """The force as the plain mapping of its kind and SI fields (a JSON-ready summary)."""
        return {"kind": self.kind, "mean_N": self.mean_N, "amplitude_N": self.amplitude_N,
                "k": self.k}


@dataclass(frozen=True)
class HydraulicForce:
    r"""Hydraulic hammer force (eq. 34 generalised): ``high_N`` for the first ``fraction`` of each
    period, ``low_N`` for the rest.

    With ``low = -high`` and ``fraction`` :math:`\ge 1/2` it is the paper's square wave with
    :math:`\kappa` twice ``fraction``; otherwise it is integrated exactly as a piecewise-constant load.

    Parameters
    ----------
    high_N, low_N : float
        Force levels (N), positive towards the stop, ``high_N > low_N``.
    fraction : float
        Fraction of the period at the high level, in :math:`(0, 1]`.
    """

    kind: ClassVar[str] = "hydraulic"
    order: ClassVar[int] = 1
    high_N: float
    low_N: float
    fraction: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "high_N", check_real("force.high", self.high_N))
        object.__setattr__(self, "low_N", check_real("force.low", self.low_N, hi=self.high_N,
                                                     hi_open=True))
        object.__setattr__(self, "fraction", check_real("force.fraction", self.fraction, lo=0.0,
                                                        hi=1.0, lo_open=True))

    @property
    def mean_force_N(self) -> float:
        """Mean force ``high fraction + low (1 - fraction)`` (N)."""
        return self.high_N * self.fraction + self.low_N * (1.0 - self.fraction)

    def load(self, force_scale_N: float) -> Load:
        r"""The dimensionless load for the force scale :math:`m L \Omega^2` (N): a
        :class:`~impactbar.SquareWaveLoad` when the levels are symmetric and ``fraction`` :math:`\ge 1/2`,
        else an exact :class:`~impactbar.PiecewiseConstantLoad`."""
        hi, lo = self.high_N / force_scale_N, self.low_N / force_scale_N
        if self.fraction == 1.0:
            return PiecewiseConstantLoad([0.0], [hi])
        if self.high_N == -self.low_N and self.fraction >= 0.5:
            return SquareWaveLoad(hi, 2.0 * self.fraction)
        return PiecewiseConstantLoad([0.0, TWO_PI * self.fraction], [hi, lo])

    def to_dict(self) -> dict:
        """The force as the plain mapping of its kind and SI fields (a JSON-ready summary)."""
        return {"kind": self.kind, "high_N": self.high_N, "low_N": self.low_N,
                "fraction": self.fraction}


@dataclass(frozen=True)
class FourierFit:
    """How well the truncated Fourier series of a measured force reproduces the curve.

    Attributes
    ----------
    n_harmonics : int
        Harmonics kept, the fewest that meet ``tolerance``.
    max_error_N : float
        ``max_t |F_K(t) - F(t)|`` (N) between the series and the piecewise-linear curve.
    relative_error : float
        ``max_error_N`` over the swing ``max F - min F`` of the curve (dimensionless).
    tolerance : float
        The stated bound on ``relative_error``.
    """

    n_harmonics: int
    max_error_N: float
    relative_error: float
    tolerance: float


@dataclass(frozen=True, eq=False)
class MeasuredForce:
    r"""A measured force over one period of the drive, taken as periodic and piecewise linear
    between the samples, and expanded in a Fourier series (eq. 7).

    The samples cover one period ``1 / f`` of the drive (``f`` the hammer's drive frequency),
    starting at ``times_s[0]``: the last sample joins the first one period later. A final sample
    at exactly ``times_s[0] + 1/f`` is the same instant as the first and is dropped (with a warning
    if its force differs). The number of harmonics is the smallest that keeps the series within
    ``tolerance`` of the curve, as a fraction of the swing ``max F - min F``; see
    :class:`FourierFit`.

    Parameters
    ----------
    times_s : array_like, shape (n,)
        Sample times (s), strictly increasing, :math:`n \ge 2`.
    forces_N : array_like, shape (n,)
        Forces (N), positive towards the stop.
    tolerance : float, optional
        Bound on the relative error of the series, ``0 < tolerance < 1``. Default 0.01.
    max_harmonics : int, optional
        Most harmonics allowed, ``1..4096``. Default 256.
    source : str, optional
        Where the samples came from (e.g. the CSV path), for reports.
    """

    kind: ClassVar[str] = "measured"
    order: ClassVar[int] = 1
    times_s: np.ndarray
    forces_N: np.ndarray
    tolerance: float = 0.01
    max_harmonics: int = 256
    source: str = ""

    def __post_init__(self) -> None:
        t = np.array(self.times_s, dtype=float).ravel()
        f = np.array(self.forces_N, dtype=float).ravel()
        if t.size < 2 or t.size != f.size:
            raise ValueError(f"force.csv: need at least 2 samples and as many times as forces; got "
                             f"{t.size} times and {f.size} forces")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(f))):
            raise ValueError("force.csv: times and forces must be finite numbers")
        if not np.all(np.diff(t) > 0):
            raise ValueError("force.csv: times must increase strictly")
        t.flags.writeable = False
        f.flags.writeable = False
        object.__setattr__(self, "times_s", t)
        object.__setattr__(self, "forces_N", f)
        object.__setattr__(self, "tolerance", check_real("force.tolerance", self.tolerance, lo=0.0,
                                                         hi=1.0, lo_open=True, hi_open=True))
        object.__setattr__(self, "max_harmonics", check_int("force.max_harmonics",
                                                            self.max_harmonics, lo=1, hi=4096))

    @classmethod
    def from_csv(cls, path, *, tolerance: float = 0.01, max_harmonics: int = 256) -> MeasuredForce:
        """Read a two-column CSV: time, force.

        Without a header, or with a header whose cells carry no unit (``time,force``), the columns
        are in s and N. A header may give units as ``time [ms]``, ``time (ms)`` or ``time_ms``
        (and ``force [kN]``, ...); they are converted through pint. Blank lines and lines starting
        with ``#`` are skipped.

        Raises
        ------
        ValueError
            A missing file, a row that is not two numbers, or a header unit of the wrong dimension.
        """
        path = Path(path)
        try:
            text = path.read_text()
        except OSError as exc:
            raise ValueError(f"force.csv: cannot read {str(path)!r}: {exc.strerror}") from exc
        rows = [r for r in csv.reader(text.splitlines())
                if r and any(c.strip() for c in r) and not r[0].lstrip().startswith("#")]
        if not rows:
            raise ValueError(f"force.csv: {str(path)!r} holds no samples")
        scale_t, scale_f = 1.0, 1.0
        if not _is_number(rows[0][0]):
            header = rows.pop(0)
            if len(header) != 2:
                raise ValueError(f"force.csv: the header must have two cells (time, force); got "
                                 f"{header}")
            time_cell, force_cell = header
            scale_t = _header_scale("force.csv time column", time_cell, "s", "'time [ms]'")
            scale_f = _header_scale("force.csv force column", force_cell, "N", "'force [kN]'")
        if not rows:
            raise ValueError(f"force.csv: {str(path)!r} holds a header but no samples")
        data = []
        for i, r in enumerate(rows, start=1):
            if len(r) != 2 or not (_is_number(r[0]) and _is_number(r[1])):
                raise ValueError(f"force.csv: data row {i} of {str(path)!r} must be two numbers "
                                 f"(time, force); got {r}")
            data.append((float(r[0]), float(r[1])))
        times, forces = np.array(data, dtype=float).reshape(-1, 2).T
        return cls(times * scale_t, forces * scale_f, tolerance=tolerance,
                   max_harmonics=max_harmonics, source=str(path))

    def _nodes(self, period_s: float):
        """Nodes in ``[0, period)`` and their forces, after the closing checks."""
        t = self.times_s - self.times_s[0]
        f = self.forces_N
        span = t[-1]
        tol = 1e-6 * period_s
        if span > period_s + tol:
            raise ValueError(
                f"force.csv: the samples span {span:.6g} s, more than one period 1/f = "
                f"{period_s:.6g} s of the drive frequency"
            )
        if span >= period_s - tol:  # the last sample is the first one a period later
            swing = float(np.ptp(f))
            if abs(f[-1] - f[0]) > 1e-3 * max(swing, 1e-300):
                warnings.warn(
                    f"force.csv: the force at the end of the period ({f[-1]:.6g} N) differs from "
                    f"the start ({f[0]:.6g} N); the start value is used", UserWarning, stacklevel=3)
            t, f = t[:-1], f[:-1]
            if t.size < 2:
                raise ValueError("force.csv: need at least 2 samples within one period")
        else:
            gap = period_s - span
            if t.size > 1 and gap > 1.5 * float(np.max(np.diff(t))) + tol:
                raise ValueError(
                    f"force.csv: the samples cover {span:.6g} s but one period 1/f is "
                    f"{period_s:.6g} s; give samples over a whole period (or check drive.frequency)"
                )
        return t, f

    def mean_over(self, period_s: float) -> float:
        """Mean force (N) of the periodic piecewise-linear curve of period ``period_s`` (s)."""
        t, f = self._nodes(period_s)
        t2 = np.append(t, period_s)
        f2 = np.append(f, f[0])
        return float(np.sum(0.5 * (f2[1:] + f2[:-1]) * np.diff(t2)) / period_s)

    def fourier(self, period_s: float):
        r"""Exact Fourier coefficients of the curve, truncated to meet :attr:`tolerance`.

        Parameters
        ----------
        period_s : float
            The drive period ``1 / f`` (s).

        Returns
        -------
        mean_N : float
            Mean force (N).
        harmonics_N : numpy.ndarray of complex, shape (K,)
            :math:`P_k` with :math:`F(T) = \bar F + \operatorname{Re} \sum_k P_k e^{2 \pi i k T / T_p}`,
            :math:`k = 1 \ldots K` (N), with :math:`\bar F` the mean and :math:`T_p` the period, time
            counted from the first sample.
        fit : FourierFit

        Raises
        ------
        ValueError
            If ``max_harmonics`` harmonics cannot meet the tolerance.
        """
        t, f = self._nodes(period_s)
        K = self.max_harmonics
        w = TWO_PI / period_s
        t2 = np.append(t, period_s)
        f2 = np.append(f, f[0])
        mean = float(np.sum(0.5 * (f2[1:] + f2[:-1]) * np.diff(t2)) / period_s)
        slope = np.diff(f2) / np.diff(t2)  # slope of the piece starting at each node
        dm = slope - np.roll(slope, 1)  # jump of the slope at each node (periodic)
        # P_k = 2 c_k, c_k = (1/T) int F e^{-ikwt} dt = -(1/(T (k w)^2)) sum_j dm_j e^{-ikw t_j}
        k = np.arange(1, K + 1, dtype=float)
        coef = np.empty(K, dtype=complex)
        chunk = max(1, 2**20 // max(t.size, 1))
        for a in range(0, K, chunk):
            kk = k[a:a + chunk]
            coef[a:a + chunk] = np.exp(-1j * w * np.outer(kk, t)) @ dm
        coef *= -2.0 / (period_s * (k * w) ** 2)
        # error of the partial sums on a fine grid and at every node (where the corners are)
        grid = np.concatenate((np.linspace(0.0, period_s, max(4096, 16 * K), endpoint=False), t))
        exact = np.interp(grid, t2, f2)
        swing = float(np.ptp(f))
        approx = np.full(grid.shape, mean)
        z1 = np.exp(1j * w * grid)
        zk = np.ones_like(z1)
        err = float(np.max(np.abs(approx - exact)))
        n = 0
        if swing == 0.0:
            fit = FourierFit(0, err, 0.0, self.tolerance)
            return mean, np.zeros(0, dtype=complex), fit
        best = err
        while err > self.tolerance * swing and n < K:
            zk = zk * z1
            approx += (coef[n] * zk).real
            n += 1
            err = float(np.max(np.abs(approx - exact)))
            best = min(best, err)
        if err > self.tolerance * swing:
            raise ValueError(
                f"force.tolerance: {K} harmonics reproduce the measured curve only to "
                f"{best / swing:.3g} of its swing ({best:.4g} N), not {self.tolerance:g}; raise "
                "force.max_harmonics or loosen force.tolerance"
            )
        return mean, coef[:n].copy(), FourierFit(n, err, err / swing, self.tolerance)

    def load(self, force_scale_N: float, period_s: float) -> FourierLoad:
        r"""The dimensionless :class:`~impactbar.FourierLoad` for the force scale :math:`m L \Omega^2` (N)
        and the drive period (s)."""
        mean, harm, _ = self.fourier(period_s)
        return FourierLoad(mean / force_scale_N, harm / force_scale_N)

    def to_dict(self) -> dict:
        """The force as a plain mapping: its kind, source file, sample count and fit settings (the
        samples themselves left out)."""
        return {"kind": self.kind, "source": self.source, "samples": int(self.times_s.size),
                "tolerance": self.tolerance, "max_harmonics": self.max_harmonics}


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


_BRACKET = re.compile(r"[\[(]\s*([^\])]+?)\s*[\])]\s*$")


def _header_scale(name: str, cell: str, unit: str, example: str) -> float:
    """Factor to ``unit`` from a header cell ``'time [ms]'``, ``'time (ms)'``, ``'time_ms'``;
    1 when the cell names no unit."""
    cell = cell.strip()
    m = _BRACKET.search(cell)
    if m:
        return to_si(name, f"1 {m.group(1)}", unit, example)
    if "_" in cell:
        suffix = cell.rsplit("_", 1)[1]
        try:
            return to_si(name, f"1 {suffix}", unit, example)
        except ValueError:
            from .units import registry

            try:
                registry().Unit(suffix)
            except Exception:
                return 1.0  # the suffix is not a unit: a plain column name
            raise  # a unit of the wrong dimension
    return 1.0


#: Any of the driving forces a :class:`~impactbar.physical.Hammer` takes.
Force = PneumaticForce | HydraulicForce | MeasuredForce
