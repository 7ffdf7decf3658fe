"""How the oil circuit's flights are integrated (theory §11, *The integrator*): the solver's options,
apart from the circuit they integrate.

:class:`CircuitFlightSettings` is the circuit's :class:`~impactbar.drives.base.FlightSettings`: CVODE's
tolerances and, beside them, the choices of how the flights are integrated, not what they are (the
compiled driver, the Newton systems' linear solver, the variational flights' fundamental matrix, the
plain flights' method). It is handed to the solvers, as ``settings`` of :func:`impactbar.simulate`,
:func:`impactbar.find_orbit` and the circuit's flight (:meth:`HydraulicCircuitDrive.flight
<impactbar.drives.circuit.HydraulicCircuitDrive.flight>`), never stored in the drive: two circuits are
equal when their parts are (scipy's ``solve_ivp(method=..., rtol=...)``, diffrax's ``diffeqsolve``
with its ``solver`` beside the vector field). A periodic orbit keeps the settings it was found with
(its problem's ``settings``), and its continuation follows them.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from ..base import FlightSettings

__all__ = ["CircuitFlightSettings", "SENSITIVITIES", "MULTISTEPS", "CARRIES", "DEFAULT_SETTINGS",
           "ROOT_TOLERANCE", "circuit_settings"]

#: How a variational flight may take its fundamental matrix (:attr:`CircuitFlightSettings.sensitivity`).
SENSITIVITIES = ("auto", "magnus", "cvode")

#: The integrators a plain flight may take (:attr:`CircuitFlightSettings.multistep`): CVODE's linear
#: multistep methods, or the explicit Dormand-Prince 8(5,3) (:mod:`._dop853`).
MULTISTEPS = ("auto", "cvode", "adams", "bdf", "dop853")
#: The values of :attr:`CircuitFlightSettings.carry`
CARRIES = ("auto", True, False)


@dataclass(frozen=True)
class CircuitFlightSettings(FlightSettings):
    """The integrator of the oil circuit's flights: SUNDIALS' CVODE at ``rtol``, ``atol`` (and the
    explicit DOP853 where :attr:`multistep` takes it), with the options of how the flights are
    integrated (module docstring). The defaults are the circuit's own
    (:attr:`HydraulicCircuitDrive.integrator <impactbar.drives.circuit.HydraulicCircuitDrive.integrator>`).

    Parameters
    ----------
    method : {"CVODE"}, optional
        The circuit's flights are CVODE's (the plain flights' method: :attr:`multistep`).
    rtol, atol : float, optional
        CVODE's tolerances, positive and finite (defaults ``1e-10`` and ``1e-12``; ``atol`` relative
        to the states' scale, 1 in the units of theory §11).
    max_step : float, optional
        Not read by the circuit's flights (:class:`~impactbar.drives.base.FlightSettings`).
    magnus_theta : float or None, optional
        The Magnus steps of a variational flight (:class:`~impactbar.drives.base.FlightSettings`).
    compiled : bool, optional
        CVODE driven from compiled code (keyword, default ``True``); ``False``: through
        scikit-sundae's Python interface, each call of the vector field a call of Python (the same
        steps, to the bit; the baseline of ``benchmarks/bench_circuit.py``).
    band : bool, optional
        The variational flights' Newton systems by SUNDIALS' band solver (keyword, default ``True``);
        ``False``: by the dense solver (the same to rounding). Only with ``compiled``.
    blocks : bool, optional
        With ``band``, that solver's LU taken on the systems' blocks (one ``n x n`` block for the
        state and each column of ``Phi``; keyword, default ``True``), and the plain flights' Newton
        systems on the state's block too (the energy integrands' rows are the identity's) where they
        took the dense solver; ``False``: the band solver's own LU, the dense solver for the plain
        flights (the same steps either way, to the bit).
    sensitivity : {"auto", "magnus", "cvode"}, optional
        How the variational flights (the Jacobians of Newton's method and the Floquet multipliers) take
        the fundamental matrix (keyword): ``"magnus"``, over the plain flight's steps by Magnus'
        method of order 6; ``"cvode"``, the variational equations integrated beside the state by
        CVODE (the way before); ``"auto"`` (default), Magnus where the piston has modes, CVODE for the
        rigid piston (:func:`~impactbar.drives.circuit.flight.circuit_flight`).
    multistep : {"auto", "cvode", "adams", "bdf", "dop853"}, optional
        The plain flights' integrator (keyword): ``"auto"`` (default), for a piston with modes the
        explicit Dormand-Prince 8(5,3) where the oil is not stiff against its steps
        (:data:`~impactbar.drives.circuit.flight.EXPLICIT_STIFFNESS`), else CVODE's Adams-Moulton
        where the steps follow the modes' oscillations
        (:data:`~impactbar.drives.circuit.flight.ADAMS_STIFFNESS`) and BDF where they follow the
        oil's stiffness, BDF for the rigid piston; ``"cvode"``, that choice among CVODE's methods only
        (the way before DOP853); ``"adams"`` or ``"bdf"`` for every flight, ``"dop853"`` for every
        plain flight.
    carry : {"auto", True, False}, optional
        Whether a period's variational flights carry the fundamental matrix from one to the next
        (keyword): ``True``, each flight's variational equations start from the Jacobian so far
        (the product of the flights' before it and the events' saltations), so that the fast
        transients of a matrix started at the identity (the stiff oil volumes' and a spool's columns,
        some 500 to 800 of CVODE's steps at each start at ``rtol = 1e-10``) are spent once a
        period, not at each event; ``False``, each flight's starts at the identity and the
        products are taken after (the way before; the same Jacobian to the flights' accuracy);
        ``"auto"`` (default), ``True`` for CVODE's variational flights (the rigid piston's) of a
        circuit with a part of mechanical state (a spool valve's, whose stops, ports and pilot ports
        end some 20 flights a period), ``False`` elsewhere (their numbers kept as they were; theory
        §11, *The integrator*).
    phi_atol : float or None, optional
        CVODE's absolute tolerance on the entries of a variational flight's fundamental matrix
        (keyword, positive and finite; in the units of theory §11, where ``Phi`` is of order 1):
        ``None`` (default), ``atol``, as on the state. A coarser one lets the state alone hold the
        error test where the matrix only steers Newton's method (the spool drill's steering flights:
        :data:`~impactbar.orbits._closing.STEER_PHI_ATOL`). Only CVODE's variational flights driven from
        compiled code (``compiled``) read it.

    Raises
    ------
    ValueError
        A method other than ``"CVODE"``, a tolerance not positive and finite (``phi_atol`` may be
        ``None``), a flag that is not
        ``True`` or ``False``, an unknown ``sensitivity``, ``multistep`` or ``carry`` (each named, with
        the allowed values).

    Examples
    --------
    >>> from impactbar.drives.circuit import CircuitFlightSettings
    >>> fast, before = CircuitFlightSettings(), CircuitFlightSettings(sensitivity="cvode")
    >>> fast == before, before.rtol, before.sensitivity
    (False, 1e-10, 'cvode')
    """

    method: str = "CVODE"
    rtol: float = 1e-10
    atol: float = 1e-12
    compiled: bool = dataclasses.field(default=True, kw_only=True)
    band: bool = dataclasses.field(default=True, kw_only=True)
    blocks: bool = dataclasses.field(default=True, kw_only=True)
    sensitivity: str = dataclasses.field(default="auto", kw_only=True)
    multistep: str = dataclasses.field(default="auto", kw_only=True)
    carry: str | bool = dataclasses.field(default="auto", kw_only=True)
    phi_atol: float | None = dataclasses.field(default=None, kw_only=True)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.method != "CVODE":
            raise ValueError(f"method must be 'CVODE' (the circuit's flights; their multistep method: "
                             f"multistep); got {self.method!r}")
        for name in ("rtol", "atol", "phi_atol"):
            value = getattr(self, name)
            if name == "phi_atol" and value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be positive and finite; got {value!r}")
        for name in ("compiled", "band", "blocks"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} must be True or False; got {getattr(self, name)!r}")
        if self.sensitivity not in SENSITIVITIES:
            raise ValueError(f"sensitivity must be one of {SENSITIVITIES}; got {self.sensitivity!r}")
        if self.multistep not in MULTISTEPS:
            raise ValueError(f"multistep must be one of {MULTISTEPS}; got {self.multistep!r}")
        if not any(self.carry is c or (isinstance(c, str) and self.carry == c) for c in CARRIES):
            raise ValueError(f"carry must be one of {CARRIES}; got {self.carry!r}")


#: The tolerance of the plain flights whose root is a spool circuit's orbit, relative to the drive's
#: (:meth:`HydraulicCircuitDrive.root_settings
#: <impactbar.drives.circuit.HydraulicCircuitDrive.root_settings>`): on the spool drill
#: (``examples/circuit_drill_spool.toml``) their root at ``rtol = 3e-11`` lies 1.3e-10 from an orbit
#: at ``rtol = 1e-12`` (relative to the unknowns), nearer than the variational flights' root at
#: ``1e-10`` (2.1e-10), where at ``1e-10`` it lies 8.8e-10 off (CVODE's error test on the fundamental
#: matrix takes the variational flights' finer steps); the closing step's variational period it saves
#: costs four times the steps it adds (``benchmarks/HISTORY.md``).
ROOT_TOLERANCE = 0.3

#: The circuit's integrator: CVODE at ``rtol = 1e-10``, ``atol = 1e-12``, every option its default.
DEFAULT_SETTINGS = CircuitFlightSettings()


def circuit_settings(settings: FlightSettings | None) -> CircuitFlightSettings:
    """The circuit's settings of a flight given ``settings``: ``settings`` itself where it is a
    :class:`CircuitFlightSettings`; the tolerances and Magnus steps of a plain
    :class:`~impactbar.drives.base.FlightSettings` of CVODE with every option its default;
    :data:`DEFAULT_SETTINGS` for ``None`` or another method (the circuit takes only CVODE).

    Parameters
    ----------
    settings : FlightSettings or None
        What a solver hands the circuit's flight (:meth:`HydraulicCircuitDrive.flight
        <impactbar.drives.circuit.HydraulicCircuitDrive.flight>`, ``end_flight``).

    Returns
    -------
    CircuitFlightSettings
    """
    if isinstance(settings, CircuitFlightSettings):
        return settings
    if settings is None or settings.method != "CVODE":
        return DEFAULT_SETTINGS
    return CircuitFlightSettings(rtol=settings.rtol, atol=settings.atol, max_step=settings.max_step,
                                 magnus_theta=settings.magnus_theta)
