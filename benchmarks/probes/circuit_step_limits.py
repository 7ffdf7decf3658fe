r"""Probe: where a circuit's rigid orbit spends CVODE's steps, counted over one ``find_orbit`` from the
default guess (after a call that compiles): by stage of the orbit's search (the settling flights at
``SETTLE_RTOL``, the chord's steering Jacobian and plain flights, the closing Newton step, the orbit's
data and multipliers), by kind of flight (plain or variational), the steps a flight spends before
CVODE's order first reaches 4 (each flight restarts at order 1 from a step of some ``1e-11``), and
which component limits each step: the one whose estimated local error, weighted by CVODE's error
weights (``|e_i| / (rtol |y_i| + atol)``), is the largest (``CVodeGetEstLocalErrors``,
``CVodeGetErrWeights``; a variational flight's ``Phi`` counted by its row's state). Then each stage's
CPU time (the best of ``--rounds`` orbits, each stage timed apart).

The flights run the loop of ``_cvode.fly`` (the same CVODE calls, so the same steps: the totals are
``circuit_flight_counts.py``'s) with the error estimates read after each step.

Run: ``PYTHONPATH=<tree>/src python benchmarks/probes/circuit_step_limits.py spool`` (``spool``:
``examples/circuit_drill_spool.toml``; ``parts``: ``circuit_drill_parts.toml``; ``preset``: the preset
``circuit-drifter``). Library behaviour is not changed.
"""

from __future__ import annotations

import collections
import ctypes
import time
import traceback

import llvmlite.binding as llvm
import numba as nb
import numpy as np
from circuit_flight_counts import arguments, drill  # (this folder's: the drills and the command line)
from numba import types

import impactbar.drives.circuit.flight as FL
from impactbar import find_orbit
from impactbar.drives.circuit import _cvode as CV
from impactbar.drives.circuit import _sundials as S
from impactbar.orbits import shooting as SH

#: the stages of ``find_orbit``, by the function of the shooting problem that flies them
STAGES = (("_settle", "settle"), ("_steered_chord", "chord"), ("close", "closing step"),
          ("orbit_data", "orbit's data"))

S.bind()
_LIB = S._BINDING.libs["sundials_cvode"]
for _name in ("CVodeGetEstLocalErrors", "CVodeGetErrWeights", "CVodeGetLastOrder"):
    llvm.add_symbol("probe_" + _name, ctypes.cast(getattr(_LIB, _name), ctypes.c_void_p).value)
_local_errors = types.ExternalFunction("probe_CVodeGetEstLocalErrors", types.intc(types.intp, types.intp))
_weights = types.ExternalFunction("probe_CVodeGetErrWeights", types.intc(types.intp, types.intp))
_order = types.ExternalFunction("probe_CVodeGetLastOrder", types.intc(types.intp, types.intp))
_new_vector = S._BINDING.libs["sundials_nvecserial"].N_VNew_Serial
_new_vector.restype, _new_vector.argtypes = ctypes.c_void_p, [ctypes.c_int64, ctypes.c_void_p]


@nb.njit
def fly(mem, yvec, y0, t_end, rtol, atol, directions, par, keep, ele_vec, ewt_vec):
    """``_cvode.fly``'s loop from 0, with each step's order and limiting component."""
    N = y0.size
    y = nb.carray(CV._nv_data(yvec), N)
    ele, ewt = nb.carray(CV._nv_data(ele_vec), N), nb.carray(CV._nv_data(ewt_vec), N)
    y[:] = y0
    roots = np.zeros(directions.size, np.int32)
    flag = CV._reinit(mem, 0.0, yvec)
    flag = max(flag, CV._tolerances(mem, rtol, atol), CV._user_data(mem, par.ctypes.data),
               CV._root_direction(mem, directions.ctypes.data), CV._stop_time(mem, t_end))
    T, Y, orders, limits = [0.0], [y0[:keep].copy()], [0], [-1]
    tret, q = np.zeros(1), np.zeros(1, np.intc)
    while flag >= 0:
        flag = CV._step(mem, t_end, yvec, tret.ctypes.data, CV.CV_ONE_STEP)
        if flag < 0:
            break
        _local_errors(mem, ele_vec)
        _weights(mem, ewt_vec)
        _order(mem, q.ctypes.data)
        T.append(tret[0])
        Y.append(y[:keep].copy())
        orders.append(q[0])
        limits.append(int(np.argmax(np.abs(ele * ewt))))
        if flag == CV.CV_ROOT_RETURN:
            CV._root_info(mem, roots.ctypes.data)
            break
        if flag == CV.CV_TSTOP_RETURN:
            break
    CV._clear_stop(mem)
    out = np.empty((len(Y), keep))
    for i in range(len(Y)):
        out[i] = Y[i]
    return flag, np.array(T), out, y.copy(), roots, np.array(orders), np.array(limits)


