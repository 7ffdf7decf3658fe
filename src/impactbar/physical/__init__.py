r"""Real hammers in SI units: from a piston, a stop and a driving force to the dimensionless model,
and back to what the designer of a rock drill reads.

Conversion (paper eq. 2, theory §1). For a bar of Young's modulus :math:`E`, density :math:`\rho`,
length :math:`L` and cross-section :math:`A`, driven at :math:`f` Hz:

- mass per unit length :math:`M = \rho A`, piston mass :math:`m = M L`, wave speed
  :math:`c = \sqrt{E / \rho}`;
- :math:`\Omega = 2 \pi f / k`: the angular frequency of the impact cycle, the first harmonic of the
  load (:math:`k` is the order of a pneumatic load, eq. 33; :math:`k = 1` for every other force);
- :math:`s = c / (L \Omega)`, :math:`d = D / (M \Omega)`, :math:`p = P / (m L \Omega^2)`,
  :math:`t = \Omega T`, :math:`u = U / L`, so velocities scale with :math:`L \Omega`:
  :math:`U_T = L \Omega u_t`.

The force scale is :math:`m L \Omega^2 = M L^2 \Omega^2`: the boundary condition
:math:`E A U_X(0) = -P` in the variables above reads :math:`s^2 u_x(0) = -P / (M L^2 \Omega^2)`, and
the rigid mode :math:`m U_{TT} = P` reads :math:`q_0'' = P / (m L \Omega^2)`. (The printed paper's
:math:`p = P / (M L \Omega^2)` drops a square: it is not dimensionless for :math:`M` a mass per unit
length; theory §1. The tests check the scale through the momentum identity
:math:`v = F_\mathrm{mean} / (f m (1 + R))`.)

Every input that has a dimension must be written with its unit (``"210 GPa"``, ``"45 mm"``) or be a
pint quantity; the dataclasses themselves hold plain SI floats in fields named with their unit
(``length_m``). Forces are positive when they push the bar towards the stop.

Outputs (:class:`PhysicalOrbit`): impact velocity (m/s), energy per blow :math:`m v^2 / 2` (J),
blow frequency :math:`\Omega / 2 \pi` (Hz), impact power (W), peak stress at impact (Pa) and, on the
hammer, the contact duration :math:`2 L / c` against the period (the paper assumes impacts are short).

Configuration keys (TOML file or a nested ``dict``, see :meth:`Hammer.from_config`)::

    name = "..."                        # optional label
    [bar]      E, density, length, diameter | area   # lists: a stepped piston, driven end first
    [damping]  coefficient | ratio      # optional section; no damping if absent
    [stop]     restitution | area
    [drive]    frequency
    [force]    kind = "pneumatic": mean, amplitude, k (optional, default 1)
               kind = "hydraulic": high, low, fraction
               kind = "measured":  csv, tolerance (optional, 0.01), max_harmonics (optional, 256)
    [model]    n_modes                  # optional, default 16
    [[rod.segments]] length, diameter | area, E, density   # with [rock]: the rod-rock law
    [bit]      mass                     # optional, default 0 kg
    [rock]     k, k_u, feed, method, cells_per_piston  # N/m, N/m, N (feed optional); the blows' method
               driven_end, contact_events       # optional: a lattice blow's end and contact events

Unknown keys are refused, naming the key.

Layout: ``units`` (pint parsing, lazily imported), ``bar`` (the piston, uniform or stepped, the
short-impact limit),
``forces`` (pneumatic, hydraulic, measured), ``config`` (the keys of a TOML config, their checks,
the presets' data), ``drifter`` (a hydraulic drifter whose valve switches on the piston's position,
theory §10: supply pressure, piston areas, switch position, valve delay; its presets), ``circuit``
(a drifter with its oil circuit, theory §11: chambers, valve, pump, accumulator; its presets),
``hydraulics`` (a circuit part's flow coefficient from its datasheet), ``hammer``
(scales and the dimensionless model; a hammer from a config, a TOML file or a preset), ``loader``
(:func:`load`: any of these machines from its TOML file, told apart by its sections), ``results``
(orbits and simulations in SI), ``rock`` (the drill string and the rock: the rod-rock law in SI and
the drilling outputs per blow), ``piston`` (the stepped piston of most work on rock per blow,
theory §12), ``sensitivity`` (a drifter's operating point differentiated by its design keys, by the
implicit function theorem), ``optimize_drifter`` (the whole drifter optimised under constraints) and
``optimize_population`` (its population search, each generation's designs evaluated together on dask).
This layer sits on
the core (``impactbar.model``, ``loads``, ``orbits``, ``simulation``) and may import pint; the core
never imports it.
"""

