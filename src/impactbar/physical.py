r"""Real hammers in SI units: from a piston, a stop and a driving force to the dimensionless model,
and back to what the designer of a rock drill reads.

Conversion (paper eq. 2, MODEL.md section 1). For a bar of Young's modulus ``E``, density ``rho``,
length ``L`` and cross-section ``A``, driven at ``f`` Hz:

- mass per unit length ``M = rho A``, piston mass ``m = M L``, wave speed ``c = sqrt(E / rho)``;
- ``Omega = 2 pi f / k``: the angular frequency of the impact cycle, the first harmonic of the load
  (``k`` is the order of a pneumatic load, eq. 33; ``k = 1`` for every other force);
- ``s = c / (L Omega)``, ``d = D / (M Omega)``, ``p = P / (m L Omega^2)``, ``t = Omega T``,
  ``u = U / L``, so velocities scale with ``L Omega``: ``U_T = L Omega u_t``.

The force scale is ``m L Omega^2 = M L^2 Omega^2``: the boundary condition ``E A U_X(0) = -P`` in
the variables above reads ``s^2 u_x(0) = -P / (M L^2 Omega^2)``, and the rigid mode
``m U_TT = P`` reads ``q_0'' = P / (m L Omega^2)``. (MODEL.md writes ``p = P / (M L Omega^2)``,
which is not dimensionless for ``M`` a mass per unit length; the tests check the scale through
the momentum identity ``v = F_mean / (f m (1 + R))``.)

Every input that has a dimension must be written with its unit (``"210 GPa"``, ``"45 mm"``) or be a
pint quantity; the dataclasses themselves hold plain SI floats in fields named with their unit
(``length_m``). Forces are positive when they push the bar towards the stop.

Outputs (:class:`PhysicalOrbit`): impact velocity (m/s), energy per blow ``m v^2 / 2`` (J), blow
frequency ``Omega / 2 pi`` (Hz), impact power (W), peak stress at impact (Pa) and, on the hammer,
the contact duration ``2 L / c`` against the period (the paper assumes impacts are short).

Configuration keys (TOML file or a nested ``dict``, see :meth:`Hammer.from_config`)::

    name = "..."                        # optional label
    [bar]      E, density, length, diameter | area
    [damping]  coefficient | ratio      # optional section; no damping if absent
    [stop]     restitution | area
    [drive]    frequency
    [force]    kind = "pneumatic": mean, amplitude, k (optional, default 1)
               kind = "hydraulic": high, low, fraction
               kind = "measured":  csv, tolerance (optional, 0.01), max_harmonics (optional, 256)
    [model]    n_modes                  # optional, default 16

Unknown keys are refused, naming the key.
"""

from __future__ import annotations

import csv
import dataclasses
import functools
import math
import re
import tomllib
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np

from ._units import to_si, to_si_any
from ._validate import check_int, check_real
from .loads import CosineLoad, FourierLoad, Load, PiecewiseConstantLoad, SquareWaveLoad
from .model import BarModel

__all__ = [
    "Bar",
    "PneumaticForce",
    "HydraulicForce",
    "MeasuredForce",
    "FourierFit",
    "Hammer",
    "Scales",
    "PhysicalOrbit",
    "SimulationResult",
    "ImpactDurationWarning",
    "SHORT_IMPACT_LIMIT",
    "PRESETS",
    "preset",
    "load_config",
    "orbits",
    "simulate",
    "add_physical_arguments",
    "run_physical_orbits",
]

TWO_PI = 2.0 * math.pi

#: Largest contact duration ``2 L / c``, as a fraction of the impact period, for which the paper's
#: instantaneous impact law (eqs. 10, 11) is taken as valid; beyond it a warning is issued.
#: In dimensionless terms the fraction is ``1 / (pi s)``, so the limit is ``s pi >= 20``.
SHORT_IMPACT_LIMIT = 0.05


class ImpactDurationWarning(UserWarning):
    """The contact duration ``2 L / c`` is not short against the impact period: the paper's
    instantaneous impact law (eqs. 10, 11) is then a poor approximation."""


# --------------------------------------------------------------------------------------------
# the bar
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Bar:
    """A uniform elastic bar (the piston), in SI units.

    Parameters
    ----------
    E_Pa : float
        Young's modulus (Pa), ``> 0``.
    density_kg_m3 : float
        Density (kg/m^3), ``> 0``.
    length_m : float
        Length ``L`` (m), ``> 0``.
    area_m2 : float
        Cross-section ``A`` (m^2), ``> 0``.

    See Also
    --------
    Bar.from_units : the same from inputs with units, with a diameter or an area.
    """

    E_Pa: float
    density_kg_m3: float
    length_m: float
    area_m2: float

    def __post_init__(self) -> None:
        for f in ("E_Pa", "density_kg_m3", "length_m", "area_m2"):
            object.__setattr__(self, f, check_real(f, getattr(self, f), lo=0.0, lo_open=True))

    @classmethod
    def from_units(cls, E, density, length, *, diameter=None, area=None,
                   prefix: str = "bar") -> Bar:
        """A bar from inputs with units, e.g. ``Bar.from_units("210 GPa", "7850 kg/m^3", "0.2 m",
        diameter="40 mm")``; exactly one of ``diameter`` (circular section) and ``area``."""
        if (diameter is None) == (area is None):
            raise ValueError(f"give exactly one of {prefix}.diameter and {prefix}.area")
        if diameter is not None:
            dia = to_si(f"{prefix}.diameter", diameter, "m", "'40 mm'", what="a length")
            check_real(f"{prefix}.diameter", dia, lo=0.0, lo_open=True)
            a = math.pi * dia * dia / 4.0
        else:
            a = to_si(f"{prefix}.area", area, "m**2", "'12.6 cm^2'", what="an area")
            check_real(f"{prefix}.area", a, lo=0.0, lo_open=True)
        return cls(
            E_Pa=_positive(f"{prefix}.E", to_si(f"{prefix}.E", E, "Pa", "'210 GPa'",
                                                  what="a pressure (Young's modulus)")),
            density_kg_m3=_positive(f"{prefix}.density", to_si(
                f"{prefix}.density", density, "kg/m**3", "'7850 kg/m^3'", what="a density")),
            length_m=_positive(f"{prefix}.length", to_si(f"{prefix}.length", length, "m", "'0.2 m'",
                                                           what="a length")),
            area_m2=a,
        )

    @property
    def wave_speed_m_s(self) -> float:
        """Bar wave speed ``c = sqrt(E / rho)`` (m/s)."""
        return math.sqrt(self.E_Pa / self.density_kg_m3)

    @property
    def mass_per_length_kg_m(self) -> float:
        """``M = rho A`` (kg/m)."""
        return self.density_kg_m3 * self.area_m2

    @property
    def mass_kg(self) -> float:
        """Piston mass ``m = rho A L`` (kg)."""
        return self.mass_per_length_kg_m * self.length_m

    @property
    def diameter_m(self) -> float:
        """Diameter of the circular section of area ``A`` (m)."""
        return math.sqrt(4.0 * self.area_m2 / math.pi)

    @property
    def impedance_N_s_m(self) -> float:
        """Mechanical impedance ``rho c A`` (N s/m)."""
        return self.density_kg_m3 * self.wave_speed_m_s * self.area_m2

    @property
    def contact_duration_s(self) -> float:
        """Duration ``2 L / c`` of an impact on a stop (s): the wave's return trip."""
        return 2.0 * self.length_m / self.wave_speed_m_s


