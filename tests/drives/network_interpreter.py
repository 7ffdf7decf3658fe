"""The circuit's network of part records (``impactbar.drives.circuit._network``) interpreted: one
compiled vector field, Jacobian and set of event functions that read any network's records after the
bar's entries of ``par`` (the loops over the records; the equations of each kind in
``_network``'s docstring). The library runs the code generated for a network's topology
(``_netgen``), which the tests check against this interpreter (and both against the hand-written
kernel ``circuit_field_reference`` for the preset drifter) to the bit.

The sums run in the order of the records, from ``-0.0`` (so that a sum's first term is that term,
sign of a zero included).
"""

import numba as nb
import numpy as np

from impactbar.drives.circuit import kinds as KD
from impactbar.drives.circuit._bar import DAMP, HEAD, end_motion
from impactbar.drives.circuit._network import (
    A_E,
    A_EV,
    A_N,
    A_NODE,
    A_ON,
    A_P0,
    A_V,
    A_WATCH,
    ACCUM,
    C_AREA,
    C_NODE,
    CHAMBER,
    CHECK,
    CUSHION,
    F_E,
    F_FROM,
    F_TO,
    KIND,
    LEAK,
    LEVEL,
    LV_EV,
    N_BETA,
    N_ECOMP,
    N_ESIGN,
    N_EWORK,
    N_HELD,
    N_P,
    N_V,
    NW_EPISTON,
    NW_NEN,
    NW_NEV,
    NW_NNODE,
    NW_NREC,
    NW_NSTATE,
    NW_SIZE,
    O_E,
    O_FROM,
    O_K,
    O_PTR2,
    O_TO,
    ORIFICE,
    P_E,
    P_FLOW,
    P_NODE,
    PUMP,
    R_E,
    R_EV,
    R_FROM,
    R_K,
    R_OPEN,
    R_SET,
    R_TO,
    R_WATCH,
    REC_SIZE,
    RELIEF,
    SPOOL,
    SPOOL_PORT,
    V_A,
    V_E,
    V_EV,
    V_K,
    V_OPEN,
    V_P,
    V_PTR2,
    V_RATE,
    V_T,
    VALVE,
)
from impactbar.drives.circuit.kinds._flow import dphi, phi
from impactbar.drives.circuit.kinds.level import _off_level
from impactbar.dynamics.compiled import CACHE

# the rows of the nodes' scratch
# (columns: the nodes; ``_SCA``, an accumulator's compliance, by record)
_SP, _SNU, _SNET, _SF, _SC, _SDC, _SNAC, _SCH, _SDP, _SCA = range(10)
_NSCRATCH = 10

_JIT = dict(cache=CACHE, nogil=True, error_model="numpy")


@nb.njit(**_JIT)
def _pressure(par, R0, y, F, ns, j):
    """Node ``j``'s pressure: its state, or a held node's own pressure."""
    return y[F + j] if j < ns else par[R0 + j * REC_SIZE + N_P]


@nb.njit(**_JIT)
def _record(par, R0, k):
    """Record ``k``'s offset in ``par`` and its kind (the records from ``R0``)."""
    r = R0 + k * REC_SIZE
    return r, int(par[r + KIND])


