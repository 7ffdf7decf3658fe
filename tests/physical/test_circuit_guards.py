"""The drifter with its oil circuit off its happy path (``impactbar.physical.circuit``): a stop that
keeps the piston (``restitution = 0``, a rest phase on the stop), the config's values checked in SI
with the user's key, and orbits that are no motion at all refused."""

import numpy as np

from impactbar.physical.circuit import circuit_preset


def test_a_run_with_restitution_zero_rests_on_the_stop_and_its_energy_account_closes():
    """With ``R = 0`` every arrival ends the piston's motion: it rests on the stop while the oil
    presses it there (the circuit's state integrated alone), then leaves when the force turns. The
    rest phase was integrated with the circuit's CVODE name handed to scipy (refused); now the rest
    carries the circuit's energy terms, so that the account closes over the whole run."""
    from impactbar.drives.flight import QuadratureRestPiece

    d = circuit_preset("circuit-drifter", stop={"restitution": 0})
    out = d.simulate(0.04)
    run = out["run"]
    assert out["impact_times_s"].size >= 1 and run.contact_intervals.shape[0] >= 1
    rests = [p for p in run.pieces if isinstance(p, QuadratureRestPiece)]
    assert len(rests) == run.contact_intervals.shape[0]
    alpha = run.drive.chambers.area_ratio
    for p in rests:
        assert p.t_end > p.t0
        t = np.linspace(p.t0, p.t_end, 201)
        z = p.drive_state(t)
        force = z[1] - alpha * z[0]
        assert np.all(force > -1e-9)  # the oil presses the piston onto the stop throughout
        assert abs(force[-1]) < 1e-8  # and it leaves where the force turns
        q, v = run.modal_state(t)
        assert np.all(q == 0.0) and np.all(v == 0.0)
        assert p.energies()[0] > 0.0 and p.energies()[1] == 0.0  # the pump works, the piston does not
    acc = run.drive.energy(run)
    assert abs(acc["relative_residual"]) < 1e-9
    # the account without the rests' terms would be off by the pump's work during them
    assert sum(p.energies()[0] for p in rests) > 1e-4 * acc["pump"]