def _positive(name, v):
    return check_real(name, v, lo=0.0, lo_open=True)


# --------------------------------------------------------------------------------------------
# forces at the driven end
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PneumaticForce:
    r"""Pneumatic hammer force (eq. 33): ``F(T) = F_mean + F_amp cos(2 pi f T)``.

    With order ``k > 1`` the bar strikes once every ``k`` cycles of the force (a subharmonic
    motion): the impact cycle, and the dimensionless time, run at ``Omega = 2 pi f / k``.

    Parameters
    ----------
    mean_N : float
        Mean force (N), positive towards the stop.
    amplitude_N : float
        Amplitude of the oscillating part (N).
    k : int, optional
        Load cycles per impact, ``1 <= k <= 4096``. Default 1.
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
        """The dimensionless :class:`~impactbar.CosineLoad` ``p0 + pk cos(k t)`` for the force
        scale ``m L Omega^2`` (N)."""
        return CosineLoad(self.mean_N / force_scale_N, self.amplitude_N / force_scale_N, self.k)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "mean_N": self.mean_N, "amplitude_N": self.amplitude_N,
                "k": self.k}


@dataclass(frozen=True)
class HydraulicForce:
    """Hydraulic hammer force (eq. 34 generalised): ``high_N`` for the first ``fraction`` of each
    period, ``low_N`` for the rest.

    With ``low = -high`` and ``fraction >= 1/2`` it is the paper's square wave with
    ``kappa = 2 fraction``; otherwise it is integrated exactly as a piecewise-constant load.

    Parameters
    ----------
    high_N, low_N : float
        Force levels (N), positive towards the stop, ``high_N > low_N``.
    fraction : float
        Fraction of the period at the high level, ``0 < fraction <= 1``.
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
        """The dimensionless load for the force scale ``m L Omega^2`` (N): a
        :class:`~impactbar.SquareWaveLoad` when the levels are symmetric and ``fraction >= 1/2``,
        else an exact :class:`~impactbar.PiecewiseConstantLoad`."""
        hi, lo = self.high_N / force_scale_N, self.low_N / force_scale_N
        if self.fraction == 1.0:
            return PiecewiseConstantLoad([0.0], [hi])
        if self.high_N == -self.low_N and self.fraction >= 0.5:
            return SquareWaveLoad(hi, 2.0 * self.fraction)
        return PiecewiseConstantLoad([0.0, TWO_PI * self.fraction], [hi, lo])

    def to_dict(self) -> dict:
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
    """A measured force over one period of the drive, taken as periodic and piecewise linear
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
        Sample times (s), strictly increasing, ``n >= 2``.
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
            scale_t = _header_scale("force.csv time column", header[0], "s", "'time [ms]'")
            scale_f = _header_scale("force.csv force column", header[1], "N", "'force [kN]'")
        data = []
        for i, r in enumerate(rows, start=1):
            if len(r) != 2 or not (_is_number(r[0]) and _is_number(r[1])):
                raise ValueError(f"force.csv: data row {i} of {str(path)!r} must be two numbers "
                                 f"(time, force); got {r}")
            data.append((float(r[0]), float(r[1])))
        arr = np.array(data, dtype=float)
        return cls(arr[:, 0] * scale_t, arr[:, 1] * scale_f, tolerance=tolerance,
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
        """Exact Fourier coefficients of the curve, truncated to meet :attr:`tolerance`.

        Parameters
        ----------
        period_s : float
            The drive period ``1 / f`` (s).

        Returns
        -------
        mean_N : float
            Mean force (N).
        harmonics_N : numpy.ndarray of complex, shape (K,)
            ``P_k`` with ``F(T) = mean + Re sum_k P_k exp(2 pi i k T / period)``, ``k = 1..K`` (N),
            time counted from the first sample.
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
        """The dimensionless :class:`~impactbar.FourierLoad` for the force scale ``m L Omega^2`` (N)
        and the drive period (s)."""
        mean, harm, _ = self.fourier(period_s)
        return FourierLoad(mean / force_scale_N, harm / force_scale_N)

    def to_dict(self) -> dict:
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
            from ._units import registry

            try:
                registry().Unit(suffix)
            except Exception:
                return 1.0  # the suffix is not a unit: a plain column name
            raise  # a unit of the wrong dimension
    return 1.0