class Counter:
    """The flights of one orbit: by stage and kind, their steps, restart steps and limiting components."""

    def __init__(self, names):
        self.names, self.vectors, self.stage = names, {}, "other"
        self.steps = collections.Counter()
        self.ramp = collections.Counter()
        self.flights = collections.Counter()
        self.limits = collections.defaultdict(collections.Counter)

    def component(self, i, n):
        """The state a component of a flight's vector stands for (``Phi``'s by its row)."""
        if i < len(self.names):
            return self.names[i]
        return "Phi: " + self.names[(i - len(self.names)) % n]

    def integrate(self, cv, band, blocks, adams, n_energy, code, par, settings, directions, y0, t, end, keep):
        n = keep - n_energy
        var = band and y0.size > keep
        rhs, jac, jac_band, events, n_events = code.CALLBACKS
        ws = cv.workspace(y0.size, n - 1 if var else 0, (rhs, jac_band if var else jac, events, n_events),
                          blocks and var, adams)
        if ws.mem not in self.vectors:
            self.vectors[ws.mem] = (_new_vector(y0.size, ws.ctx), _new_vector(y0.size, ws.ctx))
        flag, ts, Y, yend, roots, orders, limits = fly(
            ws.mem, ws.y, y0, float(end - t), float(settings.rtol), float(settings.atol),
            np.asarray(directions, dtype=np.int32), par, keep, *self.vectors[ws.mem])
        key = (self.stage, "variational" if var else "plain")
        self.flights[key] += 1
        self.steps[key] += ts.size - 1
        reached = np.flatnonzero(orders[1:] >= 4)
        self.ramp[key] += int(reached[0]) if reached.size else ts.size - 1
        self.limits[key[1]].update(self.component(int(i), n) for i in limits[1:])
        return int(flag), None, ts + t, Y, yend, np.flatnonzero(roots)


def stage_of(stack) -> str:
    names = [f.name for f in stack]
    return next((label for fn, label in STAGES if fn in names), "other")


def main() -> None:
    a = arguments(__doc__)
    model, drive = drill(a.drill)
    L = drive.layout
    find_orbit(model, drive)  # (compiles)
    counter = Counter(["q", "q'", *L.state_names, *(f"E: {e}" for e in L.energies)])
    plain_fly, plain_integrate, cpu = SH.ShootingProblem._fly, FL._integrate_compiled, collections.Counter()

    def staged(self, *args):
        counter.stage = stage_of(traceback.extract_stack(limit=12))
        t = time.process_time()
        out = plain_fly(self, *args)
        cpu[counter.stage] += time.process_time() - t
        return out

    SH.ShootingProblem._fly = staged
    try:
        FL._integrate_compiled = counter.integrate
        find_orbit(model, drive)
        FL._integrate_compiled = plain_integrate
        best = None
        for _ in range(a.rounds):
            cpu.clear()
            t = time.process_time()
            find_orbit(model, drive)
            total = time.process_time() - t
            if best is None or total < best[0]:
                best = (total, dict(cpu))
    finally:
        SH.ShootingProblem._fly, FL._integrate_compiled = plain_fly, plain_integrate
    print(f"{a.drill}: {sum(counter.flights.values())} flights, {sum(counter.steps.values())} steps; "
          f"find_orbit CPU s, best of {a.rounds}: {best[0]:.4f}")
    print(f"{'stage':<14}{'kind':<13}{'flights':>8}{'steps':>8}{'before order 4':>16}{'stage CPU s':>13}")
    timed = set()
    for (stage, kind), k in counter.flights.items():
        clock = "" if stage in timed else f"{best[1].get(stage, 0.0):.4f}"  # (a stage's, on its first row)
        timed.add(stage)
        print(f"{stage:<14}{kind:<13}{k:>8}{counter.steps[stage, kind]:>8}{counter.ramp[stage, kind]:>16}"
              f"{clock:>13}")
    for kind, limits in counter.limits.items():
        total = sum(limits.values())
        shares = ", ".join(f"{c} {v / total:.0%}" for c, v in limits.most_common(8))
        print(f"limiting the {kind} steps: {shares}")


if __name__ == "__main__":
    main()
