"""``impactbar warmup``: compile every kernel once, so that later first calls load them from the cache.

numba compiles each kernel on its first call on a machine and keeps it in its cache (next to the
package, or in ``NUMBA_CACHE_DIR``); a first call therefore costs 10 to 25 s of CPU time on a 2-core
machine (``docs/performance.md``). This command makes those first calls on small problems, one per
kind of computation, so that an installation (a container image, a cluster's shared environment,
the workers of a sweep) pays the compile once, up front, and every later process finds the kernels
compiled. numba compiles on one core, so the kinds compile in worker processes at once, one a core
by default (``--jobs``), into the same cache.
"""

from __future__ import annotations

import time

__all__ = ["add_parser", "run", "KERNELS", "KERNELS_NUMBA", "kernel_count", "default_jobs", "LINE_COST",
           "LINE_AFTER"]

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
    "oil circuit on rod and rock": 47,
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
                                              "cells_per_piston": 8, "contact_events": "slots"})
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
                       "CPU time and the kernels compiled per kind, as each kind finishes.")
    p.add_argument("--jobs", type=_jobs, default=None, metavar="N",
                   help="worker processes that compile the kinds at once into the same cache, the "
                        "longest first (default: the cores this process may run on; 1: one kind after "
                        "another in this process)")
    p.set_defaults(func=run)


def _jobs(text: str) -> int:
    """``--jobs``: an integer of at least 1 (argparse's type, whose refusal is the command's one line)."""
    import argparse

    try:
        jobs = int(text)
    except ValueError:
        jobs = 0
    if jobs < 1:
        raise argparse.ArgumentTypeError(f"--jobs must be an integer of at least 1, got {text!r}")
    return jobs


def default_jobs() -> int:
    """The worker processes ``impactbar warmup`` starts without ``--jobs``: the cores this process may
    run on (its CPU affinity, else the machine's cores).

    Returns
    -------
    int
        At least 1. Source: ``docs/performance.md``, section "How to make it fast".
    """
    import os

    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # (no CPU affinity on macOS and Windows)
        return max(1, os.cpu_count() or 1)


def run(args) -> int:
    """Make the first calls of :func:`_tasks` and print, per call as it finishes, the CPU time and the
    kernels numba compiled (0 once they are cached): one after another in this process with ``--jobs
    1``, else in worker processes (:func:`_in_workers`); 1, with one line on stderr, where numba's JIT
    is disabled (nothing to compile)."""
    import sys

    from .._shared.wrappers import jit_disabled

    if jit_disabled():
        print("impactbar warmup: error: NUMBA_DISABLE_JIT=1 turns numba's compiler off, so there is "
              "nothing to compile or cache: run it with NUMBA_DISABLE_JIT unset or 0", file=sys.stderr)
        return 1
    labels = [label for label, _ in _tasks()]
    jobs = min(getattr(args, "jobs", None) or default_jobs(), len(labels))
    w = max(map(len, labels))
    if jobs > 1:
        return _in_workers(labels, jobs, w)
    _start(in_worker=False)
    try:
        done = [_shown(_line(label), w) for label in labels]
    finally:
        _stop()
    n = sum(len(kernels) for _, _, _, kernels in done)
    print(f"\n{n} kernels compiled in {sum(dt for _, dt, _, _ in done):.1f} s of CPU time; cached for later "
          f"processes")
    return 0


#: each line's CPU seconds in a warm-up into an empty cache, one line after another in one process
#: (``impactbar warmup --jobs 1``'s figures: a line's own kernels, those of the lines before it
#: loaded; numba 0.68, a 2-core AMD EPYC virtual machine at load about 4, 2026-11-30): with ``--jobs``
#: above 1, a free worker makes the longest line whose lines before (:data:`LINE_AFTER`) have
#: finished (a greedy schedule, :func:`_next_line`); a line missing here goes first
LINE_COST = {
    "periodic orbits, flexible bar": 11.0,
    "periodic orbits, 40 modes and more": 1.9,
    "periodic orbits, wave law": 6.5,
    "simulation, rigid bar": 5.7,
    "simulation, flexible bar": 4.8,
    "simulation, wave law": 7.7,
    "position-switched drive": 7.5,
    "rod and rock": 18.4,
    "rod and rock orbits, exact blows": 7.7,
    "rod and rock orbits, lattice": 3.3,
    "rigid sweep chunks": 5.2,
    "oil circuit": 20.9,
    "oil circuit on rod and rock": 18.6,
    "piston optimiser": 5.5,
}

