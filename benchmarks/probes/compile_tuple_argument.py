"""What a tuple of 26 arrays costs numba's compiler: three nested kernels that unpack a heterogeneous
26-array workspace tuple (as the exact rod-rock kernels pass ``ws``) against the same kernels taking the
four arrays they use.

Run: ``python benchmarks/probes/compile_tuple_argument.py`` (a fresh process; no cache is used).
"""

from __future__ import annotations

import time

import numba as nb
import numpy as np

N = 26
NAMES = ", ".join(f"a{i}" for i in range(N))
BODY = """
    s = 0.0
    for i in range(3):
        s += a1[i] * x + a2[i] - a7[i]
        if s > 1.0:
            a4[i] = s
"""
TUPLE = f"""
def h(ws, x):
    ({NAMES},) = ws
{BODY}
    return s
def g(ws, x):
    ({NAMES},) = ws
{BODY}
    return s + h(ws, x)
def f(ws, x):
    ({NAMES},) = ws
{BODY}
    return s + g(ws, x) + h(ws, x)
"""
FOUR = f"""
def h(a1, a2, a4, a7, x):
{BODY}
    return s
def g(a1, a2, a4, a7, x):
{BODY}
    return s + h(a1, a2, a4, a7, x)
def f(a1, a2, a4, a7, x):
{BODY}
    return s + g(a1, a2, a4, a7, x) + h(a1, a2, a4, a7, x)
"""


def kernels(source):
    """The three kernels of ``source``, jitted (``f`` calls ``g`` and ``h``, ``g`` calls ``h``)."""
    ns: dict = {}
    exec(source, ns)
    for name in ("h", "g", "f"):
        ns[name] = nb.njit(ns[name])
    return ns["f"]


def cpu(fn, *args):
    t = time.process_time()
    fn(*args)
    return time.process_time() - t


def main():
    ws = tuple(np.zeros((4, 4)) if i % 5 == 0 else np.zeros(10, np.int64) if i % 3 == 0 else np.zeros(10)
               for i in range(N))
    nb.njit(lambda x: x + 1.0)(1.0)  # numba's own first-use cost out of the way
    a = cpu(kernels(TUPLE), ws, 1.0)
    b = cpu(kernels(FOUR), ws[1], ws[2], ws[4], ws[7], 1.0)
    print(f"three kernels: a heterogeneous {N}-array tuple {a:.3f} s of CPU; the four arrays {b:.3f} s")


if __name__ == "__main__":
    main()
