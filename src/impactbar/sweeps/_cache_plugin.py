"""The dask worker plugin of :func:`impactbar.sweeps.numba_cache_plugin` (this module imports
distributed, which :mod:`impactbar.sweeps` imports only when a cluster is used)."""

from __future__ import annotations

import os
import sys

from distributed.diagnostics.plugin import WorkerPlugin


class NumbaCacheFolder(WorkerPlugin):
    """Sets ``NUMBA_CACHE_DIR`` to ``folder`` in each worker process, now and in those that join later,
    and has numba read it again if the worker already imported numba (kernels that an earlier task
    imported keep the folder they were imported with: register the plugin on fresh workers)."""

    name = "impactbar-numba-cache"

    def __init__(self, folder: str):
        self.folder = folder

    def setup(self, worker) -> None:
        os.environ["NUMBA_CACHE_DIR"] = self.folder
        if "numba.core.config" in sys.modules:
            from numba.core import config

            config.reload_config()

    def __repr__(self) -> str:
        return f"NumbaCacheFolder({self.folder!r})"