# --------------------------------------------------------------------------------------------
# the hammer
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Scales:
    """The units of the dimensionless model (eq. 2) for one hammer, in SI.

    Attributes
    ----------
    omega_rad_s : float
        ``Omega``, the angular frequency of the impact cycle (rad/s); dimensionless time is
        ``t = Omega T``.
    time_s : float
        ``1 / Omega`` (s).
    length_m : float
        ``L`` (m): ``U = L u``.
    velocity_m_s : float
        ``L Omega`` (m/s): ``U_T = L Omega u_t``.
    force_N : float
        ``m L Omega^2 = M L^2 Omega^2`` (N): ``P = m L Omega^2 p``.
    damping_N_s_m2 : float
        ``M Omega`` (N s/m^2): ``D = M Omega d``.
    """

    omega_rad_s: float
    time_s: float
    length_m: float
    velocity_m_s: float
    force_N: float
    damping_N_s_m2: float


Force = PneumaticForce | HydraulicForce | MeasuredForce


@dataclass(frozen=True)
class Hammer:
    r"""A percussive machine in SI units: piston, stop, damping and driving force.

    Parameters
    ----------
    bar : Bar
        The piston.
    frequency_Hz : float
        Drive frequency ``f`` (Hz), the frequency of the force cycle, ``> 0``.
    force : PneumaticForce, HydraulicForce or MeasuredForce
        The force at the driven end.
    restitution : float, optional
        Restitution coefficient ``R`` of the stop, ``0 <= R <= 1`` (eq. 10).
    stop_area_m2 : float, optional
        Or the stop as a long bar of the same material and area ``A_s >= A`` (m^2):
        ``R = (A_s - A) / (A_s + A)`` (MODEL.md section 4). Give exactly one of the two.
    damping_N_s_m2 : float, optional
        Viscous damping per unit length ``D`` of eq. 2 (N s/m^2), ``>= 0``. Default 0. A total
        coefficient ``c`` (N s/m) of the whole piston is ``D = c / L``; a damping ratio ``zeta``
        of the first flexible mode is ``d = 2 zeta s pi`` (see :meth:`from_config`).
    n_modes : int, optional
        Flexible modes kept in the model, ``0..4096``; 0 is the rigid piston. Default 16.
    name : str, optional
        A label for reports.

    Notes
    -----
    ``Omega = 2 pi f / k`` with ``k`` the order of a pneumatic load (1 otherwise), so one impact
    cycle is ``k`` force cycles and the blow frequency is ``f / k``.
    """

    bar: Bar
    frequency_Hz: float
    force: Force
    restitution: float | None = None
    stop_area_m2: float | None = None
    damping_N_s_m2: float = 0.0
    n_modes: int = 16
    name: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.bar, Bar):
            raise ValueError(f"bar must be a Bar; got {type(self.bar).__name__}")
        if not isinstance(self.force, PneumaticForce | HydraulicForce | MeasuredForce):
            raise ValueError("force must be a PneumaticForce, HydraulicForce or MeasuredForce; got "
                             f"{type(self.force).__name__}")
        object.__setattr__(self, "frequency_Hz", check_real("drive.frequency", self.frequency_Hz,
                                                            lo=0.0, lo_open=True))
        if (self.restitution is None) == (self.stop_area_m2 is None):
            raise ValueError("give exactly one of stop.restitution and stop.area")
        if self.restitution is not None:
            object.__setattr__(self, "restitution", check_real("stop.restitution",
                                                               self.restitution, lo=0.0, hi=1.0))
        else:
            a_s = check_real("stop.area", self.stop_area_m2, lo=0.0, lo_open=True)
            if a_s < self.bar.area_m2:
                raise ValueError(
                    f"stop.area must be at least the piston's area A = {self.bar.area_m2:.6g} m^2 "
                    f"(a thinner stop bar would give R < 0); got {a_s:.6g} m^2")
            object.__setattr__(self, "stop_area_m2", a_s)
        object.__setattr__(self, "damping_N_s_m2", check_real("damping.coefficient",
                                                              self.damping_N_s_m2, lo=0.0))
        object.__setattr__(self, "n_modes", check_int("model.n_modes", self.n_modes, lo=0,
                                                      hi=4096))
        if not isinstance(self.name, str):
            raise ValueError(f"name must be a string; got {self.name!r}")
        if isinstance(self.force, MeasuredForce):
            self._measured  # noqa: B018  (fit the series now: a bad curve fails here, not later)

    # -- scales and dimensionless model ------------------------------------------------------
    @property
    def R(self) -> float:
        """Restitution coefficient (dimensionless): given, or ``(A_s - A)/(A_s + A)``."""
        if self.restitution is not None:
            return self.restitution
        a, a_s = self.bar.area_m2, self.stop_area_m2
        return (a_s - a) / (a_s + a)

    @property
    def order(self) -> int:
        """Force cycles per impact cycle (``k`` of a pneumatic load, else 1)."""
        return self.force.order

    @property
    def period_s(self) -> float:
        """Drive period ``1 / f`` (s)."""
        return 1.0 / self.frequency_Hz

    @property
    def blow_frequency_Hz(self) -> float:
        """Blow frequency ``Omega / 2 pi = f / k`` (Hz) of a one-impact periodic motion."""
        return self.frequency_Hz / self.order

    @property
    def scales(self) -> Scales:
        """The SI units of the dimensionless model (eq. 2)."""
        om = TWO_PI * self.blow_frequency_Hz
        L = self.bar.length_m
        m = self.bar.mass_kg
        return Scales(omega_rad_s=om, time_s=1.0 / om, length_m=L, velocity_m_s=L * om,
                      force_N=m * L * om * om, damping_N_s_m2=self.bar.mass_per_length_kg_m * om)

    @property
    def s(self) -> float:
        """``s = c / (L Omega)`` (eq. 2)."""
        return self.bar.wave_speed_m_s / (self.bar.length_m * self.scales.omega_rad_s)

    @property
    def d(self) -> float:
        """``d = D / (M Omega)`` (eq. 2)."""
        return self.damping_N_s_m2 / self.scales.damping_N_s_m2

    @property
    def damping_ratio(self) -> float:
        """Damping ratio ``zeta = d / (2 s pi)`` of the first flexible mode (dimensionless)."""
        return self.d / (2.0 * math.pi * self.s)

    @property
    def model(self) -> BarModel:
        """The dimensionless :class:`~impactbar.BarModel`."""
        return BarModel(s=self.s, d=self.d, R=self.R, n_modes=self.n_modes)

    @functools.cached_property
    def _measured(self):
        """``(mean_N, harmonics_N, fit)`` of a measured force, computed once."""
        return self.force.fourier(self.period_s)

    @property
    def load(self) -> Load:
        """The dimensionless load (:class:`~impactbar.CosineLoad`, square wave, piecewise
        constant or :class:`~impactbar.FourierLoad`), with period ``2 pi``."""
        fs = self.scales.force_N
        if isinstance(self.force, MeasuredForce):
            mean, harm, _ = self._measured
            return FourierLoad(mean / fs, harm / fs)
        return self.force.load(fs)

    @property
    def fourier_fit(self) -> FourierFit | None:
        """For a measured force, how well its Fourier series meets the tolerance; else None."""
        return self._measured[2] if isinstance(self.force, MeasuredForce) else None

    # -- derived engineering figures ---------------------------------------------------------
    @property
    def mass_kg(self) -> float:
        """Piston mass ``m`` (kg)."""
        return self.bar.mass_kg

    @property
    def mean_force_N(self) -> float:
        """Mean driving force (N)."""
        if isinstance(self.force, MeasuredForce):
            return self._measured[0]
        return self.force.mean_force_N

    @property
    def rigid_impact_velocity_m_s(self) -> float:
        """Impact velocity of the rigid-body mode in any one-impact periodic motion (m/s):
        ``v = F_mean / (f_b m (1 + R))`` with ``f_b`` the blow frequency (momentum balance over a
        period, MODEL.md section 4: ``2 pi p0 / (1 + R)`` dimensionless)."""
        return self.mean_force_N / (self.blow_frequency_Hz * self.mass_kg * (1.0 + self.R))

    @property
    def contact_duration_s(self) -> float:
        """Contact duration ``2 L / c`` of an impact (s)."""
        return self.bar.contact_duration_s

    @property
    def contact_fraction(self) -> float:
        """Contact duration over the impact period, ``2 L f_b / c = 1 / (pi s)`` (dimensionless)."""
        return self.contact_duration_s * self.blow_frequency_Hz

    def check_short_impacts(self, limit: float = SHORT_IMPACT_LIMIT) -> bool:
        """Whether impacts are short against the period (``contact_fraction <= limit``); issue an
        :class:`ImpactDurationWarning` when they are not."""
        if self.contact_fraction <= limit:
            return True
        warnings.warn(
            f"contact duration 2L/c = {self.contact_duration_s:.4g} s is "
            f"{self.contact_fraction:.1%} of the impact period {1.0 / self.blow_frequency_Hz:.4g}"
            f" s (limit {limit:.0%}): the paper's instantaneous impact law is a poor "
            "approximation here",
            ImpactDurationWarning, stacklevel=2)
        return False

    def peak_stress_Pa(self, impact_velocity_m_s) -> np.ndarray:
        """Peak compressive stress in the piston at impact (Pa).

        ``sigma = rho c v Z_s / (Z + Z_s)`` for a stop of impedance ``Z_s`` against the piston's
        ``Z = rho c A`` (two bars in contact). For a stop bar of the same material
        ``Z_s / (Z + Z_s) = A_s / (A + A_s) = (1 + R) / 2``; a restitution given directly is read
        as the same impedance ratio, so a rigid stop (``R = 1``) gives ``rho c v``.
        """
        v = np.asarray(impact_velocity_m_s, dtype=float)
        b = self.bar
        return b.density_kg_m3 * b.wave_speed_m_s * v * 0.5 * (1.0 + self.R)

    def to_dict(self) -> dict:
        """The inputs and derived scales, JSON-ready (SI floats, keys named with units)."""
        out = {
            "name": self.name,
            "mass_kg": self.mass_kg,
            "mean_force_N": self.mean_force_N,
            "frequency_Hz": self.frequency_Hz,
            "blow_frequency_Hz": self.blow_frequency_Hz,
            "restitution": self.R,
            "stop_area_m2": self.stop_area_m2,
            "E_Pa": self.bar.E_Pa,
            "density_kg_m3": self.bar.density_kg_m3,
            "length_m": self.bar.length_m,
            "area_m2": self.bar.area_m2,
            "diameter_m": self.bar.diameter_m,
            "wave_speed_m_s": self.bar.wave_speed_m_s,
            "damping_N_s_m2": self.damping_N_s_m2,
            "damping_ratio": self.damping_ratio,
            "contact_duration_s": self.contact_duration_s,
            "contact_fraction": self.contact_fraction,
            "short_impacts": self.contact_fraction <= SHORT_IMPACT_LIMIT,
            "force": self.force.to_dict(),
            "dimensionless": {"s": self.s, "d": self.d, "R": self.R, "n_modes": self.n_modes,
                              "p0": self.load.p0},
        }
        fit = self.fourier_fit
        if fit is not None:
            out["fourier"] = dataclasses.asdict(fit)
        return out

    # -- constructors ------------------------------------------------------------------------
    @classmethod
    def from_config(cls, config: dict, *, base_dir=None) -> Hammer:
        """A hammer from a nested mapping with the keys of a TOML config (module docstring).

        Values with a dimension must carry a unit (``"45 mm"``) or be pint quantities;
        ``restitution``, ``ratio``, ``fraction``, ``k``, ``tolerance``, ``max_harmonics`` and
        ``n_modes`` are plain numbers. ``damping.coefficient`` is either a total coefficient of the
        piston (N s/m, e.g. ``"2.4 N*s/m"``) or one per unit length (N s/m^2), told apart by
        dimension; ``damping.ratio`` is ``zeta`` of the first flexible mode, ``d = 2 zeta s pi``.
        A relative ``force.csv`` path is taken from ``base_dir`` (default: the working directory).

        Raises
        ------
        ValueError
            An unknown or missing key (named), a value without its unit, of the wrong dimension,
            or out of range.
        """
        return _hammer_from_config(config, base_dir)

    @classmethod
    def from_toml(cls, path) -> Hammer:
        """A hammer from a TOML file (keys as in :meth:`from_config`); relative CSV paths are
        taken from the file's folder."""
        return load_config(path)

    @classmethod
    def from_dimensionless(cls, model: BarModel, load: Load, bar: Bar, *, stop_area_m2=None,
                           name: str = "") -> Hammer:
        """The hammer whose dimensionless form, for the piston ``bar``, is ``(model, load)``:
        the inverse of :attr:`model` and :attr:`load` (eq. 2 solved for ``f``, ``D`` and forces).

        Supports :class:`~impactbar.CosineLoad`, :class:`~impactbar.SquareWaveLoad` and two-level
        :class:`~impactbar.PiecewiseConstantLoad`. The restitution is ``model.R`` unless
        ``stop_area_m2`` is given (then it must give the same ``R``).
        """
        omega = bar.wave_speed_m_s / (bar.length_m * model.s)
        fscale = bar.mass_kg * bar.length_m * omega**2
        if isinstance(load, CosineLoad):
            force = PneumaticForce(load.p0 * fscale, load.pk * fscale, load.k)
            f = omega * load.k / TWO_PI
        elif isinstance(load, SquareWaveLoad):
            force = HydraulicForce(load.q * fscale, -load.q * fscale, load.kappa / 2.0)
            f = omega / TWO_PI
        elif isinstance(load, PiecewiseConstantLoad) and load.breaks.size == 2:
            force = HydraulicForce(load.levels[0] * fscale, load.levels[1] * fscale,
                                   load.breaks[1] / TWO_PI)
            f = omega / TWO_PI
        else:
            raise ValueError(f"load: cannot express {type(load).__name__} as an SI force")
        kw = {"restitution": model.R} if stop_area_m2 is None else {"stop_area_m2": stop_area_m2}
        h = cls(bar=bar, frequency_Hz=f, force=force,
                damping_N_s_m2=model.d * bar.mass_per_length_kg_m * omega, n_modes=model.n_modes,
                name=name, **kw)
        if stop_area_m2 is not None and not math.isclose(h.R, model.R, rel_tol=1e-9, abs_tol=1e-12):
            raise ValueError(f"stop.area gives R = {h.R:.6g}, not the model's R = {model.R:.6g}")
        return h


