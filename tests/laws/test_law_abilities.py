"""A law with the base's required hooks alone runs (a simulation, the rigid bar's one-impact orbits),
checked against the rigid bar's closed forms; an optional ability a law derives from is found by
``law.ability`` and used by the solver that looks it up; a former flag is refused by name."""

import math
from dataclasses import dataclass

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, InitialState, find_orbit, periodic_orbits, simulate
from impactbar.laws import (
    BlowRecords,
    ContactLaw,
    CoupledBlow,
    InstantImpact,
    LawTraits,
    NewtonStart,
    PaperLaw,
    PhaseEquation,
)
from impactbar.laws.abilities import newton_start, require

#: the phases at which a law's phase equation was asked (by ``_WithPhaseEquation``)
ASKED = []


@dataclass(frozen=True)
class _Required(ContactLaw):
    """Eq. 10, ``(q, q') -> (q, -R q')``, by the three required hooks and a name alone (the base's
    traits: the kernel applies ``R`` itself)."""

    name = "required-only"

    def window(self, model):
        return 0.0

    def impact_map(self, model, load, t, y_minus):
        M = model.n_modes + 1
        y_plus = np.concatenate((y_minus[:M], -model.R * y_minus[M:]))
        jac = np.diag(np.concatenate((np.ones(M), np.full(M, -model.R))))
        return y_plus, jac, np.zeros(2 * M)

    def contact(self, model, load, t, q_minus, v_minus, *, kernel=None):
        rec = InstantImpact(model, t, q_minus, v_minus)
        return rec.q_after, rec.v_after, float(t), rec


@dataclass(frozen=True)
class _WithPhaseEquation(_Required, PhaseEquation):
    """The same law with the ability of a phase equation, eq. 14's (the paper law's), whose roots
    it records in ``ASKED``."""

    name = "with-phase-equation"

    def phase_roots(self, model, load):
        roots = PaperLaw().phase_roots(model, load)
        ASKED.extend(ph for ph, _ in roots)
        return roots

    def orbit_state(self, model, load, phase):
        return PaperLaw().orbit_state(model, load, phase)

    def multipliers(self, model, load, phase):
        return PaperLaw().multipliers(model, load, phase)


def _rigid_orbit(R, p0, pk):
    """The rigid bar's one-impact orbit at ``d = 0`` under ``p0 + pk cos t`` and eq. 10: the
    period's momentum ``2 pi p0`` is what the impact takes, ``(1 + R) V``; the flight from ``-R V``
    back to the stop gives ``sin(phase) = (V - pi p0) / pk``. Returns ``V`` and the two phases in
    ``[0, 2 pi)``."""
    V = 2.0 * math.pi * p0 / (1.0 + R)
    x = math.asin((V - math.pi * p0) / pk)
    return V, sorted((x % (2 * math.pi), (math.pi - x) % (2 * math.pi)))


def test_a_law_with_the_required_hooks_alone_simulates_the_closed_form_bounces():
    """A rigid bar (``d = 0``) under the constant load ``p0`` falls from rest through the gap ``g``:
    it arrives at ``w_1 = sqrt(2 p0 g)`` after ``sqrt(2 g / p0)``, leaves at ``R w_1`` and is back
    after ``2 R w_1 / p0`` with the same speed, and so on."""
    law = _Required()
    assert {n for n in vars(_Required) if not n.startswith("_")} == {"name", *ContactLaw.REQUIRED_HOOKS}
    model = BarModel(s=10.0, d=0.0, R=0.6, n_modes=0, impact=law)
    p0, g = 0.7, 0.3
    tr = simulate(model, CosineLoad(p0, 0.0), InitialState.rigid(-g, 0.0), 50.0, max_impacts=4)
    t, w = math.sqrt(2.0 * g / p0), math.sqrt(2.0 * p0 * g)
    times, speeds = [], []
    for _ in range(4):
        times.append(t)
        speeds.append(w)
        w *= model.R
        t += 2.0 * w / p0
    np.testing.assert_allclose(tr.impact_times, times, rtol=1e-12)
    np.testing.assert_allclose(tr.impact_velocities, speeds, rtol=1e-12)


def test_a_law_with_the_required_hooks_alone_finds_the_rigid_orbits_by_newton():
    """Without the ability of a phase equation, ``periodic_orbits`` takes Newton's method from the
    paper law's orbits (the defaults of ``NewtonStart``), and reaches the closed form's orbits."""
    law = _Required()
    model = BarModel(s=10.0, d=0.0, R=0.7, n_modes=0, impact=law)
    load = CosineLoad(0.3, 1.0)
    assert law.ability(PhaseEquation) is None and law.ability(NewtonStart) is None
    assert newton_start(law).paper_equivalent(model) == model.with_(impact="paper")
    with pytest.raises(ValueError, match=r"'required-only' \(_Required\) does not provide multipliers\(\)"):
        require(law, PhaseEquation, "multipliers")
    V, phases = _rigid_orbit(model.R, 0.3, 1.0)
    orbits = periodic_orbits(model, load)
    assert [o.phase for o in orbits] == pytest.approx(phases, abs=1e-10)
    for o in orbits:
        assert o.impact_velocity == pytest.approx(V, rel=1e-10)
    o = find_orbit(model, load)
    assert o.impact_velocity == pytest.approx(V, rel=1e-10)
    assert min(abs(math.remainder(o.phase - ph, 2 * math.pi)) for ph in phases) < 1e-10


def test_an_ability_the_law_derives_from_is_found_and_used():
    """The lookup finds the phase equation the law derives from (the law itself) and not the
    abilities it lacks; ``periodic_orbits`` then takes the orbits from its roots, the closed form's."""
    law = _WithPhaseEquation()
    assert law.ability(PhaseEquation) is law
    assert law.ability(BlowRecords) is None and law.ability(CoupledBlow) is None
    model = BarModel(s=10.0, d=0.0, R=0.7, n_modes=0, impact=law)
    V, phases = _rigid_orbit(model.R, 0.3, 1.0)
    ASKED.clear()
    orbits = periodic_orbits(model, CosineLoad(0.3, 1.0))
    assert ASKED == pytest.approx(phases, abs=1e-12)  # the law's phase equation was asked
    assert [o.phase for o in orbits] == pytest.approx(phases, abs=1e-12)
    for o in orbits:
        assert o.impact_velocity == pytest.approx(V, rel=1e-12)


def test_the_packaged_laws_abilities():
    wave = BarModel(s=10.0, d=0.0, R=0.5, n_modes=1, impact="wave").law
    paper = PaperLaw()
    assert [paper.ability(k) is paper for k in (PhaseEquation, BlowRecords, CoupledBlow, NewtonStart)] == \
        [True, False, False, False]
    assert [wave.ability(k) is wave for k in (PhaseEquation, BlowRecords, CoupledBlow, NewtonStart)] == \
        [True, True, True, False]


@pytest.mark.parametrize("flag", ["instantaneous", "has_phase_equation", "rigid_closed_forms"])
def test_a_former_flag_is_refused_with_what_replaces_it(flag):
    """A law that still declares a flag of the former base would be read wrongly (the kernel
    applying ``R`` to a law that meant to resolve its contact): it is refused at its definition."""
    with pytest.raises(TypeError, match=rf"_Old\.{flag}: a law no longer declares {flag}; use "):
        type("_Old", (ContactLaw,), {flag: False})
    assert LawTraits().restitution_in_kernel and not LawTraits().rigid_closed_forms
