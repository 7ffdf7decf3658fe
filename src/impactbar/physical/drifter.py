r"""A hydraulic drifter in SI units: a piston whose valve switches on its position (theory §10).

The driving force is :math:`+p A_s` (stroke, toward the stop) or :math:`-p A_r` (return), with
:math:`p` the supply pressure and :math:`A_s`, :math:`A_r` the piston's net areas under pressure in
each state; the valve goes to stroke when the piston, on its way out, passes the switch position
:math:`x_1` (measured from the stop), to return at each impact, each switch a valve delay
:math:`\tau` after its trigger. The machine is
autonomous: the blow frequency is an output.

Scales (eq. 2 with the stroke force as the force scale): :math:`\Omega = \sqrt{p A_s / (m L)}` so
that the dimensionless stroke force is 1; ``ret`` :math:`= A_r / A_s`, ``switch_out``
:math:`= x_1 / L`, ``delay`` :math:`= \Omega \tau`, :math:`s = c / (L \Omega)`,
:math:`d = D / (M \Omega)`. Outputs: blow frequency :math:`n \Omega / T` (Hz, :math:`n` impacts a
period :math:`T`), impact velocity :math:`L \Omega v` (m/s), impact energy :math:`m L^2 \Omega^2 e`
(J, :math:`e` the dimensionless kinetic energy of the bar arriving at the stop), impact power
(energy times blow frequency, kW).

Configuration keys (a nested ``dict`` or TOML, as :meth:`Drifter.from_config` reads them)::

    name = "..."                         # optional
    [bar]     E, density, length, diameter | area      # the piston
    [stop]    restitution | area
    [damping] coefficient                 # optional (N s/m, the whole piston)
    [valve]   supply_pressure, stroke_area, return_area, switch_out, delay (optional, default 0 ms)
    [model]   n_modes                     # optional, default 0 (a rigid piston)
    [[rod.segments]], [bit], [rock]       # optional: the drill string and the rock (theory §4d), as
                                          # for a hammer (impactbar.physical.rock); [stop] not needed

With a ``[rock]`` the piston strikes the drill string and the orbit's blow gives the work on rock
(J), the penetration per blow (mm), the efficiencies and the drilling rate (m/min: the penetration
times the blow frequency).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .._shared.renamed import renamed_attribute
from .._shared.validate import check_int, check_real
from . import tree
from ._circuit_checks import shown
from .bar import Bar, SteppedBar, check_piston, piston_from_units
from .config import _section
from .rock import ROCK_SECTIONS, DrillString, rock_from_config

__all__ = ["Drifter", "DrifterOrbit", "DRIFTER_PRESETS", "drifter_preset", "operating_point"]

# the sections and keys of its config, and the required ones, as the parameter tree declares them
# (the drill string's sections, rock.ROCK_SECTIONS, checked by its own reader)
_KEYS = {name: keys for name, keys in tree.config_sections("drifter").items() if name not in ROCK_SECTIONS
         and name != "rod.segments"}
_REQUIRED = {name: tuple(f.name for f in tree.MACHINES["drifter"].values()
                         if f.section == name and f.required) for name in ("bar", "valve")}


def _config_sections(config: dict, keys: dict, required: dict) -> dict:
    """A drifter's config checked section by section: a dict of sections (each a dict, ``{}`` where
    left out), unknown sections and keys and missing ``required`` keys refused (:class:`ValueError`,
    naming them); the rock's sections (:data:`~impactbar.physical.rock.ROCK_SECTIONS`) allowed."""
    if not isinstance(config, dict):
        raise ValueError(f"config must be a dict; got {type(config).__name__}")
    extra = sorted(set(config) - set(keys) - set(ROCK_SECTIONS) - {"name"})
    if extra:
        raise ValueError(f"unknown section [{extra[0]}]; allowed: "
                         f"{', '.join(sorted((*keys, *ROCK_SECTIONS)))}")
    sec = {name: _section(config, name, allowed) for name, allowed in keys.items()}
    for name, names in required.items():
        for key in names:
            if key not in sec[name]:
                raise ValueError(f"missing key {name}.{key}")
    return sec