#: the lines whose kernels a line mostly reuses: alone in a fresh process it compiles them again
#: (``benchmarks/probes/warmup_line_costs.py``: the rock's exact orbits 161 kernels in 46 s alone, 16
#: in 7.7 s after the lines before it; the optimiser 127 in 29.5 s, 11 in 5.5 s; the circuit on rock
#: 90, 18), so a parallel warm-up starts it once they have finished, and a worker waits rather than
#: compile them beside another
LINE_AFTER = {
    "periodic orbits, 40 modes and more": ("periodic orbits, flexible bar",),
    "periodic orbits, wave law": ("periodic orbits, flexible bar",),
    "simulation, rigid bar": ("periodic orbits, flexible bar",),
    "simulation, flexible bar": ("simulation, rigid bar",),
    "simulation, wave law": ("periodic orbits, wave law", "simulation, flexible bar"),
    "position-switched drive": ("simulation, rigid bar",),
    "rod and rock orbits, exact blows": ("rod and rock", "simulation, flexible bar"),
    "rod and rock orbits, lattice": ("rod and rock orbits, exact blows",),
    "oil circuit on rod and rock": ("oil circuit", "rod and rock"),
    "piston optimiser": ("rod and rock orbits, lattice",),
}

#: this process's state for the warm-up's calls (:func:`_start`): the calls by label, the keys of the
#: kernels compiled so far in order, the C callbacks compiled so far, numba's listener
_STATE: dict = {}


def _start(in_worker: bool = True, lock=None) -> None:
    """Prepare this process (a worker's initializer, or the command's own with ``--jobs 1``) to make
    the warm-up's calls: every kernel compiled, not run interpreted while a child compiles it, and
    each compile recorded by its function and argument types (a worker ignores Ctrl-C, which ends it
    through its parent's :meth:`~multiprocessing.pool.Pool.terminate`, as a terminal sends Ctrl-C to
    the parent's workers too); with ``lock``, the workers' lock, its saves to numba's cache one at a
    time (:func:`_saves_one_at_a_time`)."""
    if in_worker:
        import signal

        signal.signal(signal.SIGINT, signal.SIG_IGN)
    if lock is not None:
        _saves_one_at_a_time(lock)
    from numba.core import event

    from ..dynamics.compiled import disable_tiers

    disable_tiers()
    keys = []

    class Listener(event.Listener):
        def on_start(self, ev):
            pass

        def on_end(self, ev):  # (two dispatchers of one function differ in their options)
            disp = ev.data["dispatcher"]
            fn, options = disp.py_func, sorted((k, str(v)) for k, v in disp.targetoptions.items())
            keys.append(f"{fn.__module__}.{fn.__qualname__}{tuple(str(a) for a in ev.data['args'])}{options}")

    _STATE.update(tasks=dict(_tasks()), keys=keys, callbacks=set(), listener=Listener())
    event.register("numba:compile", _STATE["listener"])


def _saves_one_at_a_time(lock) -> None:
    """Make numba's cache in this process save an entry (read its function's index, add the entry,
    write the index and the entry's file) holding ``lock``, which the warm-up's workers share.

    numba writes each file whole (``numba/core/caching.py``: ``IndexDataCacheFile._open_for_write``
    writes a file named with a uuid4 and ``os.replace``-s it onto the name), so a reader sees an old or
    a new file, never half of one; but ``IndexDataCacheFile.save`` reads the index, adds the entry and
    writes it back without a lock: two processes saving two signatures of one function at once could
    each write an index without the other's entry, or number both entries' files alike and leave
    the index naming the other signature's code. The package's kernels take one signature each, all
    but a few (the exact blow's ``blk_bound`` and ``_put``, two: ``benchmarks/bench_first_call.py``
    lists them), so the workers save one at a time; a worker that has waited 60 s for the lock (one
    ended while holding it) saves without it."""
    from numba.core import caching

    save = caching.IndexDataCacheFile.save

    def locked(self, key, data):
        held = lock.acquire(timeout=60)
        try:
            return save(self, key, data)
        finally:
            if held:
                lock.release()

    caching.IndexDataCacheFile.save = locked


def _stop() -> None:
    from numba.core import event

    event.unregister("numba:compile", _STATE.pop("listener"))


def _line(label: str):
    """Make the first call ``label`` in this process (prepared by :func:`_start`): ``(label, its CPU
    seconds, this process's id, the kernels it compiled)``, each kernel by its function and argument
    types, a C callback by its module and name."""
    import os

    before, t0 = len(_STATE["keys"]), time.process_time()
    _STATE["tasks"][label]()
    dt = time.process_time() - t0
    new = [name for name in _callbacks_compiled() if name not in _STATE["callbacks"]]
    _STATE["callbacks"].update(new)
    return label, dt, os.getpid(), _STATE["keys"][before:] + new


def _shown(line, w: int):
    """Print one finished line of the warm-up (``label  T s CPU  N kernels compiled``); returns it."""
    label, dt, _, kernels = line
    print(f"{label:<{w}}  {dt:6.1f} s CPU  {len(kernels):3d} kernels compiled", flush=True)
    return line


