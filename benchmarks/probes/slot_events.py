r"""Probe: how the slot lattice's coupled blow (``RodRock(contact_events="slots")``) converges to the
exact blow under the oil circuit, over several arrivals, and where the shank's impulse on the piston
goes wrong inside a blow.

From the arrival of ``tests/laws/coupled_reference.drifter_arrival`` (the example's rod as given, or
with ``--whole`` the rod of whole piston lengths, ``WHOLE_CELLS``), its piston's velocity scaled by
``1 + eps`` for ``--arrivals`` values of ``eps`` evenly in ``[-0.02, 0.02]`` (so that the events fall
at other fractions of their steps), the exact blow (``method="exact"``) and the slots' on each cell
count of ``--cells``, each ended where it finds the piston free for good. Printed per arrival: the
relative difference of the piston's velocity after the blow from the exact one at each cell count;
then per cell count the largest over the arrivals of that difference, of the work dissipated in the
rock's and of the circuit's state's (each component relative), and the velocity's root mean square.

With ``--impulse`` (one arrival, ``eps = --eps``): for each cell count, the steps where the slots'
shank force averaged over the step differs from the exact blow's (its average by the midpoint rule
on 64 points, on 200,000 where the difference exceeds ``--threshold`` times the cell time, or where
the exact contact opens or closes inside the step) by more than that, and the impulse's total
difference; and the instants the exact contact opens and closes (sampled on 2,000,001 points).

Run: ``python benchmarks/probes/slot_events.py [--whole] [--cells 8 16 32 64 128] [--arrivals 9]``
or ``... --impulse [--eps 0] [--threshold 1e-7]``, from the repository's root (it reads
``examples/circuit_drifter_rock.toml``). Figures: ``benchmarks/HISTORY.md``, "the slot lattice's
re-contact".
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "laws"))

from coupled_reference import WHOLE_CELLS, blow_differences, drifter_arrival, slots_model  # noqa: E402


def envelope(arrival, cells, count):
    model, drive, state, t0, q, v = arrival
    rows = {n: [] for n in cells}
    for i, eps in enumerate(np.linspace(-0.02, 0.02, count)):
        vv = np.asarray(v, dtype=float) * (1.0 + eps)
        ex = model.law.driven_contact(model, drive, state, t0, q, vv)
        for n in cells:
            m = slots_model(model, n)
            work, _, z, velocity = blow_differences(m.law.driven_contact(m, drive, state, t0, q, vv), ex)
            rows[n].append((velocity, work, z))
        errors = " ".join(f"{rows[n][-1][0]:.1e}" for n in cells)
        print(f"arrival {i} eps {eps:+.4f}: velocity after {errors}", flush=True)
    print("cells | largest: velocity after, work on rock, circuit's state | velocity rms")
    for n in cells:
        a = np.array(rows[n])
        print(f"{n:5d} | {a[:, 0].max():.2e} {a[:, 1].max():.2e} {a[:, 2].max():.2e} | "
              f"{np.sqrt(np.mean(a[:, 0] ** 2)):.2e}")


def impulse(arrival, cells, eps, threshold):
    model, drive, state, t0, q, v = arrival
    v = np.asarray(v, dtype=float) * (1.0 + eps)
    bx = model.law.driven_contact(model, drive, state, t0, q, v).record.blow
    T = np.linspace(0.0, bx.duration, 2_000_001)
    on = bx.junction_force(0, T) > 0.0
    changes = T[np.flatnonzero(on[1:] != on[:-1])]
    print("the exact contact opens or closes at", ", ".join(f"{t:.9f}" for t in changes))
    for n in cells:
        m = slots_model(model, n)
        b = m.law.driven_contact(m, drive, state, t0, q, v).record.blow
        h, jf = b.cell_time, b.junction_forces[:, 0]
        print(f"{n} cells: the impulse {b.junction_impulse(0) - bx.junction_impulse(0):+.3e} off")
        for i in range(jf.size):
            near = np.any(np.abs(changes - (i + 0.5) * h) < h)
            ref = np.mean(bx.junction_force(0, (i + (np.arange(64) + 0.5) / 64) * h))
            if abs(jf[i] - ref) * h > threshold or near:
                ref = np.mean(bx.junction_force(0, (i + (np.arange(200_000) + 0.5) / 200_000) * h))
                if abs(jf[i] - ref) * h > threshold:
                    print(f"  step {i} [{i * h:.6f}, {(i + 1) * h:.6f}]: slots {jf[i]:.6e}, exact {ref:.6e}, "
                          f"impulse {(jf[i] - ref) * h:+.3e}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--whole", action="store_true", help="the rod of whole piston lengths")
    ap.add_argument("--cells", type=int, nargs="+", default=[8, 16, 32, 64, 128])
    ap.add_argument("--arrivals", type=int, default=9)
    ap.add_argument("--impulse", action="store_true", help="the shank's impulse step by step, one arrival")
    ap.add_argument("--eps", type=float, default=0.0)
    ap.add_argument("--threshold", type=float, default=1e-7)
    args = ap.parse_args()
    arrival = drifter_arrival(WHOLE_CELLS) if args.whole else drifter_arrival()
    if args.impulse:
        impulse(arrival, args.cells, args.eps, args.threshold)
    else:
        envelope(arrival, args.cells, args.arrivals)


if __name__ == "__main__":
    main()
