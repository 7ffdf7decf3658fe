"""The Section 5 experiments: classification of the long-run motion, the runner, plots and CLI."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, FourierLoad, InitialState, SquareWaveLoad, simulate
from impactbar.cli import main
from impactbar.plotting import plot_experiment
from impactbar.simulation.experiments import (
    classify,
    load_period,
    pneumatic_setup,
    random_start,
    run_experiment,
)

TWO_PI = 2 * math.pi


def fake_run(times, t_end, load=None, contacts=(), in_contact=False):
    """Just what ``classify`` reads from a Trajectory."""
    return SimpleNamespace(load=load or CosineLoad(0.8, 1.0), t0=0.0, t_end=t_end,
                           impact_times=np.asarray(times, dtype=float),
                           contact_intervals=np.asarray(contacts, dtype=float).reshape(-1, 2),
                           in_contact_at_end=in_contact)


def test_classify_patterns():
    n = np.arange(40)
    assert classify(fake_run(TWO_PI * (n + 0.3), TWO_PI * 40)).kind == "k=1"
    c = classify(fake_run(TWO_PI * (3 * n + 0.3), TWO_PI * 120))
    assert (c.kind, c.k) == ("k=3", 3)
    two = np.sort(np.concatenate((TWO_PI * (n + 0.1), TWO_PI * (n + 0.55))))
    c = classify(fake_run(two, TWO_PI * 40))
    assert (c.kind, c.k, c.impacts_per_cycle) == ("periodic, several impacts", 1, 2)
    jitter = TWO_PI * (n + 0.3 + 0.05 * np.sin(n * 1.7))
    assert classify(fake_run(jitter, TWO_PI * 40)).kind == "not periodic"
    assert classify(fake_run([1.0], 100.0, contacts=[[2.0, 100.0]],
                             in_contact=True)).kind == "permanent contact"
    sticks = [[TWO_PI * i + 1, TWO_PI * i + 2] for i in range(40)]
    assert classify(fake_run(TWO_PI * n, TWO_PI * 40, contacts=sticks)).kind == "stick-impact"
    # the load period sets the unit: a k = 2 cosine load has period pi
    c = classify(fake_run(TWO_PI * (n + 0.3), TWO_PI * 40, load=CosineLoad(0.8, 1.0, k=2)))
    assert (c.kind, c.k) == ("k=2", 2)
    with pytest.raises(ValueError, match="window"):
        classify(fake_run(n, 40.0), window=0.0)


def test_load_period():
    assert load_period(CosineLoad(0.5, 1.0, k=3)) == pytest.approx(TWO_PI / 3)
    assert load_period(FourierLoad(0.5, [0, 1.0, 0, 0.2])) == pytest.approx(math.pi)
    assert load_period(SquareWaveLoad(1.0, 1.5)) == TWO_PI


def test_classify_real_runs():
    model = BarModel(s=1.0, d=0.0, R=0.5, n_modes=0)
    # one-impact orbit from near its stable phase (theory §6)
    R, p0 = 0.5, 0.8
    phi = math.pi - math.asin(math.pi * p0 * (1 - R) / (1 + R))
    V = TWO_PI * p0 / (1 + R)
    tr = simulate(model, CosineLoad(p0, 1.0), InitialState([-1e-3], [-R * V]), phi + TWO_PI * 80,
                  t0=phi)
    assert classify(tr).kind == "k=1"
    # bouncing ball under a constant push: permanent contact
    tr = simulate(model, FourierLoad(1.0, []), InitialState.rigid(-0.5, 0.0), 100.0)
    assert classify(tr).kind == "permanent contact"
    # the load turns tensile once a period: stick, release, impact, stick ...
    tr = simulate(model, CosineLoad(0.8, 1.0), InitialState.rigid(-0.5, 0.0), TWO_PI * 40)
    assert classify(tr).kind == "stick-impact"


def test_random_start_is_off_the_stop_and_seeded():
    model, load = pneumatic_setup()
    a = random_start(model, load, np.random.default_rng(5))
    b = random_start(model, load, np.random.default_rng(5))
    assert a[0] == b[0]
    np.testing.assert_array_equal(a[1].modal_displacement, b[1].modal_displacement)
    for seed in range(20):
        t0, st = random_start(model, load, np.random.default_rng(seed))
        assert 0 <= t0 < TWO_PI
        assert model.end_weights @ st.modal_displacement < 0


def test_run_experiment_fractions_stats_and_plots(tmp_path):
    model = BarModel(s=1.0, d=0.0, R=0.8, n_modes=0)
    load = CosineLoad(1.2, 1.0)
    res = run_experiment(model, load, starts=12, periods=200, seed=3)
    again = run_experiment(model, load, starts=12, periods=200, seed=3, workers=1)
    assert [c.kind for c in res.classes] == [c.kind for c in again.classes]
    fr = res.fractions
    assert sum(fr.values()) == pytest.approx(1.0)
    # p0 > pk: the load always presses, so every run ends on the one-impact orbit or on the stop
    assert set(fr) <= {"k=1", "permanent contact"}
    assert fr.get("k=1", 0) > 0
    # a k = 1 run strikes once per load period, exactly, once settled
    assert res.interval_mean == pytest.approx(1.0, abs=1e-6)
    assert res.interval_std < 1e-4
    assert res.run_spread < 1e-4
    text = res.summary()
    assert "k=1" in text and "impact interval" in text
    files = plot_experiment(res, tmp_path)
    assert len(files) == 3 and all(f.stat().st_size > 1000 for f in files)


def test_cli_experiment(tmp_path, capsys):
    rc = main(["experiment", "pneumatic", "--starts", "4", "--periods", "40", "--modes", "2",
               "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 0
    assert "long-run motion" in out and "impact interval" in out
    assert (tmp_path / "impact_map.png").exists()
    rc = main(["experiment", "hydraulic", "--starts", "2", "--periods", "20", "--modes", "0",
               "--no-plots"])
    assert rc == 0
    assert main(["experiment", "pneumatic", "--starts", "0", "--no-plots"]) == 2
    assert "starts" in capsys.readouterr().err


@pytest.mark.slow
def test_batch_of_1000_rigid_runs_of_1000_impacts_from_two_threads():
    """A thousand rigid runs of a thousand impacts each, two threads sharing the compiled event loop
    (its speed: ``benchmarks/bench_simulate.py``): every run reaches its thousand impacts."""
    model = BarModel(s=1.0, d=0.0, R=0.8, n_modes=0)
    load = CosineLoad(1.2, 1.0)
    rng = np.random.default_rng(0)
    phi = math.pi - math.asin(math.pi * 1.2 * 0.2 / 1.8)
    V = TWO_PI * 1.2 / 1.8
    starts = [InitialState([-1e-3 * rng.uniform()], [-0.8 * V * rng.uniform(0.95, 1.05)])
              for _ in range(1000)]
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(2) as pool:
        runs = list(pool.map(lambda st: simulate(model, load, st, 1e6, t0=phi, max_impacts=1000),
                             starts))
    assert all(r.n_impacts == 1000 for r in runs)


def test_stick_impact_cycle_counts_one_main_impact_per_period():
    """Rigid bar, ``0.8 + cos t``, R = 0.5: each period one main impact, its chatter bounces and a
    contact; the bounces must not count as impacts of their own."""
    res = run_experiment(BarModel(s=1.0, d=0.0, R=0.5, n_modes=0), CosineLoad(0.8, 1.0),
                         starts=6, periods=60, seed=2)
    assert "stick-impact" in res.fractions
    assert res.interval_mean == pytest.approx(1.0, abs=1e-9)
    assert res.run_spread < 1e-9
