"""The lattice's coupled blow under the oil circuit ends where the piston is free for good
(``RodRock(driven_end="free")``, the default; theory §11, "The coupled blow"): the first step after
which the contact is open, the piston's momentum is ``<= 0`` and the rock is not loading, the exact
blow's certificate under a drive, not the law's fixed window ``4/s + 2 sum T_i`` (a user's choice,
``driven_end="window"``). The orbit's sensitivity to the end is the one theory §11 states."""

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest
from coupled_reference import drifter_arrival

import impactbar as ib
import impactbar.laws.rodrock.coupled as C
from impactbar.physical import build, read_config

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def arrival():
    """The drifter's second arrival (the example's rod as given), on the example's lattice of 8 cells."""
    model, drive, state, t0, q, v = drifter_arrival()
    law = dataclasses.replace(model.law, method="lattice", cells_per_piston=8, driven_end="free")
    return model.with_(impact=law), drive, state, t0, q, v


def _tested_instants(model):
    """The exact blow's window ``h``: the shortest travel time of the piston and the rod's segments."""
    return min([1.0 / model.s] + [g.travel_time(model) for g in model.law.segments])


def test_the_blow_ends_where_the_piston_is_free_for_good(arrival):
    model, drive, state, t0, q, v = arrival
    blow = C.driven_rock_contact(model, drive, state, t0, q, v)
    b = blow.record.blow
    window = model.law.window(model)
    assert b.ended_by == "separated"
    assert b.duration != pytest.approx(window, rel=1e-9)  # (not the fixed window)
    with pytest.raises(ValueError, match="driven_end must be"):
        dataclasses.replace(model.law, driven_end="later")
    F, G = b.piston_waves
    assert b.shank_forces[-1] == 0.0 and float(np.sum(F - G)) <= 0.0  # open, the piston not moving on
    assert b.penetrations[-1] <= b.max_penetration  # (the rock not loading: at or below its largest)
    # the end is the first step end at or after a multiple j h of the exact blow's window h
    h, dt = _tested_instants(model), b.cell_time
    n = round(b.duration / dt)
    j = math.floor(n * dt / h * (1.0 + 1e-12))
    assert (n - 1) * dt < j * h <= n * dt * (1.0 + 1e-12), (n, j, h / dt)
    # at the instant tested before it the piston was not free yet
    shorter = dataclasses.replace(model.law, blow_time=math.ceil((j - 1) * h / dt) * dt, driven_end="window")
    cut = C.driven_rock_contact(model.with_(impact=shorter), drive, state, t0, q, v)
    Fc, Gc = cut.record.blow.piston_waves
    assert cut.record.blow.shank_forces[-1] > 0.0 or float(np.sum(Fc - Gc)) > 0.0 \
        or cut.record.blow.bit_forces[-1] >= model.law.rock.k * cut.record.blow.max_penetration * (1 - 1e-12)
    assert blow.t_release == pytest.approx(t0 + b.duration, rel=1e-15)
    # the fixed window where the user names it
    law = dataclasses.replace(model.law, blow_time=1.5 * window, driven_end="window")
    fixed = C.driven_rock_contact(model.with_(impact=law), drive, state, t0, q, v).record.blow
    assert fixed.ended_by == "t_max"
    assert fixed.duration == pytest.approx(1.5 * window, abs=fixed.cell_time)


def test_the_blow_ends_where_the_exact_blow_ends(arrival):
    """The lattice's blow (8 cells) and the exact blow from the same arrival end at the same instant
    to a step: both test the piston free for good at the multiples of the shortest travel time
    (measured: the lattice's end 0.26 of a step after the exact blow's; tested at every step, as
    before, the lattice's ended 1.74 steps, 1.9 % of the blow, before it)."""
    model, drive, state, t0, q, v = arrival
    lattice = C.driven_rock_contact(model, drive, state, t0, q, v)
    exact_model = model.with_(impact=dataclasses.replace(model.law, method="exact"))
    exact = exact_model.law.driven_contact(exact_model, drive, state, t0, q, v)
    assert exact.record.exact is not None
    dt = lattice.record.blow.cell_time
    assert 0.0 <= lattice.t_release - exact.t_release < dt, (lattice.t_release - exact.t_release) / dt


_NUMBER = r"\$([0-9.]+\\times10\^\{-?[0-9]+\})\$"


def _stated_bounds(pattern: str) -> np.ndarray:
    """The orbit's sensitivity to the end that theory §11 states (the period, the impact velocity,
    the work on the rock), each as a bound: the number as printed plus half its last digit."""
    text = re.sub(r"\s+", " ", (ROOT / "docs" / "theory.md").read_text())
    m = re.search(pattern.replace("X", _NUMBER), text)
    assert m is not None, f"the sensitivity {pattern!r} is gone from theory §11; update this test with it"
    out = []
    for quoted in m.groups():
        mant, exp = re.fullmatch(r"([0-9.]+)\\times10\^\{(-?[0-9]+)\}", quoted).groups()
        decimals = len(mant.split(".")[1]) if "." in mant else 0
        out.append((float(mant) + 0.5 * 10.0**-decimals) * 10.0 ** int(exp))
    return np.array(out)


_FREE = (r"moved later by 10 % of the window the example's orbit moves X in the period, X in the impact "
         r"velocity and X")
_WINDOW = r"ended at the window \(`driven_end=\"window\"`\) and moved so, it moves X, X and X"


