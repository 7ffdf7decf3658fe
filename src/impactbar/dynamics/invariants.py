"""The piston's fields as Riemann invariants (theory §4c): the modal state of the struck bar, ``u = q_0
+ 2 sum q_n cos(n pi x)``, as the invariants ``alpha0(x), beta0(x)`` that the characteristics carry,
with the static correction of the drive force at ``x = 0``. The shared starting point of every law
that follows the blow along characteristics: the wave law's contact window
(:mod:`impactbar.laws.wave`) and the rod-rock law's blow (:mod:`impactbar.laws.rodrock`)."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["PistonInvariants"]


class PistonInvariants:
    """The piston's state at impact as the Riemann invariants ``alpha0(x), beta0(x)``: the modal sums
    (``u = q_0 + 2 sum q_n cos(n pi x)``) plus the static correction that carries the drive force
    ``p_end`` at ``x = 0`` (theory §4c).

    The strain of a cosine series vanishes at both ends, while the true strain at ``x = 0`` is
    ``-p_end / s^2``. The truncated modes ``n > N`` respond quasi-statically to the end force, so
    their strain is the inertia-relief static strain ``eps_s = -p_end (1 - x)/s^2`` less its first
    ``N`` sine terms (the mode-acceleration, or static-correction, method):

        s u_x = sum_{n=1}^N (b_n + 2 p_end/(s n pi)) sin(n pi x) - (p_end/s)(1 - x),

    stored as the coefficients ``b_n`` and ``b[0] = -p_end/s``, the coefficient of ``(1 - x)``
    (``sin(0) = 0`` leaves that slot free). The correction has no projection on the modes kept, so
    the modal state is unchanged; the force at ``x = 0`` is the drive's, and the invariant arriving
    at the rod has no spurious spike at ``theta = 1``.

    Parameters
    ----------
    s : float
        The bar's slenderness (eq. 2).
    q, v : array_like, shape (N + 1,)
        The modal displacements and velocities at impact (dimensionless).
    p_end : float, optional
        The drive's force at ``x = 0`` (dimensionless, eq. 2), default 0.
    """

    def __init__(self, s: float, q, v, p_end: float = 0.0):
        q = np.asarray(q, dtype=float)
        v = np.asarray(v, dtype=float)
        self.npi = math.pi * np.arange(q.size)
        self.a = v.copy()  # velocity = sum a_n cos(n pi x)
        self.a[1:] *= 2.0
        self.b = -2.0 * s * self.npi * q  # s * strain = sum b_n sin(n pi x) + b_0 (1 - x)
        self.b[1:] += 2.0 * p_end / (s * self.npi[1:])
        self.b[0] = -p_end / s

    @property
    def static_energy(self) -> float:
        """Strain energy of the static correction (orthogonal to the modes kept):
        ``(1/2) (p_end/s)^2 int_0^1 ((1 - x) - sum_{n<=N} 2 sin(n pi x)/(n pi))^2 dx``."""
        n = np.arange(1, self.npi.size)
        return 0.5 * self.b[0] ** 2 * (1.0 / 3.0 - float(np.sum(2.0 / (math.pi * n) ** 2)))

    def _cs(self, x):
        arg = np.multiply.outer(np.asarray(x, dtype=float), self.npi)
        return np.cos(arg), np.sin(arg)

    def _strain(self, x, S):
        """``s u_x`` at ``x`` from the sines ``S`` (the static part's ``(1 - x)`` in slot 0)."""
        return S[..., 1:] @ self.b[1:] + self.b[0] * (1.0 - np.asarray(x, dtype=float))

    def alpha(self, x):
        C, S = self._cs(x)
        return C @ self.a - self._strain(x, S)

    def beta(self, x):
        C, S = self._cs(x)
        return C @ self.a + self._strain(x, S)

    def alpha1(self, x: float) -> float:
        """``alpha0(x)`` for one ``x``."""
        arg = self.npi * x
        return (float(np.cos(arg) @ self.a) - float(np.sin(arg[1:]) @ self.b[1:])
                - self.b[0] * (1.0 - x))

    def beta1(self, x: float) -> float:
        """``beta0(x)`` for one ``x``."""
        arg = self.npi * x
        return (float(np.cos(arg) @ self.a) + float(np.sin(arg[1:]) @ self.b[1:])
                + self.b[0] * (1.0 - x))

    def int1(self, x: float, sign: float) -> float:
        """``int_0^x alpha0`` (``sign = 1``) or ``int_0^x beta0`` (``sign = -1``) for one ``x``."""
        arg = self.npi[1:] * x
        k = self.npi[1:]
        out = self.a[0] * x + float(np.sin(arg) @ (self.a[1:] / k))
        out += sign * float((np.cos(arg) - 1.0) @ (self.b[1:] / k))
        return out - sign * self.b[0] * (x - 0.5 * x * x)

    def _int(self, x, sign):
        x = np.asarray(x, dtype=float)
        C, S = self._cs(x)
        k = self.npi[1:]
        out = self.a[0] * x + S[..., 1:] @ (self.a[1:] / k)
        out = out + sign * ((C[..., 1:] - 1.0) @ (self.b[1:] / k))
        return out - sign * self.b[0] * (x - 0.5 * x * x)

    def int_alpha(self, x):
        """``int_0^x alpha0``."""
        return self._int(x, 1.0)

    def int_beta(self, x):
        """``int_0^x beta0``."""
        return self._int(x, -1.0)
