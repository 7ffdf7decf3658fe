"""A drifter's oil circuit drawn from its configuration (theory §11, §13): its nodes as boxes and
its parts as labelled arrows between them (:meth:`impactbar.physical.CircuitDrifter.circuit_graph`),
the preset circuit's and every ``[parts.<name>]`` table's alike; matplotlib imported on call."""

from __future__ import annotations

__all__ = ["plot_circuit_graph"]

#: where the preset's nodes sit (the supply above, the chambers either side, the tank below)
_PRESET_AT = {"supply": (0.0, 2.2), "rear": (-2.4, 0.4), "front": (2.4, 0.4), "tank": (0.0, -2.4)}


def _places(nodes) -> dict:
    """Each node's position: the preset's fixed, the parts' nodes in a column below the rear
    chamber, down to the tank's level, in the config's order."""
    at = {n.name: _PRESET_AT[n.name] for n in nodes if n.name in _PRESET_AT}
    extra = [n.name for n in nodes if n.name not in _PRESET_AT]
    for i, name in enumerate(extra):
        at[name] = (-2.4 - 0.3 * (i % 2), -0.9 - 1.5 * i / max(1, len(extra) - 1))
    return at


def plot_circuit_graph(drifter, ax=None):
    """The oil circuit of ``drifter`` as a graph: each node of oil a box with its name (the chambers,
    the supply, the tank, each part's own node), each part an arrow from its source node to its
    target (the flow's positive way) labelled with its name and kind; two parts between the same
    nodes are drawn on arcs of their own. Each box has the gid ``node:<name>``, each arrow's label
    the gid ``part:<label>``.

    Parameters
    ----------
    drifter : CircuitDrifter
        A drifter with its oil circuit (its ``parts`` read from ``[parts.<name>]``).
    ax : matplotlib.axes.Axes, optional
        Default: a new figure, 8 x 6 inches.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on (``ax`` where given).

    Raises
    ------
    ValueError
        ``drifter`` not a drifter with its oil circuit.
    """
    import matplotlib.pyplot as plt

    if not hasattr(drifter, "circuit_graph"):
        raise ValueError(f"drifter must be a drifter with its oil circuit (a CircuitDrifter); got "
                         f"{type(drifter).__name__}")
    graph = drifter.circuit_graph()
    at = _places(graph.nodes)
    if ax is None:
        _, ax = plt.subplots(figsize=(8.0, 6.0), layout="constrained")
    box = {"boxstyle": "round,pad=0.35", "fc": "#dde8f4", "ec": "k"}
    for n in graph.nodes:
        x, y = at[n.name]
        ax.text(x, y, n.label, ha="center", va="center", fontsize=9, bbox=dict(box, fc="#f6e3c8" if n.part
                                                                             else "#dde8f4"),
                zorder=4, gid=f"node:{n.name}")
    seen: dict = {}
    for e in graph.edges:
        pair = frozenset((e.source, e.target))
        k = seen.get(pair, 0)
        seen[pair] = k + 1
        rad = (0.0, 0.3, -0.3, 0.55, -0.55)[k % 5]
        (x0, y0), (x1, y1) = at[e.source], at[e.target]
        color = "C3" if e.part else "k"
        ax.annotate("", (x1, y1), (x0, y0), zorder=2,
                    arrowprops={"arrowstyle": "-|>", "color": color, "lw": 1.2, "shrinkA": 22, "shrinkB": 22,
                                "connectionstyle": f"arc3,rad={rad}"})
        # the label at the arc's middle: the quadratic Bezier's point at 1/2
        xm, ym = 0.5 * (x0 + x1) + 0.5 * rad * (y1 - y0), 0.5 * (y0 + y1) - 0.5 * rad * (x1 - x0)
        ax.text(xm, ym, e.label, ha="center", va="center", fontsize=7.5, color=color, zorder=3,
                bbox={"boxstyle": "square,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.8},
                gid=f"part:{e.label}")
    xs, ys = zip(*at.values(), strict=True)
    ax.set_xlim(min(xs) - 1.4, max(xs) + 1.4)
    ax.set_ylim(min(ys) - 0.8, max(ys) + 0.8)
    ax.set_aspect("equal")
    ax.set_axis_off()
    ax.set_title("The oil circuit's nodes and parts" + (f": {drifter.name}" if drifter.name else ""))
    return ax
