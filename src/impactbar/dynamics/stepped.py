r"""A piston of uniform segments and its exact free-free modes (theory §12).

Real drifter and down-the-hole pistons are stepped: a head, a neck, a tail of different cross-sections,
whose impedances shape the stress wave sent into the rod (Lundberg & Okrouhlik; Chiang & Stamm 1998).
Each segment is a uniform bar of the same material, so that the wave speed is the same in every
segment and only the cross-section, hence the impedance :math:`Z = \rho c A`, changes at a step. In
the piston's dimensionless units (length 1, wave-speed ratio :math:`s`) the displacement obeys
:math:`u_{tt} = s^2 u_{xx}` inside each segment, with displacement and force :math:`F = z\,u_x`
continuous at every step (:math:`z` the segment's impedance relative to the first) and no force at
either end.

In a segment of length :math:`l` a harmonic motion of wavenumber :math:`k` (frequency
:math:`\omega = s k`) carries the state :math:`(u, F)` across by the transfer matrix

.. math::

   T(k) = \begin{pmatrix} \cos kl & \sin(kl)/(z k) \\ -z k \sin kl & \cos kl \end{pmatrix},

and a free-free mode is a :math:`k` at which the product of the segments' matrices, applied to
:math:`(1, 0)`, gives zero force at the far end: the frequency equation
:math:`F_{end}(k) = [T_n(k) \cdots T_1(k)]_{21} = 0`. Its roots are bracketed on a grid finer than any
two roots can be (Sturm-Liouville: the :math:`n`-th mode has exactly :math:`n` nodes, which
:meth:`SteppedPiston.modes` checks for every mode it returns, so that no root is missed), and refined
with :func:`scipy.optimize.brentq`. The modes are normalised in the mass inner product
:math:`\int_0^1 \mu(x)\,\phi_m \phi_n\,dx = \delta_{mn}` with the mass per length :math:`\mu`
proportional to :math:`z` and the piston's mass 1. A single segment is the uniform bar: :math:`k_n =
n\pi`, :math:`\phi_n = \sqrt 2 \cos(n\pi x)`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["SteppedPiston", "PistonModes", "StickingBasis"]

#: the most modes :meth:`SteppedPiston.modes` computes (as the uniform bar's models allow)
MAX_MODES = 4096
#: the largest ratio of two segments' impedances: beyond, a mode lives in one segment alone and the
#: frequency equation loses its roots in rounding
MAX_IMPEDANCE_RATIO = 1e6


@dataclass(frozen=True)
class PistonModes:
    r"""Free-free modes of a stepped piston (theory §12).

    Attributes
    ----------
    wavenumbers : numpy.ndarray, shape (N + 1,)
        :math:`k_0 = 0 < k_1 < \dots < k_N` (dimensionless, per piston length); the frequencies are
        :math:`s k_n`.
    amplitudes : numpy.ndarray, shape (N + 1, n_segments, 2)
        Mode :math:`n` in segment :math:`j` is :math:`a \cos(k_n (x - x_j)) + b \sin(k_n (x - x_j))`
        with ``(a, b) = amplitudes[n, j]`` and :math:`x_j` the segment's start; mass-orthonormal.
    piston : SteppedPiston
        The piston they belong to.

    Examples
    --------
    >>> from impactbar import SteppedPiston
    >>> modes = SteppedPiston([0.3, 0.7], [2.0, 1.0]).modes(4)
    >>> modes.shapes([0.0, 1.0]).shape  # two positions, modes 0..4
    (2, 5)
    """

    wavenumbers: np.ndarray
    amplitudes: np.ndarray
    piston: SteppedPiston

    def __repr__(self) -> str:
        n = self.wavenumbers.size - 1
        return (f"PistonModes({self.piston.n_segments} segments, modes 0..{n}, "
                f"k_1 = {self.wavenumbers[1] if n else float('nan'):.6g})")

    def shapes(self, x) -> np.ndarray:
        r"""The mode shapes :math:`\phi_n(x)`.

        Parameters
        ----------
        x : array_like, shape (...)
            Positions along the piston, :math:`0 \le x \le 1` (dimensionless).

        Returns
        -------
        numpy.ndarray, shape (..., N + 1)

        Raises
        ------
        ValueError
            If a position is not finite or lies outside :math:`[0, 1]`.
        """
        x = np.asarray(x, dtype=float)
        if not np.all(np.isfinite(x)) or np.any((x < 0.0) | (x > 1.0)):
            raise ValueError("x must lie in [0, 1]")
        starts = self.piston.starts
        j = np.clip(np.searchsorted(starts, x, side="right") - 1, 0, starts.size - 1)
        xi = (x - starts[j])[..., None]
        k = self.wavenumbers
        a = self.amplitudes[:, j, 0]  # (N + 1, ...)
        b = self.amplitudes[:, j, 1]
        return np.moveaxis(a, 0, -1) * np.cos(k * xi) + np.moveaxis(b, 0, -1) * np.sin(k * xi)


@dataclass(frozen=True)
class StickingBasis:
    r"""The stepped piston held on the stop at its struck end (theory §8, §12): its fixed-free modes
    and the maps between them and the free-free modes, as the simulator's sticking phase uses them.

    The fixed-free modes :math:`\psi_m` (:math:`\psi_m(1) = 0`, no force at :math:`x = 0`,
    mass-orthonormal) in coordinates :math:`r_m` scaled as the free ones, :math:`u(x, t) = \sum_m
    r_m \psi_m(0) \psi_m(x)`, obey :math:`r_m'' + d r_m' + (s l_m)^2 r_m = p(t)`. The overlaps
    follow from Green's identity on the two eigenproblems (no quadrature):

    .. math:: \int_0^1 \mu\,\phi_n \psi_m\,dx = \frac{\mu_N\,\psi_m'(1)\,\phi_n(1)}{k_n^2 - l_m^2},

    :math:`\mu_N` the last segment's mass per length; the stop's reaction is
    :math:`F = p\,(1 - \sum_m a_m) + \sum_m a_m (s l_m)^2 r_m` with
    :math:`a_m = \psi_m(0) \int_0^1 \mu\,\psi_m\,dx` (the momentum balance of the bar).

    Attributes
    ----------
    wavenumbers : numpy.ndarray, shape (N,)
        :math:`l_1 < \dots < l_N`, the fixed-free wavenumbers.
    to_contact : numpy.ndarray, shape (N, N + 1)
        :math:`r = P q` for a free-free state :math:`q`.
    to_free : numpy.ndarray, shape (N + 1, N)
        :math:`q = Q r`.
    reaction_weights : numpy.ndarray, shape (N,)
        :math:`a_m`.
    contact_weights : numpy.ndarray, shape (N,)
        :math:`\psi_m(0)^2`, the weights of :math:`r_m'` in the driven end's velocity.
    modes : PistonModes
        The fixed-free modes (no rigid mode: ``modes.shapes(x)`` has N columns).
    free : PistonModes
        The free-free modes they map to (the rigid one and ``N`` flexible ones).

    Examples
    --------
    >>> import math
    >>> from impactbar import SteppedPiston
    >>> held = SteppedPiston([0.5, 0.5], [1.0, 1.0]).sticking_basis(3)  # the uniform bar
    >>> (held.wavenumbers / math.pi).round(12)  # (m - 1/2) pi
    array([0.5, 1.5, 2.5])
    >>> held.contact_weights.round(12)  # psi_m(0)^2 = 2
    array([2., 2., 2.])
    """

    wavenumbers: np.ndarray
    to_contact: np.ndarray
    to_free: np.ndarray
    reaction_weights: np.ndarray
    contact_weights: np.ndarray
    modes: PistonModes
    free: PistonModes

    def shapes(self, x) -> np.ndarray:
        r"""The fixed-free shapes scaled as the coordinates :math:`r_m`: :math:`u = \sum_m r_m
        \psi_m(0)\,\psi_m(x)` (theory §8, §12).

        Parameters
        ----------
        x : array_like, shape (X,)
            Positions along the piston, :math:`0 \le x \le 1` (dimensionless).

        Returns
        -------
        numpy.ndarray, shape (X, N)

        Raises
        ------
        ValueError
            If a position is not finite or lies outside :math:`[0, 1]`.
        """
        return self.modes.shapes(x) * self.modes.shapes(np.zeros(1))[0]


@dataclass(frozen=True)
class SteppedPiston:
    r"""A piston of uniform segments of one material (theory §12).

    Parameters
    ----------
    lengths : array_like, shape (n_segments,)
        The segments' lengths in order from the driven end (:math:`x = 0`) to the struck end
        (:math:`x = 1`), each > 0 (any unit: they are scaled to a piston of length 1).
    impedances : array_like, shape (n_segments,)
        The segments' impedances :math:`Z = \rho c A` (or cross-sections: one material), each > 0, in
        any unit: only their ratios count (scaled to the first segment's), at most
        :math:`10^6` apart.

    Raises
    ------
    ValueError
        If the arrays are not 1-d of the same length, or a length or impedance is not finite and
        positive, or two impedances are more than :math:`10^6` apart.

    Examples
    --------
    >>> import math
    >>> from impactbar.dynamics.stepped import SteppedPiston
    >>> SteppedPiston([1.0], [1.0]).modes(3).wavenumbers / math.pi  # the uniform bar: n pi
    array([0., 1., 2., 3.])
    >>> head_neck = SteppedPiston([0.3, 0.7], [2.0, 1.0])
    >>> head_neck.modes(2).wavenumbers.round(6)
    array([0.      , 2.834777, 6.460444])
    """

    lengths: np.ndarray
    impedances: np.ndarray

    def __init__(self, lengths, impedances):
        le = _positive_vector("lengths", lengths)
        z = _positive_vector("impedances", impedances)
        if le.size != z.size:
            raise ValueError(f"lengths and impedances must have the same length; got {le.size} and {z.size}")
        if z.max() > MAX_IMPEDANCE_RATIO * z.min():
            raise ValueError(f"impedances must lie within a factor {MAX_IMPEDANCE_RATIO:g} of each other; "
                             f"got {z.min():g} .. {z.max():g}")
        le = le / le.sum()
        object.__setattr__(self, "lengths", le)
        object.__setattr__(self, "impedances", z / z[0])

    def __repr__(self) -> str:
        parts = ", ".join(f"{l:.4g}@{z:.4g}" for l, z in zip(self.lengths, self.impedances, strict=True))
        return f"SteppedPiston({parts})"

    def __eq__(self, other) -> bool:
        return (isinstance(other, SteppedPiston) and np.array_equal(self.lengths, other.lengths)
                and np.array_equal(self.impedances, other.impedances))

    def __hash__(self) -> int:
        return hash((self.lengths.tobytes(), self.impedances.tobytes()))

    @property
    def n_segments(self) -> int:
        """The number of segments."""
        return int(self.lengths.size)

    @property
    def starts(self) -> np.ndarray:
        """Where each segment starts along the piston, shape ``(n_segments,)``."""
        return np.concatenate(([0.0], np.cumsum(self.lengths)[:-1]))

    @property
    def mass_per_length(self) -> np.ndarray:
        r"""The mass per length :math:`\mu_j` of each segment, the piston's mass 1 (proportional to
        the impedance: one material), shape ``(n_segments,)``."""
        return self.impedances / float(self.impedances @ self.lengths)

    def end_force(self, k) -> np.ndarray:
        r"""The frequency equation :math:`F_{end}(k)`: the force at the far end of the motion of
        wavenumber ``k`` that starts with :math:`(u, F) = (1, 0)` at :math:`x = 0` (theory §12).

        Parameters
        ----------
        k : array_like, shape (...)
            Wavenumbers (dimensionless), > 0.

        Returns
        -------
        numpy.ndarray, shape (...)
            Zero exactly at the free-free modes' wavenumbers.
        """
        k = np.asarray(k, dtype=float)
        u, f = self._propagate(k)
        return f[-1] / k  # (scaled: the transfer matrix's force row grows like k)

    def _propagate(self, k):
        """(u, F) at every segment's start and at the far end, for (u, F) = (1, 0) at x = 0."""
        u = np.ones_like(k)
        f = np.zeros_like(k)
        us, fs = [u], [f]
        for le, z in zip(self.lengths, self.impedances, strict=True):
            c, s = np.cos(k * le), np.sin(k * le)
            u, f = c * u + s / (z * k) * f, -z * k * s * u + c * f
            us.append(u)
            fs.append(f)
        return us, fs

    def modes(self, n_modes: int) -> PistonModes:
        r"""The first ``n_modes`` flexible free-free modes and the rigid one, exact (theory §12).

        Parameters
        ----------
        n_modes : int
            :math:`N`, flexible modes, :math:`0 \le N \le 4096`.

        Returns
        -------
        PistonModes
            Wavenumbers :math:`k_0 = 0 < k_1 < \dots < k_N` to rounding (Brent's method on the
            frequency equation) and mass-orthonormal shapes.

        Raises
        ------
        ValueError
            If ``n_modes`` is not an integer in range.
        RuntimeError
            If the roots cannot be separated on a grid refined 8 times (never seen: every mode
            returned has as many nodes as its index, the certificate that no root was missed).
        """
        return self._solve_modes(n_modes, fixed=False)

    def end_displacement(self, k) -> np.ndarray:
        r"""The fixed-free frequency equation: the displacement at :math:`x = 1` of the motion of
        wavenumber ``k`` (shape ``(...)``, > 0) that starts with :math:`(u, F) = (1, 0)` at
        :math:`x = 0`; zero at the wavenumbers of the piston held at its struck end (theory §12).

        Returns
        -------
        numpy.ndarray, shape (...)
        """
        k = np.asarray(k, dtype=float)
        u, _ = self._propagate(k)
        return u[-1]

    def fixed_modes(self, n_modes: int) -> PistonModes:
        r"""The first ``n_modes`` modes of the piston held at its struck end (:math:`u(1) = 0`, free
        at :math:`x = 0`), exact, mass-orthonormal (theory §8, §12); the uniform bar's are
        :math:`l_m = (m - 1/2)\pi`, :math:`\psi_m = \sqrt 2 \cos(l_m x)`.

        Parameters
        ----------
        n_modes : int
            :math:`N`, :math:`0 \le N \le 4096`.

        Returns
        -------
        PistonModes
            Wavenumbers of shape ``(N,)`` (no rigid mode) and amplitudes of shape
            ``(N, n_segments, 2)``.

        Raises
        ------
        ValueError
            If ``n_modes`` is not an integer in range.
        """
        return self._solve_modes(n_modes, fixed=True)

    def _solve_modes(self, n_modes, fixed: bool) -> PistonModes:
        """:meth:`modes` (the rigid mode and ``n_modes`` free-free ones) or :meth:`fixed_modes`:
        the roots of the frequency equation on grids refined until every mode's node count holds."""
        if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) \
                or not 0 <= n_modes <= MAX_MODES:
            raise ValueError(f"n_modes must be an integer in [0, {MAX_MODES}]; got {n_modes!r}")
        n_modes = int(n_modes)
        equation = self.end_displacement if fixed else self.end_force
        for refine in range(8):
            k = np.zeros(n_modes + 1)  # (k_0 = 0: the rigid mode, dropped when held)
            if n_modes:
                k[1:] = self._roots(n_modes, refine, equation)
            amp = self._amplitudes(k)
            modes = PistonModes(k[1:], amp[1:], self) if fixed else PistonModes(k, amp, self)
            if self._nodes_ok(modes, fixed=fixed):
                return modes
        raise RuntimeError(  # pragma: no cover - never seen
            "stepped piston: the frequency equation's roots could not be separated (a mode without as "
            "many nodes as its index)")

    def sticking_basis(self, n_modes: int) -> StickingBasis:
        r"""The fixed-free modes and their maps to the free-free ones (:class:`StickingBasis`),
        for ``n_modes`` (:math:`N`) modes of each kind (theory §8, §12).

        Parameters
        ----------
        n_modes : int
            :math:`N` of each kind, :math:`0 \le N \le 4096`.

        Returns
        -------
        StickingBasis

        Raises
        ------
        ValueError
            If ``n_modes`` is not an integer in range.
        """
        free = self.modes(n_modes)
        fixed = self.fixed_modes(n_modes)
        k, lw = free.wavenumbers, fixed.wavenumbers
        phi0, phi1 = free.shapes(np.array([0.0, 1.0]))
        psi0 = fixed.shapes(np.zeros(1))[0]
        # psi_m'(1) from the last segment's amplitudes
        a, b = fixed.amplitudes[:, -1, 0], fixed.amplitudes[:, -1, 1]
        le = float(self.lengths[-1])
        dpsi1 = lw * (-a * np.sin(lw * le) + b * np.cos(lw * le))
        mu_end = float(self.mass_per_length[-1])
        overlap = mu_end * dpsi1[None, :] * phi1[:, None] / (k[:, None] ** 2 - lw[None, :] ** 2)
        to_free = overlap * psi0[None, :] / phi0[:, None]
        to_contact = (overlap * phi0[:, None] / psi0[None, :]).T
        reaction = psi0 * overlap[0] / phi1[0]  # phi_0 = 1: int mu psi_m
        arrays = (lw, to_contact, to_free, reaction, psi0 * psi0)
        for arr in arrays:
            arr.flags.writeable = False
        return StickingBasis(*arrays, fixed, free)

    def _roots(self, n: int, refine: int, f) -> np.ndarray:
        # a grid of 16 points per pi / (4 l_min) (halved again on each retry): two roots closer than
        # a step would cancel their sign changes, which the node count of modes() detects
        h = math.pi / 16.0 * min(1.0, float(self.lengths.min()) * 4.0) / 2.0**refine
        left: list[np.ndarray] = []
        found = 0
        lo = 1e-3 * h
        g_lo = float(f(np.array([lo]))[0])
        while found < n:
            pts = lo + h * np.arange(0, 4097)
            g = f(pts)
            g[0] = g_lo
            i = np.flatnonzero(np.signbit(g[1:]) != np.signbit(g[:-1]))[:n - found]
            left.append(pts[i])
            found += i.size
            lo, g_lo = float(pts[-1]), float(g[-1])
        a = np.concatenate(left)
        return _refine(f, a, a + h)

    def _amplitudes(self, k: np.ndarray) -> np.ndarray:
        """(a, b) per segment for each mode, mass-orthonormal."""
        n, m = k.size, self.n_segments
        amp = np.empty((n, m, 2))
        amp[0, :, 0] = 1.0  # rigid mode: u = 1
        amp[0, :, 1] = 0.0
        if n > 1:
            us, fs = self._propagate(k[1:])
            for j, z in enumerate(self.impedances):
                amp[1:, j, 0] = us[j]
                amp[1:, j, 1] = fs[j] / (z * k[1:])  # F = z u_x = z k b at the segment's start
        mu = self.mass_per_length
        norm2 = np.zeros(n)
        for j, le in enumerate(self.lengths):
            a, b = amp[:, j, 0], amp[:, j, 1]
            kl = k * le
            with np.errstate(divide="ignore", invalid="ignore"):
                # int_0^l (a cos kx + b sin kx)^2 dx in closed form (its k -> 0 limit: a^2 l)
                s2 = np.where(kl > 0, np.sin(2 * kl) / (2 * np.where(k > 0, k, 1.0)), le)
                c2 = np.where(kl > 0, (1 - np.cos(2 * kl)) / (2 * np.where(k > 0, k, 1.0)), 0.0)
            norm2 += mu[j] * (a * a * (le + s2) / 2 + b * b * (le - s2) / 2 + a * b * c2)
        return amp / np.sqrt(norm2)[:, None, None]

    @staticmethod
    def _nodes_ok(modes: PistonModes, fixed: bool = False) -> bool:
        """Whether mode n has exactly n nodes for every n (Sturm-Liouville): no root was missed
        (a fixed-free mode m = 1.. has m - 1 nodes before its held end)."""
        if modes.wavenumbers.size == 0:
            return True
        k_max = float(modes.wavenumbers[-1])
        if k_max == 0.0:
            return True
        # zeros in a segment are pi/k apart: 8 samples per pi/k_max catch every sign change
        x = np.linspace(0.0, 1.0, int(8 * k_max / math.pi) + 64)
        if fixed:  # short of the held end's own zero
            x = x[:-1] + 0.5 * (x[1] - x[0])
            x = np.concatenate(([0.0], x))
        phi = modes.shapes(x)
        nodes = np.count_nonzero(np.signbit(phi[1:]) != np.signbit(phi[:-1]), axis=0)
        return bool(np.array_equal(nodes, np.arange(modes.wavenumbers.size)))