def _piston_drill_restitution(config: dict, sec: dict, *, stop_area_check: bool = False):
    """A drifter's piston (``[bar]``), its drill string (``[rod]``, ``[bit]``, ``[rock]``, or
    ``None``) and the restitution of its stop (``[stop]``: ``restitution`` or ``area``, 0 where the
    drill string replaces the stop), from the sections ``sec`` of ``config``. With
    ``stop_area_check`` a stop area smaller than the piston's is refused here, naming the key (else
    the restitution's own range check refuses it)."""
    b, st = sec["bar"], sec["stop"]
    bar = piston_from_units(b["E"], b["density"], b["length"], diameter=b.get("diameter"),
                            area=b.get("area"))
    drill = rock_from_config(config, bar)  # [rod], [bit], [rock]: the rod-rock law
    if drill is not None and not st:
        R = 0.0  # the rod and the rock replace the stop
    elif ("restitution" in st) == ("area" in st):
        raise ValueError("give exactly one of stop.restitution and stop.area")
    elif "restitution" in st:
        R = tree.read_si("stop.restitution", st["restitution"])
    else:
        a_s = tree.read_si("stop.area", st["area"])
        if stop_area_check and not a_s >= bar.area_m2:
            raise ValueError(f"stop.area must be at least the piston's area ({bar.area_m2 * 1e4:.4g} "
                             f"cm^2: the restitution (A_s - A) / (A_s + A) in [0, 1)); got "
                             f"{shown(st['area'], a_s, 'm^2')}")
        R = (a_s - bar.area_m2) / (a_s + bar.area_m2)
    return bar, drill, R


def _rigid_start(drifter, duration_s: float, start_gap_m: float, start_velocity_m_s: float):
    """The checked duration of a drifter's run (s), its piston's length (m), its time scale (1/s)
    and the rigid start (:class:`~impactbar.InitialState`) from a gap and a velocity in SI."""
    from ..simulation import InitialState

    dur = check_real("duration_s", duration_s, lo=0.0, lo_open=True)
    L, om = drifter.bar.length_m, drifter.omega_rad_s
    start = InitialState.rigid(-check_real("start_gap_m", start_gap_m, lo=0.0) / L,
                               start_velocity_m_s / (L * om), drifter.n_modes)
    return dur, L, om, start


class _ScaledDrifter:
    """What a drifter in SI units (:class:`Drifter`, :class:`~impactbar.physical.CircuitDrifter`)
    takes from its force scale ``_force_scale_N`` (N), its ``bar``, ``restitution``,
    ``damping_N_s_m``, ``n_modes`` and ``drill``: their checks, the time scale, the scales and the
    dimensionless bar."""

    def __post_init__(self) -> None:
        """Check (and convert) the fields both drifters have: the piston, the drill string, the
        restitution, the damping and the number of modes (:class:`ValueError` naming the field);
        then the drifter's own (``_check_own``)."""
        check_piston(self.bar, True)
        if self.drill is not None and not isinstance(self.drill, DrillString):
            raise ValueError(f"drill must be a DrillString; got {type(self.drill).__name__}")
        object.__setattr__(self, "restitution", check_real("restitution", self.restitution, lo=0.0,
                                                           hi=1.0, hi_open=True))
        object.__setattr__(self, "damping_N_s_m", check_real("damping_N_s_m", self.damping_N_s_m, lo=0.0))
        object.__setattr__(self, "n_modes", check_int("n_modes", self.n_modes, lo=0, hi=1024))
        self._check_own()

    @property
    def omega_rad_s(self) -> float:
        r"""The time scale :math:`\Omega = \sqrt{F / (m L)}` (1/s), :math:`F` the force scale: the
        stroke force :math:`p A_s` of a valve drifter, :math:`P A_r` with the oil circuit."""
        return math.sqrt(self._force_scale_N / (self.bar.mass_kg * self.bar.length_m))

    @property
    def scales(self):
        r"""The units of the dimensionless model (:class:`~impactbar.physical.Scales`): time
        :math:`1/\Omega`, length :math:`L`, force :math:`F = m L \Omega^2` (:attr:`omega_rad_s`)."""
        from .hammer import Scales

        om, bar = self.omega_rad_s, self.bar
        return Scales(omega_rad_s=om, time_s=1.0 / om, length_m=bar.length_m,
                      velocity_m_s=bar.length_m * om, force_N=self._force_scale_N,
                      damping_N_s_m2=bar.mass_kg / bar.length_m * om)

    def model(self):
        """The dimensionless bar (eq. 2): :class:`~impactbar.BarModel`."""
        from ..model import BarModel

        om, bar = self.omega_rad_s, self.bar
        impact = "paper" if self.drill is None else self.drill.law(bar, self.scales)
        return BarModel(s=bar.wave_speed_m_s / (bar.length_m * om),
                        d=self.damping_N_s_m / (bar.mass_kg * om), R=self.restitution,
                        n_modes=self.n_modes, impact=impact, piston=self.bar.piston)


