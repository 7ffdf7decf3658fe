"""The circuit drifter's restart check and its start from rest at the valve's switch point
(:mod:`impactbar.physical.circuit_switch`, ``orbit(switch_start=True)``); BUZZING's orbit from there is
checked in ``test_optimize_drifter_failures.py``."""

from __future__ import annotations

import numpy as np
import pytest
from drifter_optimum import DOCUMENTED_NO_ORBIT, EXAMPLE

from impactbar.physical import build, load, read_config, with_values
from impactbar.physical.circuit_switch import check_repeats

pytest.importorskip("pint")


def test_an_orbit_on_rock_repeats_when_restarted_from_its_blow_s_end_with_its_arrival_due():
    """On rod and rock the orbit's state is where its blow ends, so a run restarted there strikes at the
    orbit's arrival, ``impact_times[0]``, a contact's time before the period: checked so it repeats
    (to ``REPEAT_TOL``), where the check without the drill's arrival (due at the period) refuses it."""
    point = load("examples/circuit_drifter_rock.toml").orbit()
    o = point.orbit
    contact = o.period - float(o.impact_times[0])
    assert 0.01 * o.period < contact < 0.2 * o.period  # (a blow of some 5 % of the period)
    check_repeats(o, float(o.impact_times[0]))
    with pytest.raises(ValueError, match=r"does not repeat when simulate restarts .*the first interval 0\.9"):
        check_repeats(o)


def test_the_documented_search_s_designs_without_an_orbit_have_none_from_the_switch_point_either():
    """The documented multistart's three designs without a one-impact orbit (the example's own
    settings): none from rest at the switch point either, the error saying both starts' reasons, so
    the start would change none of that search's designs."""
    cfg, folder = read_config(EXAMPLE)
    said = []
    for changes in DOCUMENTED_NO_ORBIT:
        with pytest.raises(ValueError, match=r"no periodic orbit") as err:
            build(with_values(cfg, changes), folder).orbit(switch_start=True)
        head, sep, tail = str(err.value).partition("; from rest at the valve's switch point: ")
        assert sep and "the motion from rest on the stop" in head
        said.append(tail)
    assert np.sum(["rear chamber empties" in s for s in said]) == 2
    assert "could not be integrated" in said[2]
