"""What the coupled blow under the oil circuit assumes (theory §11, "What the coupled blow assumes"):
each number the page quotes, recomputed at the arrival of ``examples/circuit_drifter_rock.toml``'s
operating point, and the choices' effects checked against what they are (the unstressed piston's
blow differs only through the static correction's term; the energies dropped are the blow's own
account)."""

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

import impactbar as ib
import impactbar.laws.rodrock.exactmap as EM
from impactbar.physical import build, read_config

ROOT = Path(__file__).resolve().parents[2]


def _paragraph() -> str:
    text = re.sub(r"\s+", " ", (ROOT / "docs" / "theory.md").read_text())
    start = text.index("**What the coupled blow assumes.**")
    return text[start:text.index("(`tests/laws/test_coupled_blow_assumptions.py`", start)]


def _quoted(pattern: str) -> str:
    m = re.search(pattern, _paragraph())
    assert m is not None, f"the quote {pattern!r} is gone from theory §11; update this test with the text"
    return m.group(1)


def _agrees(quoted: str, value: float) -> bool:
    """``quoted`` (a number as printed, ``1.4\\times10^{-5}`` too) is ``value`` to its digits."""
    m = re.fullmatch(r"([0-9.]+)(?:\\times10\^\{(-?[0-9]+)\})?", quoted)
    mant, exp = m.group(1), int(m.group(2) or 0)
    decimals = len(mant.split(".")[1]) if "." in mant else 0
    return abs(float(mant) * 10.0**exp - value) <= 0.5 * 10.0 ** (exp - decimals) * (1 + 1e-9)


@pytest.fixture(scope="module")
def arrival():
    """The operating point on the lattice (the example as shipped), the exact model, and the circuit's
    state and the piston's at the orbit's arrival."""
    cfg, _ = read_config(str(ROOT / "examples" / "circuit_drifter_rock.toml"))
    lattice = build(cfg)
    lmodel, drive = lattice.model(), lattice.drive()
    orbit = ib.find_orbit(lmodel, drive)
    del cfg["rock"]["cells_per_piston"]
    cfg["rock"].pop("contact_events", None)  # (the lattice's plain events: the arrival as measured)
    m = build(cfg).model()
    exact = m.with_(impact=dataclasses.replace(m.law, method="exact"))
    M = lmodel.n_modes + 1
    held = dataclasses.replace(drive, start_pressures=tuple(orbit.drive_states[0]))
    t0 = float(orbit.impact_times[0])
    problem = orbit.problem  # (the orbit's own flight to its arrival: the circuit's state there)
    tau, mode = problem.blocks[0]
    _, _, _, (_, q, v, state), _, _ = problem._flight(tau, mode, np.asarray(orbit._unknowns, dtype=float),
                                                      keep=True)
    before = np.asarray(orbit.states_before_impact[0], dtype=float)
    assert np.array_equal(np.concatenate((q, v)), before)
    return orbit, exact, held, state, t0, before[:M], before[M:]


def _blow(arrival):
    _, exact, drive, state, t0, q, v = arrival
    return exact.law.driven_contact(exact, drive, state, t0, q, v)


@pytest.fixture(scope="module")
def blows(arrival):
    """The coupled exact blow, and the same with the piston unstressed at arrival (the static
    correction's force set to 0 in its waves; the drive's force itself unchanged)."""
    blow = _blow(arrival)
    real = EM.initial_waves
    EM.initial_waves = lambda basis, q, v, p: real(basis, q, v, 0.0 * np.asarray(p))
    try:
        unstressed = _blow(arrival)
    finally:
        EM.initial_waves = real
    return blow, unstressed


def test_the_stress_at_arrival(arrival, blows):
    blow, unstressed = blows
    work = float(unstressed.record.work_on_rock) / float(blow.record.work_on_rock) - 1.0
    speed = float(unstressed.v_after[0]) / float(blow.v_after[0]) - 1.0
    assert work > 0.0 and speed > 0.0  # (the page says "more work" and "faster")
    assert _agrees(_quoted(r"does ([0-9.]+) % more work on the rock and rebounds"), 100 * work)
    assert _agrees(_quoted(r"rebounds ([0-9.]+) % faster"), 100 * speed)


def test_the_rock_fresh_at_every_blow(arrival, blows):
    _, exact, *_rest = arrival
    law = exact.law
    v = arrival[-1]
    preload = law.feed**2 / (2.0 * law.rock.k) / (0.5 * float(v[0]) ** 2)
    assert _agrees(_quoted(r"The preload holds \$([0-9.]+\\times10\^\{-?[0-9]+\})\$ of the impact energy"),
                   preload)


def test_the_energies_dropped_at_the_end(arrival, blows):
    blow, _ = blows
    ex = blow.record.exact
    assert ex.ended_by == "may_yield"
    E0 = 0.5 * float(arrival[-1][0]) ** 2
    assert _agrees(_quoted(r"The rod still rings then, with ([0-9.]+) % of the impact energy"),
                   100 * float(ex.rod_energy) / E0)
    assert _agrees(_quoted(r"at most ([0-9.]+) % of the available energy"), 100 * float(ex.uncertainty))
    inner = float(ex.piston_energy) - 0.5 * float(blow.v_after[0]) ** 2
    assert inner > 0.0
    assert _agrees(_quoted(r"the rest of the energy in its waves, ([0-9.]+) % of the impact energy"),
                   100 * inner / E0)
    # the blow's own account: what the rock took and what piston and rod hold at the end are the
    # energy available less what the drive's and the feed's flows did not yet deliver (to rounding)
    assert float(ex.energy_error) < 1e-9


