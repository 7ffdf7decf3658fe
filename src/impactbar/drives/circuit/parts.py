r"""The parts of a drifter's oil circuit (theory §11), dimensionless, each a small frozen dataclass.

The circuit is composed as a lumped fluid-power network is in Hopsan's component library: capacitive
volumes (Hopsan's C-type components, ``HydraulicVolume``: a volume :math:`V` and the oil's bulk
modulus :math:`\beta`, :math:`p' = \frac{\beta}{V} \left(\sum Q_\mathrm{in} - V'\right)`), resistive
orifices between them (Q-type, ``HydraulicTurbulentOrifice``: :math:`Q = K \sqrt{\Delta p}` with
:math:`K = C_q A \sqrt{2 / \rho}`) and a gas accumulator (``HydraulicAckumulator``: a polytropic
gas :math:`p V^n = p_0 V_0^n`). Here the parts hold
the numbers and :class:`~impactbar.drives.circuit.HydraulicCircuitDrive` composes them into one
system of ordinary differential equations.

Units (theory §11, eq. 2): pressures in a pressure scale :math:`P` (absolute), areas in the rear
area :math:`A_r`, lengths in the bar's length :math:`L`, volumes in :math:`A_r L`, time in
:math:`1 / \Omega` with :math:`\Omega = \sqrt{P A_r / (m L)}` (so that the rear pressure :math:`P`
on :math:`A_r` is the force scale :math:`m L \Omega^2`), flows in :math:`A_r L \Omega`, an orifice's
coefficient :math:`K` (m^3 s^-1 Pa^-1/2) as :math:`K \sqrt{P} / (A_r L \Omega)`, the relief's
(m^3 s^-1 Pa^-1) as :math:`K_\mathrm{rel} P / (A_r L \Omega)`, the bulk modulus as
:math:`\beta / P`. :class:`impactbar.physical.CircuitDrifter` makes them from SI inputs.

References
----------
Hopsan (Linkoping University, Division of Fluid and Mechatronic Systems), component library
``componentLibraries/defaultLibrary/Hydraulic``: ``Volumes&Lines/HydraulicVolume.hpp``,
``Restrictors/HydraulicTurbulentOrifice.hpp``, ``Volumes&Lines/HydraulicAckumulator.hpp``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..._shared.validate import check_real
from . import _network as NW

__all__ = ["Chambers", "Valve", "Supply", "Accumulator", "Oil"]


def _positive(obj, *names) -> None:
    for n in names:
        object.__setattr__(obj, n, check_real(n, getattr(obj, n), lo=0.0, lo_open=True))


def _non_negative(obj, *names) -> None:
    for n in names:
        object.__setattr__(obj, n, check_real(n, getattr(obj, n), lo=0.0))


@dataclass(frozen=True)
class Chambers:
    """The piston's two chambers (C-type volumes): the rear (stroke) chamber of area 1 (the area
    scale) pushing the piston toward the stop, the front (return) annulus of area ``area_ratio``
    pushing it away.

    Parameters
    ----------
    area_ratio : float
        ``A_f / A_r``, in ``(0, 1)``: the stroke needs ``A_r > A_f`` under a common supply.
    rear_volume, front_volume : float
        The chambers' oil volumes with the rigid piston on the stop (``A_r L`` units), ``> 0``. With
        the driven end's displacement ``w`` from there (away from the stop), ``V_r = rear_volume - w``
        and ``V_f = front_volume + area_ratio w``.

    Raises
    ------
    ValueError
        A value out of its range (named).
    """

    area_ratio: float
    rear_volume: float
    front_volume: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "area_ratio", check_real("area_ratio", self.area_ratio, lo=0.0, hi=1.0,
                                                          lo_open=True, hi_open=True))
        _positive(self, "rear_volume", "front_volume")

    def least_volumes(self, w) -> tuple[float, float]:
        """The least rear and front volumes over the driven end's displacements ``w`` (theory §11):
        ``V_r`` at the greatest ``w``, ``V_f`` at the least. Rounding is monotone and
        ``area_ratio > 0``, so these are the least of ``rear_volume - w`` and
        ``front_volume + area_ratio w`` over ``w`` to the bit, without those arrays.

        Parameters
        ----------
        w : numpy.ndarray
            The displacements away from the stop (model length units), at least one.

        Returns
        -------
        rear, front : float
            In the volumes' units (``A_r L``).

        Examples
        --------
        >>> import numpy as np
        >>> Chambers(0.5, 0.4, 0.2).least_volumes(np.array([-0.1, 0.3]))
        (0.10000000000000003, 0.15000000000000002)
        """
        return self.rear_volume - float(w.max()), self.front_volume + self.area_ratio * float(w.min())

    def check_volumes(self, w, t: float, advice: str) -> None:
        """Refuse a motion that empties a chamber (theory §11: its volume at or below 0 somewhere in
        the driven end's displacements ``w``, :meth:`least_volumes`), the rear chamber named before
        the front one.

        Parameters
        ----------
        w : numpy.ndarray
            The displacements away from the stop (model length units), at least one.
        t : float
            When the motion starts (model time units), for the message.
        advice : str
            The message after the chamber's name: when and what to do, formatted with ``t``,
            ``which`` (``"rear"`` or ``"front"``) and ``now`` (that chamber's volume).

        Raises
        ------
        ValueError
            A chamber empties: the message names the chamber, then ``advice`` formatted.

        Examples
        --------
        >>> import numpy as np
        >>> Chambers(0.5, 0.4, 0.2).check_volumes(np.array([0.3, 0.5]), 1.0, "near t = {t:g}: {which}")
        Traceback (most recent call last):
        ...
        ValueError: the rear chamber empties (V <= 0) near t = 1: rear
        """
        rear, front = self.least_volumes(w)
        if rear <= 0.0 or front <= 0.0:
            which = "rear" if rear <= 0.0 else "front"
            raise ValueError(f"the {which} chamber empties (V <= 0) "
                             + advice.format(t=t, which=which, now=getattr(self, which + "_volume")))

    def records(self, front: int, rear: int, bulk_modulus: float, front_energy: int = -1,
                rear_energy: int = -1) -> list:
        """The chambers as network records (:mod:`._network`): the front and rear nodes (their dead
        volumes) and one chamber on each (the rear's first: the force ``p_r - alpha p_f`` summed in
        that order).

        Parameters
        ----------
        front, rear : int
            The nodes' numbers (each with a pressure state).
        bulk_modulus : float
            The oil's ``beta``.
        front_energy, rear_energy : int, optional
            The slots of their compression work (-1: none).

        Returns
        -------
        list of numpy.ndarray
            The front's node, the rear's, the rear's chamber and the front's (:func:`._network.record`).

        Examples
        --------
        >>> len(Chambers(0.5, 0.4, 0.2).records(0, 1, 100.0))
        4
        """
        return [NW.record(NW.NODE, id=front, volume=self.front_volume, beta=bulk_modulus,
                          compression_energy=front_energy),
                NW.record(NW.NODE, id=rear, volume=self.rear_volume, beta=bulk_modulus,
                          compression_energy=rear_energy),
                NW.record(NW.CHAMBER, node=rear, area=-1.0),
                NW.record(NW.CHAMBER, node=front, area=self.area_ratio)]


@dataclass(frozen=True)
class Valve:
    r"""The main valve (two Q-type openings that share one spool): the rear chamber to the supply
    through ``coefficient * x_v``, to the tank through ``coefficient * (1 - x_v)``, the opening ``x_v``
    ramping between 0 (return) and 1 (stroke) in ``switching_time``.

    Parameters
    ----------
    switch_out : float
        The gap (bar lengths) whose rising crossing opens the valve (armed while it is closed or
        closing), ``> 0``.
    coefficient : float
        The opening's flow coefficient ``K_v``, ``> 0``.
    switching_time : float, optional
        A full stroke of the spool, :math:`\ge 0` (0: an instant switch). Default 0.
    switch_in : float or None, optional
        The gap whose falling crossing closes the valve (armed while it is open or opening); ``None``
        (default): the valve closes at each impact.

    Raises
    ------
    ValueError
        A value out of its range (named), or ``switch_in`` :math:`\ge` ``switch_out``.
    """

    switch_out: float
    coefficient: float
    switching_time: float = 0.0
    switch_in: float | None = None

    def __post_init__(self) -> None:
        _positive(self, "switch_out", "coefficient")
        _non_negative(self, "switching_time")
        if self.switch_in is not None:
            object.__setattr__(self, "switch_in", check_real("switch_in", self.switch_in, lo=0.0,
                                                             hi=self.switch_out, lo_open=True, hi_open=True))

    def records(self, pressure_port: int, work_port: int, return_port: int, transition_pressure: float,
                rate: float = 0.0, opening: int = 0, energy: int = -1, event: int = -1) -> list:
        """The valve as a network record (:mod:`._network`): the spool between the pressure port, the
        work port (the rear chamber) and the return port.

        Parameters
        ----------
        pressure_port, work_port, return_port : int
            The nodes' numbers.
        transition_pressure : float
            The oil's ``p_tr``.
        rate : float, optional
            The spool's ``x_v'`` (0: at rest).
        opening : int, optional
            +1: ramping to 1, -1: to 0, 0: at rest (the ramp's end watched while it ramps).
        energy, event : int, optional
            The slots of the openings' losses and of the ramp's end (-1: none).

        Returns
        -------
        list of numpy.ndarray
            One record: its ports, ``K_v``, the square of the transition pressure, the spool's rate and
            mode, its slots.

        Examples
        --------
        >>> len(Valve(0.05, 2.0).records(2, 1, 3, 0.01))
        1
        """
        return [NW.record(NW.VALVE, pressure_port=pressure_port, work_port=work_port,
                          return_port=return_port, coefficient=self.coefficient,
                          ptr2=transition_pressure ** 2, rate=rate, open=opening, energy=energy, event=event)]


@dataclass(frozen=True)
class Supply:
    r"""The supply node: a pump of constant flow into a hose of volume ``hose_volume`` (a C-type
    volume), the front chamber fed from it through ``front_coefficient``, a relief valve to the tank;
    or a supply held at a pressure (``pump_flow=None``, ``pressure`` given: an ideal pressure
    source).

    Parameters
    ----------
    pump_flow : float or None
        ``Q_p``, ``> 0``; ``None`` with ``pressure`` for a held supply.
    hose_volume : float
        ``V_s``, ``> 0`` (a held supply ignores it).
    front_coefficient : float
        ``K_f``, the front chamber's feed, ``> 0``.
    tank_pressure : float
        :math:`p_t` (absolute), :math:`\ge 0`.
    relief_pressure : float, optional
        ``p_rel``, above the tank pressure; ``inf`` (default): no relief valve.
    relief_coefficient : float, optional
        :math:`K_\mathrm{rel}` of the relief flow :math:`K_\mathrm{rel} \max(0, p_s - p_\mathrm{rel})`,
        :math:`\ge 0`. Default 0.
    pressure : float or None, optional
        The held supply pressure, ``> tank_pressure`` (with ``pump_flow=None``).

    Raises
    ------
    ValueError
        A value out of its range (named); neither or both of ``pump_flow`` and ``pressure``.
    """

    pump_flow: float | None
    hose_volume: float
    front_coefficient: float
    tank_pressure: float
    relief_pressure: float = math.inf
    relief_coefficient: float = 0.0
    pressure: float | None = None

    def __post_init__(self) -> None:
        if (self.pump_flow is None) == (self.pressure is None):
            raise ValueError("give exactly one of pump_flow (a pump) and pressure (a supply held at a "
                             "pressure; the drive's supply_pressure)")
        _positive(self, "hose_volume", "front_coefficient")
        _non_negative(self, "tank_pressure", "relief_coefficient")
        if self.pump_flow is not None:
            _positive(self, "pump_flow")
        else:
            object.__setattr__(self, "pressure", check_real("pressure", self.pressure,
                                                            lo=self.tank_pressure, lo_open=True))
        if not (isinstance(self.relief_pressure, float) and math.isinf(self.relief_pressure)
                and self.relief_pressure > 0):
            relief = check_real("relief_pressure", self.relief_pressure)
            if not relief > self.tank_pressure:  # (either may be the one changed: name both)
                raise ValueError(f"relief_pressure must be above tank_pressure ({self.tank_pressure:g}); got "
                                 f"{relief:g}")
            object.__setattr__(self, "relief_pressure", relief)

    @property
    def held(self) -> bool:
        """Whether the supply is held at :attr:`pressure` (no pump, no state of its own)."""
        return self.pump_flow is None

    @property
    def has_relief(self) -> bool:
        """A relief valve that can open (finite pressure, positive coefficient)."""
        return math.isfinite(self.relief_pressure) and self.relief_coefficient > 0.0

    def records(self, node: int, tank: int, front: int, oil, relief_open: bool = False,
                energies: dict | None = None, relief_event: int = -1) -> list:
        """The supply as network records (:mod:`._network`): its node (the hose; held at its
        pressure for a held supply), the tank's node, the pump, the front chamber's feed and the
        relief valve (always there, as in the compiled kernel: infinitely high without one, and its
        event watched only where it can open).

        Parameters
        ----------
        node, tank, front : int
            The supply's node (a state), the tank's (held at ``tank_pressure``) and the front
            chamber's.
        oil : Oil
        relief_open : bool, optional
            The relief valve's mode.
        energies : dict, optional
            Slots by name: ``"pump"`` (the pump's work, or a held supply's ``p_s`` times its outflow),
            ``"orifices"``, ``"tank"``, ``"compression"``; those left out: none.
        relief_event : int, optional
            The slot of the relief's event (-1: none).

        Returns
        -------
        list of numpy.ndarray
            The supply's node, the tank's, the pump (none for a held supply), the front chamber's feed and
            the relief valve.

        Examples
        --------
        >>> s = Supply(pump_flow=0.5, hose_volume=1.0, front_coefficient=2.0, tank_pressure=0.03)
        >>> len(s.records(2, 3, 0, Oil(100.0, 0.01)))
        5
        """
        en = {"pump": -1, "orifices": -1, "tank": -1, "compression": -1, **(energies or {})}
        return (self.line_records(node, tank, front, oil, en)
                + self.relief_records(node, tank, relief_open, relief_event, en["orifices"]))

    def line_records(self, node: int, tank: int, front: int, oil, energies: dict) -> list:
        """:meth:`records` but the relief valve: the supply's node, the tank's, the pump (none for a
        held supply) and the front chamber's feed (``energies`` by name, each given)."""
        en, beta = energies, oil.bulk_modulus
        out = [NW.record(NW.NODE, id=node, volume=self.hose_volume, beta=beta, held=float(self.held),
                         work_energy=en["pump"], work_sign=-1.0, compression_energy=en["compression"]),
               NW.record(NW.NODE, id=tank, pressure=self.tank_pressure, beta=beta, work_energy=en["tank"])]
        if not self.held:
            out.append(NW.record(NW.PUMP, node=node, flow=self.pump_flow, energy=en["pump"]))
        out.append(NW.record(NW.ORIFICE, source=node, target=front, coefficient=self.front_coefficient,
                             ptr2=oil.transition_pressure ** 2, energy=en["orifices"]))
        return out

    def relief_records(self, node: int, tank: int, relief_open: bool, event: int, energy: int) -> list:
        """:meth:`records`' relief valve from ``node`` to ``tank`` (infinitely high without one; its
        event watched only where it can open), its loss into the slot ``energy``."""
        setting = self.relief_pressure if math.isfinite(self.relief_pressure) else 1e300
        return [NW.record(NW.RELIEF, source=node, target=tank, coefficient=self.relief_coefficient,
                          setting=setting, open=float(relief_open),
                          watched=float(self.has_relief and not self.held), event=event, energy=energy)]


@dataclass(frozen=True)
class Accumulator:
    r"""A gas accumulator on the supply node: below its pre-charge it holds no oil; above it the gas
    (pre-charge :math:`p_0` at volume :math:`V_0`, polytropic exponent :math:`n`) holds
    :math:`V_0 \left(1 - (p_0 / p_s)^{1/n}\right)` of oil, a compliance
    :math:`(V_0 / n) \, p_0^{1/n} p_s^{-1/n - 1}`.

    Parameters
    ----------
    precharge : float
        ``p_0`` (absolute), ``> 0``.
    volume : float
        :math:`V_0`, :math:`\ge 0` (0: no accumulator).
    polytropic_exponent : float, optional
        ``n`` in ``[1, 2]`` (1 isothermal, 1.4 adiabatic nitrogen). Default 1.4.

    Raises
    ------
    ValueError
        A value out of its range (named).
    """

    precharge: float
    volume: float
    polytropic_exponent: float = 1.4

    def __post_init__(self) -> None:
        _positive(self, "precharge")
        _non_negative(self, "volume")
        object.__setattr__(self, "polytropic_exponent", check_real(
            "polytropic_exponent", self.polytropic_exponent, lo=1.0, hi=2.0))

    def records(self, node: int, holding: bool = False, watched: bool = True, energy: int = -1,
                event: int = -1) -> list:
        """The accumulator as a network record (:mod:`._network`) on the node ``node``.

        Parameters
        ----------
        node : int
            The node's number (a state without a chamber).
        holding : bool, optional
            Whether it holds oil (its mode: the node's pressure above the pre-charge).
        watched : bool, optional
            Whether its event (the pressure through the pre-charge) is watched.
        energy, event : int, optional
            The slots of its gas work and of its event (-1: none).

        Returns
        -------
        list of numpy.ndarray
            One record, on ``node``.

        Examples
        --------
        >>> len(Accumulator(1.0, 0.5).records(2, holding=True))
        1
        """
        return [NW.record(NW.ACCUM, node=node, volume=self.volume, precharge=self.precharge,
                          exponent=self.polytropic_exponent, on=float(holding), watched=float(watched),
                          energy=energy, event=event)]


@dataclass(frozen=True)
class Oil:
    r"""The oil: its bulk modulus and the transition pressure of the orifices' smoothed law
    :math:`\phi(\Delta p) = \Delta p \, (\Delta p^2 + p_\mathrm{tr}^2)^{-1/4}` (turbulent,
    :math:`\operatorname{sign}(\Delta p) \sqrt{|\Delta p|}`, for :math:`|\Delta p| \gg p_\mathrm{tr}`,
    differentiable at 0).

    Parameters
    ----------
    bulk_modulus : float
        ``beta``, ``> 0``.
    transition_pressure : float
        ``p_tr``, ``> 0``.

    Raises
    ------
    ValueError
        A value out of its range (named).
    """

    bulk_modulus: float
    transition_pressure: float

    def __post_init__(self) -> None:
        _positive(self, "bulk_modulus", "transition_pressure")
