"""The hammer: bar, stop, damping and force together, their dimensionless scales (paper eq. 2)
and the dimensionless model they define."""

from __future__ import annotations

import dataclasses
import functools
import math
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._shared.validate import check_int, check_real
from ..laws import LAWS, RodRock, piston_law
from ..loads import FourierLoad, Load
from ..model import BarModel
from . import tree
from .bar import (
    SHORT_IMPACT_LIMIT,
    TWO_PI,
    Bar,
    ImpactDurationWarning,
    SteppedBar,
    _positive,
    check_piston,
    piston_from_units,
)
from .config import (
    _REQUIRED,
    _SECTIONS,
    CONFIG_KINDS,
    PRESETS,
    _dimensionless,
    _force_from_config,
    _need,
    _section,
    config_kind,
    read_as,
    read_toml,
)
from .forces import Force, FourierFit, HydraulicForce, MeasuredForce, PneumaticForce
from .rock import ROCK_SECTIONS, DrillString, rock_from_config
from .units import to_si_any


# --------------------------------------------------------------------------------------------
# the hammer
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Scales:
    r"""The units of the dimensionless model (eq. 2) for one hammer, in SI.

    Attributes
    ----------
    omega_rad_s : float
        ``Omega``, the angular frequency of the impact cycle (rad/s); dimensionless time is
        ``t = Omega T``.
    time_s : float
        :math:`1 / \Omega` (s).
    length_m : float
        :math:`L` (m): :math:`U = L u`.
    velocity_m_s : float
        :math:`L \Omega` (m/s): :math:`U_T = L \Omega u_t`.
    force_N : float
        :math:`m L \Omega^2 = M L^2 \Omega^2` (N): :math:`P = m L \Omega^2 p`.
    damping_N_s_m2 : float
        :math:`M \Omega` (N s/m^2): :math:`D = M \Omega d`.
    """

    omega_rad_s: float
    time_s: float
    length_m: float
    velocity_m_s: float
    force_N: float
    damping_N_s_m2: float



