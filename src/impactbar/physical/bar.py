"""The piston (bar) in SI units, uniform or stepped, and the short-impact check (paper eq. 2,
theory §1 and §12)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._shared.validate import check_real
from ..dynamics.stepped import SteppedPiston
from .units import to_si

TWO_PI = 2.0 * math.pi

#: Largest contact duration ``2 L / c``, as a fraction of the impact period, for which the paper's
#: instantaneous impact law (eqs. 10, 11) is taken as valid; beyond it a warning is issued.
#: In dimensionless terms the fraction is :math:`1 / (\pi s)`, so the limit is :math:`s \pi \ge 20`.
SHORT_IMPACT_LIMIT = 0.05


class ImpactDurationWarning(UserWarning):
    """The contact duration ``2 L / c`` is not short against the impact period: the paper's
    instantaneous impact law (eqs. 10, 11) is then a poor approximation."""


# --------------------------------------------------------------------------------------------
# the bar
# --------------------------------------------------------------------------------------------
class _Figures:
    """What a piston of one material derives from ``E_Pa``, ``density_kg_m3``, ``length_m`` and the
    struck end's ``area_m2`` (shared by :class:`Bar` and :class:`SteppedBar`)."""

    @property
    def wave_speed_m_s(self) -> float:
        r"""Bar wave speed :math:`c = \sqrt{E / \rho}` (m/s)."""
        return math.sqrt(self.E_Pa / self.density_kg_m3)

    @property
    def diameter_m(self) -> float:
        """Diameter of the circular section of area ``A`` (m): the struck end's."""
        return math.sqrt(4.0 * self.area_m2 / math.pi)

    @property
    def impedance_N_s_m(self) -> float:
        """Mechanical impedance ``rho c A`` (N s/m): the struck end's."""
        return self.density_kg_m3 * self.wave_speed_m_s * self.area_m2

    @property
    def contact_duration_s(self) -> float:
        """Duration ``2 L / c`` of an impact on a stop (s): the wave's return trip through the whole
        piston (a stepped piston's reflections at its steps lengthen a real contact)."""
        return 2.0 * self.length_m / self.wave_speed_m_s


@dataclass(frozen=True)
class Bar(_Figures):
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
        key, value = ("diameter", diameter) if diameter is not None else ("area", area)
        a = _section_area(f"{prefix}.{key}", key, value)
        return cls(
            E_Pa=_positive(f"{prefix}.E", to_si(f"{prefix}.E", E, "Pa", "'210 GPa'",
                                                  what="a pressure (Young's modulus)")),
            density_kg_m3=_positive(f"{prefix}.density", to_si(
                f"{prefix}.density", density, "kg/m**3", "'7850 kg/m^3'", what="a density")),
            length_m=_length(f"{prefix}.length", length),
            area_m2=a,
        )

    @property
    def mass_per_length_kg_m(self) -> float:
        """``M = rho A`` (kg/m)."""
        return self.density_kg_m3 * self.area_m2

    @property
    def mass_kg(self) -> float:
        """Piston mass ``m = rho A L`` (kg)."""
        return self.mass_per_length_kg_m * self.length_m

    @property
    def piston(self) -> None:
        """The dimensionless shape for :class:`~impactbar.BarModel` (``piston=``): ``None``, the
        uniform bar."""
        return None

    @property
    def first_wavenumber(self) -> float:
        r"""The first flexible free-free mode's wavenumber :math:`k_1 = \pi` (dimensionless; its
        angular frequency is :math:`s k_1`)."""
        return math.pi

    def describe(self) -> str:
        """A one-line description: length, section and wave speed."""
        return (f"L = {self.length_m:.4g} m, A = {self.area_m2 * 1e4:.4g} cm^2, "
                f"c = {self.wave_speed_m_s:.0f} m/s")


