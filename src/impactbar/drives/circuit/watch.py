"""The watched events of a circuit's extra parts, read from its network (:mod:`._network`): an
accumulator's pre-charge, a relief's setting (a node's pressure through a level), and the levels of
the kinds of :mod:`.kinds` (the piston's gap or a pressure drop through a level: a cushion's or a
check valve's kinks) or the spool's position (a spool valve's ports' kinks), and a spool's stop
(:mod:`.kinds.spool`), each a flag of the drive's mode."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import _network as NW
from .extremes import hermite_extremes
from .kinds import level as LV
from .kinds import spool as SP
from .kinds._flow import SOURCE, TARGET

__all__ = ["Watch", "border_tests", "consistent_mode", "pressure_margins", "watched"]

#: the preset's accumulator's and relief's event and border names
ACC, REL = "accumulator", "relief"


@dataclass(frozen=True)
class Watch:
    """One watched event of an extra part.

    Attributes
    ----------
    name : str
        The event's name (the part's).
    slot : int
        Its slot in the network's events (its flag is the mode's ``1 + slot``).
    level : float
        The level its quantity passes.
    kind : int
        The record's kind: :data:`._network.ACCUM`, :data:`._network.RELIEF`, :data:`._network.LEVEL`
        or :data:`._network.SPOOL` (its stop: the quantity is at or above 0 where it rests).
    node : int or None
        The node whose pressure is watched (an accumulator's, a relief's), else ``None``.
    quantity : callable
        ``quantity(q, z)``: the watched quantity at the modal displacements ``q`` and the circuit's
        state ``z``.
    form : tuple
        A level's quantity (a spool's: its position) as a linear form of the flight's columns,
        ``(terms, offset)``, each term ``(space, index, coefficient)``: ``space`` ``"q"`` a modal
        displacement, ``"z"`` a state of the circuit (:func:`border_tests`); ``()`` for a node's.
    force : tuple
        A spool's stop's: the oil's force on the spool, ``A_c p_c - A_0 p_s``, as such a form; else
        ``()``.
    """

    name: str
    slot: int
    level: float
    kind: int
    node: int | None
    quantity: Callable
    form: tuple = ()
    force: tuple = ()

    def flag(self, q, z) -> int:
        """The mode's flag at ``(q, z)``: at or above the level (above it for a relief)."""
        x = self.quantity(q, z)
        return int(x > self.level if self.kind == NW.RELIEF else x >= self.level)


def _value(form):
    """A linear form's ``quantity(q, z)`` (:func:`_level_form`): its terms summed in their order, then
    its offset where it has one, so that a gap is ``-q_0``, a position ``z_j`` and a pressure drop
    ``p_a - p_b`` (a held node's pressure in the offset) to the bit."""
    terms, offset = form

    def value(q, z):
        x = None
        for space, i, c in terms:
            t = c * float(q[i] if space == "q" else z[i])
            x = t if x is None else x + t
        return offset if x is None else (x + offset if offset != 0.0 else x)
    return value


def _stop(form, force):
    """A spool's stop's ``quantity(q, z)`` (:func:`.kinds.spool.stop_quantity`) from the linear
    forms of its position and of the oil's force on it."""
    x, f = _value(form), _value(force)
    return lambda q, z: SP.stop_quantity(x(q, z), f(q, z))


def _pressure_form(nodes, ns, recs) -> tuple:
    """``sum(sign p_node)`` over ``nodes`` (``(node, sign)`` pairs) as a linear form ``(terms,
    offset)`` of the circuit's states: a node past the states held at its pressure."""
    terms, offset = [], 0.0
    for node, sign in nodes:
        if node < ns:
            terms.append(("z", node, sign))
        else:
            offset += sign * float(recs[node][NW.N_P])
    return tuple(terms), offset


def _position(ns) -> tuple:
    """The spool's position ``z[ns]`` (the network's ``x_v`` slot) as a linear form."""
    return (("z", ns, 1.0),), 0.0


def _level_form(record, ns, recs) -> tuple:
    """A watched level's quantity (the gap ``-q_0``, the spool's position or a pressure drop, as
    :func:`.kinds.level.quantity` reads it) as a linear form of the flight's columns."""
    if record[LV.GAP] == LV.SPOOL:
        return _position(ns)
    if record[LV.GAP] > 0.5:
        return (("q", 0, -1.0),), 0.0
    return _pressure_form(((int(record[SOURCE]), 1.0), (int(record[TARGET]), -1.0)), ns, recs)


