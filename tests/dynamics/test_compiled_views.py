"""Frozen loads, the one kernel view through which a load enters compiled code, the compiled
kernels' argument lists, and the registry of fast and reference implementations."""

from __future__ import annotations

import ast
import contextvars
import dataclasses
import importlib
import importlib.util
import inspect
import os
import pathlib
import pkgutil
import subprocess
import sys
import threading
from pathlib import Path

import numba
import numpy as np
import pytest

import impactbar
from impactbar import (
    BarModel,
    CosineLoad,
    FourierLoad,
    InitialState,
    PiecewiseConstantLoad,
    SquareWaveLoad,
    simulate,
)
from impactbar.dynamics.compiled_views import LoadKernelView
from impactbar.dynamics.implementations import (
    IMPLEMENTATIONS,
    choices,
    implementation,
    use_fast,
    use_reference,
)

#: every module of the core that defines compiled kernels, found by walking the package (a new kernel
#: module is checked without being listed here)
KERNEL_MODULES = sorted(
    m.name for m in pkgutil.walk_packages(impactbar.__path__, "impactbar.")
    if m.name.split(".")[1] in ("dynamics", "orbits", "laws", "simulation")
    and "numba" in Path(importlib.util.find_spec(m.name).origin).read_text())

LOADS = {
    "FourierLoad": lambda: FourierLoad(0.5, [1.0, 0.2j]),
    "CosineLoad": lambda: CosineLoad(0.5, 1.0, 2),
    "PiecewiseConstantLoad": lambda: PiecewiseConstantLoad([0.0, 1.0, 3.0], [1.0, -0.5, 0.2]),
    "SquareWaveLoad": lambda: SquareWaveLoad(1.0, 1.3),
}
ATTRIBUTES = ["p0", "pk", "k", "q", "kappa", "breaks", "levels", "coefficients", "orders", "amplitudes",
              "_pk", "_k", "_kmax", "_b", "_lv", "_T", "kernel_view", "new_attribute"]


def _dispatchers():
    for name in KERNEL_MODULES:
        mod = importlib.import_module(name)
        for attr, obj in vars(mod).items():
            if isinstance(obj, numba.core.dispatcher.Dispatcher) and obj.__module__ == name:
                yield f"{name}.{attr}", obj


# -- frozen loads ---------------------------------------------------------------------------------
@pytest.mark.parametrize("cls", list(LOADS))
@pytest.mark.parametrize("attr", ATTRIBUTES)
def test_assigning_or_deleting_any_load_attribute_raises(cls, attr):
    load = LOADS[cls]()
    before = repr(load), load(np.linspace(0.0, 6.0, 7))
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(load, attr, 3.0)
    with pytest.raises(AttributeError):
        delattr(load, attr)
    assert repr(load) == before[0]
    np.testing.assert_array_equal(load(np.linspace(0.0, 6.0, 7)), before[1])


@pytest.mark.parametrize("cls", list(LOADS))
def test_load_arrays_are_read_only(cls):
    load = LOADS[cls]()
    arrays = [v for v in vars(load).values() if isinstance(v, np.ndarray)]
    assert arrays and all(not a.flags.writeable for a in arrays)
    for a in arrays:
        with pytest.raises(ValueError):
            a[...] = 0.0


def test_pk_assignment_refused_and_each_load_simulated_as_itself():
    """A reported case: ``l.pk = 3.0`` was accepted while the simulator kept integrating pk = 1 (a
    cache keyed by ``id(load)``). It is refused now, and a fresh CosineLoad(0.5, 3.0) simulated after
    CosineLoad(0.5, 1.0) gets its own answer, equal to a run in a clean cache."""
    S = importlib.import_module("impactbar.simulation._core")
    model = BarModel(1.37, 0.02, 0.8, 2)
    start = InitialState.rigid(-0.1, 0.0, 2)
    one = CosineLoad(0.5, 1.0)
    with pytest.raises(AttributeError):
        one.pk = 3.0
    assert one.pk == 1.0 and repr(one) == "CosineLoad(p0=0.5, pk=1.0, k=1)" and float(one(0.0)) == 1.5
    run_one = simulate(model, one, start, 20.0)
    run_three = simulate(model, CosineLoad(0.5, 3.0), start, 20.0)
    S._CORES.clear()
    clean_three = simulate(model, CosineLoad(0.5, 3.0), start, 20.0)
    np.testing.assert_array_equal(run_three.impact_times, clean_three.impact_times)
    np.testing.assert_array_equal(run_three.impact_velocities, clean_three.impact_velocities)
    assert run_three.n_impacts != run_one.n_impacts or not np.array_equal(run_three.impact_velocities,
                                                                          run_one.impact_velocities)