def test_the_work_on_rock_is_the_work_dissipated_in_it(arrival, blows):
    """Under the drive the work on rock is what the rock dissipated (its loadings' work); what it
    stores at the blow's end goes back to the bit and is a term of its own in the account, which
    closes (exact blow and the lattice's on the orbit alike)."""
    blow, _ = blows
    b, ex = blow.record.blow, blow.record.exact
    assert b.stored_apart and b.rock_stored_energy > 1e-3 * b.energy_at_impact  # (the bit has landed)
    assert b.work_on_rock == pytest.approx(float(np.sum(ex.loadings[:, 4])), rel=1e-12)
    assert b.rock_dissipated == b.work_on_rock
    lattice = arrival[0].contacts[0].blow
    assert lattice.stored_apart and lattice.rock_dissipated == lattice.work_on_rock
    for one in (b, lattice):
        parts = (one.work_on_rock + one.rock_stored_energy + one.piston_energy + one.rod_energy
                 + one.grid_loss)
        assert abs(one.available_energy - parts) <= 1e-9 * one.energy_at_impact
        assert one.energy_error <= 1e-9


def test_the_lattice_at_the_same_arrival(arrival, blows):
    orbit = arrival[0]
    blow, _ = blows
    less = 1.0 - float(orbit.contacts[0].work_on_rock) / float(blow.record.work_on_rock)
    assert less > 0.0
    assert _agrees(_quoted(r"does \$([0-9.]+\\times10\^\{-?[0-9]+\})\$ less work on the rock"), less)
    stored = blow.record.rock_stored_energy / blow.record.energy_at_impact
    assert _agrees(_quoted(r"\(([0-9.]+) % of the impact energy at the\s*exact blow's end"), 100 * stored)


def test_a_wrong_quote_fails():
    """The check can fail: a number off in its last digit is not the computed one."""
    assert _agrees("0.19", 0.0019 * 100) and not _agrees("0.18", 0.0019 * 100)
    assert _agrees("1.4\\times10^{-5}", 1.415e-5) and not _agrees("1.5\\times10^{-5}", 1.415e-5)


def _stored_in_rock(R: float, k_u: float) -> float:
    """The rock's elastic energy under its force ``R`` on the unloading line of stiffness ``k_u``
    (theory §4d): ``R^2/(2 k_u)``, 0 off the rock."""
    return max(R, 0.0) ** 2 / (2.0 * k_u)


def test_the_blow_account_has_every_term_apart(arrival, blows):
    """The coupled blow's energy account term by term, each from the blow's final state, closing to
    1e-9 of the impact energy (the exact blow from the lattice orbit's arrival, the lattice's with the
    end where the piston is free for good from there, and the lattice orbit's own blow): the work
    dissipated in the rock (its loadings'), the rock's elastic energy at the end (the unloading line's
    closed form at the final force and penetration), the piston's, the bit's kinetic energy, and the
    rod's waves and strain under the feed, apart."""
    orbit, exact, drive, state, t0, q, v = arrival
    law = exact.law
    k_u, m = law.rock.k_u, law.bit_mass
    ex_blow = blows[0].record.blow
    lmodel = exact.with_(impact=dataclasses.replace(law, method="lattice", cells_per_piston=8,
                                                    driven_end="free"))
    free = lmodel.law.driven_contact(lmodel, drive, state, t0, q, v).record.blow
    # (measured: the rock stores 0.66 % and 2.7 % of the impact energy at the ends of the first two,
    # the bit's kinetic energy 1.6 %, 0.08 % and 1.2 %; the accounts close to 1e-15)
    for b in (ex_blow, free, orbit.contacts[0].blow):
        E0 = b.energy_at_impact
        assert b.stored_apart
        if b.exact is not None:  # the work dissipated: its loadings'
            assert b.work_on_rock == pytest.approx(float(np.sum(b.loadings[:, 4])), rel=1e-12)
        end = np.array([b.duration])
        R = float(b.bit_forces[-1]) if b.exact is None else float(b.exact.bit_force(end)[0])
        assert b.rock_stored_energy == pytest.approx(_stored_in_rock(R, k_u), rel=1e-12, abs=1e-15 * E0)
        if R > 0.0:  # on the unloading line: R = k_u (p - p_perm)
            p = float(b.penetrations[-1]) if b.exact is None else float(b.exact.penetration(end)[0])
            assert R == pytest.approx(k_u * (p - b.permanent_penetration), rel=1e-9)
        assert b.bit_energy == pytest.approx(0.5 * m * b.bit_velocity**2, rel=1e-12, abs=1e-15 * E0)
        rod = b.rod_energy - b.bit_energy  # the rod's waves and its strain under the feed
        assert rod > 0.0 and b.bit_energy >= 0.0 and b.work_on_rock > 0.0
        parts = b.work_on_rock + b.rock_stored_energy + b.piston_energy + rod + b.bit_energy + b.grid_loss
        assert abs(b.available_energy - parts) <= 1e-9 * E0
    bit = 100 * ex_blow.bit_energy / ex_blow.energy_at_impact
    assert _agrees(_quoted(r"`Blow.bit_energy`, ([0-9.]+) % of the"), bit)
