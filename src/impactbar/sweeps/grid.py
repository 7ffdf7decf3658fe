"""The grid of a sweep and its work chunks, shared by the dimensionless sweep spec
(:class:`~impactbar.sweeps.SweepSpec`) and a drifter's design map
(:class:`~impactbar.sweeps.DrifterMapSpec`)."""

from __future__ import annotations

import math

import numpy as np


class ChunkedGrid:
    """The outer product of ``axes`` (each with a ``size``), first axis slowest, cut into blocks of
    about ``chunk_points`` neighbouring points: what the store and the driver read of a spec."""

    @property
    def shape(self) -> tuple[int, ...]:
        """Grid shape, one entry per axis."""
        return tuple(a.size for a in self.axes)

    @property
    def n_points(self) -> int:
        return math.prod(self.shape)

    @property
    def chunk_shape(self) -> tuple[int, ...]:
        """Shape of a work chunk (and of the zarr chunks along the axes): the last axes are filled
        first, up to ``chunk_points`` points."""
        left = self.chunk_points
        out = []
        for n in reversed(self.shape):
            c = max(1, min(n, left))
            out.append(c)
            left = max(1, left // c)
        return tuple(reversed(out))

    @property
    def chunk_grid(self) -> tuple[int, ...]:
        """Number of chunks along each axis."""
        return tuple(-(-n // c) for n, c in zip(self.shape, self.chunk_shape, strict=True))

    @property
    def n_chunks(self) -> int:
        return math.prod(self.chunk_grid)

    def block(self, chunk: int) -> tuple[slice, ...]:
        """The block of the grid covered by work chunk ``chunk`` (C order over :attr:`chunk_grid`;
        not checked: :func:`impactbar.sweeps.chunk_slices` checks it)."""
        idx = np.unravel_index(chunk, self.chunk_grid)
        return tuple(slice(int(i) * c, min((int(i) + 1) * c, n))
                     for i, c, n in zip(idx, self.chunk_shape, self.shape, strict=True))
