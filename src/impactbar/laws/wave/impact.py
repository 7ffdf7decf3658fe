"""Wave-resolved impact on a long rod (theory §4b): the contact solved exactly by characteristics.

The piston ``0 < x < 1`` strikes, at ``x = 1``, the end of a long rod of the same material whose area
is ``A_s = A (1 + R)/(1 - R)`` (so that ``R = (A_s - A)/(A_s + A)``, paper eq. 10). The rod is at rest
and unstressed when contact starts and no reflection returns from its far end during the contact.
The contact window lasts two crossing times of the piston, ``T = 2/s`` (``2 L / C``): within it no wave
sent back from the interface can return to the interface, so the interface sees only the piston's
state at impact and the drive load ``p(t)`` at ``x = 0``; every part of the solution is then explicit
(d'Alembert).

Riemann invariants (dimensionless, ``theta = s t`` so that a wave crosses the piston in ``theta = 1``;
``v = u_t`` the velocity, ``N = -s^2 u_x`` the compressive force):

    alpha = v + N/s  (carried towards the rod, dx/dtheta = +1),
    beta  = v - N/s  (carried towards the drive, dx/dtheta = -1).

At ``x = 0`` the drive force sets ``alpha = beta + 2 p/s``. At ``x = 1`` in contact the rod's impedance
``Z_s = Z (1 + R)/(1 - R)`` (piston impedance ``Z = s``) gives ``beta = -R alpha`` and the interface
force ``F = s (1 + R) alpha / 2``; separated, ``beta = alpha`` (free end) and the rod end stays where it
is (a right-going wave only: its velocity is ``F / Z_s = 0``). Contact ends when ``F`` would turn
tensile (``alpha < 0``) and resumes when the gap closes.
"""

from __future__ import annotations

import functools
import math
from functools import cached_property

import numpy as np

from ..._shared.bounded import remember
from ..._shared.columns import IV_HI
from ...dynamics.compiled_views import FOURIER, PIECEWISE
from ...dynamics.implementations import use_fast
from . import _window as KW
from ._characteristics import (
    _GL_W,
    _GL_X,
    _Contact,
    _panels,
    _window_rate,
    _WindowLoad,
    held_post_state,
    held_throughout,
)

__all__ = ["WaveImpact", "wave_impact", "window_drive", "window_drives"]


def window_drive(s: float, R: float, n_modes: int, load, t0: float, derivative: bool = False):
    """The drive load's part of the post-contact modal state, contact held for the whole window
    (theory §4b).

    With the piston pressed on the rod for the whole window ``[t0, t0 + 2/s]`` the contact map is
    affine: ``(q_n, q_n') -> -R (q_n, q_n') + (g_n, h_n)``. With ``P(theta) = p(t0 + theta/s)`` and
    ``I^c_n, I^s_n`` its moments against ``cos(n pi theta), sin(n pi theta)`` over ``[0, 1]`` (``a``)
    and ``[1, 2]`` (``b``):

        h_n = (I^c_n(b) - R I^c_n(a)) / s,            n >= 0,
        g_n = -(I^s_n(b) - R I^s_n(a)) / (s^2 n pi),  n >= 1.

    Parameters
    ----------
    s, R : float
        Wave-speed ratio and restitution of the bar model.
    n_modes : int
        ``N``.
    load : Load
    t0 : float
        Load time at which contact starts.
    derivative : bool
        Also return ``d(g, h)/d t0``, by parts so that no derivative of the load is needed (it holds
        for the square wave too): ``dI^c_n(a)/dt0 = s ([P cos(n pi theta)]_0^1 + n pi I^s_n(a))``,
        ``dI^s_n/dt0 = -s n pi I^c_n`` (likewise on ``b``), hence ``dg_n/dt0 = h_n``.

    Returns
    -------
    g : numpy.ndarray, shape (N + 1,)
        Displacement part (``g_0 = 0``: the rigid displacement is fixed by contact).
    h : numpy.ndarray, shape (N + 1,)
        Velocity part.
    dg, dh : numpy.ndarray, shape (N + 1,)
        Only with ``derivative=True``.
    """
    wl = _WindowLoad(load, s, t0)
    npi = math.pi * np.arange(n_modes + 1)
    kernel = load.abilities.kernel
    view = kernel.view if kernel is not None else None
    exact = _exact_moments(view, wl, npi) if n_modes >= _CLOSED_FROM else None
    if exact is not None:  # closed forms, O(N K): the same moments to rounding
        (ca, cb), (sa, sb) = exact
    elif view is not None and view.kind == FOURIER and not view.ks.size:  # a constant load: its table
        (mc,), (ms,) = _tabled_moments(view, s, wl.rate, np.array([float(t0)]), n_modes + 1)
        (ca, cb), (sa, sb) = mc, ms
    elif view is not None:  # the compiled quadrature (the same panels)
        (mc,), (ms,) = _kernel_moments(tuple(view), s, wl.rate, [t0], wl.jumps, n_modes + 1)
        (ca, cb), (sa, sb) = mc, ms
    else:
        h_panel = 8.0 / (npi[-1] + wl.rate + 1.0)
        out = {}
        for name, lo, hi in (("a", 0.0, 1.0), ("b", 1.0, 2.0)):
            th, w = _panels(lo, hi, wl.jumps, h_panel)
            pw = wl(th) * w
            arg = np.multiply.outer(npi, th)
            out[name] = (np.cos(arg) @ pw, np.sin(arg) @ pw)
        (ca, sa), (cb, sb) = out["a"], out["b"]
    g, h = _drive_parts(s, R, npi, ca, cb, sa, sb)
    if not derivative:
        return g, h
    sign = (-1.0) ** np.arange(n_modes + 1)
    p0p, p1m = float(wl(0.0)), float(wl(1.0, left=True))
    p1p, p2m = float(wl(1.0)), float(wl(2.0, left=True))
    dca = s * (sign * p1m - p0p + npi * sa)
    dcb = s * (p2m - sign * p1p + npi * sb)
    dh = (dcb - R * dca) / s
    dg = h.copy()
    dg[0] = 0.0
    return g, h, dg, dh


