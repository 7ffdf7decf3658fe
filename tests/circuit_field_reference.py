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
(``impactbar.drives.circuit._bar``). ``par`` (:func:`preset_par`) is the drive's
(``HydraulicCircuitDrive._par``: the bar's entries, indices those of ``_bar``) with, in place of the
network, this reference's own parameters of the preset's parts (indices below, from ``HEAD + 3 M``),
written here from the drive's parts: the library's kernels read the network instead.
"""

import math
from types import SimpleNamespace

import numba as nb
import numpy as np

from impactbar.drives.circuit._bar import (
    DAMP,
    HEAD,
    N_ENERGY,
    N_EVENTS,
    NM,
    RAMP_EV,
    VAR,
    bar_events,
    end_motion,
    jac_blocks,
    phi_rate,
)
from impactbar.drives.circuit.kinds._flow import dphi, phi
from impactbar.drives.circuit.kinds.level import _off_level
from impactbar.dynamics.compiled import CACHE

_JIT = dict(cache=CACHE, nogil=True, error_model="numpy")

# this reference's parameters of the preset's parts, from ``HEAD + 3 M`` in ``par``: the chambers',
# the valve's and the supply's values, the accumulator's, the oil's, then the mode's flags and the
# parts present
ALPHA, NUR, NUF, KV, KF, QP, NUS, PT, PREL, KREL, P0, NU0, NPOL, BETA, PTR2 = range(15)
HELD, ACC, REL, XRATE, OPEN, HASREL, HASACC = range(15, 22)
N_PRESET = 22


def preset_par(drive, model, mode, variational=False):
    """The parameter vector of these kernels for the preset drive ``drive`` on the bar ``model`` in
    the mode ``mode = (target, moving, acc, relief)``: the drive's (its bar's entries) and then this
    reference's parameters of the preset's parts (module docstring), from the drive's parts."""
    ch, va, su, oil, acc = drive.chambers, drive.valve, drive.supply, drive.oil, drive.accumulator
    target, moving, acc_on, rel_on = mode[:4]
    has_acc = acc is not None and acc.volume > 0 and not su.held
    own = np.zeros(N_PRESET)
    own[ALPHA], own[NUR], own[NUF] = ch.area_ratio, ch.rear_volume, ch.front_volume
    own[KV], own[KF] = va.coefficient, su.front_coefficient
    own[QP] = su.pump_flow if su.pump_flow is not None else 0.0
    own[NUS], own[PT] = su.hose_volume, su.tank_pressure
    own[PREL] = su.relief_pressure if math.isfinite(su.relief_pressure) else 1e300
    own[KREL] = su.relief_coefficient
    own[P0] = acc.precharge if acc is not None else 1.0
    own[NU0] = acc.volume if has_acc else 0.0
    own[NPOL] = acc.polytropic_exponent if acc is not None else 1.4
    own[BETA], own[PTR2] = oil.bulk_modulus, oil.transition_pressure ** 2
    own[HELD] = 1.0 if su.held else 0.0
    own[ACC], own[REL] = float(acc_on), float(rel_on)
    tau = va.switching_time
    own[XRATE] = (1.0 if target else -1.0) / tau if moving else 0.0
    own[OPEN] = (1.0 if target else -1.0) if moving else 0.0
    own[HASREL] = 1.0 if su.has_relief and not su.held else 0.0
    own[HASACC] = 1.0 if has_acc else 0.0
    return np.concatenate((drive._par(model, mode, variational), own))


@nb.njit(**_JIT)
def _flows(y, par, M):
    """The flows and the chambers' volumes at ``y``: ``(w, w', q_f, q_in, q_out, q_rel, nu_f, nu_r, c_a,
    C)``."""
    w, wd = end_motion(y, par, M)
    F = 2 * M
    o = HEAD + 3 * M
    pf, pr, ps, xv = y[F], y[F + 1], y[F + 2], y[F + 3]
    ptr2 = par[o + PTR2]
    qf = par[o + KF] * phi(ps - pf, ptr2)
    qin = par[o + KV] * xv * phi(ps - pr, ptr2)
    qout = par[o + KV] * (1.0 - xv) * phi(pr - par[o + PT], ptr2)
    qrel = par[o + KREL] * (ps - par[o + PREL]) if par[o + REL] > 0.5 else 0.0
    nuf = par[o + NUF] + par[o + ALPHA] * w
    nur = par[o + NUR] - w
    ca = 0.0
    if par[o + ACC] > 0.5:
        n = par[o + NPOL]
        ca = par[o + NU0] / n * par[o + P0] ** (1.0 / n) * ps ** (-1.0 / n - 1.0)
    C = par[o + NUS] / par[o + BETA] + ca
    return w, wd, qf, qin, qout, qrel, nuf, nur, ca, C


