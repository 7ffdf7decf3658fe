r"""The preset circuit's vector field, its Jacobian and its event functions written by hand (theory
§11): the tests' reference for the code the library generates for the preset drifter's network
(``impactbar.drives.circuit._netgen``), which must give the same numbers to the bit, and a flight's
kernels for ``circuit_flight(..., kernels=KERNELS)`` (CVODE's C callbacks included where SUNDIALS is
driven from compiled code), which must take the same steps as the generated code's.

The integrated state is ``Y = (q_0..q_N, q_0'..q_N', p_f, p_r, p_s, x_v, E_0..E_7[, Phi])``: the bar's
modes (eq. 6), the circuit's state, eight energy quadratures (the terms of the account of theory
§11: pump work, work on the piston, orifice losses, energy to the tank, the compression work of the
front, rear and supply volumes, the accumulator's gas) and, for the variational equations, the
fundamental matrix ``Phi`` of the first ``n = 2 N + 6`` components, stored by columns
(``impactbar.drives.circuit._bar``). ``par`` is the drive's (``HydraulicCircuitDrive._par``), its
indices those of ``_bar``, without the network after it.
"""

from types import SimpleNamespace

import numba as nb
import numpy as np

from impactbar.drives.circuit._bar import (
    ACC,
    ALPHA,
    BETA,
    DAMP,
    HASACC,
    HASREL,
    HEAD,
    HELD,
    KF,
    KREL,
    KV,
    N_ENERGY,
    N_EVENTS,
    NM,
    NPOL,
    NU0,
    NUF,
    NUR,
    NUS,
    OPEN,
    P0,
    PREL,
    PT,
    PTR2,
    QP,
    RAMP_EV,
    REL,
    VAR,
    XRATE,
    bar_events,
    end_motion,
    jac_blocks,
    phi_rate,
)
from impactbar.drives.circuit.kinds._flow import dphi, phi
from impactbar.drives.circuit.kinds.level import _off_level
from impactbar.dynamics.compiled import CACHE

_JIT = dict(cache=CACHE, nogil=True, error_model="numpy")


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
def events(t, y, g, par):
    """The event functions (their zeros; inactive ones held at 1): the arrival at the stop
    ``c . q``, the gap through ``switch_out`` and ``switch_in``, the ramp's end, the supply pressure
    through the pre-charge and through the relief pressure."""
    M = int(par[NM])
    F = 2 * M
    bar_events(y, par, M, g)
    circuit_events(y[F + 3], y[F + 2], par, g, RAMP_EV)


@nb.njit(**_JIT)
def circuit_events(xv, ps, par, g, first):
    """The circuit's own event functions into ``g[first:first + 3]``, from the spool's position
    ``xv`` and the supply pressure ``ps`` (inactive ones held at 1): the ramp's end, the supply
    through the pre-charge and through the relief pressure (each pressure's :func:`_off_level`);
    the flights' (:func:`events`) and the blows' (``circuit_blow_reference.events``)."""
    if par[OPEN] > 0.5:
        g[first] = xv - 1.0
    elif par[OPEN] < -0.5:
        g[first] = xv
    else:
        g[first] = 1.0
    g[first + 1] = _off_level(ps - par[P0], par[ACC], par[P0]) if par[HASACC] > 0.5 else 1.0
    g[first + 2] = _off_level(ps - par[PREL], par[REL], par[PREL]) if par[HASREL] > 0.5 else 1.0


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


def _callbacks():
    """CVODE's C callbacks of :func:`rhs`, :func:`jac` (dense, and in band storage for the variational
    flights) and :func:`events` (``user_data`` is ``par``), as the generated module's ``CALLBACKS``:
    ``(rhs, jac, jac_band, events, number of events)``; ``None`` where SUNDIALS is not driven from
    compiled code."""
    try:
        from impactbar.drives.circuit import _cvode as CV
    except ImportError:
        return None
    _c, _d, _p, _dp = CV._c, CV._d, CV._p, CV._dp
    _nv_data, _dense_data, band_blocks = CV._nv_data, CV._dense_data, CV.band_blocks

    @nb.njit(inline="always")
    def _sizes(par):
        M = int(par[NM])
        n = 2 * M + 4
        return M, n + N_ENERGY + (n * n if par[VAR] > 0.5 else 0)

    @nb.cfunc(_c(_d, _p, _p, _dp), cache=CACHE)
    def rhs_c(t, y, yp, user_data):
        M, N = _sizes(user_data)
        par = nb.carray(user_data, HEAD + 3 * M)
        rhs(t, nb.carray(_nv_data(y), N), nb.carray(_nv_data(yp), N), par)
        return 0

    @nb.cfunc(_c(_d, _p, _p, _p, _dp, _p, _p, _p), cache=CACHE)
    def jac_c(t, y, fy, J, user_data, tmp1, tmp2, tmp3):
        M, N = _sizes(user_data)
        par = nb.carray(user_data, HEAD + 3 * M)
        JJ = nb.carray(_dense_data(J), (N, N)).T
        jac(t, nb.carray(_nv_data(y), N), nb.carray(_nv_data(fy), N), JJ, par)
        return 0

    @nb.cfunc(_c(_d, _p, _p, _p, _dp, _p, _p, _p), cache=CACHE)
    def jac_band_c(t, y, fy, J, user_data, tmp1, tmp2, tmp3):
        M, N = _sizes(user_data)
        par = nb.carray(user_data, HEAD + 3 * M)
        n = 2 * M + 4
        A = np.empty((n, n))
        jac_base(nb.carray(_nv_data(y), N), par, M, A)
        band_blocks(A, J, N, N_ENERGY)
        return 0

    @nb.cfunc(_c(_d, _p, _dp, _dp), cache=CACHE)
    def events_c(t, y, g, user_data):
        M, N = _sizes(user_data)
        par = nb.carray(user_data, HEAD + 3 * M)
        events(t, nb.carray(_nv_data(y), N), nb.carray(g, N_EVENTS), par)
        return 0

    return rhs_c, jac_c, jac_band_c, events_c, N_EVENTS


#: the hand-written kernels as ``circuit_flight``'s ``kernels`` (the names of a generated module's)
KERNELS = SimpleNamespace(flight_rhs=rhs, flight_jac=jac, flight_events=events, field_at=field_at,
                          jac_base=jac_base, CALLBACKS=_callbacks(), network=False)
