"""The impact laws as objects (``impactbar.laws``): the table, the lookup, the model holding a law,
no law chosen by its name outside the laws' own modules, and the per-blow records."""

import ast
import math
import pickle
from pathlib import Path

import numpy as np
import pytest

from impactbar import BarModel, CosineLoad, InitialState, SquareWaveLoad, periodic_orbits, simulate
from impactbar.laws import LAWS, ContactLaw, InstantImpact, PaperLaw, PressedContact, WaveLaw, get_law

SRC = Path(__file__).resolve().parents[2] / "src" / "impactbar"


def test_table_and_lookup():
    assert LAWS == {"paper": PaperLaw, "wave": WaveLaw}
    assert get_law("paper") == PaperLaw() and get_law("wave") == WaveLaw()
    law = WaveLaw()
    assert get_law(law) is law
    for bad in ("plastic", 3, None):
        with pytest.raises(ValueError, match=r"impact must be one of \['paper', 'wave'\]"):
            get_law(bad)
    with pytest.raises(ValueError, match=r"impact must be one of \['paper', 'wave'\].*'rod'"):
        BarModel(s=10.0, d=0.0, R=0.5, n_modes=0, impact="rod")


def test_model_takes_a_name_or_a_law_object():
    by_name = BarModel(s=10.0, d=0.1, R=0.5, n_modes=2, impact="wave")
    by_law = BarModel(s=10.0, d=0.1, R=0.5, n_modes=2, impact=WaveLaw())
    assert by_name == by_law and hash(by_name) == hash(by_law)
    assert by_law.impact == "wave" and isinstance(by_law.law, WaveLaw)
    assert repr(by_law) == "BarModel(s=10.0, d=0.1, R=0.5, n_modes=2, impact='wave')"
    assert by_law != by_law.with_(impact="paper") and by_law.with_(d=0.2).law == WaveLaw()
    assert pickle.loads(pickle.dumps(by_law)) == by_law
    assert BarModel(s=10.0, d=0.1, R=0.5, n_modes=2).law == PaperLaw()


def test_law_properties():
    m = BarModel(s=4.0, d=0.0, R=0.5, n_modes=1)
    assert PaperLaw().window(m) == 0.0 and WaveLaw().window(m) == 0.5
    assert PaperLaw().traits.rigid_closed_forms and not WaveLaw().traits.rigid_closed_forms
    assert PaperLaw().traits.kernel_restitution(m) == 0.5 and WaveLaw().traits.kernel_restitution(m) == -1.0
    assert issubclass(PaperLaw, ContactLaw) and issubclass(WaveLaw, ContactLaw)
    assert PaperLaw().existence_edge(m.with_(R=1.0)) == math.inf


def _law_name_comparisons(path: Path) -> list[str]:
    """Comparisons of something named like an impact law with a law's name (``model.impact ==
    "wave"``, ``law != "paper"``, ``impact in ("paper", "wave")``) and ``getattr(x, "impact",
    "paper")`` in one module: each a choice of behaviour by the law's name."""
    names = set(LAWS)

    def is_name(p):
        return (isinstance(p, ast.Constant) and p.value in names
                or isinstance(p, ast.Tuple | ast.List | ast.Set) and any(map(is_name, p.elts)))

    def lawish(p):
        text = ast.unparse(p)
        return "impact" in text or "law" in text

    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Compare):
            parts = [node.left, *node.comparators]
            if any(map(is_name, parts)) and any(lawish(p) for p in parts if not is_name(p)):
                found.append(f"{path.name}:{node.lineno}")
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "getattr"
              and len(node.args) == 3 and is_name(node.args[2])):
            found.append(f"{path.name}:{node.lineno}")
    return found


def test_no_law_chosen_by_name_outside_the_laws():
    found = [hit for p in sorted(SRC.rglob("*.py")) if "laws" not in p.relative_to(SRC).parts
             for hit in _law_name_comparisons(p)]
    assert found == []
    # the check finds what it looks for
    probe = SRC.parent / "_probe_law_names.py"
    try:
        probe.write_text('if model.impact == "wave":\n    pass\nlaw = getattr(m, "impact", "paper")\n'
                         'ok = law not in ("paper",) or criterion == "paper"\n')
        assert len(_law_name_comparisons(probe)) == 3
    finally:
        probe.unlink()