@nb.njit(**_JIT)
def _prepare(y, par, M, S, en, dp, energies):
    """The nodes' pressures, volumes, net inflows, capacitances and rates into the scratch ``S``,
    ``p'`` of the nodes with a state into ``dp``, with ``energies`` the energy integrands into ``en``;
    returns ``(force, w', x_v')``."""
    F = 2 * M
    net0 = HEAD + 3 * M
    nrec = int(par[net0 + NW_NREC])
    nn = int(par[net0 + NW_NNODE])
    ns = int(par[net0 + NW_NSTATE])
    R0 = net0 + NW_SIZE
    w, wd = end_motion(y, par, M)
    gap = -y[0]
    xv = y[F + ns]
    if energies:
        for k in range(en.shape[0]):
            en[k] = -0.0
    for j in range(nn):
        r = R0 + j * REC_SIZE
        S[_SP, j] = y[F + j] if j < ns else par[r + N_P]
        S[_SNU, j] = par[r + N_V]
        S[_SNET, j] = -0.0
        S[_SF, j] = 1.0
        S[_SDC, j] = 0.0
        S[_SNAC, j] = 0.0
        S[_SCH, j] = 0.0
    # one pass in the records' order (the kinds' order): the flows, then the chambers (their volumes,
    # their inflow from the piston's motion, the force on the bar), then the accumulators (their
    # compliance; each node's capacitance V / beta first)
    force = -0.0
    rate = 0.0
    capacitance = False
    for k in range(nn, nrec):
        r, kind = _record(par, R0, k)
        if kind == PUMP:
            a = int(par[r + P_NODE])
            q = par[r + P_FLOW]
            S[_SNET, a] += q
            if energies and par[r + P_E] >= 0:
                en[int(par[r + P_E])] += S[_SP, a] * q
        elif kind == ORIFICE:
            a, b = int(par[r + O_FROM]), int(par[r + O_TO])
            dpab = S[_SP, a] - S[_SP, b]
            q = par[r + O_K] * phi(dpab, par[r + O_PTR2])
            S[_SNET, a] -= q
            S[_SNET, b] += q
            if energies and par[r + O_E] >= 0:
                en[int(par[r + O_E])] += q * dpab
        elif kind == VALVE:
            P, A, T = int(par[r + V_P]), int(par[r + V_A]), int(par[r + V_T])
            kv, ptr2 = par[r + V_K], par[r + V_PTR2]
            rate = par[r + V_RATE]
            qin = kv * xv * phi(S[_SP, P] - S[_SP, A], ptr2)
            qout = kv * (1.0 - xv) * phi(S[_SP, A] - S[_SP, T], ptr2)
            S[_SNET, P] -= qin
            S[_SNET, A] += qin
            S[_SNET, A] -= qout
            S[_SNET, T] += qout
            if energies and par[r + V_E] >= 0:
                ie = int(par[r + V_E])
                en[ie] += qin * (S[_SP, P] - S[_SP, A])
                en[ie] += qout * (S[_SP, A] - S[_SP, T])
        elif kind == RELIEF:
            a, b = int(par[r + R_FROM]), int(par[r + R_TO])
            q = par[r + R_K] * (S[_SP, a] - par[r + R_SET]) if par[r + R_OPEN] > 0.5 else 0.0
            S[_SNET, a] -= q
            S[_SNET, b] += q
            if energies and par[r + R_E] >= 0:
                en[int(par[r + R_E])] += q * (S[_SP, a] - S[_SP, b])
        elif kind == CHAMBER:
            a = int(par[r + C_NODE])
            area = par[r + C_AREA]
            S[_SNU, a] = S[_SNU, a] + area * w
            S[_SNET, a] += -area * wd
            S[_SCH, a] = 1.0
            force += -area * S[_SP, a]
        elif kind == ACCUM:
            if not capacitance:
                _capacitances(par, R0, nn, S)
                capacitance = True
            S[_SCA, k] = 0.0
            if par[r + A_ON] > 0.5:
                a = int(par[r + A_NODE])
                ca = _compliance(par, r, S[_SP, a])
                S[_SCA, k] = ca
                S[_SC, a] = S[_SC, a] + ca
                dc = ca * (-1.0 / par[r + A_N] - 1.0) / S[_SP, a]
                S[_SDC, a] = dc if S[_SNAC, a] == 0.0 else S[_SDC, a] + dc
                S[_SNAC, a] += 1.0
        elif kind == SPOOL:
            rate = _spool(par, r, R0, S, xv, en, energies)
        elif kind == LEAK or kind == CUSHION or kind == CHECK or kind == SPOOL_PORT:  # (a kind of .kinds)
            a, b = int(par[r + F_FROM]), int(par[r + F_TO])
            q = KD.law(kind, par, r, S[_SP, a], S[_SP, b], xv if kind == SPOOL_PORT else gap)[0]
            S[_SNET, a] -= q
            S[_SNET, b] += q
            if energies and par[r + F_E] >= 0:
                en[int(par[r + F_E])] += q * (S[_SP, a] - S[_SP, b])
    if not capacitance:
        _capacitances(par, R0, nn, S)
    # the rates and the nodes' energies
    for j in range(ns):
        r = R0 + j * REC_SIZE
        held = par[r + N_HELD] > 0.5
        if held:
            S[_SDP, j] = 0.0
        elif S[_SCH, j] > 0.5:
            S[_SF, j] = par[r + N_BETA] / S[_SNU, j]
            S[_SDP, j] = S[_SF, j] * S[_SNET, j]
        else:
            S[_SDP, j] = S[_SNET, j] / S[_SC, j]
        dp[j] = S[_SDP, j]
    if not energies:
        return force, wd, rate
    for j in range(nn):
        r = R0 + j * REC_SIZE
        held = j >= ns or par[r + N_HELD] > 0.5
        if held and par[r + N_EWORK] >= 0:
            en[int(par[r + N_EWORK])] += S[_SP, j] * (par[r + N_ESIGN] * S[_SNET, j])
        if j < ns and par[r + N_ECOMP] >= 0:
            en[int(par[r + N_ECOMP])] += 0.0 if held else \
                S[_SNU, j] * S[_SP, j] * S[_SDP, j] / par[r + N_BETA]
    for k in range(nn, nrec):
        r, kind = _record(par, R0, k)
        if kind == ACCUM and par[r + A_E] >= 0:
            a = int(par[r + A_NODE])
            held = a >= ns or par[R0 + a * REC_SIZE + N_HELD] > 0.5
            en[int(par[r + A_E])] += 0.0 if held else S[_SP, a] * S[_SCA, k] * S[_SDP, a]
    ep = int(par[net0 + NW_EPISTON])
    en[ep] += -force * wd
    return force, wd, rate


