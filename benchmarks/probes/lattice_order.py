r"""Probe: the order of the lattice's coupled blow under the oil circuit against the exact blow, on
``examples/circuit_drifter_rock.toml`` (its rod as given), and what sets it.

At the second arrival of ``bench_coupled_exact.arrival()`` the exact blow (``method="exact"``,
:func:`impactbar.laws.rodrock.coupled_exact.driven_exact_contact`, ended where it certifies the
piston free for good) and, for each cell count of ``--cells``, the lattice's
(:func:`impactbar.laws.rodrock.coupled.driven_rock_contact`) made to end at the exact blow's instant
rounded up to whole steps (``blow_time``: so that the end does not enter), against

- the exact blow on the rod as given ("true rod"), and
- the exact blow on the rod the lattice solves: each segment's length rounded to whole cells as the
  grid rounds it (``BlowGrid.segment_cells``; "rounded rod"), its own duration given to the lattice.

Per cell count: the largest change of a segment's travel time by the rounding (``length_error``),
the relative differences of the work dissipated in the rock, the permanent penetration, the
piston's velocity after the blow (``v_after[0]``) and the shank's impulse on the piston
(``sum N dt``, which does not depend on the end once the piston is free) against both, and the
observed orders ``log2(e(n) / e(2 n))``. The lattice's own end (``driven_end="free"``, the first
step after which the piston is free) is printed against the exact blow's too.

Measured on 42c7c4d (8, 16, 32, 64, 128 cells): against the true rod the work dissipated in the rock
is 1.6e-6, 1.6e-6, -1.4e-6, 1.1e-7, 1.1e-7 off, the rounding's alone (the segments' travel times
changed 1.9 %, 1.9 %, 1.6 %, 0.13 %, 0.13 %; against the rounded rod the same blows are 1.7e-8,
-9.2e-9, -7.0e-9, -1.2e-9, -3.5e-10 off: second order), so that no event located inside a step
makes the lattice converge faster than its rounding on this rod. The piston's velocity after the
blow is 1.7e-2, -8.1e-3, 2.5e-2, 3.3e-4, 3.3e-4 off (the rounded rod: 2.1e-2, 1.0e-4, 1.1e-2,
1.0e-3, 1.0e-3): the re-contact of piston and shank the lattice finds at a step's end. Located inside
its step (the contact force averaged over it, ``(1 - theta) N``; tried, not kept) the rounded rod's
errors became 3.7e-3, 1.0e-3, 5.4e-4, 2.1e-3, 1.1e-3, still first order: the front that re-contact
sends into the piston comes back ``2 T_p`` later inside a cell and opens the contact there, which
cell averages of a unilateral contact place at a step's end again. The lattice's own end
(``driven_end="free"``) is the exact blow's rounded up to a step, both tested at the multiples of
the shortest travel time (on 42c7c4d, tested every step, it was 0.5 % to 2.4 % of the blow before
it), so that its blow's numbers are those of the first columns.
Segments of fractional cells (each segment's last cell followed by a delay of its travel time's
fraction of a step, ``(1 - theta) a_k + theta a_(k-1)`` both ways; tried in numpy on the blow from
the same arrival under the force held, 11 piston travel times, not kept) converge at second order,
8.7e-3, 2.2e-3, 7.6e-4, 9.5e-5, 3.7e-5 of the work, but the delay's averaging smears the incident
wave's front and is 5000 times the rounding's 1.7e-6 at 8 cells.

Run: ``python benchmarks/probes/lattice_order.py`` (about a minute once compiled). Library
behaviour is not changed.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # (bench_coupled_exact: the arrival)


def _exact_numbers(model, drive, state, t0, q, v):
    b = model.law.driven_contact(model, drive, state, t0, q, v)
    ex = b.record.exact
    return {"work": float(b.record.work_on_rock), "pen": float(ex.permanent_penetration),
            "v": float(b.v_after[0]), "shank": float(ex.junction_impulse(ex.contact_junction)),
            "duration": float(b.t_release - t0)}


def _lattice_numbers(model, cells, duration, drive, state, t0, q, v, end="window"):
    from impactbar.laws.rodrock.coupled import driven_rock_contact

    law = dataclasses.replace(model.law, method="lattice", cells_per_piston=cells,
                              blow_time=duration if end == "window" else None, driven_end=end)
    b = driven_rock_contact(model.with_(impact=law), drive, state, t0, q, v)
    bl = b.record.blow
    return {"work": float(bl.work_on_rock), "pen": float(bl.permanent_penetration), "v": float(b.v_after[0]),
            "shank": float(np.sum(bl.shank_forces) * bl.cell_time), "duration": float(b.t_release - t0),
            "length_error": float(bl.length_error), "energy_error": float(bl.energy_error)}


def _rounded_rod(model, cells):
    """The exact model on the rod whose segments are whole cells of the lattice of ``cells``."""
    law = model.law
    dt = 1.0 / (model.s * cells)
    segs = tuple(dataclasses.replace(g, length=g.length * max(1, round(g.travel_time(model) / dt)) * dt
                                     / g.travel_time(model)) for g in law.segments)
    return model.with_(impact=dataclasses.replace(law, segments=segs))


KEYS = ("work", "pen", "v", "shank")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, nargs="*", default=[8, 16, 32, 64, 128])
    args = ap.parse_args(argv)

    from bench_coupled_exact import arrival

    model, drive, state, t0, q, v = arrival()
    true = _exact_numbers(model, drive, state, t0, q, v)
    print(f"exact blow (true rod): duration {true['duration']:.6g}, work {true['work']:.10g}, "
          f"v_after {true['v']:.10g}")
    errs = {"true": {k: [] for k in KEYS}, "rounded": {k: [] for k in KEYS}}
    print(f"{'cells':>5s} {'rounding':>9s} | {'vs true rod: work':>17s} {'pen':>9s} {'v_after':>9s} "
          f"{'shank':>9s} | {'vs rounded rod: work':>20s} {'pen':>9s} {'v_after':>9s} {'shank':>9s} | "
          f"{'free end - exact end':>20s}")
    for n in args.cells:
        lat = _lattice_numbers(model, n, true["duration"], drive, state, t0, q, v)
        rm = _rounded_rod(model, n)
        rounded = _exact_numbers(rm, drive, state, t0, q, v)
        lat_r = _lattice_numbers(model, n, rounded["duration"], drive, state, t0, q, v)
        free = _lattice_numbers(model, n, None, drive, state, t0, q, v, end="free")
        row = []
        for name, ref, got in (("true", true, lat), ("rounded", rounded, lat_r)):
            for k in KEYS:
                e = (got[k] - ref[k]) / abs(ref[k])
                errs[name][k].append(abs(e))
                row.append(f"{e:9.2e}")
        print(f"{n:5d} {lat['length_error']:9.2e} | {row[0]:>17s} {' '.join(row[1:4])} | {row[4]:>20s} "
              f"{' '.join(row[5:])} | {(free['duration'] - true['duration']) / true['duration']:20.2e}")
    for name in errs:
        for k in KEYS:
            e = np.array(errs[name][k])
            orders = np.log2(e[:-1] / e[1:])
            print(f"orders vs the {name} rod, {k:5s}: " + " ".join(f"{o:6.2f}" for o in orders))


if __name__ == "__main__":
    main()
