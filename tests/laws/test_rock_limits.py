"""The rod-rock blow's limits are continuous: a bit mass tending to 0 gives the massless
bit's efficiency (Lundberg's 0.733069 on this example) at every small mass, and a rock stiffness
tending to 0 the soft limit (the bit runs free: penetration 1 in the example's units, efficiency k),
in the compiled kernel and in its Python reference alike. Before, bit masses 1e-100 .. 1e-16 gave
efficiency 0 (a stiff bit's eigenvalue lost to cancellation) and k = 1e-16 a rigid wall (the
equilibrium p_eq = E/k, huge, subtracted from itself)."""

import pytest

from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow
from impactbar.dynamics.implementations import use_reference


def _blow(k=2.5, bit_mass=0.0, reference=False):
    law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=k, k_u=25.0),
                  bit_mass=bit_mass)
    model = BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law)
    if reference:
        with use_reference("rock.blow"):
            return single_blow(model, 1.0, t_max=39.0)
    return single_blow(model, 1.0, t_max=39.0)


@pytest.mark.parametrize("reference", [False, True])
@pytest.mark.parametrize("bit_mass", [1e-100, 1e-30, 1e-16, 1e-15, 1e-12])
def test_a_vanishing_bit_mass_tends_to_the_massless_bit(bit_mass, reference):
    massless = _blow()
    assert massless.efficiency == pytest.approx(0.733069, abs=1e-6)
    blow = _blow(bit_mass=bit_mass, reference=reference)
    assert blow.efficiency == pytest.approx(massless.efficiency, rel=1e-9)
    assert blow.max_penetration == pytest.approx(massless.max_penetration, rel=1e-9)


@pytest.mark.parametrize("reference", [False, True])
@pytest.mark.parametrize("bit_mass", [0.0, 1e-16, 0.1])
@pytest.mark.parametrize("k", [1e-16, 1e-15, 1e-14, 1e-12])
def test_a_vanishing_rock_stiffness_tends_to_the_soft_limit(k, bit_mass, reference):
    blow = _blow(k=k, bit_mass=bit_mass, reference=reference)
    assert blow.max_penetration == pytest.approx(1.0, rel=1e-9)
    assert blow.efficiency == pytest.approx(k, rel=1e-9)
