"""A circuit part written in this file, as a user writes one in their own (the public protocol of
``impactbar.drives.circuit``: ``CircuitPart``, ``record`` and the record kinds): a leak from the front
chamber to the tank through an orifice, added to the drifter on the drill string and the rock
(``examples/circuit_drifter_rock.toml``), whose blows the circuit's pressures take part in (the coupled
blow, run on the code generated for the composed network).

- A leak of no coefficient carries nothing: ``find_orbit`` on the rock gives the preset's orbit (its
  loss written into the preset's ``orifices`` integrand, so that the integrated state is the preset's
  size and CVODE's error norm the same: measured 0 apart).
- A leak of a coefficient: ``find_orbit`` on the rock gives another admissible orbit (a longer
  period: the leak drains the return chamber; 19 % longer at ``K = 0.02``), which a run of one period
  from its state repeats (to 5e-9);
  over that period the circuit's energy account closes with the leak's loss in the orifices' term,
  and the leak's own integrand is its loss ``K phi(p_f - p_t) (p_f - p_t)`` computed here from the
  histories by the trapezoidal rule (``phi`` written out here).
- Its blows by the compiled driver and through scikit-sundae's interface: the same run to the bit.
"""

from dataclasses import dataclass, replace

import numpy as np
import pytest
from scipy.integrate import trapezoid

from impactbar import InitialState, find_orbit, simulate
from impactbar.drives.circuit import ORIFICE, CircuitPart, record


@dataclass(frozen=True)
class Leak(CircuitPart):
    """An orifice of ``coefficient`` (model units) from the front chamber to the tank, its loss an
    energy integrand of its own (in the account's ``orifices`` term)."""

    coefficient: float

    energies = (("leak", "orifices"),)
    parameters = {"leak_coefficient": "coefficient"}

    def loss_slot(self, slots):
        return slots.energy["leak"]

    def records(self, slots, oil):
        return [record(ORIFICE, source=slots.nodes["front"], target=slots.nodes["tank"],
                       coefficient=self.coefficient, ptr2=oil.transition_pressure ** 2,
                       energy=self.loss_slot(slots))]


@dataclass(frozen=True)
class PooledLeak(Leak):
    """:class:`Leak` with its loss in the preset's ``orifices`` integrand (no integrand of its own)."""

    energies = ()

    def loss_slot(self, slots):
        return slots.energy["orifices"]


@pytest.fixture(scope="module")
def rock_preset(rock_drifter):
    """The orbit on the rock without the leak."""
    return find_orbit(*rock_drifter)


@pytest.mark.slow  # (a topology's coupled blow compiled afresh: some 40 s of CPU)
def test_a_leak_of_no_coefficient_gives_the_presets_orbit_on_rock(rock_drifter, rock_preset):
    model, drive = rock_drifter
    orbit = find_orbit(model, replace(drive, extra_parts=(PooledLeak(0.0),)))
    assert orbit.drive.layout == drive.layout
    assert orbit.period == pytest.approx(rock_preset.period, rel=1e-12, abs=0.0)
    assert orbit.impact_velocity == pytest.approx(rock_preset.impact_velocity, rel=1e-12, abs=0.0)
    assert np.allclose(orbit.drive_states[0], rock_preset.drive_states[0], rtol=1e-12, atol=0.0)
    assert np.allclose(orbit.multipliers, rock_preset.multipliers, rtol=0.0, atol=1e-10)


def test_a_leak_on_rock_repeats_and_its_loss_is_accounted(rock_drifter, rock_preset):
    """The blows ended at the law's window (``driven_end="window"``, a user's choice; the default end,
    where the piston is free for good: :func:`test_a_leak_on_rock_repeats_where_the_piston_is_free`)."""
    model, drive = rock_drifter
    model = model.with_(impact=replace(model.law, driven_end="window"))
    K = 0.02
    orbit = find_orbit(model, replace(drive, extra_parts=(Leak(K),)))
    assert orbit.admissible and orbit.period > 1.01 * rock_preset.period
    z, y = orbit.drive_states[0], np.asarray(orbit.states_after_impact[0])
    M = model.n_modes + 1
    leaky = replace(orbit.drive, start_pressures=tuple(z))
    run = simulate(model, leaky, InitialState(y[:M], y[M:]), orbit.period)
    assert run.n_impacts == 1
    assert np.allclose(run.drive_state(np.array([orbit.period]))[:, 0], z, rtol=0.0, atol=1e-7)
    account = leaky.energy(run)
    assert abs(account["relative_residual"]) < 1e-12
    loss = sum(p.energies() for p in run.pieces if hasattr(p, "energies"))[leaky.layout.energy["leak"]]
    assert 0.05 * account["orifices"] < loss < account["orifices"]
    t = np.linspace(0.0, orbit.period, 400_001)
    dp = leaky.histories(run, t)["p_f"] - leaky.supply.tank_pressure
    flow = K * dp * (dp * dp + leaky.oil.transition_pressure ** 2) ** -0.25
    assert loss == pytest.approx(trapezoid(flow * dp, t), rel=1e-9)  # (measured 9e-12)