def test_loads_compare_and_hash_by_value():
    assert CosineLoad(0.5, 1.0) == CosineLoad(0.5, 1.0)
    assert hash(CosineLoad(0.5, 1.0)) == hash(CosineLoad(0.5, 1.0))
    assert CosineLoad(0.5, 1.0) != CosineLoad(0.5, 1.0, 2) != CosineLoad(0.5, 3.0)
    assert CosineLoad(0.5, 1.0) != FourierLoad(0.5, [1.0])  # another class: not the same drive
    assert SquareWaveLoad(1.0, 1.3) == SquareWaveLoad(1.0, 1.3) != SquareWaveLoad(1.0, 1.4)
    assert PiecewiseConstantLoad([0.0, 1.0], [1.0, 2.0]) != PiecewiseConstantLoad([0.0, 1.0], [1.0, 2.5])
    assert len({CosineLoad(0.5, 1.0), CosineLoad(0.5, 1.0), SquareWaveLoad(1.0, 1.3)}) == 2


def test_a_pickled_load_hashes_as_an_equal_load_in_another_process():
    """The hash cached on a load is not pickled: hashes of bytes differ between processes."""
    import pickle

    load = FourierLoad(0.5, [1.0, 0.2j])
    hash(load)
    code = ("import pickle, sys; from impactbar import FourierLoad\n"
            "l = pickle.loads(sys.stdin.buffer.read())\n"
            "print({l: 1}.get(FourierLoad(0.5, [1.0, 0.2j])), l == FourierLoad(0.5, [1.0, 0.2j]))")
    env = {**os.environ, "PYTHONHASHSEED": "12345", "PYTHONPATH": os.pathsep.join(sys.path)}
    out = subprocess.run([sys.executable, "-c", code], input=pickle.dumps(load), capture_output=True,
                         check=True, env=env)
    assert out.stdout.decode().split() == ["1", "True"]


# -- the kernel view ------------------------------------------------------------------------------
@pytest.mark.parametrize("cls", list(LOADS))
def test_kernel_view_holds_the_load(cls):
    """The view against the load's own methods: harmonics, pieces and bounds."""
    load = LOADS[cls]()
    view = load.kernel_view
    assert isinstance(view, LoadKernelView) and load.kernel_view is view  # built once
    assert view.p0 == load.p0 and view.psup == pytest.approx(load.sup_abs, rel=1e-15)
    assert view.posc == pytest.approx(load.sup_oscillation, rel=1e-15)
    t = np.linspace(0.0, 2 * np.pi, 50, endpoint=False)
    if view.kind == 0:
        pk = load.harmonics()
        np.testing.assert_array_equal(view.pr + 1j * view.pim, pk[pk != 0])
        p = view.p0 + (np.exp(1j * np.outer(t, view.ks)) @ (view.pr + 1j * view.pim)).real
        assert view.p1 == pytest.approx(float(np.sum(view.ks * np.abs(pk[pk != 0]))), rel=1e-15)
    else:
        np.testing.assert_array_equal(view.breaks, load.breaks)
        np.testing.assert_array_equal(view.levels, load.levels)
        p = view.levels[np.searchsorted(view.breaks, t, side="right") - 1]
        assert view.spread == np.ptp(load.levels)
    np.testing.assert_allclose(p, load(t), rtol=1e-14, atol=1e-14)
    # writable private copies: one numba type for every load, and the load's own arrays untouched
    for a in (view.ks, view.pr, view.pim, view.breaks, view.levels):
        assert a.flags.writeable and a.flags.c_contiguous and a.dtype == float


@pytest.mark.parametrize("k", [1, 3, 10, 4096])
@pytest.mark.parametrize("pk", [1.0, -0.37, 2.5e-7, 3.0 - 4.0j])
def test_a_one_harmonic_view_is_the_sums_of_numpy_to_the_bit(k, pk):
    """The view of one harmonic (the pneumatic load's, made for every load factor of a chart) holds
    what numpy's sums over the harmonics give, to the bit: the kernels' bounds (and so every result
    that passes through them) do not depend on which way the view was made."""
    ks, pks = np.array([float(k)]), np.array([pk], dtype=complex)
    view = LoadKernelView.fourier(-0.6, ks, pks)
    a = np.abs(pks)
    want = (0.6 + float(np.sum(a)), float(np.sum(ks * a)), float(np.sum(ks**2 * a)), float(np.sum(ks**3 * a)),
            float(np.sum(a)))
    got = (view.psup, view.p1, view.p2, view.p3, view.posc)
    assert [g.hex() for g in got] == [w.hex() for w in want]
    assert (view.kind, view.p0, view.spread) == (0, -0.6, 0.0)
    assert view.pr.tolist() == [complex(pk).real] and view.pim.tolist() == [complex(pk).imag]
    for arr in view[2:7]:
        assert arr.flags.writeable and arr.flags.c_contiguous and arr.dtype == float
    assert view.ks is not ks  # a private copy
    two = LoadKernelView.fourier(-0.6, [1.0, float(k)], [0.5, pk])  # the general sums
    assert two.p1 == pytest.approx(0.5 + k * abs(pk), rel=1e-15)