# --------------------------------------------------------------------------------------------
# configuration
# --------------------------------------------------------------------------------------------
_SECTIONS = {
    "bar": {"E", "density", "length", "diameter", "area"},
    "damping": {"coefficient", "ratio"},
    "stop": {"restitution", "area"},
    "drive": {"frequency"},
    "force": {"kind", "mean", "amplitude", "k", "high", "low", "fraction", "csv", "tolerance",
              "max_harmonics"},
    "model": {"n_modes"},
}
_FORCE_KEYS = {
    "pneumatic": {"mean", "amplitude", "k"},
    "hydraulic": {"high", "low", "fraction"},
    "measured": {"csv", "tolerance", "max_harmonics"},
}
_REQUIRED = {"bar", "stop", "drive", "force"}


def _section(config: dict, name: str) -> dict:
    sec = config.get(name, {})
    if not isinstance(sec, dict):
        raise ValueError(f"[{name}] must be a table of keys; got {sec!r}")
    unknown = sorted(set(sec) - _SECTIONS[name])
    if unknown:
        raise ValueError(f"unknown key {name}.{unknown[0]}; allowed in [{name}]: "
                         f"{', '.join(sorted(_SECTIONS[name]))}")
    return sec


def _need(sec: dict, section: str, key: str):
    if key not in sec:
        raise ValueError(f"missing key {section}.{key}")
    return sec[key]


