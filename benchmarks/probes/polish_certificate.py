r"""Probe: can the documented multistart's design be polished to a first-order certificate?

The problem of docs/optimising_a_drifter.md (``bench_optimize_drifter.py``'s: six variables of
``examples/circuit_drifter_rock_piston.toml``, drilling rate per kW, peak rod stress at most 250 MPa,
drilling rate at least 2.5 m/min). ``bench_optimize_restarts.py``'s multistart reports a design,
polished by SLSQP (12 designs), "stopped at a budget" with a KKT residual of 0.054 (tolerance
:data:`~impactbar.physical.optimality.KKT_TOLERANCE`). This probe starts from a design (``--design``:
a ``bench_optimize_restarts.py --out`` result, its multistart's design, or a JSON of changes) and

1. evaluates it by a fresh orbit, its gradients the polish's
   (:func:`~impactbar.physical.optimize_problem._refined_gradient`) and its certificate
   (:func:`~impactbar.physical.optimality.certify`, SLSQP's active band);
2. with ``--along S1,S2,...``: orbits continued along the certificate's projected gradient (the
   active margins and bounds held to first order; steps in spans), the objective against its
   first-order rise, the drilling rate, or that there is no one-impact orbit;
3. with ``--polish N``: :func:`~impactbar.physical.optimize_polish.polish` (SLSQP, the implicit
   function theorem's gradients) from it with ``N`` designs, each design's orbit continued from the
   nearest one's, a design across a border refused (no value: no orbit, or a figure off the first-order
   prediction from the nearest design with gradients by more than
   :data:`~impactbar.physical.optimality.JUMP_RATIO` times its gradient's norm times the distance),
   then the certificate of its best design again, and that design by a fresh orbit.

``--inside``: the example with ``rock.contact_events = "inside"`` (the lattice blow's re-contact inside
its step), the baseline's figures printed again on it.

Run: ``python benchmarks/probes/polish_certificate.py --design result.json [--inside]
[--along 0.002,0.004] [--polish 40] [--out polished.json]``.

Measured on 6468ba24 from the multistart's design of ``bench_optimize_restarts.py`` (0.110703 m/min/kW,
KKT residual 0.054; benchmarks/HISTORY.md, "the documented multistart's design polished to a
certificate"): the residual 0.05421 again; along the projected gradient (norm 0.00576 per span) the
objective rises as the gradient says (0.997, 0.995 of it at 0.001, 0.002 of the spans), no one-impact
orbit at 0.004 and 0.006, from 0.008 another branch drilling 0.008 m/min slower; the polish of 40
designs (7 refused) reaches 0.1108699 across that border, "not stationary", KKT residual 0.085.
``--inside``: no border to 0.064 of the spans (a smooth maximum along the line near 0.024); the
polish of 40 designs ends at 0.1109513 (the baseline 0.0968652), converged, KKT residual 0.0084.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench_optimize_drifter import CONSTRAINTS, EXAMPLE, VARY  # noqa: E402

from impactbar.physical import build, read_config, with_values  # noqa: E402

FKEY = "drilling_rate_per_kW"


class Problem:
    """The documented problem in the scaled variables: designs by orbits continued from the nearest
    design evaluated, their gradients the polish's, their certificates SLSQP's."""

    def __init__(self, contact_events: str = "step"):
        from impactbar.physical.design_keys import design_bounds
        from impactbar.physical.optimize_problem import DEFAULT_CONSTRAINTS, _limits

        self.cfg, self.folder = read_config(EXAMPLE)
        self.cfg = with_values(self.cfg, {"rock.contact_events": contact_events})  # (the example's: "inside")
        self.spec = design_bounds(self.cfg, VARY, self.folder)
        self.keys = list(self.spec)
        self.lo = np.array([self.spec[k]["low"] for k in self.keys])
        self.span = np.array([self.spec[k]["high"] - self.spec[k]["low"] for k in self.keys])
        self.limits = _limits(CONSTRAINTS, build(self.cfg, self.folder), ideal=False)
        self.kept = dict.fromkeys(DEFAULT_CONSTRAINTS) | self.limits
        self.done: dict = {}  # u's bytes -> (u, record or None, orbit or None, error)
        self.grads: dict = {}  # u's bytes -> (objective gradient, margin gradients)

    def changes(self, u) -> dict:
        x = self.lo + self.span * np.asarray(u, dtype=float)
        return {k: f"{float(v)!r} {self.spec[k]['unit']}" for k, v in zip(self.keys, x, strict=True)}

    def u_of(self, values: dict) -> np.ndarray:
        return (np.array([values[k] for k in self.keys]) - self.lo) / self.span

    def evaluate(self, u, fresh: bool = False):
        """``(record, orbit)`` of the design ``u`` (``(None, None)`` without an orbit), continued from
        the nearest design with an orbit unless ``fresh``."""
        from impactbar.physical.optimize_problem import evaluate_design

        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        key = u.tobytes()
        if key in self.done and not fresh:
            return self.done[key][1:3]
        near = [d for d in self.done.values() if d[2] is not None]
        guess = None if fresh or not near else min(near, key=lambda d: float(np.sum((d[0] - u) ** 2)))[2]
        try:
            drifter = build(with_values(self.cfg, self.changes(u)), self.folder)
            rec, orbit = evaluate_design(drifter, self.kept, guess=guess)
            rec["changes"], rec["values"] = self.changes(u), dict(zip(self.keys, self.lo + self.span * u,
                                                                      strict=True))
            rec["ok"] = True
            error = ""
        except (ValueError, np.linalg.LinAlgError, ArithmeticError) as e:
            rec, orbit, error = None, None, str(e)
        if not fresh:
            self.done[key] = (u, rec, orbit, error)
        return rec, orbit

    def figures(self, rec) -> np.ndarray:
        return np.array([rec["objectives"][FKEY], *(c["scaled"] for c in rec["constraints"].values())])

    def gradients(self, u):
        """The polish's gradients of the design ``u`` (evaluated first): objective (n,), margins (m, n)."""
        from impactbar.physical.optimize_problem import _refined_gradient

        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        key = u.tobytes()
        if key not in self.grads:
            rec, orbit = self.evaluate(u)
            g = _refined_gradient(self.cfg, self.folder, rec, orbit, self.spec, self.limits, FKEY, self.span)
            self.grads[key] = (np.asarray(g.objective), np.asarray(g.constraints))
        return self.grads[key]

    def certificate(self, u, rec=None):
        from impactbar.physical.optimality import certify

        if rec is None:
            rec, _ = self.evaluate(u)
        g, G = self.gradients(u)
        return certify(g, G, rec, u, self.keys, method="the polish's refined gradients", resolution=0.0)

    def jumps(self, u, rec) -> bool:
        """Whether a figure of ``rec`` is off the first-order prediction from the nearest design
        with gradients by more than JUMP_RATIO times its gradient's norm times the distance."""
        from impactbar.physical.optimality import JUMP_FLOOR, JUMP_RATIO

        if not self.grads:
            return False
        k = min(self.grads, key=lambda b: float(np.sum((np.frombuffer(b) - u) ** 2)))
        v = np.frombuffer(k)
        d = float(np.linalg.norm(u - v))
        if d == 0.0:
            return False
        g, G = self.grads[k]
        grads = np.vstack([g, G])
        own = self.figures(self.done[k][1])
        fig = self.figures(rec)
        off = np.abs(fig - own - grads @ (u - v))
        bound = np.maximum(JUMP_RATIO * np.linalg.norm(grads, axis=1) * d,
                           JUMP_FLOOR * np.maximum(np.abs(own), np.abs(fig)))
        return bool(np.any(off > bound))


