"""impactbar: impact vibration of an elastic bar (Bjorkenstam, Int. J. Mech. Sci. 19, 1977).

The public API; everything else is private.
"""

from . import physical as physical  # SI units layer; pint is imported only when it is used
from .loads import CosineLoad as CosineLoad
from .loads import FourierLoad as FourierLoad
from .loads import Load as Load
from .loads import PiecewiseConstantLoad as PiecewiseConstantLoad
from .loads import SquareWaveLoad as SquareWaveLoad
from .model import BarModel as BarModel
from .orbits import PeriodicOrbit as PeriodicOrbit
from .orbits import periodic_orbits as periodic_orbits
from .simulate import EnergyAccount as EnergyAccount
from .simulate import InitialState as InitialState
from .simulate import Trajectory as Trajectory
from .simulate import simulate as simulate

__version__ = "0.1.0"
