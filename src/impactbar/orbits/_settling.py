"""The limit of a map's iterates that converge along one real multiplier (theory §11): how the start
of Newton for a drive with state skips the slow supply mode of the oil circuit."""

from __future__ import annotations

import numpy as np

__all__ = ["dominant_limit", "falling_limit", "drifting", "nearing", "drift_to_surface",
           "expanding_to_surface", "other_period", "SETTLE_DRIFT_IMPACTS", "DRIFT_AHEAD", "DRIFT_REACH",
           "DRIFT_PROBE", "OTHER_PERIODS", "PERIOD_CONTRAST"]

#: the dominant-mode extrapolation of :func:`dominant_limit` is taken where each of the last two
#: steps is a multiple ``rho`` of the one before to this fraction of its size, the two multiples
#: agree to ``DOMINANT_AGREE (1 - rho)`` (the map is linear enough there for the limit
#: ``1 / (1 - rho)`` to be right to about 10 %) and ``|rho| < DOMINANT_RHO``
DOMINANT_FIT = 0.02
DOMINANT_AGREE = 0.1
DOMINANT_RHO = 0.995


#: the most impacts the motion to Newton's start is followed while the drive's state drifts
#: (:func:`drifting`): the oil circuit's supply pressure charging a large accumulator toward its relief
#: valve's setting, some 4e-4 of the pressure scale an impact on a 50 L accumulator
SETTLE_DRIFT_IMPACTS = 20000
#: impacts of the drift's last step ahead of the state where a surface of its mode must not lie for
#: Newton to take over (the supply pressure charging toward the relief valve's setting: Newton's
#: root in the relief's closed mode lies past it)
DRIFT_AHEAD = 10.0
#: the farthest :func:`drift_to_surface` carries a steady drift at once, relative to the state's size
#: (at least 1): the oil circuit's supply pressure charging a 500 L accumulator by some 4e-5 of the
#: pressure scale an impact, 0.6 of it from the pre-charge to the relief valve's setting
DRIFT_REACH = 1.0
#: bisection steps of :func:`drift_to_surface` toward the surface (its distance to 2^-50 of the reach)
DRIFT_BISECTIONS = 50
#: impacts more the motion is followed where its drift heads for a surface (:func:`nearing`) but its
#: steps do not yet fit one multiple (its fast parts still settling: one impact on the 500 L
#: accumulator's, three on the 5000 L accumulator's)
DRIFT_PROBE = 8
#: the most impacts per period :func:`other_period` looks for in the impact velocities of a motion
#: followed to a one-impact start
OTHER_PERIODS = 8
#: how much more an other period's impact velocities differ impact to impact than from one cycle to
#: the next, at least, for :func:`other_period` to call the motion settled into that period: a
#: decaying oscillation of real multiplier ``lambda < 0`` about a one-impact orbit has the ratio
#: ``|lambda| / (1 - |lambda|)`` (``k = 2``), so that only one of ``|lambda| > 0.95`` (beyond the
#: optimiser's default limit, near its period doubling) could pass for one
PERIOD_CONTRAST = 20.0


