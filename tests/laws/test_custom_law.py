"""The developer page's worked example (docs/developers.md includes ``VelocityRestitution`` from
this file): a law added as one class plus one table entry runs through the simulator, the orbit
solvers (``find_orbit``, and ``periodic_orbits`` by Newton's method from guesses), the continuation
and the sweeps, checked against closed forms of the rigid bar (nothing outside this file
changes for it)."""

import math
from dataclasses import dataclass

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, InitialState, find_orbit, periodic_orbits, simulate
from impactbar.laws import LAWS, BlowRecords, ContactLaw, InstantImpact, LawTraits, PhaseEquation
from impactbar.orbits import orbit_multipliers
from impactbar.orbits.one_impact import phase_equation_orbits


@dataclass(frozen=True)
class VelocityRestitution(ContactLaw):
    """Eq. 10 with a restitution that falls with the arrival speed ``w = u_t(1, t-)``:
    ``(q, q') -> (q, -e(w) q')``, ``e(w) = R / (1 + w / w_ref)``."""

    w_ref: float = 1.0
    name = "velocity"
    # the compiled kernel applies a constant R only: the driver calls contact; no ability
    # PhaseEquation, so periodic_orbits takes Newton's method from the paper law's orbits
    traits = LawTraits(restitution_in_kernel=False)
    parameters = ("w_ref",)  # continued like R or p0

    def window(self, model):
        return 0.0

    def _e(self, model, w):
        return model.R / (1.0 + w / self.w_ref)

    def impact_map(self, model, load, t, y_minus):
        M = model.n_modes + 1
        c, v = model.end_weights, y_minus[M:]
        w = float(c @ v)
        e, de = self._e(model, w), -model.R / self.w_ref / (1.0 + w / self.w_ref) ** 2
        y_plus = np.concatenate((y_minus[:M], -e * v))
        jac = np.eye(2 * M)
        jac[M:, M:] = -e * np.eye(M) - de * np.outer(v, c)  # d(-e(c.v) v)/dv
        return y_plus, jac, np.zeros(2 * M)

    def contact(self, model, load, t, q_minus, v_minus, *, kernel=None):
        rec = InstantImpact(model, t, q_minus, v_minus, R=self._e(model, model.end_weights @ v_minus))
        return rec.q_after, rec.v_after, float(t), rec


def test_registered_by_name(monkeypatch):
    monkeypatch.setitem(LAWS, "velocity", VelocityRestitution)  # the one table entry
    model = BarModel(s=10.0, d=0.0, R=0.6, n_modes=0, impact="velocity")
    assert model.impact == "velocity" and model.law == VelocityRestitution()
    assert model == BarModel(s=10.0, d=0.0, R=0.6, n_modes=0, impact=VelocityRestitution())
    assert BarModel(s=10.0, d=0.0, R=0.6, n_modes=0, impact=VelocityRestitution(2.0)) != model


def test_simulated_bounces_against_the_closed_form():
    """A rigid bar (``d = 0``) under the constant load ``p0`` falls from rest through the gap ``g``:
    it arrives at ``w_1 = sqrt(2 p0 g)`` after ``sqrt(2 g / p0)``, leaves at ``e(w_1) w_1`` and is
    back after ``2 e(w_1) w_1 / p0`` with the same speed, and so on."""
    law = VelocityRestitution(w_ref=0.5)
    model = BarModel(s=10.0, d=0.0, R=0.8, n_modes=0, impact=law)
    p0, g = 0.7, 0.3
    tr = simulate(model, CosineLoad(p0, 0.0), InitialState.rigid(-g, 0.0), 50.0, max_impacts=4)
    t, w = math.sqrt(2.0 * g / p0), math.sqrt(2.0 * p0 * g)
    times, speeds = [], []
    for _ in range(4):
        times.append(t)
        speeds.append(w)
        w = law._e(model, w) * w
        t += 2.0 * w / p0
    np.testing.assert_allclose(tr.impact_times, times, rtol=1e-12)
    np.testing.assert_allclose(tr.impact_velocities, speeds, rtol=1e-12)
    assert tr.status == "max_impacts" and tr.contact_intervals.shape == (0, 2)
    rec = tr.impacts[1]
    assert rec.impact_velocity == pytest.approx(speeds[1], rel=1e-12)
    assert rec.energy_loss == pytest.approx(0.5 * speeds[1] ** 2 * (1 - law._e(model, speeds[1]) ** 2),
                                            rel=1e-12)


def test_periodic_orbit_by_the_multi_impact_solver():
    """One impact per period of the rigid bar at ``d = 0``: the momentum the load gives over a
    period, ``2 pi p0``, is what the impact takes, ``(1 + e(V)) V`` (eq. 14's identity with
    ``R -> e(V)``)."""
    law = VelocityRestitution(w_ref=2.0)
    model = BarModel(s=10.0, d=0.0, R=0.7, n_modes=0, impact=law)
    load = CosineLoad(0.3, 1.0)
    guess = find_orbit(model.with_(impact="paper"), load)
    o = find_orbit(model, load, guess=(guess.impact_times, guess.states_after_impact))
    V = o.impact_velocity
    assert V * (1.0 + law._e(model, V)) == pytest.approx(2.0 * math.pi * 0.3, rel=1e-10)


