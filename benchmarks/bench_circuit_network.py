"""The oil circuit's network of part records (``impactbar.drives.circuit._network``) and the code
generated for its topology (``_netgen.generate``) against the circuit's hand-written kernel
(``tests/circuit_field_reference.py``: ``_base``, ``jac_base``, ``circuit_events``), in the same run:
the time of one call of the vector field, of its Jacobian and of the events at the preset drifter's
state, rigid and with four flexible modes (the three give the same numbers to the bit:
``tests/drives/test_circuit_network.py``).

Run: ``python benchmarks/bench_circuit_network.py [--mode 1110]``. Each call repeated in a compiled
loop (so that the Python call is not timed), the best of a few repetitions of CPU time, the two
in turn.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numba as nb
import numpy as np

from impactbar.drives.circuit import _netgen as NG
from impactbar.physical import circuit_preset

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "drives"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import circuit_field_reference as K  # noqa: E402, I001  (the preset's kernel by hand: the tests' reference)
import network_interpreter as NW  # noqa: E402  (the interpreter of any network: the tests' reference)


@nb.njit
def _loop(f, y, par, M, out, n):
    for _ in range(n):
        f(y, par, M, out)


@nb.njit
def _loop_events(f, z, par, M, g, n):
    for _ in range(n):
        f(z, par, M, g, 0)


@nb.njit
def _kernel_events(z, par, M, g, first):
    """The hand-written kernel's events in the network's signature."""
    K.circuit_events(z[3], z[2], par, K.HEAD + 3 * M, g, first)


def per_call(f, y, par, M, out, n=200_000, reps=5, loop=_loop):
    """The best time of one call (ns)."""
    loop(f, y, par, M, out, 10)
    best = np.inf
    for _ in range(reps):
        t = time.process_time()
        loop(f, y, par, M, out, n)
        best = min(best, (time.process_time() - t) / n * 1e9)
    return best


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mode", default="1110", help="the circuit's mode (target, moving, acc, relief): four "
                    "digits 0 or 1 (default 1110: stroke, the spool ramping, the accumulator holding oil)")
    mode = tuple(int(x) for x in ap.parse_args().mode)
    if len(mode) != 4 or not set(mode) <= {0, 1}:
        raise ValueError(f"--mode must be four digits 0 or 1; got {mode}")
    c = circuit_preset("circuit-drifter")
    drive = c.drive()
    print(f"{'modes':>5} {'':>9} {'kernel ns':>10} {'network ns':>11} {'generated ns':>13} {'net/ker':>8} "
          f"{'gen/ker':>8}")
    for n_modes in (0, 4):
        model = c.model().with_(n_modes=n_modes)
        M = n_modes + 1
        n = 2 * M + 4
        par = K.preset_par(drive, model, mode)
        net = drive._network_par(model, mode)
        y = np.concatenate((np.full(2 * M, 0.01), [0.5, 1.0, 1.5, 0.3], np.zeros(K.N_ENERGY)))
        gen = NG.generate(net[K.HEAD + 3 * M:])
        out, A, g = np.empty(n + K.N_ENERGY), np.empty((n, n)), np.empty(3)
        z = y[2 * M:n]
        for name, fk, fn, fg, x, arg, loop in (
                ("field", K._base, NW.base, gen.base, y, out, _loop),
                ("Jacobian", K.jac_base, NW.jac_base, gen.jac_base, y, A, _loop),
                ("events", _kernel_events, NW.events, gen.events, z, g, _loop_events)):
            tk, tn, tg = np.inf, np.inf, np.inf
            for _ in range(3):
                tk = min(tk, per_call(fk, x, par, M, arg, loop=loop))
                tn = min(tn, per_call(fn, x, net, M, arg, loop=loop))
                tg = min(tg, per_call(fg, x, net, M, arg, loop=loop))
            print(f"{n_modes:>5} {name:>9} {tk:>10.1f} {tn:>11.1f} {tg:>13.1f} {tn / tk:>8.2f} "
                  f"{tg / tk:>8.2f}")


if __name__ == "__main__":
    main()