def test_no_compiled_kernel_takes_more_than_12_arguments():
    counts = {name: len(inspect.signature(d.py_func).parameters) for name, d in _dispatchers()}
    assert len(counts) > 40
    assert {name: n for name, n in counts.items() if n > 12} == {}


#: numpy functions whose numba implementation compiles a generic routine of its own on a first run
#: (np.sort's quicksort 1.3 s of CPU time, np.max's reduction 0.5 s)
_SLOW_TO_COMPILE = {"sort", "argsort", "max", "min", "amax", "amin"}


def _slow_to_compile(fn):
    """The lines of ``fn`` that call such a numpy function or assign an array to a slice (``a[:n] =
    b``: numba's broadcasting setitem with its error messages, 2.2 s on a first run; a slice filled
    with a number is cheap)."""
    tree = ast.parse(inspect.getsource(fn).lstrip())
    found = []
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                and isinstance(node.func.value, ast.Name) and node.func.value.id == "np"
                and node.func.attr in _SLOW_TO_COMPILE):
            found.append(node.lineno)
        if isinstance(node, ast.Assign | ast.AugAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            sliced = any(isinstance(t, ast.Subscript)
                         and any(isinstance(n, ast.Slice) for n in ast.walk(t.slice)) for t in targets)
            number = isinstance(node.value, ast.Constant) or (
                isinstance(node.value, ast.UnaryOp) and isinstance(node.value.operand, ast.Constant))
            if sliced and not number:
                found.append(node.lineno)
    return found


def test_slow_to_compile_finds_a_planted_use():
    def planted(a, b, n):  # pragma: no cover - parsed, never run
        a[:] = 0.0
        a[:n] = b[:n]
        return np.max(a) + np.sort(b)[0]

    assert _slow_to_compile(planted) == [3, 4, 4]


def test_no_compiled_kernel_uses_what_is_slow_to_compile():
    """A first run compiles every kernel it calls; numba's own np.sort, np.max, np.min and array
    slice assignment add seconds to it, so the kernels write those few loops out."""
    found = {name: _slow_to_compile(d.py_func) for name, d in _dispatchers()}
    assert {name: lines for name, lines in found.items() if lines} == {}


def test_sort_head_sorts_as_numpy():
    from impactbar.dynamics._flight import sort_head

    rng = np.random.default_rng(3)
    for n in (0, 1, 2, 7, 40):
        a = np.concatenate((rng.uniform(-1.0, 1.0, n), [5.0, 6.0]))
        a[: n // 3] = a[n // 2: n // 2 + n // 3]  # some equal values
        want = np.sort(a[:n])
        got = sort_head(a, n)
        assert got.size == n and np.array_equal(got, want) and np.array_equal(a[n:], [5.0, 6.0])


def test_the_kernel_view_is_the_only_path_from_a_load_into_compiled_code():
    """No module but the loads' own (``loads/``) reads a load's private attributes; no kernel that Python code
    calls takes a load's fields as separate arguments; and after simulations and orbit searches
    under both kinds of load, each entry kernel has one compiled signature, with the load's view in
    it (passed as the plain tuple of a LoadKernelView: one specialisation serves every load)."""
    root = pathlib.Path(impactbar.__file__).parent
    private = []
    for path in root.rglob("*.py"):
        if path.parent.name == "loads":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if (isinstance(node, ast.Attribute) and node.attr.startswith("_")
                    and not node.attr.startswith("__") and isinstance(node.value, ast.Name)
                    and "load" in node.value.id.lower()):
                private.append(f"{path.relative_to(root)}:{node.lineno} {node.value.id}.{node.attr}")
    assert private == []
    fields = {"kind", "p0", "ks", "pr", "pim", "breaks", "levels", "psup", "lk"}
    entries = ["run_free", "find_crossing", "propagate_many", "wave_window", "window_moments",
               "wave_contact", "square_wave_residuals", "admissibility_search", "modal_crossing"]
    kernels = dict(_dispatchers())
    for name in entries:
        (full, disp), = [(k, d) for k, d in kernels.items() if k.endswith("." + name)]
        assert not fields & set(inspect.signature(disp.py_func).parameters), full
    # in a fresh process, so that no other test's direct kernel calls add signatures
    code = """
from impactbar.dynamics.compiled import disable_tiers
disable_tiers()  # every kernel compiled on its first call (the admissibility search too, cache or not)
import numba, impactbar.orbits._admissibility_search as A
import impactbar.dynamics._event_loop as K, impactbar.laws.wave._window as KW
from impactbar import *  # noqa: F403
for impact in ("paper", "wave"):
    model = BarModel(4.0, 0.05, 0.6, 3, impact=impact)
    for load in (CosineLoad(0.6, 1.0), SquareWaveLoad(1.0, 1.3), FourierLoad(0.5, [1.0, 0.0, 0.2j])):
        periodic_orbits(model, load)
        simulate(model, load, InitialState.rigid(-0.2, 0.0, 3), 30.0)
view = numba.typeof(tuple(CosineLoad(0.6, 1.0).kernel_view))
for d in (K.run_free, K.propagate_many, KW.wave_window, A.admissibility_search):
    sig = d.signatures[0]
    print(len(d.signatures), sig[0] == view or sig[-1].types[0] == view)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert out.stdout.split() == ["1", "True"] * 4



@pytest.mark.slow  # compiles the wave law's simulate from an empty cache (about 20 s of CPU time)
def test_the_wave_kernels_and_the_crossing_search_compile_once_per_run(tmp_path):
    """A literal flag (``True``, ``0``) passed to a kernel is a signature of its own, and a wrapper
    kernel compiles its callee again: after wave-law runs under both kinds of load (in a fresh
    process with an empty numba cache, so that the helpers compile rather than load with their
    caller), the wave law's helpers, the crossing search, the flow and the sort of the window's
    jumps (``sort_head``: its count starts as the literal 0) each hold one signature."""
    code = """
import impactbar.dynamics._event_loop as K, impactbar.laws.wave._separation as WK
import impactbar.dynamics._flight as FK
from impactbar import *  # noqa: F403
for n, load in ((8, CosineLoad(0.6, 1.0)), (16, SquareWaveLoad(0.8, 1.0))):
    simulate(BarModel(5.0, 0.1, 0.5, n, impact="wave"), load, InitialState.rigid(-0.2, 0.0, n), 40.0)
for d in (WK.wave_contact, WK._p, WK._A, WK._f, WK._brent, WK._project_free, K.find_crossing,
          K.propagate_many, FK.sort_head):
    print(len(d.signatures))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path),
                              "NUMBA_CACHE_DIR": str(tmp_path)})
    assert out.stdout.split() == ["1"] * 9