@nb.njit(**_JIT)
def _spool(par, r, R0, S, xv, en, energies):
    """A spool's record at ``r`` (:mod:`.kinds.spool`): the control chamber's and the supply's volumes
    and net inflows, the spool's force into its velocity node, its damping's loss; returns ``x_v'``."""
    c, s, v = int(par[r + KD.spool.CONTROL]), int(par[r + KD.spool.SUPPLY]), int(par[r + KD.spool.VELOCITY])
    hs, b = par[r + KD.spool.STROKE], par[r + KD.spool.DAMPING]
    ac, a0 = par[r + KD.spool.LARGE], par[r + KD.spool.SMALL]
    vs = S[_SP, v]
    S[_SNU, c] = S[_SNU, c] + ac * hs * xv
    S[_SNET, c] += -ac * vs
    S[_SNU, s] = S[_SNU, s] - a0 * hs * xv
    S[_SNET, s] += a0 * vs
    S[_SNET, v] += KD.spool.force(par, r, S[_SP, c], S[_SP, s]) - b * vs
    if energies and par[r + KD.spool.ENERGY] >= 0:
        en[int(par[r + KD.spool.ENERGY])] += b * vs * vs
    return 0.0 if par[R0 + v * REC_SIZE + N_HELD] > 0.5 else vs / hs


