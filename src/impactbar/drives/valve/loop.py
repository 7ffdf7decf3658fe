"""The valve's compiled event loop, as the simulator runs it (theory §10).

:class:`ValveLoop` is what :meth:`PositionSwitchedDrive.compiled_loop
<impactbar.PositionSwitchedDrive.compiled_loop>` gives the simulator
(:func:`impactbar.simulate` under an instantaneous law, switch ``simulate.valve_loop``): it
hands the valve's state and the modal state to the compiled loop
(:func:`impactbar.drives.valve._compiled_loop.run_switched`), calls it again while its logs fill, and
returns the impacts, switches and flights it followed (a :class:`~impactbar.drives.base.KernelRun`),
with the same pieces, impacts and switches as the simulator's loop in Python
(:mod:`impactbar.simulation.driven`), which runs the pieces the compiled loop hands back.
"""

from __future__ import annotations

import numpy as np

from ..base import DriveState, FlightKernel, KernelRun
from . import _compiled_loop as SK
from ._state import KIND

__all__ = ["ValveLoop"]

#: room in the compiled loop's pending list (more pending switches: the Python loop's step)
_PEND_CAP = 64
#: impacts in the compiled loop's first logs (doubled at each call, up to 65536)
_FIRST_CAP = 256
#: the valve's states' names by index (the kinds of the switches logged)
_NAMES = [KIND[k] for k in range(len(KIND))]


class ValveLoop:
    """The compiled valve loop of one run.

    Parameters
    ----------
    drive : PositionSwitchedDrive
    kernel : FlightKernel
        The driver's data of the one-piece loads ``+stroke`` and ``-ret`` (in that order), the
        free-free basis, the law's kernel restitution, the end weights, the chatter tolerance,
        whether the rigid bar's closed forms run and which impact search.
    """

    def __init__(self, drive, kernel: FlightKernel) -> None:
        self.drive = drive
        self.views = kernel.loads
        self.B = kernel.basis
        self.R, self.c = kernel.R, kernel.c
        self.dview = tuple(drive.kernel_view)
        self.clock = np.zeros(SK.CLK_SIZE)
        self.clock[SK.CLK_TAIL] = kernel.tail
        self.ints = np.zeros(SK.INT_SIZE, dtype=np.int64)
        self.flags = (int(kernel.rigid), int(kernel.fast_search))
        self.pend_t = np.empty(_PEND_CAP)
        self.pend_k = np.empty(_PEND_CAP, dtype=np.int64)
        self.cap = _FIRST_CAP

    def run(self, state: DriveState, t: float, q, v, t_end: float, n_imp: int, max_imp: int) -> KernelRun:
        """Follow the valve from ``state`` and the modal state ``(q, v)`` at ``t`` (arrays, updated in
        place) until ``t_end``, ``max_imp`` impacts or a piece the simulator must run; ``PYTHON``
        at once where more switches are pending than the compiled list holds."""
        (valve, pending), z = state
        imp_t, imp_v, sw_t, sw_y, sw_k, blocks = [], [], [], [], [], []
        status = KernelRun.PYTHON
        clock, ints, pend_t, pend_k = self.clock, self.ints, self.pend_t, self.pend_k
        clock[SK.CLK_END] = t_end
        M = q.size
        while t < t_end and len(pending) + 2 <= _PEND_CAP:
            left = max_imp - n_imp
            n_i = max(1, min(self.cap, left))
            n_p = 4 * n_i + 8
            li_t, li_v = np.empty(n_i), np.empty(n_i)
            ls_t, ls_y, ls_k = np.empty(n_p + _PEND_CAP), np.empty(n_p + _PEND_CAP), \
                np.empty(n_p + _PEND_CAP, dtype=np.int64)
            lp_t0, lp_t1, lp_lv = np.empty(n_p), np.empty(n_p), np.empty(n_p, dtype=np.int64)
            lp_q, lp_v, cnt = np.empty((n_p, M)), np.empty((n_p, M)), np.zeros(SK.CNT_SIZE, dtype=np.int64)
            logs = (li_t, li_v, ls_t, ls_y, ls_k, lp_t0, lp_t1, lp_lv, lp_q, lp_v, cnt)
            self.cap = min(2 * self.cap, 1 << 16)
            for i, (tp, kp) in enumerate(pending):
                pend_t[i], pend_k[i] = tp, kp
            ints[SK.INT_VALVE], ints[SK.INT_NPEND], ints[SK.INT_NIMP] = valve, len(pending), n_imp
            ints[SK.INT_MAXIMP], (ints[SK.INT_RIGID], ints[SK.INT_FAST]) = max_imp, self.flags
            clock[SK.CLK_T] = t
            st = SK.run_switched(self.views, self.B, self.dview, self.R, self.c, clock, (q, v), ints,
                                 (pend_t, pend_k), logs)
            ni, ns, npc = int(cnt[SK.CNT_IMP]), int(cnt[SK.CNT_SW]), int(cnt[SK.CNT_PC])
            imp_t.append(li_t[:ni])
            imp_v.append(li_v[:ni])
            sw_t.append(ls_t[:ns])
            sw_y.append(ls_y[:ns])
            sw_k.extend(map(_NAMES.__getitem__, ls_k[:ns].tolist()))
            if npc:
                blocks.append((lp_t0[:npc], lp_t1[:npc], lp_lv[:npc], lp_q[:npc], lp_v[:npc]))
            valve, n_imp = int(ints[SK.INT_VALVE]), int(ints[SK.INT_NIMP])
            pending = tuple((float(pend_t[i]), int(pend_k[i])) for i in range(int(ints[SK.INT_NPEND])))
            t = float(clock[SK.CLK_T])
            if st == SK.MAX_IMPACTS:
                status = KernelRun.MAX_IMPACTS
                break
            if st == SK.PYTHON:
                status = KernelRun.PYTHON
                break
            if st == SK.DONE:
                status = KernelRun.DONE
                break
        else:
            status = KernelRun.DONE if t >= t_end else KernelRun.PYTHON

        def cat(parts):
            return np.concatenate(parts) if parts else np.zeros(0)

        return KernelRun(status=status, state=DriveState((valve, pending), z), t=t, q=q, v=v, n_impacts=n_imp,
                         impact_times=cat(imp_t), impact_velocities=cat(imp_v), switch_times=cat(sw_t),
                         switch_gaps=cat(sw_y), switch_names=sw_k, pieces=tuple(blocks))