def watched(net, events, own=()) -> tuple:
    """The extra parts' :class:`Watch` es of the composed network ``net`` (:func:`._network.compose`),
    in slot order; ``events`` the network's event names (slot ``i``:
    :attr:`.composition.Composition.events`), those named in ``own`` (the drive's: the preset's
    accumulator and relief) left out."""
    head, recs = net[:NW.NW_SIZE], np.asarray(net[NW.NW_SIZE:]).reshape(-1, NW.REC_SIZE)
    ns = int(head[NW.NW_NSTATE])

    def pressure(z, j):
        return float(z[j]) if j < ns else float(recs[j][NW.N_P])

    out = []
    for r in recs:
        kind = int(r[NW.KIND])
        if kind == NW.ACCUM and r[NW.A_WATCH] > 0.5 and r[NW.A_EV] >= 0:
            node = int(r[NW.A_NODE])
            out.append((int(r[NW.A_EV]), float(r[NW.A_P0]), kind, node,
                        lambda q, z, j=node: pressure(z, j), (), ()))
        elif kind == NW.RELIEF and r[NW.R_WATCH] > 0.5 and r[NW.R_EV] >= 0:
            node = int(r[NW.R_FROM])
            out.append((int(r[NW.R_EV]), float(r[NW.R_SET]), kind, node,
                        lambda q, z, j=node: pressure(z, j), (), ()))
        elif kind == NW.LEVEL and r[NW.LV_EV] >= 0:
            form = _level_form(r, ns, recs)
            out.append((int(r[NW.LV_EV]), float(r[LV.LEVEL]), kind, None, _value(form), form, ()))
        elif kind == NW.SPOOL and r[SP.EVENT] >= 0:
            form = _position(ns)
            force = _pressure_form(((int(r[SP.CONTROL]), float(r[SP.LARGE])),
                                    (int(r[SP.SUPPLY]), -float(r[SP.SMALL]))), ns, recs)
            out.append((int(r[SP.EVENT]), 0.0, kind, None, _stop(form, force), form, force))
    watches = [Watch(events[slot], slot, level, kind, node, f, form, force)
               for slot, level, kind, node, f, form, force in out]
    return tuple(sorted((w for w in watches if w.name not in own), key=lambda w: w.slot))


def consistent_mode(watches, mode, q, z) -> tuple:
    """The drive's ``mode`` with each watched level's flag (a level's, an accumulator's, a relief's:
    not a spool's stop, whose rest the state alone does not say) turned where the state ``(q, z)``
    lies strictly on the other side of its level than the flag says (theory §11, *Parts of a
    drill's circuit*). On the level itself the flag stands (the event function is moved off 0 to
    its side: :func:`.kinds.level._off_level`), and after an event the state is on its flag's side:
    only a mode given apart from the state changes, a periodic orbit's block's, fixed from the guess
    while the parameters move its state across a level. Without this, a check valve's full opening
    reached before the impact at the guess and no longer at the block's state kept its flag "open"
    while the pressure drop was below it: its falling crossing, watched from above, never came, and
    where the cracking level was passed next the flags chose the opening's rising piece far below
    its range (an opening of -13,000 by the time the supply's pressure passed the relief's
    setting, and CVODE's convergence failures).

    Parameters
    ----------
    watches : tuple of Watch
        The drive's (:func:`watched`).
    mode : tuple
        The drive's mode (a watch's flag its ``1 + slot``).
    q, z : numpy.ndarray
        The modal displacements (model units) and the circuit's state.

    Returns
    -------
    tuple
        ``mode`` itself where every flag agrees with the state, else the mode with those turned.

    Examples
    --------
    >>> w = Watch("check_open", 1, 2.0, NW.LEVEL, None, lambda q, z: z[0] - z[1])
    >>> consistent_mode((w,), (0, 0, 1), None, [2.5, 1.0]), consistent_mode((w,), (0, 0, 1), None, [3.5, 1.0])
    ((0, 0, 0), (0, 0, 1))
    >>> consistent_mode((w,), (0, 0, 0), None, [3.0, 1.0])  # (on the level: the flag stands)
    (0, 0, 0)
    """
    out = None
    for w in watches:
        if w.kind == NW.SPOOL:
            continue
        i, x = 1 + w.slot, w.quantity(q, z)
        if (x < w.level) if mode[i] else (x > w.level):
            out = list(mode) if out is None else out
            out[i] = 1 - mode[i]
    return mode if out is None else tuple(out)


