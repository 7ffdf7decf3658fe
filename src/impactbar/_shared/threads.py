"""One BLAS thread for the small dense problems of this package.

The matrices here are small (the impact map's Jacobian is ``2 N + 2`` square); OpenBLAS spreading a
130 x 130 eigenproblem over threads is several times slower than one thread, and much worse on a
loaded machine. The limit is applied only inside our calls (``threadpoolctl``), never globally.
"""

from __future__ import annotations

import contextlib

__all__ = ["single_threaded_blas"]

_controller = None


def single_threaded_blas():
    """Context manager limiting BLAS to one thread (a no-op if threadpoolctl is missing)."""
    global _controller
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:  # pragma: no cover
        return contextlib.nullcontext()
    if _controller is None:
        _controller = ThreadpoolController()
    return _controller.limit(limits=1, user_api="blas")
