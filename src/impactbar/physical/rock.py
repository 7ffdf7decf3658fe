"""The drill string and the rock in SI units (theory §4d): the ``[rod]``, ``[bit]`` and ``[rock]``
sections of a hammer configuration, the rod-rock law they define for a hammer, and the per-blow
outputs in SI (work on rock, penetration, drilling rate, efficiencies).

The rock's two stiffnesses are the slopes of the bit's force-penetration curve, measured with the
bit in use: the loading slope ``K`` while the bit penetrates, the unloading slope ``K_u`` when the
force is released (Lundberg, Int. J. Rock Mech. Min. Sci. 19 (1982) 229-239; measured by static and
dynamic indentation with the same bit in Karlsson, Lundberg & Sundin, ibid. 26 (1989) 45-50). They
depend on the rock and the bit (size, number of buttons) and are given by the user. The example of
the docs (``docs/physical.md``) is illustrative, not measured: it puts ``K`` at Lundberg's optimum
``alpha = K (2 L / c) / Z = 1.26`` for its piston, with ``K_u = 10 K``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._shared.validate import check_int, check_real
from ..laws.rodrock import BilinearRock, RodRock, RodSegment
from ..laws.rodrock.law import CONTACT_EVENTS, DRIVEN_ENDS
from . import tree
from .bar import _positive
from .config import _section
from .outputs import OUTPUTS

__all__ = ["DrillString", "RodPiece", "rock_blows", "rock_from_config", "rock_summary", "rod_from_config"]

#: keys of the sections (added to the hammer configuration's)
ROCK_SECTIONS = {name: keys for name, keys in tree.config_sections("hammer").items()
                 if name in ("rod", "bit", "rock")}
# a segment's keys ([[rod.segments]]), as the parameter tree declares them
_SEGMENT_KEYS = tree.config_sections("hammer")["rod.segments"]


@dataclass(frozen=True)
class RodPiece:
    """A uniform piece of the drill string (shank adapter, rod, coupling) in SI units.

    Parameters
    ----------
    length_m : float
        Length (m), ``> 0``.
    area_m2 : float
        Cross-section (m^2), ``> 0``.
    E_Pa, density_kg_m3 : float
        Young's modulus (Pa) and density (kg/m^3), ``> 0``.
    """

    length_m: float
    area_m2: float
    E_Pa: float
    density_kg_m3: float

    def __post_init__(self) -> None:
        for f in ("length_m", "area_m2", "E_Pa", "density_kg_m3"):
            object.__setattr__(self, f, check_real(f, getattr(self, f), lo=0.0, lo_open=True))

    @property
    def wave_speed_m_s(self) -> float:
        r"""The wave speed :math:`c = \sqrt{E / \rho}` (m/s)."""
        return math.sqrt(self.E_Pa / self.density_kg_m3)

    @property
    def impedance_kg_s(self) -> float:
        """``Z = E A / c`` (kg/s)."""
        return self.E_Pa * self.area_m2 / self.wave_speed_m_s


@dataclass(frozen=True)
class _Scaled:
    """A piston and a hammer's scales as the parameter tree's scales read a drifter
    (:data:`~impactbar.physical.tree.SCALE_STEPS`: ``bar``, ``scales`` and ``omega_rad_s``)."""

    bar: object
    scales: object

    @property
    def omega_rad_s(self) -> float:
        r""":math:`\Omega` (rad/s), the scales'."""
        return self.scales.omega_rad_s


