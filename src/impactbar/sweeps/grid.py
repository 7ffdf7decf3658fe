"""The grid of a sweep and its work chunks, shared by the dimensionless sweep spec
(:class:`~impactbar.sweeps.SweepSpec`) and a drifter's design map
(:class:`~impactbar.sweeps.DrifterMapSpec`)."""

from __future__ import annotations

import math

import numpy as np

#: most grid points a sweep or a map may have: the driver, the edges and the plots read whole
#: variables of the grid (800 MB a float64 variable at this size), and a point costs from a
#: microsecond (the rigid closed forms) to a second (a drifter's orbit)
MAX_GRID_POINTS = 10**8
#: most work chunks: each is a task on the cluster, and its flag and checksum are held in memory
MAX_CHUNKS = 10**6


def check_points(axes) -> None:
    """Refuse axes (each with a ``name`` and a ``size``) whose outer product has more than
    :data:`MAX_GRID_POINTS` points: a ``ValueError`` naming the axes and their product. Cheap: a spec
    asks it before it checks each axis value (a point built per value: hours on a mistyped size).

    Raises
    ------
    ValueError
        Too many points.
    """
    n = math.prod(a.size for a in axes)
    if n > MAX_GRID_POINTS:
        sizes = " x ".join(f"{a.name} ({a.size})" for a in axes)
        raise ValueError(f"[axes] {sizes} make {n} grid points; the limit is {MAX_GRID_POINTS}: fewer "
                         "values along an axis")


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

    def check_grid(self) -> None:
        """Refuse a grid of more than :data:`MAX_GRID_POINTS` points or :data:`MAX_CHUNKS` work
        chunks (a ``ValueError`` naming the axes and their product), before anything is created."""
        check_points(self.axes)
        sizes = " x ".join(f"{a.name} ({a.size})" for a in self.axes)
        if self.n_chunks > MAX_CHUNKS:
            raise ValueError(f"chunk_points = {self.chunk_points}: the {self.n_points} grid points of "
                             f"[axes] {sizes} make {self.n_chunks} work chunks; the limit is "
                             f"{MAX_CHUNKS}: raise chunk_points")

    def block(self, chunk: int) -> tuple[slice, ...]:
        """The block of the grid covered by work chunk ``chunk`` (C order over :attr:`chunk_grid`;
        not checked: :func:`impactbar.sweeps.chunk_slices` checks it)."""
        idx = np.unravel_index(chunk, self.chunk_grid)
        return tuple(slice(int(i) * c, min((int(i) + 1) * c, n))
                     for i, c, n in zip(idx, self.chunk_shape, self.shape, strict=True))
