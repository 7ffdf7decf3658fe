"""``impactbar warmup``: compile every kernel once, so that later first calls load them from the cache.

numba compiles each kernel on its first call on a machine and keeps it in its cache (next to the
package, or in ``NUMBA_CACHE_DIR``); a first call therefore costs 10 to 25 s of CPU time on a 2-core
machine (``docs/performance.md``). This command makes those first calls on small problems, one per
kind of computation, so that an installation (a container image, a cluster's shared environment,
the workers of a sweep) pays the compile once, up front, and every later process finds the kernels
compiled.
"""

from __future__ import annotations

import time

__all__ = ["add_parser", "run"]


def _tasks():
    """``(label, call)`` pairs, each a small first call of one kind of computation; the kernels take
    one signature each, so these compile what later calls of those kinds reach, whatever their
    parameters, loads and sizes (``tests/cli/test_warmup.py`` checks both laws, 0 to 48 modes, both
    loads, the drive, the rock and the chunks)."""
    import numpy as np

    from .. import (
        BarModel,
        BilinearRock,
        CosineLoad,
        InitialState,
        PositionSwitchedDrive,
        RodRock,
        RodSegment,
        SquareWaveLoad,
        find_orbit,
        periodic_orbits,
        simulate,
        single_blow,
    )
    from ..orbits.rigid import rigid_cosine_orbits, rigid_square_orbits

    cos, square = CosineLoad(0.6, 1.0), SquareWaveLoad(1.0, 1.2)
    rigid, flex = BarModel(5.0, 0.1, 0.5, 0), BarModel(5.0, 0.1, 0.5, 8)
    wave = flex.with_(impact="wave")
    piston, drive = BarModel(20.0, 0.0, 0.215, 0), PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    n = 4  # (the compiled loop at any size; a sweep takes it from COMPILED_CLOSED_FORMS_FROM points)
    law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=2.5, k_u=25.0))
    return (
        ("periodic orbits, flexible bar", lambda: periodic_orbits(flex, cos)),
        ("periodic orbits, 40 modes and more", lambda: periodic_orbits(flex.with_(n_modes=40), cos)),
        ("periodic orbits, wave law", lambda: (periodic_orbits(wave, cos), periodic_orbits(wave, square))),
        ("simulation, rigid bar", lambda: simulate(rigid, cos, InitialState.rigid(-0.2, 0.0), 30.0)),
        ("simulation, flexible bar", lambda: simulate(flex, cos, InitialState.rigid(-0.2, 0.0, 8), 30.0)),
        ("simulation, wave law", lambda: simulate(wave, cos, InitialState.rigid(-0.2, 0.0, 8), 30.0)),
        ("position-switched drive", lambda: (find_orbit(piston, drive),
                                             simulate(piston, drive, InitialState.rigid(-0.5, 0.0), 50.0))),
        ("rod and rock", lambda: single_blow(BarModel(2.0, 0.0, 0.0, 0, impact=law), 1.0, t_max=39.0)),
        ("rigid sweep chunks", lambda: (rigid_cosine_orbits(np.full(n, 0.1), np.full(n, 0.5), np.full(n, 0.6),
                                                            np.ones(n), 1),
                                        rigid_square_orbits(np.full(n, 0.1), np.full(n, 0.5), np.ones(n),
                                                            np.full(n, 1.2)))),
    )


def add_parser(sub) -> None:
    p = sub.add_parser("warmup", help="compile every kernel once (a first call then takes milliseconds)",
                       description="Make one small first call of each kind of computation, so that numba "
                       "compiles its kernels now and keeps them in its cache (next to the package, or in "
                       "NUMBA_CACHE_DIR): later processes on this machine compile nothing. Prints the "
                       "CPU time and the kernels compiled per kind.")
    p.set_defaults(func=run)


def run(args) -> int:
    """Make the first calls of :func:`_tasks` and print, per call, the CPU time and the number of
    kernels numba compiled (0 once they are cached)."""
    from numba.core import event

    from ..dynamics.kernels import disable_tiers

    disable_tiers()  # every kernel compiled here, not run interpreted while a child compiles it

    class Count(event.Listener):
        n = 0

        def on_start(self, ev):
            pass

        def on_end(self, ev):
            Count.n += 1

    counter = Count()
    event.register("numba:compile", counter)
    try:
        total = 0.0
        tasks = _tasks()
        w = max(len(label) for label, _ in tasks)
        for label, call in tasks:
            before, t0 = Count.n, time.process_time()
            call()
            dt = time.process_time() - t0
            total += dt
            print(f"{label:<{w}}  {dt:6.1f} s CPU  {Count.n - before:3d} kernels compiled", flush=True)
    finally:
        event.unregister("numba:compile", counter)
    print(f"\n{Count.n} kernels compiled in {total:.1f} s of CPU time; cached for later processes")
    return 0