@nb.njit(**_JIT)
def _spool_jac(par, r, R0, S, A, F, X, ns):
    """A spool's terms of the Jacobian (before the nodes' rows are divided by their capacitance)."""
    c, s, v = int(par[r + KD.spool.CONTROL]), int(par[r + KD.spool.SUPPLY]), int(par[r + KD.spool.VELOCITY])
    hs, b = par[r + KD.spool.STROKE], par[r + KD.spool.DAMPING]
    ac, a0 = par[r + KD.spool.LARGE], par[r + KD.spool.SMALL]
    if c < ns:
        A[F + v, F + c] += ac
        A[F + c, F + v] += -ac
        A[F + c, X] += -S[_SNET, c] * (ac * hs / par[R0 + c * REC_SIZE + N_BETA]) / S[_SC, c]
    if s < ns:
        A[F + v, F + s] += -a0
        A[F + s, F + v] += a0
        A[F + s, X] += S[_SNET, s] * (a0 * hs / par[R0 + s * REC_SIZE + N_BETA]) / S[_SC, s]
    A[F + v, F + v] += -b
    if par[R0 + v * REC_SIZE + N_HELD] < 0.5:
        A[X, F + v] += 1.0 / hs


@nb.njit(**_JIT)
def _capacitances(par, R0, nn, S):
    """Each node's ``V / beta`` into ``S`` (its volume's with the chambers' change)."""
    for j in range(nn):
        S[_SC, j] = S[_SNU, j] / par[R0 + j * REC_SIZE + N_BETA]


@nb.njit(**_JIT)
def _compliance(par, r, p):
    """The accumulator at record offset ``r``'s compliance at the pressure ``p`` (holding oil)."""
    n = par[r + A_N]
    return par[r + A_V] / n * par[r + A_P0] ** (1.0 / n) * p ** (-1.0 / n - 1.0)


@nb.njit(**_JIT)
def sizes(par, M):
    """``(nodes, states, energies, events)`` of the network in ``par`` on an ``M``-mode bar."""
    net0 = HEAD + 3 * M
    return (int(par[net0 + NW_NNODE]), int(par[net0 + NW_NSTATE]), int(par[net0 + NW_NEN]),
            int(par[net0 + NW_NEV]))


@nb.njit(**_JIT)
def _columns(par, M):
    """The scratch's columns: one a record (the nodes' first)."""
    return int(par[HEAD + 3 * M + NW_NREC])


@nb.njit(**_JIT)
def base(y, par, M, out):
    """The vector field of ``(q, q', p_0..p_{S-1}, x_v)`` and the energy integrands into ``out``
    (``2 M + S + 1 + K`` entries)."""
    F = 2 * M
    nn, ns, nen, _ = sizes(par, M)
    S = np.empty((_NSCRATCH, _columns(par, M)))
    E = F + ns + 1
    force, wd, rate = _prepare(y, par, M, S, out[E:E + nen], out[F:F + ns], True)
    d = par[DAMP]
    for i in range(M):
        out[i] = y[M + i]
        out[M + i] = force - d * y[M + i] - par[HEAD + M + i] * y[i]
    out[F + ns] = rate


