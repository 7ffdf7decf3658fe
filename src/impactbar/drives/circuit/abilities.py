"""What the oil circuit declares and can do as a :class:`~impactbar.Drive`: its traits (read from
its layout, which extra parts change), its parameters' records (``None`` for a part it does not
have) and its abilities (its own flights with the variational equations, the energy account's
quadratures, the coupled blows, the border tests); the properties of
:class:`~impactbar.drives.circuit.HydraulicCircuitDrive` of those names."""

from __future__ import annotations

from ..abilities import DriveAbilities, OwnFlight, Quadratures
from ..base import DriveTraits
from ..params import DriveParameters
from .watch import consistent_mode

__all__ = ["circuit_traits", "circuit_params", "circuit_abilities"]


def circuit_traits(drive) -> DriveTraits:
    """The circuit's :class:`~impactbar.DriveTraits`: its parameters and their ranges, its states
    (``layout.state_names``) and its integrator, each as the drive holds it (its extra parts'
    included).

    Examples
    --------
    >>> from impactbar.drives.circuit import Chambers, HydraulicCircuitDrive, Oil, Supply, Valve
    >>> drive = HydraulicCircuitDrive(Chambers(0.5, 0.4, 0.2), Valve(0.048, 2.0, 0.05),
    ...                               Supply(None, pressure=2.0, hose_volume=1.0, front_coefficient=2.0,
    ...                                      tank_pressure=0.03), Oil(140.0, 0.01))
    >>> drive.traits.state_names, drive.traits.integrator.method
    (('p_f', 'p_r', 'p_s', 'x_v'), 'CVODE')
    """
    return DriveTraits(parameters=drive.parameters, parameter_ranges=drive.parameter_ranges,
                       state_size=drive.state_size, state_names=drive.state_names,
                       integrator=drive.integrator)


def circuit_params(drive) -> DriveParameters:
    """The circuit's parameters (:class:`~impactbar.drives.params.DriveParameters`), each record's
    value ``None`` where the circuit has no such part or leaves the field unset."""
    return DriveParameters(drive, value=drive._parameter_value)


def circuit_abilities(drive) -> DriveAbilities:
    """The circuit's abilities: its own flights (:meth:`~.HydraulicCircuitDrive.flight`, with the
    variational equations, and :meth:`~.HydraulicCircuitDrive.variational_state_settings`), the
    energy account's quadratures (:meth:`~.HydraulicCircuitDrive.quadratures`, the work on the
    piston among them), the coupled blows (:meth:`~.HydraulicCircuitDrive.end_flight`, their tangents
    :meth:`~.HydraulicCircuitDrive.end_tangent`) and the
    border tests (:meth:`~.HydraulicCircuitDrive.border_tests`) and the watched levels' flags a
    block's state decides (:func:`.watch.consistent_mode`)."""
    return DriveAbilities(
        flight=OwnFlight(drive.flight, variational=drive.variational,
                         state_settings=drive.variational_state_settings, carried=drive.carries,
                         root_settings=drive.root_settings,
                         charged_start=drive.charged_start),
        quadratures=Quadratures(drive.n_quadratures, drive.quadratures, drive.piston_work_quadrature),
        end_flight=drive.end_flight, end_tangent=drive.end_tangent, border_tests=drive.border_tests,
        start_mode=lambda mode, q, v, z: consistent_mode(drive._watched, mode, q, z))
