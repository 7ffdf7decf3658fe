"""The coupled exact blow ends when it is certified over (theory §11, "The coupled blow"), not at
the law's window: its numbers are the same whatever the window, on the drifter's second arrival,
whose piston presses on the shank again just after the default window (where the fixed window's
blow handed the flight a state that followed the window)."""

import dataclasses

import numpy as np
import pytest
import test_coupled_exact_blow as blow_tests

arrival = blow_tests.arrival  # (the fixture: the drifter's second arrival, on a rod of whole piston lengths)


def _numbers(blow, t0):
    return np.concatenate(([blow.t_release - t0, float(blow.record.work_on_rock)], blow.q_after, blow.v_after,
                           blow.drive_state.z))


@pytest.fixture(scope="module")
def blows(arrival):
    """The blow under the default window and under 1.5 and 2 times it."""
    model, drive, state, t0, q, v = arrival
    window = model.law.window(model)
    out = []
    for factor in (1.0, 1.5, 2.0):
        law = dataclasses.replace(model.law, blow_time=factor * window)
        out.append(law.driven_contact(model.with_(impact=law), drive, state, t0, q, v))
    return window, out


def test_the_blow_does_not_depend_on_the_window(arrival, blows):
    t0 = arrival[3]
    window, (first, *longer) = blows
    ref = _numbers(first, t0)
    for blow in longer:
        assert blow.drive_state.mode == first.drive_state.mode
        np.testing.assert_allclose(_numbers(blow, t0), ref, rtol=1e-9, atol=1e-12)


def test_it_ends_certified_past_the_piston_s_second_touch(arrival, blows):
    """The piston touches the shank again after the window and leaves it before the certified end
    (the fixed window cut into that touch); the end is the solver's certificate, not a horizon."""
    window, (first, *_) = blows
    ex = first.record.exact
    assert ex.ended_by in ("separated", "lifted", "spent", "may_yield")
    t_end = first.t_release - arrival[3]
    assert window < t_end < 2.0 * window
    breaks = ex.junction_breaks(ex.contact_junction)
    assert np.any((breaks > window) & (breaks < t_end))  # (a touch's opening after the window)
    assert first.v_after[0] < 0.0  # (the piston moving back at the end)
