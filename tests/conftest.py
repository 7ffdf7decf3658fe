"""Shared test setup: seeded rng, floating-point errors raise, Agg backend, ``--runslow``."""

import os
import sys
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("MPLBACKEND", "Agg")
# the tests mirror the package in subfolders; their shared helpers (modal_reference, wave_reference)
# stay here and are imported by plain name
sys.path.insert(0, str(Path(__file__).resolve().parent))


def _import_the_package():
    """Import every module of impactbar now. Hypothesis draws some examples from the constants of
    the project's modules loaded when it draws; with all of them loaded before the first test, a
    test's examples no longer depend on which modules the tests before it happened to import."""
    import importlib
    import pkgutil

    import impactbar

    for info in pkgutil.walk_packages(impactbar.__path__, "impactbar."):
        if not info.name.endswith("__main__"):  # (that one runs the command line)
            try:
                importlib.import_module(info.name)
            except ImportError:  # an optional dependency missing: its tests say so themselves
                pass


_import_the_package()


def pytest_addoption(parser):
    parser.addoption("--runslow", action="store_true", default=False, help="run tests marked slow")


def pytest_collection_modifyitems(config, items):
    if config.getoption("--runslow"):
        return
    skip_slow = pytest.mark.skip(reason="slow: use --runslow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip_slow)


@pytest.fixture
def choose():
    """``choose(name, fast)``: run the rest of the test with the fast (``True``) or the reference
    (``False``) implementation of ``name`` (:mod:`impactbar.dynamics.implementations`)."""
    import contextlib

    from impactbar.dynamics.implementations import implementation

    with contextlib.ExitStack() as stack:
        yield lambda name, fast: stack.enter_context(implementation(name, "fast" if fast else "reference"))


@pytest.fixture
def rng():
    """A seeded generator, so every random test is repeatable."""
    return np.random.default_rng(20261121)


@pytest.fixture(autouse=True)
def _raise_on_fp_errors():
    old = np.seterr(all="raise", under="ignore")
    yield
    np.seterr(**old)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    try:
        import matplotlib.pyplot as plt
    except ImportError:  # pragma: no cover
        return
    plt.close("all")