def _dimensionless(name: str, value, **rng) -> float:
    return check_real(name, to_si(name, value, "", "0.3"), **rng)


def _hammer_from_config(config: dict, base_dir) -> Hammer:
    if not isinstance(config, dict):
        raise ValueError("a configuration must be a mapping of sections; got "
                         f"{type(config).__name__}")
    unknown = sorted(set(config) - set(_SECTIONS) - {"name"})
    if unknown:
        raise ValueError(f"unknown key {unknown[0]!r}; allowed at top level: name, "
                         f"{', '.join(sorted(_SECTIONS))}")
    missing = sorted(_REQUIRED - set(config))
    if missing:
        raise ValueError(f"missing section [{missing[0]}]")
    b = _section(config, "bar")
    bar = Bar.from_units(_need(b, "bar", "E"), _need(b, "bar", "density"),
                         _need(b, "bar", "length"), diameter=b.get("diameter"), area=b.get("area"))

    drive = _section(config, "drive")
    freq = _positive("drive.frequency", to_si("drive.frequency", _need(drive, "drive", "frequency"),
                                               "Hz", "'40 Hz' or '2400 bpm'", what="a frequency"))

    stop = _section(config, "stop")
    if ("restitution" in stop) == ("area" in stop):
        raise ValueError("give exactly one of stop.restitution and stop.area")
    if "restitution" in stop:
        stop_kw = {"restitution": _dimensionless("stop.restitution", stop["restitution"])}
    else:
        stop_kw = {"stop_area_m2": to_si("stop.area", stop["area"], "m**2", "'15.9 cm^2'",
                                         what="an area")}

    force = _force_from_config(_section(config, "force"), base_dir)

    model = _section(config, "model")
    n_modes = check_int("model.n_modes", model.get("n_modes", 16), lo=0, hi=4096)

    damp = _section(config, "damping")
    if "coefficient" in damp and "ratio" in damp:
        raise ValueError("give at most one of damping.coefficient and damping.ratio")
    name = config.get("name", "")
    h = Hammer(bar=bar, frequency_Hz=freq, force=force, n_modes=n_modes, name=name, **stop_kw)
    if "coefficient" in damp:
        val, unit = to_si_any("damping.coefficient", damp["coefficient"], ("N*s/m", "N*s/m**2"),
                              "'2.4 N*s/m' (whole piston) or '12 N*s/m^2' (per unit length)",
                              "a viscous damping coefficient")
        val = check_real("damping.coefficient", val, lo=0.0)
        h = dataclasses.replace(h, damping_N_s_m2=val / bar.length_m if unit == "N*s/m" else val)
    elif "ratio" in damp:
        zeta = _dimensionless("damping.ratio", damp["ratio"], lo=0.0)
        d = 2.0 * zeta * h.s * math.pi
        h = dataclasses.replace(h, damping_N_s_m2=d * h.scales.damping_N_s_m2)
    return h


