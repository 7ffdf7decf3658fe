"""The bases' hooks: :class:`~impactbar.laws.ContactLaw` lists the members a solver calls in one
place, split required / optional (``REQUIRED_HOOKS``, ``OPTIONAL_HOOKS``; the drive's and the load's
narrow bases: ``tests/drives/test_drive_abilities.py``, ``tests/test_load_base.py``); the solvers ask
a law's traits and abilities, never a declaration ``instantaneous``; and a load with the required
members alone runs."""

import inspect
import re
from pathlib import Path

import numpy as np
import pytest

import impactbar
from impactbar import BarModel, CosineLoad, periodic_orbits
from impactbar.laws import BlowRecords, ContactLaw, LawTraits
from impactbar.loads import Load

BASES = (ContactLaw,)
TOP = Path(impactbar.__file__).parent


def _code(path):
    """A module's lines, without its docstrings' examples."""
    return "\n".join(ln for ln in path.read_text(encoding="utf-8").splitlines()
                     if not ln.lstrip().startswith(">>>"))


def test_no_solver_reads_the_laws_instantaneous_flag():
    """Outside ``impactbar.laws`` the solvers ask what they need (the traits'
    ``restitution_in_kernel``, the ability ``BlowRecords``, ``window``), never such a flag, which
    would mean several things at once."""
    reads = []
    for p in sorted(TOP.rglob("*.py")):
        if (TOP / "laws") in p.parents:
            continue
        for j, line in enumerate(_code(p).splitlines(), 1):
            if re.search(r"\.instantaneous\b|[\"']instantaneous[\"']", line):
                reads.append(f"{p.relative_to(TOP)}:{j}: {line.strip()}")
    assert reads == []


@pytest.mark.parametrize("base", BASES, ids=lambda b: b.__name__)
def test_every_public_member_is_listed_once(base):
    required, optional = base.REQUIRED_HOOKS, base.OPTIONAL_HOOKS
    assert len(set(required)) == len(required) and len(set(optional)) == len(optional)
    assert set(required) & set(optional) == set()
    public = {n for n in dir(base) if not n.startswith("_")} - {"REQUIRED_HOOKS", "OPTIONAL_HOOKS"}
    assert public == (set(required) | set(optional)) - {"__call__"}


def test_a_loads_public_members_are_its_required_hooks_and_its_declarations():
    """A load's required hooks are the abstract methods of :class:`Load`; besides them it has its
    abilities, its parameters and its class's declarations, and its family."""
    public = {n for n in dir(Load) if not n.startswith("_")}
    assert public == (set(Load.__abstractmethods__) - {"__call__"}) | {"abilities", "params", "traits",
                                                                         "family"}


def test_the_required_law_hooks_are_refused_by_the_base():
    """A law without its required hooks says which one it lacks (a ``NotImplementedError``); every
    optional method of the base has a default, or refuses only its own computation."""

    class Bare(ContactLaw):
        name = "bare"
        traits = LawTraits(restitution_in_kernel=False)

    law, model, load = Bare(), BarModel(s=10.0, d=0.0, R=0.5, n_modes=0), CosineLoad(0.3, 1.0)
    args = {"window": (model,), "impact_map": (model, load, 0.0, np.array([0.0, -1.0])),
            "contact": (model, load, 0.0, np.zeros(1), -np.ones(1))}
    assert set(args) == set(ContactLaw.REQUIRED_HOOKS)
    for name, a in args.items():
        with pytest.raises(NotImplementedError, match=f"does not provide {name}"):
            getattr(law, name)(*a)
        assert isinstance(inspect.getattr_static(ContactLaw, name), type(lambda: None))


def test_every_law_hook_the_solvers_call_is_listed():
    called = set()
    for sub in ("orbits", "simulation", "continuation", "drives", "physical", "sweep"):
        for p in (TOP / sub).rglob("*.py"):
            called |= set(re.findall(r"\blaw\.([a-z][a-z_]*)\b", _code(p)))  # (public)
    assert {"traits", "ability", "window", "contact"} <= called
    assert called - set(ContactLaw.REQUIRED_HOOKS) - set(ContactLaw.OPTIONAL_HOOKS) == set()


@pytest.mark.parametrize(("impact", "in_kernel", "records", "window"),
                         [("paper", True, False, 0.0), ("wave", False, True, 0.2)])
def test_the_hooks_of_the_packaged_laws(impact, in_kernel, records, window):
    """The paper's law is the kernel's ``v -> -R v`` at an instant; the wave law's contact a blow of
    length ``2 / s`` with its own record, which the kernel leaves to the law (``-1``)."""
    model = BarModel(s=10.0, d=0.0, R=0.5, n_modes=2, impact=impact)
    law = model.law
    assert law.traits.restitution_in_kernel is in_kernel and (law.ability(BlowRecords) is law) is records
    assert law.window(model) == pytest.approx(window, rel=1e-15)
    assert law.traits.kernel_restitution(model) == (0.5 if in_kernel else -1.0)


def test_the_rod_rock_law_keeps_its_blows():
    law = impactbar.RodRock(segments=[impactbar.RodSegment(length=3.0, impedance=1.0)],
                            rock=impactbar.BilinearRock(k=5.0, k_u=5.0))
    model = BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law)
    assert not law.traits.restitution_in_kernel and law.ability(BlowRecords) is law
    assert law.traits.kernel_restitution(model) == -1.0 and law.window(model) > 0.0


class _Minimal(Load):
    """A load with the required members alone (and ``p0``), each the cosine load's: no kernel view,
    so that every solver reaches it through its numpy reference paths."""

    def __init__(self, p0, pk):
        self._set(p0=p0, inner=CosineLoad(p0, pk))

    def __call__(self, t):
        return self.inner(t)

    def harmonics(self, n=None):
        return self.inner.harmonics(n)

    @property
    def sup_abs(self):
        return self.inner.sup_abs

    @property
    def sup_oscillation(self):
        return self.inner.sup_oscillation

    def variation(self, mid, half):
        return self.inner.variation(mid, half)

    def propagate(self, w2, d, t0, q0, v0, t):
        return self.inner.propagate(w2, d, t0, q0, v0, t)

    def rigid_velocity(self, d, t):
        return self.inner.rigid_velocity(d, t)


def test_a_load_with_the_required_members_alone_finds_the_cosine_loads_orbits():
    """The one-impact orbits of a flexible bar under the minimal load (numpy paths) against those of
    the cosine load it copies (compiled paths)."""
    overridden = {n for n in vars(_Minimal) if not n.startswith("_")} | {"__call__"}
    assert overridden == set(Load.__abstractmethods__)
    model = BarModel(s=10.0, d=0.05, R=0.5, n_modes=2)
    ref = periodic_orbits(model, CosineLoad(0.3, 1.0))
    got = periodic_orbits(model, _Minimal(0.3, 1.0))
    assert len(ref) == len(got) == 2
    for a, b in zip(ref, got, strict=True):
        assert a.admissibility == b.admissibility
        np.testing.assert_allclose(b.phase, a.phase, rtol=0.0, atol=1e-10)
        np.testing.assert_allclose(b.impact_velocity, a.impact_velocity, rtol=1e-10)
        np.testing.assert_allclose(np.abs(b.multipliers), np.abs(a.multipliers), rtol=1e-8)
