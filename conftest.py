"""Doctest setup for the package's docstring examples (``src/impactbar``, run by ``python -m pytest``):
the Agg backend, and an example that needs an optional extra is skipped when the extra is absent."""

import importlib.util
import os

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

#: optional extras an example may use: the import name an example mentions -> the extra that brings it
_EXTRAS = {"matplotlib": "plot", "pint": "units", "xarray": "data",
           "dask": "distributed", "zarr": "distributed"}
_EXTRA_CALLS = {".plot(": "matplotlib", "to_xarray(": "xarray", "physical.": "pint"}


def pytest_collection_modifyitems(config, items):
    for item in items:
        if not isinstance(item, pytest.DoctestItem):
            continue
        text = "\n".join(ex.source for ex in item.dtest.examples)
        needed = {m for m in _EXTRAS if m in text} | {m for k, m in _EXTRA_CALLS.items() if k in text}
        missing = sorted(m for m in needed if importlib.util.find_spec(m) is None)
        if missing:
            extras = ", ".join(sorted({_EXTRAS[m] for m in missing}))
            item.add_marker(pytest.mark.skip(reason=f"needs {', '.join(missing)} (extra {extras})"))