@dataclass(frozen=True)
class DrillString:
    r"""The rod, the bit and the rock of a drill in SI units (theory §4d).

    Parameters
    ----------
    segments : sequence of RodPiece
        From the shank to the bit, at least one.
    rock_k_N_m : float
        Loading stiffness :math:`K` of the bit on the rock (N/m), :math:`> 0`.
    rock_k_u_N_m : float
        Unloading stiffness :math:`K_u \ge K` (N/m).
    bit_mass_kg : float
        Mass of the bit (kg), :math:`\ge 0`; 0 is Lundberg's massless bit.
    feed_N : float
        Static feed force on the shank (N), :math:`\ge 0`.
    cells_per_piston : int, optional
        Puts the simulator's blows on the cell grid with this many cells along the piston
        (:class:`~impactbar.RodRock`'s ``cells_per_piston``, :math:`1 \le n \le 4096`; a numerical setting,
        no physics). Its orbits converge to the exact blows' at second order where every segment is
        whole cells and no re-contact falls inside a step, otherwise at first order and not
        monotonically (theory §4d, §11).
    method : {"auto", "exact", "lattice"}
        The simulator's blows (:class:`~impactbar.RodRock`'s ``method``): exact by default.
    driven_end : {"free", "window"}, optional
        Where a lattice blow under the oil circuit ends (:class:`~impactbar.RodRock`'s
        ``driven_end``, theory §11): where the piston is free for good, or at the law's fixed
        window. Default (``None``): the law's (``"free"``).
    contact_events : {"step", "inside", "slots"}, optional
        Where the lattice's piston-shank separation and re-contact fall
        (:class:`~impactbar.RodRock`'s ``contact_events``, theory §11): at step ends, inside their
        steps, or every event of the blow at its own instant on the slot lattice. Default (``None``):
        the law's (``"step"``).
    """

    segments: tuple
    rock_k_N_m: float
    rock_k_u_N_m: float
    bit_mass_kg: float = 0.0
    feed_N: float = 0.0
    cells_per_piston: int | None = None
    method: str = "auto"
    driven_end: str | None = None
    contact_events: str | None = None

    def __post_init__(self) -> None:
        segs = tuple(self.segments)
        if not segs or not all(isinstance(g, RodPiece) for g in segs):
            raise ValueError(f"rod.segments must be a non-empty sequence of RodPiece; got {self.segments!r}")
        object.__setattr__(self, "segments", segs)
        object.__setattr__(self, "rock_k_N_m", check_real("rock.k", self.rock_k_N_m, lo=0.0, lo_open=True))
        object.__setattr__(self, "rock_k_u_N_m",
                           check_real("rock.k_u", self.rock_k_u_N_m, lo=self.rock_k_N_m))
        object.__setattr__(self, "bit_mass_kg", check_real("bit.mass", self.bit_mass_kg, lo=0.0))
        object.__setattr__(self, "feed_N", check_real("rock.feed", self.feed_N, lo=0.0))
        if self.cells_per_piston is not None:
            object.__setattr__(self, "cells_per_piston",
                               check_int("rock.cells_per_piston", self.cells_per_piston, lo=1, hi=4096))
        if self.method not in ("auto", "exact", "lattice"):
            raise ValueError(f"rock.method must be 'auto', 'exact' or 'lattice'; got {self.method!r}")
        for key, allowed in (("driven_end", DRIVEN_ENDS), ("contact_events", CONTACT_EVENTS)):
            value = getattr(self, key)
            if value is not None and value not in allowed:
                raise ValueError(f"rock.{key} must be {' or '.join(map(repr, allowed))}; got {value!r}")

    def law(self, bar, scales) -> RodRock:
        r"""The dimensionless law for a piston ``bar`` (:class:`~impactbar.physical.Bar`) and the
        hammer's ``scales`` (:class:`~impactbar.physical.Scales`): lengths in piston lengths,
        impedances and wave speeds relative to the piston's, the stiffness
        :math:`k = K / (m \Omega^2)`, the bit's mass in piston masses, the feed in
        :math:`m L \Omega^2` (theory §1, §4d). The piston's impedance is its mean, :math:`m c / L`
        (a stepped piston's rod impedances stay relative to the uniform
        piston of the same mass and length, theory §12)."""
        z_p = bar.mass_kg * bar.wave_speed_m_s / bar.length_m
        segs = [RodSegment(length=g.length_m / bar.length_m, impedance=g.impedance_kg_s / z_p,
                           wave_speed=g.wave_speed_m_s / bar.wave_speed_m_s) for g in self.segments]
        # (the stiffnesses, the bit's mass and the feed by the parameter tree's declared scales, as
        # a continuation's target of rock.k, bit.mass or rock.feed is converted)
        edge = _Scaled(bar, scales)
        rock = BilinearRock(k=tree.convert("stiffness", edge, self.rock_k_N_m),
                            k_u=tree.convert("stiffness", edge, self.rock_k_u_N_m))
        named = {key: value for key, value in (("driven_end", self.driven_end),
                                                ("contact_events", self.contact_events)) if value is not None}
        return RodRock(segments=segs, rock=rock,
                       bit_mass=tree.convert("mass", edge, self.bit_mass_kg),
                       feed=tree.convert("force", edge, self.feed_N),
                       cells_per_piston=self.cells_per_piston, method=self.method, **named)

    def to_dict(self) -> dict:
        """A JSON-ready summary (SI floats)."""
        return {"rod_segments": [{"length_m": g.length_m, "area_m2": g.area_m2, "E_Pa": g.E_Pa,
                                  "density_kg_m3": g.density_kg_m3} for g in self.segments],
                "rock_k_N_m": self.rock_k_N_m, "rock_k_u_N_m": self.rock_k_u_N_m,
                "bit_mass_kg": self.bit_mass_kg, "feed_N": self.feed_N,
                "cells_per_piston": self.cells_per_piston, "method": self.method,
                "driven_end": self.driven_end, "contact_events": self.contact_events}