def other_period(speeds, tol: float, most: int = OTHER_PERIODS) -> int:
    """The impacts per period of a motion whose impact velocities repeat every ``k > 1`` impacts but
    not every impact (a period-``k`` motion, a double blow, a blow with its chatter): 0 where there is
    none (still settling, too few velocities, or one impact per period).

    The smallest ``k`` from 2 to ``most`` (with at least ``4 k + 1`` velocities) for which the last
    ``2 k`` velocities each repeat the one
    ``k`` impacts before to ``tol`` (relative, at least 1), the velocities within the last cycle
    differ from impact to impact :data:`PERIOD_CONTRAST` times more than that (and above ``tol``),
    and that difference has shrunk since the cycle before by no more than the velocities' change over a
    cycle (a decaying oscillation about a one-impact orbit shrinks by about twice that; a period-``k``
    motion's cycle drifts with the oil's supply pressure, its difference shrinking by some 5 % of that
    change). A design of the example rock drifter beside the optimiser's optimum
    (docs/optimising_a_drifter.md), followed from rest: the velocities alternate 0.16 % apart after
    some 15 impacts, a cycle repeating to 1e-5 at the 20th impact and to 2e-8 at the 400th.

    Parameters
    ----------
    speeds : sequence of float
        Consecutive impact velocities (dimensionless), the last the newest.
    tol : float
        Relative agreement of a velocity with the one a cycle before, ``> 0``.
    most : int
        The largest period looked for.

    Returns
    -------
    int
        ``k``, or 0.

    Examples
    --------
    >>> from impactbar.orbits._settling import other_period
    >>> other_period([0.5, 0.4] * 5, 1e-4), other_period([0.5, 0.4] * 2, 1e-4), other_period([0.5] * 9, 1e-4)
    (2, 0, 0)
    """
    s = np.asarray(speeds, dtype=float)
    for k in range(2, most + 1):
        if s.size < 4 * k + 1:
            return 0
        scale = max(1.0, float(np.max(np.abs(s[-2 * k:]))))
        again = float(np.max(np.abs(s[-2 * k:] - s[-3 * k:-k])))
        step = np.abs(np.diff(s[-4 * k - 1:]))
        last, before = float(np.max(step[-k:])), float(np.max(step[-2 * k:-k]))
        contrast = last > max(PERIOD_CONTRAST * again, tol * scale)
        if again <= tol * scale and contrast and before - last <= again:
            return k
    return 0


def drifting(y0, y1, y2, tol: float) -> bool:
    """Whether three iterates of a map (every ``m``-th state after an impact) still drift: the last
    step is above ``tol`` of the state (relative, at least 1) and not shrinking, a multiple of at
    least :data:`DOMINANT_RHO` of the step before.

    Such a drift is a mode of multiplier near (or above) 1 far from the orbit: the oil circuit's
    supply pressure charging a large accumulator from its pre-charge, its steps growing as the gas
    stiffens, toward the relief valve's setting where it stops. The impact velocities may repeat to
    ``tol`` meanwhile (the blow barely feels the supply pressure's slow rise), but Newton's linear
    model of that mode cannot see the relief's kink some MPa away: its step goes the other way, to
    negative pressures. The motion is followed on instead (theory §11).

    Parameters
    ----------
    y0, y1, y2 : numpy.ndarray, shape (n,)
        Consecutive iterates (dimensionless).
    tol : float
        Relative size of a step that counts as settled.

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> drifting(np.array([1.0]), np.array([1.001]), np.array([1.002001]), 1e-4)
    True
    >>> drifting(np.array([1.0]), np.array([1.001]), np.array([1.0019]), 1e-4)
    False
    """
    d2 = y2 - y1
    if not float(np.linalg.norm(d2)) > tol * max(1.0, float(np.linalg.norm(y2))):
        return False
    rho = _ratio(y1 - y0, d2)
    return rho is not None and rho >= DOMINANT_RHO


def nearing(drive, mode, y0, y1, y2, M: int) -> bool:
    """Whether three iterates of a map near a switching surface of ``mode`` in a steady drift: the
    surface still ahead of the last (as :func:`surfaces_ahead` reads it) and its value, signed by its
    direction, rising by two steps of one size (the last within ``1 -`` :data:`DOMINANT_RHO` of the
    one before).

    It tells, where the motion's impacts repeat to the hand-over's tolerance, whether a drift too slow
    to tell there (:func:`drifting`) heads for a surface, so that the motion is followed a few
    impacts more (:data:`DRIFT_PROBE`) for :func:`drift_to_surface`. The surface's value sees that
    drift alone: the oil circuit's supply pressure charging a 5000 L accumulator by the same 4.05e-6
    of the relief's pressure scale impact after impact (two steps within 3e-6 of each other) while
    the state's step is still half the fast parts' settling (the last step 0.83 times the one before
    along it, 39 % of it off that multiple): the state's steps fit one multiple three impacts later.

    Parameters
    ----------
    drive, mode, y0, y1, y2, M
        As :func:`drift_to_surface` takes them: the drive, its discrete state at the three iterates,
        the iterates (dimensionless, shape ``(2 M + k,)``) and the modes' count.

    Returns
    -------
    bool
        Whether a surface nears in a steady drift (the motion then followed on).

    Examples
    --------
    >>> import numpy as np
    >>> from impactbar.drives.base import SurfaceEvent
    >>> class Drive:
    ...     def events(self, mode):
    ...         return (SurfaceEvent("top", direction=1, function=lambda t, q, v, z: z[0] - 1.0),)
    >>> y = [np.array([0.0, 0.0, z]) for z in (0.2, 0.3, 0.4)]
    >>> nearing(Drive(), 0, *y, 1)
    True
    >>> nearing(Drive(), 0, y[0], y[1], np.array([0.0, 0.0, 0.35]), 1)  # (the step halved)
    False
    """
    for g0, g1, g2 in zip(*(_surface_values(drive, mode, y, M) for y in (y0, y1, y2)), strict=True):
        s1, s2 = g1 - g0, g2 - g1
        if g2 <= 0.0 and s1 > 0.0 and abs(s2 - s1) <= (1.0 - DOMINANT_RHO) * s1:
            return True
    return False


