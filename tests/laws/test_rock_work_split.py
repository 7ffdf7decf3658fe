"""Work on rock split into what the rock keeps and what it stores: a blow window cut
while the bit still loads reports, in ``work_on_rock``, elastic energy that a longer window gives
back (0.262 at t_max = 5 against 0.155 for the whole blow below), so the work is also given as
``rock_dissipated`` (never decreasing with the window) and ``rock_stored_energy`` (``R^2/(2 k_u)`` of
the rock force left). The same on the simulator's blows and on the SI blow table."""

import numpy as np
import pytest

import impactbar as ib
from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow


def _model(k=1.0, k_u=2.0, length=3.0, n_modes=0, s=2.0, d=0.0, **rock):
    law = RodRock(segments=[RodSegment(length=length, impedance=1.0)],
                  rock=BilinearRock(k=k, k_u=k_u), **rock)
    return BarModel(s=s, d=d, R=0.0, n_modes=n_modes, impact=law)


def test_a_shorter_window_never_reports_more_dissipated_work():
    model = _model()
    whole = single_blow(model, 1.0)
    windows = [single_blow(model, 1.0, t_max=t) for t in (1.0, 2.0, 3.0, 4.0, 5.0, 6.0)]
    dissipated = [b.rock_dissipated for b in windows] + [whole.rock_dissipated]
    assert np.all(np.diff(dissipated) >= -1e-12)
    # the cut windows' work on rock overshoots the whole blow's: the rock's elastic energy
    assert max(b.work_on_rock for b in windows) > 1.5 * whole.work_on_rock
    for b in (*windows, whole):
        R = b.bit_forces[-1]
        assert b.rock_stored_energy == pytest.approx(max(R, 0.0) ** 2 / (2 * 2.0), rel=1e-14, abs=0)
        assert b.rock_dissipated == pytest.approx(b.work_on_rock - b.rock_stored_energy, rel=1e-14)
        assert 0.0 <= b.rock_dissipated <= b.work_on_rock
    assert whole.rock_stored_energy == 0.0  # the bit lifted off: nothing stored
    assert "rock_dissipated" in whole.to_dict() and "rock_stored_energy" in whole.to_dict()


@pytest.mark.parametrize("t_max", [2.5, 3.5, 5.0, None])
def test_an_elastic_rock_keeps_nothing(t_max):
    """Unloading along the loading line (``k_u = k``): whatever the window, the rock stores all the
    work it has taken and keeps none."""
    model = _model(k=1.0, k_u=1.0)
    b = single_blow(model, 1.0) if t_max is None else single_blow(model, 1.0, t_max=t_max)
    assert b.work_on_rock > 0.0 or t_max is None
    assert abs(b.rock_dissipated) <= 1e-12 * max(b.available_energy, 1.0)


def test_the_simulators_blows_report_both():
    """A run under the rod-rock law with a feed: each blow's record splits its work on rock, and the
    SI table carries both parts."""
    model = _model(k=20.0, k_u=200.0, length=1.5, n_modes=8, s=10.0, d=0.05, bit_mass=0.2, feed=0.3)
    tr = ib.simulate(model, ib.CosineLoad(0.5, 1.0), ib.InitialState.rigid(-0.1, 0.0, n_modes=8), 30.0)
    assert len(tr.impacts) >= 3
    for b in tr.impacts:
        R = b.blow.bit_forces[-1]
        assert b.rock_stored_energy == pytest.approx(max(R, 0.0) ** 2 / 400.0, rel=1e-14, abs=0)
        assert b.rock_dissipated == pytest.approx(b.work_on_rock - b.rock_stored_energy, rel=1e-14)
        assert b.rock_dissipated > 0.0


@pytest.mark.parametrize("t_max", [2.5, 5.0, None])
def test_the_exact_and_lattice_blows_split_the_work_alike(t_max):
    """The exact solver reports the work as the lattice does: the rock's dissipated work
    (the sum over its loadings) plus its elastic energy at the end; a fine lattice (first order,
    1024 cells) agrees to its refinement error, and the energy account closes."""
    model = _model()
    exact = single_blow(model, 1.0, t_max=t_max, method="exact")
    fine = single_blow(model, 1.0, t_max=exact.duration, method="lattice", cells_per_piston=1024)
    assert exact.rock_dissipated == pytest.approx(float(np.sum(exact.loadings[:, 4])), rel=1e-12)
    for name in ("work_on_rock", "rock_stored_energy", "rock_dissipated"):
        assert getattr(exact, name) == pytest.approx(getattr(fine, name), abs=1e-7), name
    assert exact.energy_error < 1e-12
    if t_max == 5.0:  # cut while the bit still loads: stored energy a longer window gives back
        assert exact.rock_stored_energy > 0.1