def rod_from_config(config: dict, *, E: float | None = None, density: float | None = None
                    ) -> tuple[RodPiece, ...]:
    """The drill string's pieces of a configuration's ``[[rod.segments]]``, from the shank to the bit.

    The one reader of a rod's segments: a hammer's configuration (:func:`rock_from_config`) and a
    measurement's spec (:func:`impactbar.measure.read_spec`) both read their ``[rod]`` with it.
    Each segment takes ``length``, ``diameter`` or ``area``, ``E`` and ``density``, each with its
    unit (``"1.2 m"``, ``"32 mm"``, ``"210 GPa"``, ``"7850 kg/m^3"``; the parameter tree's keys
    ``rod.segments.<i>.<key>``).

    Parameters
    ----------
    config : dict
        The configuration (or spec), its ``rod`` table holding the array ``segments``.
    E, density : float, optional
        The Young's modulus (Pa) and density (kg/m^3) of a segment that gives none (a hammer's: its
        piston's); without them every segment must give its own.

    Returns
    -------
    tuple of RodPiece
        In SI, from the shank (the struck end) to the bit.

    Raises
    ------
    ValueError
        A missing, unknown or invalid key, named by its place (``rod.segments[1].diameter``).

    Examples
    --------
    >>> # quantities with their units (read by pint)
    >>> rod = {"rod": {"segments": [{"length": "0.4 m", "diameter": "45 mm"},
    ...                             {"length": "1.2 m", "area": "8 cm^2", "E": "200 GPa"}]}}
    >>> pieces = rod_from_config(rod, E=210e9, density=7850.0)
    >>> [round(p.area_m2 * 1e4, 3) for p in pieces], [p.E_Pa for p in pieces]
    ([15.904, 8.0], [210000000000.0, 200000000000.0])
    """
    _section(config, "rod", ROCK_SECTIONS["rod"])
    raw = config.get("rod", {}).get("segments")
    if not isinstance(raw, list) or not raw:
        raise ValueError("rod.segments must be a non-empty array of tables ([[rod.segments]])")
    pieces = []
    for i, g in enumerate(raw):
        where = f"rod.segments[{i}]"
        if not isinstance(g, dict):
            raise ValueError(f"{where} must be a table; got {g!r}")
        unknown = sorted(set(g) - _SEGMENT_KEYS)
        if unknown:
            raise ValueError(f"unknown key {where}.{unknown[0]}; allowed: {', '.join(sorted(_SEGMENT_KEYS))}")
        if ("diameter" in g) == ("area" in g):
            raise ValueError(f"give exactly one of {where}.diameter and {where}.area")
        for key, default in (("length", None), ("E", E), ("density", density)):
            if key not in g and default is None:
                raise ValueError(f"missing key {where}.{key}")

        def given(key, i=i, g=g, where=where):  # (positive, in the tree's unit, named)
            return _positive(f"{where}.{key}", tree.read_si(f"rod.segments.{i}.{key}", g[key],
                                                            name=f"{where}.{key}"), g[key])

        length = given("length")
        # (a diameter's sign checked before it is squared: -32 mm was read as the area of +32 mm)
        dia = given("diameter") if "diameter" in g else None
        area = math.pi * dia * dia / 4.0 if dia is not None else given("area")
        e = given("E") if "E" in g else E
        rho = given("density") if "density" in g else density
        pieces.append(RodPiece(length_m=length, area_m2=area, E_Pa=e, density_kg_m3=rho))
    return tuple(pieces)


