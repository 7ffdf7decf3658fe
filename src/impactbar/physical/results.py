"""What a rock-drill designer reads: one-impact orbits and simulations of a hammer, in SI units."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from .._shared import tables as _tables
from .._shared.renamed import renamed_attribute
from .._shared.schema import Field, Schema
from .._shared.validate import check_real
from ..laws.abilities import BlowRecords
from ..orbits import periodic_orbits
from ..orbits.orbit import ORBIT_FIELDS
from ..simulation import InitialState
from ..simulation import simulate as run_simulation
from .bar import TWO_PI
from .display_units import display_unit
from .hammer import Hammer
from .outputs import OUTPUTS


# --------------------------------------------------------------------------------------------
# results in SI
# --------------------------------------------------------------------------------------------
def _orbit_si_fields() -> tuple[Schema, dict]:
    """The orbit's fields in SI, generated from its declared fields (:data:`ORBIT_FIELDS`): each in
    the view ``"si"`` as it is, and each SI column a field declares; with ``name -> (orbit field,
    scale)``, the scale an attribute of :class:`~impactbar.physical.Scales` (``None``: the number
    as it is)."""
    fields, convert = [], {}
    for f in ORBIT_FIELDS:
        if "si" in f.views:
            fields.append(dataclasses.replace(f, views={"dict", "table", "cli"}))
            convert[f.name] = (f.name, None)
        if f.si is not None:
            fields.append(Field(f.si.name, f.si.long_name or f.long_name, f.si.units, f.dtype,
                                views={"dict", "table", "cli", "cli_rock"}, label=f.si.label,
                                fmt=f.si.fmt))
            convert[f.si.name] = (f.name, f.si.scale)
    return Schema(*fields), convert


_ORBIT_SI, _CONVERT = _orbit_si_fields()


def _shown(declared: Field, label: str) -> Field:
    """``declared`` in the CLI's table in its display unit (a stress in Pa as MPa,
    :func:`~impactbar.physical.display_units.display_unit`): headed ``label/<display unit>``, its value
    divided by the scale."""
    factor, unit = display_unit(declared.units)
    return dataclasses.replace(declared, label=f"{label}/{unit}", scale=float(round(1.0 / factor)))


#: The declared fields of :class:`PhysicalOrbit`: the orbit's in SI (generated from
#: :data:`impactbar.orbits.orbit.ORBIT_FIELDS`), then the hammer's figures per blow; a figure that is
#: an output of a drifter (:data:`impactbar.physical.outputs.OUTPUTS`) takes its name, unit and long
#: name from it (:meth:`~impactbar.physical.outputs.Output.column`), its label and format its own
PHYSICAL_ORBIT_FIELDS = _ORBIT_SI + Schema(
    OUTPUTS["impact_energy"].column(views={"dict", "table", "cli"}, label="E/J", fmt=".2f"),
    OUTPUTS["blow_frequency"].column(views={"dict", "table"}),
    OUTPUTS["impact_power"].column(views={"dict", "table", "cli"}, label="P/kW", fmt=".4f"),
    _shown(Field("peak_piston_stress_Pa", "peak compressive stress in the piston at impact", "Pa",
                 views={"dict", "table", "cli"}, fmt=".1f"), "sigma"),
    OUTPUTS["rod_energy"].column(views={"dict", "table", "cli"}, label="E_rod/J", fmt=".2f"),
    _shown(OUTPUTS["peak_rod_stress"].column(views={"dict", "table", "cli"}, fmt=".1f"), "rod"),
    OUTPUTS["efficiency"].column(views={"dict", "table", "cli", "cli_rock"}, label="eff.", fmt=".3f"),
    Field("rod_advance_m", "advance of the rod end per blow", "m", views={"dict", "table"}),
    OUTPUTS["work_on_rock"].column(views={"dict", "cli_rock"}, label="rock/J", fmt=".2f"),
    OUTPUTS["penetration"].column(views={"dict", "cli_rock"}, label="pen./mm", fmt=".4f"),
    OUTPUTS["drilling_rate"].column(views={"dict", "cli_rock"}, label="rate m/min", fmt=".4f"),
    Field("efficiency_with_rebound", "work on rock over the available energy less the rebound's",
          views={"dict", "cli_rock"}, label="eff.+reb.", fmt=".3f"),
)


@dataclass(frozen=True)
class PhysicalOrbit:
    r"""A one-impact periodic motion with its engineering figures in SI.

    Its fields are declared once, in :data:`PHYSICAL_ORBIT_FIELDS` (what :meth:`to_dict`, the
    tables and the CLI show): the orbit's own in SI, generated from the dimensionless orbit's
    declared fields (a field of :class:`~impactbar.PeriodicOrbit` in the view ``"si"``, or with an
    SI column, appears here with nothing else changed), then the hammer's figures per blow.

    Attributes
    ----------
    orbit : PeriodicOrbit
        The dimensionless orbit (``impactbar.periodic_orbits``).
    scales : Scales
        The hammer's units (what the orbit's fields are converted with).
    phase_rad : float
        Phase :math:`\phi` of the load at impact (rad).
    impact_velocity : float
        Dimensionless impact velocity :math:`u_t(1, 2\pi^-)`.
    impact_velocity_m_s : float
        Impact velocity :math:`v = L \Omega u_t` (m/s).
    admissible, stable : bool
        As in the dimensionless orbit (theory §5, §7).
    max_abs_multiplier : float
        Largest modulus of the Floquet multipliers.
    impact_energy_J : float
        Energy per blow :math:`m v^2 / 2` (J): the kinetic energy of the piston moving as a rigid body
        at the struck end's velocity (the output ``impact_energy``). This is the standard figure of
        merit of rock drills; it ignores the elastic vibration energy of the piston
        (``blow_energy_J`` the name it had: a ``DeprecationWarning``).
    blow_frequency_Hz : float
        Blows per second :math:`\Omega / 2 \pi` (Hz).
    impact_power_kW : float
        Impact power, energy per blow times blow frequency (kW; the output ``impact_power``).
        ``power_W``, the name it had, gives it in W, :math:`E f_b` (a ``DeprecationWarning``).
    peak_piston_stress_Pa : float
        Peak compressive stress in the piston at impact (Pa), see :meth:`Hammer.peak_stress_Pa`
        (``peak_stress_Pa`` the name it had: a ``DeprecationWarning``).
    rod_energy_J : float
        Energy carried into the rod by the transmitted stress wave per blow (J), :math:`\int F^2 / Z_s \, dt`.
        Under the wave law (theory §4b) from the contact solved by characteristics, the drive
        included; under eq. 10 :math:`(1 - R^2)` times the piston's kinetic energy at impact (what
        eq. 10 removes from it).
    peak_rod_stress_Pa : float
        Peak compressive stress of the transmitted wave in the rod (Pa), :math:`F_\mathrm{max} / A_s`; under
        eq. 10 the plateau of a rigid-body piston at the impact velocity, ``rho c v (1 - R)/2`` (of
        a stepped piston: the first step of its staircase, the struck segment's).
    efficiency : float
        ``rod_energy_J`` over the energy available to the blow: the piston's kinetic plus strain
        energy at impact plus the drive's work during the contact (Lundberg's transfer efficiency,
        with the drive); at most 1.
    rod_advance_m : float
        Advance of the rod end per blow (m), impulse over ``Z_s`` (the stop's impedance, from
        ``R`` and the struck end's).
    work_on_rock_J, penetration_mm, drilling_rate_m_min, efficiency_with_rebound : float
        Under the rod-rock law (a ``[rock]`` section, theory §4d) the blow's work on rock (J),
        permanent penetration (mm), the drilling rate at the blow frequency (m/min) and the
        efficiency with the rebound credited; there ``rod_energy_J`` is the energy the piston gave
        rod and rock, ``efficiency`` work on rock over the energy available to the blow,
        ``rod_advance_m`` the penetration (``impactbar.physical.rock.rock_orbit_figures``).
        NaN under the other laws.
    """

    orbit: object
    scales: object = field(repr=False)
    impact_energy_J: float
    blow_frequency_Hz: float
    impact_power_kW: float
    peak_piston_stress_Pa: float
    rod_energy_J: float
    peak_rod_stress_Pa: float
    efficiency: float
    rod_advance_m: float
    work_on_rock_J: float = math.nan
    penetration_mm: float = math.nan
    drilling_rate_m_min: float = math.nan
    efficiency_with_rebound: float = math.nan

    #: the declared fields (:data:`PHYSICAL_ORBIT_FIELDS`)
    fields: ClassVar[Schema] = PHYSICAL_ORBIT_FIELDS

    peak_stress_Pa = renamed_attribute("peak_stress_Pa", "peak_piston_stress_Pa")
    blow_energy_J = renamed_attribute("blow_energy_J", "impact_energy_J")
    power_W = renamed_attribute("power_W", "impact_power_kW",
                                lambda o: o.impact_energy_J * o.blow_frequency_Hz)  # (W, as it was)

    def __getattr__(self, name: str):
        """The orbit's fields in SI: its own value, or converted with the hammer's scales."""
        if name not in _CONVERT:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        source, scale = _CONVERT[name]
        value = getattr(self.orbit, source)
        return value if scale is None else float(value) * getattr(self.scales, scale)

    @classmethod
    def from_orbit(cls, orbit, hammer: Hammer) -> PhysicalOrbit:
        """Convert a dimensionless ``PeriodicOrbit`` of ``hammer``'s model."""
        v = float(orbit.impact_velocity) * hammer.scales.velocity_m_s
        energy = 0.5 * hammer.mass_kg * v * v
        fb = hammer.blow_frequency_Hz
        rod = _rod_figures(orbit, hammer, v)
        return cls(orbit=orbit, scales=hammer.scales, impact_energy_J=energy, blow_frequency_Hz=fb,
                   impact_power_kW=energy * fb / 1e3,
                   peak_piston_stress_Pa=float(hammer.peak_stress_Pa(v)), **rod)

    def to_dict(self) -> dict:
        """JSON-ready figures (without the dimensionless orbit object): the fields of
        :data:`PHYSICAL_ORBIT_FIELDS`."""
        return self.fields.record(self)

def _rod_figures(orbit, hammer: Hammer, v_m_s: float) -> dict:
    """The transmitted wave's figures of one orbit in SI (see :class:`PhysicalOrbit`)."""
    sc = hammer.scales
    R = hammer.R
    energy_J = sc.force_N * sc.length_m  # the energy unit m L^2 Omega^2
    rod_area_ratio = (1.0 - R) / (1.0 + R)  # A / A_s
    b = hammer.bar
    if getattr(hammer, "drill", None) is not None:  # the rod-rock law: the blow's drilling figures
        from .rock import rock_orbit_figures

        return rock_orbit_figures(orbit, hammer)
    w = orbit.impact
    if w is not None:  # the wave law: the contact solved by characteristics
        return {"rod_energy_J": float(w.rod_energy * energy_J),
                "peak_rod_stress_Pa": float(w.peak_force * sc.force_N * rod_area_ratio / b.area_m2),
                "efficiency": float(w.efficiency), "rod_advance_m": float(w.advance * sc.length_m)}
    # the paper's law (eq. 10) reverses the whole velocity field times R: the rod takes (1 - R^2) of the
    # kinetic energy, E = 1/2 sum kappa_n (q_n'^2 + w_n^2 q_n^2) with a stepped piston's weights (theory §12)
    model = orbit.model  # (the hammer's, already built: a stepped piston's modes are not solved again)
    M = hammer.n_modes + 1
    q, v = orbit.state_before_impact[:M], orbit.state_before_impact[M:]
    if model.piston is None:
        wn = hammer.s * np.pi * np.arange(1, M)
        kinetic = 0.5 * v[0] ** 2 + float(np.sum(v[1:] ** 2))
        strain = float(np.sum((wn * q[1:]) ** 2))
        end_mass = 1.0
    else:
        kappa, w = model.drive_weights, model.frequencies
        kinetic = 0.5 * float(kappa @ (v * v))
        strain = 0.5 * float(kappa @ ((w * q) ** 2))
        end_mass = float(model.piston.mass_per_length[-1])  # the struck end's impedance, the mean's 1
    rod = (1.0 - R * R) * kinetic
    # the stop's impulse (1 + R) q_0' pushes a long rod of impedance Z_e (1 + R)/(1 - R) by impulse / Z
    return {"rod_energy_J": float(rod * energy_J),
            "peak_rod_stress_Pa": float(b.density_kg_m3 * b.wave_speed_m_s * v_m_s * 0.5 * (1.0 - R)),
            "efficiency": float(rod / (kinetic + strain)) if kinetic + strain > 0 else float("nan"),
            "rod_advance_m": float((1.0 - R) * v[0] / (hammer.s * end_mass) * sc.length_m)}


#: the columns of :meth:`PhysicalOrbitList.to_dataframe`: the fields in the view ``"table"``
PHYSICAL_ORBIT_COLUMNS = PHYSICAL_ORBIT_FIELDS.select("table")


class PhysicalOrbitList(list):
    """The list of :class:`PhysicalOrbit` that :func:`orbits` returns: a plain ``list`` with
    ``to_dataframe()`` and ``to_xarray()`` (one row per orbit, SI units in the column names and in
    each column's ``units``)."""

    __slots__ = ()

    def to_dataframe(self):
        """One row per orbit, the columns of :data:`PHYSICAL_ORBIT_COLUMNS`.

        Returns
        -------
        pandas.DataFrame
            Index ``orbit``; ``attrs["columns"]`` gives each column's ``long_name`` and ``units``.
        """
        return PHYSICAL_ORBIT_COLUMNS.frame(self, index="orbit",
                                            index_meta=("orbit number, in order of phase", "1"))

    def to_xarray(self):
        """:meth:`to_dataframe` as an ``xarray.Dataset`` along ``orbit``.

        Raises
        ------
        ModuleNotFoundError
            xarray is not installed (extra ``data``).
        """
        return _tables.to_xarray(self.to_dataframe())


def orbits(hammer: Hammer) -> PhysicalOrbitList:
    """The one-impact periodic motions of ``hammer`` with their SI figures.

    Calls ``periodic_orbits(hammer.model, hammer.load)`` and converts each orbit; warns
    (:class:`ImpactDurationWarning`) when impacts are not short against the period.

    Returns
    -------
    PhysicalOrbitList
        A ``list`` of :class:`PhysicalOrbit`, in order of phase; ``.to_dataframe()`` makes it a
        table.
    """
    hammer.check_short_impacts()
    found = periodic_orbits(hammer.model, hammer.load)
    return PhysicalOrbitList(PhysicalOrbit.from_orbit(o, hammer) for o in found)


#: default threshold of :meth:`SimulationResult.is_blow`: a blow's impact velocity is at least this
#: fraction of the run's largest
BLOW_FRACTION = 0.25
#: default relative tolerance of the settled-motion verdict of :meth:`SimulationResult.blow_statistics`
SETTLE_TOLERANCE = 0.01


@dataclass(frozen=True)
class BlowStatistics:
    """The blows of a simulated hammer, chatter apart (:meth:`SimulationResult.blow_statistics`).

    Means are over the blows of the run's second half (past the start-up); a figure that cannot be
    had (fewer than two blows, or a law without a rod wave) is NaN.

    Attributes
    ----------
    blow_fraction, settle_tolerance : float
        The thresholds used (see :meth:`SimulationResult.blow_statistics`).
    n_impacts, n_blows, n_chatter : int
        Impacts of the whole run, and how many of them are blows and chatter.
    n_blows_second_half, n_chatter_second_half : int
        The same over the second half.
    mean_impact_velocity_m_s, impact_velocity_std_m_s : float
        Mean and standard deviation of the blows' impact velocities (m/s).
    mean_impact_energy_J : float
        Mean kinetic energy at impact per blow :math:`m v^2 / 2` (J; the output ``impact_energy``;
        ``mean_blow_energy_J`` the name it had: a ``DeprecationWarning``).
    mean_blow_interval_s, blow_interval_std_s : float
        Mean and standard deviation of the time between blows (s).
    mean_impact_power_kW : float
        Impact power: the blows' kinetic energy at impact per unit time over the blows of the second
        half (kW; the output ``impact_power``). ``mean_power_W``, the name it had, gives it in W (a
        ``DeprecationWarning``).
    mean_rod_energy_J, mean_peak_rod_stress_Pa, mean_efficiency : float
        Wave law only: the blows' mean rod energy (J), peak rod stress (Pa) and transfer efficiency
        (each <= 1, see :class:`PhysicalOrbit`).
    blows_per_cycle : int
        ``m`` when the blows repeat a cycle of ``m`` blows, 0 when the motion has not settled.
    message : str
        The verdict in words.
    """

    blow_fraction: float
    settle_tolerance: float
    n_impacts: int
    n_blows: int
    n_chatter: int
    n_blows_second_half: int
    n_chatter_second_half: int
    mean_impact_velocity_m_s: float
    impact_velocity_std_m_s: float
    mean_impact_energy_J: float
    mean_blow_interval_s: float
    blow_interval_std_s: float
    mean_impact_power_kW: float
    mean_rod_energy_J: float
    mean_peak_rod_stress_Pa: float
    mean_efficiency: float
    blows_per_cycle: int
    message: str

    mean_blow_energy_J = renamed_attribute("mean_blow_energy_J", "mean_impact_energy_J")
    mean_power_W = renamed_attribute("mean_power_W", "mean_impact_power_kW",
                                     lambda s: s.mean_impact_power_kW * 1e3)  # (W, as it was)

    @property
    def settled(self) -> bool:
        """Whether the blows repeat a cycle (``blows_per_cycle > 0``)."""
        return self.blows_per_cycle > 0

    def to_dict(self) -> dict:
        """The fields and ``settled``, JSON-ready (NaN for the figures that cannot be had)."""
        return {**dataclasses.asdict(self), "settled": self.settled}


#: differences of blows below this fraction (of the largest impact velocity, of the mean interval)
#: are the run's rounding and its last settling, not a difference between the blows of a cycle
CYCLE_FLOOR = 1e-6
#: a cycle of ``m`` blows is the motion's period only where its blows repeat to within this factor
#: of how well the cycles of ``2 m, 3 m, ...`` blows repeat: a period-2 motion's two blows differ by
#: far more than its cycles do, however close the two blows are
CYCLE_SEPARATION = 10.0


def _cycle_length(t: np.ndarray, v: np.ndarray, tol: float) -> int:
    """The period, in blows, of the last blows: the smallest ``m`` whose last ``m`` blows repeat the
    ``m`` before them (impact velocities to ``tol`` of the largest, intervals to ``tol`` of the
    mean), and repeat them nearly as well as every cycle of ``k m`` blows does (within
    :data:`CYCLE_SEPARATION`, differences below :data:`CYCLE_FLOOR` counted as equal); 0 when none
    does, or when that cycle still drifts by more than ``tol`` (:func:`_cycle_drift`)."""
    if t.size < 3:
        return 0
    dt = np.diff(t)
    vmax, dmean = float(np.max(np.abs(v))), float(np.mean(dt))
    top = dt.size // 2
    err = np.full(top + 1, np.inf)
    for m in range(1, top + 1):
        err[m] = max(float(np.max(np.abs(v[-m:] - v[-2 * m:-m]))) / vmax,
                     float(np.max(np.abs(dt[-m:] - dt[-2 * m:-m]))) / dmean)
    for m in range(1, top + 1):
        if err[m] > tol:
            continue
        multiples = err[2 * m::m]
        if multiples.size == 0 or err[m] <= CYCLE_SEPARATION * max(float(np.min(multiples)), CYCLE_FLOOR):
            return m if max(_cycle_drift(v / vmax, m), _cycle_drift(dt / dmean, m)) <= tol else 0
    return 0


def _cycle_drift(x: np.ndarray, m: int) -> float:
    """How far a sequence's cycles of ``m`` still move, extrapolated: its
    last cycle's step ``s`` (the largest change of a member against the cycle before) and the one
    before, ``s0``, give the ratio ``r = s / s0`` of a geometric approach, and the steps still to
    come add up to ``s r / (1 - r)`` (infinite for ``r >= 1``: a drift that does not slow). 0 where
    the step is below :data:`CYCLE_FLOOR` or the sequence holds fewer than three cycles (source:
    docs/physical.md, the settled motion of ``impactbar simulate``).

    A drifter's blows from rest rise with its supply pressure by some 0.2 % a blow after 40 blows,
    each step 0.94 of the one before: within 1 % of the blow before, 3 % short of where they head."""
    if x.size < 3 * m + 1:
        return 0.0
    s = float(np.max(np.abs(x[-m:] - x[-2 * m:-m])))
    s0 = float(np.max(np.abs(x[-2 * m:-m] - x[-3 * m:-2 * m])))
    if s <= CYCLE_FLOOR:
        return 0.0
    return s * (s / s0) / (1.0 - s / s0) if s < s0 else math.inf


def _chatter_after(blow: np.ndarray, last: int) -> list[int]:
    """The chatter impacts after each of the ``last`` blows of a run (up to the next blow, or the
    run's end)."""
    where = np.flatnonzero(blow)[-last:]
    ends = np.append(where[1:], blow.size)
    return [int(b - a - 1) for a, b in zip(where, ends, strict=True)]


def _settled_message(m: int, v: np.ndarray, chatter: list[int]) -> str:
    """The verdict of a settled motion: its blows per cycle, each blow's impact velocity and the
    chatter after each."""
    if m == 1:
        after = "" if chatter[0] == 0 else (f", each followed by {chatter[0]} chatter "
                                            f"impact{'s' if chatter[0] > 1 else ''}")
        return "the motion has settled: one blow per cycle" + after
    speeds = ", ".join(f"{x:.4g}" for x in v[-m:])
    after = "" if not any(chatter) else (" followed by " + ", ".join(str(c) for c in chatter)
                                          + " chatter impacts")
    return (f"the motion has settled into a cycle of {m} different blows ({speeds} m/s{after}); the "
            f"means are over the cycle")


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
    impact_energies_J : numpy.ndarray, shape (n,)
        The kinetic energy at impact :math:`m v^2 / 2` of each impact (J; the output
        ``impact_energy``; ``blow_energies_J`` the name it had: a ``DeprecationWarning``).
    rod_energies_J, peak_rod_stresses_Pa, efficiencies : numpy.ndarray, shape (n,)
        Under the wave law (theory §4b) the energy and the peak stress of the wave each blow sends
        into the rod, and the transfer efficiency (see :class:`PhysicalOrbit`); NaN under eq. 10.

    Notes
    -----
    Not every impact is a blow: after a blow the piston may rebound and chatter on the rod with
    impacts far slower than the blows. :meth:`is_blow` separates them and :meth:`blow_statistics`
    reports the blows alone, chatter counted apart, with a verdict on whether the motion has
    settled.
    """

    hammer: Hammer
    trajectory: object
    t_end_s: float
    impact_times_s: np.ndarray
    impact_velocities_m_s: np.ndarray
    impact_energies_J: np.ndarray
    rod_energies_J: np.ndarray = None
    peak_rod_stresses_Pa: np.ndarray = None
    efficiencies: np.ndarray = None

    blow_energies_J = renamed_attribute("blow_energies_J", "impact_energies_J")

    def force_wave(self, i: int, t_s) -> np.ndarray:
        """Force (N) of the wave sent into the rod by impact ``i`` (wave law), at times ``t_s`` (s)
        counted from the start of that contact; 0 outside its window ``2 L / c``.

        Raises
        ------
        ValueError
            Under eq. 10 (an instant impact has no force history), or for a bad index.
        """
        model = self.hammer.model
        impacts = self.trajectory.impacts if model.law.ability(BlowRecords) is not None else ()
        if not impacts:
            raise ValueError("force waves need the wave impact law (Hammer(impact='wave'))")
        if not -len(impacts) <= i < len(impacts):
            raise ValueError(f"i must index one of the {len(impacts)} impacts; got {i}")
        sc = self.hammer.scales
        w = impacts[i]
        t = np.asarray(t_s, dtype=float) / sc.time_s
        inside = (t >= 0.0) & (t <= w.duration)
        return np.where(inside, w.force(np.clip(t, 0.0, w.duration)), 0.0) * sc.force_N

    def is_blow(self, blow_fraction: float = BLOW_FRACTION) -> np.ndarray:
        """Which impacts are blows rather than chatter.

        Parameters
        ----------
        blow_fraction : float, optional
            An impact is a blow when its impact velocity is at least this fraction of the largest
            impact velocity of the run, in ``(0, 1]``; the default 0.25 keeps the impacts with at
            least 1/16 of the hardest blow's energy.

        Returns
        -------
        numpy.ndarray of bool, shape (n,)
            One flag per impact; the others are chatter.
        """
        blow_fraction = check_real("blow_fraction", blow_fraction, lo=0.0, hi=1.0, lo_open=True)
        v = self.impact_velocities_m_s
        if v.size == 0:
            return np.zeros(0, dtype=bool)
        return v >= blow_fraction * float(np.max(v)) if np.max(v) > 0 else np.zeros(v.size, bool)

    def blow_statistics(self, *, blow_fraction: float = BLOW_FRACTION,
                        settle_tolerance: float = SETTLE_TOLERANCE) -> BlowStatistics:
        """Per-blow figures over the blows of the run's second half, and whether the motion has
        settled.

        Parameters
        ----------
        blow_fraction : float, optional
            Threshold between blows and chatter, see :meth:`is_blow`.
        settle_tolerance : float, optional
            The motion has settled when the last blows repeat a cycle of ``m`` blows (``m = 1, 2,
            ...``, two whole cycles inside the second half): each blow's impact velocity within
            ``settle_tolerance`` times the largest, and each interval within ``settle_tolerance``
            times the mean interval, of the blow one cycle earlier, and the cycle's steps still to
            come, extrapolated from its last two, within it too (a motion still drifting toward its
            cycle, the supply pressure of an oil circuit charging, has not settled). In ``(0, 1)``.

        Returns
        -------
        BlowStatistics
        """
        settle_tolerance = check_real("settle_tolerance", settle_tolerance, lo=0.0, hi=1.0,
                                      lo_open=True, hi_open=True)
        blow = self.is_blow(blow_fraction)
        t = self.impact_times_s
        late = blow & (t >= 0.5 * self.t_end_s)
        nan = float("nan")
        stats = {"blow_fraction": blow_fraction, "settle_tolerance": settle_tolerance,
                 "n_impacts": int(t.size), "n_blows": int(np.count_nonzero(blow)),
                 "n_chatter": int(t.size - np.count_nonzero(blow)),
                 "n_blows_second_half": int(np.count_nonzero(late)),
                 "n_chatter_second_half": int(np.count_nonzero(~blow & (t >= 0.5 * self.t_end_s)))}
        tl, vl, el = t[late], self.impact_velocities_m_s[late], self.impact_energies_J[late]
        if tl.size >= 2:
            dt = np.diff(tl)
            stats.update(mean_blow_interval_s=float(np.mean(dt)), blow_interval_std_s=float(np.std(dt)),
                         mean_impact_power_kW=float(np.sum(el[1:]) / (tl[-1] - tl[0])) / 1e3)
        if tl.size:
            stats.update(mean_impact_velocity_m_s=float(np.mean(vl)),
                         impact_velocity_std_m_s=float(np.std(vl)),
                         mean_impact_energy_J=float(np.mean(el)))
        rod = self.rod_energies_J
        if tl.size and rod is not None and np.all(np.isfinite(rod[late])):  # the wave law
            stats.update(mean_rod_energy_J=float(np.mean(rod[late])),
                         mean_peak_rod_stress_Pa=float(np.mean(self.peak_rod_stresses_Pa[late])),
                         mean_efficiency=float(np.mean(self.efficiencies[late])))
        m = _cycle_length(tl, vl, settle_tolerance)
        stats["blows_per_cycle"] = m
        if m == 0:
            if tl.size >= 2:
                cv_t = stats["blow_interval_std_s"] / stats["mean_blow_interval_s"]
                cv_v = stats["impact_velocity_std_m_s"] / stats["mean_impact_velocity_m_s"]
                spread = (f"the intervals between blows vary by {cv_t:.0%} and their impact "
                          f"velocities by {cv_v:.0%} (std over mean)")
            else:
                spread = f"there are only {tl.size} blow(s)"
            stats["message"] = (f"the motion has not settled: over the second half's {tl.size} blows "
                                f"{spread}, and no cycle of blows repeats to {settle_tolerance:.0%} "
                                f"without drifting further; "
                                f"run longer, or the motion is not periodic")
        else:
            stats["message"] = _settled_message(m, vl, _chatter_after(blow, m))
        defaults = {f.name: nan for f in dataclasses.fields(BlowStatistics)}
        return BlowStatistics(**{**defaults, **stats})

    def to_dataframe(self):
        """The impacts as a table, in SI units.

        Returns
        -------
        pandas.DataFrame
            Index ``impact`` (0, 1, ...), columns ``time_s`` (s), ``impact_velocity_m_s`` (m/s) and
            ``impact_energy_J`` (J; the output ``impact_energy``, its key and long name the
            registry's, :mod:`~impactbar.physical.outputs`), and under the wave law ``rod_energy_J`` (J),
            ``peak_rod_stress_Pa`` (Pa) and ``efficiency``; ``attrs`` holds the hammer's name,
            ``t_end_s`` and each column's ``long_name`` and ``units``.
        """
        energy = OUTPUTS["impact_energy"]
        cols = {"impact": np.arange(self.impact_times_s.size), "time_s": self.impact_times_s,
                "impact_velocity_m_s": self.impact_velocities_m_s, energy.key: self.impact_energies_J}
        meta = {"impact": ("impact number", "1"), "time_s": ("time of the impact", "s"),
                "impact_velocity_m_s": ("arrival velocity of the struck end", "m/s"),
                energy.key: (energy.long_name, energy.unit)}
        if self.rod_energies_J is not None and np.any(np.isfinite(self.rod_energies_J)):  # wave law
            cols.update(rod_energy_J=self.rod_energies_J, peak_rod_stress_Pa=self.peak_rod_stresses_Pa,
                        efficiency=self.efficiencies)
            meta.update(rod_energy_J=("energy carried into the rod (theory §4b)", "J"),
                        peak_rod_stress_Pa=("peak compressive stress of the transmitted wave", "Pa"),
                        efficiency=("rod energy over the energy available to the blow", "1"))
        return _tables.frame(cols, meta, index="impact",
                             attrs={"hammer": self.hammer.name or "", "t_end_s": self.t_end_s})

    def to_xarray(self):
        """:meth:`to_dataframe` as an ``xarray.Dataset`` along ``impact``, with ``long_name`` and
        ``units`` on every variable.

        Raises
        ------
        ModuleNotFoundError
            xarray is not installed (extra ``data``).
        """
        return _tables.to_xarray(self.to_dataframe())

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
             max_impacts: int | None = None, progress=None) -> SimulationResult:
    r"""Simulate ``hammer`` from rest, ``gap_m`` off the stop, over ``periods`` impact periods.

    Parameters
    ----------
    hammer : Hammer
    periods : float, optional
        Length of the run in impact periods ``1 / f_b`` (``k`` force cycles each), ``> 0``.
    gap_m : float, optional
        Initial distance of the struck end from the stop (m), :math:`\ge 0`; the piston starts at rest.
    max_impacts : int, optional
        Passed to ``impactbar.simulate``.
    progress : callable, optional
        Passed to ``impactbar.simulate``: called as ``progress(fraction)`` with the fraction of
        the run done (e.g. to drive a progress bar).

    Returns
    -------
    SimulationResult

    Raises
    ------
    """
    periods = check_real("periods", periods, lo=0.0, lo_open=True)
    gap_m = check_real("gap", gap_m, lo=0.0)
    hammer.check_short_impacts()
    sc = hammer.scales
    t_end = TWO_PI * periods
    traj = run_simulation(hammer.model, hammer.load,
                          InitialState.rigid(end_displacement=-gap_m / sc.length_m, velocity=0.0), t_end,
                          max_impacts=max_impacts, **({} if progress is None else {"progress": progress}))
    v = np.asarray(traj.impact_velocities, dtype=float) * sc.velocity_m_s
    # the records of a law with a contact (the wave law's rod outputs); an instant impact has none
    # (the rod-rock law's per-blow outputs: impactbar.physical.rock.rock_blows)
    model = hammer.model
    impacts = traj.impacts if model.law.ability(BlowRecords) is not None and hammer.drill is None else ()
    rod = np.full(v.size, np.nan)
    stress = np.full(v.size, np.nan)
    eff = np.full(v.size, np.nan)
    for j, w in enumerate(impacts):  # the wave law: each contact solved by characteristics
        rod[j] = w.rod_energy * sc.force_N * sc.length_m
        stress[j] = w.peak_force * sc.force_N * (1.0 - hammer.R) / ((1.0 + hammer.R) * hammer.bar.area_m2)
        eff[j] = w.efficiency
    return SimulationResult(
        hammer=hammer, trajectory=traj, t_end_s=t_end * sc.time_s,
        impact_times_s=np.asarray(traj.impact_times, dtype=float) * sc.time_s,
        impact_velocities_m_s=v, impact_energies_J=0.5 * hammer.mass_kg * v * v,
        rod_energies_J=rod, peak_rod_stresses_Pa=stress, efficiencies=eff)