#: From this many modes on, :func:`window_drive` takes the moments in closed form (below it the
#: compiled quadrature is the faster one)
_CLOSED_FROM = 48


def _kernel_moments(view: tuple, s: float, rate: float, t0s, jumps, M: int):
    """The compiled quadrature's moments ``(cos (P, 2, M), sin (P, 2, M))`` of :func:`window_drive`
    at the ``P`` starts ``t0s``, in one compiled call, the load's kernel view as a plain tuple."""
    t0s = np.array(t0s, dtype=float).ravel()
    mc, ms = np.zeros((t0s.size, 2, M)), np.zeros((t0s.size, 2, M))
    KW.window_moments(view, s, rate, t0s, np.ascontiguousarray(jumps), _GL_X, _GL_W, mc, ms)
    return mc, ms


def _drive_parts(s: float, R: float, npi, ca, cb, sa, sb):
    """``(g, h)`` of :func:`window_drive` from the moments (each may carry a leading axis of starts)."""
    h = (cb - R * ca) / s
    g = np.zeros(cb.shape)
    g[..., 1:] = -(sb[..., 1:] - R * sa[..., 1:]) / (s * s * npi[1:])
    return g, h


def window_drives(s: float, R: float, n_modes: int, load, t0s) -> tuple[np.ndarray, np.ndarray]:
    """:func:`window_drive` at many starts of contact (theory §4b), without the derivative.

    The same numbers as :func:`window_drive` start by start, to the bit; under a load with a
    compiled view and no jumps, and fewer than ``_CLOSED_FROM`` modes (the compiled quadrature),
    what does not depend on the start (the view, the load's rate, ``n pi``) is set up once, the
    moments of all starts come from one compiled call and the drive's parts from them at once (the
    phase series of
    :mod:`impactbar.laws.wave.periodic` takes ``2 K + 1`` starts per load).

    Parameters
    ----------
    s, R, n_modes, load
        As for :func:`window_drive`.
    t0s : array_like, shape (P,)
        Load times at which contact starts.

    Returns
    -------
    g, h : numpy.ndarray, shape (P, N + 1)
        The displacement and velocity parts of each start.
    """
    t0s = np.asarray(t0s, dtype=float).ravel()
    own = load.abilities
    if own.kernel is None or own.jumps is not None or n_modes >= _CLOSED_FROM or not t0s.size:
        drives = [window_drive(s, R, n_modes, load, float(t)) for t in t0s]
        return (np.array([g for g, _ in drives]).reshape(t0s.size, n_modes + 1),
                np.array([h for _, h in drives]).reshape(t0s.size, n_modes + 1))
    view, rate = own.kernel.view, _window_rate(load, s)
    if view.kind == FOURIER and view.ks.size <= 1:  # one harmonic (the pneumatic load) or none: tabled
        mc, ms = _tabled_moments(view, s, rate, t0s, n_modes + 1)
    else:
        mc, ms = _kernel_moments(tuple(view), s, rate, t0s, np.empty(0), n_modes + 1)
    (ca, cb), (sa, sb) = np.moveaxis(mc, 1, 0), np.moveaxis(ms, 1, 0)  # by the moments' order, start by start
    return _drive_parts(s, R, math.pi * np.arange(n_modes + 1), ca, cb, sa, sb)


