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

__all__ = ["add_parser", "run", "KERNELS", "KERNELS_NUMBA", "kernel_count"]

#: the kernels each first call of :func:`_tasks` compiles into an empty cache, by its label, in order:
#: numba's compiles (one a kernel and signature) and the oil circuit's C callbacks, as ``impactbar
#: warmup`` prints them per line (``tests/cli/test_warmup.py`` compares the two); the documentation
#: quotes their sum, :func:`kernel_count` (``tests/docs/test_quoted_numbers.py``)
KERNELS = {
    "periodic orbits, flexible bar": 40,
    "periodic orbits, 40 modes and more": 12,
    "periodic orbits, wave law": 25,
    "simulation, rigid bar": 16,
    "simulation, flexible bar": 6,
    "simulation, wave law": 12,
    "position-switched drive": 11,
    "rod and rock": 78,
    "rod and rock orbits, exact blows": 16,
    "rod and rock orbits, lattice": 22,
    "rigid sweep chunks": 25,
    "oil circuit": 81,
    "oil circuit on rod and rock": 18,
    "piston optimiser": 11,
}

#: the numba release (major.minor) :data:`KERNELS` was counted with: numba's compile events count the
#: library's own overloads a kernel pulls in too, so another release may count a few more or fewer
KERNELS_NUMBA = "0.68"


def kernel_count() -> int:
    """The number of kernels ``impactbar warmup`` compiles into an empty cache, without compiling.

    Returns
    -------
    int
        The sum of :data:`KERNELS`: every kind of computation's kernels, the oil circuit's C callbacks
        among them (with pint installed; without it the warm-up leaves the oil circuit out). Source:
        ``docs/performance.md``, section "How to make it fast".
    """
    return sum(KERNELS.values())


def _tasks():
    """``(label, call)`` pairs, each a small first call of one kind of computation; the kernels take
    one signature each, so these compile what later calls of those kinds reach, whatever their
    parameters, loads and sizes (``tests/cli/test_warmup.py`` checks both laws, 0 to 48 modes, both
    loads, the drive, the rock's blows and orbits, exact and on the lattice, the chunks, and with
    pint the oil circuit, alone and on a rod and rock, and the piston's optimiser)."""
    import numpy as np

    from ..drives import PositionSwitchedDrive
    from ..laws.rodrock import BilinearRock, RodRock, RodSegment, single_blow
    from ..loads import CosineLoad, SquareWaveLoad
    from ..model import BarModel
    from ..orbits import find_orbit, periodic_orbits
    from ..orbits.rigid import rigid_cosine_orbits, rigid_square_orbits
    from ..simulation import InitialState, simulate

    cos, square = CosineLoad(0.6, 1.0), SquareWaveLoad(1.0, 1.2)
    rigid, flex = BarModel(5.0, 0.1, 0.5, 0), BarModel(5.0, 0.1, 0.5, 8)
    wave = flex.with_(impact="wave")
    piston, drive = BarModel(20.0, 0.0, 0.215, 0), PositionSwitchedDrive(stroke=1.0, ret=1.0, switch_out=1.0)
    n = 4  # (the compiled loop at any size; a sweep takes it from COMPILED_CLOSED_FORMS_FROM points)
    law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=2.5, k_u=25.0))
    short = RodRock(segments=[RodSegment(length=2.0, impedance=2.0)], rock=BilinearRock(k=20.0, k_u=200.0))
    on_rock = BarModel(10.0, 0.3, 0.0, 2, impact=short)
    on_grid = on_rock.with_(impact=RodRock(segments=short.segments, rock=short.rock, method="lattice"))

    def rock_orbit(model):  # two blows in two periods from a settled run (Newton on the blow's tangents)
        gentle = CosineLoad(0.3, 1.0)
        run = simulate(model, gentle, InitialState.rigid(-0.1, 0.0, 2), 60.0)
        return find_orbit(model, gentle, impacts=2, periods=2, guess=run)

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
        ("rod and rock orbits, exact blows", lambda: rock_orbit(on_rock)),
        ("rod and rock orbits, lattice", lambda: rock_orbit(on_grid)),
        ("rigid sweep chunks", lambda: (rigid_cosine_orbits(np.full(n, 0.1), np.full(n, 0.5), np.full(n, 0.6),
                                                            np.ones(n), 1),
                                        rigid_square_orbits(np.full(n, 0.1), np.full(n, 0.5), np.ones(n),
                                                            np.full(n, 1.2)))),
    ) + _physical_tasks()