@pytest.fixture(scope="module")
def free_leak(rock_drifter):
    """``(model, orbit)``: the leak's orbit on the rock with the blows ended where the piston is free
    for good (``driven_end="free"``)."""
    model, drive = rock_drifter
    # (the plain lattice's events at its steps' ends: its blow leaves the piston off the stop here)
    model = model.with_(impact=replace(model.law, driven_end="free", contact_events="step"))
    return model, find_orbit(model, replace(drive, extra_parts=(Leak(0.02),)))


def test_a_leak_on_rock_repeats_where_the_piston_is_free(free_leak):
    """With the leak the blow leaves the piston behind the shank's new rest position (the gap
    ``-c . q > 0`` after it, some 6e-6), and the orbit's flight starts there, so that a run of one
    period from the orbit's state repeats it (measured 8e-10; 1.4e-3 where the orbit's flight
    started on the stop)."""
    model, orbit = free_leak
    z, y = orbit.drive_states[0], np.asarray(orbit.states_after_impact[0])
    M = model.n_modes + 1
    assert float(model.end_weights @ y[:M]) < -1e-6  # (off the stop: the case this test is about)
    run = simulate(model, replace(orbit.drive, start_pressures=tuple(z)), InitialState(y[:M], y[M:]),
                   orbit.period)
    assert run.n_impacts == 1
    assert run.impact_times[0] == pytest.approx(orbit.impact_times[0], rel=0.0, abs=5e-9)
    assert run.switch_times[0] == pytest.approx(orbit.switch_times[0], rel=0.0, abs=5e-9)
    assert np.allclose(run.drive_state(np.array([orbit.period]))[:, 0], z, rtol=0.0, atol=5e-9)


def test_the_free_leaks_multipliers_are_a_runs_contraction(free_leak):
    """The orbit's two leading multipliers (its flights from off the stop: the eigenvalues of the
    period's Jacobian but its structural 0) against runs from its state with the supply pressure
    moved by +-1e-4: the half-difference ``d_k`` of their k-th impact velocities falls by ``mu_1``
    a period, and ``d_{k+1} - mu_1 d_k`` by ``mu_2`` (measured 1.3e-4 from it; 6.6e-3 by the
    section's reduction ``B^T Phi B`` that holds for flights from the stop)."""
    model, orbit = free_leak
    z, y = orbit.drive_states[0], np.asarray(orbit.states_after_impact[0])
    M = model.n_modes + 1
    i = orbit.drive.layout["supply"]
    v = []
    for s in (1.0, -1.0):
        zs = np.array(z)
        zs[i] += s * 1e-4
        run = simulate(model, replace(orbit.drive, start_pressures=tuple(zs)), InitialState(y[:M], y[M:]),
                       4.2 * orbit.period)
        v.append(run.impact_velocities[:4])
    d = 0.5 * (v[0] - v[1])
    mu1, mu2 = orbit.multipliers[:2]
    assert mu1 == pytest.approx(d[3] / d[2], rel=1e-3)  # (mu_2's part left: measured 6e-4)
    e = d[1:] - mu1 * d[:-1]
    assert mu2 == pytest.approx(e[1] / e[0], rel=2e-3)


def test_the_leaks_blows_are_the_bindings_to_the_bit(rock_drifter):
    """A run on the rock with the leak by the compiled driver and through scikit-sundae's interface
    (the settings' ``compiled=False``: the generated blow's Python-called functions against its C
    callbacks and compiled loop): the same impacts, blows and account to the bit."""
    from impactbar.drives.circuit import CircuitFlightSettings, _sundials

    if not _sundials.available():
        pytest.skip(_sundials.reason())
    model, drive = rock_drifter
    leaky = replace(drive, extra_parts=(Leak(0.02),))
    runs = [simulate(model, leaky, InitialState.rigid(-0.02, 0.0), 3.0,
                     settings=CircuitFlightSettings(compiled=c)) for c in (True, False)]
    assert runs[0].n_impacts >= 2
    assert np.array_equal(runs[0].impact_times, runs[1].impact_times)
    assert np.array_equal(runs[0].impact_velocities, runs[1].impact_velocities)
    assert leaky.energy(runs[0]) == leaky.energy(runs[1])
