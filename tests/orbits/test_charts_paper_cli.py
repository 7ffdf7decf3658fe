"""Chart boundaries against closed forms (eqs. 38, 39; Fig. 8 at d = 0), the paper job, the CLI."""

import json
import math
from collections import Counter

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, periodic_orbits
from impactbar.cli import main
from impactbar.orbits import charts
from impactbar.orbits.charts import (
    find_sign_changes,
    hydraulic_existence_edge,
    pneumatic_existence_edge,
    pneumatic_stability_curve,
    pneumatic_stability_edges,
)
from impactbar.paper import hydraulic_edge_closed_form

R = np.array([0.0, 0.2, 0.5, 0.8])


def test_existence_edge_closed_form_and_orbit_count():
    assert np.allclose(pneumatic_existence_edge(R), (1 + R) / (math.pi * (1 - R)), rtol=1e-14)
    d = 0.03 / (2 * math.pi)
    for r, edge in zip(R, pneumatic_existence_edge(R, d), strict=True):
        m = BarModel(10.0, d, float(r), 0)
        assert len(periodic_orbits(m, CosineLoad(edge * (1 - 1e-7), 1.0))) == 2
        assert periodic_orbits(m, CosineLoad(edge * (1 + 1e-7), 1.0)) == []


@pytest.mark.parametrize("k", [1, 10])
def test_stability_edge_matches_eq39_to_1e8(k):
    """Rigid bar (sigma = 0): the root-found edge is eq. 39 to better than 1e-8."""
    model = BarModel(50.0, 0.0, 0.0, 0)
    b = pneumatic_stability_curve(model, R, k)
    lo = (1 + R) ** 2 / np.sqrt(4 * (1 + R * R) ** 2 / k**2 + math.pi**2 * (1 - R * R) ** 2)
    assert np.max(np.abs(b.y - lo)) < 1e-8
    assert b.kind == "period-doubling"


def test_paper_criterion_with_flexible_sigma_matches_eq37_eq39():
    k, Rv, spi, N = 10, 0.5, 10.1, 8
    model = BarModel(spi / math.pi, 0.0, Rv, N)
    sig = -((1 - Rv) / (1 + Rv)) * sum((-1) ** n * k**2 / ((spi * n) ** 2 - k**2) for n in range(1, N + 1))
    cf = (1 + Rv) ** 2 / math.sqrt(4 * (1 + Rv**2 + (1 - Rv**2) * sig) ** 2 / k**2
                                   + math.pi**2 * (1 - Rv**2) ** 2)
    edges = pneumatic_stability_edges(model, k, criterion="paper")
    assert edges[-1][0] == pytest.approx(cf, abs=1e-8)
    # the exact multipliers disagree near resonance (s pi = 10.1 against k = 10)
    exact = pneumatic_stability_edges(model, k)
    assert exact and abs(exact[-1][0] - cf) > 0.1


def test_sign_changes_evaluate_each_point_once():
    """Brent's first two evaluations are the scan's ends: read back, the roots are Brent's own on
    the same bracket to the bit, and no point is evaluated twice."""
    from scipy.optimize import brentq

    seen = Counter()

    def h(x):
        seen[float(x)] += 1
        return (x - 0.3) * (x - 1.1) * (x + 0.7)

    roots = find_sign_changes(h, -1.0, 2.0, n_scan=7)
    assert roots == pytest.approx([-0.7, 0.3, 1.1], abs=1e-12)
    xs = np.linspace(-1.0, 2.0, 7)
    assert roots == [brentq(h, a, b, xtol=1e-12, rtol=8.9e-16) for a, b in zip(xs[:-1], xs[1:], strict=True)
                     if h(a) * h(b) < 0.0]
    seen.clear()
    find_sign_changes(h, -1.0, 2.0, n_scan=7)
    assert max(seen.values()) == 1


