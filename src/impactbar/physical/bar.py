"""The piston (bar) in SI units, and the short-impact check (paper eq. 2, theory §1)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .._shared.validate import check_real
from .units import to_si

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


