r"""An independent solution of the rod-rock law's coupled blow under the oil circuit (theory §11, "The
coupled blow"; §4d): the neutral delay-differential system of d'Alembert waves, integrated
monolithically by the method of steps.

Each uniform segment (the piston; each rod segment) is a delay line of its exact travel time: the
right-going wave ``F_j`` a node emits into segment ``j`` arrives at the far node ``T_j`` later, the
left-going ``G_j`` alike. The nodes are algebraic (the welded junctions: force and velocity
continuous, ``N = 2 (Z_b F_a + Z_a G_b) / (Z_a + Z_b)``; the piston-shank contact, compressive only,
free ends and an integrated gap while open) or carry ordinary differential equations: the piston's
driven end, loaded by the circuit's force ``p = p_r - alpha p_f`` (``F_0 = p - G_in``, the end
moving at ``(p - 2 G_in) / Z_0``, which drives the circuit's vector field: the library's compiled
one written by hand, ``circuit_blow_reference.rhs``, with ``a = -2 G_in / Z_0``), and the bit, a
mass on Lundberg's bilinear rock under the feed, ``m p'' + Z p' + R(p) = 2 F_in + f``. The rod's
waves are those above its static state under the feed (at rest at impact, the rock loaded to the
feed); the piston's are total, its fields at impact those of a rigid piston under the force ``p``
at its driven end (``v = q_0'``, ``N = p (1 - x)``).

All the ordinary differential equations (circuit, bit, gap, the shank's displacement and the
quadratures) are one system integrated by :func:`scipy.integrate.solve_ivp` (DOP853) over steps
no longer than the shortest travel time, split at every time a discontinuity of a wave reaches a
node (the impact's step waves and their echoes, tracked as a closure of arrivals over the chain) and
at every event (separation, re-contact, the rock's unloading, reloading, lift-off and landing),
located by the integrator's root finding on its dense output. The waves a node emits over a step
are kept as Chebyshev interpolants of the delayed waves (adaptive in degree, split where they do
not converge) or, at the two dynamic nodes, through the step's dense output. Nothing of the
library's exact solver (pieces of exponential polynomials), its lattice or its iteration of the
drive's force is used: the circuit's force is carried by the monolithic integration itself.

Modelling choices matched to the library (theory §4d, §11): the blow lasts the law's window
``4/s + 2 sum T_i``; the piston is rigid in the modal flight (``n_modes = 0``), uniform; the piston's
state after is its mean velocity (the rigid mode's projection) and the struck end's position from
the new stop (the shank's displacement less the gap less the rock's permanent penetration).
"""

from __future__ import annotations

import bisect
import heapq
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import chebyshev as C
from scipy.fft import dct
from scipy.integrate import solve_ivp

__all__ = ["ReferenceBlow", "WHOLE_CELLS", "blow_differences", "drifter_arrival", "held_blow",
           "reference_blow", "slots_model"]

#: The rod of whole piston lengths (448.54236 mm and three times that) for :func:`drifter_arrival`.
WHOLE_CELLS = {"rod.segments.0.length": "448.54236 mm", "rod.segments.1.length": "1345.62708 mm"}


def _cheb(f, a, b, atol, max_deg=128, depth=0):
    """Chebyshev interpolants of ``f`` on ``[a, b]`` at points of the first kind (none at the ends):
    ``[(a, b, coefs), ...]``, the degree doubled from 16 until the last three coefficients are below
    ``atol``, else the interval halved (at most 6 times; then the last fit, its tail returned)."""
    n = 16
    while True:
        x = np.cos(np.pi * (np.arange(n + 1) + 0.5) / (n + 1))
        vals = f(0.5 * (a + b) + 0.5 * (b - a) * x)
        c = dct(vals, type=2) / (n + 1)
        c[0] *= 0.5
        tail = float(np.max(np.abs(c[-3:])))
        if tail <= atol:
            return [(a, b, c)], 0.0
        if n >= max_deg:
            break
        n *= 2
    if depth >= 6:
        return [(a, b, c)], tail
    m = 0.5 * (a + b)
    left, e1 = _cheb(f, a, m, atol, max_deg, depth + 1)
    right, e2 = _cheb(f, m, b, atol, max_deg, depth + 1)
    return left + right, max(e1, e2)