def drift_to_surface(drive, mode, y0, y1, y2, M: int):
    """The state that a steady drift of three iterates of a map reaches just short of a switching
    surface of ``mode`` (the first along its last step), where that surface lies short of the drift's
    linear limit: the motion carried there at once instead of followed, or ``None``.

    A drift whose steps are each a multiple ``rho >=`` :data:`DOMINANT_RHO` of the step before (a
    mode of multiplier near or above 1) may be too slow for :func:`drifting` to tell it at its
    tolerance: the oil circuit's 500 L accumulator charging from its pre-charge by some 4e-5 of the
    pressure an impact, its impact velocities repeating to 1e-5, some 15,000 impacts from the relief
    valve's setting. Newton's linear model of that mode (its limit ``y2 + rho / (1 - rho) d``, none
    ahead for ``rho >= 1``) cannot see the relief's kink: its step goes to negative pressures. The
    drift is carried along its last step ``d = y2 - y1`` to the first surface of ``mode`` that a
    state ``y2 + s d`` crosses (:func:`surfaces_ahead`), ``s`` no farther than that limit nor than
    :data:`DRIFT_REACH` times the state's size (at least 1), and from there the motion is followed
    on: its fast parts settle in a few impacts.

    Parameters
    ----------
    drive : Drive
    mode : object
        The drive's discrete state at the three iterates.
    y0, y1, y2 : numpy.ndarray, shape (2 M + k,)
        Consecutive iterates (dimensionless).
    M : int

    Returns
    -------
    numpy.ndarray, shape (2 M + k,), or None
        ``y2 + s d`` on the near side of the surface (to 2^-50 of the reach); ``None`` where the
        last step is not a multiple of at least :data:`DOMINANT_RHO` of the one before to
        :data:`DOMINANT_FIT` of its size (the fast parts still settling: :func:`nearing` tells whether
        to follow the motion on), no surface lies within reach or the drift reaches it within
        :data:`DRIFT_AHEAD` steps (the motion followed on gets there).
    """
    d = y2 - y1
    rho = _ratio(y1 - y0, d)
    size = float(np.linalg.norm(d))
    if rho is None or rho < DOMINANT_RHO or not size > 0.0:
        return None
    reach = DRIFT_REACH * max(1.0, float(np.linalg.norm(y2))) / size
    if rho < 1.0:
        reach = min(reach, rho / (1.0 - rho))
    if surfaces_ahead(drive, mode, y2 + reach * d, M):
        return None
    lo, hi = 0.0, reach
    for _ in range(DRIFT_BISECTIONS):
        mid = 0.5 * (lo + hi)
        if surfaces_ahead(drive, mode, y2 + mid * d, M):
            lo = mid
        else:
            hi = mid
    return y2 + lo * d if lo > DRIFT_AHEAD else None