def test_paper_law_records_per_impact():
    """The paper law's per-blow record (:class:`InstantImpact`), one per impact, against eq. 10:
    the velocity field reversed and scaled by R, the kinetic energy lost ``(1 - R^2)`` of it, the
    impulse ``(1 + R)`` times the rigid momentum."""
    model = BarModel(s=3.0, d=0.05, R=0.6, n_modes=3)
    tr = simulate(model, CosineLoad(0.5, 1.0), InitialState.rigid(-0.2, 0.0, n_modes=3), 30.0)
    recs = tr.impacts
    assert len(recs) == tr.n_impacts > 3
    for t, v, rec in zip(tr.impact_times, tr.impact_velocities, recs, strict=True):
        assert isinstance(rec, InstantImpact) and rec.t0 == t and rec.duration == 0.0
        assert rec.impact_velocity == pytest.approx(v, rel=1e-9)
        np.testing.assert_allclose(rec.v_after, -0.6 * rec.v_before, rtol=1e-15)
        kin = 0.5 * (rec.v_before[0] ** 2 + 2.0 * np.sum(rec.v_before[1:] ** 2))
        assert rec.energy_loss == pytest.approx((1 - 0.36) * kin, rel=1e-9)
        assert rec.impulse == pytest.approx(1.6 * rec.v_before[0], rel=1e-15)
        if v > 1e-3:  # the run continues from the record's state (not in a chatter's hold)
            q, vv = tr.modal_state([t])
            np.testing.assert_allclose(vv[:, 0], rec.v_after, rtol=1e-9, atol=1e-12)


def test_contact_intervals_mean_sustained_contact_under_every_law():
    """``contact_intervals`` holds the intervals of sustained contact (the bar held on the stop after
    chatter or a touch) under both laws: the square wave presses the paper law's rigid bar onto the
    stop after each blow's chatter; the wave law's pressed blows go on after their window as the
    sustained contact (theory §4b), listed from the window's end to the release."""
    load = SquareWaveLoad(1.0, 1.5)
    paper = BarModel(s=10.0, d=0.1, R=0.5, n_modes=0)
    tp = simulate(paper, load, InitialState.rigid(-0.1, 0.0), 8 * 2 * math.pi)
    assert tp.contact_intervals.shape[0] >= 1
    assert np.all(np.diff(tp.contact_intervals, axis=1) > 0.0)
    # every sustained contact starts where the end sits on the stop, and the end stays there
    mid = tp.contact_intervals.mean(axis=1)
    np.testing.assert_allclose(tp.end_displacement(mid), 0.0, atol=1e-12)
    wave = paper.with_(impact="wave", n_modes=4)
    tw = simulate(wave, load, InitialState.rigid(-0.1, 0.0, n_modes=4), 8 * 2 * math.pi)
    assert tw.contact_intervals.shape[0] >= 1 and tw.n_impacts >= 4
    starts = list(tw.contact_intervals[:, 0])
    for t, rec in zip(tw.impact_times, tw.impacts, strict=True):
        assert rec.t0 == t
        if isinstance(rec, PressedContact):  # pressed: the window, then the sustained contact
            assert rec.sustained.t0 == pytest.approx(t + 2.0 / 10.0, rel=1e-15)
            assert rec.sustained.t0 in starts
        else:
            assert rec.duration == pytest.approx(2.0 / 10.0, rel=1e-15)
    np.testing.assert_allclose(tw.end_displacement(tw.contact_intervals.mean(axis=1)), 0.0, atol=1e-12)


def test_orbits_follow_the_law_object():
    """The one-impact orbits through the law: the wave law's object and its name give the same
    orbits; the paper law's orbits have no per-blow record, the wave law's a WaveImpact."""
    load = CosineLoad(0.4, 1.0)
    m = BarModel(s=12.0, d=0.05, R=0.5, n_modes=2)
    by_name = periodic_orbits(m.with_(impact="wave"), load)
    by_law = periodic_orbits(m.with_(impact=WaveLaw()), load)
    assert [o.phase for o in by_name] == [o.phase for o in by_law] and len(by_law) >= 1
    assert all(o.impact is not None for o in by_law)
    assert all(o.impact is None for o in periodic_orbits(m, load))
