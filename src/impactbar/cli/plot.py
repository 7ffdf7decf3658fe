"""``impactbar plot RESULTS.zarr --out FIG.png``: draw a stored sweep (stability chart, fraction
maps or bifurcation diagram, by the store's task)."""

from __future__ import annotations


def add_parser(sub) -> None:
    p = sub.add_parser(
        "plot",
        help="draw a stored sweep: stability chart, fraction maps, bifurcation diagram or design map",
        description="Read a store written by 'impactbar sweep' and draw it: a stability chart for "
        "task orbits, maps of the motion fractions for montecarlo, a bifurcation diagram for "
        "bifurcation. Chunks not yet computed show as blank.",
    )
    p.add_argument("store", help="the zarr store written by 'impactbar sweep'")
    p.add_argument("--out", required=True, help="the figure file (PNG, PDF, SVG, ...)")
    p.add_argument("--select", action="append", default=[], metavar="AXIS=VALUE",
                   help="fix an axis at the grid value nearest VALUE (repeatable): a number, or for a "
                   "drifter's design map a quantity with its unit ('85 L/min'; a bare number is "
                   "in the axis' SI unit); the chart uses at most two remaining axes")
    p.add_argument("--variable", default=None, metavar="NAME",
                   help="for a drifter's design map (impactbar sweep of a spec with config): the "
                   "variable drawn, e.g. hydraulic_efficiency (default blow_frequency)")
    p.add_argument("--dpi", type=int, default=150,
                   help="resolution of raster output, 1 to 1200 (default 150)")
    p.set_defaults(func=run)


def _selection(items) -> dict:
    sel = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name:
            raise ValueError(f"--select must be AXIS=VALUE; got {item!r}")
        try:
            sel[name.strip()] = float(value)
        except ValueError:  # a quantity with its unit ("85 L/min"): the store's axis converts it
            sel[name.strip()] = value.strip()
    return sel


def run(args) -> int:
    from ._common import check_dpi, output_file, require

    check_dpi(args.dpi)
    require("matplotlib")
    output_file(args.out)
    from ..sweeps.plot import plot_sweep

    path = plot_sweep(args.store, args.out, select=_selection(args.select), dpi=args.dpi,
                      variable=args.variable)
    print(f"wrote {path}")
    return 0
