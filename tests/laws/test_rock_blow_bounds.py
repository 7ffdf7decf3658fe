"""Reproducers of the fuzz campaign (benchmarks/fuzz_campaign.py, category rodrock): a
blow whose characteristics grid would take hours is refused up front, naming the bound."""

import pytest

from impactbar import (
    BarModel,
    BilinearRock,
    CosineLoad,
    InitialState,
    RodRock,
    RodSegment,
    simulate,
    single_blow,
)
from impactbar.laws.rodrock.grid import MAX_CELL_STEPS


def _slow_rod_model():
    law = RodRock(segments=[RodSegment(49.10396243098472, 1.8499758631209577, 0.0140436958290981),
                            RodSegment(0.025078054844875672, 1.2155685467900768, 2.2838179408877153)],
                  rock=BilinearRock(k=0.023885578120748503, k_u=0.024925763021845633),
                  bit_mass=58.25702528463839)
    return BarModel(7.422277214326867, 0.0, 0.0, 0, impact=law)


def test_a_blow_past_the_bound_is_refused_at_once():
    model = _slow_rod_model()
    with pytest.raises(ValueError, match=r"223842 cells over 4.477e\+06 steps .* exceed 5e\+09"):
        single_blow(model, 0.3)  # ran past 40 s (hours: 1e12 cell updates)
    with pytest.raises(ValueError):  # (simulate refuses the law, or the blow)
        simulate(model, CosineLoad(0.6, 1.0), InitialState.rigid(-0.1, 0.0), 20.0)
    assert MAX_CELL_STEPS == 5e9


def test_the_bound_leaves_ordinary_blows_alone():
    law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=2.5, k_u=25.0))
    blow = single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law), 1.0, t_max=39.0)
    assert blow.efficiency == pytest.approx(0.733069, abs=1e-6)  # Lundberg's closed form
    with pytest.raises(ValueError, match="record_field would keep"):
        single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law), 1.0, t_max=1e5,
                    record_field=True, method="lattice")


def test_a_vanishing_wave_speed_is_one_line():
    """5e-324 (was an OverflowError from round(inf)) is now refused by the segment itself; the
    slowest wave allowed, 1e-100, by the blow's grid, in one line."""
    with pytest.raises(ValueError, match=r"wave_speed must be in \[1e-100, 1e\+100\]; got 5e-324"):
        RodSegment(60.15705218861109, 0.11682630816557603, 5e-324)
    law = RodRock(segments=[RodSegment(60.15705218861109, 0.11682630816557603, 1e-100),
                            RodSegment(6.950329550497215, 0.6089494913145446, 0.039082731548657566)],
                  rock=BilinearRock(k=0.0814835830846851, k_u=2.7244921698302234), feed=2.0)
    with pytest.raises(ValueError, match="cells") as info:
        single_blow(BarModel(25.141997661656262, 0.0, 0.0, 0, impact=law), 1.0)
    assert "\n" not in str(info.value)
