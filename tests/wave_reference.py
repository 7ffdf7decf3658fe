"""An independent reference for the wave law's force history: the whole system, piston plus
semi-infinite rod, on characteristics, with no modes (tests only).

The piston ``0 < x < 1`` (``d = 0``) carries the Riemann invariants ``alpha = v + N/s`` (to the rod)
and ``beta = v - N/s`` (to the drive) unchanged along its characteristics; in ``theta = s t`` a wave
crosses it in 1. With ``A(theta)`` the invariant arriving at the rod end and ``B(theta)`` the one sent
back from it, the drive end gives ``alpha(0) = beta(0) + 2 p/s``, hence the scalar recursion with
delay 2

    A(theta) = B(theta - 2) + 2 p(t(theta) - 1/s) / s,

and the rod end closes it: ``B = -R A`` in contact (the rod's impedance ``s (1 + R)/(1 - R)``, the
interface force ``F = s (1 + R) A / 2``), ``B = A`` separated (a free end), with the gap
``g' = -A / s`` (per ``theta``) while separated (the rod end stands still: it carries a right-going
wave only). Contact ends when ``A`` turns negative and resumes when the gap closes. The flights
between blows are the same recursion with a free end: the whole motion, blows and flights, needs
nothing else, so this reference shares no code and no truncation with the modal solver.

It is marched on a grid of step ``h = 1/J`` in ``theta``, a block of length 2 at a time (the delay);
the invariants are exact at the nodes; a switch is located between nodes by linear interpolation and
acts from the next node, so switch instants carry an error ``O(h)`` in the history they leave behind,
and extremes of the force are read at the nodes (``O(h^2)`` at a smooth extremum, ``O(h |F'|)``
at a jump). Started from any piston state on a stable orbit, the blows forget the start as ``R^k``
(every blow sends the fraction ``1 - R^2`` of the piston's wave energy into the rod and the flights
keep the rest at ``d = 0``), so after many load periods the blows are those of the exact orbit,
independent of the start; :func:`steady_blows` reports how much the last two cycles still differ.
"""

from __future__ import annotations

import math

import numpy as np


def _series_fields(s, q, v, p_end, x):
    """``alpha0, beta0`` at ``x`` from a modal state (any start will do: the reference forgets it);
    the strain carries the end force ``p_end`` at ``x = 0`` linearly."""
    n = np.arange(q.size)
    vel = np.cos(np.pi * np.outer(x, n)) @ (v * np.where(n == 0, 1.0, 2.0))
    se = -np.sin(np.pi * np.outer(x, n)) @ (2 * s * np.pi * n * q)
    se += -p_end / s * (1.0 - x) + np.sin(np.pi * np.outer(x, n[1:])) @ (2 * p_end / (s * np.pi * n[1:]))
    return vel - se, vel + se


