"""Results at an end against their closed forms: force, velocity, energy, impact velocity, specimen."""

import numpy as np
import pytest

from impactbar.measure import Bar, Waves, end_history, impact_velocity, specimen_response, wave_energy

BAR = Bar(200e9, 8000.0, 1e-3)  # c = 5000 m/s, EA = 2e8 N, Z = 4e4 N s/m


def test_one_wave_force_velocity_and_energy():
    """A striker of the bar's section at V = 10 m/s sends a pulse of velocity V/2, strain -V/(2c),
    force Z V/2, of length 2 L / c; its energy is the striker's kinetic energy (equal impedances)."""
    V, L, dt = 10.0, 0.5, 1e-7
    t = np.arange(4000) * dt
    a = np.where((t >= 1e-5) & (t < 1e-5 + 2 * L / BAR.wave_speed), -V / (2 * BAR.wave_speed), 0.0)
    h = end_history(Waves(t, a, np.zeros_like(a)), BAR)
    assert h.force.max() == pytest.approx(BAR.impedance * V / 2, rel=1e-12)
    assert h.velocity.max() == pytest.approx(V / 2, rel=1e-12)
    kinetic = 0.5 * BAR.density * BAR.area * L * V ** 2
    assert h.energy_fv[-1] == pytest.approx(kinetic, rel=1e-3)  # (the trapezoid's two edge samples)
    assert wave_energy(a, dt, BAR) == pytest.approx(kinetic, rel=1e-12)
    assert h.displacement[-1] == pytest.approx(V / 2 * 2 * L / BAR.wave_speed, rel=1e-3)


def test_force_velocity_energy_is_the_incident_less_the_reflected():
    """EFV = EA c int (a^2 - b^2); the force-squared form counts both waves and overstates it."""
    dt = 1e-7
    t = np.arange(3000) * dt
    a = -1e-4 * np.sin(np.pi * t / t[-1])
    b = 0.6e-4 * np.sin(2 * np.pi * t / t[-1])
    h = end_history(Waves(t, a, b), BAR)
    expected = wave_energy(a, dt, BAR) - wave_energy(b, dt, BAR)
    assert h.energy_fv[-1] == pytest.approx(expected, rel=1e-6)
    assert h.energy_f2[-1] > h.energy_fv[-1]


@pytest.mark.parametrize("ratio", [1.0, 0.5])
def test_impact_velocity_from_the_plateau(ratio):
    """V = v_p (1 + Z / Z_s): a striker of half the bar's section sends a third of V."""
    striker = Bar(200e9, 8000.0, ratio * 1e-3)
    V = 12.0
    vp = V * striker.impedance / (striker.impedance + BAR.impedance)
    ramp = np.linspace(0, -vp / BAR.wave_speed, 5)[:-1]  # below 85 % of the peak
    strain = np.r_[ramp, np.full(100, -vp / BAR.wave_speed), ramp[::-1]]
    v = impact_velocity(strain, BAR, striker=striker)
    assert v["velocity"] == pytest.approx(V, rel=1e-12) and v["velocity_std"] < 1e-9
    assert v["plateau_samples"] == 100


def test_impact_velocity_refuses_a_spike():
    with pytest.raises(ValueError, match="no plateau"):
        impact_velocity(np.r_[np.zeros(10), -1.0, np.zeros(10)], BAR)


def test_specimen_in_equilibrium_gives_one_stress():
    """With eps_T = eps_I + eps_R (equal bars) the three analyses agree: stress EA eps_T / A_s and
    strain rate 2 c eps_R / L_s."""
    t = np.linspace(0, 1, 200)
    eI = -1e-3 * np.sin(np.pi * t)
    eR = 0.6e-3 * np.sin(np.pi * t) ** 2
    eT = eI + eR
    r = specimen_response(eI, eR, eT, 1e-8, BAR, BAR, 2e-3, 2e-4)
    for k in "123":
        np.testing.assert_allclose(r.stress[k], -BAR.stiffness * eT / 2e-4, rtol=1e-12, atol=1e-3)
        np.testing.assert_allclose(r.strain_rate[k], 2 * BAR.wave_speed * eR / 2e-3, rtol=1e-12, atol=1e-6)


def test_specimen_refuses_waves_of_different_lengths():
    with pytest.raises(ValueError, match="of one length"):
        specimen_response(np.zeros(5), np.zeros(5), np.zeros(4), 1e-8, BAR, BAR, 1e-3, 1e-6)
