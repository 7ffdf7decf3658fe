"""A contact law defined in this file alone, entered in the table of laws by
:func:`impactbar.laws.register_law`, reaches ``simulate``, ``find_orbit``, ``continue_orbit`` and a
sweep (its ``[law]`` table), its own parameter ``c`` continued and swept with no line in
continuation/, sweeps/ or cli/ for it.

Each point is checked against a fresh :func:`impactbar.find_orbit` at that value (``1e-8``), the
run from an orbit's state against the orbit (the impacts repeat), and the law at ``c = 0`` against
the paper's law (eq. 10), whose orbits come from its own phase equation (eq. 14)."""

import math
from dataclasses import dataclass

import numpy as np
import pytest

from impactbar import (
    BarModel,
    CosineLoad,
    InitialState,
    Parameter,
    continue_orbit,
    find_orbit,
    periodic_orbits,
    simulate,
)
from impactbar.laws import LAWS, ContactLaw, InstantImpact, LawTraits, register_law

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class LinearRestitution(ContactLaw):
    """Eq. 10 with a restitution that falls linearly with the arrival speed ``w = u_t(1, t-)``:
    ``(q, q') -> (q, -e(w) q')``, ``e(w) = R - c w``."""

    c: float = 0.0
    name = "linear-restitution"
    # the compiled kernel applies a constant R only: the driver calls contact; no phase equation
    # (the ability PhaseEquation): its orbits by Newton's method from the paper law's
    traits = LawTraits(restitution_in_kernel=False)
    parameters = ("c",)

    def parameter_table(self, model=None):
        return (Parameter("c", float(self.c), low=0.0, description="fall of the restitution per unit speed"),)

    def window(self, model):
        return 0.0

    def e(self, model, w):
        return model.R - self.c * w

    def impact_map(self, model, load, t, y_minus):
        M = model.n_modes + 1
        cw, v = model.end_weights, y_minus[M:]
        e = self.e(model, float(cw @ v))
        jac = np.eye(2 * M)
        jac[M:, M:] = -e * np.eye(M) + self.c * np.outer(v, cw)  # d(-e(c . v) v)/dv
        return np.concatenate((y_minus[:M], -e * v)), jac, np.zeros(2 * M)

    def contact(self, model, load, t, q_minus, v_minus, *, kernel=None):
        rec = InstantImpact(model, t, q_minus, v_minus, R=self.e(model, model.end_weights @ v_minus))
        return rec.q_after, rec.v_after, float(t), rec


LOAD = CosineLoad(0.5, 1.0)


def _model(c):
    return BarModel(s=10.0, d=0.05, R=0.35, n_modes=2, impact=LinearRestitution(c))


@pytest.fixture
def registered():
    register_law(LinearRestitution)
    yield
    LAWS.pop(LinearRestitution.name, None)


def test_registered_by_name_and_refusals(registered):
    model = BarModel(s=10.0, d=0.05, R=0.35, n_modes=2, impact="linear-restitution")
    assert model.law == LinearRestitution() and model.impact == "linear-restitution"
    assert register_law(LinearRestitution) is LinearRestitution

    class Other(LinearRestitution):
        name = "paper"

    with pytest.raises(ValueError, match="name 'paper' is already the impact law PaperLaw"):
        register_law(Other)
    with pytest.raises(ValueError, match="subclass of ContactLaw"):
        register_law(int)


def test_simulate_from_the_orbit_repeats_it():
    """The stable orbit at ``c = 0.02``; the run from its state after the impact strikes at the
    orbit's phase every period with its speed; at ``c = 0`` the orbit is the paper law's."""
    o = find_orbit(_model(0.02), LOAD)
    assert o.stable and o.admissible and o.model.law.c == 0.02
    q, v = o.modal_state_after_impact
    run = simulate(o.model, LOAD, InitialState(q, v), o.phase + 5.5 * TWO_PI, t0=o.phase)
    assert run.n_impacts == 5
    np.testing.assert_allclose(run.impact_times, o.phase + TWO_PI * np.arange(1, 6), rtol=0, atol=1e-9)
    np.testing.assert_allclose(run.impact_velocities, o.impact_velocity, rtol=1e-9)
    w = o.impact_velocity  # the record's restitution is the law's at the arrival speed
    assert run.impacts[0].R == pytest.approx(0.35 - 0.02 * w, rel=1e-9)

    paper = [p for p in periodic_orbits(_model(0.0).with_(impact="paper"), LOAD) if p.stable]
    zero = find_orbit(_model(0.0), LOAD)
    assert len(paper) == 1
    assert zero.phase == pytest.approx(paper[0].phase, abs=1e-8)
    assert zero.impact_velocity == pytest.approx(paper[0].impact_velocity, abs=1e-8)