def expanding_to_surface(drive, mode, y0, y1, y2, y3, M: int):
    """Where four iterates of a map move away along one real multiplier above 1, the state their
    drift reaches just short of a switching surface of ``mode`` (:func:`drift_to_surface` of the last
    three), else ``None``.

    Each of the last two steps a multiple ``rho > 1 +`` :data:`DOMINANT_FIT` of the one before (a
    growth the fit of one multiple tells from 1): the map expands along that mode there, its linear
    model has no fixed point ahead (:func:`dominant_limit` has none) and the motion drifts on until
    a surface stops it. The oil circuit's spool drill from rest (``examples/circuit_drill_spool.toml``):
    the supply pressure's steps grow by 5 % to 1.4 % an impact as it charges from the pre-charge
    (1.08 to 2.44 of the pressure scale in 15 impacts) until the relief valve opens at its setting,
    where its orbit lies; carried there at once, the motion is followed on from the surface (theory
    §11). A drive whose steps' multiple is below ``1 + DOMINANT_FIT`` (the preset's, from 1.003 to
    0.92) is left to :func:`dominant_limit`.

    Parameters
    ----------
    drive : Drive
    mode : object
        The drive's discrete state at the four iterates.
    y0, y1, y2, y3 : numpy.ndarray, shape (2 M + k,)
        Consecutive iterates (dimensionless).
    M : int

    Returns
    -------
    numpy.ndarray, shape (2 M + k,), or None
        :func:`drift_to_surface` of ``y1, y2, y3`` where both steps' multiples exceed
        ``1 + DOMINANT_FIT``; ``None`` otherwise.

    Examples
    --------
    A drive whose one surface is ``z[0] = 1.5``, approached by steps growing by 5 %:

    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from impactbar.drives.base import SurfaceEvent
    >>> top = SurfaceEvent("top", direction=1, function=lambda t, q, v, z: z[0] - 1.5)
    >>> drive = SimpleNamespace(events=lambda mode: (top,))
    >>> y = [np.array([0.0, 0.0, z]) for z in (1.0, 1.01, 1.0205, 1.031525)]
    >>> z = float(expanding_to_surface(drive, 0, *y, 1)[2])  # (just short of the surface)
    >>> z <= 1.5, round(z, 9)
    (True, 1.5)
    >>> y[3] = np.array([0.0, 0.0, 1.0308])  # (the multiple falls to 1.019: a limit may lie ahead)
    >>> expanding_to_surface(drive, 0, *y, 1) is None
    True
    """
    r1, r2 = _ratio(y1 - y0, y2 - y1), _ratio(y2 - y1, y3 - y2)
    if r1 is None or r2 is None or not min(r1, r2) > 1.0 + DOMINANT_FIT:
        return None
    return drift_to_surface(drive, mode, y1, y2, y3, M)


def _ratio(d1, d2):
    """``rho`` with ``d2 = rho d1`` in least squares, or None where that does not fit."""
    n1 = float(d1 @ d1)
    if not n1 > 0.0:
        return None
    rho = float(d1 @ d2) / n1
    if float(np.linalg.norm(d2 - rho * d1)) > DOMINANT_FIT * float(np.linalg.norm(d2)):
        return None
    return rho


def dominant_limit(y0, y1, y2, y3):
    """The limit of four iterates of a map that converge along one real multiplier (theory §11).

    Parameters
    ----------
    y0, y1, y2, y3 : numpy.ndarray, shape (n,)
        Consecutive iterates (the states after successive impacts; dimensionless).

    Returns
    -------
    numpy.ndarray, shape (n,), or None
        ``y3 + rho / (1 - rho) (y3 - y2)`` (Aitken's delta-squared in vector form, as in
        Steffensen's method) where each of the last two steps is one multiple ``rho`` of the step
        before (:data:`DOMINANT_FIT`, :data:`DOMINANT_AGREE`, ``|rho| <`` :data:`DOMINANT_RHO`);
        where the multiple falls from one step to the next (the map not yet linear, its steps
        shrinking faster as they near its fixed point, where Aitken's limit overshoots), the fixed
        point of the quadratic through the three steps along the last (:func:`falling_limit`);
        ``None`` where they do not fit one multiplier (a complex pair, two modes of one size, a
        multiple that grows) or that quadratic has no fixed point short of Aitken's.
    """
    d1, d2, d3 = y1 - y0, y2 - y1, y3 - y2
    r1, r2 = _ratio(d1, d2), _ratio(d2, d3)
    if r1 is None or r2 is None or not abs(r2) < DOMINANT_RHO:
        return None
    if abs(r2 - r1) <= DOMINANT_AGREE * (1.0 - r2):
        return y3 + r2 / (1.0 - r2) * d3
    if 0.0 < r2 < r1:
        return falling_limit(y0, y1, y2, y3)
    return None


