r"""The drifter's oil circuit as a drive with state (theory §11): chambers, valve, supply node with
pump, accumulator and relief valve, composed from the frozen parts of :mod:`.parts`.

State ``z = (p_f, p_r, p_s, x_v)``: the front and rear chamber pressures, the supply pressure and the
valve's opening. Mode ``(target, moving, acc, relief)``: the valve's commanded position (1 stroke,
0 return), whether its spool is ramping there, whether the accumulator holds oil (``p_s > p_0``) and
whether the relief valve is open (``p_s > p_rel``); each flag changes at an event, so that the vector
field is smooth between events.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass

import numpy as np

from ..._shared.bounded import remember
from ..base import Drive, DriveState, GapCrossing, SurfaceEvent
from . import _bar as K
from . import _network as NW
from ._flight_cache import FlightData, _network_code, _par_base, _rate_model, flight_data
from .abilities import circuit_abilities, circuit_params, circuit_traits
from .composition import compose_parts
from .energy import CircuitEnergy
from .layout import PRESET
from .parameters import DECLARED
from .part_flows import part_flows
from .parts import Accumulator, Chambers, Oil, Supply, Valve
from .preset import preset_parts
from .settings import DEFAULT_SETTINGS, ROOT_TOLERANCE, circuit_settings
from .watch import ACC as _ACC
from .watch import REL as _REL
from .watch import border_tests as surface_tests
from .watch import pressure_margins, watched

__all__ = ["HydraulicCircuitDrive", "CircuitEnergy", "PARAMETERS"]

#: The circuit's continuation parameters and the part and field that hold each (``with_`` takes them
#: by name): a view of their declaration (:data:`.parameters.DECLARED`).
PARAMETERS = {p.name: (p.part, p.field) for p in DECLARED}
#: The ranges and descriptions of :data:`PARAMETERS` (their records:
#: ``drive.params.parameter_table()``), from the same declaration.
_RANGES = {p.name: p.ranges for p in DECLARED}

_SWITCH_OUT = "switch_out"
_SWITCH_IN = "switch_in"
_RAMP = "ramp_end"
#: the events the drive reads itself (the others an extra part's, :func:`.watch.watched`)
_OWN_EVENTS = (_RAMP, _ACC, _REL)
#: the most (mode, slots) keys whose fired events a drive keeps (:meth:`HydraulicCircuitDrive._fired`)
_FIRED_SIZE = 256
#: the drive's caches computed on use (its ``functools.cached_property`` s), left out of its pickle
_CACHED = ("_composition", "_stand_in", "_watched", "traits", "abilities", "_event_parts", "_event_slots",
           "_event_flags", "_per_mode", "_flights", "_fired_store")


@dataclass(frozen=True)
class HydraulicCircuitDrive(Drive):
    r"""A hydraulic drifter's oil circuit driving the piston (theory §11): a drive with state
    ``z = (p_f, p_r, p_s, x_v)``.

    The force on the piston's driven end (eq. 4) is ``p = p_r - alpha p_f`` (pressures in the
    pressure scale, the rear area 1, the front annulus ``alpha``). Between events

    - ``p_f' = beta / V_f (K_f phi(p_s - p_f) - alpha w')``, ``V_f = V_f0 + alpha w``;
    - ``p_r' = beta / V_r (K_v x_v phi(p_s - p_r) - K_v (1 - x_v) phi(p_r - p_t) + w')``,
      ``V_r = V_r0 - w``;
    - ``p_s' = (Q_p - K_f phi(p_s - p_f) - K_v x_v phi(p_s - p_r) - K_rel max(0, p_s - p_rel)) / C``,
      ``C = V_s / beta + C_a(p_s)`` (0 for a supply held at a pressure);
    - ``x_v' = +-1 / tau_v`` while the spool ramps, else 0;

    with ``w = -u(0, t)`` the driven end's displacement away from the stop and ``phi`` the smoothed
    orifice law (:class:`~impactbar.drives.circuit.Oil`). Events: the gap ``y = -q_0`` rising through
    ``switch_out`` opens the valve (armed while it is closed or closing), each impact closes it (or,
    with ``switch_in``, the gap falling through it), each a ramp from where the spool is; the ramp's
    end; ``p_s`` through the pre-charge and the relief pressure. Pressures and ``x_v`` are continuous
    through impacts.

    The drive is the circuit alone: how its flights are integrated (CVODE's tolerances, the compiled
    driver, the linear solvers, the variational flights' fundamental matrix, the plain flights'
    method) is a :class:`~impactbar.drives.circuit.CircuitFlightSettings` handed to the solvers
    (``settings`` of :func:`~impactbar.simulate` and :func:`~impactbar.find_orbit`; default
    :attr:`integrator`), so that two drives of the same parts are equal however they are solved.

    Parameters
    ----------
    chambers : Chambers
    valve : Valve
    supply : Supply
    oil : Oil
    accumulator : Accumulator, optional
        ``None``: none.
    start_pressures : tuple of float, optional
        ``(p_f, p_r, p_s)`` or ``(p_f, p_r, p_s, x_v)`` at the start of a run; default: the supply
        and the front chamber at the pre-charge (the accumulator just empty; the held pressure for a
        held supply, the tank pressure without an accumulator), the rear chamber at the tank
        pressure, the valve at the position the start's gap commands (with ``x_v`` given and away
        from it, the spool starts ramping there: an orbit's state after an impact, restarted).
        Each pressure in ``[0, beta)``, ``beta`` the oil's bulk modulus.
    extra_parts : tuple of CircuitPart, optional
        Parts added to the circuit (keyword, left out of the repr;
        :class:`~impactbar.drives.circuit.composition.CircuitPart`): their nodes' pressures are
        states after ``p_s`` (starting at the tank pressure unless ``start_pressures`` gives them),
        their energy integrands follow the preset's, each watched event of theirs is a flag of the
        mode after ``relief``, and a part may take over the valve's return port. The :attr:`layout`
        then comes from the composition (:func:`~impactbar.drives.circuit.composition.compose_parts`)
        and the flights, like the coupled blows (:meth:`end_flight`, the rod-rock and the wave laws),
        run the code generated for the network (:mod:`._netgen`, :mod:`._endgen`). Default: none (the
        preset circuit).

    Raises
    ------
    ValueError
        A part of the wrong type, a pre-charge above the relief pressure, start pressures out of range,
        extra parts that do not compose (:func:`~impactbar.drives.circuit.composition.compose_parts`).

    Examples
    --------
    >>> from impactbar import BarModel, InitialState, simulate
    >>> from impactbar.drives.circuit import (Accumulator, Chambers, HydraulicCircuitDrive, Oil,
    ...                                       Supply, Valve)
    >>> drive = HydraulicCircuitDrive(
    ...     Chambers(area_ratio=0.5, rear_volume=0.4, front_volume=0.2),
    ...     Valve(switch_out=0.048, coefficient=2.0, switching_time=0.05),
    ...     Supply(pump_flow=None, pressure=2.0, hose_volume=1.0, front_coefficient=2.0,
    ...            tank_pressure=0.03),
    ...     Oil(bulk_modulus=140.0, transition_pressure=0.01))
    >>> run = simulate(BarModel(s=52, d=0, R=0.215, n_modes=0), drive, InitialState.rigid(0.0, 0.0),
    ...                10.0)
    >>> run.n_impacts > 3, abs(drive.energy(run)["relative_residual"]) < 1e-8
    (True, True)

    The same run through scikit-sundae's Python interface (the way before the compiled driver: the
    same steps, to the bit), the drive unchanged:

    >>> from impactbar.drives.circuit import CircuitFlightSettings
    >>> before = simulate(BarModel(s=52, d=0, R=0.215, n_modes=0), drive, InitialState.rigid(0.0, 0.0),
    ...                   10.0, settings=CircuitFlightSettings(compiled=False))
    >>> bool((before.impact_times == run.impact_times).all())
    True
    """

    chambers: Chambers
    valve: Valve
    supply: Supply
    oil: Oil
    accumulator: Accumulator | None = None
    start_pressures: tuple | None = None
    extra_parts: tuple = dataclasses.field(default=(), repr=False, kw_only=True)

    #: where the circuit keeps its states and energy terms (:class:`~.layout.CircuitLayout`: ``z``'s
    #: indices by name, ``layout["supply"]``, and the energy integrands' ``layout.energy["pump"]``)
    layout = PRESET
    state_size = PRESET.n_states
    state_names = PRESET.state_names
    parameters = tuple(PARAMETERS)
    parameter_ranges = _RANGES
    #: how the flights are integrated (CVODE's tolerances and the solver's options,
    #: :class:`~.settings.CircuitFlightSettings`): the default of the solvers' ``settings``, not a
    #: part of the drive (its equality and hash are its parts')
    integrator = DEFAULT_SETTINGS
    variational = True

    def __repr__(self) -> str:
        # (the dataclass's repr, with the extra parts where there are any)
        shown = [f"{f.name}={getattr(self, f.name)!r}" for f in dataclasses.fields(self) if f.repr]
        if self.extra_parts:
            shown.append(f"extra_parts={self.extra_parts!r}")
        return f"{type(self).__name__}({', '.join(shown)})"

    def __post_init__(self) -> None:
        for name, cls in (("chambers", Chambers), ("valve", Valve), ("supply", Supply), ("oil", Oil)):
            if not isinstance(getattr(self, name), cls):
                raise ValueError(f"{name} must be a {cls.__name__}; got {type(getattr(self, name)).__name__}")
        acc = self.accumulator
        if acc is not None and not isinstance(acc, Accumulator):
            raise ValueError(f"accumulator must be an Accumulator or None; got {type(acc).__name__}")
        sup = self.supply
        if acc is not None and acc.volume > 0 and math.isfinite(sup.relief_pressure) \
                and acc.precharge >= sup.relief_pressure:
            raise ValueError(f"accumulator.precharge must be below the relief pressure "
                             f"{sup.relief_pressure:g}; got {acc.precharge:g} (the accumulator would never "
                             "take oil: a lower precharge or a higher relief_pressure)")
        if self.extra_parts:
            parts = tuple(self.extra_parts)
            object.__setattr__(self, "extra_parts", parts)
            comp = self._composition
            names = tuple(PARAMETERS) + tuple(n for p in parts for n in p.parameters)
            ranges = {**_RANGES, **{n: r for p in parts for n, r in p.parameter_ranges.items()}}
            L = comp.layout
            for name, value in (("layout", L), ("state_size", L.n_states), ("state_names", L.state_names),
                                ("n_quadratures", L.n_energy), ("parameters", names),
                                ("parameter_ranges", ranges)):
                object.__setattr__(self, name, value)
        if self.start_pressures is not None:
            sp = tuple(float(x) for x in self.start_pressures)
            beta = self.oil.bulk_modulus
            L = self.layout  # (the pressures, then optionally the spool's opening)
            if len(sp) not in (L.n_states - 1, L.n_states) \
                    or not all(math.isfinite(x) and (x >= 0.0 or n in L.mechanical)
                               for x, n in zip(sp, L.states, strict=False)) \
                    or (len(sp) == L.n_states and sp[L["spool"]] > 1.0) \
                    or not all(sp[i] < beta for i in range(L.n_states - 1)):
                raise ValueError(f"start_pressures must be the {L.n_states - 1} finite pressures >= 0 "
                                 f"{L.state_names[:-1]}, "
                                 f"each below the oil's bulk modulus {beta:g} (past it the oil's "
                                 f"compressibility law means nothing), optionally with the valve opening "
                                 f"x_v in [0, 1]; got {self.start_pressures!r}")
            object.__setattr__(self, "start_pressures", sp)

    def __getstate__(self) -> dict:
        """What pickles: the instance's attributes without the caches computed on use (the composed
        network, its parts' watched events, whose quantities are closures, the traits), which an
        unpickled drive computes again."""
        return {k: v for k, v in self.__dict__.items() if k not in _CACHED}

    # -- parameters --------------------------------------------------------------------------------
    def with_(self, **changes) -> HydraulicCircuitDrive:
        """A copy with parameters changed by name (:data:`PARAMETERS`: ``pump_flow``, ``precharge``,
        ``switching_time``, ...), validated again.

        Raises
        ------
        ValueError
            An unknown name (the allowed ones listed) or a value a part refuses.
        """
        parts: dict = {}
        extra = list(self.extra_parts)
        for name, value in list(changes.items()):
            for i, p in enumerate(extra):  # (an extra part's parameter: its field)
                if name in p.parameters:
                    extra[i] = dataclasses.replace(extra[i], **{p.parameters[name]: value})
                    del changes[name]
        for name, value in changes.items():
            if name not in PARAMETERS:
                raise ValueError(f"parameter must be one of {self.parameters}; got {name!r}")
            part, field = PARAMETERS[name]
            if getattr(self, part) is None:
                raise ValueError(f"{name}: the circuit has no {part}")
            parts.setdefault(part, {})[field] = value
        new = {p: dataclasses.replace(getattr(self, p), **f) for p, f in parts.items()}
        if self.extra_parts:
            new["extra_parts"] = tuple(extra)
        return dataclasses.replace(self, **new)

    def value(self, name: str) -> float:
        """The value of a parameter by name (:data:`PARAMETERS`, an extra part's ``parameters``)."""
        for p in self.extra_parts:
            if name in p.parameters:
                return float(getattr(p, p.parameters[name]))
        part, field = PARAMETERS[name]
        return float(getattr(getattr(self, part), field))

    def _parameter_value(self, name: str) -> float | None:
        # (a record's value: None for a part the circuit does not have, or a field it leaves unset)
        if name not in PARAMETERS:
            return self.value(name)
        part, field = PARAMETERS[name]
        holder = getattr(self, part)
        value = None if holder is None else getattr(holder, field)
        return None if value is None else float(value)

    # -- compiled data ----------------------------------------------------------------------------
    def _par(self, model, mode, variational=False) -> np.ndarray:
        par = _par_base(self, model).copy()
        target, *_ = mode  # (the valve's target: which switch is armed)
        par[K.ARMO] = 1.0 if target == 0 else 0.0
        par[K.ARMI] = 1.0 if (target == 1 and self.valve.switch_in is not None) else 0.0
        if self._stand_in:  # (a part in the valve's place: no switches)
            par[K.ARMO] = par[K.ARMI] = 0.0
        par[K.VAR] = 1.0 if variational else 0.0
        return par

    def _network(self, mode) -> np.ndarray:
        """The circuit as a network of part records (:mod:`._network`, header and records) in the
        mode ``mode``: the preset's parts (:func:`.preset.preset_parts`) and the extra ones, composed
        (:meth:`.composition.Composition.network`)."""
        return self._composition.network(mode, self.oil)

    @functools.cached_property
    def _composition(self):
        """The circuit composed of the preset's parts and its extra parts
        (:func:`.composition.compose_parts`)."""
        return compose_parts(self.extra_parts, preset_parts(self))

    @functools.cached_property
    def _stand_in(self) -> bool:
        """Whether a part that replaces the preset's valve (:attr:`.composition.CircuitPart.replaces`)
        writes no ramped valve (a spool valve): its switches, ramp and the impact's closing are then
        not used (the mode's target and ramp stay 0), the part's state is ``x_v``."""
        recs = np.asarray(self._network((0,) * (1 + len(self._composition.events)))[NW.NW_SIZE:])
        return not any(int(r[NW.KIND]) == NW.VALVE for r in recs.reshape(-1, NW.REC_SIZE))

    def _flags(self, mode) -> tuple:
        """The mode's flags ``(acc, rel)`` of the preset's accumulator and relief (by their events' slots)."""
        ev = self._composition.events
        return mode[1 + ev.index(_ACC)], mode[1 + ev.index(_REL)]

    @functools.cached_property
    def _watched(self) -> tuple:
        """The extra parts' watched events read from the network (:func:`.watch.watched`)."""
        comp = self._composition
        return watched(self._network((0,) * (1 + len(comp.events))), comp.events, _OWN_EVENTS)

    def _network_par(self, model, mode, variational=False) -> np.ndarray:
        """:meth:`_par` with the circuit's network of part records (:meth:`_network`) after it."""
        return np.concatenate((self._par(model, mode, variational), self._network(mode)))

    def _compiled_network(self, mode):
        """``(net, code)``: the circuit's network in the mode ``mode`` (:meth:`_network`) and the code
        generated for its topology (:func:`._netgen.generate`: its flight's kernels and CVODE's C
        callbacks), made once per drive and mode."""
        return _network_code(self, tuple(mode))

    def _flight_data(self, model, mode, variational=False) -> FlightData:
        """The parameters, the generated code and the events' directions of a flight of ``model`` in
        ``mode`` (``variational``: with the variational equations), made once and kept
        (:func:`._flight_cache.flight_data`)."""
        return flight_data(self, model, mode, variational)

    @functools.cached_property
    def _flights(self) -> dict:
        """:meth:`_flight_data`'s store, by model, mode and kind of flight."""
        return {}

    @functools.cached_property
    def _per_mode(self) -> dict:
        """:meth:`events`' store, by mode."""
        return {}

    def _directions(self, mode):
        # (the bar's, the ramp's end, then one a flag of the mode: the network's event slots 1..)
        target, _, *flags = mode
        return (1, 1, -1, 1 if target else -1) + tuple(-1 if f else 1 for f in flags)

    @functools.cached_property
    def _event_slots(self) -> dict:
        """The events' names by their slots in the kernels' event functions (:meth:`_fired`)."""
        names = {K.OUT_EV: _SWITCH_OUT, K.IN_EV: _SWITCH_IN, K.RAMP_EV: _RAMP}
        names.update((K.RAMP_EV + i, name) for i, name in enumerate(self._composition.events))
        return names

    @functools.cached_property
    def _fired_store(self) -> dict:
        """:meth:`_fired`'s store, by mode and the slots hit (at most 256 keys)."""
        return {}

    def _fired(self, mode, hit):
        """The events of ``mode`` whose slots in the kernels' event functions are in ``hit``, in the
        drive's order (made once per mode and slots: a flight's end asks it again and again)."""
        key = (tuple(mode), tuple(hit))
        store = self._fired_store
        out = store.get(key)
        if out is None:
            names = self._event_slots
            wanted = {names[i] for i in hit if i in names}
            out = remember(store, key, tuple(e for e in self.events(mode) if e.name in wanted), _FIRED_SIZE)
        return out

    def _failure(self, model, message, t) -> str:
        if "max_num_steps" in message:  # (CVODE's CV_TOO_MUCH_WORK: the flight, not the circuit)
            from .flight import _MAX_STEPS

            return (f"the oil circuit's flight from t = {t:.6g} took more than {_MAX_STEPS} steps without an "
                    f"event ({message}): a flight that long at the flight's tolerance with {model.n_modes} "
                    "modes of the piston; fewer modes or a looser integrator tolerance shorten it")
        return (f"the oil circuit's flight from t = {t:.6g} could not be integrated ({message}): "
                "check that the chambers keep a positive volume (rear_volume against the stroke) and that "
                "the pump flow and the areas can move the piston")

    # -- the Drive interface ----------------------------------------------------------------------
    def start(self, model, q, v) -> DriveState:
        return self._start(model, q, v)

    def charged_start(self, model, q, v) -> DriveState | None:
        """The start from rest of :meth:`start` with the supply and the front chamber charged to the
        relief valve's setting rather than left at the pre-charge: where the pump delivers more than
        the drill takes (the spool drill's 70 L/min), the orbit's supply pressure lies just above that
        setting, else below it, the motion from there discharging toward it by the supply's slow
        multiplier (theory §11, *The integrator*: a start for the motion followed to Newton's start,
        :func:`impactbar.orbits._closing.settle_start`). Where the motion from rest charges the
        supply impact by impact, some 5 % an impact on the spool drill, this start is nearer.

        Parameters
        ----------
        model : BarModel
        q, v : numpy.ndarray
            The piston's modal displacements and velocities at rest on the stop (m, m/s; scaled).

        Returns
        -------
        DriveState or None
            ``None`` where :meth:`start` takes the user's ``start_pressures``, the supply is held or
            has no relief valve, or its setting is below the pre-charge.
        """
        sup, acc = self.supply, self.accumulator
        precharge = acc.precharge if acc is not None and acc.volume > 0 else sup.tank_pressure
        if self.start_pressures is not None or sup.held or not sup.has_relief \
                or sup.relief_pressure < max(precharge, sup.tank_pressure):
            return None
        return self._start(model, q, v, sup.relief_pressure)

    def _start(self, model, q, v, charged=None) -> DriveState:
        sup, acc = self.supply, self.accumulator
        xv, L = None, self.layout
        if self.start_pressures is not None:  # (in the layout's order, the spool's opening optional)
            sp = self.start_pressures
            pf, pr, ps = sp[L["front"]], sp[L["rear"]], sp[L["supply"]]
            if len(sp) == L.n_states:
                xv = sp[L["spool"]]
        else:
            if sup.held:
                ps = sup.pressure
            elif charged is not None:  # (charged_start's: the relief valve's setting)
                ps = charged
            elif acc is not None and acc.volume > 0:
                ps = max(acc.precharge, sup.tank_pressure)
            else:
                ps = sup.tank_pressure
            pf, pr = ps, sup.tank_pressure
        if sup.held:
            ps = sup.pressure
        gap = -float(np.asarray(q)[0])
        target = 1 if gap >= self.valve.switch_out and not self._stand_in else 0
        z = np.empty(L.n_states)
        for name in L.states[L["supply"] + 1:L["spool"]]:  # (the extra parts' nodes: the tank's pressure)
            z[L[name]] = (0.0 if name in L.mechanical else sup.tank_pressure) \
                if self.start_pressures is None else self.start_pressures[L[name]]
        z[L["front"]], z[L["rear"]], z[L["supply"]], z[L["spool"]] = pf, pr, ps, float(target)
        if xv is not None and self._stand_in:  # (its position as given: no ramp)
            z[L["spool"]] = xv
        elif xv is not None and xv != float(target):
            z[L["spool"]] = xv
            return self._toward(self._mode(1 - target, 0, ps, z, q), z, target)
        return DriveState(self._mode(target, 0, ps, z, q), z)

    def _mode(self, target, moving, ps, z, q):
        acc = self.accumulator
        has_acc = acc is not None and acc.volume > 0 and not self.supply.held
        a = 1 if has_acc and ps >= acc.precharge else 0
        r = 1 if self.supply.has_relief and not self.supply.held and ps > self.supply.relief_pressure else 0
        flags = {_ACC: a, _REL: r, **{w.name: w.flag(q, z) for w in self._watched}}
        # (each event's flag after the ramp's end, slot 0 whose flag is ``moving``; an extra part's
        # event not watched 0)
        return (target, moving, *(flags.get(name, 0) for name in self._composition.events[1:]))

    def mode_name(self, mode) -> str:
        target, *_ = mode
        return "stroke" if target == 1 else "return"

    def force(self, mode, z, q, v) -> float:
        L = self.layout
        return float(z[L["rear"]] - self.chambers.area_ratio * z[L["front"]])

    n_quadratures = PRESET.n_energy
    piston_work_quadrature = PRESET.energy["piston"]
    traits = functools.cached_property(circuit_traits)
    params = property(circuit_params)
    abilities = functools.cached_property(circuit_abilities)

    def _field(self, mode, z, q, v, model):
        """The compiled vector field at one state (the code generated for the network's topology,
        :meth:`_compiled_network`): ``(M, out)``, ``out`` of shape ``(2 M + n_states + n_energy,)``
        (:attr:`layout`)."""
        L = self.layout
        q = np.asarray(q, dtype=float)
        M = q.size
        par, code, *_ = self._flight_data(_rate_model(M) if model is None else model, mode)
        y = np.concatenate((q, np.asarray(v, dtype=float), np.asarray(z, dtype=float)[:L.n_states]))
        out = np.empty(L.size(M) + L.n_energy)
        code.field_at(np.concatenate((y, np.zeros(L.n_energy)))[None, :], par, out[None, :])
        return M, out

    def rate(self, mode, z, q, v, model=None) -> np.ndarray:
        M, out = self._field(mode, z, q, v, model)
        return out[2 * M:self.layout.size(M)].copy()

    def quadratures(self, mode, z, q, v, model=None) -> np.ndarray:
        """The integrands of the eight terms of the energy account (:class:`CircuitEnergy`)."""
        M, out = self._field(mode, z, q, v, model)
        return out[self.layout.size(M):].copy()

    def events(self, mode):
        mode = tuple(mode)
        out = self._per_mode.get(mode)
        if out is None:  # (made once a mode: its events are frozen)
            out = self._per_mode[mode] = self._events(mode)
        return out

    def _events(self, mode):
        """:meth:`events`, made."""
        target, moving = mode[:2]
        acc, rel = self._flags(mode)
        sp, ps = self.layout["spool"], self.layout.supply
        out = []
        if target == 0 and not self._stand_in:
            out.append(GapCrossing(_SWITCH_OUT, level=self.valve.switch_out, direction=1))
        if target == 1 and self.valve.switch_in is not None:
            out.append(GapCrossing(_SWITCH_IN, level=self.valve.switch_in, direction=-1))
        if moving:
            lvl = float(target)
            out.append(SurfaceEvent(_RAMP, direction=1 if target else -1,
                                    function=lambda t, q, v, z, lvl=lvl, i=sp: float(z[i]) - lvl))
        if self.accumulator is not None and self.accumulator.volume > 0 and not self.supply.held:
            p0 = self.accumulator.precharge
            out.append(SurfaceEvent(_ACC, direction=-1 if acc else 1,
                                    function=lambda t, q, v, z, p0=p0, i=ps: float(z[i]) - p0))
        if self.supply.has_relief and not self.supply.held:
            pr = self.supply.relief_pressure
            out.append(SurfaceEvent(_REL, direction=-1 if rel else 1,
                                    function=lambda t, q, v, z, pr=pr, i=ps: float(z[i]) - pr))
        for w in self._watched:  # (the extra parts')
            out.append(SurfaceEvent(w.name, direction=-1 if mode[1 + w.slot] else 1,
                                    function=lambda t, q, v, z, w=w: w.quantity(q, z) - w.level))
        return tuple(out)

    def _held(self, z) -> np.ndarray:
        """``z`` with a held supply's pressure written again (it never changes: written at each map,
        the return map's Jacobian has no unit multiplier along ``p_s``, so Newton's is regular)."""
        z = np.array(z, dtype=float)
        if self.supply.held:
            z[self.layout.supply] = self.supply.pressure
        return z

    def _toward(self, mode, z, target):
        z = self._held(z)
        flags = tuple(mode[2:])  # (acc, rel, and the extra parts' flags)
        tau = self.valve.switching_time
        sp = self.layout["spool"]
        if tau <= 0.0 or z[sp] == float(target):
            z[sp] = float(target)
            return DriveState((target, 0, *flags), z)
        return DriveState((target, 1, *flags), z)

    def jump(self, mode, z, event, t, q, v) -> DriveState:
        target, *_ = mode
        name = event.name
        if name == _SWITCH_OUT:
            return self._toward(mode, z, 1)
        if name == _SWITCH_IN:
            return self._toward(mode, z, 0)
        z = self._held(z)
        if name == _RAMP:
            z[self.layout["spool"]] = float(target)
            return DriveState((target, 0, *mode[2:]), z)
        i = self._event_flags.get(name)
        if i is not None:  # (its flag toggled: acc, rel, an extra part's)
            flag = 1 - mode[i]
            for part in self._event_parts.get(name, ()):  # (its part's say on the flag and the state)
                flag, z = part.at_event(name, flag, z, self.layout)
            return DriveState((*mode[:i], flag, *mode[i + 1:]), z)
        raise ValueError(f"unknown event {name!r} of the oil circuit")  # pragma: no cover

    @functools.cached_property
    def _event_flags(self) -> dict:
        """Each event's flag in the mode (``1 +`` its slot in the network's events), by its name."""
        events = self._composition.events
        return {name: 1 + events.index(name) for name in events}

    @functools.cached_property
    def _event_parts(self) -> dict:
        """The extra parts that own each event, by its name (:meth:`jump`), in their order."""
        names = {name for part in self.extra_parts for name in part.events}
        return {name: tuple(p for p in self.extra_parts if name in p.events) for name in names}

    def impact(self, mode, z, t, q, v) -> DriveState:
        if self.valve.switch_in is not None or self._stand_in:
            return DriveState(mode, self._held(z))
        return self._toward(mode, z, 0)

    def flight(self, model, state, t, q, v, t_stop, settings=None, variational=False, start=None):
        from .flight import circuit_flight

        return circuit_flight(self, model, state, t, q, v, t_stop, settings, variational, start=start)

    def carries(self, model, settings=None) -> bool:
        """Whether the variational flights of ``model`` with ``settings`` (default :attr:`integrator`)
        carry the Jacobian so far (:attr:`~.settings.CircuitFlightSettings.carry`; ``"auto"``: CVODE's
        variational flights of a circuit with a part of mechanical state, a spool valve's)."""
        from .flight import uses_magnus

        settings = circuit_settings(settings if settings is not None else self.integrator)
        if settings.carry == "auto":
            return bool(self.layout.mechanical) and not uses_magnus(settings.sensitivity, model)
        return bool(settings.carry)

    def root_settings(self, model, settings=None):
        """The integrator of the plain flights whose root is the orbit of ``model`` with ``settings``
        (default :attr:`integrator`), where the variational flights carry the Jacobian so far
        (:meth:`carries`: a spool valve's circuit under CVODE's variational flights): ``settings``'
        tolerances :data:`~.settings.ROOT_TOLERANCE` times finer, their root as accurate as the
        variational flights' state, so that the orbit needs no closing Newton step by a variational
        flight (theory §11, *The integrator*); ``None`` otherwise (the orbit is the variational
        flights' root, as on the preset).

        Parameters
        ----------
        model : BarModel
        settings : FlightSettings or None, optional

        Returns
        -------
        CircuitFlightSettings or None
        """
        settings = circuit_settings(settings if settings is not None else self.integrator)
        if not self.carries(model, settings):
            return None
        return dataclasses.replace(settings, rtol=settings.rtol * ROOT_TOLERANCE,
                                   atol=settings.atol * ROOT_TOLERANCE)

    def variational_state_settings(self, model, settings=None):
        """Where the variational flights with ``settings`` (default :attr:`integrator`) take their
        fundamental matrix by Magnus' method (a piston with modes, their ``sensitivity``,
        :class:`~.settings.CircuitFlightSettings`), the integrator of the plain flight under them
        (:func:`~impactbar.drives.circuit.flight.magnus_state_settings`: the variational flight's
        state, bit for bit, without the fundamental matrix); ``None`` otherwise (CVODE's
        variational flights of the rigid piston)."""
        from .flight import magnus_state_settings, uses_magnus

        settings = circuit_settings(settings if settings is not None else self.integrator)
        if not uses_magnus(settings.sensitivity, model):
            return None
        return magnus_state_settings(settings)

    def end_flight(self, model, state, breaks, w0, incoming, impedance, settings=None):
        """The circuit over a stretch of a blow with the driven end moved by the law's waves
        (``impactbar.drives.circuit.endflight.circuit_end_flight``, theory §11, "The coupled
        blow").

        Returns
        -------
        EndFlight
        """
        from .endflight import circuit_end_flight

        return circuit_end_flight(self, model, state, breaks, w0, incoming, impedance, settings,
                                  _rate_model(1))

    def end_tangent(self, pieces, events, mode, breaks, splines, impedance, t0):
        """The circuit's variational equations along a blow's flight (theory §11, "The coupled blow";
        ``impactbar.drives.circuit.endtangent.EndTangent``, its parameters).

        Returns
        -------
        EndTangent
        """
        from .endtangent import EndTangent

        return EndTangent(self, pieces, events, mode, breaks, splines, impedance, t0, _rate_model(1))

    def border_tests(self, pieces, surfaces: bool = True) -> dict:
        """The circuit's border collisions over one period (theory §11): ``"accumulator"``, the
        least supply pressure less the pre-charge (through 0 where the accumulator starts emptying
        during the cycle), and ``"relief"``, the relief pressure less the greatest supply pressure
        (through 0 where the relief valve starts opening); each extreme from the flights' cubic
        Hermite interpolants (the integrator's accuracy). A held supply has neither. Each watched
        event of an extra part the same way, by its name (its node's least pressure less an
        accumulator's pre-charge, a relief's setting less the greatest). With ``surfaces``, the
        extra parts' levels and spool stops too (:func:`.watch.border_tests`: a check valve
        starting to crack open, a cushion's kink or a spool's port passed or not, a spool starting
        or ceasing to reach its stop).

        Parameters
        ----------
        pieces : list
            The period's pieces (flights and blows).
        surfaces : bool, optional
            Whether to add the levels' and stops' tests (default ``True``; ``False``: the pressure
            margins alone, in pressure units).

        Returns
        -------
        dict of float
        """
        out = pressure_margins(self, self._watched, pieces)
        if surfaces:
            out.update(surface_tests(self._watched, pieces))
        return out

    # -- results ----------------------------------------------------------------------------------
    def energy(self, run) -> CircuitEnergy:
        """The circuit's energy account over a run of :func:`impactbar.simulate` under this drive
        (theory §11): each term the sum of the flights' quadratures.

        Returns
        -------
        CircuitEnergy
        """
        total = np.zeros(self.layout.n_energy)
        for j in range(len(run.pieces)):
            piece = run.pieces[j]
            if hasattr(piece, "energies"):
                total += piece.energies()
        return CircuitEnergy.from_terms(total, self.layout)

    def histories(self, run, t=None) -> dict:
        """The circuit's time histories over a run: ``t`` (the integrator's steps, or the given
        times) and ``p_f``, ``p_r``, ``p_s``, ``x_v``, the gap ``y`` and the chambers' volumes
        ``V_f``, ``V_r`` (units of theory §11); with extra parts each of their nodes' pressure (its
        symbol, ``p_<name>``) and each part's flow ``q_<name>`` (:func:`.part_flows.part_flows`).

        Returns
        -------
        dict of numpy.ndarray
        """
        if t is None:
            t = np.unique(np.concatenate([run.pieces[j].t for j in range(len(run.pieces))
                                          if hasattr(run.pieces[j], "t")]))
        t = np.asarray(t, dtype=float)
        z = run.drive_state(t)
        q, _ = run.modal_state(t)
        M = q.shape[0]
        w = -(run.model.drive_weights[:M] @ q)
        for j in range(len(run.pieces)):  # inside a blow the driven end as integrated (theory §11)
            p = run.pieces[j]
            if hasattr(p, "displacement"):
                sel = (t > p.t0) & (t < p.t_end)
                if np.any(sel):
                    w[sel] = p.displacement(t[sel])
        return {"t": t, **{name: z[i] for i, name in enumerate(self.layout.state_names)}, "y": -q[0],
                "V_f": self.chambers.front_volume + self.chambers.area_ratio * w,
                "V_r": self.chambers.rear_volume - w, **part_flows(self, z, -q[0])}

    # -- the ideal drive it tends to (theory §11) ---------------------------------------------------
    def ideal_levels(self, supply_pressure: float) -> tuple[float, float]:
        """The forces of the ideal valve it tends to with the supply held at ``supply_pressure``
        (``beta``, every ``K`` to infinity, ``tau_v`` to 0): ``(stroke, ret)`` =
        ``(p_s (1 - alpha), alpha p_s - p_t)``."""
        a = self.chambers.area_ratio
        return supply_pressure * (1.0 - a), a * supply_pressure - self.supply.tank_pressure
