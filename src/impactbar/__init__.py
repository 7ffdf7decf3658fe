"""impactbar: impact vibration of an elastic bar (Bjorkenstam, Int. J. Mech. Sci. 19, 1977).

The public API; everything else is private.

Layout, bottom to top (each layer imports only from the layers below it):

- the core, on plain dimensionless arrays (numpy, scipy, numba only):
  ``dynamics`` (closed-form modal flow, certified zero search, compiled kernel), then ``model``
  (:class:`BarModel`) and ``loads`` (periodic loads with their exact modal response), then
  ``orbits`` (periodic orbits, admissibility, stability, charts) and ``simulation`` (the
  event-driven simulator and the random-start experiments);
- the product, on top of the core: ``physical`` (SI units through pint), ``sweeps`` (dask,
  xarray, zarr), ``plotting`` and ``paper`` (matplotlib), ``cli`` (one module per subcommand).

The import contract (``[tool.importlinter]`` in ``pyproject.toml``) keeps it so.
"""

from . import physical as physical  # SI units layer; pint is imported only when it is used
from ._version import __version__ as __version__
from .dynamics import WaveImpact as WaveImpact
from .dynamics import wave_impact as wave_impact
from .loads import CosineLoad as CosineLoad
from .loads import FourierLoad as FourierLoad
from .loads import Load as Load
from .loads import PiecewiseConstantLoad as PiecewiseConstantLoad
from .loads import SquareWaveLoad as SquareWaveLoad
from .model import BarModel as BarModel
from .orbits import PeriodicOrbit as PeriodicOrbit
from .orbits import periodic_orbits as periodic_orbits
from .simulation import EnergyAccount as EnergyAccount
from .simulation import InitialState as InitialState
from .simulation import Trajectory as Trajectory
from .simulation import simulate as simulate
from .sweeps import SweepSpec as SweepSpec
from .sweeps import load_spec as load_spec
from .sweeps import open_sweep as open_sweep
from .sweeps import plot_sweep as plot_sweep
from .sweeps import run_sweep as run_sweep

__all__ = [
    "BarModel",
    "Load",
    "CosineLoad",
    "SquareWaveLoad",
    "FourierLoad",
    "PiecewiseConstantLoad",
    "PeriodicOrbit",
    "periodic_orbits",
    "WaveImpact",
    "wave_impact",
    "InitialState",
    "Trajectory",
    "EnergyAccount",
    "simulate",
    "SweepSpec",
    "load_spec",
    "open_sweep",
    "run_sweep",
    "plot_sweep",
    "physical",
]