def _force_from_config(sec: dict, base_dir) -> Force:
    kind = _need(sec, "force", "kind")
    if kind not in _FORCE_KEYS:
        raise ValueError(f"force.kind must be one of {', '.join(sorted(_FORCE_KEYS))}; "
                         f"got {kind!r}")
    extra = sorted(set(sec) - _FORCE_KEYS[kind] - {"kind"})
    if extra:
        raise ValueError(f"key force.{extra[0]} does not apply to force.kind = {kind!r}; allowed: "
                         f"{', '.join(sorted(_FORCE_KEYS[kind]))}")

    def force(key):
        return to_si(f"force.{key}", _need(sec, "force", key), "N", "'2.5 kN'", what="a force")

    if kind == "pneumatic":
        return PneumaticForce(force("mean"), force("amplitude"), sec.get("k", 1))
    if kind == "hydraulic":
        return HydraulicForce(force("high"), force("low"),
                              _dimensionless("force.fraction", _need(sec, "force", "fraction")))
    path = _need(sec, "force", "csv")
    if not isinstance(path, str):
        raise ValueError(f"force.csv must be a file path; got {path!r}")
    p = Path(path)
    if not p.is_absolute() and base_dir is not None:
        p = Path(base_dir) / p
    return MeasuredForce.from_csv(p, tolerance=_dimensionless("force.tolerance",
                                                              sec.get("tolerance", 0.01)),
                                  max_harmonics=sec.get("max_harmonics", 256))


def load_config(path) -> Hammer:
    """Read a hammer from a TOML file (keys in the module docstring).

    Raises
    ------
    ValueError
        A missing or malformed file, or any invalid key or value (named).
    """
    path = Path(path)
    try:
        with path.open("rb") as fh:
            config = tomllib.load(fh)
    except OSError as exc:
        raise ValueError(f"cannot read the configuration {str(path)!r}: {exc.strerror}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{str(path)!r} is not valid TOML: {exc}") from exc
    return _hammer_from_config(config, path.parent)


