"""Benchmark of the rod-rock law.

1. One blow on a 3-segment rod with 400 cells (:func:`impactbar.single_blow`, the rod-and-rock law),
   against elwaspatid's Bacon-method characteristics on the same rod, grid and number of steps (its
   far end anechoic, no rock), the baseline, in the same run, and against the numpy loop (the
   reference of ``"rock.blow"``). Goal: <= 1 ms.
2. A periodic orbit under the rod-rock law (``find_orbit``, 2 blows in 2 load periods, 4 modes, a rod
   of impedance 2 on a soft rock, from a simulation), its blows exact (the default)
   and on the lattice (``method="lattice"``, the baseline), against the wave law's orbit of the same
   bar with the same rod's restitution ``R = 1/3`` (``find_orbit``, 2 impacts in 2 periods, from a
   simulation), the simulations outside the timing. Goals: <= 10x the wave law's; with exact blows, a rock
   orbit with 4 modes <= 20 ms.
3. A stepped piston under the rod-rock law: one contact step, ``simulate`` over 100 time
   units and ``find_orbit`` (1 blow a period, from a settled simulation) of a heavy-headed piston
   (sections 1 and 2, ``SteppedPiston([0.6, 0.4], [1, 2])``), against the uniform piston of the same
   mass, exact and on the lattice, in the same run.

Run: ``python benchmarks/bench_rock.py [--quick]``. Prints a table; nothing is asserted.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import math

import numpy as np
from _timing import median_time  # this folder's shared timer

import impactbar as ib
from impactbar.dynamics.implementations import use_reference


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)
    repeat = 3 if args.quick else 11
    # the piston (40 cells) and three segments (40 + 20 + 300 cells): 400 cells
    lengths, impedances = [1.0, 0.5, 7.5], [2.25, 1.6, 1.0]
    segments = [ib.RodSegment(length=x, impedance=z) for x, z in zip(lengths, impedances, strict=True)]
    law = ib.RodRock(segments=segments, rock=ib.BilinearRock(k=1.0, k_u=4.0), bit_mass=0.0)
    model = ib.BarModel(s=1.0, d=0.0, R=0.0, n_modes=0, impact=law)
    steps = 800  # twice the rod's and the piston's travel: the reflection from the bit back to the piston
    dt = 1.0 / 40
    blow = ib.single_blow(model, 1.0, cells_per_piston=40, t_max=steps * dt * (1 - 1e-12))
    assert blow.piston_cells + sum(blow.segment_cells) == 400
    t_rock = median_time(lambda: ib.single_blow(model, 1.0, cells_per_piston=40,
                                                t_max=steps * dt * (1 - 1e-12)), repeat)
    rows = [("single_blow (rod and rock)", t_rock, len(blow.shank_forces))]
    with use_reference("rock.blow"):
        t_ref = median_time(lambda: ib.single_blow(model, 1.0, cells_per_piston=40,
                                                   t_max=steps * dt * (1 - 1e-12)), repeat)
    rows.append(("single_blow, numpy loop (reference)", t_ref, len(blow.shank_forces)))
    try:
        import elwaspatid.elwaspatid as E
    except ImportError:
        E = None
    if E is not None:
        d = [math.sqrt(4 * z / math.pi) for z in [1.0] + impedances]

        def elw():
            with contextlib.redirect_stdout(io.StringIO()):
                bar = E.BarSet([1.0] * 4, [1.0] * 4, [1.0] + lengths, d, nmin=20, right="infinite")
                E.WP2(bar, incw=None, nstep=steps, left="free", right="infinite", Vinit=1.0, contactLoss=None)

        rows.append(("elwaspatid WP2 (same grid, no rock)", median_time(elw, repeat), steps))
    print(f"{'solver':40s} {'time (ms)':>10s} {'steps':>6s}")
    for name, t, n in rows:
        print(f"{name:40s} {1e3 * t:10.3f} {n:6d}")
    print(f"energy error {blow.energy_error:.2e}, efficiency {blow.efficiency:.4f}")
    orbits(repeat)
    stepped(repeat)


def stepped(repeat):
    """Section 3: a stepped piston under the rod-rock law against the uniform piston, each with the
    simulator's exact blows (the default) and on the lattice (``method="lattice"``)."""
    from impactbar.laws.rodrock.step import rock_contact

    head = ib.SteppedPiston([0.6, 0.4], [1.0, 2.0])
    load = ib.CosineLoad(0.3, 1.0)
    start = ib.InitialState.rigid(-0.1, 0.0, n_modes=4)
    print(f"\n{'N = 4, one blow a period':36s} {'contact ms':>10s} {'simulate, t<=100, ms':>20s} "
          f"{'find_orbit ms':>14s} {'blows/100':>9s}")
    for method in ("exact", "lattice"):
        law = ib.RodRock(segments=[ib.RodSegment(length=2.0, impedance=2.0)],
                         rock=ib.BilinearRock(k=20.0, k_u=200.0), method=method)
        for name, piston in (("uniform piston", None), ("stepped piston (2 segments)", head)):
            model = ib.BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=law, piston=piston)
            guess = ib.simulate(model, load, start, 600.0)
            b = guess.impacts[-1]
            t_c = median_time(lambda m=model, b=b: rock_contact(m, load, b.t0, b.q_before, b.v_before),
                              repeat)
            t_s = median_time(lambda m=model: ib.simulate(m, load, start, 100.0), repeat)
            t_o = median_time(lambda m=model, g=guess: ib.find_orbit(m, load, 1, 1, guess=g), repeat)
            n = ib.simulate(model, load, start, 100.0).n_impacts
            print(f"{name + ', ' + method:36s} {1e3 * t_c:10.3f} {1e3 * t_s:20.1f} {1e3 * t_o:14.1f} {n:9d}")


