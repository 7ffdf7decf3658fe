"""The command line's note while numba compiles: :func:`impactbar._shared.compiling.compile_note`,
under the subcommand's name (the mechanism lives in ``_shared``, where the kernels' module starts
the same note for the Python API)."""

from __future__ import annotations

from .._shared.compiling import compile_note

__all__ = ["compile_note"]