@dataclass(frozen=True)
class SteppedBar(_Figures):
    r"""A piston of uniform segments of one material, in SI units (theory §12).

    Its dimensionless form is :class:`~impactbar.SteppedPiston` (the segments' lengths over the
    piston's length, their areas as impedances: one material), given to
    :class:`~impactbar.BarModel` as ``piston=``. Everything :class:`Bar` offers is offered with the
    same meaning: ``length_m`` and ``mass_kg`` of the whole piston, ``mass_per_length_kg_m`` their
    ratio (the mean), and ``area_m2``, ``diameter_m`` and ``impedance_N_s_m`` at the struck end
    (the last segment), the one that meets the stop.

    Parameters
    ----------
    E_Pa, density_kg_m3 : float
        Young's modulus (Pa) and density (kg/m^3) of the one material, each ``> 0``.
    lengths_m : array_like, shape (n,)
        The segments' lengths (m), each :math:`> 0`, from the driven end to the struck end; :math:`n \ge 2`.
    areas_m2 : array_like, shape (n,)
        Their cross-sections (m^2), each :math:`> 0`, within a factor :math:`10^6` of each other.

    Raises
    ------
    ValueError
        A value not finite and positive (named), fewer than two segments (a single one is a
        :class:`Bar`), or the two arrays of different lengths.

    See Also
    --------
    piston_from_units : a :class:`Bar` or a :class:`SteppedBar` from inputs with units.

    Examples
    --------
    >>> from impactbar.physical import SteppedBar
    >>> head_neck = SteppedBar(2.1e11, 7850.0, [0.12, 0.33], [3.85e-3, 1.59e-3])
    >>> round(head_neck.mass_kg, 3), round(head_neck.length_m, 3)
    (7.746, 0.45)
    >>> head_neck.piston
    SteppedPiston(0.2667@1, 0.7333@0.413)
    """

    E_Pa: float
    density_kg_m3: float
    lengths_m: np.ndarray
    areas_m2: np.ndarray

    def __post_init__(self) -> None:
        for f in ("E_Pa", "density_kg_m3"):
            object.__setattr__(self, f, check_real(f, getattr(self, f), lo=0.0, lo_open=True))
        vecs = {}
        for f in ("lengths_m", "areas_m2"):
            try:
                v = np.array(getattr(self, f), dtype=float).ravel()
            except (TypeError, ValueError) as exc:
                raise ValueError(f"{f} must be an array of positive numbers; got {getattr(self, f)!r}"
                                 ) from exc
            for j, x in enumerate(v):
                check_real(f"{f}[{j}]", x, lo=0.0, lo_open=True)
            v.setflags(write=False)
            vecs[f] = v
            object.__setattr__(self, f, v)
        if vecs["lengths_m"].size != vecs["areas_m2"].size:
            raise ValueError(f"lengths_m and areas_m2 must have the same length; got "
                             f"{vecs['lengths_m'].size} and {vecs['areas_m2'].size}")
        if vecs["lengths_m"].size < 2:
            raise ValueError("a SteppedBar has at least 2 segments; one segment is a Bar")
        SteppedPiston(self.lengths_m, self.areas_m2)  # its checks (impedance ratio) here, not later

    def __eq__(self, other) -> bool:
        return (isinstance(other, SteppedBar) and (self.E_Pa, self.density_kg_m3)
                == (other.E_Pa, other.density_kg_m3) and np.array_equal(self.lengths_m, other.lengths_m)
                and np.array_equal(self.areas_m2, other.areas_m2))

    def __hash__(self) -> int:
        return hash((self.E_Pa, self.density_kg_m3, self.lengths_m.tobytes(), self.areas_m2.tobytes()))

    def __repr__(self) -> str:
        seg = ", ".join(f"{le * 1e3:.4g} mm x {a * 1e4:.4g} cm^2"
                        for le, a in zip(self.lengths_m, self.areas_m2, strict=True))
        return f"SteppedBar(E={self.E_Pa:.4g} Pa, density={self.density_kg_m3:.4g} kg/m^3; {seg})"

    @property
    def n_segments(self) -> int:
        """The number of segments."""
        return int(self.lengths_m.size)

    @property
    def length_m(self) -> float:
        """The piston's length ``L`` (m): the segments' sum."""
        return float(self.lengths_m.sum())

    @property
    def area_m2(self) -> float:
        """The struck end's cross-section (m^2): the last segment's, the one that meets the stop."""
        return float(self.areas_m2[-1])

    @property
    def mass_kg(self) -> float:
        r"""Piston mass :math:`m = \rho \sum_j A_j L_j` (kg)."""
        return float(self.density_kg_m3 * (self.areas_m2 @ self.lengths_m))

    @property
    def mass_per_length_kg_m(self) -> float:
        """The mean mass per length ``m / L`` (kg/m): the unit of the damping ``D`` (theory §12:
        the damping is mass-proportional, ``d`` the same in every mode)."""
        return self.mass_kg / self.length_m

    @property
    def diameters_m(self) -> np.ndarray:
        """The segments' diameters for circular sections (m), shape ``(n,)``."""
        return np.sqrt(4.0 * self.areas_m2 / math.pi)

    @property
    def piston(self) -> SteppedPiston:
        """The dimensionless shape for :class:`~impactbar.BarModel` (``piston=``)."""
        return SteppedPiston(self.lengths_m, self.areas_m2)

    @property
    def first_wavenumber(self) -> float:
        r"""The first flexible free-free mode's wavenumber :math:`k_1` (dimensionless: its angular
        frequency is :math:`s k_1`; the uniform bar's :math:`\pi`)."""
        return float(self.piston.modes(1).wavenumbers[1])

    def describe(self) -> str:
        """A one-line description: the segments, driven end first, and the wave speed."""
        seg = " + ".join(f"{le * 1e3:.4g} mm x {a * 1e4:.4g} cm^2"
                         for le, a in zip(self.lengths_m, self.areas_m2, strict=True))
        return (f"L = {self.length_m:.4g} m in {self.n_segments} segments ({seg}), "
                f"c = {self.wave_speed_m_s:.0f} m/s")


