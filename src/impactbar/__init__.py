"""impactbar: impact vibration of an elastic bar (Bjorkenstam, Int. J. Mech. Sci. 19, 1977).

The public API; everything else is private.

Layout, bottom to top (each layer imports only from the layers below it):

- the core, on plain dimensionless arrays (numpy, scipy, numba only):
  ``dynamics`` (closed-form modal flow, certified zero search, compiled kernel), then ``loads``
  (periodic loads with their exact modal response) and ``drives`` (:class:`Drive`: autonomous drives
  with state of their own, the valve with its numerics), then ``laws`` (the impact laws, each a
  package with its numerics: ``paper``, ``wave``, ``rodrock``), then ``model`` (:class:`BarModel`),
  then ``simulation`` (the event-driven simulator and the random-start experiments), then ``orbits``
  (periodic orbits, admissibility, stability, charts; simulations are its guesses), then
  ``continuation`` (branches of periodic motions and their bifurcations; pandas, xarray, matplotlib
  only inside its views);
- the product, on top of the core: ``physical`` (SI units through pint), ``sweeps`` (dask,
  xarray, zarr), ``plotting`` and ``paper`` (matplotlib), ``cli`` (one module per subcommand).

The import contract (``[tool.importlinter]`` in ``pyproject.toml``) keeps it so.
"""

import importlib
import sys

from ._shared.parameters import Parameter as Parameter
from ._shared.renamed import renamed
from ._shared.status import Admissibility as Admissibility
from ._shared.status import BranchStatus as BranchStatus
from ._shared.status import CurveKind as CurveKind
from ._shared.status import EventKind as EventKind
from ._shared.status import RunStatus as RunStatus
from ._version import __version__ as __version__
from .drives import Drive as Drive
from .drives import DriveState as DriveState
from .drives import DriveTraits as DriveTraits
from .drives import PositionSwitchedDrive as PositionSwitchedDrive
from .loads import CosineLoad as CosineLoad
from .loads import FourierLoad as FourierLoad
from .loads import Load as Load
from .loads import PiecewiseConstantLoad as PiecewiseConstantLoad
from .loads import SquareWaveLoad as SquareWaveLoad
from .model import BarModel as BarModel

#: public names imported on first use (PEP 562), so that ``import impactbar`` and the command line
#: start without scipy.optimize, numba, pint, dask or matplotlib: name -> module that defines it
_LAZY = {
    "PeriodicOrbit": ".orbits",
    "periodic_orbits": ".orbits",
    "MultiImpactOrbit": ".orbits",
    "find_orbit": ".orbits",
    "DrivenOrbit": ".orbits",
    "Branch": ".continuation",
    "BranchEvent": ".continuation",
    "continue_orbit": ".continuation",
    "BifurcationCurve": ".continuation",
    "continue_bifurcation": ".continuation",
    "WaveImpact": ".laws.wave",
    "RodRock": ".laws",
    "RodSegment": ".laws",
    "BilinearRock": ".laws",
    "single_blow": ".laws",
    "Blow": ".laws.rodrock",
    "wave_impact": ".laws.wave",
    "InitialState": ".simulation",
    "SteppedPiston": ".dynamics.stepped",
    "PistonModes": ".dynamics.stepped",
    "StickingBasis": ".dynamics.stepped",
    "Trajectory": ".simulation",
    "EnergyAccount": ".simulation",
    "simulate": ".simulation",
    "DrivenTrajectory": ".simulation",
    "SweepSpec": ".sweeps",
    "load_spec": ".sweeps",
    "open_sweep": ".sweeps",
    "run_sweep": ".sweeps",
    "plot_sweep": ".sweeps",
}

#: subpackages reachable as attributes (``impactbar.physical``) without an explicit import
_SUBPACKAGES = ("parameters", "drives", "physical", "orbits", "simulation", "continuation", "sweeps",
                "dynamics", "cli", "paper", "plotting")


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name], __name__), name)
    elif name in _SUBPACKAGES:
        value = importlib.import_module(f".{name}", __name__)
    elif (value := renamed(sys.modules[__name__], name)) is not None:
        return value  # (not kept: each use of an old name warns)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__) | set(_SUBPACKAGES))


__all__ = [
    "BarModel",
    "Parameter",
    "Load",
    "CosineLoad",
    "SquareWaveLoad",
    "FourierLoad",
    "PiecewiseConstantLoad",
    "Drive",
    "DriveState",
    "DriveTraits",
    "PositionSwitchedDrive",
    "PeriodicOrbit",
    "periodic_orbits",
    "MultiImpactOrbit",
    "find_orbit",
    "DrivenOrbit",
    "Branch",
    "BranchEvent",
    "continue_orbit",
    "BifurcationCurve",
    "continue_bifurcation",
    "WaveImpact",
    "wave_impact",
    "RodRock",
    "RodSegment",
    "BilinearRock",
    "single_blow",
    "Blow",
    "InitialState",
    "SteppedPiston",
    "PistonModes",
    "StickingBasis",
    "Trajectory",
    "EnergyAccount",
    "simulate",
    "DrivenTrajectory",
    "SweepSpec",
    "load_spec",
    "open_sweep",
    "run_sweep",
    "plot_sweep",
    "physical",
    "Admissibility",
    "RunStatus",
    "BranchStatus",
    "EventKind",
    "CurveKind",
]
