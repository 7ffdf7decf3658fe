"""Argument checks shared by the public classes: every failure is a ``ValueError`` naming the
parameter and its allowed range."""

from __future__ import annotations

import math
import numbers

import numpy as np

__all__ = ["check_real", "check_int", "check_complex_array"]


def check_real(
    name: str,
    value,
    *,
    lo: float | None = None,
    hi: float | None = None,
    lo_open: bool = False,
    hi_open: bool = False,
) -> float:
    """Return ``value`` as a finite float, or raise ``ValueError`` naming ``name`` and its range."""
    if type(value) is float and math.isfinite(value) and (lo is None or lo < value) \
            and (hi is None or value < hi):  # the common case, inside the range
        return value
    if isinstance(value, bool) or not isinstance(value, numbers.Real | np.floating | np.integer):
        rng = _range_text(lo, hi, lo_open, hi_open)
        raise ValueError(f"{name} must be a real number {rng}; got {value!r} ({type(value).__name__})")
    try:
        v = float(value)
    except OverflowError:  # an int beyond the float range
        rng = _range_text(lo, hi, lo_open, hi_open)
        raise ValueError(f"{name} must be a finite real number {rng}; got an integer beyond the "
                         "float range") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be a finite real number {_range_text(lo, hi, lo_open, hi_open)}; "
                         f"got {v}")
    bad = (
        (lo is not None and (v < lo or (lo_open and v == lo)))
        or (hi is not None and (v > hi or (hi_open and v == hi)))
    )
    if bad:
        raise ValueError(f"{name} must be {_range_text(lo, hi, lo_open, hi_open)}; got {v}")
    return v


def check_int(name: str, value, *, lo: int | None = None, hi: int | None = None) -> int:
    """Return ``value`` as an int, or raise ``ValueError`` naming ``name`` and its range."""
    if type(value) is int and (lo is None or lo <= value) and (hi is None or value <= hi):
        return value  # the common case, inside the range
    if isinstance(value, bool) or not isinstance(value, numbers.Integral | np.integer):
        rng = _range_text(lo, hi, False, False)
        raise ValueError(f"{name} must be an integer {rng}; got {value!r} ({type(value).__name__})")
    v = int(value)
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        raise ValueError(f"{name} must be an integer {_range_text(lo, hi, False, False)}; got {v}")
    return v


def check_complex_array(name: str, value) -> np.ndarray:
    """Return ``value`` as a finite 1-d complex array, or raise ``ValueError``."""
    try:
        arr = np.atleast_1d(np.asarray(value, dtype=complex))
    except (TypeError, ValueError, OverflowError) as exc:
        raise ValueError(f"{name} must be a 1-d sequence of complex numbers; got {value!r}") from exc
    if arr.ndim != 1:
        raise ValueError(f"{name} must be 1-d; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must contain only finite numbers; got {arr}")
    return arr


def _range_text(lo, hi, lo_open, hi_open) -> str:
    if lo is None and hi is None:
        return "(any finite value)"
    left = "(" if lo_open else "["
    right = ")" if hi_open else "]"
    a = "-inf" if lo is None else f"{lo:g}"
    b = "inf" if hi is None else f"{hi:g}"
    if lo is None:
        left = "("
    if hi is None:
        right = ")"
    return f"in {left}{a}, {b}{right}"
