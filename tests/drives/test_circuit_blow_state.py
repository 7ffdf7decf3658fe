"""The coupled blow without its piece (the blows of the orbits' Jacobians, settling runs and residuals):
the same state after it as the kept blow and as the law's blow followed by the drive's map; and the
lattice's blow map with the drive's averages left to its caller, the same record as the held load's
blow once they are filled in."""

import numpy as np
import test_circuit_laws as laws_tests  # this folder's: the pump-fed drifter and the rod on rock

from impactbar import BarModel
from impactbar.drives import DriveState
from impactbar.laws.rodrock.contact import BlowMap
from impactbar.loads import FourierLoad
from impactbar.orbits.coupled import blow_state, coupled_blow


def _model():
    return BarModel(s=laws_tests.S, d=0, R=0.0, n_modes=0, impact=laws_tests.rock(2.0, cells=8))


def _drive():
    return laws_tests.pumped()


def test_the_blow_without_its_piece_is_the_kept_blow_and_the_laws():
    model, drive = _model(), _drive()
    q, v = np.zeros(1), np.array([0.34])
    st = DriveState((1, 0, 1, 0), np.array([1.15, 1.15, 1.15, 1.0]))
    y, res, after = blow_state(model, drive, 0.3, q, v, st)
    kept, t_after, after_kept, piece = coupled_blow(model, drive, 0.3, q, v, st)
    np.testing.assert_array_equal(y, kept)
    assert res.t_release == t_after == piece.t_end
    assert after.mode == after_kept.mode
    # the law's blow and the drive's map at its end, by hand
    law = model.law.driven_contact(model, drive, st, 0.3, q, v)
    end = law.drive_state
    mapped = drive.impact(end.mode, end.z, law.t_release, law.q_after, law.v_after)
    np.testing.assert_array_equal(y, np.concatenate((law.q_after, law.v_after, mapped.z)))


def test_a_blow_map_with_its_averages_left_to_the_caller():
    model = _model()
    load = FourierLoad(0.8, [0.1, 0.05j])
    q, v = np.zeros(1), np.array([0.3])
    bm = BlowMap(model, load, 0.2, averaged=False)
    assert bm.drive.shape == (bm.n_max,) and not np.any(bm.drive)
    bm.drive[:] = BlowMap(model, load, 0.2).drive
    rec = bm.contact(q, v)
    qa, va, t_after, ref = model.law.contact(model, load, 0.2, q, v)
    np.testing.assert_array_equal(rec.q_after, qa)
    np.testing.assert_array_equal(rec.v_after, va)
    assert rec.work_on_rock == ref.work_on_rock and 0.2 + rec.duration == t_after
