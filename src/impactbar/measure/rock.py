r"""A rock's loading and unloading stiffness fitted from the force and velocity at a bit.

The bilinear rock of Lundberg (1982, "Microcomputer simulation of stress wave energy transfer to
rock in percussive drilling", *Int. J. Rock Mech. Min. Sci.* 19, 229-239; Karlsson, Lundberg and
Sundin 1989) pushes back on the bit with a force that grows as :math:`dF = k\,du` while the bit
penetrates further than ever (the virgin loading) and as :math:`dF = k_u\,du` on unloading and
reloading below it. Over one sample interval :math:`\Delta F = \kappa\,\Delta u` with
:math:`\Delta u = \int v\,dt` (the trapezoid of the bit's velocity), so each stiffness is the
least-squares slope of the steps of its kind, a linear least squares whose residuals give the
standard error. A step is virgin loading where the force passes its running maximum; steps where a
wave front passes (their slopes beyond ``outlier`` median absolute deviations from the median
slope) are left out. The trapezoid biases the slopes by a relative :math:`O(\Delta t^2)` (the
velocity's curvature within a step), which the standard errors do not count.
"""

from __future__ import annotations

import numpy as np

__all__ = ["fit_bilinear_rock"]


def _slope(dF: np.ndarray, du: np.ndarray, outlier: float, name: str) -> tuple[float, float, int]:
    if dF.size < 3:
        raise ValueError(f"the force-penetration curve has {dF.size} {name} steps (fewer than 3): no "
                         f"{name} stiffness to fit")
    ratio = dF / du
    med = np.median(ratio)
    mad = np.median(np.abs(ratio - med))
    keep = np.abs(ratio - med) <= outlier * max(mad, 1e-12 * abs(med))
    dF, du = dF[keep], du[keep]
    kappa = float(dF @ du / (du @ du))
    resid = dF - kappa * du
    std = float(np.sqrt(resid @ resid / max(1, du.size - 1) / (du @ du)))
    return kappa, std, int(du.size)


def fit_bilinear_rock(force, velocity, dt: float, *, outlier: float = 20.0, contact: float = 0.0) -> dict:
    """The rock's loading and unloading stiffness from the force on the bit and its velocity.

    Parameters
    ----------
    force : array_like, shape (n,) (N)
        The rock's force on the bit (compression positive), e.g. :func:`end_history`'s ``force``.
    velocity : array_like, shape (n,) (m/s)
        The bit's velocity into the rock.
    dt : float (s)
        The sample interval.
    outlier : float
        Steps whose slope lies beyond this many median absolute deviations from the median are
        left out (a wave front within the step).
    contact : float
        Only the steps where the force exceeds this fraction of its peak, in ``[0, 1)``, are read (0:
        every step of positive force; a noisy record's steps out of contact have a force of noise).

    Returns
    -------
    dict
        ``k``, ``k_u`` (N/m), their standard errors ``k_std``, ``k_u_std`` and the steps each used.

    Raises
    ------
    ValueError
        Fewer than 3 steps of virgin loading or of unloading.

    Examples
    --------
    >>> t = np.arange(200) * 1e-3
    >>> v = np.where(t < 0.1, 1.0, -1.0)  # in for 0.1, back out
    >>> u = np.cumsum(np.r_[0, 0.5 * (v[1:] + v[:-1])]) * 1e-3
    >>> f = np.where(t < 0.1, 3.0 * u, 3.0 * u[99] + 6.0 * (u - u[99]))
    >>> fit = fit_bilinear_rock(np.clip(f, 0, None), v, 1e-3)
    >>> round(fit["k"], 9), round(fit["k_u"], 9)
    (3.0, 6.0)
    """
    F, v = np.asarray(force, dtype=float), np.asarray(velocity, dtype=float)
    if F.shape != v.shape:
        raise ValueError(f"force and velocity must be of one length, got {F.size} and {v.size}")
    if not 0.0 <= contact < 1.0:
        raise ValueError(f"contact must lie in [0, 1) (a fraction of the peak force), got {contact!r}")
    dF = np.diff(F)
    du = 0.5 * (v[1:] + v[:-1]) * dt
    floor = contact * F.max() if contact > 0 else 0.0
    on = (F[1:] > floor) & (F[:-1] > floor) & (du != 0)
    virgin = on & (F[1:] > np.maximum.accumulate(F)[:-1])
    elastic = on & ~virgin
    k, k_std, n_k = _slope(dF[virgin], du[virgin], outlier, "loading")
    k_u, k_u_std, n_u = _slope(dF[elastic], du[elastic], outlier, "unloading")
    return {"k": k, "k_std": k_std, "k_u": k_u, "k_u_std": k_u_std, "loading_steps": n_k,
            "unloading_steps": n_u}
