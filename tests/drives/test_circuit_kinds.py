"""The kinds of the circuit's network written each in a module of its own
(``impactbar.drives.circuit.kinds``: laminar leakage, a position-controlled orifice, a check valve
and their watched levels), composed by the parts ``LaminarLeak``, ``Cushion`` and ``CheckValve`` into
the drifter's circuit: at random states (the piston's gap across the cushion's points, the check
valve's pressure drop across its kinks, the mode's flags those of the state), the interpreted network
(``_network``) against the same equations written out with numpy (``circuit_parts_reference``), its
Jacobian against central differences, its events against the levels, and the code generated for its
topology (``_netgen``) the interpreted network's numbers to the bit."""

import dataclasses

import numpy as np
import pytest
from circuit_parts_reference import both_ways, field, network_jacobian_fd, random_state

from impactbar.drives.circuit import CheckValve, Cushion, LaminarLeak
from impactbar.physical import circuit_preset

PARTS = (LaminarLeak("rear", "front", conductance=0.005),
         Cushion(volume=0.05, coefficient=2.0, gaps=(0.06, 0.08, 0.1), openings=(1.0, 0.4, 0.1)),
         CheckValve("front", "supply", coefficient=1.0, cracking_pressure=0.005, opening_span=0.01))


@pytest.mark.parametrize("n_modes", [0, 2])
def test_the_kinds_give_their_equations_and_the_generated_code_their_numbers(n_modes):
    d = circuit_preset("circuit-drifter")
    drive = dataclasses.replace(d.drive(), extra_parts=PARTS)
    model = d.model().with_(n_modes=n_modes)
    L = drive.layout
    M = n_modes + 1
    n, ne = L.size(M), L.n_energy
    ns = L.n_states - 1
    rng = np.random.default_rng(3)
    gen = None
    for _ in range(60):
        q, z = random_state(rng, L, M, 0.12, "cushion")
        target, moving = int(rng.integers(2)), int(rng.integers(2))
        mode = drive._mode(target, moving, z[L["supply"]], z, q)
        y = np.concatenate((q, rng.normal(0.0, 0.3, M), z, np.zeros(ne)))
        par = drive._network_par(model, mode)
        out, g, A, gen = both_ways(y, -q[0], par, M, n, ne, len(drive._composition.events), gen)
        want = field(drive, model, mode, y[:n])
        assert np.allclose(out[:n], want[:n], rtol=1e-12, atol=1e-12 * np.max(np.abs(want[:n])))
        losses = [out[n + L.energy[k]] for k in ("leak", "cushion_port", "check")]
        assert np.allclose(losses, want[n:], rtol=1e-12, atol=1e-15)
        # the account closes: the pump's work goes to the other terms
        assert abs(out[n] - np.sum(out[n + 1:])) <= 1e-12 * np.sum(np.abs(out[n:]))
        dp = z[L["front"]] - z[L["supply"]]
        assert np.allclose(g[3:], [-q[0] - 0.06, -q[0] - 0.08, -q[0] - 0.1, dp - 0.005, dp - 0.015], rtol=0,
                           atol=1e-15)
        fd = network_jacobian_fd(y, par, M, n, ne)
        scale = np.max(np.abs(A), axis=1, keepdims=True)
        assert np.allclose(A, fd, rtol=1e-6, atol=1e-7 * scale), np.max(np.abs(A - fd))
        assert ns == 4