@pytest.mark.parametrize("h", [
    lambda x: (x - 0.3) * (x - 1.1) * (x + 0.7),                   # three brackets: the top one's root
    lambda x: math.nan if x > 1.5 else (x - 0.3) * (x + 0.7),      # undefined on top: below it
    lambda x: math.nan if 0.6 < x < 1.6 else (x - 0.2) * (x - 1.9),  # a gap between the roots
    lambda x: x - 2.0,                                             # a zero at the scan's top
    lambda x: (x - 0.5) * (x + 0.25),                              # zeros on scan points (step 0.25)
    lambda x: x * x + 1.0,                                         # none
])
def test_the_last_sign_change_is_the_full_scans_last_root(h):
    """``last=True`` scans from the top down: the full scan's last root to the bit (the same bracket,
    the same Brent iterates), with no point below its bracket evaluated."""
    seen = []

    def rec(x):
        seen.append(float(x))
        return h(x)

    full = find_sign_changes(h, -1.0, 2.0, n_scan=13)
    last = find_sign_changes(rec, -1.0, 2.0, n_scan=13, last=True)
    assert last == full[-1:]
    assert all(type(r) is float for r in last)
    if full:  # nothing evaluated below the bracket holding the last root
        assert min(seen) >= full[-1] - 0.25


def test_stability_edges_evaluate_each_load_factor_once(monkeypatch):
    """The scan, Brent's iterates and the root's classification share each load factor's
    multipliers; the edge is still eq. 39's."""
    seen = Counter()
    branch = charts._stable_branch_phase

    def counted(model, load):
        seen[load.p0] += 1
        return branch(model, load)

    monkeypatch.setattr(charts, "_stable_branch_phase", counted)
    r = 0.5
    (edge, kind), = pneumatic_stability_edges(BarModel(50.0, 0.0, r, 0), 1)
    eq39 = (1 + r) ** 2 / math.sqrt(4 * (1 + r * r) ** 2 + math.pi**2 * (1 - r * r) ** 2)
    assert edge == pytest.approx(eq39, abs=1e-8)
    assert kind == "period-doubling"
    assert max(seen.values()) == 1


def test_hydraulic_edge_closed_form():
    model = BarModel(50.0, 0.0, 0.0, 0)
    for r in (0.0, 0.3, 0.7):
        assert hydraulic_existence_edge(model.with_(R=r)) == pytest.approx(
            float(hydraulic_edge_closed_form(r)), abs=1e-10)
    assert hydraulic_edge_closed_form(0.0) == pytest.approx(math.sqrt(2))


def test_sticking_part_of_the_R0_band():
    """At R = 0 the stable-branch orbit sticks once the load at impact pushes: kappa_0 > 0, i.e.
    p0/p1 > 1/sqrt(1 + pi^2)."""
    from impactbar.paper import _inadmissible_segment

    a, b = _inadmissible_segment(BarModel(50.0, 0.0, 0.0, 0), 0.2685146, 0.3183098)
    assert a == pytest.approx(1 / math.sqrt(1 + math.pi**2), abs=1e-8)
    assert b == pytest.approx(0.3183098, abs=1e-6)


def test_paper_job_writes_figures(tmp_path, capsys):
    assert main(["paper", "--out", str(tmp_path), "--quick"]) == 0
    for n in range(4, 9):
        assert (tmp_path / f"fig{n}.png").stat().st_size > 10_000
        assert (tmp_path / f"fig{n}.csv").read_text().count("\n") > 5
    out = capsys.readouterr().out
    assert "1.4142135624" in out  # Fig. 8 at R = 0: sqrt 2


def test_orbits_cli_table_and_json(capsys):
    assert main(["orbits", "--s", "5", "--d", "0.1", "--R", "0.5", "--n-modes", "4", "--p0", "0.6"]) == 0
    out = capsys.readouterr().out
    assert "admissible" in out and "True" in out
    assert main(["orbits", "--load", "square", "--kappa", "1.2", "--n-modes", "0", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["orbits"]) == 2
    assert doc["orbits"][0]["impact_velocity"] == pytest.approx(2 * math.pi * 0.2 / 1.5)


def test_cli_bad_input_is_a_clear_error(capsys):
    assert main(["orbits", "--R", "1.5"]) == 2
    assert "R must be in [0, 1]" in capsys.readouterr().err
