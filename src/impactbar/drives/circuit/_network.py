r"""The oil circuit as a network of part records, compiled once for every topology (theory §11).

Each part of the circuit describes itself as records (:func:`record`): small float arrays of
:data:`REC_SIZE` slots, the slot ``KIND`` first and the kind's fields at the named offsets below. The
drive composes them (:func:`compose`) into one array appended to the parameter vector ``par`` of
:mod:`._kernel` after the bar's ``HEAD + 3 M`` entries: a header (``NW_*``) and the records, the
nodes first (node ``j`` is record ``j``), then the other parts in the order of their kinds
(:data:`PUMP`, :data:`ORIFICE`, :data:`VALVE`, :data:`RELIEF`, :data:`CHAMBER`, :data:`ACCUM`), each
kind in the order given. The functions here (:func:`base`, :func:`jac_base`, :func:`events`) read
only the records, so that a new part made of these kinds needs no edit of a kernel.

The state is ``y = (q_0..q_{M-1}, q_0'..q_{M-1}', p_0..p_{S-1}, x_v, E_0..E_{K-1})``: the bar's modes,
the pressures of the ``S`` nodes with a state (nodes ``0..S-1``; the nodes after them are held at
their own pressure, a tank), the valve's spool and ``K`` energy integrands (each part adds its terms
to the slots its record names).

Kinds and their equations (``p`` a node's pressure, ``w = -sum_i e_i q_i`` the driven end's
displacement away from the stop, ``phi`` the smoothed orifice law of :func:`._kernel.phi`):

- ``NODE``: a volume ``V`` of oil of bulk modulus ``beta`` (``N_V``, ``N_BETA``); with a chamber on
  it ``p' = beta / V (net)``, ``V = N_V + a w``; else ``p' = net / C``, ``C = V / beta + sum C_a``;
  ``N_HELD``: ``p' = 0`` (a supply held at its pressure); a node past the states is held at ``N_P``.
  Energy: ``V p p' / beta`` into ``N_ECOMP`` (0 when held); a held node's ``p (N_ESIGN net)`` into
  ``N_EWORK`` (the held supply's work, the tank's inflow at its pressure).
- ``PUMP``: the flow ``P_FLOW`` into ``P_NODE``; energy ``p Q`` into ``P_E``.
- ``ORIFICE``: ``q = K phi(p_from - p_to)``; its loss ``q (p_from - p_to)`` into ``O_E``.
- ``VALVE``: a spool of position ``x_v`` (rate ``V_RATE``) between the pressure port ``V_P``, the
  work port ``V_A`` and the return port ``V_T``: ``q_in = K x_v phi(p_P - p_A)``,
  ``q_out = K (1 - x_v) phi(p_A - p_T)``; losses into ``V_E``; the ramp's end an event
  (``V_OPEN`` +1: at ``x_v = 1``, -1: at 0, 0: none).
- ``RELIEF``: while open (``R_OPEN``) the laminar flow ``K (p_from - p_set)`` to ``R_TO``; its
  loss into ``R_E``; watched (``R_WATCH``): the event ``p_from - p_set``.
- ``CHAMBER``: node ``C_NODE``'s volume changes by ``C_AREA w`` and it pushes the bar with the force
  ``-C_AREA p`` (the force ``p_r - alpha p_f`` of the rear chamber, area -1, and the front, area
  ``alpha``); its node's net flow takes ``-C_AREA w'``.
- ``ACCUM``: a gas accumulator on ``A_NODE``: while it holds oil (``A_ON``) the compliance
  ``C_a = (V_0 / n) p_0^{1/n} p^{-1/n - 1}``; energy ``p C_a p'`` into ``A_E``; watched
  (``A_WATCH``): the event ``p - p_0``.
- ``LEAK``, ``CUSHION``, ``CHECK``: a flow from ``F_FROM`` to ``F_TO`` whose law and derivatives
  are written in a module of its own (:mod:`.kinds`: laminar leakage, a position-controlled orifice,
  a check valve), added to the nodes' balances, its loss ``q (p_from - p_to)`` into ``F_E``.
- ``LEVEL``: a watched level (:mod:`.kinds.level`): the event of the piston's gap ``y = -q_0``, the
  spool's position ``x_v`` or a pressure drop through a level.
- ``SPOOL``: a pilot-operated spool in place of the valve (:mod:`.kinds.spool`): its position
  ``x_v = x_s / h_s``, its velocity a node's state (the node's volume its mass), the control chamber's
  and the supply's volumes changed by its motion; its stop an event.
- ``SPOOL_PORT``: a flow as a cushion's with its opening a function of the spool's position
  (:mod:`.kinds.spool_port`: the spool valve's main ports).

The sums run in the order of the records, from ``-0.0`` (so that a sum's first term is that term,
sign of a zero included): the preset drifter's records reproduce :mod:`._kernel`'s arithmetic to the
bit (``tests/drives/test_circuit_network.py``).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ...dynamics.kernels import CACHE
from . import kinds as KD
from ._kernel import DAMP, HEAD, _off_level, dphi, end_motion, phi

# the network's header (after the bar's entries of ``par``)
NW_NREC, NW_NNODE, NW_NSTATE, NW_NEN, NW_NEV, NW_EPISTON = range(6)
NW_SIZE = 6

#: the size of every record; its first slot is its kind
REC_SIZE = 10
KIND = 0
NODE, PUMP, ORIFICE, VALVE, RELIEF, CHAMBER, ACCUM = range(7)
# the kinds written in modules of their own (:mod:`.kinds`: their equations there)
LEAK, CUSHION, CHECK, LEVEL = KD.leak.CODE, KD.cushion.CODE, KD.check.CODE, KD.level.CODE
SPOOL, SPOOL_PORT = KD.spool.CODE, KD.spool_port.CODE
#: where a kind sorts among the records if not at its code: a spool changes nodes' volumes, as a
#: chamber does, before the accumulators take the nodes' capacitances
_ORDER = {SPOOL: CHAMBER + 0.5}
KINDS = ("node", "pump", "orifice", "valve", "relief", "chamber", "accumulator") + tuple(
    KD.MODULES[k].NAME for k in sorted(KD.MODULES))
# a flow kind's nodes and energy slot (:mod:`.kinds._flow`), a level's event slot
F_FROM, F_TO, F_E = KD.leak.SOURCE, KD.leak.TARGET, KD.leak.ENERGY
LV_EV = KD.level.EVENT

# the fields of each kind
N_ID, N_V, N_BETA, N_HELD, N_P, N_EWORK, N_ESIGN, N_ECOMP = range(1, 9)
P_NODE, P_FLOW, P_E = range(1, 4)
O_FROM, O_TO, O_K, O_PTR2, O_E = range(1, 6)
V_P, V_A, V_T, V_K, V_PTR2, V_E, V_RATE, V_OPEN, V_EV = range(1, 10)
R_FROM, R_TO, R_K, R_SET, R_OPEN, R_WATCH, R_EV, R_E = range(1, 9)
C_NODE, C_AREA = range(1, 3)
A_NODE, A_V, A_P0, A_N, A_ON, A_WATCH, A_EV, A_E = range(1, 9)

_FIELDS = {
    NODE: {"id": N_ID, "volume": N_V, "beta": N_BETA, "held": N_HELD, "pressure": N_P,
           "work_energy": N_EWORK, "work_sign": N_ESIGN, "compression_energy": N_ECOMP},
    PUMP: {"node": P_NODE, "flow": P_FLOW, "energy": P_E},
    ORIFICE: {"source": O_FROM, "target": O_TO, "coefficient": O_K, "ptr2": O_PTR2, "energy": O_E},
    VALVE: {"pressure_port": V_P, "work_port": V_A, "return_port": V_T, "coefficient": V_K,
            "ptr2": V_PTR2, "energy": V_E, "rate": V_RATE, "open": V_OPEN, "event": V_EV},
    RELIEF: {"source": R_FROM, "target": R_TO, "coefficient": R_K, "setting": R_SET, "open": R_OPEN,
             "watched": R_WATCH, "event": R_EV, "energy": R_E},
    CHAMBER: {"node": C_NODE, "area": C_AREA},
    ACCUM: {"node": A_NODE, "volume": A_V, "precharge": A_P0, "exponent": A_N, "on": A_ON,
            "watched": A_WATCH, "event": A_EV, "energy": A_E},
    **{code: m.FIELDS for code, m in KD.MODULES.items()},
}
#: a field left out of :func:`record` (an energy or an event slot: -1, none)
_DEFAULTS = {"work_energy": -1.0, "compression_energy": -1.0, "work_sign": 1.0, "energy": -1.0,
             "event": -1.0}

# the rows of the nodes' scratch
# (columns: the nodes; ``_SCA``, an accumulator's compliance, by record)
_SP, _SNU, _SNET, _SF, _SC, _SDC, _SNAC, _SCH, _SDP, _SCA = range(10)
_NSCRATCH = 10

_JIT = dict(cache=CACHE, nogil=True, error_model="numpy")


def record(kind: int, **fields) -> np.ndarray:
    """One part record: ``kind`` (:data:`NODE`, :data:`PUMP`, ...) and its fields by name (the module
    docstring; node numbers, energy and event slots as numbers, flags as 0 or 1).

    Parameters
    ----------
    kind : int
        One of :data:`NODE`, :data:`PUMP`, :data:`ORIFICE`, :data:`VALVE`, :data:`RELIEF`,
        :data:`CHAMBER`, :data:`ACCUM`.
    **fields : float
        The kind's fields (node numbers, energy and event slots as numbers, flags 0 or 1; the
        equations in the module docstring); energy and event slots left out are none (-1).
        ``NODE``: ``id``, ``volume``, ``beta``, ``held``, ``pressure``, ``work_energy``,
        ``work_sign``, ``compression_energy``; ``PUMP``: ``node``, ``flow``, ``energy``;
        ``ORIFICE``: ``source``, ``target``, ``coefficient``, ``ptr2`` (the transition pressure
        squared), ``energy``; ``VALVE``: ``pressure_port``, ``work_port``, ``return_port``,
        ``coefficient``, ``ptr2``, ``energy``, ``rate``, ``open``, ``event``; ``RELIEF``:
        ``source``, ``target``, ``coefficient``, ``setting``, ``open``, ``watched``, ``event``,
        ``energy``; ``CHAMBER``: ``node``, ``area``; ``ACCUM``: ``node``, ``volume``,
        ``precharge``, ``exponent``, ``on``, ``watched``, ``event``, ``energy``.

    Returns
    -------
    numpy.ndarray
        Shape ``(REC_SIZE,)``.

    Raises
    ------
    ValueError
        An unknown kind or field.

    Examples
    --------
    >>> r = record(PUMP, node=2, flow=0.5, energy=0)
    >>> float(r[KIND]), float(r[P_FLOW])
    (1.0, 0.5)
    """
    if kind not in _FIELDS:
        raise ValueError(f"kind must be one of {sorted(_FIELDS)}; got {kind!r}")
    names = _FIELDS[kind]
    out = np.zeros(REC_SIZE)
    out[KIND] = float(kind)
    for name, slot in names.items():
        if name in _DEFAULTS:
            out[slot] = _DEFAULTS[name]
    for name, value in fields.items():
        if name not in names:
            raise ValueError(f"a {KINDS[kind]} record's fields are {sorted(names)}; got {name!r}")
        out[names[name]] = float(value)
    return out


def compose(records, n_states: int, n_energy: int, n_events: int, piston_energy: int) -> np.ndarray:
    """The network's array (header and records) of a circuit's part records.

    Parameters
    ----------
    records : iterable of numpy.ndarray
        The parts' records (:func:`record`), in any order of kinds; the nodes numbered ``0..`` without
        a gap (``N_ID``), the first ``n_states`` with a pressure state.
    n_states : int
        Nodes with a state, ``>= 1``.
    n_energy, n_events : int
        The energy integrands and the circuit's events (the slots the records name lie below).
    piston_energy : int
        The slot of the oil's work on the piston ``-F w'``.

    Returns
    -------
    numpy.ndarray
        ``NW_SIZE + REC_SIZE * len(records)`` floats: the nodes by number, then the other records
        by kind, each kind in the given order (the order of the sums).

    Raises
    ------
    ValueError
        Nodes not numbered ``0..``, fewer than ``n_states``, a record naming a node that is not there
        or a slot out of range, a chamber on a node with an accumulator or two chambers on one node,
        no valve or more than one.

    Examples
    --------
    >>> recs = [record(NODE, id=0, volume=1.0, beta=100.0), record(NODE, id=1, pressure=0.0),
    ...         record(ORIFICE, source=0, target=1, coefficient=1.0, ptr2=1e-4),
    ...         record(VALVE, pressure_port=0, work_port=1, return_port=1, coefficient=1.0, ptr2=1e-4)]
    >>> compose(recs, 1, 1, 1, 0).shape
    (46,)
    """
    recs = [np.asarray(r, dtype=float) for r in records]
    nodes = sorted((r for r in recs if int(r[KIND]) == NODE), key=lambda r: r[N_ID])
    n_nodes = len(nodes)
    if [int(r[N_ID]) for r in nodes] != list(range(n_nodes)) or not 1 <= n_states <= n_nodes:
        raise ValueError(f"the nodes must be numbered 0..{n_nodes - 1} and n_states in [1, {n_nodes}]; "
                         f"got ids {[int(r[N_ID]) for r in nodes]} and n_states={n_states}")
    others = sorted((r for r in recs if int(r[KIND]) != NODE),
                    key=lambda r: _ORDER.get(int(r[KIND]), int(r[KIND])))
    own = KD.MODULES.items()  # (the kinds of .kinds declare their slots)
    node_fields = {PUMP: (P_NODE,), ORIFICE: (O_FROM, O_TO), VALVE: (V_P, V_A, V_T), RELIEF: (R_FROM, R_TO),
                   CHAMBER: (C_NODE,), ACCUM: (A_NODE,), **{k: m.NODES for k, m in own}}
    energy_fields = {NODE: (N_EWORK, N_ECOMP), PUMP: (P_E,), ORIFICE: (O_E,), VALVE: (V_E,),
                     RELIEF: (R_E,), CHAMBER: (), ACCUM: (A_E,), **{k: m.ENERGIES for k, m in own}}
    event_fields = {VALVE: (V_EV,), RELIEF: (R_EV,), ACCUM: (A_EV,), **{k: m.EVENTS for k, m in own}}
    for r in nodes + others:
        k = int(r[KIND])
        for f in node_fields.get(k, ()):
            if not 0 <= r[f] < n_nodes or r[f] != int(r[f]):
                raise ValueError(f"a {KINDS[k]} record names node {r[f]:g}; the nodes are 0..{n_nodes - 1}")
        for f in energy_fields[k]:
            if not -1 <= r[f] < n_energy:
                raise ValueError(f"a {KINDS[k]} record's energy slot {r[f]:g} is out of 0..{n_energy - 1}")
        for f in event_fields.get(k, ()):
            if not -1 <= r[f] < n_events:
                raise ValueError(f"a {KINDS[k]} record's event slot {r[f]:g} is out of 0..{n_events - 1}")
    chambers = [int(r[C_NODE]) for r in others if int(r[KIND]) == CHAMBER]
    accums = {int(r[A_NODE]) for r in others if int(r[KIND]) == ACCUM}
    if len(set(chambers)) != len(chambers) or set(chambers) & accums or any(c >= n_states for c in chambers):
        raise ValueError("a chamber needs a node of its own with a state and without an accumulator; got "
                         f"chambers on nodes {chambers}, accumulators on {sorted(accums)}")
    if sum(int(r[KIND]) in (VALVE, SPOOL) for r in others) != 1:
        raise ValueError("the network needs exactly one valve or spool (its position is the state x_v)")
    if not 0 <= piston_energy < n_energy:
        raise ValueError(f"piston_energy must be in 0..{n_energy - 1}; got {piston_energy}")
    head = np.zeros(NW_SIZE)
    head[NW_NREC], head[NW_NNODE], head[NW_NSTATE] = len(recs), n_nodes, n_states
    head[NW_NEN], head[NW_NEV], head[NW_EPISTON] = n_energy, n_events, piston_energy
    return np.concatenate([head] + nodes + others)


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
    (:func:`._kernel._off_level`), each watched level of the gap or of a pressure drop
    (:mod:`.kinds.level`)."""
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