def projected(cert, keys) -> np.ndarray:
    """The certificate's projected gradient (the active margins and bounds held to first order)."""
    p = np.array(cert.objective_gradient, dtype=float)
    for name, lam in cert.multipliers.items():
        if name in cert.constraint_gradients:
            p = p + lam * np.array(cert.constraint_gradients[name], dtype=float)
    for key, side in cert.bounds.items():
        j = keys.index(key)
        p[j] += cert.multipliers.get(f"{key} {side}", 0.0) * (1.0 if side == "low" else -1.0)
        if (p[j] < 0.0) == (side == "low"):
            p[j] = 0.0
    return p


def show(tag, cert, rec) -> None:
    print(f"{tag}: {FKEY} {rec['objectives'][FKEY]:.7f}, drilling rate "
          f"{rec['objectives']['drilling_rate_m_min']:.7f} m/min, feasible {rec['feasible']}; certificate "
          f"{cert.verdict}, KKT residual {cert.residual:.4g}, active {cert.active}, bounds {cert.bounds}, "
          f"multipliers " + ", ".join(f"{k} {v:.4g}" for k, v in cert.multipliers.items()), flush=True)


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--design", required=True, help="a bench_optimize_restarts.py --out result, or changes")
    p.add_argument("--inside", action="store_true", help='the law\'s contact_events="inside"')
    p.add_argument("--along", default="", help="comma-separated steps along the projected gradient")
    p.add_argument("--polish", type=int, default=0, help="the polish's most designs (0: none)")
    p.add_argument("--out", default=None, help="the polished design's changes and certificate (JSON)")
    args = p.parse_args(argv)
    P = Problem("inside" if args.inside else "step")
    data = json.loads(Path(args.design).read_text())
    values = data["multistart"]["values"] if "multistart" in data else data.get("values", data)
    u0 = P.u_of(values)
    if args.inside:
        c0 = time.process_time()
        base, _ = P.evaluate(P.u_of({k: P.spec[k]["start"] for k in P.keys}), fresh=True)
        print(f"baseline: {FKEY} {base['objectives'][FKEY]:.7f}, drilling rate "
              f"{base['objectives']['drilling_rate_m_min']:.7f} m/min, feasible {base['feasible']} "
              f"({time.process_time() - c0:.1f} s CPU)", flush=True)
    c0 = time.process_time()
    rec, _ = P.evaluate(u0)
    cert = P.certificate(u0, rec)
    show(f"start ({time.process_time() - c0:.1f} s CPU)", cert, rec)
    pg = projected(cert, P.keys)
    norm = float(np.linalg.norm(pg))
    print(f"projected gradient: norm {norm:.5g} per span, direction "
          + ", ".join(f"{k.split('.')[-1]} {x:+.3f}" for k, x in zip(P.keys, pg / norm, strict=True)),
          flush=True)
    base = rec["objectives"][FKEY]
    for s in [float(x) for x in args.along.split(",") if x]:
        u = np.clip(u0 + s * pg / norm, 0.0, 1.0)
        c0 = time.process_time()
        r, _ = P.evaluate(u)
        if r is None:
            print(f"  s {s:.4f}: no orbit ({P.done[u.tobytes()][3][:100]})", flush=True)
            continue
        f = r["objectives"][FKEY]
        print(f"  s {s:.4f}: {FKEY} {f:.7f} (ratio of rises {(f - base) / (s * norm):.4f}), drilling rate "
              f"{r['objectives']['drilling_rate_m_min']:.7f} m/min, jump {P.jumps(u, r)}, "
              f"{time.process_time() - c0:.1f} s CPU", flush=True)
    if args.polish:
        from impactbar.physical.optimize_polish import polish

        def objective(v):
            r, _ = P.evaluate(v)
            if r is None or P.jumps(np.clip(np.asarray(v, dtype=float), 0, 1), r):
                return None
            return r["objectives"][FKEY]

        def margins(v):
            r, _ = P.evaluate(v)
            return np.array([c["scaled"] for c in r["constraints"].values()]) if r is not None else \
                -np.ones(len(P.limits))

        t0, c0 = time.perf_counter(), time.process_time()
        res = polish(objective, margins, P.gradients, u0, designs=args.polish, ftol=(2e-3) ** 3)
        refused = sum(1 for d in P.done.values() if d[1] is None or P.jumps(d[0], d[1]))
        print(f"polish: {res.nfev} designs ({refused} refused), {len(P.grads)} gradients, {res.message}; "
              f"{FKEY} {base:.7f} -> {res.fun:.7f}; {time.perf_counter() - t0:.0f} s wall, "
              f"{time.process_time() - c0:.0f} s CPU", flush=True)
        rec, _ = P.evaluate(res.x)
        cert = P.certificate(res.x, rec)
        show("polished", cert, rec)
        fresh, _ = P.evaluate(res.x, fresh=True)
        print(f"fresh orbit: feasible {fresh['feasible']}, {FKEY} {fresh['objectives'][FKEY]:.7f}",
              flush=True)
        if args.out:
            Path(args.out).write_text(json.dumps({"changes": P.changes(res.x), "values": rec["values"],
                                                  "objective": fresh["objectives"][FKEY],
                                                  "certificate": cert.to_dict()}, indent=1))


if __name__ == "__main__":
    main()
