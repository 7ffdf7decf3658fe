"""Kernels compiled for other kernels only (:func:`impactbar._shared.wrappers.internal_kernels`)."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap

import numba
import numpy as np
import pytest

from impactbar._shared.wrappers import internal_kernels


def _kernels():
    """A module's namespace: ``root_sum`` (called from Python) and its callee ``norm2``."""

    @numba.njit
    def norm2(x):
        s = 0.0
        for v in x:
            s += v * v
        return s

    @numba.njit
    def root_sum(ws):
        a, b = ws
        return math.sqrt(norm2(a) + norm2(b))

    return {"__name__": norm2.py_func.__module__, "norm2": norm2, "root_sum": root_sum}


def test_an_internal_kernel_computes_for_its_caller_and_refuses_python():
    ns = _kernels()
    assert internal_kernels(ns, python=("root_sum",)) == 1
    a, b = np.array([3.0, 1.0, 2.0]), np.array([0.5, -4.0])
    assert ns["root_sum"]((a, b)) == math.sqrt(np.dot(a, a) + np.dot(b, b))
    with pytest.raises(TypeError, match="without its Python wrapper"):
        ns["norm2"](a)
    # norm2 made no machine code of its own (its LLVM module went into root_sum's, which made some)
    (own,) = ns["norm2"].overloads.values()
    (caller,) = ns["root_sum"].overloads.values()
    jit = caller.library.codegen._engine._ee  # (llvmlite's execution engine: the modules it compiles)
    assert caller.library._final_module in jit._modules
    assert own.library._final_module not in jit._modules


def test_internal_kernels_names_only_the_modules_kernels():
    with pytest.raises(ValueError, match="python"):
        internal_kernels(_kernels(), python=("root_sum", "nothing"))
    with pytest.raises(ValueError, match="from_python"):
        internal_kernels(_kernels(), from_python="twin")


def test_a_link_only_kernel_called_from_python_compiles_a_kernel_of_its_own():
    """With ``from_python="compile"`` the callee stays link-only for its caller (no machine code of its
    own there) and a call from Python compiles it once more, whole, with the caller's numbers."""
    ns = _kernels()
    assert internal_kernels(ns, python=("root_sum",), from_python="compile") == 1
    a, b = np.array([3.0, 1.0, 2.0]), np.array([0.5, -4.0])
    assert ns["root_sum"]((a, b)) == math.sqrt(ns["norm2"](a) + ns["norm2"](b))
    assert ns["norm2"](a) == 14.0 and ns["norm2"](b) == 16.25  # (exact sums of squares)
    (own,) = ns["norm2"].overloads.values()
    whole = ns["norm2"]._impactbar_whole
    (mine,) = whole.overloads.values()
    jit = own.library.codegen._engine._ee
    assert own.library._final_module not in jit._modules  # (link-only still, for root_sum)
    assert mine.library._final_module in jit._modules  # (the kernel Python called: its machine code)
    ns["norm2"](b)
    assert ns["norm2"]._impactbar_whole is whole and len(whole.overloads) == 1  # (made once)


_MODULE = '''
import math
import numba
from impactbar._shared.wrappers import internal_kernels


@numba.njit(cache=True)
def norm2(x):
    s = 0.0
    for v in x:
        s += v * v
    return s


@numba.njit(cache=True)
def root_sum(ws):
    a, b = ws
    return math.sqrt(norm2(a) + norm2(b))


internal_kernels(globals(), python=("root_sum",))
'''

_RUN = '''
import json
import numpy as np
from numba.core import event
import kernels_mod

compiled = []


class Count(event.Listener):
    def on_start(self, ev):
        compiled.append(ev.data["dispatcher"].py_func.__name__)

    def on_end(self, ev):
        pass


event.register("numba:compile", Count())
r = kernels_mod.root_sum((np.array([3.0, 1.0, 2.0]), np.array([0.5, -4.0])))
print(json.dumps({"r": r.hex(), "compiled": compiled}))
'''


def test_a_cached_caller_needs_no_compile_of_its_internal_callees(tmp_path):
    """The caller's cache holds the callee's machine code: a second process compiles nothing."""
    (tmp_path / "kernels_mod.py").write_text(textwrap.dedent(_MODULE))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path)] + sys.path),
               NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    runs = [json.loads(subprocess.run([sys.executable, "-c", _RUN], env=env, check=True, capture_output=True,
                                      text=True).stdout.strip().splitlines()[-1]) for _ in range(2)]
    assert sorted(runs[0]["compiled"]) == ["norm2", "root_sum"]
    assert runs[1]["compiled"] == []
    cached = [f.name for f in (tmp_path / "cache").rglob("*.nbi")]  # (the index files: one per kernel)
    assert any("root_sum" in f for f in cached) and not any("norm2" in f for f in cached)
    expected = math.sqrt(3.0**2 + 1.0 + 2.0**2 + 0.25 + 16.0)
    assert float.fromhex(runs[0]["r"]) == float.fromhex(runs[1]["r"]) == pytest.approx(expected, rel=1e-15)


def test_link_only_makes_a_kernel_of_another_modules_function_internal():
    """:func:`link_only` on one dispatcher (a kernel made here from a function defined elsewhere):
    its caller computes with it, Python may not call it, and it made no machine code of its own."""
    from impactbar._shared.wrappers import link_only

    ns = _kernels()
    norm2 = link_only(ns["norm2"])
    a, b = np.array([3.0, 1.0, 2.0]), np.array([0.5, -4.0])
    assert ns["root_sum"]((a, b)) == math.sqrt(np.dot(a, a) + np.dot(b, b))
    with pytest.raises(TypeError, match="without its Python wrapper"):
        norm2(a)
    (own,) = norm2.overloads.values()
    (caller,) = ns["root_sum"].overloads.values()
    jit = caller.library.codegen._engine._ee
    assert caller.library._final_module in jit._modules
    assert own.library._final_module not in jit._modules


def test_an_internal_jitable_is_python_for_python_and_link_only_for_kernels():
    """:func:`internal_jitable`: the function itself for Python; a kernel compiles it into its own
    code, its implementation with no machine code and no wrappers of its own."""
    from numba.core import event

    from impactbar._shared.wrappers import internal_jitable

    def hypot3(x, y, z):
        return math.sqrt(x * x + y * y + z * z)

    assert internal_jitable(hypot3) is hypot3
    assert hypot3(2.0, 3.0, 6.0) == 7.0  # (plain Python)

    @numba.njit
    def caller(v):
        return hypot3(v[0], v[1], v[2]) + 1.0

    compiled = []

    class Listen(event.Listener):
        def on_start(self, ev):
            pass

        def on_end(self, ev):
            compiled.append(ev.data["dispatcher"])

    with event.install_listener("numba:compile", Listen()):
        assert caller(np.array([1.0, 4.0, 8.0])) == 10.0
    (impl,) = [d for d in compiled if d.py_func is hypot3]
    (own,) = impl.overloads.values()
    assert own.fndesc is not None and own.library.get_pointer_to_function(own.fndesc.llvm_func_name) == 0
    assert not own.library._final_module.get_function(own.fndesc.llvm_func_name).is_declaration
    functions = own.library._final_module.functions
    wrappers = [f.name for f in functions if f.name.startswith(("cpython.", "cfunc."))]
    assert wrappers == []
    (top,) = caller.overloads.values()
    jit = top.library.codegen._engine._ee
    assert top.library._final_module in jit._modules and own.library._final_module not in jit._modules