@nb.njit(**_JIT)
def jac_base(y, par, M, A):
    """The Jacobian ``A`` (``n x n``, ``n = 2 M + S + 1``) of :func:`base`'s vector field of
    ``(q, q', p_0..p_{S-1}, x_v)``."""
    F = 2 * M
    nn, ns, _, _ = sizes(par, M)
    n = F + ns + 1
    X = F + ns
    for i in range(n):
        for j in range(n):
            A[i, j] = 0.0
    S = np.empty((_NSCRATCH + 1, _columns(par, M)))
    _prepare(y, par, M, S, S[_NSCRATCH], S[_NSCRATCH], False)
    R0 = HEAD + 3 * M + NW_SIZE
    nrec = int(par[HEAD + 3 * M + NW_NREC])
    xv = y[X]
    d = par[DAMP]
    for i in range(M):
        A[i, M + i] = 1.0
        A[M + i, i] = -par[HEAD + M + i]
        A[M + i, M + i] = -d
    for k in range(nn, nrec):
        r, kind = _record(par, R0, k)
        if kind == CHAMBER:
            a = int(par[r + C_NODE])
            area = par[r + C_AREA]
            b = par[R0 + a * REC_SIZE + N_BETA]
            for i in range(M):
                A[M + i, F + a] += -area
            for i in range(M):
                e = par[HEAD + 2 * M + i]
                A[F + a, i] = S[_SDP, a] * area * e / S[_SNU, a]
                A[F + a, M + i] = b * area * e / S[_SNU, a]
        elif kind == ORIFICE:
            a, b2 = int(par[r + O_FROM]), int(par[r + O_TO])
            dq = par[r + O_K] * dphi(S[_SP, a] - S[_SP, b2], par[r + O_PTR2])
            if a < ns:
                if b2 < ns:
                    A[F + a, F + b2] += S[_SF, a] * dq
                A[F + a, F + a] += -(S[_SF, a] * dq)
            if b2 < ns:
                A[F + b2, F + a] += S[_SF, b2] * dq
                A[F + b2, F + b2] += -(S[_SF, b2] * dq)
        elif kind == VALVE:
            P, Q, T = int(par[r + V_P]), int(par[r + V_A]), int(par[r + V_T])
            kv, ptr2 = par[r + V_K], par[r + V_PTR2]
            gin = phi(S[_SP, P] - S[_SP, Q], ptr2)
            dgin = dphi(S[_SP, P] - S[_SP, Q], ptr2)
            gout = phi(S[_SP, Q] - S[_SP, T], ptr2)
            dgout = dphi(S[_SP, Q] - S[_SP, T], ptr2)
            if Q < ns:  # the work port: q_in - q_out
                f = S[_SF, Q]
                A[F + Q, F + Q] += -(f * kv * (xv * dgin + (1.0 - xv) * dgout))
                if P < ns:
                    A[F + Q, F + P] += f * kv * xv * dgin
                if T < ns:
                    A[F + Q, F + T] += f * kv * (1.0 - xv) * dgout
                A[F + Q, X] += f * kv * (gin + gout)
            if P < ns:  # the pressure port: -q_in
                f = S[_SF, P]
                A[F + P, F + P] += -(f * kv * xv * dgin)
                if Q < ns:
                    A[F + P, F + Q] += f * kv * xv * dgin
                A[F + P, X] += -(f * kv * gin)
            if T < ns:  # the return port: q_out
                f = S[_SF, T]
                A[F + T, F + T] += -(f * kv * (1.0 - xv) * dgout)
                if Q < ns:
                    A[F + T, F + Q] += f * kv * (1.0 - xv) * dgout
                A[F + T, X] += -(f * kv * gout)
        elif kind == RELIEF and par[r + R_OPEN] > 0.5:
            a, b2 = int(par[r + R_FROM]), int(par[r + R_TO])
            if a < ns:
                A[F + a, F + a] += -(S[_SF, a] * par[r + R_K])
            if b2 < ns:
                A[F + b2, F + a] += S[_SF, b2] * par[r + R_K]
        elif kind == SPOOL:
            _spool_jac(par, r, R0, S, A, F, X, ns)
        elif kind == SPOOL_PORT:  # (the source loses q, the target gains it; its opening in x_v)
            a, b2 = int(par[r + F_FROM]), int(par[r + F_TO])
            _, da, db, dx = KD.law(kind, par, r, S[_SP, a], S[_SP, b2], xv)
            if a < ns:
                A[F + a, F + a] += -(S[_SF, a] * da)
                if b2 < ns:
                    A[F + a, F + b2] += -(S[_SF, a] * db)
                A[F + a, X] += -(S[_SF, a] * dx)
            if b2 < ns:
                if a < ns:
                    A[F + b2, F + a] += S[_SF, b2] * da
                A[F + b2, F + b2] += S[_SF, b2] * db
                A[F + b2, X] += S[_SF, b2] * dx
        elif kind == LEAK or kind == CUSHION or kind == CHECK:
            a, b2 = int(par[r + F_FROM]), int(par[r + F_TO])
            _, da, db, dg = KD.law(kind, par, r, S[_SP, a], S[_SP, b2], -y[0])
            # the source loses q, the target gains it; the gap y = -q_0
            if a < ns:
                A[F + a, F + a] += -(S[_SF, a] * da)
                if b2 < ns:
                    A[F + a, F + b2] += -(S[_SF, a] * db)
                A[F + a, 0] += S[_SF, a] * dg if S[_SCH, a] > 0.5 else dg / S[_SC, a]
            if b2 < ns:
                if a < ns:
                    A[F + b2, F + a] += S[_SF, b2] * da
                A[F + b2, F + b2] += S[_SF, b2] * db
                A[F + b2, 0] += S[_SF, b2] * -dg if S[_SCH, b2] > 0.5 else -dg / S[_SC, b2]
    # the nodes without a chamber: the sums over C, less net C' / C^2; the held ones: zero rows
    for j in range(ns):
        row = F + j
        if par[R0 + j * REC_SIZE + N_HELD] > 0.5:
            for c in range(n):
                A[row, c] = 0.0
        elif S[_SCH, j] < 0.5:
            C = S[_SC, j]
            for c in range(F, n):
                A[row, c] = A[row, c] / C
            A[row, row] = A[row, row] - S[_SNET, j] * S[_SDC, j] / (C * C)