# --------------------------------------------------------------------------------------------
# presets
# --------------------------------------------------------------------------------------------
# Both presets use a steel piston: E = 210 GPa and rho = 7850 kg/m^3 are the textbook values of
# carbon and low-alloy steel (e.g. EN 1993-1-1, section 3.2.6: E = 210 000 N/mm^2). Their rod,
# the stop, is a long steel bar (the shank adapter / drill steel), so R follows from its area.
# The forces are chosen from the rigid-limit identity v = F_mean / (f m (1 + R)) (MODEL.md
# section 4) to give a typical impact velocity, and checked to give an admissible orbit.
PRESETS: dict[str, dict] = {
    # A pneumatic top-hammer rock drill (the class of a heavy hand-held drill or a light drifter).
    "pneumatic-drill": {
        "name": "pneumatic-drill",
        "bar": {
            "E": "210 GPa",  # steel, see above
            "density": "7850 kg/m^3",  # steel
            # 200 mm x 40 mm: m = 7850 * pi/4 * 0.04^2 * 0.2 = 1.97 kg, a piston of "a few kg"
            # (pistons of hand-held and light pneumatic drills weigh about 1-3 kg)
            "length": "200 mm",
            "diameter": "40 mm",
        },
        # A 45 mm shank against the 40 mm piston: R = (45^2 - 40^2)/(45^2 + 40^2) = 0.117.
        "stop": {"area": "15.904 cm^2"},  # pi/4 * 4.5^2 cm^2
        # 40 Hz = 2400 blows per minute, inside the 2000-3000 bpm of pneumatic drills; a jackhammer
        # strikes about 25 times a second (ritchiewiki.com, "Pneumatic Drill").
        "drive": {"frequency": "40 Hz"},
        # Mean force 800 N: about 0.63 MPa (the usual 6-7 bar shop air) on the 12.6 cm^2 piston
        # face. It gives v = 800 / (40 * 1.97 * 1.117) = 9.1 m/s (energy 81 J, power 3.2 kW),
        # inside the 5-12 m/s of air hammers. Amplitude 2150 N puts p0/p1 = 0.372 inside the
        # paper's stable band (MODEL.md section 6: 0.337 < p0/p1 < 0.403 at R = 0.117).
        "force": {"kind": "pneumatic", "mean": "800 N", "amplitude": "2150 N"},
        # Viscous friction of the guided piston, unknown in practice: 2.4 N s/m makes
        # 2 pi d = 0.03, the damped case of the paper's Fig. 5.
        "damping": {"coefficient": "2.4 N*s/m"},
        "model": {"n_modes": 16},
    },
    # A hydraulic top-hammer rock drill (drifter) with a differential piston.
    "hydraulic-drill": {
        "name": "hydraulic-drill",
        "bar": {
            "E": "210 GPa",
            "density": "7850 kg/m^3",
            # A long slender piston, 450 mm x 45 mm: m = 5.6 kg. Hydraulic drifter pistons are
            # longer and heavier than pneumatic ones (a few kg up to about 10 kg).
            "length": "450 mm",
            "diameter": "45 mm",
        },
        # A 56 mm shank: R = (56^2 - 45^2)/(56^2 + 45^2) = 0.215. (With a 52 or 57 mm shank the
        # struck end's ringing after the jumps of the square wave grazes the stop between impacts
        # and the one-impact orbits are inadmissible: see MODEL.md section 5.)
        "stop": {"area": "24.630 cm^2"},  # pi/4 * 5.6^2 cm^2
        # 55 Hz: hydraulic drills strike at 40-70 Hz; a stress-wave bench study measured up to
        # 62 Hz and up to 346 J per blow at 18-23 MPa ("Influence of piston mass and working
        # pressure on the impact performance of a hydraulic rock drill using the stress wave
        # method"; see also Ma et al., Adv. Mech. Eng. 11(4), 2019, doi:10.1177/1687814019841486).
        "drive": {"frequency": "55 Hz"},
        # Differential piston: the front annulus A_f is always at supply pressure p, the rear area
        # A_r = 2 A_f is switched between p and tank, so the net force is +p A_f (forward stroke)
        # and -p A_f (return): the paper's symmetric square wave (eq. 34). p = 20 MPa on
        # A_f = 10 cm^2 gives +-20 kN. A fraction 0.58 of the period forward (kappa = 1.16) gives
        # a mean of 3.2 kN and a rigid-limit v = 3200 / (55 * 5.62 * 1.215) = 8.5 m/s (204 J,
        # 11 kW); the flexible piston's struck end arrives at 9.3 m/s in the admissible orbit.
        # That orbit is unstable, as every hydraulic one-impact orbit (paper eq. 41): simulated
        # from rest the motion does not settle (paper Section 5). A real drifter switches its
        # valve on the piston's position, which this time-periodic load does not represent.
        "force": {"kind": "hydraulic", "high": "20 kN", "low": "-20 kN", "fraction": 0.58},
        # Oil-film damping of the piston guides, unknown in practice: 9 N s/m makes 2 pi d = 0.03,
        # the damped case of the paper's Fig. 8.
        "damping": {"coefficient": "9 N*s/m"},
        "model": {"n_modes": 16},
    },
}


def preset(name: str) -> Hammer:
    """A preset hammer: ``"pneumatic-drill"`` or ``"hydraulic-drill"`` (numbers documented in
    the source).

    Raises
    ------
    ValueError
        For an unknown name; the message lists the presets.
    """
    if name not in PRESETS:
        raise ValueError(f"unknown preset {name!r}; available: {', '.join(sorted(PRESETS))}")
    return _hammer_from_config(PRESETS[name], None)


# --------------------------------------------------------------------------------------------
# results in SI
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PhysicalOrbit:
    """A one-impact periodic motion with its engineering figures in SI.

    Attributes
    ----------
    orbit : PeriodicOrbit
        The dimensionless orbit (``impactbar.periodic_orbits``).
    phase_rad : float
        Phase ``phi`` of the load at impact (rad).
    impact_velocity : float
        Dimensionless impact velocity ``u_t(1, 2 pi-)``.
    impact_velocity_m_s : float
        Impact velocity ``v = L Omega u_t`` (m/s).
    blow_energy_J : float
        Energy per blow ``m v^2 / 2`` (J): the kinetic energy of the piston moving as a rigid body
        at the struck end's velocity. This is the standard figure of merit of rock drills; it
        ignores the elastic vibration energy of the piston.
    blow_frequency_Hz : float
        Blows per second ``Omega / 2 pi`` (Hz).
    power_W : float
        Impact power, energy per blow times blow frequency (W).
    peak_stress_Pa : float
        Peak compressive stress at impact (Pa), see :meth:`Hammer.peak_stress_Pa`.
    admissible, stable : bool
        As in the dimensionless orbit (MODEL.md sections 5, 7).
    max_abs_multiplier : float
        Largest modulus of the Floquet multipliers.
    """

    orbit: object
    phase_rad: float
    impact_velocity: float
    impact_velocity_m_s: float
    blow_energy_J: float
    blow_frequency_Hz: float
    power_W: float
    peak_stress_Pa: float
    admissible: bool
    stable: bool
    max_abs_multiplier: float

    @classmethod
    def from_orbit(cls, orbit, hammer: Hammer) -> PhysicalOrbit:
        """Convert a dimensionless ``PeriodicOrbit`` of ``hammer``'s model."""
        v = float(orbit.impact_velocity) * hammer.scales.velocity_m_s
        energy = 0.5 * hammer.mass_kg * v * v
        fb = hammer.blow_frequency_Hz
        return cls(
            orbit=orbit, phase_rad=float(orbit.phase),
            impact_velocity=float(orbit.impact_velocity), impact_velocity_m_s=v,
            blow_energy_J=energy, blow_frequency_Hz=fb, power_W=energy * fb,
            peak_stress_Pa=float(hammer.peak_stress_Pa(v)), admissible=bool(orbit.admissible),
            stable=bool(orbit.stable), max_abs_multiplier=float(orbit.max_abs_multiplier))

    def to_dict(self) -> dict:
        """JSON-ready figures (without the dimensionless orbit object)."""
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if f.name != "orbit"}