def march(s, R, load, t_start, q, v, periods, J=20000, keep=None):
    """March the whole system from contact at ``t_start`` (state ``q, v``, the piston end on the rod
    end) over ``periods`` load periods. With ``keep`` (a ``theta``) the invariants ``A``, ``B`` at
    the rod end from ``keep`` on are returned too (the fields inside the piston follow from them:
    ``alpha(x, theta) = A(theta + 1 - x)``, ``beta(x, theta) = B(theta - 1 + x)``).

    Returns
    -------
    theta : numpy.ndarray
        Grid times (``theta = s (t - t_start)``).
    F : numpy.ndarray
        Interface force at the nodes (0 while separated).
    switches : list of (float, bool)
        Switch instants (``theta``) and the state entered (True: contact).
    A, B : numpy.ndarray
        Only with ``keep``: the invariants at the nodes ``theta >= keep`` (from the block holding it).
    """
    h = 1.0 / J
    As, Bs, kept = [], [], None
    n_blk = 2 * J
    jj = np.arange(n_blk)
    x = 1.0 - jj[:J] * h
    p_end = float(load(t_start))
    al0, be0 = _series_fields(s, q, v, p_end, np.concatenate((x, jj[:J] * h)))
    A = np.concatenate((al0[:J], be0[J:] + 2.0 * np.asarray(load(t_start + jj[:J] * h / s)) / s))
    total = int(math.ceil(periods * 2.0 * math.pi * s / 2.0))
    Fs, thetas, switches = [], [], []
    on, gap, a_last = True, 0.0, None
    B = np.zeros(n_blk)  # B on the previous block (the first block's A is the start state's)
    for k in range(total):
        th0 = 2.0 * k
        if k > 0:
            A = B + 2.0 * np.asarray(load(t_start + (th0 + jj * h - 1.0) / s)) / s
        B = np.empty(n_blk)
        F = np.zeros(n_blk)
        pos = 0
        while pos < n_blk:
            if on:
                neg = np.flatnonzero(A[pos:] < 0.0)
                end = n_blk if neg.size == 0 else pos + neg[0]
                B[pos:end] = -R * A[pos:end]
                F[pos:end] = 0.5 * s * (1.0 + R) * A[pos:end]
                if end == n_blk:
                    break
                # separation where the interpolant of A crosses zero
                prev = A[end - 1] if end > 0 else a_last
                frac = prev / (prev - A[end]) if prev is not None and prev > 0.0 else 0.0
                th_sep = th0 + (end - 1 + frac) * h
                switches.append((th_sep, False))
                on = False
                gap = -0.5 * A[end] * (1.0 - frac) * h / s  # from the switch to the node
                B[end] = A[end]
                pos = end + 1
                a_last = A[end]
            else:
                seg = A[pos:]
                prev = a_last if pos == 0 else A[pos - 1]
                prev = seg[0] if prev is None else prev
                steps = 0.5 * (np.concatenate(([prev], seg[:-1])) + seg) * h / s
                g = gap - np.cumsum(steps)
                hit = np.flatnonzero(g <= 0.0)
                if hit.size == 0:
                    B[pos:] = seg
                    gap = float(g[-1])
                    break
                i = hit[0]
                g_before = gap if i == 0 else g[i - 1]
                frac = g_before / (g_before - g[i])
                th_re = th0 + (pos + i - 1 + frac) * h
                switches.append((th_re, True))
                B[pos:pos + i] = seg[:i]
                on, gap = True, 0.0
                pos = pos + i
            a_last = A[pos - 1] if pos > 0 else a_last
        a_last = A[-1]
        Fs.append(F)
        thetas.append(th0 + jj * h)
        if keep is not None and th0 + 2.0 > keep:
            As.append(A)
            Bs.append(B.copy())
            kept = len(thetas) - 1 if kept is None else kept
    if keep is None:
        return np.concatenate(thetas), np.concatenate(Fs), switches
    return (np.concatenate(thetas), np.concatenate(Fs), switches, np.concatenate(As),
            np.concatenate(Bs), thetas[kept][0])


def piston_stress_extremes(s, R, load, t_start, q, v, periods, J=2000):
    """Largest and smallest axial force in the piston, ``N = s (alpha - beta)/2``, over the window
    ``[0, 2]`` of the last blow whose window and the crossing time before it lie in the last two load
    periods, at the nodes of the ``J``-cell lattice. Returns ``(phase, max, min)``."""
    theta, F, switches, A, B, th_k = march(s, R, load, t_start, q, v, periods, J,
                                           keep=2.0 * math.pi * s * (periods - 2))
    starts = [t for t, c in switches if c and t - 1.0 >= th_k and t + 3.0 <= theta[-1]]
    tb = starts[-1]
    kb = int(math.ceil((tb - th_k) * J - 1e-9))  # the first node in contact
    i = np.arange(J + 1)
    hi, lo = -np.inf, np.inf
    for m in range(2 * J + 1):
        N = 0.5 * s * (A[kb + m + J - i] - B[kb + m - J + i])
        hi = max(hi, float(N.max()))
        lo = min(lo, float(N.min()))
    return (t_start + tb / s) % (2.0 * math.pi), hi, lo