# -- implementations ------------------------------------------------------------------------------
def test_registry_switches_by_name_only_where_asked():
    assert all(use_fast(n) for n in IMPLEMENTATIONS)
    with use_reference("simulate.impact_search"):
        assert not use_fast("simulate.impact_search") and use_fast("loads.flow")
        with implementation("simulate.impact_search", "fast"):
            assert use_fast("simulate.impact_search")
        assert choices()["simulate.impact_search"] == "reference"
    with use_reference():
        assert not any(use_fast(n) for n in IMPLEMENTATIONS)
    assert set(choices().values()) == {"fast"}
    with pytest.raises(ValueError, match="unknown"):
        use_fast("simulate.no_such_switch")
    with pytest.raises(ValueError, match="unknown"), use_reference("FAST_SEARCH"):
        pass
    with pytest.raises(ValueError, match="choice"), implementation("loads.flow", "slow"):
        pass


def test_registry_choice_is_per_thread():
    seen = {}
    gate = threading.Event()

    def other():
        gate.wait(5)
        seen["other"] = use_fast("admissibility.search")

    th = threading.Thread(target=other)
    th.start()
    with use_reference("admissibility.search"):
        gate.set()
        th.join(5)
        seen["here"] = use_fast("admissibility.search")
        seen["copied"] = contextvars.copy_context().run(use_fast, "admissibility.search")
    assert seen == {"other": True, "here": False, "copied": False}


def test_no_module_global_chooses_an_implementation():
    """The old switches are gone from the package (the registry replaced them)."""
    from impactbar.laws.wave import periodic as wave
    from impactbar.orbits import admissibility, one_impact
    from impactbar.sweeps import store

    S = importlib.import_module("impactbar.simulation.simulate")

    old = [(impactbar.loads, "_COMPILED_FLOW"), (admissibility, "_COMPILED_BOUND"),
           (admissibility, "_COMPILED_SEARCH"), (one_impact, "RIGID_SCALAR"), (S, "FAST_SEARCH"),
           (S, "FAST_WAVE_SEPARATION"), (wave, "_COMPILED_RESIDUAL"), (store, "CREATE_WITH_XARRAY")]
    assert [name for mod, name in old if hasattr(mod, name)] == []
