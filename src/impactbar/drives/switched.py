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

from .._shared.validate import check_real

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


def _gap(d: float, y0: float, w0: float, a: float, t: float) -> tuple[float, float]:
    """Gap and its rate after ``t`` under ``y'' + d y' = a`` from ``(y0, w0)`` (closed form)."""
    if d == 0.0:
        return y0 + t * (w0 + 0.5 * a * t), w0 + a * t
    e = math.exp(-d * t)
    b = -math.expm1(-d * t) / d  # int_0^t e^{-d s} ds
    y = d * t
    c = t * t * (0.5 - y / 6.0 + y * y / 24.0 - y**3 / 120.0) if abs(y) < 1e-3 else (t - b) / d
    return y0 + w0 * b + a * c, w0 * e + a * b


def first_rising_crossing(d: float, y0: float, w0: float, a: float, level: float) -> float:
    """First ``t > 0`` at which the gap ``y`` rises through ``level`` under ``y'' + d y' = a``.

    The rate ``y' = w0 e^{-d t} + a b(t)`` is monotone in ``t`` (its derivative ``(a - d w0)
    e^{-d t}`` keeps its sign), so ``y`` has at most one turning point and at most one rising
    crossing of any level: no crossing can be missed. It is bracketed on the rising piece and
    refined to rounding by Newton's method, which converges monotonically there (``y`` is convex
    or concave throughout) (theory §10).

    Parameters
    ----------
    d : float
        Damping, ``>= 0``.
    y0, w0 : float
        Gap and its rate at ``t = 0``.
    a : float
        Constant acceleration of the gap (``-p``).
    level : float
        The switch position.

    Returns
    -------
    float
        The crossing time, ``inf`` if there is none.
    """
    if d == 0.0 and a == 0.0:
        if w0 <= 0.0 or y0 >= level:
            return math.inf
        return (level - y0) / w0
    # the rising piece [t_lo, t_hi] of y (t_hi may be infinite)
    slope = a - d * w0  # sign of y''
    if w0 > 0.0:
        t_lo = 0.0
        if slope >= 0.0:
            t_hi = math.inf
        else:  # y' falls to 0 at t* (if ever)
            t_hi = _rate_zero(d, w0, a)
    else:
        if slope <= 0.0:
            return math.inf  # y' <= 0 for ever
        t_lo = _rate_zero(d, w0, a) if w0 < 0.0 else 0.0
        if not math.isfinite(t_lo):
            return math.inf
        t_hi = math.inf
    y_lo = _gap(d, y0, w0, a, t_lo)[0]
    if y_lo >= level:  # starts at or above the level moving up: no rising crossing ahead
        return math.inf
    if not math.isfinite(t_hi):
        h = max(1.0, t_lo)
        t_hi = t_lo + h
        while _gap(d, y0, w0, a, t_hi)[0] < level:
            h *= 2.0
            t_hi = t_lo + h
            if h > 1e300:  # the gap tends to a finite limit below the level
                return math.inf
    elif _gap(d, y0, w0, a, t_hi)[0] < level:
        return math.inf
    if d == 0.0:  # the rising root of a t^2/2 + w0 t + y0 - level = 0, in its stable form
        r = math.sqrt(max(w0 * w0 + 2.0 * a * (level - y0), 0.0))  # the rate at the crossing
        return 2.0 * (level - y0) / (w0 + r) if w0 >= 0.0 else (r - w0) / a
    # y'' = (a - d w0) e^{-d t} keeps its sign: y is convex or concave. Newton from the end of the
    # bracket on the level's far side converges monotonically to the one root (no overshoot): from
    # the upper end where y is convex, from the lower end where it is concave.
    t = t_hi if slope > 0.0 else t_lo
    sign = 0.0
    for _ in range(200):
        y, w = _gap(d, y0, w0, a, t)
        if w <= 0.0:
            break
        step = (y - level) / w
        if step == 0.0 or step * sign < 0.0:  # an overshoot can only be rounding: done
            break
        sign = step
        t_new = min(max(t - step, t_lo), t_hi)
        if t_new == t:
            break
        t = t_new
    return t


def _rate_zero(d: float, w0: float, a: float) -> float:
    """The time ``y' = 0`` (``inf`` if never): ``w0 e^{-d t} + a b(t) = 0``."""
    if d == 0.0:
        t = -w0 / a if a != 0.0 else math.inf
        return t if t > 0.0 else math.inf
    # w0 e^{-dt} + (a/d)(1 - e^{-dt}) = 0  ->  e^{-dt} = (a/d) / (a/d - w0)
    r = a / d
    den = r - w0
    if den == 0.0:
        return math.inf
    x = r / den
    if not 0.0 < x < 1.0:
        return math.inf
    return -math.log(x) / d