def steady_blows(s, R, load, t_start, q, v, periods=60, cycle=1, J=20000):
    """The blows of the last ``cycle`` load periods after marching ``periods`` of them.

    Returns
    -------
    blows : list of dict
        For each blow of the last cycle (sorted by its start): ``phase`` (load time of the impact,
        modulo ``2 pi cycle``), ``peak`` and ``min`` (largest and smallest interface force over the
        window ``2/s`` from the impact; ``min`` is 0 where contact is lost), ``switches`` (separation
        and re-contact instants inside the window, time since the impact).
    drift : float
        Largest change of a blow's phase or peak between the last two cycles (self-convergence).
    """
    theta, F, switches = march(s, R, load, t_start, q, v, periods, J)
    T = 2.0 * math.pi * cycle * s  # theta per cycle
    window = 2.0
    starts = [th for th, c in switches if c]
    blows = []
    last_start = -np.inf
    for th in starts:
        if th - last_start > window + 1e-9:
            blows.append(th)
            last_start = th
    full = [th for th in blows if th + window <= theta[-1]]
    if not full:
        return [], math.inf
    top = full[-1] + 1.0  # the cycles end just after the last blow with a whole window
    out = {}
    for label, lo in (("last", top - T), ("prev", top - 2 * T)):
        res = []
        for th in full:
            if lo <= th < lo + T:
                m = (theta >= th) & (theta <= th + window)
                inner = [(t - th) / s for t, c in switches if th < t < th + window - 1e-12]
                res.append({"phase": (t_start + th / s) % (2 * math.pi * cycle),
                            "peak": float(F[m].max()), "min": float(F[m].min()),
                            "switches": inner})
        out[label] = sorted(res, key=lambda b: b["phase"])
    drift = max((max(abs(a["phase"] - b["phase"]), abs(a["peak"] - b["peak"]))
                 for a, b in zip(out["last"], out["prev"], strict=True)), default=math.inf)
    if len(out["last"]) != len(out["prev"]):
        drift = math.inf
    return out["last"], drift


def steady_fields(s, R, load, t_start, q, v, periods=60, cycle=1, J=20000):
    """The piston's fields at the impact of each blow of the last ``cycle`` load periods, after
    marching ``periods`` of them: the exact fields of the steady motion (jumps and all), to hand to
    the modal solver projected on its modes (:func:`project`).

    Returns
    -------
    list of (t0, alpha0, beta0, F)
        Load time of the impact, the invariants at ``x = j/J`` (``j = 0..J``) at that instant, and
        the interface force at the nodes of the window ``[0, 2]`` (in ``theta``) that follows.
    """
    theta, F, switches, A, B, th_k = march(s, R, load, t_start, q, v, periods, J,
                                           keep=2.0 * math.pi * s * (periods - cycle - 1))
    th = th_k + np.arange(A.size) / J
    blows = []
    for t, on in switches:
        if on and t - 1.0 > th_k and t + 2.0 < th[-1] and (not blows or t - blows[-1] > 2.0 + 1e-9):
            blows.append(t)
    T = 2.0 * math.pi * s * cycle
    out = []
    jj = np.arange(J + 1)
    for tb in blows:
        if tb < blows[-1] - T + 1e-9:
            continue
        kb = int(round((tb - th_k) * J))  # the impact's node (the switch acts from a node)
        tbn = th_k + kb / J
        k0 = int(np.searchsorted(theta, tbn - 0.5 / J))
        out.append((t_start + tbn / s, A[kb + J - jj], B[kb - J + jj], F[k0:k0 + 2 * J]))
    return out


def project(s, alpha, beta, model):
    """The modal state ``(q, v)`` of fields given as invariants at ``x = j/J``: the first ``N + 1``
    free-free modes by the trapezoidal rule (``O(1/J)`` at a jump), ``u(1) = 0``."""
    J = alpha.size - 1
    x = np.arange(J + 1) / J
    w = np.full(J + 1, 1.0 / J)
    w[[0, -1]] = 0.5 / J
    n = np.arange(model.n_modes + 1)
    v = np.cos(np.pi * np.outer(n, x)) @ (0.5 * (alpha + beta) * w)  # v_n = int v cos(n pi x)
    sux = 2.0 * np.sin(np.pi * np.outer(n, x)) @ (0.5 * (beta - alpha) * w)  # s u_x's sine terms
    q = np.zeros(n.size)
    q[1:] = -sux[1:] / (2.0 * s * np.pi * n[1:])
    q[0] = -(model.end_weights[1:] @ q[1:])
    return q, v


def random_state(rng, model, amplitude):
    """A modal state with ``u(1) = 0`` and ``u_t(1) = 1`` (arriving at unit speed)."""
    N, s = model.n_modes, model.s
    n = np.arange(1, N + 2)
    q = amplitude * rng.normal(size=N + 1) / (s * np.pi * n)
    v = rng.normal(size=N + 1) / n
    v[1:] *= amplitude
    c = model.end_weights
    q[0] = -(c[1:] @ q[1:])
    v[0] += 1.0 - c @ v
    return q, v