def rock_from_config(config: dict, bar) -> DrillString | None:
    """The drill string of a configuration's ``[rod]``, ``[bit]`` and ``[rock]`` sections, or None
    when it has no ``[rock]``. ``[[rod.segments]]``: ``length``, ``diameter`` or ``area``, and
    ``E`` and ``density`` (default the piston's); ``[bit]``: ``mass`` (default 0 kg);
    ``[rock]``: ``k``, ``k_u`` (N/m, e.g. ``"250 kN/mm"``), ``feed`` (N, default 0), and the
    simulator's blows' ``method`` and ``cells_per_piston`` (:class:`DrillString`; default exact).

    Raises
    ------
    ValueError
        A missing or invalid key (named), or ``[rod]``/``[bit]`` without ``[rock]``.
    """
    for name, keys in ROCK_SECTIONS.items():
        _section(config, name, keys)
    if "rock" not in config:
        if "rod" in config or "bit" in config:
            raise ValueError("[rod] and [bit] need a [rock] section (rock.k, rock.k_u)")
        return None
    rock, bit = config["rock"], config.get("bit", {})
    pieces = rod_from_config(config, E=bar.E_Pa, density=bar.density_kg_m3)
    for key in ("k", "k_u"):
        if key not in rock:
            raise ValueError(f"missing key rock.{key}")
    k, k_u = tree.read_si("rock.k", rock["k"]), tree.read_si("rock.k_u", rock["k_u"])
    feed = tree.read_si("rock.feed", rock["feed"]) if "feed" in rock else 0.0
    mass = tree.read_si("bit.mass", bit["mass"]) if "mass" in bit else 0.0
    return DrillString(segments=pieces, rock_k_N_m=k, rock_k_u_N_m=k_u, bit_mass_kg=mass, feed_N=feed,
                       cells_per_piston=rock.get("cells_per_piston"), method=rock.get("method", "auto"),
                       driven_end=rock.get("driven_end"), contact_events=rock.get("contact_events"))


def rock_blows(hammer, trajectory) -> dict:
    """Per-blow outputs in SI of a simulation under the rod-rock law (theory §4d).

    Parameters
    ----------
    hammer : Hammer
        With a :class:`DrillString` (``hammer.drill``).
    trajectory : Trajectory
        Its dimensionless run (``SimulationResult.trajectory``).

    Returns
    -------
    dict of numpy.ndarray, shape (n,) each
        ``work_on_rock_J`` (J), split as ``rock_dissipated_J`` (taken for good) and
        ``rock_stored_J`` (the rock's elastic energy when the blow's window ends, J),
        ``penetration_mm`` (the permanent penetration of each blow, mm), ``efficiency`` and
        ``efficiency_with_rebound`` (work on rock over the energy available to the blow, without and
        with the piston's rebound energy credited), and ``drilling_rate_m_min`` (penetration per
        blow times the hammer's blow frequency ``f / k``, m/min).
    """
    sc = hammer.scales
    energy_J = sc.force_N * sc.length_m
    blows = trajectory.impacts
    pen = np.array([b.permanent_penetration for b in blows], dtype=float) * sc.length_m
    return {
        "work_on_rock_J": np.array([b.work_on_rock for b in blows], dtype=float) * energy_J,
        "rock_dissipated_J": np.array([b.rock_dissipated for b in blows], dtype=float) * energy_J,
        "rock_stored_J": np.array([b.rock_stored_energy for b in blows], dtype=float) * energy_J,
        "penetration_mm": pen * 1e3,
        "efficiency": np.array([b.efficiency for b in blows], dtype=float),
        "efficiency_with_rebound": np.array([b.efficiency_with_rebound for b in blows], dtype=float),
        "drilling_rate_m_min": pen * hammer.blow_frequency_Hz * 60.0,
    }


#: the power into the rock, as the output registry declares it (its key: ``rock_power_W``)
_ROCK_POWER = OUTPUTS["rock_power"]