def _physical_tasks():
    """The first calls of :mod:`impactbar.physical` that reach kernels of their own: the oil circuit
    (its flights' C callbacks and variational flights), the circuit on a rod and rock (the coupled
    blow), the piston's optimiser (the lattice blow's tangent); none where pint (the ``units``
    extra), which that layer needs, is missing."""
    try:
        import pint  # noqa: F401
    except ImportError:
        return ()
    import math

    from ..physical import CIRCUIT_PRESETS, CircuitDrifter, circuit_preset, optimize_piston
    from ..physical.rock import RodPiece

    # the preset on a drill string and rock (examples/circuit_drifter_rock.toml's, the stop left out)
    cfg = {k: v for k, v in CIRCUIT_PRESETS["circuit-drifter"].items() if k != "stop"}
    cfg.update(rod={"segments": [{"length": "0.4 m", "diameter": "45 mm"}, {"length": "1.2 m",
                                                                              "diameter": "32 mm"}]},
               bit={"mass": "1.5 kg"}, rock={"k": "470 kN/mm", "k_u": "4700 kN/mm", "feed": "2 kN",
                                              "cells_per_piston": 8})
    rod = [RodPiece(length_m=6.0, area_m2=1e-3, E_Pa=2.1e11, density_kg_m3=7850.0)]

    def circuit(drifter, flexible=False):
        from ..drives.circuit.flight import compile_callbacks
        from ..orbits import find_orbit

        out = drifter.orbit(), drifter.simulate(0.03)
        compile_callbacks()  # (the flights' C callbacks compile at first use: the Jacobian not taken too)
        if flexible:  # (a flexible piston's variational flights: Magnus' Phi, generated with the network)
            out += (find_orbit(drifter.model().with_(n_modes=1), drifter.drive()),)
        return out

    return (
        ("oil circuit", lambda: circuit(circuit_preset("circuit-drifter"), flexible=True)),
        ("oil circuit on rod and rock", lambda: circuit(CircuitDrifter.from_config(cfg))),
        ("piston optimiser", lambda: optimize_piston(rod, (1e8, 1e9), mass=2.4, length=0.3,
                                                     max_stress=math.inf, impact_velocity=10.0, segments=2,
                                                     max_evaluations=3)),
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
    kernels numba compiled (0 once they are cached); 1, with one line on stderr, where numba's JIT is
    disabled (nothing to compile)."""
    import sys

    from numba.core import event

    from .._shared.wrappers import jit_disabled

    if jit_disabled():
        print("impactbar warmup: error: NUMBA_DISABLE_JIT=1 turns numba's compiler off, so there is "
              "nothing to compile or cache: run it with NUMBA_DISABLE_JIT unset or 0", file=sys.stderr)
        return 1
    from ..dynamics.compiled import disable_tiers

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
        callbacks = 0
        for label, call in tasks:
            before, t0 = Count.n, time.process_time()
            call()
            dt = time.process_time() - t0
            total += dt
            new = _callbacks_compiled() - callbacks
            callbacks += new
            print(f"{label:<{w}}  {dt:6.1f} s CPU  {Count.n - before + new:3d} kernels compiled", flush=True)
    finally:
        event.unregister("numba:compile", counter)
    n = Count.n + callbacks
    print(f"\n{n} kernels compiled in {total:.1f} s of CPU time; cached for later processes")
    return 0


def _callbacks_compiled() -> int:
    """How many C callbacks (``numba.cfunc``, compiled or loaded from the cache when their module is
    imported, or a flight's at its first use, without numba's compile event) this process compiled: the
    oil circuit's own and those of the modules generated for a network or a circuit on a rod and rock
    (``impactbar_netgen_...``, ``impactbar_endgen_...``)."""
    import sys

    from numba.core.ccallback import CFunc

    modules = [m for name, m in list(sys.modules.items()) if name.startswith("impactbar") and m is not None]
    cvode = sys.modules.get("impactbar.drives.circuit._cvode")  # (a callback compiled at first use:
    late = () if cvode is None else cvode.Callback  # its CFunc, None before)
    found = [v.cfunc if isinstance(v, late) else v for m in modules for v in list(vars(m).values())]
    return sum(1 for v in found if isinstance(v, CFunc) and v.cache_hits == 0)