def orbits(repeat):
    """Section 2: a periodic orbit under the rod-rock law, its blows exact (the default) and on the
    lattice (the baseline), against the wave law's."""
    rock, lattice = (ib.BarModel(s=10.0, d=0.3, R=0.0, n_modes=4, impact=ib.RodRock(
        segments=[ib.RodSegment(length=2.0, impedance=2.0)], rock=ib.BilinearRock(k=20.0, k_u=200.0),
        method=method)) for method in ("auto", "lattice"))
    wave = ib.BarModel(s=10.0, d=0.3, R=1.0 / 3.0, n_modes=4, impact="wave")
    load = ib.CosineLoad(0.3, 1.0)
    start = ib.InitialState.rigid(-0.1, 0.0, n_modes=4)
    guesses = {m: ib.simulate(m, load, start, 200.0) for m in (rock, lattice, wave)}
    times = {m: median_time(lambda m=m: ib.find_orbit(m, load, 2, 2, guess=guesses[m]), repeat)
             for m in (rock, lattice, wave)}
    with _before():
        t_before = median_time(lambda: ib.find_orbit(rock, load, 2, 2, guess=guesses[rock]), repeat)
    o = ib.find_orbit(rock, load, 2, 2, guess=guesses[rock])
    o_lat = ib.find_orbit(lattice, load, 2, 2, guess=guesses[lattice])
    print(f"\n{'periodic orbit (2 in 2, N = 4)':40s} {'time (ms)':>10s}")
    print(f"{'find_orbit, rod-rock law, exact blows':40s} {1e3 * times[rock]:10.1f}")
    print(f"{'  before (lattice, chord, differences)':40s} {1e3 * t_before:10.1f}")
    print(f"{'find_orbit, rod-rock law, lattice':40s} {1e3 * times[lattice]:10.1f}")
    print(f"{'find_orbit, wave law':40s} {1e3 * times[wave]:10.1f}")
    # the map with its Jacobians at the orbit's first impact: tangent runs against differences
    from impactbar.laws.rodrock.step import blow_map, fd_impact_map

    y = np.concatenate((o.states_before_impact[0][:5], o.states_before_impact[0][5:]))
    t0 = float(o.impact_times[0])
    t_tan = median_time(lambda: rock.law.impact_map(rock, load, t0, y), repeat)
    t_fd = median_time(lambda: fd_impact_map(blow_map(rock, load, t0), y, t0), repeat)
    t_one = median_time(lambda: rock.law.impact_state(rock, load, t0, y), repeat)
    print(f"{'impact map with Jacobians, tangent runs':40s} {1e3 * t_tan:10.2f}")
    print(f"{'  central differences (4 N + 6 blows)':40s} {1e3 * t_fd:10.2f}")
    print(f"{'  the map alone (one blow)':40s} {1e3 * t_one:10.2f}")
    print("the lattice's orbit: impact velocities "
          f"{np.max(np.abs(o.impact_velocities - o_lat.impact_velocities)):.1e} off the exact blows'")
    print(f"ratio {times[rock] / times[wave]:.1f} to the wave law; the orbit: stable {o.stable}, work on "
          f"rock per blow {[round(c.work_on_rock, 4) for c in o.contacts]}")


@contextlib.contextmanager
def _before():
    """find_orbit as it was before the exact Jacobian: Newton on the lattice first, the chord
    method, the multipliers' Jacobian by central differences of the exact blows."""
    from impactbar.laws.rodrock import exactjac
    from impactbar.orbits import find

    direct, exact = find.DIRECT_ITERATIONS, exactjac.exact_impact_map
    find.DIRECT_ITERATIONS = 0
    exactjac.exact_impact_map = lambda *args: None
    try:
        yield
    finally:
        find.DIRECT_ITERATIONS, exactjac.exact_impact_map = direct, exact


if __name__ == "__main__":
    main()
