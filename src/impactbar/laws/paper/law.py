"""The paper's impact law (eq. 10, theory §4): an instantaneous impact on a rigid stop. Its phase
equation (eq. 14) is :mod:`impactbar.laws.paper.phase`, its one-impact orbits and their multipliers
:mod:`impactbar.laws.paper.periodic` and :mod:`impactbar.laws.paper.stability`."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..abilities import PhaseEquation
from ..base import ContactLaw, LawTraits

__all__ = ["PaperLaw", "InstantImpact"]


class InstantImpact:
    """One instantaneous impact (eq. 10): the paper law's counterpart of
    :class:`~impactbar.WaveImpact`, with the same names where they mean the same.

    Attributes
    ----------
    t0 : float
        Load time of the impact.
    duration : float
        0: the impact takes no time.
    R : float
        Restitution coefficient (eq. 10): ``model.R`` unless given.
    q_before, v_before : numpy.ndarray, shape (N + 1,)
        Free-free modal state just before the impact.
    q_after, v_after : numpy.ndarray, shape (N + 1,)
        Just after: ``q`` kept, ``v -> -R v``.
    impact_velocity : float
        ``u_t(1, t0-) = c . v_before``, the struck end's arrival speed (dimensionless).
    impulse : float
        Momentum the stop gives the bar, ``(1 + R) q_0'(t0-)`` (the bar's mass is 1): the limit of
        the wave law's ``int F dt`` as the contact shortens.
    energy_before, energy_after : float
        Energy of the bar (kinetic plus strain, ``sum kappa_n (q_n'^2 + (s n pi)^2 q_n^2) / 2``,
        ``kappa = 1, 2, 2, ...``) just before and just after.
    energy_loss : float
        ``energy_before - energy_after``, the kinetic energy lost, ``(1 - R^2)`` times the kinetic
        energy at arrival.
    """

    duration = 0.0

    def __init__(self, model, t0: float, q_before, v_before, R: float | None = None):
        self.R, self.t0 = float(model.R if R is None else R), float(t0)
        self._c = model.end_weights
        self._w2 = model.frequencies**2
        self.q_before = np.array(q_before, dtype=float)
        self.v_before = np.array(v_before, dtype=float)
        self.q_after = self.q_before.copy()
        self.v_after = -self.R * self.v_before

    @property
    def impact_velocity(self) -> float:
        return float(self._c @ self.v_before)

    @property
    def impulse(self) -> float:
        return (1.0 + self.R) * float(self.v_before[0])

    def _energy(self, q, v) -> float:
        kappa = np.full(v.size, 2.0)
        kappa[0] = 1.0
        return float(0.5 * np.sum(kappa * v * v) + 0.5 * np.sum(kappa * self._w2 * q * q))

    @property
    def energy_before(self) -> float:
        return self._energy(self.q_before, self.v_before)

    @property
    def energy_after(self) -> float:
        return self._energy(self.q_after, self.v_after)

    @property
    def energy_loss(self) -> float:
        return self.energy_before - self.energy_after

    def state_at(self, tau: float):
        """The state after the impact (the impact takes no time), ``(q, v)`` each shape ``(N + 1,)``."""
        return self.q_after.copy(), self.v_after.copy()

    def account(self, tau: float) -> tuple[float, float, float]:
        """The energy balance, as :meth:`impactbar.WaveImpact.account`: ``(0, energy_loss,
        energy_after)`` (no drive work in no time)."""
        return 0.0, self.energy_loss, self.energy_after

    def resolve(self) -> InstantImpact:
        """Itself (every record of a blow resolves to its full form)."""
        return self

    def __repr__(self) -> str:
        return (f"InstantImpact(t0={self.t0!r}, impact_velocity={self.impact_velocity!r}, "
                f"impulse={self.impulse!r}, energy_loss={self.energy_loss!r})")


@dataclass(frozen=True)
class PaperLaw(ContactLaw, PhaseEquation):
    """The paper's impact law (eqs. 10, 11, theory §4): at an instant impact the displacement is
    kept and the whole velocity field reversed and scaled by ``R``, ``(q, q') -> (q, -R q')``.

    The compiled free-flight kernel applies it itself (chatter, sticking and release are the
    simulator's, theory §8); the rigid bar's closed forms and the paper's Schur criterion belong to it.
    """

    # the declarations where the law differs from ContactLaw's defaults (its restitution applied by
    # the kernel, as they say)
    name = "paper"
    traits = LawTraits(rigid_closed_forms=True, supports_schur=True, stepped_piston=True)

    def window(self, model) -> float:
        """0: the impact is instantaneous."""
        return 0.0

    def impact_map(self, model, load, t, y_minus):
        """Eq. 10: ``y_plus = (q, -R q')``, ``jac_y = diag(1, -R)``, ``jac_t = 0``
        (see :meth:`ContactLaw.impact_map`)."""
        M = model.n_modes + 1
        y_plus = np.array(y_minus, dtype=float)
        y_plus[M:] *= -model.R
        diag = np.ones(2 * M)
        diag[M:] = -model.R
        return y_plus, np.diag(diag), np.zeros(2 * M)

    def phase_roots(self, model, load):
        """The certified roots of eq. 14 (:func:`impactbar.laws.paper.phase.phase_roots`)."""
        from .phase import phase_roots

        return phase_roots(model, load)

    def orbit_state(self, model, load, phase):
        """The orbit of eqs. 10-13 with its exact multipliers
        (:func:`impactbar.laws.paper.periodic.orbit_state`)."""
        from .periodic import orbit_state

        return orbit_state(model, load, phase)

    def multipliers(self, model, load, phase):
        """The impact map's multipliers: in closed form for the rigid bar, else from the
        monodromy with its saltation term (theory §7; :func:`impactbar.laws.paper.periodic.multipliers`)."""
        from .periodic import multipliers

        return multipliers(model, load, phase)

    def existence_edge(self, model, k: int = 1) -> float:
        """Eq. 38's edge ``k (1 + R) / (sqrt(d^2 + k^2) G)`` (``inf`` for ``R = 1``)."""
        from .phase import pneumatic_existence_edge

        return pneumatic_existence_edge(model.R, model.d, k) if model.R < 1 else math.inf

    def contact(self, model, load, t, q_minus, v_minus, *, kernel=None):
        """Eq. 10 at load time ``t``: ``(q, -R q')``, the flight resuming at once."""
        rec = InstantImpact(model, t, q_minus, v_minus)
        return rec.q_after.copy(), rec.v_after.copy(), float(t), rec