class _Local:
    """A function on one step as Chebyshev interpolants (a list of ``(a, b, coefs)``)."""

    __slots__ = ("parts", "starts")

    def __init__(self, parts):
        self.parts = parts
        self.starts = [p[0] for p in parts]

    def __call__(self, t):
        if np.ndim(t) == 0:
            a, b, c = self.parts[max(bisect.bisect_right(self.starts, t) - 1, 0)]
            return float(C.chebval((2.0 * t - a - b) / (b - a), c))
        t = np.asarray(t, dtype=float)
        out = np.empty(t.shape)
        idx = np.clip(np.searchsorted(self.starts, t, side="right") - 1, 0, len(self.parts) - 1)
        for i in np.unique(idx):
            a, b, c = self.parts[i]
            sel = idx == i
            out[sel] = C.chebval((2.0 * t[sel] - a - b) / (b - a), c)
        return out

    def combine(self, other, x, y):
        """``x self + y other`` (the same parts; as one interpolant where they differ)."""
        same = len(self.parts) == len(other.parts)
        if same and all(p[0] == q[0] for p, q in zip(self.parts, other.parts, strict=True)):
            parts = []
            for (a, b, c), (_, _, d) in zip(self.parts, other.parts, strict=True):
                n = max(c.size, d.size)
                parts.append((a, b, x * np.pad(c, (0, n - c.size)) + y * np.pad(d, (0, n - d.size))))
            return _Local(parts)
        a, b = self.parts[0][0], self.parts[-1][1]
        size = max(float(np.max(np.abs(c))) for _, _, c in self.parts + other.parts)
        return _Local(_cheb(lambda t: x * self(t) + y * other(t), a, b, 1e-15 * size)[0])