from .bar import SHORT_IMPACT_LIMIT as SHORT_IMPACT_LIMIT
from .bar import Bar as Bar
from .bar import ImpactDurationWarning as ImpactDurationWarning
from .bar import SteppedBar as SteppedBar
from .bar import piston_from_units as piston_from_units
from .circuit import CIRCUIT_PRESETS as CIRCUIT_PRESETS
from .circuit import CircuitDrifter as CircuitDrifter
from .circuit import CircuitDrifterOrbit as CircuitDrifterOrbit
from .circuit import circuit_preset as circuit_preset
from .circuit_branch import CircuitBranch as CircuitBranch
from .circuit_branch import continue_circuit as continue_circuit
from .circuit_graph import circuit_graph as circuit_graph
from .circuit_parts import part_kinds as part_kinds
from .circuit_parts import register_part as register_part
from .config import PRESETS as PRESETS
from .drifter import DRIFTER_PRESETS as DRIFTER_PRESETS
from .drifter import Drifter as Drifter
from .drifter import DrifterOrbit as DrifterOrbit
from .drifter import drifter_preset as drifter_preset
from .forces import FourierFit as FourierFit
from .forces import HydraulicForce as HydraulicForce
from .forces import MeasuredForce as MeasuredForce
from .forces import PneumaticForce as PneumaticForce
from .hammer import Hammer as Hammer
from .hammer import Scales as Scales
from .hammer import load_config as load_config
from .hammer import preset as preset
from .hydraulics import flow_coefficient as flow_coefficient
from .loader import build as build
from .loader import config_keys as config_keys
from .loader import config_value as config_value
from .loader import load as load
from .loader import read_config as read_config
from .loader import with_values as with_values
from .optimize_drifter import DrifterOptimum as DrifterOptimum
from .optimize_drifter import optimize_drifter as optimize_drifter
from .piston import OptimalPiston as OptimalPiston
from .piston import optimize_piston as optimize_piston
from .plausibility import ImplausibleValueWarning as ImplausibleValueWarning
from .sensitivity import OperatingPointSensitivities as OperatingPointSensitivities
from .sensitivity import operating_point_sensitivities as operating_point_sensitivities

#: names from ``results`` (which needs the orbit solver and the compiled simulator), imported on
#: first use (PEP 562) so that importing this layer, and the command line, stays fast
_LAZY = ("PhysicalOrbit", "PhysicalOrbitList", "SimulationResult", "BlowStatistics", "orbits",
         "simulate")


def __getattr__(name: str):
    if name in _LAZY:
        from . import results

        value = getattr(results, name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))

__all__ = [
    "Bar",
    "SteppedBar",
    "piston_from_units",
    "PneumaticForce",
    "HydraulicForce",
    "MeasuredForce",
    "FourierFit",
    "Hammer",
    "Scales",
    "PhysicalOrbit",
    "PhysicalOrbitList",
    "SimulationResult",
    "BlowStatistics",
    "ImpactDurationWarning",
    "ImplausibleValueWarning",
    "SHORT_IMPACT_LIMIT",
    "PRESETS",
    "preset",
    "load",
    "load_config",
    "config_keys",
    "read_config",
    "build",
    "with_values",
    "config_value",
    "orbits",
    "simulate",
    "Drifter",
    "CircuitDrifter",
    "CircuitDrifterOrbit",
    "CIRCUIT_PRESETS",
    "circuit_preset",
    "CircuitBranch",
    "continue_circuit",
    "circuit_graph",
    "register_part",
    "part_kinds",
    "flow_coefficient",
    "DrifterOrbit",
    "DRIFTER_PRESETS",
    "drifter_preset",
    "OptimalPiston",
    "optimize_piston",
    "DrifterOptimum",
    "optimize_drifter",
    "OperatingPointSensitivities",
    "operating_point_sensitivities",
]