def piston_from_units(E, density, length, *, diameter=None, area=None, prefix: str = "bar"):
    """The piston from inputs with units: a :class:`Bar`, or a :class:`SteppedBar` when ``length``
    and the section are lists of its segments, driven end first (theory §12).

    Parameters
    ----------
    E, density : str, pint.Quantity or float
        Young's modulus (``"210 GPa"``) and density (``"7850 kg/m^3"``).
    length : str, pint.Quantity or sequence of them
        The length (``"450 mm"``), or the segments' lengths (``["120 mm", "330 mm"]``).
    diameter, area : str, pint.Quantity or sequence of them, optional
        Exactly one: the circular section's diameter or the area, one per segment when ``length``
        is a list (a single value: every segment the same).

    Returns
    -------
    Bar or SteppedBar
        A :class:`Bar` for one segment (a list of one included: the uniform piston, exactly).

    Raises
    ------
    ValueError
        A value without its unit or of the wrong dimension, not positive, lists of different
        lengths, or not exactly one of ``diameter`` and ``area`` (each named with ``prefix``).

    Examples
    --------
    >>> from impactbar.physical import piston_from_units
    >>> piston_from_units("210 GPa", "7850 kg/m^3", ["120 mm", "330 mm"], diameter=["70 mm", "45 mm"])
    SteppedBar(E=2.1e+11 Pa, density=7850 kg/m^3; 120 mm x 38.48 cm^2, 330 mm x 15.9 cm^2)
    """
    if not any(isinstance(v, list | tuple) for v in (length, diameter, area)):
        return Bar.from_units(E, density, length, diameter=diameter, area=area, prefix=prefix)
    lengths = list(length) if isinstance(length, list | tuple) else [length]
    n = len(lengths)
    if n == 0:
        raise ValueError(f"{prefix}.length must give at least one segment; got an empty list")
    if (diameter is None) == (area is None):
        raise ValueError(f"give exactly one of {prefix}.diameter and {prefix}.area")
    key, sec = ("diameter", diameter) if diameter is not None else ("area", area)
    secs = list(sec) if isinstance(sec, list | tuple) else [sec] * n
    if len(secs) != n:
        raise ValueError(f"{prefix}.{key} must give one value per segment of {prefix}.length "
                         f"({n}); got {len(secs)}")
    first = Bar.from_units(E, density, lengths[0], prefix=prefix, **{key: secs[0]})
    if n == 1:
        return first
    le = [_length(f"{prefix}.length[{j}]", x) for j, x in enumerate(lengths)]
    a = [_section_area(f"{prefix}.{key}[{j}]", key, x) for j, x in enumerate(secs)]
    return SteppedBar(first.E_Pa, first.density_kg_m3, le, a)


def check_piston(bar, stepped_ok: bool, law: str = "") -> None:
    """Refuse ``bar`` unless a :class:`Bar`, or a :class:`SteppedBar` where the impact law takes one
    (``stepped_ok``: the law's ``stepped_piston`` flag; ``law`` names it in the message)."""
    if not isinstance(bar, Bar | SteppedBar):
        raise ValueError(f"bar must be a Bar or a SteppedBar; got {type(bar).__name__}")
    if isinstance(bar, SteppedBar) and not stepped_ok:
        raise ValueError(
            f"bar: a stepped piston (bar.length a list of segments) is supported under the paper's, the "
            f"wave and the rod-rock laws; got {law or 'another law'}")


def _positive(name, v, given=None):
    """``v`` where positive, else a ``ValueError`` naming ``name``, the range and the value as
    ``given`` in the config (``"-32 mm"``; default ``v``)."""
    if given is None:
        return check_real(name, v, lo=0.0, lo_open=True)
    if not v > 0.0:
        raise ValueError(f"{name} must be in (0, inf); got {given!r}")
    return v


def _positive_si(name, value, unit, example, what) -> float:
    """A positive quantity in ``unit`` from an input with units (:func:`to_si`), named ``name``."""
    return _positive(name, to_si(name, value, unit, example, what=what), value)


def _length(name, value) -> float:
    """A positive length (m) from an input with units, named ``name`` in errors."""
    return _positive_si(name, value, "m", "'0.2 m'", "a length")


def _section_area(name, key, value) -> float:
    """A positive cross-section (m^2) from a ``"diameter"`` (circular) or an ``"area"`` with units,
    named ``name`` in errors (a diameter's sign is checked before it is squared)."""
    if key == "diameter":
        dia = _positive_si(name, value, "m", "'40 mm'", "a length")
        return math.pi * dia * dia / 4.0
    return _positive_si(name, value, "m**2", "'12.6 cm^2'", "an area")