def _along(piece, form, rates: bool = True):
    """A linear form's values over a flight piece's steps and, with ``rates``, their rates, shapes
    ``(S,)``."""
    terms, offset = form
    cols = [i if space == "q" else 2 * piece.M + i for space, i, _ in terms]
    c = np.array([coef for *_, coef in terms])
    values = piece.y[:, cols] @ c + offset
    return (values, piece.f[:, cols] @ c) if rates else values


def border_tests(watches, pieces) -> dict:
    r"""The border-collision tests of the watched levels and spool stops over a period's flights
    (theory §11, *Parts of a drill's circuit*), each through 0 where the orbit's crossings of its
    surface change: for a level (a check valve's cracking or full opening, a cushion's kink, a
    spool's port) ``<name>.max`` and ``<name>.min``, the greatest and the least of its quantity over
    the period less the level (from the flights' cubic Hermite interpolants, as the pressures'
    extremes); for a spool's stop ``<name>.high`` and ``<name>.low``, at the stop of the full
    stroke (:math:`x = 1`) and of none (:math:`x = 0`): the greatest force pushing the spool into
    it while it rests there, else how far short of it the spool turns (:math:`\max x - 1`,
    :math:`-\min x`), so that each passes 0 where the spool starts or stops reaching that stop.

    Parameters
    ----------
    watches : tuple of Watch
        The drive's (:func:`watched`); those of a node (accumulators, reliefs) are left out.
    pieces : list
        The period's pieces; those without a flight's steps (a blow's) are left out.

    Returns
    -------
    dict of float
        In the quantity's model units (a level's: a pressure, the gap or the spool's position as a
        fraction of its stroke; a stop's: a force where the spool rests there, else its position),
        only the sign and the zero of which a border collision reads. Empty without flights.
    """
    flights = [p for p in pieces if hasattr(p, "M") and hasattr(p, "f")]
    out = {}
    for w in watches if flights else ():
        if w.kind == NW.LEVEL:
            (lo,), (hi,) = hermite_extremes(((p.t, *_along(p, w.form)) for p in flights), 1)
            out[f"{w.name}.max"], out[f"{w.name}.min"] = float(hi) - w.level, float(lo) - w.level
        elif w.kind == NW.SPOOL:
            x = np.concatenate([_along(p, w.form, rates=False) for p in flights])
            f = np.concatenate([_along(p, w.force, rates=False) for p in flights])
            high, low = x >= 1.0, x <= 0.0
            out[f"{w.name}.high"] = float(f[high].max()) if high.any() else float(x.max()) - 1.0
            out[f"{w.name}.low"] = float((-f[low]).max() if low.any() else -x.min())
    return out


def pressure_margins(drive, watches, pieces) -> dict:
    """The circuit's pressure margins over a period (:meth:`.HydraulicCircuitDrive.border_tests`
    without its levels and stops): each watched node's (an extra part's accumulator: its least
    pressure less the pre-charge; a relief: its setting less the greatest), then the preset's
    ``"accumulator"`` and ``"relief"`` on the supply's extremes (theory §11).

    Parameters
    ----------
    drive : HydraulicCircuitDrive
        Its supply and accumulator.
    watches : tuple of Watch
        The drive's (:func:`watched`); those of a node read here.
    pieces : list
        The period's pieces (those without a flight's extremes left out).

    Returns
    -------
    dict of float
        In model pressure units.
    """
    sup, acc = drive.supply, drive.accumulator
    out: dict = {}
    for w in watches:
        ext = [p.extremes(w.node) for p in pieces if hasattr(p, "extremes") and w.node is not None]
        if ext:
            lo, hi = min(low for low, _ in ext), max(high for _, high in ext)
            out[w.name] = lo - w.level if w.kind == NW.ACCUM else w.level - hi
    has_acc = acc is not None and acc.volume > 0 and not sup.held
    if has_acc or (sup.has_relief and not sup.held):
        lo, hi = math.inf, -math.inf
        for p in pieces:
            if not hasattr(p, "supply_extremes"):
                continue
            a, b = p.supply_extremes()
            lo, hi = min(lo, a), max(hi, b)
        if has_acc:
            out[ACC] = lo - acc.precharge
        if sup.has_relief and not sup.held:
            out[REL] = sup.relief_pressure - hi
    return out
