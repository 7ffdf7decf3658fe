r"""The oil circuit as a network of part records, compiled once for every topology (theory §11).

Each part of the circuit describes itself as records (:func:`record`): small float arrays of
:data:`REC_SIZE` slots, the slot ``KIND`` first and the kind's fields at the named offsets below. The
drive composes them (:func:`compose`) into one array appended to the parameter vector ``par`` of
:mod:`._bar` after the bar's ``HEAD + 3 M`` entries: a header (``NW_*``) and the records, the
nodes first (node ``j`` is record ``j``), then the other parts in the order of their kinds
(:data:`PUMP`, :data:`ORIFICE`, :data:`VALVE`, :data:`RELIEF`, :data:`CHAMBER`, :data:`ACCUM`), each
kind in the order given. The code generated for a network's topology (:mod:`._netgen`) reads only
the records, so that a new part made of these kinds needs no edit of a kernel; an interpreter of any
network (``base``, ``jac_base``, ``events``: the loops over the records, compiled once) is the tests'
reference (``tests/drives/network_interpreter.py``).

The state is ``y = (q_0..q_{M-1}, q_0'..q_{M-1}', p_0..p_{S-1}, x_v, E_0..E_{K-1})``: the bar's modes,
the pressures of the ``S`` nodes with a state (nodes ``0..S-1``; the nodes after them are held at
their own pressure, a tank), the valve's spool and ``K`` energy integrands (each part adds its terms
to the slots its record names).

Kinds and their equations (``p`` a node's pressure, ``w = -sum_i e_i q_i`` the driven end's
displacement away from the stop, ``phi`` the smoothed orifice law of :func:`.kinds._flow.phi`):

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
sign of a zero included): the preset drifter's records reproduce the arithmetic of the preset's
kernel written by hand (``tests/circuit_field_reference.py``) to the bit
(``tests/drives/test_circuit_network.py``).
"""

from __future__ import annotations

import numpy as np

from . import kinds as KD

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