def falling_limit(y0, y1, y2, y3):
    """The fixed point of the quadratic through the map's three steps of four iterates, along the last
    step: where the steps' multiple falls as the iterates near the map's fixed point (the oil
    circuit's supply pressure from rest: 0.998, 0.994, 0.991, ... on to 0.92 at the orbit), Aitken's
    limit from the last two steps overshoots, by a factor near 1.5 there.

    With ``u`` the last step's direction and ``s_k = u . y_k``, the map along ``u`` is taken as the
    quadratic ``g`` with ``g(s_k) = s_(k+1)``, ``k = 0, 1, 2``; its fixed point nearest ahead of
    ``s_3`` is the limit, where it lies no farther than Aitken's (the multiple ``rho`` of the last
    step) and the quadratic's slope there is below 1 in size (a fixed point that attracts).

    Parameters
    ----------
    y0, y1, y2, y3 : numpy.ndarray, shape (n,)
        Consecutive iterates whose steps are each a multiple of the one before (as
        :func:`dominant_limit` checks).

    Returns
    -------
    numpy.ndarray, shape (n,), or None
        ``y3 + e u``; ``None`` where the quadratic has no such fixed point.
    """
    d3 = y3 - y2
    size = float(np.linalg.norm(d3))
    if not size > 0.0:
        return None
    u = d3 / size
    s = np.array([float(u @ y) for y in (y0, y1, y2, y3)]) - float(u @ y3)
    x, g = s[:3], s[1:]  # G(x) = g(s_3 + x) - s_3 through (x_k, G(x_k)), k = 0, 1, 2
    if not (x[0] < x[1] < x[2] < 0.0):  # (the iterates must advance along u)
        return None
    a, b, c = np.polyfit(x, g, 2)
    rho = _ratio(y2 - y1, d3)
    if rho is None or not 0.0 < rho < 1.0:
        return None
    reach = rho / (1.0 - rho) * size  # Aitken's
    roots = np.roots([a, b - 1.0, c])
    ahead = [float(r.real) for r in roots if abs(r.imag) <= 1e-12 * max(1.0, abs(r.real))
             and 0.0 < r.real <= reach and abs(2.0 * a * r.real + b) < 1.0]
    if not ahead:
        return None
    return y3 + min(ahead) * u


def surfaces_ahead(drive, mode, y, M: int, tol: float = 0.0) -> bool:
    """Whether the state ``y = (q, q', z)`` (``M`` modes) lies on the near side of each of ``mode``'s
    surface events (``direction * value <= 0``: a crossing in the event's direction is still ahead),
    as a flight in ``mode`` needs: past one (the oil circuit's supply pressure above the relief
    pressure with the relief valve's flag closed) the flight never fires it, and its motion is not the
    drive's.

    Parameters
    ----------
    drive : Drive
    mode : object
        The drive's discrete state.
    y : numpy.ndarray, shape (2 M + k,)
    M : int
    tol : float, optional
        How far past a surface still counts as on it.

    Returns
    -------
    bool
    """
    return all(g <= tol for g in _surface_values(drive, mode, y, M))


def _surface_values(drive, mode, y, M: int) -> list:
    """``direction * value`` of each of ``mode``'s surface events at the state ``y = (q, q', z)``
    (``M`` modes), in the drive's order: at most 0 where a crossing in the event's direction is
    still ahead."""
    from ..drives.base import SurfaceEvent

    q, v, z = y[:M], y[M:2 * M], y[2 * M:]
    return [e.direction * e.value(0.0, q, v, z) for e in drive.events(mode) if isinstance(e, SurfaceEvent)]
