r"""Probe: how a flexible circuit orbit's Newton iterations end, over variations of the preset
``circuit-drifter`` (``impactbar.orbits._closing``).

For the preset and for each of ten one-parameter variations (pump flow x0.7 and x1.3, pre-charge
x0.8 and x1.2, switch-out x0.85 and x1.15, front volume x2, bulk modulus x0.5, valve coefficient
x0.6, switching time x2) with each number of modes of ``--modes``, ``find_orbit`` is run once with
``STEER_ERROR`` as given (``--steer-error``, default the library's) and the sizes of the steps after
the chord are recorded in order (``_closing.step_size``'s calls: the closing step, any chord steps
after it on the variational state's plain flights, then each check by the multipliers' flight), with
the flights by kind (``ShootingProblem._fly``: plain at the loose, the drive's and the state's
tolerance, steering, multipliers').

Per orbit: CPU time, the closing step, the steering Jacobian's error as that step meets it (the next
size over the closing step's), the number of multipliers' flights. The summary counts the orbits
whose check failed at least once (a multipliers' flight flown twice) and those that took a plain
period at the state's tolerance.

Run: ``python benchmarks/probes/closing_handover.py`` (2, 4, 8 and 16 modes) and
``... --steer-error 0`` (no chord steps after the closing step). Library behaviour is not changed
(the probe wraps functions for its counts and sets the one constant it is asked to).
"""

from __future__ import annotations

import argparse
import collections
import time

VARIATIONS = (("pump_flow", 0.7), ("pump_flow", 1.3), ("precharge", 0.8), ("precharge", 1.2),
              ("switch_out", 0.85), ("switch_out", 1.15), ("front_volume", 2.0), ("bulk_modulus", 0.5),
              ("valve_coefficient", 0.6), ("switching_time", 2.0))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", type=int, nargs="*", default=[2, 4, 8, 16])
    ap.add_argument("--steer-error", type=float, default=None)
    args = ap.parse_args(argv)

    from impactbar import find_orbit
    from impactbar.orbits import _closing as C
    from impactbar.orbits import shooting as S
    from impactbar.physical import circuit_preset

    d = circuit_preset("circuit-drifter")
    drive0, model = d.drive(), d.model()
    find_orbit(model.with_(n_modes=2), drive0)  # (compiled, warm)
    if args.steer_error is not None:
        C.STEER_ERROR = args.steer_error
    sizes, flights = [], collections.Counter()
    step_size, fly = C.step_size, S.ShootingProblem._fly

    def sized(step, X, positive, states=None):
        sizes.append(step_size(step, X, positive, states))
        return sizes[-1]

    def counted(self, tau, mode, y, keep, variational, settings):
        if self.M > 1:
            s = settings or self.settings
            flights[f"{variational} {s.rtol:g}"] += 1
        return fly(self, tau, mode, y, keep, variational, settings)

    C.step_size, S.ShootingProblem._fly = sized, counted
    twice = stepped = total = 0
    print(f"STEER_ERROR = {C.STEER_ERROR:g}")
    print(f"{'case':26s} {'modes':>5s} {'CPU s':>7s} {'closing':>9s} {'error':>9s} {'checks':>6s}  flights")
    for name, factor in (("preset", 1.0),) + VARIATIONS:
        drive = drive0 if name == "preset" else drive0.with_(**{name: drive0.value(name) * factor})
        for n in args.modes:
            sizes.clear()
            flights.clear()
            t = time.process_time()
            find_orbit(model.with_(n_modes=n), drive)
            cpu = time.process_time() - t
            checks = flights["True 1e-10"]
            fine = sum(v for k, v in flights.items() if k.startswith("False") and k.endswith("1e-13"))
            twice += checks > 1
            stepped += fine > 0
            total += 1
            err = sizes[1] / sizes[0] if len(sizes) > 1 and sizes[0] > 0 else float("nan")
            print(f"{name + ' x' + format(factor, 'g'):26s} {n:5d} {cpu:7.3f} {sizes[0]:9.2e} {err:9.2e} "
                  f"{checks:6d}  {dict(flights)}")
    print(f"{total} orbits: {twice} flew the multipliers' flight twice, {stepped} took a plain period at "
          "the state's tolerance")


if __name__ == "__main__":
    main()
