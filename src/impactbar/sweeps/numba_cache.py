"""A cluster's workers reading one shared numba cache, filled once, instead of compiling on every node.

numba compiles each kernel on its first call in a process whose cache does not hold it, and finds
its cache in the folder the environment variable ``NUMBA_CACHE_DIR`` names when the kernel's module
is imported. :func:`numba_cache_plugin` is a dask worker plugin that sets that variable in each
worker process when it is registered (and in each worker that joins later), before the worker's
first task imports impactbar's kernels. The folder is filled once, by ``NUMBA_CACHE_DIR=FOLDER
impactbar warmup`` on a machine of the same CPU kind with the same installation (numba keys a
cached kernel by its source file's path, size and time stamp and by the CPU; another kind of CPU or
another installation compiles again, into the same folder).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["PLUGIN_NAME", "numba_cache_plugin", "use_numba_cache"]

#: the name under which :func:`use_numba_cache` registers its plugin (registering again replaces it)
PLUGIN_NAME = "impactbar-numba-cache"  # (NumbaCacheFolder.name)


def cache_folder(folder) -> str:
    """``folder`` as an absolute path (a relative one taken from this process's working folder)."""
    if not isinstance(folder, str | os.PathLike) or not os.fspath(folder):
        raise ValueError(f"numba_cache must be a folder path (str or os.PathLike); got {folder!r}")
    path = Path(folder).expanduser()
    if path.exists() and not path.is_dir():
        raise ValueError(f"numba_cache {os.fspath(folder)!r} is a file, not a folder")
    return str(path.absolute())


def numba_cache_plugin(folder):
    """A dask worker plugin that sets ``NUMBA_CACHE_DIR`` to ``folder`` in each worker process.

    Parameters
    ----------
    folder : str or os.PathLike
        The shared numba cache, as the workers see it; a relative path is taken from this process's
        working folder. Fill it once with ``NUMBA_CACHE_DIR=FOLDER impactbar warmup``.

    Returns
    -------
    distributed.diagnostics.plugin.WorkerPlugin
        Register it with ``client.register_plugin(plugin)`` (or :func:`use_numba_cache`) before the
        workers compute anything: each worker's numba then finds the kernels in ``folder`` instead
        of compiling them. A worker that already ran impactbar's kernels keeps the cache it
        imported them with (``client.restart()`` first).

    Raises
    ------
    ValueError
        If ``folder`` is not a path, or names an existing file.

    Examples
    --------
    >>> numba_cache_plugin("/shared/numba")
    NumbaCacheFolder('/shared/numba')
    """
    path = cache_folder(folder)
    from ._cache_plugin import NumbaCacheFolder

    return NumbaCacheFolder(path)


def use_numba_cache(client, folder) -> None:
    """Point the workers of ``client``'s cluster, and those that join it later, at the shared numba
    cache ``folder`` (:func:`numba_cache_plugin`, registered as :data:`PLUGIN_NAME`); the workers
    restart, so call it before submitting work.

    Parameters
    ----------
    client : distributed.Client
    folder : str or os.PathLike
        The shared numba cache, as the workers see it.

    Raises
    ------
    ValueError
        If ``folder`` is not a path, or names an existing file.
    """
    client.register_plugin(numba_cache_plugin(folder), name=PLUGIN_NAME)
