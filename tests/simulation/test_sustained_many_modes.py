"""Reproducer of the fuzz campaign (category wave): a sustained contact under the wave law
at 256 modes took minutes (every sample of the end's velocity built the whole state, O(N^2) per
time); the end's velocity alone is O(N). Checked against the whole state."""

import numpy as np

import impactbar as ib


def test_end_velocity_equals_the_whole_states_row():
    model = ib.BarModel(s=31.17426330513957, d=0.24738196413160912, R=0.13940301245053743, n_modes=24,
                        impact="wave")
    for load in (ib.SquareWaveLoad(q=1.007809624685486, kappa=1.4600185369260859), ib.CosineLoad(0.6, 1.0)):
        tr = ib.simulate(model, load, ib.InitialState.rigid(-0.1, 0.0, 24), 3.0)
        sus = [r.sustained for r in tr.impacts if getattr(r, "sustained", None) is not None]
        assert sus, "the case has a sustained contact"
        s = sus[0]
        for piece in s._pieces:
            t = np.linspace(piece.ta, piece.tb, 7)
            whole = s.c @ piece.states(t)[s.N:]
            np.testing.assert_allclose(s.fv_at(piece, t), whole, rtol=0,
                                       atol=1e-10 * max(1.0, float(np.max(np.abs(whole)))))
