r"""Probe: the oil circuit's state along the slot lattice's coupled blow, against the exact blow's.

The coupled blow (theory §11, "The coupled blow") flies the circuit over the blow in pieces
(``DrivenContact.pieces``, each a :class:`~impactbar.drives.circuit.endflight.EndPiece` with its
dense output). From the tests' arrival (``tests/laws/coupled_reference.drifter_arrival``, the
example's rod), this probe solves the exact coupled blow and the slots' on each cell count of
``--cells``, and prints at ``--points`` instants evenly from the fraction ``--start`` of the exact
blow's duration to its end the relative differences of the front and rear chambers' pressures and
the difference of the driven end's displacement ``w`` (model units), with ``w`` itself.

Run: ``python benchmarks/probes/slot_circuit_trace.py [--cells 128 194] [--start 0.05]
[--points 20]`` from the repository's root. Figures: ``benchmarks/HISTORY.md``, "slots that carry
their slopes".
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "laws"))

from coupled_reference import drifter_arrival, slots_model  # noqa: E402


def state_at(contact, t):
    """The circuit's states and the driven end's displacement of a coupled blow at time ``t`` (the
    first piece that holds it)."""
    for piece in contact.pieces:
        if piece.t0 - 1e-15 <= t <= piece.t_end + 1e-15:
            return piece.drive_state(np.array([t]))[:, 0], float(piece.displacement(np.array([t]))[0])
    raise ValueError(f"no piece holds t = {t}")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cells", type=int, nargs="+", default=[128, 194])
    parser.add_argument("--start", type=float, default=0.05)
    parser.add_argument("--points", type=int, default=20)
    args = parser.parse_args(argv)

    model, drive, state, t0, q, v = drifter_arrival()
    ex = model.law.driven_contact(model, drive, state, t0, q, v)
    duration = ex.t_release - t0
    for n in args.cells:
        m = slots_model(model, n)
        c = m.law.driven_contact(m, drive, state, t0, q, v)
        print(f"{n} cells: fraction of the blow | front, rear chamber (relative) | w's difference | w")
        for f in np.linspace(args.start, 1.0, args.points):
            t = t0 + f * duration
            zx, wx = state_at(ex, min(t, ex.t_release))
            zl, wl = state_at(c, min(t, c.t_release))
            print(f"{f:.3f} | {(zl[0] - zx[0]) / abs(zx[0]):+.2e} {(zl[1] - zx[1]) / abs(zx[1]):+.2e} | "
                  f"{wl - wx:+.2e} | {wx:.4e}", flush=True)


if __name__ == "__main__":
    main()
