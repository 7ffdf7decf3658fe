"""A drifter on a drill string and rock: the SI figures of its blow, the drilling
rate, and the command line."""

import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

import impactbar
from impactbar import InitialState, simulate
from impactbar.physical import Drifter

EXAMPLE = Path(__file__).parents[2] / "examples" / "drifter_rock.toml"


def load_config(path):
    with open(path, "rb") as f:
        return tomllib.load(f)


@pytest.fixture(scope="module")
def drifter():
    return Drifter.from_config(load_config(EXAMPLE))


def test_drilling_rate_is_penetration_times_the_simulated_blow_frequency(drifter):
    """The orbit's figures against a simulation of the same drifter (independent time integration):
    the blow frequency from the simulated impacts, the penetration from the blow of the simulated
    arrival (rigid piston: the arrival state is (0, v))."""
    o = drifter.orbit()
    r = o.rock()
    model, drive = drifter.model(), drifter.drive()
    tr = simulate(model, drive, InitialState.rigid(-0.05, 0.0, 0), 60 * o.orbit.period)
    ti = np.asarray(tr.impact_times)
    f_hz = drifter.omega_rad_s / float(ti[-1] - ti[-2])
    assert o.blow_frequency_Hz == pytest.approx(f_hz, rel=1e-12)
    from impactbar.loads import FourierLoad

    blow = model.law.blow(model, FourierLoad(1.0, []), 0.0, np.array([0.0, tr.impact_velocities[-1]]))
    pen_m = float(blow.permanent_penetration) * drifter.bar.length_m
    assert r["penetration_mm"] == pytest.approx(pen_m * 1e3, rel=1e-9)
    assert r["drilling_rate_m_min"] == pytest.approx(pen_m * f_hz * 60.0, rel=1e-9)
    assert 0.0 < r["efficiency"] <= r["efficiency_with_rebound"] <= 1.0
    assert r["work_on_rock_J"] < o.impact_energy_J  # the stroke force does little work in the blow
    assert o.stable and model.impact == "rodrock"


def test_drifter_rock_config_needs_rock_for_rod_and_refuses_unknown_sections():
    cfg = load_config(EXAMPLE)
    del cfg["rock"]
    with pytest.raises(ValueError, match=r"\[rod\] and \[bit\] need a \[rock\]"):
        Drifter.from_config(cfg)
    cfg = load_config(EXAMPLE)
    cfg["drill"] = {}
    with pytest.raises(ValueError, match=r"unknown section \[drill\]"):
        Drifter.from_config(cfg)


def test_cli_orbits_prints_the_blow_on_rock():
    env = dict(os.environ, PYTHONPATH=str(Path(impactbar.__file__).resolve().parents[1]), MPLBACKEND="Agg")
    res = subprocess.run([sys.executable, "-m", "impactbar.cli", "orbits", str(EXAMPLE)], env=env,
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    assert "drilling rate" in res.stdout and "work on rock" in res.stdout
    assert "drill string of 2 segment(s)" in res.stdout


def test_simulated_drilling_figures_equal_the_orbits(drifter):
    """``Drifter.simulate`` reads the blows' records of the run (an independent time integration)
    and, once settled, gives the orbit's work on rock, penetration and drilling rate."""
    o = drifter.orbit()
    _, s = drifter.simulate(40 * o.period_s)
    r = o.rock()
    for key in ("work_on_rock_J", "penetration_mm", "efficiency", "drilling_rate_m_min"):
        assert s[key] == pytest.approx(r[key], rel=1e-6), key


def test_cli_simulate_draws_a_blow_s_force_history_and_the_stress_along_the_rod(tmp_path):
    """``impactbar simulate examples/drifter_rock.toml``: the hammer's figures, and on the drill
    string the last blow's forces at the boundaries and on the rock, and the stress along the rod
    (whose largest compression at the shank is the shank force's peak over its area)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from impactbar.cli import main
    from impactbar.plotting.physical import plot_rod_stress

    assert main(["simulate", str(EXAMPLE), "--out", str(tmp_path / "s"), "--periods", "8"]) == 0
    names = {p.name for p in (tmp_path / "s").glob("*.png")}
    assert names == {"motion.png", "blows.png", "forces.png", "stress.png"}
    d = Drifter.from_config(tomllib.loads(EXAMPLE.read_text()))
    run, _ = d.simulate(8 * d.orbit().period_s)
    rec = [r for i in range(len(run.pieces)) for r in getattr(run.pieces[i], "impacts", ())][-1]
    ax = plot_rod_stress(d, rec)
    shank = float(np.max(rec.blow.junction_forces[:, 0])) * d.scales.force_N
    assert ax.lines[0].get_ydata()[0] == pytest.approx(shank / d.drill.segments[0].area_m2 / 1e6, rel=1e-12)
    plt.close(ax.figure)


def test_a_stepped_drifter_on_rock():
    """A drifter's stepped piston on a drill string (theory §4d, §12): cut into two segments of one
    section it gives the uniform piston's operating point on the rock (1e-9); a heavy head
    (``examples/stepped_drifter_rock.toml``: a 56 mm head and a 38.3 mm tail, the same mass) gives
    another one, its blow longer and its peak higher, as the example says."""
    cfg = load_config(EXAMPLE)
    base = Drifter.from_config(cfg).orbit()
    half = f"{448.54236 / 2!r} mm"
    cfg["bar"]["length"], cfg["bar"]["diameter"] = [half, half], ["45 mm", "45 mm"]
    even = Drifter.from_config(cfg).orbit()
    for name in ("blow_frequency_Hz", "impact_velocity_m_s"):
        assert getattr(even, name) == pytest.approx(getattr(base, name), rel=1e-9)
    for name in ("work_on_rock_J", "penetration_mm"):
        assert even.rock()[name] == pytest.approx(base.rock()[name], rel=1e-9)
    stepped = Drifter.from_config(load_config(EXAMPLE.with_name("stepped_drifter_rock.toml")))
    heavy = stepped.orbit()
    w0 = base.rock()["work_on_rock_J"]
    assert heavy.stable and abs(heavy.rock()["work_on_rock_J"] - w0) > 1e-3 * w0
    # the example's words: the stepped piston's blow lasts longer and peaks higher (exact blows at 1)
    waves = []
    for d in (Drifter.from_config(load_config(EXAMPLE)), stepped):
        m = d.model()
        b = impactbar.single_blow(m.with_(impact=m.law.with_parameter("feed", 0.0)), 1.0)
        t = np.linspace(0.0, 4.0 / m.s, 4001)
        f = b.shank_force(t)
        waves.append((float(np.max(f)), float(np.ptp(t[f > 1e-9 * np.max(f)]))))
    assert waves[1][0] > 1.1 * waves[0][0] and waves[1][1] > 1.2 * waves[0][1]
