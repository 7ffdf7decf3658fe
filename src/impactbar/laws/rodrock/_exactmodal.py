"""The piston's waves of an exact blow projected on its modes (theory §4d, "in the simulator"): the
integrals of each piston segment's right- and left-going waves against ``e^{i omega theta}`` along the
segment, in closed form per piece (:func:`~impactbar.laws.rodrock._exactintegrals.blk_integral_exp`).
The driver is :func:`impactbar.laws.rodrock.exactmap.project`."""

from __future__ import annotations

import cmath

import numba
import numpy as np

from ..._shared.literals import plain_literals
from ..._shared.wrappers import internal_kernels
from ...dynamics.compiled import CACHE
from ._exactintegrals import blk_integral_exp
from ._exactpieces import DC, piece_span, pool_load
from ._records import PI_COUNT  # the pool's columns


@numba.njit(cache=CACHE, nogil=True)
def piston_integrals(pool, heads, travel, t, om, out):
    """``out[i, n, 0] = int_0^{T_i} F_i(theta) e^{i om_n theta} dtheta`` and ``out[i, n, 1]`` the same of
    ``G_i``, at time ``t``, for each piston segment ``i < travel.size`` (``theta`` the travel time from
    its driven-side end, ``T_i = travel[i]``): ``F_i(theta)`` is the wave that left that end at
    ``t - theta`` (channel ``2 i``), ``G_i(theta)`` the one that left the other end at
    ``t - T_i + theta`` (channel ``2 i + 1``). ``heads[c]`` is a piece of channel ``c`` emitted at or
    before ``t - T_i`` (its first piece, or its receiver's cursor at ``t``). ``pool`` is
    ``(PF, PI, TK, TC, lam, BIN)``."""
    PF, PI, TK, TC, lam, BIN = pool
    E = lam.size
    B = np.zeros((E, DC), dtype=np.complex128)
    N = np.zeros(E, dtype=np.int64)
    for i in range(travel.size):
        T = travel[i]
        lo = t - T
        for side in range(2):
            p = heads[2 * i + side]
            while p >= 0:
                t0, nx, tend, a, b = piece_span(PF, PI, p, lo, t)
                if b > a and PI[p, PI_COUNT] > 0:
                    pool_load(B, N, p, 0.0, lam, BIN, PI, TK, TC)
                    for n in range(om.size):
                        w = om[n]
                        if side == 0:  # theta = t - t0 - tau
                            val = cmath.exp(1j * w * (t - t0)) * blk_integral_exp(B, N, lam, -1j * w,
                                                                                  a - t0, b - t0)
                        else:  # theta = T - t + t0 + tau
                            val = cmath.exp(1j * w * (T - t + t0)) * blk_integral_exp(B, N, lam, 1j * w,
                                                                                      a - t0, b - t0)
                        out[i, n, side] += val
                if tend >= t:
                    break
                p = nx


plain_literals(globals())  # one machine code per kernel for all constant arguments (a shorter compile)
# the kernels Python calls keep their wrapper and cache entry; the others are link-only (for kernels)
internal_kernels(globals(), python=("piston_integrals",))
