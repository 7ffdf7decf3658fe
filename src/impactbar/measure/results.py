r"""Results at a bar's end: force, particle velocity, displacement, energy; a Kolsky bar's specimen.

With the two strain waves at the end, :math:`a` toward it and :math:`b` away from it (tension
positive, :mod:`impactbar.measure.waves`), a bar of stiffness :math:`EA`, wave speed :math:`c` and
impedance :math:`Z = EA/c` gives at the end

.. math:: F = -EA\,(a + b), \qquad v = c\,(b - a), \qquad u(t) = \int_0^t v\,dt',

the force compression positive (what the end pushes on: a specimen, a bit's rock) and the velocity
positive toward the end. The energy that passes the section toward the end is the force-velocity
integral of ASTM D4633 ("Standard test method for energy measurement for dynamic penetrometers"),
:math:`E_{FV}(t) = \int_0^t F\,v\,dt' = EA\,c \int_0^t (a^2 - b^2)\,dt'`; its force-squared form
:math:`E_{F2}(t) = \int_0^t F^2/Z\,dt'` equals it only while one wave passes (ASTM D4633 takes it up to
the first return, :math:`2L/c`). A single wave :math:`w` carries :math:`EA\,c \int w^2\,dt`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .recording import Bar
from .waves import Waves

__all__ = ["EndHistory", "end_history", "wave_energy", "impact_velocity", "specimen_response",
           "SpecimenResponse"]


def _cumulative(y, dt: float) -> np.ndarray:
    """The cumulative trapezoid integral of ``y``, starting at 0."""
    y = np.asarray(y, dtype=float)
    out = np.zeros_like(y)
    out[1:] = np.cumsum(0.5 * (y[1:] + y[:-1])) * dt
    return out


@dataclass(frozen=True)
class EndHistory:
    r"""Force (N, compression positive), particle velocity (m/s, toward the end), displacement (m)
    and the energies that passed toward the end (J): ``energy_fv`` (force-velocity integral) and
    ``energy_f2`` (:math:`\int F^2/Z`), on ``time`` (s)."""

    time: np.ndarray
    force: np.ndarray
    velocity: np.ndarray
    displacement: np.ndarray
    energy_fv: np.ndarray
    energy_f2: np.ndarray


def end_history(waves: Waves, bar: Bar) -> EndHistory:
    """The end's force, velocity, displacement and energies from its two waves (the module's formulas).

    Examples
    --------
    >>> bar = Bar(200e9, 8000.0, 1e-3)
    >>> t = np.arange(200) * 1e-6
    >>> a = np.where((t >= 10e-6) & (t < 60e-6), -1e-4, 0.0)  # one compressive wave, nothing back
    >>> h = end_history(Waves(t, a, np.zeros_like(a)), bar)
    >>> round(float(h.force.max()), 6), round(float(h.velocity.max()), 6)  # EA 1e-4, c 1e-4
    (20000.0, 0.5)
    >>> bool(np.isclose(h.energy_fv[-1], h.energy_f2[-1]))  # one wave: the two forms agree
    True
    """
    dt = float(waves.time[1] - waves.time[0])
    force = -bar.stiffness * (waves.toward + waves.away)
    velocity = bar.wave_speed * (waves.away - waves.toward)
    return EndHistory(waves.time, force, velocity, _cumulative(velocity, dt),
                      _cumulative(force * velocity, dt), _cumulative(force ** 2 / bar.impedance, dt))


def wave_energy(strain, dt: float, bar: Bar) -> float:
    r"""The energy (J) one wave carries: :math:`EA\,c \int \varepsilon^2\,dt`.

    >>> round(wave_energy(np.full(50, 1e-4), 1e-6, Bar(200e9, 8000.0, 1e-3)), 6)  # 2e8 5000 1e-8 50e-6
    0.5
    """
    return float(bar.stiffness * bar.wave_speed * np.sum(np.asarray(strain, dtype=float) ** 2) * dt)


def impact_velocity(strain, bar: Bar, *, striker: Bar | None = None, fraction: float = 0.85) -> dict:
    r"""The striker's impact velocity from an incident pulse's plateau.

    A striker of impedance :math:`Z_s` hitting a bar of impedance :math:`Z` at :math:`V` sends a
    pulse of particle velocity :math:`v_p = V Z_s / (Z_s + Z)` (the contact face's velocity), so
    :math:`V = v_p (1 + Z / Z_s)` with :math:`v_p = c\,|\bar\varepsilon|`; for a striker of the bar's
    material and section, :math:`V = 2 c\,|\bar\varepsilon|` (HopPyBar's relation). The plateau is
    the samples beyond ``fraction`` of the pulse's peak (HopPyBar's 85 %); its mean is
    :math:`\bar\varepsilon`.

    Returns
    -------
    dict
        ``velocity`` (m/s), ``velocity_std`` (m/s: the plateau's standard deviation carried through
        the relation, the scatter of the velocity the plateau's samples give), ``plateau_strain``,
        ``plateau_samples``.

    Raises
    ------
    ValueError
        A pulse of fewer than 3 plateau samples.
    """
    strain = np.asarray(strain, dtype=float)
    peak = strain[np.argmax(np.abs(strain))]
    plateau = strain[strain / peak >= fraction] if peak != 0 else strain[:0]
    if plateau.size < 3:
        raise ValueError(f"the incident pulse has {plateau.size} samples beyond {fraction:g} of its peak "
                         "(fewer than 3): no plateau to read the impact velocity from")
    factor = bar.wave_speed * (1.0 + (bar.impedance / striker.impedance if striker is not None else 1.0))
    return {"velocity": factor * abs(float(plateau.mean())), "velocity_std": factor * float(plateau.std()),
            "plateau_strain": float(plateau.mean()), "plateau_samples": int(plateau.size)}


@dataclass(frozen=True)
class SpecimenResponse:
    """A Kolsky-bar specimen's engineering stress (Pa), strain and strain rate (1/s), compression
    positive, by the one-, two- and three-wave analyses (keys ``"1"``, ``"2"``, ``"3"``), on ``time``
    (s, from the incident pulse's arrival at the specimen), and the forces on its two faces (N)."""

    time: np.ndarray
    stress: dict
    strain: dict
    strain_rate: dict
    front_force: np.ndarray
    back_force: np.ndarray


def specimen_response(incident, reflected, transmitted, dt: float, incident_bar: Bar, transmitted_bar: Bar,
                      length: float, area: float) -> SpecimenResponse:
    r"""The specimen's stress, strain and strain rate from the three waves at its faces.

    ``incident``, ``reflected`` and ``transmitted`` are the strains (tension positive) at the
    specimen's faces on one time base (the incident and reflected at the incident bar's end, the
    transmitted at the transmitted bar's). The faces' forces are :math:`F_1 = -E_iA_i(\varepsilon_I +
    \varepsilon_R)` and :math:`F_2 = -E_tA_t\,\varepsilon_T`, their velocities :math:`v_1 = c_i
    (\varepsilon_R - \varepsilon_I)` and :math:`v_2 = -c_t\,\varepsilon_T`. Following Gray (2000,
    "Classic split-Hopkinson pressure bar testing", *ASM Handbook* 8, 462-476) and Chen and Song
    (2011, *Split Hopkinson (Kolsky) Bar*, ch. 1):

    - one-wave: stress :math:`F_2/A_s` (the transmitted wave), strain rate :math:`2 c_i
      \varepsilon_R / L_s` (the reflected wave, equilibrium assumed);
    - two-wave: stress :math:`F_1/A_s` (the front face), strain rate :math:`2 c_i \varepsilon_R / L_s`;
    - three-wave: stress :math:`(F_1 + F_2)/(2 A_s)`, strain rate :math:`(v_1 - v_2)/L_s`;

    the strain the strain rate's time integral.
    """
    eI, eR, eT = (np.asarray(w, dtype=float) for w in (incident, reflected, transmitted))
    if not eI.shape == eR.shape == eT.shape:
        raise ValueError(f"incident, reflected and transmitted must be of one length, got {eI.size}, "
                         f"{eR.size}, {eT.size}")
    for name, value in (("length", length), ("area", area)):
        if not value > 0:
            raise ValueError(f"the specimen's {name} must be > 0, got {value!r}")
    f1 = -incident_bar.stiffness * (eI + eR)
    f2 = -transmitted_bar.stiffness * eT
    v1 = incident_bar.wave_speed * (eR - eI)
    v2 = -transmitted_bar.wave_speed * eT
    rate_r = 2 * incident_bar.wave_speed * eR / length
    rates = {"1": rate_r, "2": rate_r, "3": (v1 - v2) / length}
    stress = {"1": f2 / area, "2": f1 / area, "3": 0.5 * (f1 + f2) / area}
    strain = {k: _cumulative(r, dt) for k, r in rates.items()}
    return SpecimenResponse(np.arange(eI.size) * dt, stress, strain, rates, f1, f2)