def _example(**rock):
    """The example's model and drive, with ``rock`` keys set in its ``[rock]`` table."""
    cfg, _ = read_config(str(ROOT / "examples" / "circuit_drifter_rock.toml"))
    cfg["rock"].update(rock)
    h = build(cfg)
    return h.model(), h.drive()


def _orbit_numbers(o, model):
    """The orbit's period, impact velocity and work on the rock (the dissipated work)."""
    b = o.contacts[0].blow
    M = model.n_modes + 1
    return np.array([float(o.period), float(np.asarray(o.states_before_impact[0])[M]), b.work_on_rock])


def test_the_stated_bounds_are_read():
    """The docs' numbers are read as bounds, and a difference above one fails."""
    bounds = _stated_bounds(_WINDOW)
    assert bounds.shape == (3,) and np.all(bounds > 0.0) and np.all(bounds < 0.1)
    assert bounds[0] == pytest.approx(1.35e-3, rel=1e-12)  # (1.3e-3 printed: below 1.35e-3)


def test_the_orbit_with_the_window_moved_later():
    """The orbit with the blow ended at the law's window (``driven_end="window"``) and with that end
    moved later by 10 % of the window differ by less than theory §11 states (measured: the period
    1.3e-3, the impact velocity 2.7e-3, the work on the rock 5.6e-3; the bit lifted off the rock at
    both ends, the later end's flight from the piston's gap behind the shank's rest position)."""
    model, drive = _example(driven_end="window")  # (the config's key, a user's choice)
    assert model.law == dataclasses.replace(_example()[0].law, driven_end="window")
    window = model.law.window(model)
    default = ib.find_orbit(model, drive)
    later_model = model.with_(impact=dataclasses.replace(model.law, blow_time=1.1 * window))
    later = ib.find_orbit(later_model, drive)
    b, bl = default.contacts[0].blow, later.contacts[0].blow
    assert b.ended_by == bl.ended_by == "t_max"
    assert b.duration == pytest.approx(window, rel=1e-12)
    assert bl.duration - b.duration == pytest.approx(0.1 * window, abs=b.cell_time)
    rel = np.abs(_orbit_numbers(later, model) / _orbit_numbers(default, model) - 1.0)
    assert np.all(rel < _stated_bounds(_WINDOW)), rel
    assert np.all(rel > 0.1 * _stated_bounds(_WINDOW)), rel  # (the numbers stated are the measured)


def test_the_orbit_with_the_end_moved_later(monkeypatch):
    """The default's orbit (the blow ended where the piston is free for good; the example's slots)
    with the end moved later by 10 % of the window differs from it by less than theory §11 states
    (measured: the period 2.8e-3, the impact velocity 2.0e-3, the work on the rock 4.1e-3: the later
    end takes in the
    piston's next touch of the shank, which the default leaves to the flight with the piston's rigid
    momentum, its waves dropped; the later end's flight starts from the piston's gap behind the
    shank's rest position)."""
    model, drive = _example()
    assert model.law.driven_end == "free"  # (the default)

    def numbers(o):
        return _orbit_numbers(o, model)

    default = ib.find_orbit(model, drive)
    assert default.contacts[0].blow.ended_by == "separated"
    monkeypatch.setattr(C, "END_DELAY", 0.1)
    later = ib.find_orbit(model, drive)
    assert later.contacts[0].blow.duration > default.contacts[0].blow.duration
    rel = np.abs(numbers(later) / numbers(default) - 1.0)
    assert np.all(rel < _stated_bounds(_FREE)), rel
    assert np.all(rel > 0.1 * _stated_bounds(_FREE)), rel  # (the numbers stated are the measured)


@pytest.mark.slow
def test_the_orbit_converges_to_the_exact_orbit():
    """Ended where the piston is free for good (the default) the example's orbit (its slots on 8
    cells) is the exact blows' orbit to 1e-5 in the blow frequency, the impact velocity, the work on
    the rock, the penetration and the mean supply pressure (measured 2.0e-6); on the plain lattice
    (``contact_events="step"``) at 64 cells to 1e-4 (measured 2.0e-5, the rod rounded to whole
    cells: the same at 128 cells, whose rounding is 64's) and on 8 cells to 1.4e-3 (measured
    1.37e-3, the work on the rock)."""
    import tomllib

    from impactbar.physical import CircuitDrifter
    from impactbar.physical.circuit import CircuitDrifterOrbit

    with open(ROOT / "examples" / "circuit_drifter_rock.toml", "rb") as f:
        drifter = CircuitDrifter.from_config(tomllib.load(f))
    model = drifter.model()
    assert model.law.contact_events == "slots"

    def figures(law):
        point = CircuitDrifterOrbit(drifter, ib.find_orbit(model.with_(impact=law), drifter.drive()))
        rock = point.rock()
        return np.array([point.blow_frequency_Hz, point.impact_velocity_m_s, rock["work_on_rock_J"],
                         rock["penetration_mm"], point.mean_supply_pressure_Pa])

    exact = figures(dataclasses.replace(model.law, method="exact"))
    default = np.abs(figures(model.law) / exact - 1.0)
    assert np.max(default) < 1e-5, default
    plain = dataclasses.replace(model.law, contact_events="step")
    rel = np.abs(figures(dataclasses.replace(plain, cells_per_piston=64)) / exact - 1.0)
    assert np.all(rel < 1e-4), rel
    eight = np.abs(figures(plain) / exact - 1.0)
    assert 1.3e-3 < np.max(eight) < 1.45e-3, eight
