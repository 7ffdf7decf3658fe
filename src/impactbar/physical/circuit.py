r"""A hydraulic drifter with its oil circuit, in SI units (theory §11): chambers, valve, pump, supply
hose, gas accumulator and relief valve driving the piston; the blow frequency, the impact energy and
the supply pressure are outputs.

Scales (theory §11, eq. 2): the pressure scale :math:`P` = :data:`PRESSURE_SCALE` (10 MPa; pressures
are absolute), the rear area :math:`A_r` as the area scale, :math:`\Omega = \sqrt{P A_r / (m L)}`,
volumes in :math:`A_r L`, flows in :math:`A_r L \Omega`, an orifice's coefficient :math:`K`
(m^3 s^-1 Pa^-1/2) as :math:`K \sqrt{P} / (A_r L \Omega)`, the relief's (m^3 s^-1 Pa^-1) as
:math:`K_\mathrm{rel} P / (A_r L \Omega)`.

Configuration keys (a nested ``dict`` or TOML, as :meth:`CircuitDrifter.from_config` reads them)::

    name = "..."                                   # optional
    [bar]         E, density, length, diameter | area        # the piston
    [piston]      E, density, rear_rod_diameter, rear_rod_length, collar_diameter, collar_length,
                  front_rod_diameter, front_rod_length, end_diameters, end_lengths
                  # or: the piston's shape, in place of [bar] and the chamber areas
                  # (impactbar.physical.geometry: A_r = pi/4 (D_c^2 - d_r^2), A_f = pi/4 (D_c^2 - d_f^2))
    [stop]        restitution | area
    [damping]     coefficient                                # optional (N s/m)
    [model]       n_modes                                    # optional, default 0 (rigid)
    [chambers]    rear_area, front_area, rear_volume, front_volume   # the volumes at impact
    [valve]       switch_out, switch_in (optional), switching_time, flow_coefficient
                  # or none where a part stands in for it ([parts.<name>] of kind spool_valve)
    [supply]      pump_flow, hose_volume, front_flow_coefficient, tank_pressure,
                  relief_pressure, relief_coefficient        # the relief optional
    [accumulator] precharge, volume, polytropic_exponent     # optional section
    [oil]         bulk_modulus, transition_pressure
    [parts.<name>] kind, its connections and fields          # optional: parts added to the circuit
                                                             # (impactbar.physical.circuit_parts)
    [[rod.segments]], [bit], [rock]                          # optional: the drill string and the rock
                                                             # (impactbar.physical.rock, theory §4d)

With a ``[rock]`` the piston strikes the drill string (the rod-rock law; ``[stop]`` not needed), each
blow solved together with the circuit's state (theory §11, "The coupled blow"), and the orbit also
gives per blow the work on rock, the penetration and the drilling rate (the penetration times the
blow frequency).

Pressures are absolute ("0.3 MPa" of tank pressure is 0.2 MPa gauge), flow coefficients in
:math:`\mathrm{m^3\,s^{-1}\,Pa^{-1/2}}` (the relief's in :math:`\mathrm{m^3\,s^{-1}\,Pa^{-1}}`).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .._shared.validate import check_int
from . import tree
from ._circuit_checks import check_circuit_si, shown
from .bar import Bar, SteppedBar
from .circuit_parts import part_field, part_kinds, read_parts, unused_valve, valve_stand_in
from .circuit_switch import check_repeats as _check_repeats
from .circuit_switch import switch_start_orbit
from .drifter import (
    DrifterOrbit,
    _config_sections,
    _piston_drill_restitution,
    _preset_config,
    _rigid_start,
    _ScaledDrifter,
)
from .geometry import PISTON_KEYS, expand_piston
from .plausibility import warn_implausible
from .rock import DrillString
from .units import to_si

__all__ = ["CircuitDrifter", "CircuitDrifterOrbit", "CIRCUIT_PRESETS", "circuit_preset", "PRESSURE_SCALE",
           "ROCK_SI_PARAMETERS", "SI_PARAMETERS"]

#: The pressure scale ``P`` of the dimensionless circuit (Pa).
PRESSURE_SCALE = tree.PRESSURE_SCALE

#: The circuit's and the rock's parameters by their config names (``section.key``), in SI: the
#: dimensionless parameter each one sets, its unit and an example value (a view of
#: :data:`impactbar.physical.tree.FIELDS`: those set in the drive or the impact law).
SI_PARAMETERS = {k: (f.parameter, f.unit, f.example) for k, f in tree.FIELDS.items()
                 if f.holder in ("drive", "law")}

#: The keys of :data:`SI_PARAMETERS` that need a drill string (a ``[rock]`` section).
ROCK_SI_PARAMETERS = tuple(k for k in SI_PARAMETERS if tree.FIELDS[k].needs == "rock")

# the sections' keys and the required ones, from the tree (the piston's shape: its own section)
_KEYS = {**tree.section_keys(), "piston": PISTON_KEYS}
_REQUIRED = tree.required_keys()


@dataclass(frozen=True)
class CircuitDrifter(_ScaledDrifter):
    """A hydraulic drifter with its oil circuit (theory §11), in SI units; built by
    :meth:`from_config` (the keys in the module's docstring).

    Parameters
    ----------
    bar : Bar or SteppedBar
        The piston, as for :class:`~impactbar.physical.Drifter` (stepped: theory §12).
    restitution : float
        ``R`` of the impact (eq. 10), ``[0, 1)``.
    si : dict
        The circuit's SI values by key (``rear_area_m2``, ``front_area_m2``, ``rear_volume_m3``,
        ``front_volume_m3``, ``switch_out_m``, ``switch_in_m`` (or ``None``), ``switching_time_s``,
        ``valve_coefficient``, ``pump_flow_m3_s``, ``hose_volume_m3``, ``front_coefficient``,
        ``tank_pressure_Pa``, ``relief_pressure_Pa`` (``inf``: none), ``relief_coefficient``,
        ``precharge_Pa``, ``accumulator_volume_m3`` (0: none), ``polytropic_exponent``,
        ``bulk_modulus_Pa``, ``transition_pressure_Pa``).
    damping_N_s_m : float, optional
    n_modes : int, optional
    name : str, optional
    drill : DrillString, optional
        The drill string and the rock (``impactbar.physical.rock``, theory §4d): the model's law is
        then the rod-rock law (``restitution`` plays no part), each blow solved with the circuit's
        state (theory §11, "The coupled blow").
    config : dict, optional
        The configuration :meth:`from_config` read it from (not compared): what
        :func:`~impactbar.physical.operating_point_sensitivities` changes by key.
    parts : tuple of PartSpec, optional
        Parts added to the circuit (``[parts.<name>]``, :func:`~impactbar.physical.circuit_parts.read_parts`),
        each field a key ``parts.<name>.<field>``.

    Raises
    ------
    ValueError
        A value out of range (named).

    Examples
    --------
    >>> from impactbar.physical.circuit import circuit_preset
    >>> o = circuit_preset("circuit-drifter").orbit()
    >>> o.stable, 40 < o.blow_frequency_Hz < 60, 0 < o.hydraulic_efficiency < 1
    (True, True, True)
    """

    bar: Bar | SteppedBar
    restitution: float
    si: dict
    damping_N_s_m: float = 0.0
    n_modes: int = 0
    name: str = ""
    drill: DrillString | None = None
    config: dict | None = field(default=None, compare=False, repr=False)
    parts: tuple = ()

    def _check_own(self) -> None:
        si = self.si
        if si["front_area_m2"] >= si["rear_area_m2"]:
            raise ValueError(f"chambers.front_area must be below chambers.rear_area "
                             f"({si['rear_area_m2']:g} m^2) for the stroke to push toward the stop; "
                             f"got {si['front_area_m2']:g} m^2")
        self.drive()  # the parts' own checks, with their names

    # -- scales ------------------------------------------------------------------------------------
    @property
    def _force_scale_N(self) -> float:
        """``P A_r`` (N)."""
        return PRESSURE_SCALE * self.si["rear_area_m2"]

    # (the base's, named here so that the class's page lists them)
    omega_rad_s, scales, model = _ScaledDrifter.omega_rad_s, _ScaledDrifter.scales, _ScaledDrifter.model

    @property
    def volume_scale_m3(self) -> float:
        """``A_r L`` (m^3)."""
        return self.si["rear_area_m2"] * self.bar.length_m

    @property
    def flow_scale_m3_s(self) -> float:
        """``A_r L Omega`` (m^3/s)."""
        return self.volume_scale_m3 * self.omega_rad_s

    @property
    def energy_scale_J(self) -> float:
        r"""The energy scale :math:`m L^2 \Omega^2` (J)."""
        return self.bar.mass_kg * (self.bar.length_m * self.omega_rad_s) ** 2

    @property
    def valve_stand_in(self) -> str | None:
        """The name of the part in the ramped valve's place (a ``spool_valve``, theory §13: its kind
        :attr:`~impactbar.drives.circuit.CircuitPart.replaces` the valve), or ``None`` where the
        drifter's ramped valve switches (its ``valve.switch_out`` then applies). A ``[valve]`` table
        beside such a part is not used.

        Examples
        --------
        >>> circuit_preset("circuit-drifter").valve_stand_in is None
        True
        """
        kinds = part_kinds()
        return next((p.name for p in self.parts if "valve" in getattr(kinds[p.kind], "replaces", ())), None)

    def key_field(self, name: str) -> tree.Field | None:
        """The declaration of the config key ``name``: the parameter tree's
        (:data:`~impactbar.physical.tree.FIELDS`) or a part's (``parts.<name>.<field>``,
        :func:`~impactbar.physical.circuit_parts.part_field`); ``None`` for neither."""
        return tree.FIELDS.get(name) if isinstance(name, str) and name in tree.FIELDS else \
            part_field(self.parts, name)

    def _si_scale(self, name: str):
        """The scale that takes the SI value of the config key ``name`` to its dimensionless parameter
        as the config's value is taken (:func:`~impactbar.physical.tree.convert`): the tree's field's
        (:func:`~impactbar.physical.tree.continued`) or a part's field's (as
        :meth:`~impactbar.physical.circuit_parts.PartSpec.build` builds the part)."""
        f = part_field(self.parts, name)
        if f is None:
            if isinstance(name, str) and name.startswith("valve.") and isinstance(self.config, dict) \
                    and "valve" not in self.config and self.parts:
                raise ValueError(f"{name}: this drifter has no [valve]: the part "
                                 f"{valve_stand_in(self.config, self.parts)} stands in for it")
            return tree.continued(self, name).scale
        return f.scale

    def to_dimensionless(self, name: str, value) -> tuple[str, float]:
        r"""The dimensionless circuit parameter (theory §11) that the config key ``name`` sets, and
        its value for ``value`` in SI (``"12 MPa"``, ``"80 L/min"``; a bare number only for the
        polytropic exponent).

        Parameters
        ----------
        name : str
            A continuable key of :data:`impactbar.physical.tree.FIELDS` (``"accumulator.precharge"``,
            ``"supply.pump_flow"``, ``"stop.restitution"``, ...).
        value : str, pint.Quantity or float

        Returns
        -------
        parameter : str
            The drive's parameter (``"precharge"``, ...), for :func:`impactbar.continue_orbit`.
        value : float
            Dimensionless (pressures in 10 MPa, volumes in :math:`A_r L`, flows in :math:`A_r L \Omega`; the
            rock's stiffnesses in :math:`m \Omega^2`, the feed in :math:`P A_r`, the bit's mass in the
            piston's: theory §4d). The rock's keys (:data:`ROCK_SI_PARAMETERS`) need a drill
            string. Converted as the config's value is (its scale's steps,
            :func:`~impactbar.physical.tree.convert`): the same to the bit as the parameter of the
            drifter whose config sets ``value``.

        Raises
        ------
        ValueError
            An unknown key, one that cannot be continued (its declared reason), or a value without
            its unit, of the wrong dimension or not finite; a rock's key for a drifter without a
            ``[rock]`` section, an accumulator's for one without an accumulator.

        Examples
        --------
        >>> from impactbar.physical.circuit import circuit_preset
        >>> circuit_preset("circuit-drifter").to_dimensionless("accumulator.precharge", "12 MPa")
        ('precharge', 1.2)
        """
        scale = self._si_scale(name)
        f = self.key_field(name)
        return f.parameter, tree.convert(scale, self, to_si(name, value, f.unit, f.example))

    def from_dimensionless(self, name: str, value: float) -> float:
        """The SI value (in its declared unit) of the config key ``name`` whose
        dimensionless parameter has ``value``: the inverse of :meth:`to_dimensionless`, its scale's
        steps undone (:func:`~impactbar.physical.tree.convert_back`).

        Raises
        ------
        ValueError
            An unknown key.
        """
        return tree.convert_back(self._si_scale(name), self, float(value))

    def circuit_graph(self):
        """The circuit's nodes and parts as a graph
        (:func:`~impactbar.physical.circuit_graph.circuit_graph`)."""
        from .circuit_graph import circuit_graph

        return circuit_graph(self)

    def drive(self):
        """The dimensionless circuit: :class:`~impactbar.drives.circuit.HydraulicCircuitDrive`, each
        part's values converted from :attr:`si` by the parameter tree's declarations
        (:func:`~impactbar.physical.tree.drive_values`: each field's scale and the drive's part and
        field of its parameter); no accumulator where its volume is 0."""
        from ..drives.circuit import Accumulator, Chambers, HydraulicCircuitDrive, Oil, Supply, Valve

        v = tree.drive_values(self)
        return HydraulicCircuitDrive(
            Chambers(**v["chambers"]), Valve(**v["valve"]), Supply(**v["supply"]), Oil(**v["oil"]),
            Accumulator(**v["accumulator"]) if "accumulator" in v else None,
            extra_parts=tuple(p.build(self) for p in self.parts))

    # -- results -----------------------------------------------------------------------------------
    def orbit(self, guess=None, *, allow_cavitation: bool = False,
              switch_start: bool = False) -> CircuitDrifterOrbit:
        """The one-impact periodic motion, its operating point in SI (:func:`impactbar.find_orbit`
        with the circuit: from rest on the stop, the motion followed until it settles, then Newton
        with the variational equations' Jacobian).

        Parameters
        ----------
        guess : CircuitDrifterOrbit, DrivenOrbit or run, optional
            Where Newton starts: an orbit of this drifter, or the operating point of another design
            (other piston, chambers, valve or circuit values, the same number of modes): its
            unknowns (the state after the impact, the pressures, the flights' times) are taken as
            they are, in the model's units, and its flights' modes adopted (as a continuation step
            does); without one, the default chain below.
        allow_cavitation : bool
            Return a cavitating orbit (below) rather than refuse it.
        switch_start : bool
            Where the default chain finds no orbit, start again from the piston at rest at the
            valve's switch point (:func:`~impactbar.physical.circuit_switch.switch_start_orbit`:
            an orbit whose basin does not hold the rest on the stop, e.g. where the piston from
            rest buzzes on the shank), the orbit found checked by a restart from its arrival, stable
            or not (its ``stable`` says). Default ``False``: the default chain alone, as the design
            maps and the optimiser find their orbits.

        Raises
        ------
        ValueError
            Where the motion from rest does not settle onto a periodic one (e.g. a pump flow that
            cannot move the piston), or only onto the piston resting on the stop (its bounces dying
            away: no orbit with a blow), or a chamber empties; or where the orbit found does not
            repeat when :func:`impactbar.simulate` restarts it (checked over two periods to
            :data:`~impactbar.physical.circuit_switch.REPEAT_TOL`, without a drill string; with
            ``switch_start`` that start's orbit, rock or not), or where an absolute pressure of the orbit
            falls below 0 (the oil would cavitate: :attr:`CircuitDrifterOrbit.cavitates`), unless
            ``allow_cavitation`` (then the orbit is returned with ``cavitates`` set: a design map
            draws the region).
        """
        from ..orbits import find_orbit

        g = guess.orbit if isinstance(guess, CircuitDrifterOrbit) else guess
        model, drive = self.model(), self.drive()
        try:
            orbit = find_orbit(model, drive, guess=g)  # (another design's: its unknowns)
        except ValueError as err:
            if not (switch_start and g is None and "no periodic orbit" in str(err)):
                raise
            try:  # (checked by a restart from its arrival there, rock or not)
                orbit = switch_start_orbit(self, model, drive)
            except ValueError as again:
                raise ValueError(f"{err}; from rest at the valve's switch point: {again}") from None
        else:
            if self.drill is None:  # (the default chain's: a blow with the rock not restarted here)
                _check_repeats(orbit)
        point = CircuitDrifterOrbit(self, orbit)
        if not allow_cavitation:
            _refuse_cavitation(point.minimum_pressures_Pa,
                               f"the orbit (period {point.period_s * 1e3:.5g} ms)")
        return point

    def simulate(self, duration_s: float, *, start_gap_m: float = 0.0, start_velocity_m_s: float = 0.0,
                 histories: bool = True, max_impacts: int | None = None):
        """Simulate from the piston at rest on the stop (or a given gap and velocity), the circuit at
        its start pressures, for ``duration_s`` (:func:`impactbar.simulate`), or until its
        ``max_impacts``-th impact (an integer of at least 1; default no bound: the settle task's runs,
        :func:`~impactbar.physical.settle.settle_run`, are bounded so).

        Returns
        -------
        dict
            ``impact_times_s``, ``impact_velocities_m_s`` (arrays), ``histories`` (``t_s`` and the
            pressures ``p_f_Pa``, ``p_r_Pa``, ``p_s_Pa``, the valve opening ``x_v``, the gap
            ``gap_m``; ``None`` with ``histories=False``, which saves most of the time a run of the
            drifter on the rock takes, and most of its memory: each blow of ``run`` is then kept as
            its :class:`~impactbar.simulation.blows.BlowSummary`) and ``run`` (the dimensionless
            :class:`~impactbar.DrivenTrajectory`); with a drill string also ``work_on_rock_J`` and
            ``penetration_mm`` (arrays, per blow).

        Raises
        ------
        ValueError
            Where an absolute pressure falls below 0 during the run (the oil would cavitate).
        """
        from ..simulation import simulate

        dur, L, om, start = _rigid_start(self, duration_s, start_gap_m, start_velocity_m_s)
        drive = self.drive()
        run = simulate(self.model(), drive, start, dur * om, histories=histories, max_impacts=max_impacts)
        _refuse_cavitation(_least_pressures(run.pieces), f"the run of {dur:g} s")
        hist = None
        if histories:
            h = drive.histories(run)
            P = PRESSURE_SCALE
            hist = {"t_s": h["t"] / om, "p_f_Pa": h["p_f"] * P, "p_r_Pa": h["p_r"] * P,
                    "p_s_Pa": h["p_s"] * P, "x_v": h["x_v"], "gap_m": h["y"] * L}
        out = {"impact_times_s": np.asarray(run.impact_times) / om,
               "impact_velocities_m_s": np.asarray(run.impact_velocities) * L * om, "histories": hist,
               "run": run}
        if self.drill is not None:  # the blows' records, one per impact
            sc = self.scales
            blows = run.impacts
            out["work_on_rock_J"] = np.array([float(b.work_on_rock) for b in blows]) * sc.force_N * L
            out["penetration_mm"] = np.array([float(b.permanent_penetration) for b in blows]) * L * 1e3
        return out

    @classmethod
    def from_config(cls, config: dict) -> CircuitDrifter:
        """A drifter with its oil circuit from a nested dict of inputs with units (the keys in the
        module's docstring; unknown keys refused, naming them).

        Raises
        ------
        ValueError
            An unknown section or key, a missing key, a value with the wrong unit or out of range
            (each named).
        """
        given = copy.deepcopy(config)
        if isinstance(config, dict) and "piston" in config:  # the piston's shape: the stepped [bar] and
            config = expand_piston(config)  # the chamber areas it implies
        parts = read_parts(config.get("parts")) if isinstance(config, dict) else ()
        stand_in = valve_stand_in(config, parts)
        required = {k: v for k, v in _REQUIRED.items() if not (stand_in and k == "valve")}
        sec = _config_sections({k: v for k, v in config.items() if k != "parts"}
                               if isinstance(config, dict) else config, _KEYS, required)
        bar, drill, R = _piston_drill_restitution(config, sec, stop_area_check=True)

        acc = sec["accumulator"]
        if acc and not {"precharge", "volume"} <= set(acc):
            raise ValueError("[accumulator] needs precharge and volume")
        si = {f.si: _read_field(f, sec[f.section]) for f in tree.in_sections()
              if f.si and not (stand_in and f.section == "valve")}
        if stand_in:  # (the drive's ramped valve, never switched: the part stands in for it)
            si.update(unused_valve(si))
        check_circuit_si(sec, si, R)
        damping = to_si("damping.coefficient", sec["damping"].get("coefficient", "0 N*s/m"), "N*s/m",
                        "'9 N*s/m'", what="a damping coefficient")
        if not damping >= 0.0:
            raise ValueError(f"damping.coefficient must be 0 or above; got "
                             f"{shown(sec['damping']['coefficient'], damping, 'N*s/m')}")
        out = cls(bar=bar, restitution=R, si=si, damping_N_s_m=damping,
                  n_modes=check_int("model.n_modes", sec["model"].get("n_modes", 0), lo=0, hi=1024),
                  name=str(config.get("name", "")), drill=drill, config=given, parts=parts)
        warn_implausible(given)  # (values far outside their typical ranges: warned of, then run)
        return out


def _read_field(f, section: dict):
    """A declared field's SI value from its section (its default where the section leaves it out)."""
    if f.name not in section:  # an optional key left out
        d = f.default
        return to_si(f.key, d, f.unit, f.example, what=tree.WORDS.get(f.unit)) if isinstance(d, str) else d
    value, what = section[f.name], tree.WORDS.get(f.unit)
    if value is None:
        what = what if what is None or "(" in what else f"{what} in {f.unit.replace('**', '^')}"
        raise ValueError(f"{f.key} must be {what or 'a number'}, e.g. {f.example}; got None (leave an "
                         "optional key out)")
    return to_si(f.key, value, f.unit, f.example, what=what)


def _least_pressures(pieces) -> dict:
    """The least absolute pressure (Pa) of ``front``, ``rear``, ``supply`` and the extra parts' nodes
    (``[parts]``, by name) over the circuit's pieces among ``pieces`` (their Hermite interpolants'
    extremes)."""
    pieces = [p for p in pieces if hasattr(p, "extremes")]
    if not pieces:
        return {}
    layout = pieces[0].layout
    extra = [s for s in layout.states[3:-1] if s not in layout.mechanical]  # (the pressures after p_s)
    names = ("front", "rear", "supply", *extra)
    steps = [p for p in pieces if hasattr(p, "extremes_over")]  # (the flights' together)
    lows = []
    if steps:
        low, _ = next(iter(steps)).extremes_over(steps, names)
        lows.append(low)
    for p in pieces:
        if not hasattr(p, "extremes_over"):  # (a blow's: BlowPiece.extremes_of)
            low, _ = p.extremes_of(names)
            lows.append(low)
    return {name: float(low) * PRESSURE_SCALE for name, low in zip(names, np.min(lows, axis=0), strict=True)}


def _refuse_cavitation(low: dict, what: str) -> None:
    """Refuse a motion along which an absolute pressure of ``low`` (Pa, by volume) falls below 0:
    the oil would cavitate, which the model does not represent (theory §11)."""
    name = min(low, key=low.get) if low else None
    if name is not None and low[name] < 0.0:
        raise ValueError(f"{what} takes the {name} pressure to {low[name] / 1e6:.4g} MPa absolute, below "
                         "0: the oil would cavitate, which the circuit's model does not represent (widen "
                         "the opening that feeds that volume, or raise the tank pressure)")


@dataclass(frozen=True, repr=False)  # (the base's repr, with the supply pressure)
class CircuitDrifterOrbit(DrifterOrbit):
    """A drifter's operating point with its oil circuit, in SI units (theory §11): a
    :class:`~impactbar.physical.DrifterOrbit` (blow frequency, impact velocity and energy,
    multipliers, stability, the rock's figures) with the circuit's pressures, powers and energy
    account.

    Attributes
    ----------
    drifter : CircuitDrifter
    orbit : DrivenOrbit
        The dimensionless orbit (its state includes the pressures and the valve opening).
    """

    _kind = "circuit"

    def _more(self) -> str:
        return f", mean supply {self.mean_supply_pressure_Pa / 1e6:.4g} MPa"

    @cached_property
    def _pieces(self) -> list:
        """The orbit's flights and blows over one period, integrated once for every output."""
        problem = self.orbit.problem
        return problem.flights(problem.unknowns(self.orbit))

    def _energies(self) -> np.ndarray:
        return np.sum([p.energies() for p in self._pieces if hasattr(p, "energies")], axis=0)

    @property
    def energy_account(self) -> dict:
        """The circuit's energy account over one period (J): the terms of
        :class:`~impactbar.drives.circuit.CircuitEnergy` in SI."""
        from ..drives.circuit import CircuitEnergy

        acc = CircuitEnergy.from_terms(self._energies(), self.orbit.drive.layout)
        scale = self.drifter.energy_scale_J
        return {k: (v if k == "relative_residual" else v * scale) for k, v in acc.items()}

    @property
    def mean_supply_pressure_Pa(self) -> float:
        """The supply pressure averaged over the period (Pa, absolute): the pump's work over
        ``Q_p T`` (the held pressure for a held supply)."""
        sup = self.orbit.drive.supply
        if sup.held:
            return sup.pressure * PRESSURE_SCALE
        pump = self._energies()[self.orbit.drive.layout.energy["pump"]]
        return float(pump / (sup.pump_flow * self.orbit.period)) * PRESSURE_SCALE

    @property
    def pump_power_kW(self) -> float:
        """The pump's mean power ``Q_p (p_s - p_t)`` over the period (kW)."""
        sup = self.orbit.drive.supply
        E = self._energies()[self.orbit.drive.layout.energy["pump"]]
        if sup.held:
            used = E * (1.0 - sup.tank_pressure / sup.pressure)
        else:
            used = E - sup.tank_pressure * sup.pump_flow * self.orbit.period
        return float(used * self.drifter.energy_scale_J / self.period_s / 1e3)

    @property
    def minimum_pressures_Pa(self) -> dict:
        """The least absolute pressure of each oil volume over the period (Pa): ``front``, ``rear``,
        ``supply`` and the extra parts' nodes by name (from the flights' Hermite interpolants). The
        model has no cavitation: where one falls below the oil's vapour pressure (a few kPa;
        :attr:`cavitates` flags below 0) the motion it computes is not the machine's."""
        return _least_pressures(self._pieces)

    @property
    def cavitates(self) -> bool:
        """Whether an absolute pressure of the orbit falls below 0 (:attr:`minimum_pressures_Pa`):
        the oil would cavitate there, which the model does not represent (:meth:`CircuitDrifter.orbit`
        and :meth:`CircuitDrifter.simulate` refuse such a motion)."""
        return min(self.minimum_pressures_Pa.values()) < 0.0

    @property
    def border_margins_Pa(self) -> dict:
        """How far the orbit stays from the circuit's borders over the period (Pa), from its flights
        (:meth:`~impactbar.drives.circuit.HydraulicCircuitDrive.border_tests`): ``relief``, the
        relief's setting less the greatest supply pressure (below 0: the relief valve opens), and
        ``accumulator``, the least supply pressure less the pre-charge (below 0: the accumulator
        empties); a border the circuit does not have (no relief, no accumulator) is left out."""
        return {k: float(v) * PRESSURE_SCALE
                for k, v in self.orbit.drive.border_tests(self._pieces, surfaces=False).items()}

    @property
    def pressures_at_impact_Pa(self) -> dict:
        """The absolute pressure of each oil volume at the impact (Pa): ``front``, ``rear``,
        ``supply``."""
        o = self.orbit
        z = np.asarray(o.drive_states[0], dtype=float) * PRESSURE_SCALE
        return {name: float(z[o.drive.layout[name]]) for name in ("front", "rear", "supply")}

    @property
    def hydraulic_efficiency(self) -> float:
        """The energy the blows deliver (the piston's kinetic energy before the impacts less after
        them) per second over :attr:`pump_power_kW`: a fraction of the hydraulic power, below 1."""
        o = self.orbit
        M = o.model.n_modes + 1

        def ke(states):
            return sum(0.5 * (v[0] ** 2 + 2.0 * float(np.sum(v[1:] ** 2))) for v in (s[M:] for s in states))

        delivered = (ke(o.states_before_impact) - ke(o.states_after_impact)) * self.drifter.energy_scale_J
        return float(delivered / self.period_s / 1e3 / self.pump_power_kW)

    def histories(self, points: int = 400) -> dict:
        """The pressures (Pa), the valve opening and the chambers' volumes (m^3) over one period,
        from the impact: ``t_s``, ``p_f_Pa``, ``p_r_Pa``, ``p_s_Pa``, ``x_v``, ``gap_m``, ``V_f_m3``,
        ``V_r_m3`` at ``points`` times; with parts (``[parts.<name>]``) each part's node's pressure
        ``p_<name>_Pa`` (a spool valve's velocity ``v_<name>_m_s``) and each part's flow from its
        source to its target ``q_<name>_m3_s``
        (:func:`~impactbar.drives.circuit.part_flows.part_flows`)."""
        from ..drives.circuit.part_flows import part_flows

        points = check_int("points", points, lo=2)
        d, o = self.drifter, self.orbit
        pieces = self._pieces
        t0 = pieces[0].t0
        t = np.linspace(t0, pieces[-1].t_end, points)
        dr = o.drive
        L = dr.layout
        z = np.empty((L.n_states, points))
        q0 = np.empty(points)
        M = o.model.n_modes + 1
        w = np.zeros(points)
        for p in pieces:
            sel = (t >= p.t0) & (t <= p.t_end)
            if np.any(sel):
                z[:, sel] = p.drive_state(t[sel])
                q, _ = p.modal(t[sel])
                q0[sel] = q[0]
                # inside a blow the driven end as the circuit integrated it (theory §11)
                w[sel] = p.displacement(t[sel]) if hasattr(p, "displacement") else \
                    -(o.model.drive_weights[:M] @ q)
        P, V = PRESSURE_SCALE, d.volume_scale_m3
        speed = d.bar.length_m * d.omega_rad_s  # (a mechanical node's value is a velocity)
        nodes = {f"{name}_m_s" if node in L.mechanical else f"{name}_Pa":
                 z[L[name]] * (speed if node in L.mechanical else P)
                 for p in dr.extra_parts for node, name in zip(p.nodes, p.symbols, strict=True)}
        flows = {f"{k}_m3_s": v * d.flow_scale_m3_s for k, v in part_flows(dr, z, -q0).items()}
        return {"t_s": (t - t0) / d.omega_rad_s, "p_f_Pa": z[L["p_f"]] * P, "p_r_Pa": z[L["p_r"]] * P,
                "p_s_Pa": z[L["p_s"]] * P, "x_v": z[L["x_v"]], "gap_m": -q0 * d.bar.length_m,
                "V_f_m3": (dr.chambers.front_volume + dr.chambers.area_ratio * w) * V,
                "V_r_m3": (dr.chambers.rear_volume - w) * V, **nodes, **flows}

    def indicator_work_J(self, points: int = 4000, *, histories: dict | None = None) -> dict:
        r"""The work each chamber's oil does on the piston over one period, the area of its
        indicator (p-V) diagram (theory §11): ``rear`` :math:`\oint p_r\,dV_r`, ``front``
        :math:`\oint p_f\,dV_f` and their sum ``piston`` (J; positive where the chamber drives the
        piston, its loop running clockwise in the p-V plane), by the trapezoidal rule over
        :meth:`histories` (second order in their spacing; at the default 4000 points the sum
        matches the energy account's ``piston`` term, a quadrature along the integration, to 2e-6
        on the preset, and their Richardson extrapolation from 8000 and 16000 points to 1e-8).

        Parameters
        ----------
        points : int
            Samples over the period, :math:`\ge 2`.
        histories : dict, optional
            :meth:`histories`' output to use instead of sampling again.

        Returns
        -------
        dict
            ``rear``, ``front``, ``piston`` (J).

        Raises
        ------
        ValueError
            ``points`` below 2.
        """
        from scipy.integrate import trapezoid

        h = self.histories(points) if histories is None else histories
        rear = float(trapezoid(h["p_r_Pa"], h["V_r_m3"]))
        front = float(trapezoid(h["p_f_Pa"], h["V_f_m3"]))
        return {"rear": rear, "front": front, "piston": rear + front}

    def plot(self, axes=None, points: int = 2000):
        """The pressures and the valve over one period and each chamber's indicator diagram
        (:func:`impactbar.plotting.circuit.plot_circuit_orbit`; matplotlib imported on this call).

        Returns
        -------
        numpy.ndarray of matplotlib.axes.Axes, shape (4,)
        """
        from ..plotting.circuit import plot_circuit_orbit

        return plot_circuit_orbit(self, axes=axes, points=points)


#: Presets of drifters with their oil circuit.
CIRCUIT_PRESETS: dict[str, dict] = {
    # The piston of the "hydraulic-drifter" preset (5.6 kg, 45 mm, 448.54 mm; R = 0.215 from its
    # 56 mm shank), areas that give the same 5.6 kN each way at 20 MPa (A_r - A_f = A_f = 2.8 cm^2),
    # the same switch position; the pump sized to the ideal orbit's oil use (the rear chamber's
    # stroke volume, about 30 cm^3, at about 47 blows per second: 70 L/min); chamber volumes of a
    # few times the stroke volume; a spool that switches in 1 ms; openings that pass the piston's
    # peak flow (about 6 L/s) with a drop of about 1 MPa (K = Q / sqrt(dp) = 6e-3 / 1e3); mineral
    # oil's effective bulk modulus with some air, 1.4 GPa; a 0.5 L accumulator pre-charged to
    # 10 MPa with nitrogen (adiabatic, n = 1.4); 0.3 MPa absolute in the tank line; a relief valve
    # at 25 MPa.
    "circuit-drifter": {
        "name": "circuit-drifter",
        "bar": {"E": "210 GPa", "density": "7850 kg/m^3", "length": "448.54236 mm", "diameter": "45 mm"},
        "stop": {"restitution": 0.215},
        "chambers": {"rear_area": "5.6 cm^2", "front_area": "2.8 cm^2", "rear_volume": "0.1 L",
                     "front_volume": "0.05 L"},
        "valve": {"switch_out": "21.5 mm", "switching_time": "1 ms",
                  "flow_coefficient": "6e-6 m^3/s/Pa^0.5"},
        "supply": {"pump_flow": "70 L/min", "hose_volume": "0.25 L",
                   "front_flow_coefficient": "6e-6 m^3/s/Pa^0.5", "tank_pressure": "0.3 MPa",
                   "relief_pressure": "25 MPa", "relief_coefficient": "5e-10 m^3/s/Pa"},
        "accumulator": {"precharge": "10 MPa", "volume": "0.5 L", "polytropic_exponent": 1.4},
        "oil": {"bulk_modulus": "1.4 GPa", "transition_pressure": "0.2 MPa"},
    },
}


def circuit_preset(name: str, **changes) -> CircuitDrifter:
    """A preset of a drifter with its oil circuit by name (:data:`CIRCUIT_PRESETS`); ``changes``
    replace sections' keys, e.g. ``circuit_preset("circuit-drifter", accumulator={"precharge":
    "12 MPa"})``.

    Raises
    ------
    ValueError
        An unknown preset name, or a change that makes the config invalid (the key named).
    """
    return CircuitDrifter.from_config(_preset_config(CIRCUIT_PRESETS, "circuit", name, changes))