def _in_workers(labels, jobs: int, w: int) -> int:
    """The warm-up's calls in ``jobs`` fresh worker processes (``spawn``: numba's compiler is not
    forked), handed out by :func:`_next_line`, each line printed as it finishes; after them the
    kernels compiled (one a kernel and argument types, however many workers compiled it: a worker
    compiles a callee that another has not yet cached, so the compiles add up to more), the wall
    time and the calls' CPU time. A Ctrl-C ends the workers and keeps what they cached.

    The workers write one cache, each save whole and one at a time (:func:`_saves_one_at_a_time`),
    so a worker ended in the middle leaves at most a temporary file. The C callbacks
    (``numba.cfunc(cache=True)``) use the same cache (``FunctionCache``); the modules generated for
    a network are written once under their content's hash (``os.replace``) and numba keys its cache
    by their content (a hash of the source file since numba 0.57), so two workers that generate one
    write the same file."""
    import multiprocessing
    import queue
    import signal
    import sys
    import threading

    print(f"{len(labels)} kinds of computation in {jobs} worker processes, each as it finishes:", flush=True)
    t0 = time.perf_counter()
    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    try:  # (the workers start ignoring Ctrl-C, which a terminal sends them too: terminate() ends them)
        spawn = multiprocessing.get_context("spawn")
        pool = spawn.Pool(jobs, initializer=_start, initargs=(True, spawn.Lock()))
    finally:
        if main:
            signal.signal(signal.SIGINT, previous)
    pending, done, results, free = list(labels), [], queue.SimpleQueue(), jobs

    def hand_out():  # (to each free worker the next line, while one is ready)
        nonlocal free
        while free and pending:
            label = _next_line(pending, [label for label, *_ in done], labels, wait=free < jobs)
            if label is None:
                return  # (a line running makes one ready)
            pending.remove(label)
            free -= 1
            pool.apply_async(_line, (label,), callback=results.put, error_callback=results.put)

    try:
        hand_out()
        while len(done) < len(labels):
            try:
                line = results.get(timeout=0.5)  # (a wait that a Ctrl-C interrupts)
            except queue.Empty:
                continue
            if isinstance(line, BaseException):
                raise line
            done.append(_shown(line, w))
            free += 1
            hand_out()
        pool.close()
    except KeyboardInterrupt:
        pool.terminate()
        print(f"impactbar warmup: {len(done)} of {len(labels)} kinds finished, their kernels cached",
              file=sys.stderr)
        raise
    except BaseException:
        pool.terminate()
        raise
    finally:
        pool.join()
    print("\n" + _summary(done, time.perf_counter() - t0, jobs))
    return 0


def _next_line(pending, finished, labels, wait: bool = True):
    """The line a free worker makes next: the longest (:data:`LINE_COST`) of those pending whose
    lines before (:data:`LINE_AFTER`, those among ``labels``) have finished, so that it loads their
    kernels from the cache rather than compile them again beside them; while none is, ``None`` (the
    worker waits for a running line to finish), or with ``wait`` false (no line runs) the longest
    pending."""
    ready = [label for label in pending if set(LINE_AFTER.get(label, ())) & set(labels) <= set(finished)]
    return max(ready or ([] if wait else pending), key=lambda label: LINE_COST.get(label, float("inf")),
               default=None)


def _summary(done, wall: float, jobs: int) -> str:
    """The parallel warm-up's last line: the kernels compiled, each once (a kernel as often as one
    worker compiled it: numba's own overloads are not cached, so a worker compiles one again for a
    kernel it compiles), the wall and CPU time, and how many compiles were a kernel another worker
    compiled too."""
    from collections import Counter

    by_worker = {}
    for _, _, pid, kernels in done:
        by_worker.setdefault(pid, Counter()).update(kernels)
    union = Counter()
    for counts in by_worker.values():
        union |= counts
    distinct = sum(union.values())
    total, cpu = sum(len(kernels) for _, _, _, kernels in done), sum(dt for _, dt, _, _ in done)
    return (f"{distinct} kernels compiled in {wall:.1f} s, {cpu:.1f} s of CPU time in {jobs} worker "
            f"processes ({total - distinct} of the {total} compiles a kernel that another worker compiled "
            f"too); cached for later processes")


def _callbacks_compiled() -> list:
    """The names (``module.name``) of the C callbacks (``numba.cfunc``, compiled or loaded from the
    cache when their module is imported, or a flight's at its first use, without numba's compile
    event) this process compiled: the oil circuit's own and those of the modules generated for a
    network or a circuit on a rod and rock
    (``impactbar_netgen_...``, ``impactbar_endgen_...``)."""
    import sys

    from numba.core.ccallback import CFunc

    modules = [m for name, m in list(sys.modules.items()) if name.startswith("impactbar") and m is not None]
    cvode = sys.modules.get("impactbar.drives.circuit._cvode")  # (a callback compiled at first use:
    late = () if cvode is None else cvode.Callback  # its CFunc, None before)
    found = [(f"{m.__name__}.{k}", v.cfunc if isinstance(v, late) else v) for m in modules
             for k, v in list(vars(m).items())]
    return [name for name, v in found if isinstance(v, CFunc) and v.cache_hits == 0]
