r"""The oil circuit's vector field, its Jacobian and its event functions, compiled with numba
(theory §11). Plain arrays only: what SUNDIALS' CVODE calls at every step (as C callbacks,
:mod:`._cvode`, or through scikit-sundae's interface).

The integrated state is ``Y = (q_0..q_N, q_0'..q_N', p_f, p_r, p_s, x_v, E_0..E_7[, Phi])``: the bar's
modes (eq. 6), the circuit's state, eight energy quadratures (the terms of the account of theory
§11: pump work, work on the piston, orifice losses, energy to the tank, the compression work of the
front, rear and supply volumes, the accumulator's gas) and, for the variational equations, the
fundamental matrix ``Phi`` of the first ``n = 2 N + 6`` components, stored by columns (column ``j`` at
``n + 8 + j n``: each column's equations couple only its own ``n`` components, so that the Newton
matrix is banded, of half-bandwidth ``n - 1``), ``Phi' = A Phi`` with ``A`` the Jacobian of the vector
field.

``par`` holds the parameters and the mode (indices below); the callers write the mode's flags
before each flight.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ...dynamics.compiled import CACHE

# parameter indices in ``par``
ALPHA, NUR, NUF, KV, KF, QP, NUS, PT, PREL, KREL, P0, NU0, NPOL, BETA, PTR2 = range(15)
HELD, PSH, XOUT, XIN, ACC, REL, XRATE, ARMO, ARMI, DAMP, NM, OPEN, VAR, HASREL, HASACC = range(15, 30)
HEAD = 30  # then the struck end's weights (M), the squared frequencies (M) and the driven end's (M)

N_ENERGY = 8
N_EVENTS = 6
ARRIVAL_EV, OUT_EV, IN_EV, RAMP_EV, ACC_EV, REL_EV = range(N_EVENTS)

_JIT = dict(cache=CACHE, nogil=True, error_model="numpy")  # (in memory where no cache is writable)


@nb.njit(**_JIT)
def phi(dp, ptr2):
    """The smoothed turbulent orifice law ``dp (dp^2 + p_tr^2)^(-1/4)``."""
    return dp * (dp * dp + ptr2) ** -0.25


@nb.njit(**_JIT)
def dphi(dp, ptr2):
    """``phi'(dp)``."""
    s = dp * dp + ptr2
    return s ** -0.25 - 0.5 * dp * dp * s ** -1.25


@nb.njit(**_JIT)
def end_motion(y, par, M):
    """The piston's driven end at ``y``: its displacement ``w`` away from where it is on the stop and
    its rate ``w'``, ``-sum e_i q_i`` and ``-sum e_i q_i'`` with the driven end's weights ``e``."""
    w = 0.0
    wd = 0.0
    for i in range(M):
        e = par[HEAD + 2 * M + i]
        w -= e * y[i]
        wd -= e * y[M + i]
    return w, wd


@nb.njit(**_JIT)
def _flows(y, par, M):
    """The flows and the chambers' volumes at ``y``: ``(w, w', q_f, q_in, q_out, q_rel, nu_f, nu_r, c_a,
    C)``."""
    w, wd = end_motion(y, par, M)
    F = 2 * M
    pf, pr, ps, xv = y[F], y[F + 1], y[F + 2], y[F + 3]
    ptr2 = par[PTR2]
    qf = par[KF] * phi(ps - pf, ptr2)
    qin = par[KV] * xv * phi(ps - pr, ptr2)
    qout = par[KV] * (1.0 - xv) * phi(pr - par[PT], ptr2)
    qrel = par[KREL] * (ps - par[PREL]) if par[REL] > 0.5 else 0.0
    nuf = par[NUF] + par[ALPHA] * w
    nur = par[NUR] - w
    ca = 0.0
    if par[ACC] > 0.5:
        n = par[NPOL]
        ca = par[NU0] / n * par[P0] ** (1.0 / n) * ps ** (-1.0 / n - 1.0)
    C = par[NUS] / par[BETA] + ca
    return w, wd, qf, qin, qout, qrel, nuf, nur, ca, C


