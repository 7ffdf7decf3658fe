r"""Periodic motions under a drive: autonomous, with an unknown period (theory §10).

:func:`find_driven_orbit` (what :func:`impactbar.find_orbit` calls with a
:class:`~impactbar.Drive` in place of the load) solves the drive's periodic-orbit problem, an
:class:`~impactbar.drives.OrbitProblem`, by Newton's method and returns a :class:`DrivenOrbit`,
which is a :class:`~impactbar.PeriodicOrbit`. It calls only the interface:

- a drive that brings a problem of its own (its ability ``orbit_problem``,
  :attr:`~impactbar.Drive.abilities`) with it;
- a drive whose class has a problem in the table :data:`ORBIT_PROBLEMS` is solved with it: the
  valve of :class:`~impactbar.PositionSwitchedDrive` has closed-form flights and the exact Jacobian
  (:mod:`impactbar.orbits.valve_segment`);
- any other drive with the generic shooting problem :class:`ShootingProblem`: the unknowns are the
  bar's and the drive's states just after each of the ``m`` impacts of the period, the residual the
  flight from each to the next impact (:func:`impactbar.drives.flight.fly`: closed forms for a force
  constant between events, ``solve_ivp`` for a drive with state) followed by the impact law and
  the drive's map at the impact, minus the next unknowns (multiple shooting); the period is the sum
  of the flights. Its Jacobian, hence the multipliers, is by central finite differences (module
  constants ``FD_STEP_CLOSED``, ``FD_STEP_ODE``): with closed-form flights and events the
  multipliers' errors measured against the valve's exact Jacobian (the same motion, ``s = 10``,
  ``R = 0.215``) are ``6e-11`` on the rigid bar, ``3e-8`` with 3 modes, ``1e-7`` with 6 (the
  truncation error of the differences grows with the stiffest mode's frequency); with a drive's
  state integrated by LSODA to ``rtol = 1e-10``, ``4e-10`` on the lag drive of
  ``tests/drives/test_new_drive.py`` (against differences of an integration at ``1e-12``). The
  fixed point itself is exact to rounding with closed-form flights (the Jacobian only steers
  Newton), to the integrator's tolerance otherwise.

The multipliers are those of the return map on the section just after the impacts (the arrival
surface ``c . q = 0`` times the drive's state); the trivial one along the flow is set apart
(``trivial_multiplier``).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .._shared.status import Admissibility
from ..drives.flight import FlightSettings
from ..drives.orbitproblem import OrbitData, OrbitProblem
from ..drives.valve import PositionSwitchedDrive
from ..laws.abilities import BlowRecords
from ..model import BarModel
from .admissibility import _window_departure
from .driven_orbit import DrivenOrbit, _constant_load
from .orbit import PeriodicOrbit
from .shooting import ShootingProblem as ShootingProblem
from .valve_segment import ValveProblem

__all__ = ["DrivenOrbit", "ORBIT_PROBLEMS", "orbit_problem", "orbit_of", "ShootingProblem", "check_orbit"]

TWO_PI = 2.0 * math.pi


def check_orbit(orbit, name: str = "orbit") -> PeriodicOrbit:
    """``orbit`` if it is a :class:`~impactbar.PeriodicOrbit` (a :class:`DrivenOrbit` included),
    else a ``ValueError`` naming ``name``."""
    if not isinstance(orbit, PeriodicOrbit):
        raise ValueError(f"{name} must be a PeriodicOrbit, MultiImpactOrbit, DrivenOrbit or BranchEvent; "
                         f"got {type(orbit).__name__}")
    return orbit


#: The orbit solvers' own periodic-orbit problems, by drive class: ``ORBIT_PROBLEMS[cls](model, drive,
#: impacts, constant_load)`` is the problem of a drive of class ``cls`` or of a subclass, where the
#: drive brings no problem of its own (its ability ``orbit_problem``). The drives
#: hold the models only (no contact law, no restitution); the numerics of their orbits sit here, as
#: the loads' do: the valve of :class:`~impactbar.PositionSwitchedDrive` has closed-form flights and
#: the exact Jacobian (:class:`~impactbar.orbits.valve_segment.ValveProblem`).
ORBIT_PROBLEMS: dict[type, Callable[..., OrbitProblem]] = {PositionSwitchedDrive: ValveProblem}


def _table_problem(drive) -> Callable[..., OrbitProblem] | None:
    """The entry of :data:`ORBIT_PROBLEMS` for ``drive``: that of the first class of its MRO in the
    table."""
    for cls in type(drive).__mro__:
        if cls in ORBIT_PROBLEMS:
            return ORBIT_PROBLEMS[cls]
    return None


def orbit_problem(model: BarModel, drive, impacts: int = 1,
                  settings: FlightSettings | None = None, *, newton: str = "chord") -> OrbitProblem:
    """The periodic-orbit problem of ``drive`` on ``model`` with ``impacts`` impacts per period: the
    drive's own (its ability ``orbit_problem``, :attr:`~impactbar.Drive.abilities`), else the orbit
    solvers' own for its class (:data:`ORBIT_PROBLEMS`), else the generic :class:`ShootingProblem`
    (``newton``: its iteration where the flights integrate the variational equations, as there)."""
    own = drive.abilities.orbit_problem
    problem = own(model, impacts, _constant_load) if own is not None else None
    if problem is not None:
        return problem
    table = _table_problem(drive)
    if table is not None:
        return table(model, drive, impacts, _constant_load)
    return ShootingProblem(model, drive, impacts, settings, newton=newton)


def orbit_of(problem: OrbitProblem, X, *, multipliers: bool = True) -> DrivenOrbit:
    """The :class:`DrivenOrbit` of a solution ``X`` of ``problem``: its data
    (:meth:`OrbitProblem.orbit`), the admissibility of the flights (:meth:`OrbitProblem.admissibility`)
    and, under a law whose contact takes time, of the contacts (held for their whole window: the wave
    law's ``separates`` and ``sticks``, theory §4b). Used by :func:`find_driven_orbit` and by the
    continuation of driven orbits. ``multipliers=False`` (a :class:`ShootingProblem` only) leaves
    the multipliers ``nan`` and the monodromy out, for the figures alone at a fraction of the cost
    (no variational flight: a coupled blow's Jacobian is most of an orbit's cost)."""
    model = problem.model
    m = problem.impacts
    X = np.asarray(X, dtype=float)
    data: OrbitData = problem.orbit(X) if multipliers else problem.orbit(X, multipliers=False)
    blows = model.law.ability(BlowRecords)
    adm = Admissibility.ADMISSIBLE
    records = getattr(problem, "blow_records", None)
    coupled = records(X) if records is not None else None
    for k in range(m):
        if adm != Admissibility.ADMISSIBLE:
            break
        adm = problem.admissibility(X, k)
        if blows is not None and data.impact_velocities[k] > 0.0:
            rec = coupled[k] if coupled is not None else \
                blows.blow(model, _constant_load(float(data.contact_forces[k])), 0.0, data.states_before[k])
            separates = bool(getattr(rec, "separations", ()))
            v_after = data.states_after[k][model.n_modes + 1:]
            adm = _window_departure(adm, False, float(model.end_weights @ v_after), separates)
    mu = data.multipliers
    stable = adm == Admissibility.ADMISSIBLE and bool(np.all(np.abs(mu) < 1.0))
    impact_times = data.impact_times
    phases = np.mod(TWO_PI * impact_times / data.period, TWO_PI) if m > 1 else np.zeros(1)
    return DrivenOrbit(
        model=model, load=problem.drive, impacts=m, periods=1, impact_times=impact_times,
        phases=phases, impact_velocities=data.impact_velocities,
        admissible=adm == Admissibility.ADMISSIBLE, admissibility=adm, clearance=math.nan,
        clearance_error=math.nan, multipliers=mu, stable=stable,
        states_after_impact=np.roll(data.states_after, -1, axis=0) if m > 1 else data.states_after,
        states_before_impact=data.states_before,
        contacts=None, period=data.period, durations=data.durations,
        trivial_multiplier=data.trivial_multiplier, switch_times=data.switch_times,
        switch_velocity=data.switch_velocity, contact_time=data.contact_time, drive_states=data.drive_states,
        contact_forces=data.contact_forces, _monodromy=data.monodromy, _problem=problem, _unknowns=X)


# --------------------------------------------------------------------------------------------------
# the generic problem: shooting over the drive's flights
# --------------------------------------------------------------------------------------------------

