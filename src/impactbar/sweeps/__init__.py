"""Parameter sweeps and Monte Carlo on ``dask.distributed``, stored chunk by chunk in zarr.

A sweep is described by a :class:`SweepSpec` (usually read from a TOML file with :func:`load_spec`):
a task, a machine (the dimensionless bar and its load, or a drifter's config in SI) and axes, each
sweeping one scalar parameter of it. The grid is the outer product of the axes, cut into blocks of
neighbouring points ("chunks"); :func:`compute_chunk` computes one chunk from plain arguments (no
dask, no storage) and :func:`run_sweep` farms the chunks out to a ``dask.distributed`` cluster and
writes each one into a zarr store as soon as it arrives. A sweep whose every point takes the rigid
bar's vectorised closed forms (:func:`impactbar.sweeps.spec.closed_form_task`) is computed in
threads of the driver instead, by default: starting a cluster would cost more than the whole work.

Tasks
-----
``orbits``
    :func:`impactbar.periodic_orbits` at every point: ``phase``, ``admissible``, ``stable``,
    ``schur_stable``, ``max_abs_multiplier``, ``impact_velocity`` along an ``orbit`` dimension
    (padded with NaN / False) and ``n_orbits``.
``montecarlo``
    :func:`impactbar.simulation.experiments.run_experiment` at every point: ``starts`` seeded random starts of
    ``periods`` load periods each, the long-run motion of each classified
    (:func:`impactbar.simulation.experiments.classify`); ``fraction`` of each class along a ``motion``
    dimension and the impact-interval statistics.
``bifurcation``
    One long run from a seeded random start at every point; the velocities and load phases of the
    last ``keep`` impacts along an ``impact`` dimension (a brute-force bifurcation diagram).

Store layout and resumption
---------------------------
The whole store (every variable, its fill value, a zarr chunk grid equal to the work chunks, the
spec and the package version as attributes) is created up front, into a temporary folder that is
renamed into place, so a store either exists complete or not at all. Each finished chunk is
written into its own zarr chunks; only then its entry of ``chunk_done`` (one ``int8`` per chunk) is
set. zarr's local store replaces files atomically, so a run killed at any moment, SIGKILL included,
loses only the chunks in flight. Rerunning resumes: the stored spec must equal the requested one,
and only chunks whose flag is set *and* whose data, read back, match their stored CRC-32
(``chunk_checksum``) are kept; every other chunk (missing, truncated, corrupted) is recomputed. A
lock file next to the store keeps a second driver out. Every random start is seeded from the spec's
``seed`` and the point's flat index in the grid (``numpy.random.SeedSequence([seed, index])``),
never from the chunk order or the worker, so a resumed sweep equals an uninterrupted one.

Design maps of a drifter
------------------------
The same :class:`SweepSpec` with a top-level ``config`` (a drifter's TOML file or preset) is a design
map over 1 to 3 of its SI config keys (:mod:`impactbar.sweeps.map_spec`), task ``operating_point``
(or ``settle``): the operating point at every point, each continued from its neighbour, stored in SI
through the same store and driver; :func:`run_map` then records the edges (:func:`map_edges`).

Layout: ``spec`` (the one spec class, its TOML schema), ``bar_spec`` (the dimensionless bar's
tables), ``map_spec`` (a drifter's config keys), ``tasks`` (one chunk's work), ``store`` (zarr layout, done
flags), ``run`` (the driver: dask, or threads), ``numba_cache`` (the workers' shared numba cache),
``plot`` (figures from a finished store; the only module that imports matplotlib). This layer sits
on the core and imports dask, xarray and zarr lazily; the core never imports it.
"""

from __future__ import annotations

import sys

from .._shared.renamed import renamed
from .grid import TASKS as TASKS
from .grid import Axis as Axis
from .maps import map_edges as map_edges
from .maps import run_map as run_map
from .numba_cache import numba_cache_plugin as numba_cache_plugin
from .numba_cache import use_numba_cache as use_numba_cache
from .plot import plot_sweep as plot_sweep
from .run import NoWorkersError as NoWorkersError
from .run import SweepRun as SweepRun
from .run import run_sweep as run_sweep
from .spec import LOAD_KINDS as LOAD_KINDS
from .spec import SweepSpec as SweepSpec
from .spec import load_spec as load_spec
from .spec import motion_classes as motion_classes
from .spec import parse_spec as parse_spec
from .store import open_sweep as open_sweep
from .store import point_done as point_done
from .store import stored_spec as stored_spec
from .store import sweep_progress as sweep_progress
from .tasks import chunk_slices as chunk_slices
from .tasks import compute_chunk as compute_chunk

__all__ = [
    "TASKS",
    "LOAD_KINDS",
    "Axis",
    "SweepSpec",
    "SweepRun",
    "load_spec",
    "parse_spec",
    "motion_classes",
    "chunk_slices",
    "compute_chunk",
    "run_sweep",
    "numba_cache_plugin",
    "use_numba_cache",
    "NoWorkersError",
    "open_sweep",
    "point_done",
    "stored_spec",
    "sweep_progress",
    "plot_sweep",
    "run_map",
    "map_edges",
]


def __getattr__(name: str):
    if (value := renamed(sys.modules[__name__], name)) is not None:
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
