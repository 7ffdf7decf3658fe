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

from .._shared.validate import check_real
from ..dynamics.kernelview import DriveKernelView

__all__ = ["PositionSwitchedDrive", "STROKE", "RETURN", "first_rising_crossing"]

#: The valve's two states (indices into :meth:`PositionSwitchedDrive.level`).
STROKE = 0
RETURN = 1


@dataclass(frozen=True)
class PositionSwitchedDrive:
    r"""A drive whose force switches on the piston's position (a hydraulic drifter's valve, theory §10).

    The force at ``x = 0`` (eq. 4) is ``p = +stroke`` in the stroke state and ``p = -ret`` in the
    return state. The valve goes

    - from return to stroke when the gap ``y = -q_0`` (the piston's rigid coordinate, measured from
      the stop) rises through ``switch_out`` (on the way out);
    - from stroke to return at each impact;

    each switch taking effect ``delay`` after the event that triggers it. The system is autonomous:
    a periodic motion has an unknown period, found with the impact and switch times
    (:func:`impactbar.find_orbit`), and the blow frequency is an output. Such a drive takes the place
    of a load in :func:`impactbar.simulate` and :func:`impactbar.find_orbit`; the time-periodic
    machinery (harmonics, :func:`impactbar.periodic_orbits`, sweeps) refuses it.

    Rigid piston, no damping, no delay (the check of theory §10): with accelerations ``a_s = stroke``,
    ``a_r = ret`` the period-1 orbit has the impact velocity
    ``v = sqrt(2 x_1 (a_s + a_r) / (1 - R^2))``, the period
    ``T = (u_1 - R v)/a_r + (u_1 + v)/a_s`` with ``u_1 = sqrt(R^2 v^2 + 2 a_r x_1)``, and the
    non-trivial multiplier ``R^2``.

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
        Valve delay ``tau`` (dimensionless time): each switch takes effect this long after the
        crossing or the impact that triggers it, ``>= 0``. Default 0.

    Raises
    ------
    ValueError
        If a level or position is not finite or out of its range (named in the message): with
        ``stroke <= 0`` the piston never reaches the stop, with ``ret <= 0`` it never reaches the
        switch position, with ``switch_out <= 0`` the valve switches at the stop itself.

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
    """

    stroke: float
    ret: float
    switch_out: float
    delay: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "stroke", check_real("stroke", self.stroke, lo=0.0, lo_open=True))
        object.__setattr__(self, "ret", check_real("ret", self.ret, lo=0.0, lo_open=True))
        object.__setattr__(self, "switch_out", check_real("switch_out", self.switch_out, lo=0.0,
                                                          lo_open=True))
        object.__setattr__(self, "delay", check_real("delay", self.delay, lo=0.0))

    @cached_property
    def kernel_view(self) -> DriveKernelView:
        """The drive as the compiled valve loop reads it (built once)."""
        return DriveKernelView(self.stroke, self.ret, self.switch_out, self.delay)

    def level(self, state: int) -> float:
        """The force ``p`` in valve state ``state`` (``STROKE = 0``: ``+stroke``; ``RETURN = 1``:
        ``-ret``)."""
        return self.stroke if state == STROKE else -self.ret

    def harmonics(self, n=None):
        """Refused: the drive is not a function of time (theory §10)."""
        raise ValueError("a PositionSwitchedDrive is not periodic in time: it has no harmonics "
                         "(use simulate or find_orbit with it, theory §10)")

    def rigid_orbit(self, R: float) -> dict:
        """The rigid, undamped, undelayed period-1 orbit in closed form (theory §10).

        Parameters
        ----------
        R : float
            Restitution coefficient, ``0 <= R < 1``.

        Returns
        -------
        dict
            ``impact_velocity`` ``v``, ``period`` ``T``, ``switch_velocity`` ``u_1`` (the gap's
            rate at the switch), ``switch_time`` (from the impact), ``multiplier`` ``R^2``.
        """
        R = check_real("R", R, lo=0.0, hi=1.0, hi_open=True)
        a_s, a_r, x1 = self.stroke, self.ret, self.switch_out
        v = math.sqrt(2.0 * x1 * (a_s + a_r) / (1.0 - R * R))
        u1 = math.sqrt(R * R * v * v + 2.0 * a_r * x1)
        t1 = (u1 - R * v) / a_r
        return {"impact_velocity": v, "period": t1 + (u1 + v) / a_s, "switch_velocity": u1,
                "switch_time": t1, "multiplier": R * R}


def first_rising_crossing(d: float, y0: float, w0: float, a: float, level: float) -> float:
    """First ``t > 0`` at which the gap rises through ``level`` under ``y'' + d y' = a``, ``inf`` if
    never (theory §10).

    The compiled closed form of the valve loop,
    :func:`impactbar.dynamics._switchkernel.first_rising_crossing`, imported on first use so that
    ``import impactbar`` does not load numba.

    Parameters
    ----------
    d, y0, w0, a, level : float
        Damping (``>= 0``), the gap and its rate at ``t = 0``, the gap's constant acceleration
        (``-p``) and the switch position.

    Returns
    -------
    float
    """
    from ..dynamics._switchkernel import first_rising_crossing as compiled

    return float(compiled(float(d), float(y0), float(w0), float(a), float(level)))