@nb.njit(**_JIT)
def _base(y, par, M, out):
    """The vector field of the first ``n`` components and the energy integrands into ``out``."""
    F = 2 * M
    w, wd, qf, qin, qout, qrel, nuf, nur, ca, C = _flows(y, par, M)
    pf, pr, ps = y[F], y[F + 1], y[F + 2]
    alpha, b, d = par[ALPHA], par[BETA], par[DAMP]
    p = pr - alpha * pf
    for i in range(M):
        out[i] = y[M + i]
        out[M + i] = p - d * y[M + i] - par[HEAD + M + i] * y[i]
    dpf = b / nuf * (qf - alpha * wd)
    dpr = b / nur * (qin - qout + wd)
    held = par[HELD] > 0.5
    dps = 0.0 if held else (par[QP] - qf - qin - qrel) / C
    out[F] = dpf
    out[F + 1] = dpr
    out[F + 2] = dps
    out[F + 3] = par[XRATE]
    E = F + 4
    out[E] = ps * (qf + qin) if held else ps * par[QP]
    out[E + 1] = -p * wd
    out[E + 2] = qf * (ps - pf) + qin * (ps - pr) + qout * (pr - par[PT]) + qrel * (ps - par[PT])
    out[E + 3] = par[PT] * (qout + qrel)
    out[E + 4] = nuf * pf * dpf / b
    out[E + 5] = nur * pr * dpr / b
    out[E + 6] = 0.0 if held else par[NUS] * ps * dps / b
    out[E + 7] = 0.0 if held else ps * ca * dps


@nb.njit(**_JIT)
def jac_base(y, par, M, A):
    """The Jacobian ``A`` (``n x n``, ``n = 2 M + 4``) of the vector field of ``(q, q', p_f, p_r, p_s,
    x_v)``."""
    n = 2 * M + 4
    for i in range(n):
        for j in range(n):
            A[i, j] = 0.0
    F = 2 * M
    w, wd, qf, qin, qout, qrel, nuf, nur, ca, C = _flows(y, par, M)
    pf, pr, ps, xv = y[F], y[F + 1], y[F + 2], y[F + 3]
    alpha, b, d, kv, kf, ptr2 = par[ALPHA], par[BETA], par[DAMP], par[KV], par[KF], par[PTR2]
    for i in range(M):
        A[i, M + i] = 1.0
        A[M + i, i] = -par[HEAD + M + i]
        A[M + i, M + i] = -d
        A[M + i, F] = -alpha
        A[M + i, F + 1] = 1.0
    fpf = b / nuf * (qf - alpha * wd)
    fpr = b / nur * (qin - qout + wd)
    for i in range(M):
        e = par[HEAD + 2 * M + i]
        A[F, i] = fpf * alpha * e / nuf
        A[F, M + i] = b * alpha * e / nuf
        A[F + 1, i] = -fpr * e / nur
        A[F + 1, M + i] = -b * e / nur
    dqf = kf * dphi(ps - pf, ptr2)
    gin = phi(ps - pr, ptr2)
    dgin = dphi(ps - pr, ptr2)
    gout = phi(pr - par[PT], ptr2)
    dgout = dphi(pr - par[PT], ptr2)
    A[F, F] = -b / nuf * dqf
    A[F, F + 2] = b / nuf * dqf
    A[F + 1, F + 1] = -b / nur * kv * (xv * dgin + (1.0 - xv) * dgout)
    A[F + 1, F + 2] = b / nur * kv * xv * dgin
    A[F + 1, F + 3] = b / nur * kv * (gin + gout)
    if par[HELD] < 0.5:
        dC = 0.0
        if par[ACC] > 0.5:
            dC = ca * (-1.0 / par[NPOL] - 1.0) / ps
        drel = par[KREL] if par[REL] > 0.5 else 0.0
        num = par[QP] - qf - qin - qrel
        A[F + 2, F] = dqf / C
        A[F + 2, F + 1] = kv * xv * dgin / C
        A[F + 2, F + 2] = (-dqf - kv * xv * dgin - drel) / C - num * dC / (C * C)
        A[F + 2, F + 3] = -kv * gin / C


@nb.njit(**_JIT)
def rhs(t, y, yp, par):
    """CVODE's right-hand side: ``yp = f(y)`` of the integrated state (module docstring)."""
    M = int(par[NM])
    n = 2 * M + 4
    _base(y, par, M, yp)
    if par[VAR] > 0.5:
        A = np.empty((n, n))
        jac_base(y, par, M, A)
        phi_rate(A, y, yp, n + N_ENERGY)


@nb.njit(**_JIT)
def phi_rate(A, y, yp, off):
    """``Phi' = A Phi`` into ``yp`` from ``Phi`` in ``y``, stored by columns from ``off`` (``n`` the
    order of ``A``)."""
    n = A.shape[0]
    # A's nonzeros by rows (some 9 M + 10 of n^2), each row's in increasing column, and Phi by
    # rows: each entry of A Phi is the sum over the row's nonzeros, from 0 in increasing column (its
    # zeros skipped), the sums of n entries side by side (each row's contiguous)
    cols = np.empty(n * n, np.int64)
    vals = np.empty(n * n)
    rows = np.empty(n + 1, np.int64)
    nz = 0
    for i in range(n):
        rows[i] = nz
        for k in range(n):
            a = A[i, k]
            if a != 0.0:
                cols[nz] = k
                vals[nz] = a
                nz += 1
    rows[n] = nz
    P = np.empty((n, n))
    for j in range(n):  # column j of Phi at off + j n
        for k in range(n):
            P[k, j] = y[off + j * n + k]
    out = np.zeros((n, n))
    for i in range(n):
        for p in range(rows[i], rows[i + 1]):
            a = vals[p]
            k = cols[p]
            for j in range(n):
                out[i, j] += a * P[k, j]
    for j in range(n):
        for i in range(n):
            yp[off + j * n + i] = out[i, j]


