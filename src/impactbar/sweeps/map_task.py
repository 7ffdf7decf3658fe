"""A drifter map's work: the operating point at each point of a chunk, each continued from its
neighbour (:mod:`impactbar.sweeps.map_spec`), and the bisection of an edge between two points; or,
task ``settle``, the motion from rest at each point, classified
(:func:`~impactbar.physical.settle.settle_point`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..physical.config import config_kind
from ..physical.drifter import operating_point
from ..physical.outputs import outputs as _outputs
from ..physical.settle import settle_point
from .tasks import _blank_chunk

if TYPE_CHECKING:
    from .spec import SweepSpec

#: longest failure message kept per point (characters)
REASON_CHARS = 200
#: largest relative change of the period or the impact velocity from the neighbour a continued
#: orbit may show; beyond it the point is found again by the default chain (another branch)
JUMP = 0.25
#: relative width to which :func:`refine_edge` bisects an edge
EDGE_RTOL = 1e-6
#: the flags whose changes along an axis are edges (the outputs declared with ``edge``,
#: :mod:`impactbar.physical.outputs`)
EDGE_FLAGS = tuple(o.name for o in _outputs("store") if o.edge)


# ------------------------------------------------------------------------------------------------
def point_values(point, kind: str, rock: bool) -> dict:
    """The stored values of one operating point, in SI (the names of :func:`map_variables`).

    Parameters
    ----------
    point : DrifterOrbit or CircuitDrifterOrbit
    kind : {"drifter", "circuit"}
    rock : bool

    Returns
    -------
    dict of str to float or bool
    """
    from ..physical.outputs import output_values

    stored = _outputs("store", kind, rock)
    values = output_values(point, stored)
    return {o.name: o.to_si(values[o.name]) for o in stored}


def _snake(block: tuple) -> list:
    """The local indices of a block in snake order: each index a neighbour of the one before."""
    order = [()]
    for n in block:
        new = []
        for j, head in enumerate(order):
            rng = range(n) if j % 2 == 0 else range(n - 1, -1, -1)
            new.extend((*head, i) for i in rng)
        order = new
    # (the order above runs the first axis slowest, turning at each end of the faster ones)
    return order


def _origin(prev: tuple, here: tuple) -> int:
    for k, (a, b) in enumerate(zip(prev, here, strict=True)):
        if a != b:
            return k + 1 if a < b else -(k + 1)
    return 0  # pragma: no cover - consecutive points differ


def _landed_elsewhere(point, prev) -> bool:
    for a, b in ((point.period_s, prev.period_s), (point.impact_velocity_m_s, prev.impact_velocity_m_s)):
        if not abs(a - b) <= JUMP * abs(b):
            return True
    return False


def compute_map_chunk(spec: SweepSpec, chunk: int) -> dict:
    """One work chunk of a drifter map (what :func:`impactbar.sweeps.compute_chunk` runs for one).

    Parameters
    ----------
    spec : SweepSpec
    chunk : int
        ``0 <= chunk < spec.n_chunks``.

    Returns
    -------
    dict of str to numpy.ndarray
        Every variable of :meth:`SweepSpec.variables`, each of the chunk's block's shape.
    """
    from .._shared.threads import single_threaded_blas

    if spec.task == "settle":
        return _settle_chunk(spec, chunk)
    slices, block, out = _blank_chunk(spec, chunk)
    prev, prev_local, kind = None, None, config_kind(spec.config)
    with single_threaded_blas():
        for local in _snake(block):
            index = tuple(s.start + i for s, i in zip(slices, local, strict=True))
            point, origin, reason, status = None, 0, "", 0
            try:
                machine = spec.point(index)
                if prev is not None and spec.options["chain"] == "continue":
                    try:
                        point = operating_point(machine, prev)
                        origin = _origin(prev_local, local)
                        if _landed_elsewhere(point, prev):
                            point, origin = None, 0
                    except ValueError:
                        point = None
                if point is None:
                    point = operating_point(machine)
                values = point_values(point, kind, "rock" in spec.config)
            except Exception as exc:  # noqa: BLE001 - one point's failure is kept, the map goes on
                point, (status, reason) = None, _failure(exc)
            if point is None:
                out["status"][local] = status
                out["failure"][local] = reason[:REASON_CHARS]
                prev = None  # the next point starts again from the default chain
                continue
            for name, v in values.items():
                out[name][local] = v
            out["origin"][local] = origin
            prev, prev_local = point, local
    return out


def _one_line(exc) -> str:
    return " ".join(str(exc).split())


def _failure(exc: Exception) -> tuple:
    """A point's status and why: 1 and the message for a ValueError (the machine's refusal), 2 and
    the error's type and message for another."""
    if isinstance(exc, ValueError):
        return 1, _one_line(exc)
    return 2, f"{type(exc).__name__}: {_one_line(exc)}"