class _Stream:
    """A wave emitted at a node over time: its value before the impact (``before``) and one function a
    step after it."""

    def __init__(self, before):
        self.before = before
        self.starts: list = []
        self.funcs: list = []

    def add(self, a, func):
        self.starts.append(a)
        self.funcs.append(func)

    def __call__(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.empty(t.shape)
        neg = t < 0.0
        if np.any(neg):
            out[neg] = self.before(t[neg])
        if np.any(~neg):
            tt = t[~neg]
            idx = np.searchsorted(self.starts, tt, side="right") - 1
            res = np.empty(tt.shape)
            for i in np.unique(idx):
                sel = idx == i
                res[sel] = self.funcs[max(i, 0)](tt[sel])
            out[~neg] = res
        return out


@dataclass
class ReferenceBlow:
    """The blow's numbers by :func:`reference_blow` (model units, times from the impact).

    Attributes
    ----------
    duration : float
        The blow's length (default the window ``4/s + 2 sum T_i``).
    v_after : float
        The piston's mean velocity at the end (its momentum: mass 1), from the waves in it.
    v_balance : float
        The same from the momentum balance: arrival velocity plus the circuit's impulse less the
        shank's.
    work_on_rock : float
        ``int R dp + f^2 / (2 k_u)`` (theory §4d).
    drive_state : numpy.ndarray, shape (4,)
        The circuit's ``(p_f, p_r, p_s, x_v)`` at the end.
    w : float
        The driven end's displacement ``-u(0)`` at the end.
    drive_work : float
        The circuit's work on the piston over the blow.
    shank_displacement, gap, max_penetration, permanent_penetration : float
        At the end; the penetrations from the rock's surface (the rest under the feed at ``f / k``).
    end_position : float
        The struck end's position from the next flight's stop: shank less gap less permanent
        penetration.
    steps : int
        The method of steps' intervals.
    fit_error : float
        The largest Chebyshev tail left where a fit did not converge (0 where all did).
    events : list of tuple
        ``(t, what)``: the contact's and the rock's switches.
    waves : tuple of list
        The waves each node emitted, ``(F, G)``: ``F[j]`` into segment ``j`` at its left node,
        ``G[j]`` at its right node, each a callable of the time (arrays).
    """

    duration: float
    v_after: float
    v_balance: float
    work_on_rock: float
    drive_state: np.ndarray
    w: float
    drive_work: float
    shank_displacement: float
    gap: float
    max_penetration: float
    permanent_penetration: float
    end_position: float
    steps: int
    fit_error: float
    events: list
    waves: tuple = ()


def reference_blow(model, drive, state, q, v, *, rtol=1e-12, fit_tol=1e-14, duration=None):
    r"""The coupled blow of a rigid, uniform piston arriving on the shank in state ``(q, q')`` with
    the oil circuit in ``state``, solved as a delay-differential system (module docstring).

    Parameters
    ----------
    model : BarModel
        Under :class:`~impactbar.RodRock` with a bit of mass ``> 0``, a rigid (``n_modes = 0``) and
        uniform piston.
    drive : HydraulicCircuitDrive
        The preset circuit (its compiled vector field during a blow).
    state : DriveState
        The circuit's state at the arrival (a valve not ramping: no circuit event in the blow).
    q, v : array_like, shape (1,)
        The piston's modal state at the arrival (its struck end on the shank).
    rtol : float
        The integrator's relative tolerance (absolute: ``rtol`` times each state's scale).
    fit_tol : float
        The Chebyshev fits' tolerance, relative to the impact's wave ``Z_0 v_0``.
    duration : float, optional
        How long the blow lasts (model time from the impact; default the law's window
        ``4/s + 2 sum T_i``): the library's blow ends when it is certified over, and is compared over
        its own duration.

    Returns
    -------
    ReferenceBlow

    Raises
    ------
    ValueError
        A model outside those above, or a circuit event inside the blow.

    Examples
    --------
    >>> import inspect
    >>> list(inspect.signature(reference_blow).parameters)[:5]
    ['model', 'drive', 'state', 'q', 'v']
    """
    import circuit_blow_reference as EK
    import circuit_field_reference as FK
    from impactbar.drives.circuit.drive import _rate_model

    law = model.law
    if model.n_modes != 0 or getattr(model, "piston", None) is not None:
        raise ValueError("model: the reference takes a rigid, uniform piston (n_modes = 0)")
    if not law.bit_mass > 0.0:
        raise ValueError(f"model: the reference takes a bit of mass > 0, got {law.bit_mass}")
    s = float(model.s)
    R = len(law.segments)
    Z = [s] + [float(g.impedance) * s for g in law.segments]
    T = [1.0 / s] + [float(g.travel_time(model)) for g in law.segments]
    mb, k, ku, f = float(law.bit_mass), float(law.rock.k), float(law.rock.k_u), float(law.feed)
    D = 4.0 / s + 2.0 * sum(T[1:]) if duration is None else float(duration)
    Tmin = min(T)
    v0 = float(np.asarray(v, dtype=float)[0])
    mode = state.mode
    z0 = np.array(state.z, dtype=float)
    par = FK.preset_par(drive, _rate_model(1), mode)
    alpha = float(drive.chambers.area_ratio)
    L = drive.layout
    p0 = float(z0[L["rear"]] - alpha * z0[L["front"]])
    scale = abs(Z[0] * v0)
    atol_fit = fit_tol * scale
    merge = 1e-12 * D

    # the waves emitted at each node: F[j] into segment j from its left node, G[j] from its right
    T0 = T[0]
    # (before the impact: the rigid piston's fields, v = v_0 and N = p_0 (1 - x); the rod at rest)
    F = [_Stream(lambda t: 0.5 * (p0 * (1.0 + t / T0) + Z[0] * v0))]
    G = [_Stream(lambda t: 0.5 * (p0 * (-t / T0) - Z[0] * v0))]
    F += [_Stream(np.zeros_like) for _ in range(R)]
    G += [_Stream(np.zeros_like) for _ in range(R)]

    def f_in(j):  # the right-going wave arriving at node j (1..R+1)
        src, d = F[j - 1], T[j - 1]
        return lambda t: src(np.asarray(t) - d)

    def g_in(j):  # the left-going wave arriving at node j (0..R)
        src, d = G[j], T[j]
        return lambda t: src(np.asarray(t) - d)

    # state: circuit (w, z, I, E), bit (p, p'), shank displacement, gap, shank impulse, work on rock
    nc = EK.N_STATE
    IB, IV, IX, IG, IN, IW = nc, nc + 1, nc + 2, nc + 3, nc + 4, nc + 5
    y = np.zeros(nc + 6)
    y[0] = -float(np.asarray(model.drive_weights) @ np.asarray(q, dtype=float))
    y[1:1 + L.n_states] = z0
    y_scale = np.ones(y.size)
    y_scale[0] = y_scale[IX] = y_scale[IG] = y_scale[IB] = 1e-3
    y_scale[5:nc] = 1e-2
    y_scale[IN] = y_scale[IW] = 1e-2
    atol = rtol * y_scale

    # breakpoints: (time, node); every arrival at a node is re-emitted both ways
    heap: list = []
    seen: list = [[] for _ in range(R + 2)]

    def push(t, j):
        if t > D + merge:
            return
        lst = seen[j]
        i = bisect.bisect_left(lst, t - merge)
        if i < len(lst) and lst[i] <= t + merge:
            return
        lst.insert(i, t)
        heapq.heappush(heap, (t, j))

    def emit(t, j):
        if j >= 1:
            push(t + T[j - 1], j - 1)
        if j <= R:
            push(t + T[j], j + 1)

    push(0.0, 0)
    push(0.0, 1)
    contact, loading, lifted = True, True, False
    pmax = 0.0  # the largest penetration above the rest under the feed
    t_bit = sum(T[1:])  # the impact's wave reaches the bit
    events: list = []
    fit_error = 0.0
    ext = np.array([0.0, 1.0 / Z[0]])
    out_c = np.zeros(nc)
    steps = 0
    Z0, Z1, ZR = Z[0], Z[1], Z[R]
    cz = 2.0 / (Z0 + Z1)

    def perm():
        return (pmax + f / k) * (1.0 - k / ku)  # the permanent penetration from the rock's surface

    def rock(pb):
        """The rock's force above the feed at the penetration ``pb`` above the rest."""
        if loading:
            return k * pb
        return max(-f, ku * (pb + f / k - perm()) - f)

    t = 0.0
    y_end = y
    while t < D - merge:
        while heap and heap[0][0] <= t + merge:
            tb, j = heapq.heappop(heap)
            emit(tb, j)
        t1 = min(heap[0][0] if heap else D, t + Tmin, D)
        fits = {}
        for name, fn in [("g0", g_in(0))] + [(f"f{j}", f_in(j)) for j in range(1, R + 2)] + \
                [(f"g{j}", g_in(j)) for j in range(1, R + 1)]:
            parts, err = _cheb(fn, t, t1, atol_fit)
            fits[name] = _Local(parts)
            fit_error = max(fit_error, err)
        g0, f1, g1, fd = fits["g0"], fits["f1"], fits["g1"], fits[f"f{R + 1}"]

        def force_n(tt, f1=f1, g1=g1):
            return cz * (Z1 * f1(tt) + Z0 * g1(tt))

        # switches at the step's start (a step wave that turns the contact at once)
        if contact and force_n(t) < 0.0:
            contact = False
            events.append((t, "separation"))
            emit(t, 1)
        elif not contact and y[IG] <= 0.0 and -2.0 * g1(t) / Z1 - 2.0 * f1(t) / Z0 < 0.0:
            contact = True
            events.append((t, "contact"))
            emit(t, 1)

        def rhs(tt, yy, contact=contact, g0=g0, f1=f1, g1=g1, fd=fd, force_n=force_n):
            ext[0] = -2.0 * g0(tt) / Z0
            dy = np.empty_like(yy)
            EK.rhs(yy[:nc], out_c, par, ext)
            dy[:nc] = out_c
            fi, gi = f1(tt), g1(tt)
            if contact:
                n = force_n(tt)
                dy[IX] = (n - 2.0 * gi) / Z1
                dy[IG] = 0.0
            else:
                n = 0.0
                dy[IX] = -2.0 * gi / Z1
                dy[IG] = dy[IX] - 2.0 * fi / Z0
            dy[IN] = n
            pb, vb = yy[IB], yy[IV]
            r = rock(pb)
            dy[IB] = vb
            dy[IV] = (2.0 * fd(tt) - ZR * vb - r) / mb
            dy[IW] = (f + r) * vb
            return dy

        evs, names = [], []
        if contact:
            def e_sep(tt, yy, force_n=force_n):
                return force_n(tt)
            e_sep.terminal, e_sep.direction = True, -1
            evs.append(e_sep)
            names.append("separation")
        else:
            def e_con(tt, yy):
                return yy[IG]
            e_con.terminal, e_con.direction = True, -1
            evs.append(e_con)
            names.append("contact")
        if t >= t_bit - merge:
            if loading:
                def e_unl(tt, yy):
                    return yy[IV]
                e_unl.terminal, e_unl.direction = True, -1
                evs.append(e_unl)
                names.append("unloading")
            else:
                pm, pp = pmax, perm()

                def e_rel(tt, yy, pm=pm):
                    return yy[IB] - pm
                e_rel.terminal, e_rel.direction = True, 1
                evs.append(e_rel)
                names.append("reloading")

                def e_lift(tt, yy, pp=pp):
                    return yy[IB] + f / k - pp
                e_lift.terminal, e_lift.direction = True, (1 if lifted else -1)
                evs.append(e_lift)
                names.append("landing" if lifted else "lift-off")
        g_before = np.ones(EK.N_EVENTS)
        EK.events(y[:nc], g_before, par)
        sol = solve_ivp(rhs, (t, t1), y, method="DOP853", rtol=rtol, atol=atol, events=evs, dense_output=True)
        if sol.status < 0:
            raise ValueError(f"the reference's integration failed at t = {t:.6g}: {sol.message}")
        steps += 1
        te = float(sol.t[-1])
        y_end = sol.y[:, -1].copy()
        g_after = np.ones(EK.N_EVENTS)
        EK.events(y_end[:nc], g_after, par)
        if np.any(np.sign(g_before) != np.sign(g_after)):
            raise ValueError(f"a circuit event inside the blow near t = {te:.6g}: not in the reference")
        dense = sol.sol
        fired = [names[i] for i, te_i in enumerate(sol.t_events) if te_i.size] if sol.status == 1 else []

        # the waves the nodes emitted over [t, te]
        def f_out0(tt, dense=dense, g0=g0):
            yy = dense(tt)
            return yy[2] - alpha * yy[1] - g0(tt)

        def g_outr(tt, dense=dense, fd=fd):
            return fd(tt) - ZR * dense(tt)[IV]

        F[0].add(t, f_out0)
        G[R].add(t, g_outr)
        if contact:
            n = fits["f1"].combine(fits["g1"], cz * Z1, cz * Z0)
            G[0].add(t, n.combine(fits["f1"], 1.0, -1.0))
            F[1].add(t, n.combine(fits["g1"], 1.0, -1.0))
        else:
            G[0].add(t, fits["f1"].combine(fits["f1"], -1.0, 0.0))
            F[1].add(t, fits["g1"].combine(fits["g1"], -1.0, 0.0))
        for j in range(2, R + 1):
            fa, gb = fits[f"f{j}"], fits[f"g{j}"]
            cj = 2.0 / (Z[j - 1] + Z[j])
            n = fa.combine(gb, cj * Z[j], cj * Z[j - 1])
            G[j - 1].add(t, n.combine(fa, 1.0, -1.0))
            F[j].add(t, n.combine(gb, 1.0, -1.0))

        for what in fired:
            events.append((te, what))
            if what == "separation":
                contact = False
                emit(te, 1)
            elif what == "contact":
                contact = True
                y_end[IG] = 0.0
                emit(te, 1)
            elif what == "unloading":
                loading, lifted = False, False
                pmax = float(y_end[IB])
                emit(te, R + 1)
            elif what == "reloading":
                loading = True
                emit(te, R + 1)
            else:
                lifted = what == "lift-off"
                emit(te, R + 1)
        y = y_end
        t = te

    # the piston's momentum from its waves at the end: int (F - G) dtheta over its travel time
    xg, wg = np.polynomial.legendre.leggauss(48)

    def integral(stream, a, b):
        cuts = [a] + [c for c in stream.starts if a < c < b] + [b]
        total = 0.0
        for lo, hi in zip(cuts[:-1], cuts[1:], strict=True):
            total += 0.5 * (hi - lo) * float(wg @ stream(0.5 * (lo + hi) + 0.5 * (hi - lo) * xg))
        return total

    v_after = integral(F[0], D - T0, D) - integral(G[0], D - T0, D)
    v_balance = v0 + y[5] - y[IN]
    if loading:
        pmax = max(pmax, float(y[IB]))
    pp = perm()  # from the rock's surface
    return ReferenceBlow(
        duration=D, v_after=v_after, v_balance=v_balance, work_on_rock=float(y[IW] + f * f / (2.0 * ku)),
        drive_state=y[1:1 + L.n_states].copy(), w=float(y[0]),
        drive_work=float(y[6 + L.energy["piston"]]), shank_displacement=float(y[IX]), gap=float(y[IG]),
        max_penetration=pmax + f / k, permanent_penetration=pp,
        end_position=float(y[IX] - y[IG] - pp), steps=steps, fit_error=fit_error, events=events,
        waves=(F, G))


def drifter_arrival(values=None):
    """The oil-circuit drifter of ``examples/circuit_drifter_rock.toml`` (its rod as given, or with the
    config ``values``, e.g. :data:`WHOLE_CELLS`), its second arrival at the shank from a run on the
    lattice (16 cells per piston, the first blow ended at the law's window: the arrival the tests'
    figures were measured at) from rest 0.05 behind the shank.

    Parameters
    ----------
    values : dict, optional
        Dotted config keys and their values.

    Returns
    -------
    tuple
        ``(model, drive, state, t0, q, v)``: the model on exact blows, the circuit, its state at the
        arrival, the arrival's time and the piston's modal state.

    Examples
    --------
    >>> sorted(WHOLE_CELLS)
    ['rod.segments.0.length', 'rod.segments.1.length']
    """
    import dataclasses

    import impactbar as ib
    from impactbar.physical import build, read_config, with_values

    cfg, _ = read_config("examples/circuit_drifter_rock.toml")
    del cfg["rock"]["cells_per_piston"]
    cfg["rock"].pop("contact_events", None)  # (the lattice's plain events: the arrival as measured)
    if values:
        cfg = with_values(cfg, values)
    drifter = build(cfg)
    model, drive = drifter.model(), drifter.drive()
    exact = model.with_(impact=dataclasses.replace(model.law, method="exact"))
    lattice = model.with_(impact=dataclasses.replace(model.law, method="lattice", cells_per_piston=16,
                                                     driven_end="window"))
    start = ib.InitialState.rigid(-0.05, 0.0, n_modes=model.n_modes)
    blow = ib.simulate(lattice, drive, start, 7.0).impacts[1]
    state = ib.simulate(lattice, drive, start, blow.t0 - 1e-12)._final_drive
    return exact, drive, state, blow.t0, blow.q_before, blow.v_before


def slots_model(model, cells: int):
    """``model`` with its rod-rock law's blows on the slot lattice of ``cells`` cells a piston
    (``method="lattice"``, ``contact_events="slots"``).

    Parameters
    ----------
    model : BarModel
        Under :class:`~impactbar.RodRock` (:func:`drifter_arrival`'s).
    cells : int
        Cells per piston.

    Returns
    -------
    BarModel
    """
    import dataclasses

    law = dataclasses.replace(model.law, method="lattice", cells_per_piston=cells, contact_events="slots")
    return model.with_(impact=law)


def held_blow(arrival, model, window: float = 14.0):
    """The blow of ``model`` (a model of :func:`drifter_arrival`'s, its law as the caller set it) from
    ``arrival`` with the drive's force held at its value there, over ``window`` travel times of the
    piston (``window / s``): no drive's state, so that what differs is the rod's and the bit's.

    Parameters
    ----------
    arrival : tuple
        :func:`drifter_arrival`'s.
    model : BarModel
        The model whose law solves the blow (its ``blow_time`` set here).
    window : float, optional
        The blow's duration in the piston's travel times.

    Returns
    -------
    tuple of float
        ``(v_after[0], work dissipated in the rock)``: the piston's velocity after the blow and the
        work on the rock less the energy stored in it at the end (model units).
    """
    import dataclasses

    from impactbar.loads import FourierLoad

    _, drive, state, _, q, v = arrival
    load = FourierLoad(float(drive.force(state.mode, state.z, q, v)), [])
    m = model.with_(impact=dataclasses.replace(model.law, blow_time=window / model.s))
    _, va, _, rec = m.law.contact(m, load, 0.0, q, v)
    return float(va[0]), float(rec.blow.work_on_rock - rec.blow.rock_stored_energy)


def blow_differences(c, ex):
    """A coupled blow ``c``'s differences from another, ``ex`` (``DrivenContact``s; the exact one),
    each relative and absolute: the work dissipated in the rock, the permanent penetration, the
    circuit's state after the blow (its largest component's) and the piston's velocity after it.

    Returns
    -------
    numpy.ndarray, shape (4,)
    """
    b, bx = c.record.blow, ex.record.blow
    z_ex = np.asarray(ex.drive_state.z)
    return np.array([abs(b.work_on_rock / bx.work_on_rock - 1.0),
                     abs(b.permanent_penetration / bx.permanent_penetration - 1.0),
                     float(np.max(np.abs(np.asarray(c.drive_state.z) - z_ex) / np.abs(z_ex))),
                     abs(c.v_after[0] / ex.v_after[0] - 1.0)])