#: :func:`_node_table`'s tables by ``(s, rate, starts, M, k, p_k)``, read-only, the last 16
_NODE_TABLES: dict = {}


def _node_table(view, s: float, rate: float, t0s: np.ndarray, M: int):
    """What the compiled quadrature of the window's moments (``_window._window_moments``, a load of
    one harmonic or none, and no jumps) computes at its nodes apart from the mean load ``p0``: the
    weights ``w``, shape ``(2, J)`` (rows: the halves ``[0, 1]``, ``[1, 2]``; ``J`` nodes each), the
    harmonic ``a = Re(p_k e^{i k t})`` (``-0.0`` without a harmonic) at each start's nodes, shape
    ``(P, 2, J)``, and ``cos, sin(n pi theta)`` by the kernel's rotation, shape ``(2, J, M)`` each;
    the load there is ``p0 + a``. The same floats as the kernel's (the same operations in the same
    order; ``math``'s ``cos``, ``sin`` are the C library's, as compiled code's). Kept per window,
    starts and harmonic: a chart's load factors differ only in ``p0`` (theory §4b)."""
    harmonic = (*view.ks.tolist(), *view.pr.tolist(), *view.pim.tolist())  # (k, Re p_k, Im p_k), or none
    # (without a harmonic nothing depends on the starts but their number)
    key = (float(s), float(rate), t0s.tobytes() if harmonic else t0s.size, M, harmonic)
    table = _NODE_TABLES.get(key)
    if table is not None:
        return table
    hq = 8.0 / (math.pi * (M - 1) + rate + 1.0)
    npan = max(1, int(math.ceil(1.0 / hq)))  # (each half is one piece, of width 1: no jumps)
    half_w = 0.5 * 1.0 / npan
    gl_x, gl_w = _GL_X.tolist(), _GL_W.tolist()
    ths, ws = [], []
    for half in range(2):
        for pnl in range(npan):
            mid = float(half) + half_w * (2.0 * pnl + 1.0)
            ths += [mid + half_w * x for x in gl_x]
            ws += [half_w * w for w in gl_w]
    J = len(gl_x) * npan
    C, S = np.empty((2 * J, M)), np.empty((2 * J, M))
    for j, th in enumerate(ths):
        c1, s1 = math.cos(math.pi * th), math.sin(math.pi * th)
        cn, sn = 1.0, 0.0
        for n in range(M):
            C[j, n], S[j, n] = cn, sn
            cn, sn = cn * c1 - sn * s1, sn * c1 + cn * s1
    if harmonic:
        k, pr, pim = harmonic
        a = np.array([[pr * math.cos(k * t) - pim * math.sin(k * t) for t in (t0 + th / s for th in ths)]
                      for t0 in t0s.tolist()])
    else:  # a constant load: p0 + (-0.0) is p0, its zero's sign included
        a = np.full((t0s.size, 2 * J), -0.0)
    table = (np.array(ws).reshape(2, J), a.reshape(t0s.size, 2, J), C.reshape(2, J, M), S.reshape(2, J, M))
    for x in table:
        x.flags.writeable = False
    return remember(_NODE_TABLES, key, table, 16)


