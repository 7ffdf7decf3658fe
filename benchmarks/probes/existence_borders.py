r"""Probe: which of the orbit's border margins ends the one-impact orbit at the documented problem's
no-orbit designs (docs/optimising_a_drifter.md, ``tests/physical/drifter_optimum.py``), as the
whole-drifter search's border model (:mod:`~impactbar.physical.optimize_border`) would need its
existence constraint to locate them?

Along lines through the no-orbit designs, each orbit continued from the one before (as the search
continues its designs), it prints at each design the margins the orbit reports for its borders: the
largest Floquet multiplier's modulus (the existence margin is ``1 - |mu|max``), the impact velocity
(0 at a grazing impact), the gap's rate at the valve's switch (``switch_velocity``, 0 where the switch
surface is grazed), the circuit's pressure borders (``border_margins_Pa``: ``relief``, the relief
setting less the greatest supply pressure; ``accumulator``, the least supply pressure less the
pre-charge) and the extra parts' levels and stops where there are any (none on this example), and
whether a fresh ``orbit()`` finds the orbit there. On the line where the relief margin falls to 0
before fresh orbits end, its first-order extrapolation (central differences of fresh orbits, step
1e-4 mm) from two designs, against where fresh orbits end (bisected to 1e-5 mm).

Lines (the step setting and the window's end of ``drifter_optimum.window_end``, where these designs
were found): ``collar``, ``WINDOW_OPTIMUM`` with its collar times 1 to 1.01 and from 1.03 down to
1.012 (the band ``collar`` names: no one-impact orbit from about 1.0095 to 1.0125); ``front rod``,
``BUZZING`` (the twentieth restarted search's design) with its front rod from 46.90 mm to 46.99 mm
(BUZZING's own 46.99465 mm: no orbit by a fresh ``orbit()``); ``collar at BUZZING``, BUZZING's collar
from 47.3 mm down to its own 47 mm.

Run: ``python benchmarks/probes/existence_borders.py`` (some minutes). Measured on s20-polishborder,
2026-11-30 (benchmarks/HISTORY.md, "Which border ends the one-impact orbit").
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests" / "physical"))
from drifter_optimum import BUZZING, EXAMPLE, WINDOW_OPTIMUM, window_end  # noqa: E402

from impactbar.physical import build, read_config, with_values  # noqa: E402


def _orbit(cfg, folder, changes, guess=None):
    try:
        return build(with_values(cfg, changes), folder).orbit(guess)
    except ValueError:
        return None


def _margins(point) -> str:
    o = point.orbit
    parts = {k: round(float(v) / 1e6, 5) for k, v in point.border_margins_Pa.items()}
    surfaces = {k: v for k, v in o.drive.border_tests(point._pieces, surfaces=True).items() if k not in parts}
    return (f"|mu|max {float(np.abs(o.multipliers).max()):.6g}, impact velocity "
            f"{float(o.impact_velocity):.6g} m/s, switch velocity {float(o.switch_velocity):.6g}, "
            f"pressure borders (MPa) {parts}"
            + (f", levels and stops {surfaces}" if surfaces else ""))


def _line(cfg, folder, name, designs):
    print(f"-- {name}")
    guess = None
    for label, changes in designs:
        point = _orbit(cfg, folder, changes, guess)
        found = _orbit(cfg, folder, changes) is not None
        fresh = "fresh orbit() finds it" if found else "fresh orbit(): none"
        print(f"{label}: " + ("no one-impact orbit (continued)" if point is None else _margins(point))
              + f"; {fresh}", flush=True)
        guess = point or guess


def _relief_extrapolation(cfg, folder, key, ok_mm, bad_mm, h=1e-4):
    def at(x, guess=None):
        return _orbit(cfg, folder, dict(BUZZING, **{key: f"{x!r} mm"}), guess)

    m0 = at(ok_mm).border_margins_Pa["relief"]
    slope = (at(ok_mm + h).border_margins_Pa["relief"] - at(ok_mm - h).border_margins_Pa["relief"]) / (2 * h)
    zero = ok_mm - m0 / slope
    a, b = ok_mm, bad_mm
    while b - a > 1e-5:
        c = 0.5 * (a + b)
        a, b = (a, c) if at(c) is None else (c, b)
    print(f"{key} from {ok_mm} mm: relief margin {m0 / 1e6:.5f} MPa, {slope / 1e6:.4f} MPa/mm, its zero "
          f"extrapolated at {zero:.5f} mm; fresh orbits end in [{a:.5f}, {b:.5f}] mm: "
          f"{(zero - 0.5 * (a + b)) / (bad_mm - ok_mm):+.4f} of the step to {bad_mm} mm", flush=True)


def main() -> None:
    mp = pytest.MonkeyPatch()
    window_end(mp)
    cfg, folder = read_config(EXAMPLE)
    collar = 0.04721879723846864

    def at_collar(f):
        return f"collar x {f:g}", dict(WINDOW_OPTIMUM, **{"piston.collar_diameter": f"{collar * f!r} m"})

    _line(cfg, folder, "collar, up", [at_collar(f) for f in (1.0, 1.003, 1.006, 1.008, 1.009, 1.0093, 1.0095,
                                                              1.01)])
    _line(cfg, folder, "collar, down", [at_collar(f) for f in (1.03, 1.013, 1.0125, 1.012)])
    rod = "piston.front_rod_diameter"
    _line(cfg, folder, "front rod", [(f"front rod {x:.3f} mm", dict(BUZZING, **{rod: f"{x!r} mm"}))
                                     for x in (round(46.90 + 0.005 * i, 3) for i in range(19))])
    _relief_extrapolation(cfg, folder, rod, 46.90, 46.95)
    _relief_extrapolation(cfg, folder, rod, 46.85, 46.99465)
    _line(cfg, folder, "collar at BUZZING", [(f"collar {c} mm", dict(BUZZING, **{"piston.collar_diameter":
                                                                                 f"{c!r} mm"}))
                                             for c in (47.3, 47.2, 47.15, 47.1, 47.05, 47.0)])
    mp.undo()


if __name__ == "__main__":
    main()
