"""The documented whole-drifter search reaches a certified optimum (docs/optimising_a_drifter.md, "Where a
certificate is within reach"): the multistart of ``benchmarks/bench_optimize_restarts.py`` (six variables
of ``examples/circuit_drifter_rock_piston.toml``, drilling rate per kW, the peak rod stress at most 250
MPa, the drilling rate at least 2.5 m/min; a sample of 256, three local searches of 40 designs) on the
example's own lattice setting, the blow's re-contact inside its step (``rock.contact_events = "inside"``:
no border of the lattice's along the drilling rate's limit), and a polish of at most 40 designs (it stops
at its first certified iterate). Checked without
trusting the search: the design rebuilt from its config values and solved by a fresh ``orbit()`` meets
every constraint, and it is at least as good per kilowatt as the best of twenty COBYLA searches from the
same sample; its KKT residual recomputed from central differences of fresh orbits (not the implicit
function theorem's gradients the certificate used) is below the tolerance at a step of 1e-5 of the spans
(at 1e-4 and more the front rod's derivative is not that at the design: the figures bend within 1e-4 of
the spans there, and the residual of those differences is printed, not asserted). The same run with the
sample on a local cluster started inside the call (``workers=1``) and on a client's cluster started
before it (whose start sets ``OPENBLAS_NUM_THREADS=1`` in this process: the polish's SLSQP takes one BLAS
thread itself, so both take the same path)."""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path

import numpy as np
import pytest

from impactbar.physical import build, optimize_drifter, read_config, with_values
from impactbar.physical.optimality import KKT_TOLERANCE, central_gradients, certify
from impactbar.physical.optimize_problem import evaluate_design

pytest.importorskip("pint")
pytest.importorskip("distributed")
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

from bench_optimize_drifter import CONSTRAINTS, EXAMPLE, VARY  # noqa: E402

#: The best of the twenty restarted COBYLA searches (30 designs each, ``optimize_drifter``'s default)
#: from the sample's designs ranked, on the same setting (``bench_optimize_restarts.py --contact-events
#: inside``, the example's own since 2026-11-30; benchmarks/HISTORY.md 2026-11-29: search 4 of 20, each
#: confirmed by a fresh orbit).
BEST_SEARCH = 0.110644
FKEY = "drilling_rate_per_kW"


def _search(cfg, workers):
    return optimize_drifter(cfg, VARY, objective=FKEY, constraints=CONSTRAINTS, method="multistart",
                            sample=256, local_starts=3, seed=0, max_evaluations=256 + 3 * 40, polish=40,
                            progress=False, workers=workers)


@pytest.fixture(scope="module", params=["workers=1", "client"])
def searched(request):
    """The search (some 3 minutes of wall time alone on the 2-core development machine: 376 designs, 3
    gradients, the certificate's orbits), its config and folder."""
    cfg, folder = read_config(EXAMPLE)
    assert cfg["rock"]["contact_events"] == "inside"  # (the example's own)
    if request.param == "client":
        import dask
        from distributed import Client, LocalCluster

        environ = dict(os.environ)
        try:
            with (dask.config.set({"distributed.scheduler.http.routes": [],
                                   "distributed.worker.http.routes": []}),
                  LocalCluster(n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1",
                               dashboard_address="127.0.0.1:0", scheduler_kwargs={"dashboard": False},
                               worker_dashboard_address=None, silence_logs=logging.ERROR) as cluster,
                  Client(cluster) as client):
                res = _search(cfg, client)
        finally:
            os.environ.clear()
            os.environ.update(environ)
    else:
        res = _search(cfg, 1)
    return res, cfg, folder


@pytest.mark.slow
@pytest.mark.timeout(3600)  # the search past the default 600 s
def test_the_documented_search_ends_certified(searched):
    """Measured with the polish stopped at its first certified iterate (``bench_optimize_drifter.py
    --method multistart``, 2026-11-30, ``workers=2``, and on 4 workers of a 16-core machine with other
    numpy and scipy versions, the same design to 3e-6 of the spans): 0.1108848 m/min/kW, converged, KKT
    residual 0.00867, the drilling rate (multiplier 0.279) and the rear volume's and pre-charge's low
    bounds active, after the polish's second design. (The polish run to its 40 designs: 0.1109521,
    residual 0.00798, here; 0.110946, residual 0.031, "stopped at a budget", on the 16-core machine.)"""
    res, cfg, folder = searched
    cert = res.certificate
    assert cert.verdict == "converged" and cert.residual < KKT_TOLERANCE, str(cert)
    assert "min_drilling_rate" in cert.active
    fresh, _ = evaluate_design(build(with_values(cfg, res.optimum["changes"]), folder), CONSTRAINTS)
    assert fresh["feasible"]
    assert fresh["objectives"][FKEY] >= BEST_SEARCH


@pytest.mark.slow
@pytest.mark.timeout(3600)
def test_central_differences_of_fresh_orbits_confirm_the_certificate(searched):
    """The KKT residual again from central differences of fresh orbits, not the certificate's
    gradients: at a step of 1e-5 of the spans (a fresh orbit's figures to some 1e-9: the differences
    to some 1e-4 of the gradient) below the tolerance, the objective's gradient within 1 % of the
    certificate's. Measured at the design the search reports (its polish stopped where it is
    certified): 0.00868 at 1e-5 and 0.00866 at 1e-4 (the certificate's 0.00867), the objective's
    gradient off the certificate's by 3.4e-4 of its norm. At the bench's design before the border
    model: 0.0079 at 1e-5 (the gradients agree to 1e-4), 0.022 at 1e-4, 0.058 at 1e-3, the difference
    all in the front rod's derivative."""
    res, cfg, folder = searched
    cert = res.certificate
    fresh, _ = evaluate_design(build(with_values(cfg, res.optimum["changes"]), folder), CONSTRAINTS)
    keys = list(res.vary)
    lo = np.array([res.vary[k]["low"] for k in keys])
    span = np.array([res.vary[k]["high"] - res.vary[k]["low"] for k in keys])
    u = (np.array([res.optimum["values"][k] for k in keys]) - lo) / span

    def point(v):
        changes = {k: f"{float(x)!r} {res.vary[k]['unit']}" for k, x in zip(keys, lo + span * v, strict=True)}
        rec, _ = evaluate_design(build(with_values(cfg, changes), folder), CONSTRAINTS)
        return [rec["objectives"][FKEY], *(c["scaled"] for c in rec["constraints"].values())]

    wide = certify(*central_gradients(point, u, 1e-4)[:2], fresh, u, keys, method="central differences")
    g, G, how = central_gradients(point, u, 1e-5)
    again = certify(g, G, fresh, u, keys, method=how)
    print(f"{res.optimum['objectives'][FKEY]:.7f} m/min/kW; {cert}; central differences' residual "
          f"{again.residual:.5f} at 1e-5, {wide.residual:.5f} at 1e-4; the objective's gradient off the "
          f"certificate's by {np.linalg.norm(g - cert.objective_gradient) / np.linalg.norm(g):.2e} of its "
          f"norm; {res.evaluations} designs, {res.gradients} gradients, {res.seconds:.0f} s")
    assert again.residual < KKT_TOLERANCE and "min_drilling_rate" in again.active
    assert np.linalg.norm(g - cert.objective_gradient) < 0.01 * np.linalg.norm(g)
