"""A blow whose window ends while the bit still advances into the rock reports the penetration it
reached: the largest penetration is the last one, and the permanent one is what the
unloading line from there would leave, p (1 - k/k_u); they were those of the last unloading (0 on a
first loading)."""

import numpy as np
import pytest

from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow


@pytest.mark.parametrize("t_max", [0.8, 1.0, 1.5])
def test_a_blow_cut_while_loading_keeps_its_penetration(t_max):
    k, k_u = 0.05, 25.0
    law = RodRock(segments=[RodSegment(length=1.0, impedance=1.0)], rock=BilinearRock(k=k, k_u=k_u))
    blow = single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law), 1.0, t_max=t_max)
    assert blow.penetrations[-1] == pytest.approx(np.max(blow.penetrations), rel=1e-12)  # still loading
    assert blow.max_penetration == pytest.approx(blow.penetrations[-1], rel=1e-12)
    assert blow.permanent_penetration == pytest.approx(blow.max_penetration * (1.0 - k / k_u), rel=1e-12)
    assert 0.0 < blow.permanent_penetration <= blow.max_penetration
