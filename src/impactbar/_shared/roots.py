"""Brent's root search on a bracket in plain Python floats: the iterates of :func:`scipy.optimize.brentq`.

The package's charts and the wave law's phase scans refine every sign change of a scalar function
by Brent's method. :func:`brentq` here is scipy's algorithm (``scipy/optimize/Zeros/brentq.c``)
operation for operation, so it evaluates the function at the same points and returns the same
root to the bit, without loading :mod:`scipy.optimize` (some 0.4 s of CPU time on a first import,
for this one function). The compiled twin for the wave law's contact windows is
``impactbar.laws.wave._separation._brent``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

__all__ = ["brentq"]

#: scipy's smallest relative tolerance, ``4 eps``
RTOL_MIN = 4.0 * 2.220446049250313e-16


def brentq(f: Callable[[float], float], a: float, b: float, *, xtol: float = 2e-12,
           rtol: float = RTOL_MIN, maxiter: int = 100) -> float:
    """A root of ``f`` in ``[a, b]`` by Brent's method, as :func:`scipy.optimize.brentq`.

    Parameters
    ----------
    f : callable
        ``f(x) -> float`` (``x`` a Python float, in the units of ``a``), continuous on the bracket,
        with ``f(a)`` and ``f(b)`` of opposite signs.
    a, b : float
        The bracket's ends (any units; the root is in the same).
    xtol : float
        Absolute tolerance of the root, ``> 0`` (units of ``a``).
    rtol : float
        Relative tolerance of the root, ``>= 4 eps``.
    maxiter : int
        Iterations at most, ``>= 0``.

    Returns
    -------
    float
        The root, with ``|root - x*| <= xtol + rtol |x*|`` for the exact root ``x*`` (scipy's
        criterion): the same float scipy's ``brentq(f, a, b, xtol=xtol, rtol=rtol, maxiter=maxiter)``
        returns, after evaluating ``f`` at the same points.

    Raises
    ------
    ValueError
        For ``xtol <= 0``, ``rtol < 4 eps`` or ``maxiter < 0``, when ``f(a)`` and ``f(b)`` have the
        same sign, or when ``f`` returns NaN.
    RuntimeError
        Not converged after ``maxiter`` iterations.

    Notes
    -----
    Brent (1973), *Algorithms for minimization without derivatives*, ch. 4; the bracket ``[xblk,
    xcur]`` with the previous iterate ``xpre``, inverse quadratic (or secant) steps accepted while
    they are short, bisection otherwise. Python's float arithmetic is the C double arithmetic of
    scipy's code, so each step is the same float.
    """
    if not xtol > 0.0:
        raise ValueError(f"xtol must be > 0; got {xtol!r}")
    if not rtol >= RTOL_MIN:
        raise ValueError(f"rtol must be >= 4 eps = {RTOL_MIN!r}; got {rtol!r}")
    if maxiter < 0:
        raise ValueError(f"maxiter must be >= 0; got {maxiter!r}")
    xpre, xcur = float(a), float(b)
    fpre, fcur = _value(f, xpre), _value(f, xcur)
    if fpre == 0.0:
        return xpre
    if fcur == 0.0:
        return xcur
    if math.copysign(1.0, fpre) == math.copysign(1.0, fcur):
        raise ValueError("f(a) and f(b) must have different signs")
    xblk = fblk = spre = scur = 0.0
    for _ in range(maxiter):
        if fpre != 0.0 and fcur != 0.0 and math.copysign(1.0, fpre) != math.copysign(1.0, fcur):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # interpolate
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # extrapolate
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):  # a good short step
                spre, scur = scur, stry
            else:  # bisect
                spre = scur = sbis
        else:  # bisect
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur = _value(f, xcur)
    raise RuntimeError(f"Brent's method did not converge in {maxiter} iterations (at x = {xcur!r})")


def _value(f: Callable[[float], float], x: float) -> float:
    """``f(x)`` as a float; NaN refused, as scipy does."""
    fx = float(f(x))
    if math.isnan(fx):
        raise ValueError(f"the function is NaN at x = {x!r}: Brent's method cannot converge")
    return fx