@nb.njit(**_JIT)
def events(z, par, M, g, first, gap):
    """The network's event functions into ``g[first:first + n_events]`` from the circuit's state
    ``z = (p_0..p_{S-1}, x_v)`` and the piston's gap ``gap`` (the inactive ones held at 1): each
    valve's ramp end, each watched accumulator's and relief's pressure level
    (:func:`impactbar.drives.circuit.kinds.level._off_level`), each watched level of the gap or of a
    pressure drop (:mod:`.kinds.level`)."""
    net0 = HEAD + 3 * M
    nrec = int(par[net0 + NW_NREC])
    nn = int(par[net0 + NW_NNODE])
    ns = int(par[net0 + NW_NSTATE])
    nev = int(par[net0 + NW_NEV])
    R0 = net0 + NW_SIZE
    for k in range(nev):
        g[first + k] = 1.0
    xv = z[ns]
    for k in range(nn, nrec):
        r, kind = _record(par, R0, k)
        if kind == VALVE and par[r + V_EV] >= 0:
            o = par[r + V_OPEN]
            g[first + int(par[r + V_EV])] = xv - 1.0 if o > 0.5 else (xv if o < -0.5 else 1.0)
        elif kind == RELIEF and par[r + R_EV] >= 0 and par[r + R_WATCH] > 0.5:
            a = int(par[r + R_FROM])
            p = _pressure(par, R0, z, 0, ns, a)
            g[first + int(par[r + R_EV])] = _off_level(p - par[r + R_SET], par[r + R_OPEN], par[r + R_SET])
        elif kind == ACCUM and par[r + A_EV] >= 0 and par[r + A_WATCH] > 0.5:
            a = int(par[r + A_NODE])
            p = _pressure(par, R0, z, 0, ns, a)
            g[first + int(par[r + A_EV])] = _off_level(p - par[r + A_P0], par[r + A_ON], par[r + A_P0])
        elif kind == LEVEL and par[r + LV_EV] >= 0:
            pa = _pressure(par, R0, z, 0, ns, int(par[r + F_FROM]))
            pb = _pressure(par, R0, z, 0, ns, int(par[r + F_TO]))
            x = xv if par[r + KD.level.GAP] > 1.5 else gap
            g[first + int(par[r + LV_EV])] = KD.level.value(par, r, pa, pb, x)
        elif kind == SPOOL and par[r + KD.spool.EVENT] >= 0:
            v = int(par[r + KD.spool.VELOCITY])
            pc = _pressure(par, R0, z, 0, ns, int(par[r + KD.spool.CONTROL]))
            ps = _pressure(par, R0, z, 0, ns, int(par[r + KD.spool.SUPPLY]))
            g[first + int(par[r + KD.spool.EVENT])] = KD.spool.value(par, r, par[R0 + v * REC_SIZE + N_HELD],
                                                                     xv, pc, ps)
