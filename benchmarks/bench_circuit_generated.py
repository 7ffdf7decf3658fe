r"""The oil circuit's flights through the code generated for its network's topology
(``circuit_flight``: ``_netgen``'s kernels and C callbacks) against the preset's hand-written kernels
(``kernels=circuit_field_reference.KERNELS``, the tests' reference), in the same run, alternated: one plain
flight of the rigid piston and one variational flight with 4 modes of the preset ``circuit-drifter``
from the start of its orbit search, each checked the same to the bit.

Usage: ``python benchmarks/bench_circuit_generated.py [--rounds R]`` (CPU seconds, best of ``R``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from impactbar.drives import DriveState
from impactbar.drives.circuit import flight as F
from impactbar.physical import circuit_preset

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import circuit_field_reference as K  # noqa: E402  (the preset's kernel written by hand: the tests' reference)


def _case(drive, model, variational):
    M = model.n_modes + 1
    q, v = np.zeros(M), np.zeros(M)
    q[0] = -0.08
    state = DriveState((1, 1, 1, 0), np.array([0.9, 0.9, 0.9, 0.3]))

    def run(generated):
        return F.circuit_flight(drive, model, state, 0.3, q, v, 50.0, variational=variational,
                                kernels=None if generated else K.KERNELS)
    return run


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=10)
    args = parser.parse_args(argv)
    preset = circuit_preset("circuit-drifter")
    drive, rigid = preset.drive(), preset.model()
    head = f"case (CPU ms, best of {args.rounds})"
    print(f"{head:34s} {'kernels':>9s} {'generated':>10s}  same")
    for name, model, var in (("rigid plain flight", rigid, False), ("4 modes variational flight",
                                                                   rigid.with_(n_modes=4), True)):
        run = _case(drive, model, var)
        a, b = run(False), run(True)
        same = np.array_equal(a.piece.t, b.piece.t) and np.array_equal(a.piece.y, b.piece.y) and (
            not var or np.array_equal(a.sensitivity, b.sensitivity))
        best = {False: np.inf, True: np.inf}
        for _ in range(args.rounds):
            for g in (False, True):
                t0 = time.process_time()
                run(g)
                best[g] = min(best[g], time.process_time() - t0)
        ms = 1e3 * best[False], 1e3 * best[True]
        print(f"{name:34s} {ms[0]:9.2f} {ms[1]:10.2f}  {same} ({a.piece.t.size} steps)")


if __name__ == "__main__":
    main()