def _tabled_moments(view, s: float, rate: float, t0s: np.ndarray, M: int):
    """:func:`_kernel_moments` for a load of one harmonic or none, without jumps, the same floats:
    its nodes tabled once (:func:`_node_table`), each start's moments from them by one compiled call
    (``_window.tabled_moments``) that adds each node's weighted load ``p0 + a`` in the kernel's order."""
    w, a, c, sn = _node_table(view, s, rate, t0s, M)
    mc, ms = np.zeros((t0s.size, 2, M)), np.zeros((t0s.size, 2, M))
    KW.tabled_moments(float(view.p0), w, a, c, sn, mc, ms)
    return mc, ms


def _unit_moment(w):
    """``int_0^1 e^{i w theta} dtheta = sin(w)/w + i 2 sin^2(w/2)/w`` (1 at ``w = 0``), without the
    cancellation of ``(e^{i w} - 1)/(i w)`` at small ``w``."""
    w = np.asarray(w, dtype=float)
    half = np.sinc(w / (2.0 * math.pi))  # sin(w/2) / (w/2)
    return np.sinc(w / math.pi) + 0.5j * w * half * half


@functools.lru_cache(maxsize=32)
def _fourier_moment_tables(M: int, s: float, ks: tuple):
    """The parts of :func:`_exact_moments` under a Fourier load that do not depend on the start of
    contact, shape ``(2, M)`` and ``(2, M, K)`` (rows: the halves ``[0, 1]``, ``[1, 2]``):
    ``e^{i w lo} E(w)`` at ``w = n pi`` and ``n pi +/- k/s``; the moments are then
    ``p0 T0 + (Tp a + Tm conj(a)) / 2``, ``a_k = p_k e^{i k t0}``. Cached per window (read-only):
    the phase scan and the orbits' series take them at many starts."""
    npi = math.pi * np.arange(M)
    kappa = np.asarray(ks, dtype=float) / s
    wp = npi[:, None] + kappa[None, :]
    wm = npi[:, None] - kappa[None, :]
    e0, ep, em = _unit_moment(npi), _unit_moment(wp), _unit_moment(wm)
    out = tuple(np.stack([f * np.exp(1j * w * lo) for lo in (0.0, 1.0)])
                for f, w in ((e0, npi), (ep, wp), (em, wm)))
    for t in out:
        t.flags.writeable = False
    return out


def _exact_moments(view, wl, npi):
    """The moments ``I^c_n, I^s_n`` of :func:`window_drive` over ``[0, 1]`` and ``[1, 2]`` in closed
    form, as ``(cos (2, M), sin (2, M))``, for a load whose kernel view (``view``, the
    :class:`~impactbar.dynamics.compiled_views.LoadKernelView` the compiled quadrature would read) holds
    finitely many harmonics (``O(N K)``) or pieces (``O(N)`` per piece); ``None`` without a view,
    which the numpy quadrature serves. ``int_lo^hi e^{i w theta} = e^{i w lo} (hi - lo) E(w (hi -
    lo))`` with ``E`` of :func:`_unit_moment`."""
    if view is None:
        return None
    out = np.zeros((2, npi.size), dtype=complex)
    if view.kind == FOURIER:
        # P(theta) = p0 + Re sum a_k e^{i kappa_k theta}, a_k = p_k e^{i k t0}, kappa_k = k / s
        k = np.asarray(view.ks, dtype=float)
        a = (view.pr + 1j * view.pim) * np.exp(1j * k * wl.t0)
        t0, tp, tm = _fourier_moment_tables(npi.size, float(wl.s), tuple(k.tolist()))
        out[:] = view.p0 * t0
        if k.size:
            out += 0.5 * (tp @ a + tm @ np.conj(a))
        return out.real, out.imag
    if view.kind == PIECEWISE and wl._pieces is not None:
        levels, _, edges = wl._pieces
        th = wl.s * edges  # the pieces in theta, [0, 2] cut at the load's jumps
        th[0], th[-1] = 0.0, 2.0
        for row, (lo, hi) in enumerate(((0.0, 1.0), (1.0, 2.0))):
            for j in range(levels.size):
                a, b = max(th[j], lo), min(th[j + 1], hi)
                if b > a:
                    out[row] += levels[j] * (b - a) * np.exp(1j * npi * a) * _unit_moment(npi * (b - a))
        return out.real, out.imag
    return None


