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


_BORROW = '''
import re
import numba
import numpy as np
from impactbar._shared.wrappers import internal_kernels


@numba.njit
def pick(a, b):
    return a[0] + b[1]


internal_kernels(globals(), python=("pick",))
pick(np.arange(3.0), np.arange(3.0))
ir = pick.inspect_llvm(pick.signatures[0])
# the kernel's own function (not its Python wrapper, whose name starts with cpython)
names = [f.split("(")[0] for f in ir.split("define ")[1:]]
(own,) = [f for f, n in zip(ir.split("define ")[1:], names) if "pick" in n and "cpython" not in n]
print(len(re.findall(r"NRT_incref\\(", own)), len(re.findall(r"NRT_decref\\(", own)))
'''


def test_a_kernel_borrows_the_arrays_it_is_given(tmp_path):
    """An argument never bound again takes no reference of its own: no count of its memory block on
    entry and none at its end, seen in the kernel's code before LLVM's optimisation (``NUMBA_OPT=0``,
    where numba's would count each array once up and once down)."""
    env = dict(os.environ, NUMBA_OPT="0", NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    out = subprocess.run([sys.executable, "-c", _BORROW], env=env, check=True, capture_output=True, text=True)
    assert out.stdout.split() == ["0", "0"]


def _counted():
    """Kernels that return an argument, bind one again, and hand views and a tuple of arrays to a
    link-only callee."""

    @numba.njit
    def head_sum(ws, n):
        a, b = ws
        s = 0.0
        for i in range(n):
            s += a[i:][0] + b[i:][0]
        return s

    @numba.njit
    def same(x):
        return x

    @numba.njit
    def tail_sum(x):
        x = x[1:]  # (bound again: its own reference)
        return head_sum((x, x), x.size)

    @numba.njit
    def mixed(x, y):
        z = same(x)
        return head_sum((z, y[:z.size]), z.size) + tail_sum(y)

    return {"__name__": head_sum.py_func.__module__, "head_sum": head_sum, "same": same,
            "tail_sum": tail_sum, "mixed": mixed}


def test_borrowed_arguments_keep_every_count():
    """Each array's count as before the calls, after many (a reference lost or one too many would
    show), and an argument returned is the caller's own (kept alive after the kernel's end)."""
    ns = _counted()
    internal_kernels(ns, python=("same", "tail_sum", "mixed"))
    x, y = np.arange(4.0), np.arange(6.0)
    before = sys.getrefcount(x), sys.getrefcount(y)
    for _ in range(1000):
        assert ns["mixed"](x, y) == (6.0 + 6.0) + 2 * 15.0  # (x and y[:4]; y[1:] twice)
    r = ns["same"](x)
    assert np.shares_memory(r, x)
    del r
    assert (sys.getrefcount(x), sys.getrefcount(y)) == before
    z = ns["same"](np.arange(3.0))  # (the only reference left: the kernel's result's)
    assert z.tolist() == [0.0, 1.0, 2.0]


_BORROW_TUPLE = '''
import re
import numba
import numpy as np
from impactbar._shared.wrappers import internal_kernels


@numba.njit
def pick(ws):
    a, b = ws
    c = ws[-1]
    s = 0.0
    for i in range(a.size):
        s += a[i] + b[i]
    return s + c[1]


internal_kernels(globals(), python=("pick",))
pick((np.arange(3.0), np.arange(3.0)))
ir = pick.inspect_llvm(pick.signatures[0])
names = [f.split("(")[0] for f in ir.split("define ")[1:]]
(own,) = [f for f, n in zip(ir.split("define ")[1:], names) if "pick" in n and "cpython" not in n]
print(len(re.findall(r"NRT_incref\\(", own)), len(re.findall(r"NRT_decref\\(", own)))
'''


def test_a_kernel_borrows_the_elements_of_a_tuple_it_is_given(tmp_path):
    """The arrays unpacked from a tuple argument, or taken from it by index, take no reference of
    their own: the kernel's code before LLVM's optimisation (``NUMBA_OPT=0``) counts nothing up or
    down (numba's counts the tuple unpacked, and each element, up and down again)."""
    env = dict(os.environ, NUMBA_OPT="0", NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    out = subprocess.run([sys.executable, "-c", _BORROW_TUPLE], env=env, check=True, capture_output=True,
                         text=True)
    assert out.stdout.split() == ["0", "0"]


def _elements():
    """Kernels that return an element of a tuple argument, store it into a new tuple they return,
    hand it and a slice of it to a link-only callee, and bind an element again."""

    @numba.njit
    def total(x):
        s = 0.0
        for v in x:
            s += v
        return s

    @numba.njit
    def first(ws):
        a, _ = ws
        return a

    @numba.njit
    def swapped(ws):
        a, b = ws
        return b, a

    @numba.njit
    def sums(ws, n):
        a, b = ws
        s = 0.0
        for i in range(n):
            c = ws[1]  # (bound at each pass, used in another block)
            if i > 0:
                s += total(c[i:])
            s += total(a) + total(b[:i])
        return s + total(c)

    @numba.njit
    def rebound(ws, n):
        a, b = ws
        if n > 0:
            a = a[n:]  # (bound again: then its own reference, at either binding)
        return a, total(a) + total(b)

    return {"__name__": total.py_func.__module__, "total": total, "first": first, "swapped": swapped,
            "sums": sums, "rebound": rebound}


def test_borrowed_elements_keep_every_count():
    """Each array's count as before the calls, after many, and an element returned, alone or in a
    new tuple, is the caller's own (kept alive after the tuple it came in is gone)."""
    ns = _elements()
    internal_kernels(ns, python=("first", "swapped", "sums", "rebound"))
    x, y = np.arange(4.0), np.arange(6.0)
    before = sys.getrefcount(x), sys.getrefcount(y)
    for _ in range(1000):
        assert ns["sums"]((x, y), 3) == 3 * 6.0 + (15.0 + 14.0) + (0.0 + 0.0 + 1.0) + 15.0
        for n in (0, 1):
            r, s = ns["rebound"]((x, y), n)
            assert r.size == 4 - n and s == 6.0 + 15.0 and np.shares_memory(r, x)
        assert np.shares_memory(ns["first"]((x, y)), x)
        b, a = ns["swapped"]((x, y))
        assert np.shares_memory(a, x) and np.shares_memory(b, y)
    del r, a, b
    assert (sys.getrefcount(x), sys.getrefcount(y)) == before
    z = ns["first"]((np.arange(3.0), np.arange(2.0)))  # (the only references left: the results')
    b, a = ns["swapped"]((np.arange(3.0), np.arange(2.0)))
    assert z.tolist() == a.tolist() == [0.0, 1.0, 2.0] and b.tolist() == [0.0, 1.0]