def _refine(f, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The roots of ``f`` in the brackets ``[a, b]``, to rounding: Chandrupatla's method on all of
    them at once (:func:`scipy.optimize.elementwise.find_root`, scipy >= 1.15), else Brent's
    method one by one."""
    eps = np.finfo(float).eps
    try:
        from scipy.optimize.elementwise import find_root
    except ImportError:  # pragma: no cover - scipy < 1.15
        from scipy.optimize import brentq

        return np.array([brentq(lambda x: float(f(np.array([x]))[0]), lo, hi, xtol=1e-300,
                                rtol=4.0 * eps, maxiter=200) for lo, hi in zip(a, b, strict=True)])
    res = find_root(f, (a, b), tolerances={"xatol": 1e-300, "xrtol": 4.0 * eps, "fatol": 0.0,
                                           "frtol": 0.0}, maxiter=200)
    if not np.all(res.success):  # pragma: no cover - a bracket that lost its sign change
        raise RuntimeError("stepped piston: a root of the frequency equation did not converge")
    return np.asarray(res.x, dtype=float)


def _positive_vector(name: str, value) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float, ndmin=1)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a 1-d array of positive numbers; got {value!r}") from exc
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-d array; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0.0):
        raise ValueError(f"{name} must be finite and > 0; got {arr}")
    return arr
