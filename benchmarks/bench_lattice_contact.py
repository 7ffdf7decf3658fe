"""How the lattice's coupled blow under the oil circuit converges to the exact one as its cells
double: one blow from the same arrival (``bench_coupled_exact.arrival``) on the lattice with
``RodRock(driven_end="free")`` at 8 to 256 cells per piston and with ``method="exact"``, neither's
duration set from the other's.

Printed per cell count: where the lattice's blow ends after the exact one's (``tl - te``, model
time: the step end at or after the same tested instant); the piston's rigid velocity after the blow
less the exact's, as returned (``dv_raw``) and carried back to the exact's end by the lattice's own
drive and shank forces over the steps between (``dv_at_te``); the work dissipated in the rock less
the exact's (``dW_diss``) and the same with the rock's stored energy at the end (``dW_total``).
``--whole`` puts the rod on whole piston lengths (448.54236 and 1345.62708 mm), where no segment is
rounded to whole cells. A table per ``contact_events`` of the lattice (``--events``; ``"inside"``
locates the contact's switches inside their steps). The exact blow takes about a minute.

Run: ``python benchmarks/bench_lattice_contact.py [--whole] [--events step inside]``.
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np
from bench_coupled_exact import arrival

from impactbar.laws.rodrock.coupled import driven_rock_contact

WHOLE = {"rod.segments.0.length": "448.54236 mm", "rod.segments.1.length": "1345.62708 mm"}


def errors(model, drive, state, t0, q, v, exact, cells, events="step"):
    """``(tl - te, dv_raw, dv_at_te, dW_diss, dW_total)`` of the lattice's blow on ``cells`` (its
    ``contact_events``: ``events``)."""
    law = dataclasses.replace(model.law, method="lattice", cells_per_piston=cells, driven_end="free",
                              contact_events=events)
    b = driven_rock_contact(model.with_(impact=law), drive, state, t0, q, v)
    blow, te = b.record.blow, exact.t_release
    n, dt = blow.shank_forces.size, blow.cell_time
    starts = t0 + dt * np.arange(n)
    overlap = np.clip(np.minimum(starts + dt, b.t_release) - np.maximum(starts, te), 0.0, None)
    v_te = float(b.v_after[0]) - float(np.sum((b.record._drive[:n] - blow.shank_forces) * overlap))
    ve, we, se = float(exact.v_after[0]), exact.record.work_on_rock, exact.record.rock_stored_energy
    return (b.t_release - te, float(b.v_after[0]) - ve, v_te - ve, blow.work_on_rock - we,
            blow.work_on_rock + blow.rock_stored_energy - we - se)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--whole", action="store_true", help="the rod on whole piston lengths")
    parser.add_argument("--cells", type=int, nargs="+", default=[8, 16, 32, 64, 128, 256])
    parser.add_argument("--events", nargs="+", default=["step", "inside"], choices=["step", "inside"],
                        help="the lattice's contact_events, a table each")
    args = parser.parse_args(argv)
    model, drive, state, t0, q, v = arrival(WHOLE if args.whole else None)
    exact = model.law.driven_contact(model, drive, state, t0, q, v)
    print(f"exact: duration {exact.t_release - t0:.6g}, v_after {float(exact.v_after[0]):.10g}, "
          f"dissipated {exact.record.work_on_rock:.10g}, stored {exact.record.rock_stored_energy:.4g}")
    for events in args.events:
        print(f"contact_events={events!r}")
        print(f"{'cells':>5} {'tl - te':>10} {'dv_raw':>10} {'dv_at_te':>10} {'dW_diss':>10}"
              f" {'dW_total':>10}")
        for cells in args.cells:
            row = errors(model, drive, state, t0, q, v, exact, cells, events)
            print(f"{cells:5d} " + " ".join(f"{x:10.3e}" for x in row), flush=True)


if __name__ == "__main__":
    main()