class WaveImpact:
    """One contact of the piston with the long rod, solved by characteristics (theory §4b).

    Made by :func:`wave_impact`. Times are dimensionless and counted from the start of contact; the
    window is ``[0, 2/s]``. Forces are dimensionless like the load (paper eq. 2), compressive
    positive; stresses are forces per piston area (the rod's stress is ``F A / A_s =
    F (1 - R)/(1 + R)``). The contact intervals and the post-contact state are solved at once; the
    integrals (energies, impulse, force extremes) on first access.

    Attributes
    ----------
    s, R : float
        The model's wave-speed ratio and restitution.
    t0 : float
        Load time at the start of contact.
    duration : float
        The window ``2/s``.
    q_before, v_before : numpy.ndarray, shape (N + 1,)
        Modal state at the start of contact (positions from the rod end).
    q_after, v_after : numpy.ndarray, shape (N + 1,)
        Modal state at the end of the window, projected on the ``N + 1`` free-free modes, positions
        measured from the advanced rod end (``u(1) = -gap``).
    contact : numpy.ndarray, shape (K, 2)
        Contact intervals (start, end) within the window.
    gap : float
        Distance between piston end and rod end at the end of the window (0 when still touching).
    impulse : float
        ``int F dt`` over the window.
    advance : float
        Advance of the rod end during the blow, ``impulse / Z_s`` (dimensionless like ``u``).
    rod_energy : float
        ``int F^2 / Z_s dt``, energy carried into the rod by the transmitted wave.
    drive_work : float
        Work of the drive load on the piston during the window.
    energy_before, energy_after : float
        Piston energy (kinetic + strain) before (the modes plus the static correction that carries
        the drive's force at ``x = 0``, theory §4c), and after projected on the modes kept.
    energy_after_field : float
        Energy of the exact post-window field (``energy_before + drive_work - rod_energy``).
    efficiency : float
        ``rod_energy / (energy_before + drive_work)``: the share of the energy available to the blow
        (the piston's energy at impact plus the drive's work during the window) that the rod
        carries away (Lundberg's transfer efficiency, with the drive); at most 1, since the energy
        balance leaves ``energy_after_field >= 0``.
    peak_force_error : float
        An estimate of the truncation error of ``peak_force`` (see the property).
    peak_force, min_force : float
        Largest and smallest interface force over the window (``min_force`` is 0 when contact is
        lost). The piston's fields at impact carry the drive's force at ``x = 0`` (static
        correction) and the jumps that earlier releases and separations left in them, located
        from the modal coefficients and carried exactly (theory §4c); the contact intervals and
        the post-window state are those of the modal fields. Accuracy against the exact whole
        system (``d = 0``, measured, theory §4c): for ``64 <= N <= 256`` within 2e-5 relative on
        the stable orbits checked (2e-6 to 1e-6 where the peak sits on a jump, ``s = 10``; 2e-6,
        then below 1e-6, at ``s = 3``, whose weak jumps are not located at ``N = 32``: 6e-4
        there), and within 2e-5 on the three blows of a 3-in-2 cycle (``s = 5``) at ``N = 256``.
        No jump is located below ``N = 32``, nor where two lie closer than about ``1.5/N`` (a
        pulse narrower than that), nor where the location would move the peak by more than the
        series can overshoot: a peak on a jump ``[A]`` of the arriving invariant is then high by
        up to its Gibbs overshoot, ``0.09 (1 + R) s |[A]| / 2``, at every ``N`` (2-4 % on that
        cycle at ``N = 128``), and ``peak_force_error`` shows it. A feature narrower than
        ``1/(s N)`` is not resolved.

    Examples
    --------
    >>> import numpy as np
    >>> from impactbar import BarModel, CosineLoad, wave_impact
    >>> q, v = np.zeros(6), np.zeros(6)
    >>> v[0] = 1.0  # a rigid piston arriving at unit speed, no drive
    >>> imp = wave_impact(BarModel(s=7.0, d=0.0, R=0.3, n_modes=5), CosineLoad(0.0, 0.0), 0.0, q, v)
    >>> round(imp.duration, 12), round(float(imp.efficiency), 12)  # 2/s and 1 - R^2
    (0.285714285714, 0.91)
    """

    def __init__(self, s, R, t0, q_before, v_before, q_after, v_after, solver):
        self.s, self.R, self.t0 = s, R, t0
        self.duration = 2.0 / s
        self.q_before, self.v_before = q_before, v_before
        self.q_after, self.v_after = q_after, v_after
        self._solver = solver
        self.contact = solver.contact / s
        self.gap = solver.gap_theta / s

    @classmethod
    def _held(cls, s, R, t0, q_before, v_before, q_after, v_after, load) -> WaveImpact:
        """A window known to hold contact throughout (``_characteristics.held_throughout``): one
        contact interval ``[0, 2/s]``, no gap, its solver built on first use."""
        imp = cls.__new__(cls)
        imp.s, imp.R, imp.t0 = s, R, t0
        imp.duration = 2.0 / s
        imp.q_before, imp.v_before = q_before, v_before
        imp.q_after, imp.v_after = q_after, v_after
        imp._load = load
        imp.contact = np.array([[0.0, 2.0]]) / s  # the solver's, as __init__ takes them
        imp.gap = 0.0 / s
        return imp

    @cached_property
    def _solver(self) -> _Contact:
        """The characteristics solution of a window made by :meth:`_held` (``__init__`` sets it)."""
        return _Contact(self.s, self.R, self.q_before, self.v_before, self._load, self.t0).solve()

    def resolve(self) -> WaveImpact:
        """Itself (the simulator's lazily solved windows resolve to a ``WaveImpact``)."""
        return self

    def __repr__(self) -> str:
        return (f"WaveImpact(t0={self.t0!r}, duration={self.duration!r}, "
                f"separations={self.separations}, gap={self.gap!r})")

    @cached_property
    def impulse(self) -> float:
        return self._solver.impulse()

    @property
    def advance(self) -> float:
        return self.impulse * (1.0 - self.R) / ((1.0 + self.R) * self.s)

    @cached_property
    def rod_energy(self) -> float:
        return self._solver.rod_energy()

    @cached_property
    def drive_work(self) -> float:
        return self._solver.drive_work()

    @cached_property
    def energy_before(self) -> float:
        return modal_energy(self.s, self.q_before, self.v_before) + self._solver.piston.static_energy

    @cached_property
    def energy_after(self) -> float:
        return modal_energy(self.s, self.q_after, self.v_after)

    @cached_property
    def energy_after_field(self) -> float:
        return self._solver.field_energy()

    @property
    def efficiency(self) -> float:
        available = self.energy_before + self.drive_work
        return self.rod_energy / available if available > 0.0 else math.nan

    @cached_property
    def _located(self):
        """The window's solver whose fields at impact carry their jumps exactly (theory §4c)."""
        return self._solver.located()

    @cached_property
    def _force_extremes(self):
        return self._located.force_extremes()

    @property
    def peak_force(self) -> float:
        peak, _ = self._force_extremes
        return peak

    @property
    def min_force(self) -> float:
        _, least = self._force_extremes
        return least

    @cached_property
    def peak_force_error(self) -> float:
        """An estimate of the truncation error of :attr:`peak_force` (theory §4c), not a guaranteed
        bound: ``|peak_force - P_J| + 2 s (1 + R) N max_{n >= 3N/4} |c_n|``, with ``P_J`` the peak
        of the same window whose continuous remainder (the fields less their located jumps) is
        smoothed by a positive (Jackson) kernel, and ``c_n`` the remainder's top coefficients (the
        second term bounds the remainder's truncation when its coefficients fall as ``n^-2``, as
        those of a field with kinks do). A jump that was not located (too weak, or not confirmed
        by the coefficients) shows in the first term as its Gibbs overshoot."""
        if not len(self._solver.contact):
            return 0.0
        loc = self._located
        N = loc.N
        c = 0.5 * np.abs(loc.piston.a[1:] + 1j * loc.piston.b[1:])
        tail = 2.0 * self.s * (1.0 + self.R) * N * float(c[max(0, (3 * N) // 4 - 1):].max())
        smoothed, _ = loc.smoothed().force_extremes()
        return abs(self.peak_force - smoothed) + tail

    def account(self, t) -> tuple[float, float, float]:
        """The energy balance of the contact up to time ``t`` in ``[0, 2/s]``.

        Returns
        -------
        drive_work, rod_energy, field_energy : float
            Work of the drive, energy sent into the rod, and energy of the exact piston fields at
            ``t``: ``energy_before + drive_work = field_energy + rod_energy``.
        """
        th = self._window_theta(t)
        sol = self._solver
        return sol.drive_work(th), sol.rod_energy(th), sol.field_energy(th)

    def _window_theta(self, t) -> float:
        t = float(t)
        # a time measured as a difference of absolute times carries their rounding
        slack = 1e-14 * self.duration + 8.0 * np.finfo(float).eps * max(1.0, abs(self.t0))
        if not -slack <= t <= self.duration + slack:
            raise ValueError(f"t must lie in [0, {self.duration}] (the contact window); got {t}")
        return min(max(t * self.s, 0.0), 2.0)

    @property
    def peak_rod_stress(self) -> float:
        """Largest compressive stress in the rod, ``peak_force (1 - R)/(1 + R)`` (per piston area)."""
        return self.peak_force * (1.0 - self.R) / (1.0 + self.R)

    @property
    def min_rod_stress(self) -> float:
        """Smallest stress in the rod (0 when contact is lost inside the window)."""
        return self.min_force * (1.0 - self.R) / (1.0 + self.R)

    @property
    def separations(self) -> int:
        """Number of times contact was lost inside the window."""
        c = self.contact
        n = len(c)
        return n - 1 + int(n > 0 and c[-1, IV_HI] < self.duration * (1 - 1e-14))

    def force(self, t) -> np.ndarray:
        """Interface force ``F(t)`` (the transmitted wave's force at the rod end), shape of ``t``,
        for ``0 <= t <= 2/s`` (0 outside the window)."""
        t = np.asarray(t, dtype=float)
        return self._located.force(t * self.s)

    def state_at(self, t):
        """Modal state ``(q, q')`` at time ``t`` in ``[0, 2/s]`` since contact started: the exact
        characteristics fields projected on the modes kept, positions measured from the rod end
        where it is at ``t`` (``u(1, t) = -gap``).

        Returns
        -------
        q, v : numpy.ndarray, shape (N + 1,)
        """
        return self._solver.state_at(self._window_theta(t))

    def fields(self, x):
        """Exact velocity ``u_t`` and strain ``u_x`` at the end of the window (before projection).

        Parameters
        ----------
        x : array_like, shape (P,)
            Positions in ``[0, 1]``.

        Returns
        -------
        velocity, strain : numpy.ndarray, shape (P,)
        """
        al, be = self._solver.invariants_at(np.asarray(x, dtype=float), 2.0)
        return 0.5 * (al + be), (be - al) / (2.0 * self.s)

    def piston_stress_extremes(self, cells: int | None = None) -> tuple[float, float]:
        """Largest compressive and largest tensile axial force in the piston over the window.

        Evaluated exactly at the nodes of the characteristics lattice of ``cells`` cells (default
        ``8 (N + 1)``, at least 64, at most 2048); between nodes the fields are trigonometric sums
        resolved by that lattice. The fields at impact carry the drive's force at ``x = 0`` (static
        correction, theory §4c); their accuracy is that of :attr:`peak_force`.

        Returns
        -------
        (max, min) : tuple of float
            ``max N`` (compressive, >= 0 when any part is compressed) and ``min N`` (< 0 if tensile).
        """
        J = cells or int(min(2048, max(64, 8 * self.q_before.size)))
        return self._located.stress_extremes(J)

    def to_dict(self) -> dict:
        """A JSON-ready summary (floats)."""
        return {
            "duration": self.duration, "gap": self.gap, "impulse": self.impulse,
            "advance": self.advance, "rod_energy": self.rod_energy, "drive_work": self.drive_work,
            "energy_before": self.energy_before, "energy_after": self.energy_after,
            "efficiency": self.efficiency, "peak_force": self.peak_force,
            "min_force": self.min_force, "peak_rod_stress": self.peak_rod_stress,
            "separations": self.separations,
            "contact": self.contact.tolist(),
        }


def modal_energy(s: float, q, v) -> float:
    """Kinetic plus strain energy of the piston, ``q_0'^2/2 + sum (q_n'^2 + (s n pi)^2 q_n^2)``."""
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    w = s * math.pi * np.arange(q.size)
    return float(0.5 * v[0] ** 2 + np.sum(v[1:] ** 2 + (w[1:] * q[1:]) ** 2))


def wave_impact(model, load, t0: float, q, v) -> WaveImpact:
    r"""Contact of the piston with the long rod, solved exactly by characteristics (theory §4b).

    The piston arrives at load time ``t0`` with modal state ``(q, q')`` (positions from the rod end,
    ``u(1) = c . q = 0``, ``u_t(1) > 0``). Over the window ``[t0, t0 + 2/s]`` the fields are
    propagated along characteristics with the drive load at ``x = 0`` (any load, jumps included),
    compressive contact with the rod at ``x = 1``, separation when the interface force would turn
    tensile, and re-contact when the gap closes. Without drive and without separation the result is
    exactly ``(q_n, q_n') -> -R (q_n, q_n')`` for ``n >= 1`` and ``q_0' -> -R q_0'`` (theory §4b);
    the drive adds :func:`window_drive`; a separation adds the waves reflected by the free end.
    The post-window fields are projected on the ``N + 1`` free-free modes (exact without drive and
    separation; otherwise the truncation of the exact field, whose energy is
    ``energy_after_field``). The fields at impact are the modal sums plus the static correction that
    carries the drive's force ``p(t0)`` at ``x = 0`` (theory §4c; it has no component on the modes
    kept, so the post-window state of a window held in contact is unchanged by it).

    Damping is neglected inside the window only. Along a characteristic the invariants then decay at
    the rate ``d/2`` (``u_tt + d u_t = s^2 u_xx``), so over the window of length ``2/s`` the post-
    contact fields, the force and the impulse are in error by a relative ``O(d/s)`` (at most about
    ``d/s``: 5e-4 for ``d = 0.005``, ``s = 10``), the energies by ``O(2 d/s)``.

    Parameters
    ----------
    model : BarModel
        Uses ``s``, ``R`` and ``n_modes``.
    load : Load
        The drive load (paper eqs. 7, 33, 34).
    t0 : float
        Load time at which contact starts.
    q, v : array_like, shape (N + 1,)
        Modal displacements and velocities at the start of contact.

    Returns
    -------
    WaveImpact

    Raises
    ------
    ValueError
        If the shapes do not match the model, a value is not finite, or the piston arrives moving
        away from the rod (``u_t(1) < 0`` beyond rounding).

    Examples
    --------
    >>> import numpy as np
    >>> from impactbar import BarModel, CosineLoad, wave_impact
    >>> q, v = np.zeros(6), np.zeros(6)
    >>> v[0] = 1.0
    >>> imp = wave_impact(BarModel(s=7.0, d=0.0, R=0.3, n_modes=5), CosineLoad(0.0, 0.0), 0.0, q, v)
    >>> round(imp.impulse, 12), round(float(imp.v_after[0]), 12)  # momentum (1 + R) v, rebound -R v
    (1.3, -0.3)
    """
    s, R = float(model.s), float(model.R)
    M = model.n_modes + 1
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    if q.shape != (M,) or v.shape != (M,):
        raise ValueError(f"q and v must have shape ({M},) (n_modes + 1); got {q.shape} and {v.shape}")
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
        raise ValueError("q and v must be finite")
    t0 = float(t0)
    if not math.isfinite(t0):
        raise ValueError(f"t0 must be finite; got {t0}")
    return _wave_impact(model, load, t0, q, v, window_drive(s, R, model.n_modes, load, t0))


def _wave_impact(model, load, t0: float, q, v, drive) -> WaveImpact:
    """:func:`wave_impact` from checked inputs, with the window's drive part ``drive = (g, h)`` of
    :func:`window_drive` already computed (the orbit builder has it)."""
    s, R = float(model.s), float(model.R)
    if use_fast("wave.held_window") and held_throughout(s, q, v, load, t0):
        # held throughout: the solver's post-window state without its scan; solved when asked
        qa, va = held_post_state(s, R, q, v, drive)
        return WaveImpact._held(s, R, t0, q.copy(), v.copy(), qa, va, load)
    sol = _Contact(s, R, q, v, load, t0).solve()
    qa, va = sol.post_state(q, v, drive)
    return WaveImpact(s, R, t0, q.copy(), v.copy(), qa, va, sol)