@dataclass(frozen=True)
class Hammer:
    r"""A percussive machine in SI units: piston, stop, damping and driving force.

    Parameters
    ----------
    bar : Bar or SteppedBar
        The piston: uniform, or of uniform segments (theory §12; under the paper's impact law or,
        with a ``drill``, the rod-rock law).
    frequency_Hz : float
        Drive frequency ``f`` (Hz), the frequency of the force cycle, ``> 0``.
    force : PneumaticForce, HydraulicForce or MeasuredForce
        The force at the driven end.
    restitution : float, optional
        Restitution coefficient :math:`R` of the stop, :math:`0 \le R \le 1` (eq. 10).
    stop_area_m2 : float, optional
        Or the stop as a long bar of the same material and area :math:`A_s \ge A` (m^2):
        :math:`R = (A_s - A) / (A_s + A)` (theory §4). Give exactly one of the two.
    damping_N_s_m2 : float, optional
        Viscous damping per unit length :math:`D` of eq. 2 (N s/m^2), :math:`\ge 0`. Default 0. A total
        coefficient :math:`c` (N s/m) of the whole piston is :math:`D = c / L`; a damping ratio :math:`\zeta`
        of the first flexible mode is :math:`d = 2 \zeta s \pi` (see :meth:`from_config`).
    n_modes : int, optional
        Flexible modes kept in the model, ``0..4096``; 0 is the rigid piston. Default 16.
    name : str, optional
        A label for reports.
    impact : {"paper", "wave"}, optional
        The impact law of :class:`~impactbar.BarModel`: ``"paper"`` (eq. 10, default) or
        ``"wave"`` (the stop as a long rod, the contact solved by characteristics, theory §4b);
        ``"rodrock"`` with ``drill``.
    drill : DrillString, optional
        The rod, bit and rock (theory §4d, :mod:`impactbar.physical.rock`): the model's law is then
        the rod-rock law they define (``impact = "rodrock"``; the stop's ``R`` plays no part).

    Notes
    -----
    :math:`\Omega = 2 \pi f / k` with :math:`k` the order of a pneumatic load (1 otherwise), so one impact
    cycle is :math:`k` force cycles and the blow frequency is :math:`f / k`.
    """

    bar: Bar | SteppedBar
    frequency_Hz: float
    force: Force
    restitution: float | None = None
    stop_area_m2: float | None = None
    damping_N_s_m2: float = 0.0
    n_modes: int = 16
    name: str = ""
    impact: str = "paper"
    drill: DrillString | None = None

    def __post_init__(self) -> None:
        check_piston(self.bar, True)  # a Bar or a SteppedBar; the law is checked below
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
        if self.drill is not None:
            if not isinstance(self.drill, DrillString):
                raise ValueError(f"drill must be a DrillString; got {type(self.drill).__name__}")
            object.__setattr__(self, "impact", "rodrock")
        elif self.impact not in LAWS:
            raise ValueError(f"model.impact must be one of {list(LAWS)}; got {self.impact!r}")
        law = RodRock if self.drill is not None else piston_law(LAWS[self.impact](), True)
        check_piston(self.bar, law.traits.stepped_piston, f"impact = {self.impact!r}")
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
        r"""Blow frequency :math:`\Omega / 2 \pi = f / k` (Hz) of a one-impact periodic motion."""
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
        r"""Damping ratio ``zeta = d / (2 s k_1)`` of the first flexible mode (dimensionless;
        :math:`k_1 = \pi` for a uniform piston, the stepped piston's first wavenumber otherwise)."""
        return self.d / (2.0 * self.bar.first_wavenumber * self.s)

    @property
    def model(self) -> BarModel:
        """The dimensionless :class:`~impactbar.BarModel`."""
        impact = self.impact if self.drill is None else self.drill.law(self.bar, self.scales)
        return BarModel(s=self.s, d=self.d, R=self.R, n_modes=self.n_modes, impact=impact,
                        piston=self.bar.piston)

    @functools.cached_property
    def _measured(self):
        """``(mean_N, harmonics_N, fit)`` of a measured force, computed once."""
        return self.force.fourier(self.period_s)

    @property
    def load(self) -> Load:
        r"""The dimensionless load (:class:`~impactbar.CosineLoad`, square wave, piecewise
        constant or :class:`~impactbar.FourierLoad`), with period :math:`2 \pi`."""
        fs = self.scales.force_N
        if isinstance(self.force, MeasuredForce):
            mean, harm, _ = self._measured
            return FourierLoad(mean / fs, harm / fs)
        return self.force.load(fs)

    @property
    def fourier_fit(self) -> FourierFit | None:
        """For a measured force, how well its Fourier series meets the tolerance; else None."""
        if not isinstance(self.force, MeasuredForce):
            return None
        _, _, fit = self._measured
        return fit

    # -- derived engineering figures ---------------------------------------------------------
    @property
    def mass_kg(self) -> float:
        """Piston mass ``m`` (kg)."""
        return self.bar.mass_kg

    @property
    def mean_force_N(self) -> float:
        """Mean driving force (N)."""
        if isinstance(self.force, MeasuredForce):
            mean, _, _ = self._measured
            return mean
        return self.force.mean_force_N

    @property
    def rigid_impact_velocity_m_s(self) -> float:
        r"""Impact velocity of the rigid-body mode in any one-impact periodic motion (m/s):
        ``v = F_mean / (f_b m (1 + R))`` with ``f_b`` the blow frequency (momentum balance over a
        period, theory §4: :math:`2 \pi p_0 / (1 + R)` dimensionless)."""
        return self.mean_force_N / (self.blow_frequency_Hz * self.mass_kg * (1.0 + self.R))

    @property
    def contact_duration_s(self) -> float:
        """Contact duration ``2 L / c`` of an impact (s)."""
        return self.bar.contact_duration_s

    @property
    def contact_fraction(self) -> float:
        r"""Contact duration over the impact period, :math:`2 L f_b / c = 1 / (\pi s)` (dimensionless)."""
        return self.contact_duration_s * self.blow_frequency_Hz

    def check_short_impacts(self, limit: float = SHORT_IMPACT_LIMIT) -> bool:
        r"""Whether impacts are short against the period (``contact_fraction`` :math:`\le` ``limit``);
        issue an :class:`ImpactDurationWarning` when they are not."""
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
                              "p0": self.load.p0, "impact": self.impact},
        }
        fit = self.fourier_fit
        if fit is not None:
            out["fourier"] = dataclasses.asdict(fit)
        if self.drill is not None:
            out["drill"] = self.drill.to_dict()
        if isinstance(self.bar, SteppedBar):  # area_m2 and diameter_m above: the struck end's
            out["segments"] = {"lengths_m": self.bar.lengths_m.tolist(),
                               "areas_m2": self.bar.areas_m2.tolist()}
        return out

    # -- constructors ------------------------------------------------------------------------
    @classmethod
    def from_config(cls, config: dict, *, base_dir=None) -> Hammer:
        r"""A hammer from a nested mapping with the keys of a TOML config (module docstring).

        Values with a dimension must carry a unit (``"45 mm"``) or be pint quantities;
        ``restitution``, ``ratio``, ``fraction``, ``k``, ``tolerance``, ``max_harmonics`` and
        ``n_modes`` are plain numbers. ``damping.coefficient`` is either a total coefficient of the
        piston (N s/m, e.g. ``"2.4 N*s/m"``) or one per unit length (N s/m^2), told apart by
        dimension; ``damping.ratio`` is :math:`\zeta` of the first flexible mode, :math:`d = 2 \zeta s \pi`.
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
    def from_dimensionless(cls, model: BarModel, load: Load, bar: Bar | SteppedBar, *, stop_area_m2=None,
                           name: str = "") -> Hammer:
        """The hammer whose dimensionless form, for the piston ``bar``, is ``(model, load)``:
        the inverse of :attr:`model` and :attr:`load` (eq. 2 solved for ``f``, ``D`` and forces).

        Supports :class:`~impactbar.CosineLoad`, :class:`~impactbar.SquareWaveLoad` and two-level
        :class:`~impactbar.PiecewiseConstantLoad`. The restitution is ``model.R`` unless
        ``stop_area_m2`` is given (then it must give the same ``R``).
        """
        check_piston(bar, True)
        if model.piston != bar.piston:
            raise ValueError(f"bar: the model's piston is {model.piston!r}, the bar's {bar.piston!r}")
        omega = bar.wave_speed_m_s / (bar.length_m * model.s)
        fscale = bar.mass_kg * bar.length_m * omega**2
        own = load.abilities
        cosine, square, pieces = own.cosine, own.square, own.pieces
        if cosine is not None:
            p0, pk, k = cosine
            force = PneumaticForce(p0 * fscale, pk * fscale, k)
            f = omega * k / TWO_PI
        elif square is not None:
            q, kappa = square
            force = HydraulicForce(q * fscale, -q * fscale, kappa / 2.0)
            f = omega / TWO_PI
        elif pieces is not None and pieces[0].size == 2:
            breaks, levels = pieces
            force = HydraulicForce(levels[0] * fscale, levels[1] * fscale, breaks[1] / TWO_PI)
            f = omega / TWO_PI
        else:
            raise ValueError(f"load: cannot express {type(load).__name__} as an SI force")
        kw = {"restitution": model.R} if stop_area_m2 is None else {"stop_area_m2": stop_area_m2}
        h = cls(bar=bar, frequency_Hz=f, force=force,
                damping_N_s_m2=model.d * bar.mass_per_length_kg_m * omega, n_modes=model.n_modes,
                name=name, impact=model.impact, **kw)
        if stop_area_m2 is not None and not math.isclose(h.R, model.R, rel_tol=1e-9, abs_tol=1e-12):
            raise ValueError(f"stop.area gives R = {h.R:.6g}, not the model's R = {model.R:.6g}")
        return h


def _hammer_from_config(config: dict, base_dir) -> Hammer:
    """The hammer a configuration mapping describes (keys and checks: :mod:`impactbar.physical.config`)."""
    if not isinstance(config, dict):
        raise ValueError("a configuration must be a mapping of sections; got "
                         f"{type(config).__name__}")
    unknown = sorted(set(config) - set(_SECTIONS) - set(ROCK_SECTIONS) - {"name"})
    if unknown:
        raise ValueError(f"unknown key {unknown[0]!r}; allowed at top level: name, "
                         f"{', '.join(sorted(set(_SECTIONS) | set(ROCK_SECTIONS)))}")
    missing = sorted(_REQUIRED - set(config))
    if missing:
        raise ValueError(f"missing section [{missing[0]}]")
    b = _section(config, "bar")
    bar = piston_from_units(_need(b, "bar", "E"), _need(b, "bar", "density"),
                            _need(b, "bar", "length"), diameter=b.get("diameter"), area=b.get("area"))

    drive = _section(config, "drive")
    freq = _positive("drive.frequency", tree.read_si("drive.frequency", _need(drive, "drive", "frequency"),
                                                     "hammer"))

    stop = _section(config, "stop")
    if ("restitution" in stop) == ("area" in stop):
        raise ValueError("give exactly one of stop.restitution and stop.area")
    if "restitution" in stop:
        stop_kw = {"restitution": _dimensionless("stop.restitution", stop["restitution"])}
    else:
        stop_kw = {"stop_area_m2": tree.read_si("stop.area", stop["area"], "hammer")}

    force = _force_from_config(_section(config, "force"), base_dir)

    model = _section(config, "model")
    n_modes = check_int("model.n_modes", model.get("n_modes", 16), lo=0, hi=4096)
    impact = model.get("impact", "paper")  # checked by Hammer: "paper" or "wave"

    damp = _section(config, "damping")
    if "coefficient" in damp and "ratio" in damp:
        raise ValueError("give at most one of damping.coefficient and damping.ratio")
    name = config.get("name", "")
    drill = rock_from_config(config, bar)  # [rod], [bit], [rock]: the rod-rock law
    h = Hammer(bar=bar, frequency_Hz=freq, force=force, n_modes=n_modes, name=name, impact=impact,
               drill=drill, **stop_kw)
    if "coefficient" in damp:
        val, unit = to_si_any("damping.coefficient", damp["coefficient"], ("N*s/m", "N*s/m**2"),
                              "'2.4 N*s/m' (whole piston) or '12 N*s/m^2' (per unit length)",
                              "a viscous damping coefficient")
        val = check_real("damping.coefficient", val, lo=0.0)
        h = dataclasses.replace(h, damping_N_s_m2=val / bar.length_m if unit == "N*s/m" else val)
    elif "ratio" in damp:
        zeta = _dimensionless("damping.ratio", damp["ratio"], lo=0.0)
        d = 2.0 * zeta * h.s * bar.first_wavenumber
        h = dataclasses.replace(h, damping_N_s_m2=d * h.scales.damping_N_s_m2)
    return h


def load_config(path) -> Hammer:
    """Read a hammer from a TOML file (keys in the module docstring); :func:`~impactbar.physical.load`
    reads any configuration in SI units (a hammer's, a drifter's, a circuit's).

    Raises
    ------
    ValueError
        A missing or malformed file; a drifter's configuration (naming its kind and the reader that
        takes it); any invalid key or value (named, after the kind of machine the file was read as).
    """
    path = Path(path)
    config = read_toml(path)
    kind = config_kind(config)
    if kind != "hammer":
        raise ValueError(f"{path} describes {CONFIG_KINDS[kind].what}, not a hammer: read it with "
                         "impactbar.physical.load")
    try:
        return _hammer_from_config(config, path.parent)
    except ValueError as exc:
        raise read_as(kind, path, exc) from exc


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
