"""One registry of the fast implementations and the reference implementations they are tested
against.

Several computations have a fast implementation (compiled, specialised, or lighter to import) and a
reference one that is simpler and slower; both give the same answer to rounding, and the tests hold
one to the other. Which one runs is chosen here, by name, never by module globals, and never by the
environment (whether numba's cache folder is writable, for instance, chooses nothing: numba then
compiles in memory). The fast implementation is the default.

================================  ===================================  ==================================
name                              fast (default)                       reference
================================  ===================================  ==================================
``loads.flow``                    compiled flows of Fourier and        numpy closed forms (``Load.flow``)
                                  piecewise-constant loads
``admissibility.bound``           compiled bound of ``|g''|`` inside   numpy bound
                                  the numpy admissibility search
``admissibility.search``          whole certified admissibility        numpy search (theory §5)
                                  search compiled (its interpreted
                                  twin, the same bits, for a
                                  process's first CPU second of
                                  calls while numba has no machine
                                  code of it)
``admissibility.rigid_cosine``    rigid bar's flights under a cosine   the certified search
                                  load: one zero of the velocity per
                                  arc of constant load sign
``orbits.rigid_scalar``           rigid-bar closed forms in plain      vectorised numpy closed forms on
                                  floats, one point                    1-element arrays
``orbits.rigid_arrays``           rigid-bar closed forms compiled,     vectorised numpy closed forms
                                  point by point over arrays
``orbits.rigid_segments``         rigid bar's multi-impact segment     the general segment problem's
                                  problem (``find_orbit``,             numpy evaluation (any ``N``)
                                  continuation) in plain floats
``simulate.impact_search``        specialised certified searches       general certified search
                                  after an impact                      (``find_crossing``)
``simulate.short_run``            a run's first block of impacts in    the general driver from the start
                                  one kernel call, the result built
                                  from its output when it ends the
                                  run in flight
``simulate.wave_separation``      compiled characteristics solver      Python solver (``wave_impact``)
                                  where contact is lost
``simulate.valve_rigid``          rigid bar under a position-          the general driver, piece by
                                  switched drive in scalar closed      piece (theory §10)
                                  forms
``simulate.valve_loop``           compiled valve loop under a          the valve's loop in Python, piece
                                  position-switched drive, every       by piece (theory §10)
                                  piece in one call
``wave.residual``                 compiled wave-law phase residual     ``wave_orbit_states`` phase by
                                  of a piecewise-constant load         phase
``wave.held_window``              a contact window held throughout     the characteristics solver's scan
                                  decided by a tabulated scan with a   (``wave_impact``)
                                  margin; its solver built on first
                                  use
``rock.blow``                     compiled loop of a blow on the rod   the numpy loop
                                  and the rock (theory §4d)
``sweeps.create_store``           sweep store written by zarr alone    store written by xarray's
                                                                       ``to_zarr``
================================  ===================================  ==================================

Examples
--------
>>> from impactbar.dynamics.implementations import use_fast, use_reference
>>> use_fast("simulate.impact_search")
True
>>> with use_reference("simulate.impact_search"):
...     use_fast("simulate.impact_search")
False

The choice is held in a :mod:`contextvars` variable: it applies to the current thread (and task)
and to nothing else, so concurrent runs do not see each other's choices. A thread started inside
the block starts with the defaults unless it runs in a copy of the context
(``contextvars.copy_context().run``).
"""

from __future__ import annotations

import contextvars
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["IMPLEMENTATIONS", "use_fast", "use_reference", "implementation", "choices"]

#: every switch, with what its fast implementation is (the reference is the table above)
IMPLEMENTATIONS: dict[str, str] = {
    "loads.flow": "compiled flows of Fourier and piecewise-constant loads",
    "admissibility.bound": "compiled bound of |g''| inside the numpy admissibility search",
    "admissibility.search": "whole certified admissibility search compiled (its interpreted twin first "
                            "while numba has no machine code of it)",
    "admissibility.rigid_cosine": "rigid bar's clearance under a cosine load from its velocity's zeros",
    "orbits.rigid_scalar": "rigid-bar closed forms in plain floats for one point",
    "orbits.rigid_arrays": "rigid-bar closed forms compiled, point by point over parameter arrays",
    "orbits.rigid_segments": "rigid-bar multi-impact segment problem in plain floats",
    "simulate.impact_search": "specialised certified searches after an impact",
    "simulate.short_run": "a run's first block in one kernel call, its result built from the kernel's output",
    "simulate.wave_separation": "compiled characteristics solver for contact windows that lose contact",
    "simulate.valve_rigid": "rigid bar under a position-switched drive in scalar closed forms",
    "simulate.valve_loop": "compiled valve loop under a position-switched drive",
    "wave.residual": "compiled wave-law phase residual of a piecewise-constant load",
    "wave.held_window": "contact window held throughout decided by a tabulated scan, solved when asked",
    "sweeps.create_store": "sweep store written by zarr alone (without xarray)",
    "rock.blow": "compiled loop of a blow on the rod and the rock",
}

_REFERENCE: contextvars.ContextVar[frozenset] = contextvars.ContextVar("impactbar_reference",
                                                                       default=frozenset())


def _check(names) -> frozenset:
    unknown = [n for n in names if n not in IMPLEMENTATIONS]
    if unknown:
        raise ValueError(f"unknown implementation switch(es) {unknown}; known: {list(IMPLEMENTATIONS)}")
    return frozenset(names)


def use_fast(name: str) -> bool:
    """Whether the fast implementation of ``name`` runs here (``False``: the reference).

    Raises
    ------
    ValueError
        If ``name`` is not one of :data:`IMPLEMENTATIONS`.
    """
    if name not in IMPLEMENTATIONS:
        _check([name])
    return name not in _REFERENCE.get()


def choices() -> dict[str, str]:
    """The implementation each switch takes here: ``{name: "fast" | "reference"}``."""
    ref = _REFERENCE.get()
    return {n: "reference" if n in ref else "fast" for n in IMPLEMENTATIONS}


@contextmanager
def implementation(name: str, choice: str = "reference") -> Iterator[None]:
    """Run the block with ``name`` switched to ``choice``, ``"fast"`` or ``"reference"``.

    Raises
    ------
    ValueError
        If ``name`` is unknown or ``choice`` is neither ``"fast"`` nor ``"reference"``.
    """
    names = _check([name])
    if choice not in ("fast", "reference"):
        raise ValueError(f"choice must be 'fast' or 'reference'; got {choice!r}")
    cur = _REFERENCE.get()
    token = _REFERENCE.set(cur | names if choice == "reference" else cur - names)
    try:
        yield
    finally:
        _REFERENCE.reset(token)


@contextmanager
def use_reference(*names: str) -> Iterator[None]:
    """Run the block with the reference implementations of ``names`` (all of them if none given).

    Raises
    ------
    ValueError
        If a name is not one of :data:`IMPLEMENTATIONS`.
    """
    chosen = _check(names) if names else frozenset(IMPLEMENTATIONS)
    token = _REFERENCE.set(_REFERENCE.get() | chosen)
    try:
        yield
    finally:
        _REFERENCE.reset(token)
