"""The parts of the rod-and-rock law (theory §4d): a uniform segment of the rod
(:class:`RodSegment`) and Lundberg's bilinear rock (:class:`BilinearRock`), in the model's
dimensionless units (:mod:`impactbar.laws.rodrock.law`)."""

from __future__ import annotations

from dataclasses import dataclass

from ..._shared.validate import check_real

__all__ = ["BilinearRock", "RodSegment"]


@dataclass(frozen=True)
class RodSegment:
    """A uniform piece of the rod (theory §4d).

    Parameters
    ----------
    length : float
        In piston lengths, in ``[1e-100, 1e100]``.
    impedance : float
        ``E A / C`` relative to the piston's, in ``[1e-100, 1e100]`` (beyond, the waves' energies
        ``F^2/Z`` leave the float range).
    wave_speed : float
        Relative to the piston's, in ``[1e-100, 1e100]``; default 1 (the same material).

    Raises
    ------
    ValueError
        A value that is not a finite real number in its range (named).

    Examples
    --------
    >>> from impactbar import RodSegment
    >>> RodSegment(length=40.0, impedance=1.0)  # the wave speed defaults to the piston's
    RodSegment(length=40.0, impedance=1.0, wave_speed=1.0)
    """

    length: float
    impedance: float
    wave_speed: float = 1.0

    def __post_init__(self) -> None:
        for name in ("length", "impedance", "wave_speed"):  # (bounded: 1e308 and 5e-324 gave a NaN
            # efficiency, a length of 5e-324 a travel time of 0)
            object.__setattr__(self, name, check_real(name, getattr(self, name), lo=1e-100, hi=1e100))

    def travel_time(self, model) -> float:
        """Time a wave takes to cross the segment (model time): ``length / (wave_speed s)``."""
        return self.length / (self.wave_speed * model.s)


@dataclass(frozen=True)
class BilinearRock:
    """Lundberg's bilinear bit-rock law (Lundberg 1982; Karlsson, Lundberg and Sundin 1989): the force
    grows as ``k p`` with the penetration ``p`` while it grows past its largest value, and follows
    ``k_u (p - p_perm)`` on unloading and reloading below it, with ``p_perm = p_max - R_max / k_u``;
    the force is compressive only (the bit lifts off for ``p < p_perm``).

    Parameters
    ----------
    k : float
        Loading stiffness (model units of force per length, ``K / (m Omega^2)``), ``> 0``.
    k_u : float
        Unloading stiffness, ``k_u >= k`` (``gamma = k_u / k``).

    Examples
    --------
    >>> from impactbar import BilinearRock
    >>> BilinearRock(k=2.5, k_u=25.0)
    BilinearRock(k=2.5, k_u=25.0)
    """

    k: float
    k_u: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "k", check_real("k", self.k, lo=0.0, lo_open=True))
        object.__setattr__(self, "k_u", check_real("k_u", self.k_u, lo=self.k))

    @property
    def gamma(self) -> float:
        """``k_u / k >= 1``."""
        return self.k_u / self.k