@dataclass(frozen=True)
class Drifter(_ScaledDrifter):
    r"""A hydraulic drifter: piston, stop, valve (theory §10), in SI units.

    Parameters
    ----------
    bar : Bar or SteppedBar
        The piston: uniform, or of uniform segments (theory §12; ``[bar]`` with lists of lengths
        and diameters or areas, driven end first).
    supply_pressure_Pa : float
        Supply pressure ``p`` (Pa), ``> 0``.
    stroke_area_m2, return_area_m2 : float
        Net piston areas under pressure in the stroke and the return state (m^2), ``> 0``: the
        forces are ``p A_s`` toward the stop and ``p A_r`` away from it.
    switch_out_m : float
        Switch position ``x_1`` (m, from the stop, on the way out), ``> 0``.
    restitution : float
        Restitution coefficient :math:`R` of the impact (eq. 10), :math:`0 \le R < 1`.
    delay_s : float, optional
        Valve delay :math:`\tau` (s), :math:`\ge 0`. Default 0.
    damping_N_s_m : float, optional
        Viscous damping coefficient of the whole piston (N s/m), :math:`\ge 0`. Default 0.
    n_modes : int, optional
        Flexible modes of the piston, :math:`\ge 0` (0: rigid). Default 0.
    name : str, optional
    drill : DrillString, optional
        The drill string and the rock (``impactbar.physical.rock``, theory §4d): the model's law
        is then the rod-rock law (``restitution`` plays no part).

    Raises
    ------
    ValueError
        Naming the parameter and its range.

    Examples
    --------
    >>> from impactbar.physical.drifter import drifter_preset
    >>> o = drifter_preset("hydraulic-drifter").orbit()
    >>> round(o.impact_velocity_m_s, 4), round(o.blow_frequency_Hz, 2)
    (9.4957, 47.19)
    """

    bar: Bar | SteppedBar
    supply_pressure_Pa: float
    stroke_area_m2: float
    return_area_m2: float
    switch_out_m: float
    restitution: float
    delay_s: float = 0.0
    damping_N_s_m: float = 0.0
    n_modes: int = 0
    name: str = ""
    drill: DrillString | None = None

    def _check_own(self) -> None:
        for f in ("supply_pressure_Pa", "stroke_area_m2", "return_area_m2", "switch_out_m"):
            object.__setattr__(self, f, check_real(f, getattr(self, f), lo=0.0, lo_open=True))
        object.__setattr__(self, "delay_s", check_real("delay_s", self.delay_s, lo=0.0))

    # -- scales -----------------------------------------------------------------------------
    @property
    def stroke_force_N(self) -> float:
        """``p A_s`` (N)."""
        return self.supply_pressure_Pa * self.stroke_area_m2

    @property
    def return_force_N(self) -> float:
        """``p A_r`` (N)."""
        return self.supply_pressure_Pa * self.return_area_m2

    @property
    def _force_scale_N(self) -> float:
        """The stroke force ``p A_s`` (N): the stroke force is 1."""
        return self.stroke_force_N

    # (the base's, named here so that the class's page lists them)
    omega_rad_s, scales, model = _ScaledDrifter.omega_rad_s, _ScaledDrifter.scales, _ScaledDrifter.model

    def drive(self):
        """The dimensionless valve: :class:`~impactbar.PositionSwitchedDrive`."""
        from ..drives import PositionSwitchedDrive

        return PositionSwitchedDrive(stroke=1.0, ret=self.return_area_m2 / self.stroke_area_m2,
                                     switch_out=self.switch_out_m / self.bar.length_m,
                                     delay=self.delay_s * self.omega_rad_s)

    # -- results ----------------------------------------------------------------------------
    def orbit(self, guess=None) -> DrifterOrbit:
        """The one-impact periodic motion (:func:`impactbar.find_orbit` with the drive), in SI."""
        from ..orbits import find_orbit

        return DrifterOrbit(self, find_orbit(self.model(), self.drive(), guess=guess))

    def simulate(self, duration_s: float, *, start_gap_m: float = 0.0, start_velocity_m_s: float = 0.0):
        """Simulate from the piston at rest (or a given gap and velocity) for ``duration_s``
        (:func:`impactbar.simulate`); returns the :class:`~impactbar.DrivenTrajectory` and a
        dict of SI summaries over the last half of the run: ``blows``, ``blow_frequency_Hz``,
        ``impact_velocity_m_s`` (mean), ``impact_energy_J`` (mean, :math:`m v^2 / 2` of the rigid
        mode's arrival), ``impact_power_kW``; with a drill string also the means per blow of
        ``work_on_rock_J``, ``penetration_mm`` and ``efficiency``, and ``drilling_rate_m_min``
        (the mean penetration times the blow frequency): each output's under its key and in its display
        unit as the registry declares them (:mod:`~impactbar.physical.outputs`)."""
        from ..simulation import simulate
        from .outputs import OUTPUTS

        def figures(**values) -> dict:
            """The run's figures by output name, in the outputs' units, under their keys."""
            return {OUTPUTS[k].shown_key: OUTPUTS[k].shown(x) for k, x in values.items()}

        dur, L, om, start = _rigid_start(self, duration_s, start_gap_m, start_velocity_m_s)
        tr = simulate(self.model(), self.drive(), start, dur * om)
        t = tr.impact_times / om
        late = t >= 0.5 * dur
        v = tr.impact_velocities[late] * L * om
        n = int(late.sum())
        f = (n - 1) / float(t[late][-1] - t[late][0]) if n > 1 else math.nan
        e = 0.5 * self.bar.mass_kg * float((v * v).mean()) if n else math.nan
        out = {"blows": n, **figures(blow_frequency=f, impact_velocity=float(v.mean()) if n else math.nan,
                                     impact_energy=e, impact_power=e * f / 1e3)}
        pieces = tr.pieces if self.drill is not None else ()
        recs = [r for i in range(len(pieces)) for r in getattr(pieces[i], "impacts", ())]
        if recs and len(recs) == late.size:  # with a drill string: the blows' records, one per impact
            late_recs = [r for r, keep in zip(recs, late, strict=True) if keep]
            sc = self.scales
            work = [float(r.work_on_rock) * sc.force_N * sc.length_m for r in late_recs]
            pen = [float(r.permanent_penetration) * sc.length_m for r in late_recs]

            def mean(x):
                return float(np.mean(x)) if x else math.nan

            out.update(figures(work_on_rock=mean(work), penetration=1e3 * mean(pen),
                               efficiency=mean([float(r.efficiency) for r in late_recs]),
                               drilling_rate=mean(pen) * f * 60.0))
        return tr, out

    @classmethod
    def from_config(cls, config: dict) -> Drifter:
        """A drifter from a nested dict of inputs with units (the keys in the module's docstring;
        unknown keys refused, naming them)."""
        sec = _config_sections(config, _KEYS, _REQUIRED)
        v = sec["valve"]
        bar, drill, R = _piston_drill_restitution(config, sec)

        def valve(key, default=None):
            return tree.read_si(f"valve.{key}", v.get(key, default), "drifter")

        return cls(bar=bar, supply_pressure_Pa=valve("supply_pressure"), stroke_area_m2=valve("stroke_area"),
                   return_area_m2=valve("return_area"), switch_out_m=valve("switch_out"), restitution=R,
                   delay_s=valve("delay", "0 ms"),
                   damping_N_s_m=tree.read_si("damping.coefficient",
                                              sec["damping"].get("coefficient", "0 N*s/m"), "drifter"),
                   n_modes=sec["model"].get("n_modes", 0), name=str(config.get("name", "")), drill=drill)


