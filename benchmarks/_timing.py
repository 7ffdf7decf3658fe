"""The benchmarks' shared timer: the median wall time of a call after one warm-up call (numba's
compilation, caches). Imported by the scripts of this folder (run as ``python benchmarks/...``)."""

from __future__ import annotations

import time

import numpy as np


def median_time(fn, repeat: int) -> float:
    """Median of ``repeat`` timed calls of ``fn()`` (seconds), after one untimed call."""
    fn()
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return float(np.median(ts))
