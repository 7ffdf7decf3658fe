r"""Probe: what the slot lattice's blow (``RodRock(contact_events="slots")``) on the example's rod owes
to where its delays fall in the step.

A rod segment whose travel time is not whole steps is its whole cells and a *delay* of the fraction
``delta`` of a step left over (theory §11, the slot lattice). The delay itself is exact for the
slots' waves; what ``delta`` changes is where in its step a front reflected there comes back. This
probe solves the blow with the drive's force held at the arrival's
(``tests/laws/coupled_reference.held_blow``: no drive's state, the rod and the bit alone) from the
tests' arrival, exactly and on the slots at each cell count of ``--cells``, on one of four rods:

- ``example``: the example's rod (a 0.4 m shank, a 1.2 m rod: two delays);
- ``shank``: the rod's far segment made whole piston lengths (1345.62708 mm): the shank's delay only;
- ``far``: the shank made one piston length (448.54236 mm): the far segment's delay only;
- ``whole``: both whole (``WHOLE_CELLS``): no delay.

Printed per cell count: each delay's fraction of a step, and the relative differences from the exact
blow of the piston's velocity after the blow and of the work dissipated in the rock. ``--cut-jump``
and ``--max-slots`` replace the slots' cut rule (``CUT_JUMP``; a negative value cuts at every jump, so
that a delay hands on its wave exactly) and their cap a step (``MAX_SLOTS``), to show what the
differences do not come from.

Run: ``python benchmarks/probes/slot_delay_fraction.py [--rod shank] [--cells 8 16 32 64 128 256]
[--cut-jump 1e-4] [--max-slots 24]`` from the repository's root (it reads
``examples/circuit_drifter_rock.toml``). Figures: ``benchmarks/HISTORY.md``, "the slot lattice's
tail on the example's rod".
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "laws"))

from coupled_reference import WHOLE_CELLS, drifter_arrival, held_blow, slots_model  # noqa: E402

RODS = {"example": None,
        "shank": {"rod.segments.1.length": WHOLE_CELLS["rod.segments.1.length"]},
        "far": {"rod.segments.0.length": WHOLE_CELLS["rod.segments.0.length"]},
        "whole": WHOLE_CELLS}


def delays(model):
    """Each delay's ``(cell, fraction of a step)`` of ``model``'s slot lattice."""
    from impactbar.laws.rodrock.contact import BlowMap
    from impactbar.loads import FourierLoad

    return [(int(j), float(d)) for j, d in BlowMap(model, FourierLoad(1.0, []), 0.0).grid.delays if d > 0.0]


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rod", choices=sorted(RODS), default="shank")
    parser.add_argument("--cells", type=int, nargs="+", default=[8, 16, 32, 64, 128, 256])
    parser.add_argument("--cut-jump", type=float, default=None)
    parser.add_argument("--max-slots", type=int, default=None)
    args = parser.parse_args(argv)

    from impactbar.laws.rodrock import _rockslots

    if args.cut_jump is not None:
        _rockslots.CUT_JUMP = args.cut_jump
    if args.max_slots is not None:
        _rockslots.SlotLattice.__init__.__defaults__ = (args.max_slots,)

    arrival = drifter_arrival(RODS[args.rod])
    model = arrival[0]
    v_ex, w_ex = held_blow(arrival, model)
    print(f"rod {args.rod}; cut jump {_rockslots.CUT_JUMP:g}, "
          f"max slots {_rockslots.SlotLattice.__init__.__defaults__[0]}")
    print("cells | delays' fractions | velocity after | work dissipated")
    for n in args.cells:
        m = slots_model(model, n)
        v, w = held_blow(arrival, m)
        fractions = " ".join(f"{d:.3f}" for _, d in delays(m)) or "-"
        print(f"{n:5d} | {fractions:>11} | {v / v_ex - 1.0:+.2e} | {w / w_ex - 1.0:+.2e}", flush=True)


if __name__ == "__main__":
    main()