@dataclass(frozen=True)
class DrifterOrbit:
    """A drifter's periodic motion in SI units (theory §10): the valve drifter's, and the base of the
    oil circuit's :class:`~impactbar.physical.CircuitDrifterOrbit` (theory §11), which adds what the
    circuit has.

    Attributes
    ----------
    drifter : Drifter or CircuitDrifter
    orbit : DrivenOrbit
        The dimensionless orbit.
    """

    drifter: Drifter
    orbit: object
    _kind = "drifter"  #: the machine whose outputs it reports (:mod:`~impactbar.physical.outputs`)

    def __repr__(self) -> str:
        return (f"{type(self).__name__}({self.drifter.name or 'drifter'}: {self.blow_frequency_Hz:.4g} Hz, "
                f"impact {self.impact_velocity_m_s:.4g} m/s, {self.impact_energy_J:.4g} J{self._more()}, "
                f"{'stable' if self.stable else 'not stable'})")

    def _more(self) -> str:
        """What a subclass adds to the repr."""
        return ""

    @property
    def period_s(self) -> float:
        r""":math:`T / \Omega` (s)."""
        return self.orbit.period / self.drifter.omega_rad_s

    @property
    def blow_frequency_Hz(self) -> float:
        """Blows per second: the orbit's impacts over its period (Hz)."""
        return self.orbit.impacts / self.period_s

    @property
    def impact_velocity_m_s(self) -> float:
        r"""The struck end's velocity arriving at the stop, :math:`L \Omega v` (m/s)."""
        return self.drifter.bar.length_m * self.drifter.omega_rad_s * self.orbit.impact_velocity

    @property
    def impact_energy_J(self) -> float:
        r"""Kinetic energy of the piston arriving at the stop, :math:`m L^2 \Omega^2 e` (J)."""
        d = self.drifter
        return float(d.bar.mass_kg * (d.bar.length_m * d.omega_rad_s) ** 2 * self.orbit.impact_energy)

    @property
    def impact_power_kW(self) -> float:
        """The kinetic energy at impact times the blow frequency (kW)."""
        return self.impact_energy_J * self.blow_frequency_Hz / 1e3

    percussive_power_kW = renamed_attribute("percussive_power_kW", "impact_power_kW")

    @property
    def multipliers(self) -> np.ndarray:
        """The Floquet multipliers of the return map, the trivial one along the flow set apart."""
        return self.orbit.multipliers

    @property
    def stable(self) -> bool:
        """Admissible with every non-trivial multiplier inside the unit circle."""
        return bool(self.orbit.stable)

    def rock(self) -> dict:
        """The SI figures of the orbit's first blow on the rock (theory §4d, §10, §11).

        Returns
        -------
        dict
            With a drill string (``drifter.drill``), those of
            ``impactbar.physical.rock.rock_orbit_figures``: ``work_on_rock_J`` (J),
            ``penetration_mm`` (mm), ``drilling_rate_m_min`` (the penetration times the blow
            frequency, m/min), ``efficiency`` and ``efficiency_with_rebound`` (at most 1),
            ``rod_energy_J``, ``peak_rod_stress_Pa``, ``rod_advance_m``; an empty dict without one.
        """
        if self.drifter.drill is None:
            return {}
        from types import SimpleNamespace

        from .rock import rock_orbit_figures

        view = SimpleNamespace(scales=self.drifter.scales, drill=self.drifter.drill,
                               blow_frequency_Hz=self.blow_frequency_Hz)
        return rock_orbit_figures(self.orbit, view)

    def summary(self) -> dict:
        """The SI outputs as a dict (JSON-ready), with :meth:`rock`'s figures under ``rock`` when the
        drifter has a drill string."""
        out = self._summary()
        if self.drifter.drill is not None:
            out["rock"] = self.rock()
        return out

    def _summary(self) -> dict:
        """The SI outputs without the rock's: those of the view ``"summary"`` the machine has
        (:mod:`~impactbar.physical.outputs`), in their display units."""
        from .outputs import output_values, outputs

        shown = outputs("summary", self._kind, rock=False)
        values = output_values(self, shown)
        return {o.shown_key: o.shown(values[o.name]) for o in shown}