def orbits(hammer: Hammer) -> list[PhysicalOrbit]:
    """The one-impact periodic motions of ``hammer`` with their SI figures.

    Calls ``impactbar.periodic_orbits(hammer.model, hammer.load)`` and converts each orbit; warns
    (:class:`ImpactDurationWarning`) when impacts are not short against the period.

    Returns
    -------
    list of PhysicalOrbit
    """
    import impactbar

    hammer.check_short_impacts()
    found = impactbar.periodic_orbits(hammer.model, hammer.load)
    return [PhysicalOrbit.from_orbit(o, hammer) for o in found]


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """A simulated motion of a hammer in SI units.

    Attributes
    ----------
    hammer : Hammer
    trajectory : Trajectory
        The dimensionless trajectory (``impactbar.simulate``).
    t_end_s : float
        Simulated time (s), from 0.
    impact_times_s : numpy.ndarray, shape (n,)
        Impact times (s).
    impact_velocities_m_s : numpy.ndarray, shape (n,)
        Arrival velocities of the struck end (m/s).
    blow_energies_J : numpy.ndarray, shape (n,)
        ``m v^2 / 2`` per impact (J).
    """

    hammer: Hammer
    trajectory: object
    t_end_s: float
    impact_times_s: np.ndarray
    impact_velocities_m_s: np.ndarray
    blow_energies_J: np.ndarray

    def end_displacement_m(self, t_s) -> np.ndarray:
        """Displacement of the struck end (m, negative off the stop) at times ``t_s`` (s)."""
        sc = self.hammer.scales
        t = np.asarray(t_s, dtype=float) / sc.time_s
        return _evaluate(self.trajectory.end_displacement, t) * sc.length_m

    def end_velocity_m_s(self, t_s) -> np.ndarray:
        """Velocity of the struck end (m/s) at times ``t_s`` (s); from the trajectory's own
        ``end_velocity`` when it has one, else by a central difference of the displacement."""
        sc = self.hammer.scales
        t = np.asarray(t_s, dtype=float) / sc.time_s
        ev = getattr(self.trajectory, "end_velocity", None)
        if callable(ev):
            return _evaluate(ev, t) * sc.velocity_m_s
        h = 1e-6
        tend = self.t_end_s / sc.time_s
        lo = np.clip(t - h, 0.0, tend)
        hi = np.clip(t + h, 0.0, tend)
        u = self.trajectory.end_displacement
        return (_evaluate(u, hi) - _evaluate(u, lo)) / (hi - lo) * sc.velocity_m_s


def _evaluate(fn, t: np.ndarray) -> np.ndarray:
    """``fn`` at the times ``t``: in one call when ``fn`` takes arrays, else one time at a time."""
    try:
        out = np.asarray(fn(t), dtype=float)
        if out.shape == t.shape:
            return out
    except (TypeError, ValueError):
        pass
    return np.array([float(fn(float(x))) for x in t.ravel()]).reshape(t.shape)


def simulate(hammer: Hammer, *, periods: float = 40.0, gap_m: float = 0.0,
             max_impacts: int | None = None) -> SimulationResult:
    """Simulate ``hammer`` from rest, ``gap_m`` off the stop, over ``periods`` impact periods.

    Parameters
    ----------
    hammer : Hammer
    periods : float, optional
        Length of the run in impact periods ``1 / f_b`` (``k`` force cycles each), ``> 0``.
    gap_m : float, optional
        Initial distance of the struck end from the stop (m), ``>= 0``; the piston starts at rest.
    max_impacts : int, optional
        Passed to ``impactbar.simulate``.

    Returns
    -------
    SimulationResult

    Raises
    ------
    RuntimeError
        If this build of impactbar has no simulator (``impactbar.simulate``).
    """
    import impactbar

    periods = check_real("periods", periods, lo=0.0, lo_open=True)
    gap_m = check_real("gap", gap_m, lo=0.0)
    sim = getattr(impactbar, "simulate", None)
    initial_state = getattr(impactbar, "InitialState", None)
    if sim is None or initial_state is None:
        raise RuntimeError("this build of impactbar has no simulator (impactbar.simulate)")
    hammer.check_short_impacts()
    sc = hammer.scales
    t_end = TWO_PI * periods
    traj = sim(hammer.model, hammer.load,
               initial_state.rigid(end_displacement=-gap_m / sc.length_m, velocity=0.0), t_end,
               max_impacts=max_impacts)
    v = np.asarray(traj.impact_velocities, dtype=float) * sc.velocity_m_s
    return SimulationResult(
        hammer=hammer, trajectory=traj, t_end_s=t_end * sc.time_s,
        impact_times_s=np.asarray(traj.impact_times, dtype=float) * sc.time_s,
        impact_velocities_m_s=v, blow_energies_J=0.5 * hammer.mass_kg * v * v)


# --------------------------------------------------------------------------------------------
# command line (the implementation lives in _cli_physical; imported lazily, no cycle)
# --------------------------------------------------------------------------------------------
def add_physical_arguments(parser) -> None:
    """Add an optional positional ``config`` (a TOML file) and ``--preset NAME`` to an argparse
    ``parser`` (used by ``impactbar orbits`` and ``impactbar simulate``)."""
    from ._cli_physical import add_physical_arguments as add

    add(parser)


def run_physical_orbits(args) -> int:
    """``impactbar orbits CONFIG.toml | --preset NAME [--json]``: the SI table or JSON of the
    hammer's one-impact orbits; returns the exit status. See ``impactbar._cli_physical``."""
    from ._cli_physical import run_physical_orbits as run

    return run(args)