def find_edges(ds, flags=EDGE_FLAGS) -> list:
    """The edges of a map: along each axis, the neighbouring points (both with an orbit) where a
    flag changes.

    Parameters
    ----------
    ds : xarray.Dataset or dict of numpy.ndarray
        The map's variables (``status`` and the flags).
    flags : sequence of str
        The flags looked at (those the store has).

    Returns
    -------
    list of tuple
        ``(axis, index, flag)``: the axis number, the lower point's index (a tuple) and the flag's name;
        the upper point is one step up the axis.
    """
    status = np.asarray(ds["status"])
    ok = status == 0
    out = []
    for name in flags:
        if name not in ds:
            continue
        f = np.asarray(ds[name], dtype=bool)
        for axis in range(f.ndim):
            lo = [slice(None)] * f.ndim
            hi = [slice(None)] * f.ndim
            lo[axis], hi[axis] = slice(0, -1), slice(1, None)
            lo, hi = tuple(lo), tuple(hi)
            change = (f[lo] != f[hi]) & ok[lo] & ok[hi]
            for idx in zip(*np.nonzero(change), strict=True):
                out.append((axis, tuple(int(i) for i in idx), name))
    out.sort()
    return out


def refine_edge(spec: SweepSpec, axis: int, index: tuple, flag: str, *, rtol: float = EDGE_RTOL):
    """Locate an edge by bisection on the axis' parameter, the other keys at the point's values.

    Parameters
    ----------
    spec : SweepSpec
    axis : int
        The axis along which the flag changes.
    index : tuple of int
        The lower grid point (the upper one is a step up ``axis``).
    flag : str
        One of :data:`EDGE_FLAGS`.
    rtol : float
        Bisect until the bracket is narrower than ``rtol`` times its larger end.

    Returns
    -------
    low, high : float
        The bracket (SI, in the axis' unit): the flag as at the lower point at ``low``, as at the upper
        one at ``high``.

    Raises
    ------
    ValueError
        Where an orbit is missing at an end.
    """
    ax = spec.axes[axis]
    a, b = float(ax.values[index[axis]]), float(ax.values[index[axis] + 1])
    others = {x.name: x.values[i] for k, (x, i) in enumerate(zip(spec.axes, index, strict=True)) if k != axis}

    def at(value, guess=None):
        machine = spec.point(values={**others, ax.name: value})
        point = None
        if guess is not None:
            try:
                point = operating_point(machine, guess)
                if _landed_elsewhere(point, guess):
                    point = None
            except ValueError:
                point = None
        if point is None:
            point = operating_point(machine)
        return point, bool(point_values(point, config_kind(spec.config), False)[flag])

    pa, fa = at(a)
    _, fb = at(b, pa)
    if fa == fb:
        raise ValueError(f"{flag} does not change between {spec.axis_text(ax.name, a)} and "
                         f"{spec.axis_text(ax.name, b)} along {ax.name}")
    while abs(b - a) > rtol * max(abs(a), abs(b)):
        m = 0.5 * (a + b)
        pm, fm = at(m, pa)
        if fm == fa:
            a, pa = m, pm
        else:
            b = m
    return a, b


# ------------------------------------------------------------------------------------------------
# the settle task
# ------------------------------------------------------------------------------------------------
def _settle_chunk(spec: SweepSpec, chunk: int) -> dict:
    """:func:`compute_map_chunk` of a ``settle`` map: :func:`settle_point` at each point."""
    from .._shared.threads import single_threaded_blas

    slices, block, out = _blank_chunk(spec, chunk)
    opts = spec.options
    with single_threaded_blas():
        for local in np.ndindex(*block):
            index = tuple(s.start + i for s, i in zip(slices, local, strict=True))
            try:
                values = settle_point(spec.point(index), opts["blows"], opts["blow_fraction"],
                                      opts["settle_tolerance"])
            except Exception as exc:  # noqa: BLE001 - one point's failure is kept, the map goes on
                status, reason = _failure(exc)
                out["status"][local], out["failure"][local] = status, reason[:REASON_CHARS]
                continue
            for name, value in values.items():
                out[name][local] = value
    return out