@nb.njit(**_JIT)
def jac(t, y, yp, JJ, par):
    """CVODE's Jacobian of :func:`rhs` for its Newton iteration: ``A`` on the circuit and the bar,
    ``A`` on each column of ``Phi`` (the term in ``dA/dy Phi`` left out: the iteration matrix need
    not be exact), zero rows for the energy quadratures (they feed nothing back)."""
    M = int(par[NM])
    n = 2 * M + 4
    A = np.empty((n, n))
    jac_base(y, par, M, A)
    jac_blocks(A, JJ, n + N_ENERGY if par[VAR] > 0.5 else -1)


@nb.njit(**_JIT)
def jac_blocks(A, JJ, off):
    """``JJ`` zero but ``A`` in its leading block and, where ``off >= 0``, into the block of each column of
    ``Phi`` (stored by columns from ``off``)."""
    N = JJ.shape[0]
    for i in range(N):
        for j in range(N):
            JJ[i, j] = 0.0
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            JJ[i, j] = A[i, j]
    if off >= 0:
        for col in range(n):  # Phi[:, col] at off + col n
            c = off + col * n
            for i in range(n):
                for k in range(n):
                    JJ[c + i, c + k] = A[i, k]


@nb.njit(**_JIT)
def events(t, y, g, par):
    """The event functions (their zeros; inactive ones held at 1): the arrival at the stop
    ``c . q``, the gap through ``switch_out`` and ``switch_in``, the ramp's end, the supply pressure
    through the pre-charge and through the relief pressure."""
    M = int(par[NM])
    F = 2 * M
    bar_events(y, par, M, g)
    circuit_events(y[F + 3], y[F + 2], par, g, RAMP_EV)


@nb.njit(**_JIT)
def bar_events(y, par, M, g):
    """The bar's and the valve's switches' event functions into ``g[:RAMP_EV]``: the arrival at the
    stop ``c . q``, the gap through ``switch_out`` and ``switch_in`` (where armed, else 1)."""
    s = 0.0
    for i in range(M):
        s += par[HEAD + i] * y[i]
    g[ARRIVAL_EV] = s
    g[OUT_EV] = -y[0] - par[XOUT] if par[ARMO] > 0.5 else 1.0
    g[IN_EV] = -y[0] - par[XIN] if par[ARMI] > 0.5 else 1.0


@nb.njit(**_JIT)
def circuit_events(xv, ps, par, g, first):
    """The circuit's own event functions into ``g[first:first + 3]``, from the spool's position
    ``xv`` and the supply pressure ``ps`` (inactive ones held at 1): the ramp's end, the supply
    through the pre-charge and through the relief pressure (each pressure's :func:`_off_level`);
    the flights' (:func:`events`) and the blows' (``_endfield.events``)."""
    if par[OPEN] > 0.5:
        g[first] = xv - 1.0
    elif par[OPEN] < -0.5:
        g[first] = xv
    else:
        g[first] = 1.0
    g[first + 1] = _off_level(ps - par[P0], par[ACC], par[P0]) if par[HASACC] > 0.5 else 1.0
    g[first + 2] = _off_level(ps - par[PREL], par[REL], par[PREL]) if par[HASREL] > 0.5 else 1.0


@nb.njit(**_JIT)
def _off_level(g, above, level):
    """An event function ``p - level`` exactly 0 moved by one unit in the last place of ``level`` to
    the side the mode's flag says the pressure is on (``above`` 1: at or above the level, watched
    for falling through it): the level is crossed where the pressure passes it, not where it
    touches it. A flight starts on the level where its event ended the last flight, and over the
    first steps the pressure's change can be below the rounding of the level: CVODE leaves an event
    function that is 0 at the start unwatched until it moves off 0 (a pressure that turns back
    through the level at once was missed, and CVODE warned that a root function stayed identically
    0), and takes a 0 after a step for a root (the accumulator would empty at once where the pump
    fills it)."""
    if g != 0.0:
        return g
    u = np.spacing(abs(level))
    return u if above > 0.5 else -u


@nb.njit(**_JIT)
def field_at(ys, par, out):
    """The vector field of the first ``n`` components at each row of ``ys`` (for the histories'
    Hermite interpolation and the saltation matrices)."""
    M = int(par[NM])
    n = 2 * M + 4
    buf = np.empty(n + N_ENERGY)
    for r in range(ys.shape[0]):
        _base(ys[r], par, M, buf)
        for j in range(n + N_ENERGY):
            out[r, j] = buf[j]