def test_what_the_law_leaves_out_is_refused_by_name():
    model = BarModel(s=10.0, d=0.0, R=0.7, n_modes=0, impact=VelocityRestitution())
    with pytest.raises(NotImplementedError, match=r"'velocity' \(VelocityRestitution\) does not provide "
                                                  r"multipliers\(\)"):
        orbit_multipliers(model, CosineLoad(0.3, 1.0), 1.0)
    assert model.law.ability(PhaseEquation) is None
    with pytest.raises(ValueError, match=r"does not provide phase_roots\(\)"):
        phase_equation_orbits(model, CosineLoad(0.3, 1.0))


def test_the_law_implements_the_required_hooks_and_declarations_alone():
    """``ContactLaw.REQUIRED_HOOKS`` are the methods this law defines, and everything else it sets is
    a declaration the base lists among its optional hooks; the solvers see it through its traits and
    the abilities it has (none)."""
    methods = {n for n, v in vars(VelocityRestitution).items() if callable(v) and not n.startswith("_")}
    assert methods == set(ContactLaw.REQUIRED_HOOKS)
    declared = {n for n in vars(VelocityRestitution) if not n.startswith("_")} - methods - {"w_ref"}
    assert declared <= set(ContactLaw.OPTIONAL_HOOKS)
    model = BarModel(s=10.0, d=0.0, R=0.7, n_modes=0, impact=VelocityRestitution())
    law = model.law
    assert not law.traits.restitution_in_kernel and law.traits.kernel_restitution(model) == -1.0
    assert law.ability(BlowRecords) is None and law.window(model) == 0.0


def _closed_form(law, model, p0, pk):
    """The rigid bar's one-impact orbits at ``d = 0`` under the law, independently of the solvers:
    the period's momentum ``2 pi p0`` is what the impact takes, ``(1 + e(V)) V`` with
    ``e(V) = R / (1 + V / w_ref)`` (a quadratic in ``V``); the flight from ``-e V`` back to the stop,
    ``2 pi (-e V) + int_0^{2 pi} (2 pi - t) p(phase + t) dt = 0``, gives ``sin(phase) = (V - pi p0) / pk``
    for ``p = p0 + pk cos t``. Returns ``V`` and the two phases in ``[0, 2 pi)``."""
    w, R, c = law.w_ref, model.R, 2.0 * math.pi * p0
    # V^2 / w + V (1 + R - c / w) - c = 0
    a, b = 1.0 / w, 1.0 + R - c / w
    V = (-b + math.sqrt(b * b + 4.0 * a * c)) / (2.0 * a)
    x = math.asin((V - math.pi * p0) / pk)
    return V, sorted(((x % (2 * math.pi)), (math.pi - x) % (2 * math.pi)))


def test_a_law_added_in_this_file_reaches_the_orbits_continuation_and_sweeps(monkeypatch, tmp_path):
    """The law above, registered by name and nothing else changed, reaches
    ``periodic_orbits`` (by Newton's method from guesses: it has no phase equation),
    ``continue_orbit`` (in the load's ``p0`` and in its own ``w_ref``) and a sweep, each checked
    against the rigid bar's closed form (:func:`_closed_form`)."""
    pytest.importorskip("xarray")
    from impactbar import continue_orbit
    from impactbar.sweeps import open_sweep, parse_spec, run_sweep

    monkeypatch.setitem(LAWS, "velocity", VelocityRestitution)
    model = BarModel(s=10.0, d=0.0, R=0.9, n_modes=0, impact="velocity")
    law, load = model.law, CosineLoad(0.5, 1.0)  # one of the two orbits stable: no simulated guess

    orbits = periodic_orbits(model, load)
    V, phases = _closed_form(law, model, 0.5, 1.0)
    assert [o.phase for o in orbits] == pytest.approx(phases, abs=1e-10)
    for o in orbits:
        assert o.impact_velocity == pytest.approx(V, rel=1e-10)
    assert any(o.stable for o in orbits)

    start = next(o for o in orbits if o.stable)
    branch = continue_orbit(start, "p0", to=0.45)
    assert str(branch.status) == "reached" and len(branch) > 3
    for p0, o in zip(branch.values, branch.orbits, strict=True):
        V, phases = _closed_form(law, model, p0, 1.0)
        assert o.impact_velocity == pytest.approx(V, rel=1e-9)
        assert min(abs(math.remainder(o.phase - ph, 2 * math.pi)) for ph in phases) < 1e-8
    branch = continue_orbit(start, "w_ref", to=1.2)  # the law's own parameter
    assert str(branch.status) == "reached"
    for w, o in zip(branch.values, branch.orbits, strict=True):
        assert o.model.law.w_ref == w
        assert o.impact_velocity == pytest.approx(_closed_form(o.model.law, model, 0.5, 1.0)[0], rel=1e-9)

    spec = parse_spec({"task": "orbits", "model": {"s": 10.0, "d": 0.0, "R": 0.9, "n_modes": 0,
                                                   "impact": "velocity"},
                       "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
                       "axes": {"p0": {"values": [0.45, 0.5]}}})
    run_sweep(spec, tmp_path / "sweep.zarr", executor="threads", n_workers=1, progress=False)
    ds = open_sweep(tmp_path / "sweep.zarr")
    for i, p0 in enumerate((0.45, 0.5)):
        V, phases = _closed_form(law, model, p0, 1.0)
        assert int(ds["n_orbits"][i]) == 2 and not bool(ds["failed"][i])
        np.testing.assert_allclose(ds["phase"][i, :2], phases, atol=1e-10)
        np.testing.assert_allclose(ds["impact_velocity"][i, :2], V, rtol=1e-10)
