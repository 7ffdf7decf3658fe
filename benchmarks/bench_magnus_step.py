"""The Magnus step of the flexible piston's variational flight: the steps, the milliseconds and the
microseconds per step of the generated ``magnus_phi`` over the first flight of the
``circuit-drifter`` preset's orbit with 4 and 8 modes (the plain flight's steps, the flight's
balance, ``theta`` the default), and the parts of a step (the Jacobian at an interpolated state, the
exponential, the step's ``exp(Omega)``, the product ``E Phi``) with 8 modes.

The least CPU time of repeated calls after a warm-up (numba's compilation; the machine's other
sessions move wall time more than CPU time). Run:
``python benchmarks/bench_magnus_step.py``; ``--against REF`` runs it on the git ref ``REF`` too, in
fresh processes, alternately, and prints both side by side (the best of ``--rounds`` each).
"""

from __future__ import annotations

import argparse
import json
import math
import sys

import numpy as np
from _timing import best_cpu, fresh_runs, ref_tree  # this folder's shared runner


def _flight(n_modes):
    """The generated code, its arguments for ``magnus_phi`` and the flight's size."""
    from impactbar import find_orbit
    from impactbar.drives.base import DriveState
    from impactbar.drives.circuit import _magnus
    from impactbar.physical import circuit_preset

    d = circuit_preset("circuit-drifter")
    model, drive = d.model().with_(n_modes=n_modes), d.drive()
    orbit = find_orbit(model, drive)
    problem, X = orbit._problem, np.asarray(orbit._unknowns, dtype=float)
    M, n = problem.M, problem.n
    tau, mode = problem.blocks[0]
    y = X[:n]
    start = (DriveState(mode, y[2 * M:]), tau, y[:M], y[M:2 * M])
    try:
        from impactbar.drives.circuit import CircuitFlightSettings
    except ImportError:  # (--against a tree before the solver's settings: the option was the drive's)
        import dataclasses

        fl = dataclasses.replace(drive, sensitivity="cvode").flight(model, *start, math.inf, None, False)
    else:
        fl = drive.flight(model, *start, math.inf, CircuitFlightSettings(sensitivity="cvode"), False)
    piece, state = fl.piece, start[0]
    net, code = drive._compiled_network(state.mode)
    par = np.concatenate((drive._par(model, state.mode, False), net))
    d = _magnus.balance(code.jac_base, piece.y[piece.t.size // 2], par, M, n)
    own = np.ascontiguousarray(piece.t - piece.t[0])
    return code, (own, piece.y, piece.f, par, M, _magnus.DEFAULT_THETA, d), n


def cases(modes=(4, 8)) -> dict:
    """``{case: microseconds}``."""
    from impactbar.drives.circuit import _magnus

    out = {}
    for m in modes:
        code, args, n = _flight(m)
        steps = code.magnus_phi(*args)[1]
        sec = best_cpu(lambda c=code, a=args: c.magnus_phi(*a), 7)
        out[f"{m} modes: Magnus steps (n {n})"] = steps
        out[f"{m} modes: the flight (ms)"] = 1e3 * sec
        out[f"{m} modes: us per step"] = 1e6 * sec / steps
    own, y, f, par, M, _, d = args
    A1, A2, ys = np.empty((n, n)), np.empty((n, n)), np.empty(y.shape[1])
    rng = np.random.default_rng(1)
    Om = rng.standard_normal((n, n))
    Om *= 0.5 / np.max(np.sum(np.abs(Om), axis=0))
    code.jac_base(y[0], par, M, A1)
    code.jac_base(y[1], par, M, A2)
    reps = 2000

    def loop(fn):
        return 1e6 * best_cpu(lambda: [fn() for _ in range(reps)], 5) / reps

    out[f"{modes[-1]} modes: jac_base (us)"] = loop(lambda: code.jac_base(ys, par, M, A1))
    out[f"{modes[-1]} modes: state_at (us)"] = loop(lambda: _magnus.state_at(own, y, f, own[1], 0, ys))
    out[f"{modes[-1]} modes: expm, norm 0.5 (us)"] = loop(lambda: _magnus.expm(Om))
    out[f"{modes[-1]} modes: expm, norm 1 (us)"] = loop(lambda: _magnus.expm(2.0 * Om))
    h = _magnus.DEFAULT_THETA / np.max(np.sum(np.abs(A1), axis=0))
    if hasattr(_magnus, "scales"):  # (order 6: the Jacobians at three Gauss points, the balance's ratios)
        A3, S = np.empty((n, n)), _magnus.scales(d)
        code.jac_base(y[2], par, M, A3)
        out[f"{modes[-1]} modes: magnus_exp (us)"] = loop(lambda: _magnus.magnus_exp(A1, A2, A3, h, S))
    else:  # (order 4, two Gauss points: the way before)
        out[f"{modes[-1]} modes: magnus_exp (us)"] = loop(lambda: _magnus.magnus_exp(A1, A2, h, d))
    out[f"{modes[-1]} modes: product (us)"] = loop(lambda: Om @ A1)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", metavar="REF", help="compare with the git ref REF (e.g. main)")
    parser.add_argument("--rounds", type=int, default=1, help="processes each with --against")
    parser.add_argument("--modes", type=int, nargs="+", default=[4, 8])
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)  # (--against's child)
    args = parser.parse_args(argv)
    modes = tuple(args.modes)
    if args.json or not args.against:
        out = cases(modes)
        print(json.dumps(out) if args.json else "\n".join(f"{c:40s} {us:10.2f}" for c, us in out.items()))
        return
    runs = fresh_runs(__file__, ref_tree(args.against), args.rounds, ["--modes", *map(str, modes)])
    print(f"{'case (best of ' + str(args.rounds) + ')':40s} {args.against[:10]:>10s} {'this tree':>10s}")
    for case in runs["new"][0]:
        b = min(r.get(case, math.nan) for r in runs["baseline"])
        n = min(r[case] for r in runs["new"])
        print(f"{case:40s} {b:10.2f} {n:10.2f}   ({b / n:.2f}x)")


if __name__ == "__main__":
    sys.exit(main())
