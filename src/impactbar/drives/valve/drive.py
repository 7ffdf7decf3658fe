"""A drive switched by the piston's position: the hydraulic drifter's valve (theory §10).

The force at the driven end is piecewise constant, ``+stroke`` (toward the stop) or ``-ret`` (away
from it), and the valve changes it when the piston's rigid coordinate crosses a given position, or at
an impact, a time ``delay`` after the triggering event. The system is autonomous: the blow frequency is
an output, not an input as for the time-periodic loads of :mod:`impactbar.loads`.

Positions are measured from the stop along the rigid coordinate: the gap ``y = -q_0`` (``q_0`` the
mean displacement of eq. 15; ``y = 0`` where the undeformed bar touches the stop). Between switches and
impacts every mode moves in closed form under a constant force (eq. 8 with ``p`` constant), and the
rigid coordinate obeys ``y'' + d y' = -p`` alone, so its crossings are found in closed form (theory §10).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

from ..._shared.validate import check_real
from ..abilities import CompiledLoop, DriveAbilities
from ..base import Drive, DriveState, DriveTraits, GapCrossing, TimedEvent
from ._state import _NO_STATE, KIND, RETURN, STROKE, DriveKernelView, _due, initial_valve

_MAX_LEVEL = 1e100  # the largest stroke, ret and switch_out

__all__ = ["PositionSwitchedDrive", "DriveKernelView", "STROKE", "RETURN", "KIND", "first_rising_crossing",
           "initial_valve"]

@dataclass(frozen=True)
class PositionSwitchedDrive(Drive):
    r"""A drive whose force switches on the piston's position (a hydraulic drifter's valve, theory §10).

    The force at ``x = 0`` (eq. 4) is ``p = +stroke`` in the stroke state and ``p = -ret`` in the
    return state. The valve goes

    - from return to stroke when the gap ``y = -q_0`` (the piston's rigid coordinate, measured from
      the stop) rises through ``switch_out`` (on the way out), taking effect ``delay_out`` later;
    - from stroke to return at each impact, taking effect ``delay_in`` later

    (a spool valve's own closing and opening times; ``delay`` gives both). The system is autonomous:
    a periodic motion has an unknown period, found with the impact and switch times
    (:func:`impactbar.find_orbit`), and the blow frequency is an output. Such a drive takes the place
    of a load in :func:`impactbar.simulate`, :func:`impactbar.find_orbit` and
    :func:`impactbar.continue_orbit`; the time-periodic machinery (harmonics,
    :func:`impactbar.periodic_orbits`, sweeps) refuses it.

    As a :class:`~impactbar.Drive` it has no continuous state (``traits.state_size = 0``): its mode is the
    pair ``(valve, pending)``, the valve's state and the switches triggered but not yet in effect
    (``(time, state)`` pairs, sorted); its events are the gap's rising crossing of ``switch_out``
    (a :class:`~impactbar.drives.GapCrossing`, in return with no switch to stroke pending) and the
    first pending switch (a :class:`~impactbar.drives.TimedEvent`). It brings a compiled event loop
    of its own (its :attr:`abilities`, :mod:`impactbar.drives.valve.loop`); the orbit solvers
    hold the closed-form segment problem of its periodic orbits with the exact Jacobian
    (:mod:`impactbar.orbits.valve_segment`, chosen by :data:`impactbar.orbits.driven.ORBIT_PROBLEMS`).

    Rigid piston, no damping, no delay (the check of theory §10): with accelerations :math:`a_s` = ``stroke``,
    :math:`a_r` = ``ret`` and :math:`x_1` = ``switch_out`` the period-1 orbit has the impact velocity
    :math:`v = \sqrt{2 x_1 (a_s + a_r) / (1 - R^2)}`, the period
    :math:`T = (u_1 - R v)/a_r + (u_1 + v)/a_s` with :math:`u_1 = \sqrt{R^2 v^2 + 2 a_r x_1}`, and the
    non-trivial multiplier :math:`R^2`.

    Parameters
    ----------
    stroke : float
        Force toward the stop in the stroke state (dimensionless, eq. 2), ``> 0``.
    ret : float
        Force away from the stop in the return state (dimensionless), ``> 0``.
    switch_out : float
        Gap ``y = -q_0`` (dimensionless, in bar lengths) at which the return force gives way to the
        stroke force on the way out, ``> 0``.
    delay : float, optional
        Valve delay :math:`\tau` (dimensionless time) of both switches: each takes effect this long after
        the crossing or the impact that triggers it, :math:`\ge 0`. Default 0. After construction it is
        the common delay, or ``None`` where ``delay_out`` and ``delay_in`` differ.
    delay_out : float, optional
        The delay of the switch to stroke after the ``switch_out`` crossing (dimensionless time),
        :math:`\ge 0`. Default ``delay``.
    delay_in : float, optional
        The delay of the switch to return after the impact (dimensionless time), :math:`\ge 0`. Default
        ``delay``.

    Raises
    ------
    ValueError
        If a level, position or delay is not finite or out of its range (named in the message):
        with ``stroke`` :math:`\le 0` the piston never reaches the stop, with ``ret`` :math:`\le 0`
        it never reaches the switch position, with ``switch_out`` :math:`\le 0` the valve switches at
        the stop itself; each of the three at most :math:`10^{100}` (beyond, the motion's energies
        leave the float range).

    References
    ----------
    W. Ma et al., "Percussion characteristic analysis for hydraulic rock drill with no
    constant-pressurized chamber through numerical simulation and experiment", Adv. Mech. Eng. 11(4)
    (2019), doi:10.1177/1687814019841486 (the valve switched by the piston's position).
    I. A. Hiskens, M. A. Pai, "Trajectory sensitivity analysis of hybrid systems", IEEE Trans.
    Circuits Syst. I 47(2) (2000) (switching surfaces and their jump conditions).

    Examples
    --------
    >>> from impactbar import PositionSwitchedDrive
    >>> PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0).level(0)
    1.0
    >>> valve = PositionSwitchedDrive(1.0, 1.0, 1.0, delay=0.1, delay_in=0.05)
    >>> valve.delay_out, valve.delay_in, valve.delay
    (0.1, 0.05, None)
    >>> valve.with_(delay=0.2) == PositionSwitchedDrive(1.0, 1.0, 1.0, delay=0.2)
    True
    """

    stroke: float
    ret: float
    switch_out: float
    delay: float | None = 0.0
    delay_out: float | None = None
    delay_in: float | None = None

    traits = DriveTraits(
        kind="position-switched",
        parameters=("stroke", "ret", "switch_out", "delay", "delay_out", "delay_in"),
        parameter_ranges={
            "stroke": {"low": 0.0, "high": _MAX_LEVEL, "low_open": True,
                       "description": "force of the stroke"},
            "ret": {"low": 0.0, "high": _MAX_LEVEL, "low_open": True, "description": "force of the return"},
            "switch_out": {"low": 0.0, "high": _MAX_LEVEL, "low_open": True,
                           "description": "gap at which the valve switches to the return"},
            "delay": {"low": 0.0, "description": "both switching delays (None where they differ)"},
            "delay_out": {"low": 0.0, "description": "delay of the switch to the return"},
            "delay_in": {"low": 0.0, "description": "delay of the switch to the stroke"},
        })

    def __post_init__(self) -> None:
        # (at most 1e100: the motion's squares, energies and forces stay inside the float range)
        for name in ("stroke", "ret", "switch_out"):
            object.__setattr__(self, name, check_real(name, getattr(self, name), lo=0.0, hi=_MAX_LEVEL,
                                                      lo_open=True))
        both = 0.0 if self.delay is None else check_real("delay", self.delay, lo=0.0)
        out = both if self.delay_out is None else check_real("delay_out", self.delay_out, lo=0.0)
        inn = both if self.delay_in is None else check_real("delay_in", self.delay_in, lo=0.0)
        object.__setattr__(self, "delay_out", out)
        object.__setattr__(self, "delay_in", inn)
        object.__setattr__(self, "delay", out if out == inn else None)

    def with_(self, **changes) -> PositionSwitchedDrive:
        """A copy with the given parameters changed (validated again): ``delay`` sets both delays,
        ``delay_out`` and ``delay_in`` one each.

        Raises
        ------
        ValueError
            For a name not in ``traits.parameters`` or a value the constructor refuses.
        """
        names = self.traits.parameters
        bad = sorted(set(changes) - set(names))
        if bad:
            raise ValueError(f"parameter must be one of {names} for a PositionSwitchedDrive; "
                             f"got {bad[0]!r}")
        kw = {"stroke": self.stroke, "ret": self.ret, "switch_out": self.switch_out,
              "delay_out": self.delay_out, "delay_in": self.delay_in}
        if "delay" in changes:
            kw["delay_out"] = kw["delay_in"] = changes.pop("delay")
        kw.update(changes)
        return PositionSwitchedDrive(**kw)

    @cached_property
    def kernel_view(self) -> DriveKernelView:
        """The drive as the compiled valve loop reads it (built once)."""
        return DriveKernelView(self.stroke, self.ret, self.switch_out, self.delay_out, self.delay_in)

    def level(self, state: int) -> float:
        """The force ``p`` in valve state ``state`` (``STROKE = 0``: ``+stroke``; ``RETURN = 1``:
        ``-ret``)."""
        return self.stroke if state == STROKE else -self.ret

    # -- the Drive interface ----------------------------------------------------------------------
    def start(self, model, q, v) -> DriveState:
        """Return while the gap ``-q_0`` is below ``switch_out``, stroke beyond it; nothing pending."""
        return DriveState((initial_valve(self, float(q[0])), ()), _NO_STATE)

    def mode_name(self, mode) -> str:
        """``"stroke"`` or ``"return"``: the valve's state."""
        valve, _ = mode
        return KIND[valve]

    def force(self, mode, z, q, v) -> float:
        """``+stroke`` or ``-ret``, by the valve's state (:meth:`level`)."""
        valve, _ = mode
        return self.level(valve)

    @cached_property
    def _crossing(self) -> GapCrossing:
        return GapCrossing("switch_out", level=self.switch_out, direction=1)

    def events(self, mode) -> tuple:
        """The rising crossing of ``switch_out`` while in return with no switch to stroke pending,
        then the first pending switch."""
        valve, pending = mode
        out = ()
        if valve == RETURN and not any(k == STROKE for _, k in pending):
            out = (self._crossing,)
        if pending:
            t_switch, _ = pending[0]
            out += (TimedEvent("switch", time=t_switch),)
        return out

    def jump(self, mode, z, event, t, q, v) -> DriveState:
        """The crossing triggers the switch to stroke, ``delay_out`` later; the switches due at
        ``t`` take effect."""
        valve, pending = mode
        if event is self._crossing:
            pending = tuple(sorted(pending + ((t + self.delay_out, STROKE),)))
        return DriveState(_due(valve, pending, t), z)

    def impact(self, mode, z, t, q, v) -> DriveState:
        """The impact triggers the switch to return, ``delay_in`` later; the switches due at ``t``
        take effect."""
        valve, pending = mode
        pending = tuple(sorted(pending + ((t + self.delay_in, RETURN),)))
        return DriveState(_due(valve, pending, t), z)

    @property
    def abilities(self) -> DriveAbilities:
        """Its compiled event loop (:meth:`compiled_loop` over the forces :attr:`levels`)."""
        return DriveAbilities(compiled_loop=CompiledLoop(self.levels, self.compiled_loop))

    @property
    def levels(self) -> tuple[float, float]:
        """The forces of the compiled valve loop, by valve state: ``(+stroke, -ret)``."""
        return (self.stroke, -self.ret)

    def compiled_loop(self, model, kernel):
        """The compiled valve loop (:class:`~impactbar.drives.valve.loop.ValveLoop`) under an
        instantaneous law."""
        from .loop import ValveLoop

        return ValveLoop(self, kernel)

    def rigid_orbit(self, R: float) -> dict:
        r"""The rigid, undamped, undelayed period-1 orbit in closed form (theory §10).

        Parameters
        ----------
        R : float
            Restitution coefficient, :math:`0 \le R < 1`.

        Returns
        -------
        dict
            ``impact_velocity`` :math:`v`, ``period`` :math:`T`, ``switch_velocity`` :math:`u_1` (the
            gap's rate at the switch), ``switch_time`` (from the impact), ``multiplier`` :math:`R^2`.
        """
        R = check_real("R", R, lo=0.0, hi=1.0, hi_open=True)
        a_s, a_r, x1 = self.stroke, self.ret, self.switch_out
        v = math.sqrt(2.0 * x1 * (a_s + a_r) / (1.0 - R * R))
        u1 = math.sqrt(R * R * v * v + 2.0 * a_r * x1)
        t1 = (u1 - R * v) / a_r
        return {"impact_velocity": v, "period": t1 + (u1 + v) / a_s, "switch_velocity": u1,
                "switch_time": t1, "multiplier": R * R}


def first_rising_crossing(d: float, y0: float, w0: float, a: float, level: float) -> float:
    r"""First ``t > 0`` at which the gap rises through ``level`` under ``y'' + d y' = a``, ``inf`` if
    never (theory §10).

    The compiled closed form, :func:`impactbar.drives._crossing.first_rising_crossing`, imported on
    first use so that ``import impactbar`` does not load numba.

    Parameters
    ----------
    d, y0, w0, a, level : float
        Damping (:math:`\ge 0`), the gap and its rate at ``t = 0``, the gap's constant acceleration
        (``-p``) and the switch position.

    Returns
    -------
    float
    """
    from .._crossing import first_rising_crossing as compiled

    return float(compiled(float(d), float(y0), float(w0), float(a), float(level)))