def rock_summary(result, *, blow_fraction: float | None = None) -> dict:
    """Drilling statistics of a :class:`~impactbar.physical.SimulationResult` under the rod-rock law,
    over the blows of the second half of the run (past the start-up), chatter apart, JSON-ready.

    Parameters
    ----------
    result : SimulationResult
        A run of a hammer with a drill string.
    blow_fraction : float, optional
        The threshold between blows and chatter of
        :meth:`~impactbar.physical.SimulationResult.is_blow` (its default when omitted).

    Returns
    -------
    dict
        ``n_blows`` and ``n_chatter`` (the second half's blows and chatter impacts),
        ``blow_frequency_Hz`` (the blows' measured frequency: blows per second between the first and
        the last of them), ``mean_work_on_rock_J`` (J) and ``mean_penetration_mm`` (mm) per blow,
        ``drilling_rate_m_min`` (mean penetration per blow times the measured blow frequency, m/min),
        ``measured_rate_m_min`` (the penetration of every impact between the first and the last blow,
        chatter included, over the time they span, m/min), ``rock_power_W`` (the output
        ``rock_power`` of :mod:`~impactbar.physical.outputs`: the work on rock over that time, W),
        ``mean_efficiency`` and ``mean_efficiency_with_rebound`` of the blows; only
        ``n_blows`` and ``n_chatter`` when fewer than two blows fall in the second half.

    Raises
    ------
    ValueError
        ``blow_fraction`` outside ``(0, 1]``.
    """
    blows = rock_blows(result.hammer, result.trajectory)
    t = result.impact_times_s
    second = t >= 0.5 * result.t_end_s
    blow = result.is_blow() if blow_fraction is None else result.is_blow(blow_fraction)
    late = blow & second
    out = {"n_blows": int(np.count_nonzero(late)), "n_chatter": int(np.count_nonzero(~blow & second))}
    if out["n_blows"] < 2:
        return out
    tl = t[late]
    span = float(tl[-1] - tl[0])
    frequency = (tl.size - 1) / span
    inside = second & (t >= tl[0]) & (t < tl[-1])  # the blows but the last, and their chatter
    pen = blows["penetration_mm"][late]
    out.update({
        "blow_frequency_Hz": float(frequency),
        "mean_work_on_rock_J": float(np.mean(blows["work_on_rock_J"][late])),
        "mean_penetration_mm": float(np.mean(pen)),
        "drilling_rate_m_min": float(np.mean(pen) * 1e-3 * frequency * 60.0),
        "measured_rate_m_min": float(np.sum(blows["penetration_mm"][inside]) * 1e-3 / span * 60.0),
        _ROCK_POWER.key: float(np.sum(blows["work_on_rock_J"][inside]) / span),  # (J/s: W, its unit)
        "mean_efficiency": float(np.mean(blows["efficiency"][late])),
        "mean_efficiency_with_rebound": float(np.mean(blows["efficiency_with_rebound"][late])),
    })
    return out


def rock_orbit_figures(orbit, hammer) -> dict:
    """The SI figures of a periodic orbit under the rod-rock law (theory §4d), per blow (the first
    of the orbit): the fields of :class:`~impactbar.physical.PhysicalOrbit` that
    :func:`~impactbar.physical.orbits` fills from the blow instead of from a transmitted wave.

    Returns
    -------
    dict
        ``rod_energy_J`` (the energy the piston gave the rod and rock, J), ``peak_rod_stress_Pa``
        (the peak of the incident wave, Pa: the largest shank force over the first segment's area
        before the rock's first reflection is back at the shank,
        :meth:`~impactbar.laws.rodrock.Blow.incident_peak_force`), ``efficiency`` and
        ``efficiency_with_rebound`` (work on rock over the energy available to the blow),
        ``rod_advance_m`` and ``penetration_mm`` (the permanent penetration, m and mm),
        ``work_on_rock_J`` (J) and ``drilling_rate_m_min`` (penetration times the blow frequency
        ``f / k``, m/min).
    """
    sc = hammer.scales
    b = orbit.contacts[0]
    back = 2.0 * sum(g.length_m / g.wave_speed_m_s for g in hammer.drill.segments) / sc.time_s
    pen_m = float(b.permanent_penetration) * sc.length_m
    return {"rod_energy_J": float(b.energy_out) * sc.force_N * sc.length_m,
            "peak_rod_stress_Pa": b.blow.incident_peak_force(back) * sc.force_N
            / hammer.drill.segments[0].area_m2,
            "efficiency": float(b.efficiency), "rod_advance_m": pen_m,
            "work_on_rock_J": float(b.work_on_rock) * sc.force_N * sc.length_m,
            "penetration_mm": pen_m * 1e3,
            "drilling_rate_m_min": pen_m * hammer.blow_frequency_Hz * 60.0,
            "efficiency_with_rebound": float(b.efficiency_with_rebound)}