def test_the_laws_parameter_is_continued():
    """A branch in ``c`` from 0.02 down to 0; each point against a fresh find_orbit at that ``c``,
    the end against the paper law's orbit (eq. 14)."""
    branch = continue_orbit(find_orbit(_model(0.02), LOAD), "c", to=0.0)
    assert branch.parameter == "c" and str(branch.status) == "reached" and len(branch) > 2
    assert branch.values[-1] == pytest.approx(0.0, abs=1e-12)
    for c, o in zip(branch.values, branch.orbits, strict=True):
        assert type(o.model.law) is LinearRestitution and o.model.law.c == c
        ref = find_orbit(_model(c), LOAD)
        assert o.phase == pytest.approx(ref.phase, abs=1e-8)
        assert o.impact_velocity == pytest.approx(ref.impact_velocity, abs=1e-8)
    paper = next(p for p in periodic_orbits(_model(0.0).with_(impact="paper"), LOAD) if p.stable)
    assert branch.orbits[-1].phase == pytest.approx(paper.phase, abs=1e-8)


def test_the_laws_parameter_is_swept(registered, tmp_path):
    """A ``[law]`` table names the law by its registered name and sets ``c``; an axis sweeps ``c``.
    Each point's stable orbit against a fresh find_orbit at that ``c``; at ``c = 0`` every orbit
    against the paper law's (eq. 14)."""
    pytest.importorskip("xarray")
    pytest.importorskip("zarr")
    from impactbar.sweeps import open_sweep, parse_spec, run_sweep

    doc = {"task": "orbits", "model": {"s": 10.0, "d": 0.05, "R": 0.35, "n_modes": 2},
           "law": {"kind": "linear-restitution", "c": 0.02},
           "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
           "axes": {"c": {"values": [0.0, 0.01, 0.02]}}}
    spec = parse_spec(doc)
    assert spec.model["impact"] == "linear-restitution"
    assert spec.law == {"kind": "linear-restitution", "c": 0.02}
    assert parse_spec(spec.to_dict()) == spec
    model, load = spec.point((1,))
    assert model.law == LinearRestitution(0.01) and load == LOAD
    run_sweep(spec, tmp_path / "c.zarr", executor="threads", n_workers=1, progress=False)
    ds = open_sweep(tmp_path / "c.zarr")
    assert ds["c"].values.tolist() == [0.0, 0.01, 0.02] and not ds["failed"].values.any()
    for i, c in enumerate((0.0, 0.01, 0.02)):
        n = int(ds["n_orbits"].values[i])
        stable = [j for j in range(n) if ds["stable"].values[i, j]]
        assert n >= 1 and len(stable) == 1
        ref = find_orbit(_model(c), LOAD)
        assert ds["phase"].values[i, stable[0]] == pytest.approx(ref.phase, abs=1e-8)
        assert ds["impact_velocity"].values[i, stable[0]] == pytest.approx(ref.impact_velocity, abs=1e-8)
    paper = periodic_orbits(_model(0.0).with_(impact="paper"), LOAD)
    n = int(ds["n_orbits"].values[0])
    assert n == len(paper)
    np.testing.assert_allclose(np.sort(ds["phase"].values[0, :n]), [p.phase for p in paper], atol=1e-8)

    with pytest.raises(ValueError, match=r"\[axes\] c = -1.0: c must be in \[0, inf\)"):
        parse_spec({**doc, "axes": {"c": {"values": [-1.0]}}})
    with pytest.raises(ValueError, match=r"^\[law\] kind must be one of \[.*\] \(impactbar.laws.register_law "
                                         r"adds one\); got 'nope'$"):
        parse_spec({**doc, "law": {"kind": "nope"}})
    with pytest.raises(ValueError, match=r"^\[law\] the impact law 'linear-restitution' takes keys of "
                                         r"LinearRestitution: .*'slope'"):
        parse_spec({**doc, "law": {"kind": "linear-restitution", "slope": 1.0}})
    with pytest.raises(ValueError, match=r"impact = 'wave' but \[law\] kind = 'linear-restitution'"):
        parse_spec({**doc, "model": {**doc["model"], "impact": "wave"}})
    rock = {"k": 60.0, "k_u": 600.0, "segments": [{"length": 10.0, "impedance": 1.0}]}
    with pytest.raises(ValueError, match=r"^\[law\] and \[rock\] both name the impact law: give one$"):
        parse_spec({**doc, "rock": rock})


def test_the_command_line_reads_a_law_table(registered, tmp_path, capsys):
    """``impactbar sweep SPEC.toml`` reads the same ``[law]`` table (the TOML), and refuses an
    unknown kind in one line before any work (exit status 2)."""
    pytest.importorskip("xarray")
    from impactbar.cli import main
    from impactbar.sweeps import load_spec, parse_spec

    lines = ['task = "orbits"', "[model]", "s = 10.0", "d = 0.05", "R = 0.35", "n_modes = 2",
             "[law]", 'kind = "linear-restitution"', "c = 0.02",
             "[load]", 'kind = "cosine"', "p0 = 0.5", "pk = 1.0", "k = 1",
             "[axes]", "c = { values = [0.0, 0.01] }"]
    path = tmp_path / "law.toml"
    path.write_text("\n".join(lines) + "\n")
    spec = load_spec(path)
    assert spec == parse_spec(spec.to_dict()) and spec.law == {"kind": "linear-restitution", "c": 0.02}
    path.write_text("\n".join(lines).replace('"linear-restitution"', '"nope"') + "\n")
    assert main(["sweep", str(path), "--out", str(tmp_path / "out.zarr")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "[law] kind must be one of" in err[0] and "got 'nope'" in err[0]