def operating_point(machine, guess=None):
    """A drifter's operating point, the one way a design map (:mod:`impactbar.sweeps.map_task`) and
    the optimiser (:func:`~impactbar.physical.optimize_drifter`, a valve drifter) find it: the default
    chain (``guess=None``) or Newton from a nearby point's orbit; a circuit drifter's cavitating orbit
    is returned with ``cavitates`` set (theory §10, §11).

    Parameters
    ----------
    machine : Drifter or CircuitDrifter
    guess : DrifterOrbit or CircuitDrifterOrbit, optional
        A nearby operating point of the same kind of machine.

    Returns
    -------
    DrifterOrbit or CircuitDrifterOrbit

    Raises
    ------
    ValueError
        Where there is no orbit (the machine's ``orbit()`` says why).
    """
    if isinstance(machine, Drifter):  # (the circuit drifter is no subclass of it)
        return machine.orbit(None if guess is None else guess.orbit)
    return machine.orbit(guess, allow_cavitation=True)


#: Drifter presets, from documented numbers.
DRIFTER_PRESETS: dict[str, dict] = {
    # The worked example of theory §10: a 5.6 kg piston, 5.6 kN each way, the switch 21.5 mm
    # from the stop, R = 0.215. The piston is the steel cylinder of the "hydraulic-drill" preset
    # scaled to 5.6 kg: 45 mm diameter, length 5.6 / (7850 pi/4 0.045^2) = 448.54 mm; its 56 mm
    # shank gives R = 0.215. 5.6 kN each way: 20 MPa (the hydraulic-drill preset's supply) on
    # 2.8 cm^2 in both states. Rigid by default (n_modes = 0): v = 9.4957 m/s, 47.19 Hz, 252.47 J.
    "hydraulic-drifter": {
        "name": "hydraulic-drifter",
        "bar": {"E": "210 GPa", "density": "7850 kg/m^3", "length": "448.54236 mm",
                "diameter": "45 mm"},
        "stop": {"restitution": 0.215},
        "valve": {"supply_pressure": "20 MPa", "stroke_area": "2.8 cm^2", "return_area": "2.8 cm^2",
                  "switch_out": "21.5 mm", "delay": "0 ms"},
        "model": {"n_modes": 0},
    },
}


def drifter_preset(name: str, **changes) -> Drifter:
    """A drifter preset by name (:data:`DRIFTER_PRESETS`); ``changes`` replace sections' keys, e.g.
    ``drifter_preset("hydraulic-drifter", valve={"delay": "1 ms"})``.

    Raises
    ------
    ValueError
        An unknown preset name, or a change that makes the config invalid (the key named).
    """
    return Drifter.from_config(_preset_config(DRIFTER_PRESETS, "drifter", name, changes))


def _preset_config(presets: dict, kind: str, name: str, changes: dict) -> dict:
    """A copy of the config ``presets[name]`` with ``changes`` (section: keys) merged into its
    sections; an unknown name refused (:class:`ValueError`, naming the ``kind`` of preset and the
    known ones)."""
    if name not in presets:
        raise ValueError(f"unknown {kind} preset {name!r}; known: {', '.join(presets)}")
    cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in presets[name].items()}
    for sec, keys in changes.items():
        cfg.setdefault(sec, {}).update(keys)
    return cfg