@nb.njit(**_JIT)
def _base(y, par, M, out):
    """The vector field of the first ``n`` components and the energy integrands into ``out``."""
    F = 2 * M
    o = HEAD + 3 * M
    w, wd, qf, qin, qout, qrel, nuf, nur, ca, C = _flows(y, par, M)
    pf, pr, ps = y[F], y[F + 1], y[F + 2]
    alpha, b, d = par[o + ALPHA], par[o + BETA], par[DAMP]
    p = pr - alpha * pf
    for i in range(M):
        out[i] = y[M + i]
        out[M + i] = p - d * y[M + i] - par[HEAD + M + i] * y[i]
    dpf = b / nuf * (qf - alpha * wd)
    dpr = b / nur * (qin - qout + wd)
    held = par[o + HELD] > 0.5
    dps = 0.0 if held else (par[o + QP] - qf - qin - qrel) / C
    out[F] = dpf
    out[F + 1] = dpr
    out[F + 2] = dps
    out[F + 3] = par[o + XRATE]
    E = F + 4
    out[E] = ps * (qf + qin) if held else ps * par[o + QP]
    out[E + 1] = -p * wd
    out[E + 2] = qf * (ps - pf) + qin * (ps - pr) + qout * (pr - par[o + PT]) + qrel * (ps - par[o + PT])
    out[E + 3] = par[o + PT] * (qout + qrel)
    out[E + 4] = nuf * pf * dpf / b
    out[E + 5] = nur * pr * dpr / b
    out[E + 6] = 0.0 if held else par[o + NUS] * ps * dps / b
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
    o = HEAD + 3 * M
    w, wd, qf, qin, qout, qrel, nuf, nur, ca, C = _flows(y, par, M)
    pf, pr, ps, xv = y[F], y[F + 1], y[F + 2], y[F + 3]
    alpha, b, d = par[o + ALPHA], par[o + BETA], par[DAMP]
    kv, kf, ptr2 = par[o + KV], par[o + KF], par[o + PTR2]
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
    gout = phi(pr - par[o + PT], ptr2)
    dgout = dphi(pr - par[o + PT], ptr2)
    A[F, F] = -b / nuf * dqf
    A[F, F + 2] = b / nuf * dqf
    A[F + 1, F + 1] = -b / nur * kv * (xv * dgin + (1.0 - xv) * dgout)
    A[F + 1, F + 2] = b / nur * kv * xv * dgin
    A[F + 1, F + 3] = b / nur * kv * (gin + gout)
    if par[o + HELD] < 0.5:
        dC = 0.0
        if par[o + ACC] > 0.5:
            dC = ca * (-1.0 / par[o + NPOL] - 1.0) / ps
        drel = par[o + KREL] if par[o + REL] > 0.5 else 0.0
        num = par[o + QP] - qf - qin - qrel
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
    circuit_events(y[F + 3], y[F + 2], par, HEAD + 3 * M, g, RAMP_EV)


@nb.njit(**_JIT)
def circuit_events(xv, ps, par, o, g, first):
    """The circuit's own event functions into ``g[first:first + 3]``, from the spool's position
    ``xv``, the supply pressure ``ps`` and the preset's parameters from ``par[o]`` (inactive ones held
    at 1): the ramp's end, the supply
    through the pre-charge and through the relief pressure (each pressure's :func:`_off_level`);
    the flights' (:func:`events`) and the blows' (``circuit_blow_reference.events``)."""
    if par[o + OPEN] > 0.5:
        g[first] = xv - 1.0
    elif par[o + OPEN] < -0.5:
        g[first] = xv
    else:
        g[first] = 1.0
    p0, prel = par[o + P0], par[o + PREL]
    g[first + 1] = _off_level(ps - p0, par[o + ACC], p0) if par[o + HASACC] > 0.5 else 1.0
    g[first + 2] = _off_level(ps - prel, par[o + REL], prel) if par[o + HASREL] > 0.5 else 1.0


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
        par = nb.carray(user_data, HEAD + 3 * M + N_PRESET)
        rhs(t, nb.carray(_nv_data(y), N), nb.carray(_nv_data(yp), N), par)
        return 0

    @nb.cfunc(_c(_d, _p, _p, _p, _dp, _p, _p, _p), cache=CACHE)
    def jac_c(t, y, fy, J, user_data, tmp1, tmp2, tmp3):
        M, N = _sizes(user_data)
        par = nb.carray(user_data, HEAD + 3 * M + N_PRESET)
        JJ = nb.carray(_dense_data(J), (N, N)).T
        jac(t, nb.carray(_nv_data(y), N), nb.carray(_nv_data(fy), N), JJ, par)
        return 0

    @nb.cfunc(_c(_d, _p, _p, _p, _dp, _p, _p, _p), cache=CACHE)
    def jac_band_c(t, y, fy, J, user_data, tmp1, tmp2, tmp3):
        M, N = _sizes(user_data)
        par = nb.carray(user_data, HEAD + 3 * M + N_PRESET)
        n = 2 * M + 4
        A = np.empty((n, n))
        jac_base(nb.carray(_nv_data(y), N), par, M, A)
        band_blocks(A, J, N, N_ENERGY)
        return 0

    @nb.cfunc(_c(_d, _p, _dp, _dp), cache=CACHE)
    def events_c(t, y, g, user_data):
        M, N = _sizes(user_data)
        par = nb.carray(user_data, HEAD + 3 * M + N_PRESET)
        events(t, nb.carray(_nv_data(y), N), nb.carray(g, N_EVENTS), par)
        return 0

    return rhs_c, jac_c, jac_band_c, events_c, N_EVENTS


#: the hand-written kernels as ``circuit_flight``'s ``kernels`` (the names of a generated module's)
KERNELS = SimpleNamespace(flight_rhs=rhs, flight_jac=jac, flight_events=events, field_at=field_at,
                          jac_base=jac_base, CALLBACKS=_callbacks(), network=False, par=preset_par)
