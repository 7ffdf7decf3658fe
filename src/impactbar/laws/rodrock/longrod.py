r"""The wave law's long rod struck by a stepped piston (theory §4b, §12): ``BarModel(...,
impact="wave", piston=SteppedPiston(...))``.

The wave law (:mod:`impactbar.laws.wave`) takes the stop for a long rod of the piston's material
whose impedance is the struck end's times :math:`(1 + R)/(1 - R)`, and solves the uniform piston's
contact by characteristics over its round trip :math:`2/s`. A stepped piston's waves are reflected
and transmitted at each of its steps, so its contact has no such fixed length: here each contact
is the exact blow of :mod:`impactbar.laws.rodrock.exactmap` (the piston's modal state and the drive
as exact pieces, each segment a delay line, the projections on its modes in closed form) on a
semi-infinite rod of that impedance: the wave the piston sends into the rod never returns, so the
rod end moves with the force on it, :math:`v = N/Z`, and keeps no memory. The contact step lasts
a fixed :meth:`SteppedLongRod.window` of :math:`2/s`, the round trip of a wave through the piston
(the uniform piston's whole contact), so that it is a smooth map of the arrival state; a piston
still pressed on the rod at its end arrives again at once (a new window: the rod being memoryless,
the windows chain into the contact exactly), and positions stay measured from the rod's end, which
each contact advances. As in the wave law, damping is neglected over the window. On a long rod of
the head's impedance a two-segment piston sends the staircase of the characteristics' closed form
(theory §12).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..abilities import BlowRecords, NewtonStart
from ..base import ContactLaw, LawTraits

__all__ = ["LongRodContact", "SteppedLongRod"]


@dataclass(frozen=True)
class SteppedLongRod(ContactLaw, BlowRecords, NewtonStart):
    """The wave law for a stepped piston (theory §4b, §12; the module's text): each contact the exact
    blow on a semi-infinite rod of impedance ``Z_s (1 + R)/(1 - R)`` (``Z_s`` the struck segment's),
    lasting :meth:`window`. A :class:`~impactbar.BarModel` takes it in place of the wave law when it
    is given a stepped piston under ``impact="wave"`` (its name is ``"wave"``); orbits by Newton's
    method from guesses (no phase equation), stability from the contact map's finite-difference
    Jacobian.

    Examples
    --------
    >>> from impactbar import BarModel, SteppedPiston
    >>> model = BarModel(10.0, 0.0, 0.5, 2, impact="wave", piston=SteppedPiston([0.3, 0.7], [2.0, 1.0]))
    >>> type(model.law).__name__, model.impact, model.law.window(model)
    ('SteppedLongRod', 'wave', 0.2)
    """

    # the declarations where the law differs from ContactLaw's defaults (its contact ends with its
    # window: not open-ended, unlike the wave law it stands in for)
    name = "wave"
    traits = LawTraits(restitution_in_kernel=False, flight_starts_on_stop=False, stepped_piston=True)

    def check_model(self, model) -> None:
        """Refuse ``R = 1``: the long rod's impedance ``(1 + R)/(1 - R)`` times the struck end's is then
        infinite (a rigid stop, the paper's law with ``R = 1``).

        Raises
        ------
        ValueError
            Naming ``R``.
        """
        if not model.R < 1.0:
            raise ValueError(f"R must be below 1 under the wave law with a stepped piston (got R = "
                             f"{model.R:g}): the long rod's impedance (1 + R)/(1 - R) times the struck "
                             "end's would be infinite; a rigid stop is the paper's law, impact='paper'")

    def rod_impedance(self, model) -> float:
        """The long rod's impedance ``Z_s (1 + R)/(1 - R)`` (model units; ``Z_s = s mu`` of the struck
        segment, ``mu`` its mass per length)."""
        mu = model.piston.mass_per_length[-1]
        return float(model.s) * float(mu) * (1.0 + model.R) / (1.0 - model.R)

    def window(self, model) -> float:
        """``2/s``: the contact step's length, the round trip of a wave through the piston (the
        uniform piston's whole contact; damping is neglected over it, as in the wave law's)."""
        return 2.0 / model.s

    def _spec(self, model):
        from .exactmap import RodSpec

        Z = self.rod_impedance(model)
        h = float(np.min(model.piston.lengths)) / model.s  # (nothing returns: any length)
        k = Z / h  # (the bit's rock takes what leaves: any stiffness)
        return RodSpec(np.array([h]), np.array([Z]), dict(k=k, k_u=k, bit_mass=0.0, feed=0.0),
                       np.array([h * model.s]), semi_infinite=True, on_rock=False)

    def _map(self, model, load, t):
        from .exactmap import ExactBlowMap

        return ExactBlowMap(model, load, float(t), rod=self._spec(model))

    def impact_map(self, model, load, t, y_minus):
        """The contact step as a map of the arrival state, with its exact Jacobians
        (:func:`~impactbar.laws.rodrock.step.map_with_jacobians`: the exact blow's tangent runs)."""
        from .step import map_with_jacobians

        return map_with_jacobians(self._map(model, load, t), y_minus, t)

    def impact_state(self, model, load, t, y_minus):
        """``y_plus`` of :meth:`impact_map` alone: one exact blow."""
        return self._map(model, load, t)(np.asarray(y_minus, dtype=float))

    def blow(self, model, load, t, y_minus):
        """The contact of an arrival at load time ``t`` in state ``y_minus`` (shape ``(2 N + 2,)``):
        the record of :meth:`contact`."""
        M = model.n_modes + 1
        c = model.end_weights
        qm = np.array(y_minus[:M], dtype=float)
        qm[0] -= float(c @ qm)
        _, _, _, record = self.contact(model, load, t, qm, np.array(y_minus[M:], dtype=float))
        return record

    def contact(self, model, load, t, q_minus, v_minus, *, kernel=None):
        """The simulator's contact step: the exact blow over :meth:`window` (``kernel`` is not used).

        Returns
        -------
        q_after, v_after : numpy.ndarray, shape (N + 1,)
            Positions from the rod end where the contact left it.
        t_release : float
        record : LongRodContact
        """
        rec = LongRodContact.of(self._map(model, load, t).contact(q_minus, v_minus))
        return rec.q_after.copy(), rec.v_after.copy(), float(t) + rec.duration, rec


class LongRodContact:
    """One contact of a stepped piston with the wave law's long rod (:class:`SteppedLongRod`): the
    exact blow's record (:class:`~impactbar.laws.rodrock.exactmap.ExactRockContact`, whose attributes
    it reads through: ``state_at``, ``account``, ``blow`` with its force history ``shank_force``),
    with the wave law's outputs.

    Attributes
    ----------
    rod_energy : float
        The energy the piston sent into the rod: ``energy_before + drive_work - field energy``.
    efficiency : float
        ``rod_energy / (energy_before + drive_work)`` (at most 1).
    advance : float
        How far the rod end moved (model length unit ``L``); the next flight's positions are
        measured from it.
    peak_force : float
        The largest interface force over the window (the exact maximum of its pieces).
    peak_rod_stress : float
        ``peak_force (1 - R)/(1 + R)``: the rod's largest compressive stress per struck-end area
        (the wave law's).
    """

    #: contact losses that make a periodic orbit's verdict ``separates``: none (the window is exact)
    separations = 0
    sustained = None

    def __init__(self, record):
        self.record = record

    @classmethod
    def of(cls, record):
        return cls(record)

    def __getattr__(self, name):
        if name.startswith("__") or name == "record":
            raise AttributeError(name)
        return getattr(self.__dict__["record"], name)

    def __repr__(self) -> str:
        return (f"LongRodContact(t0={self.t0!r}, duration={self.duration!r}, rod_energy="
                f"{self.rod_energy!r}, efficiency={self.efficiency!r})")

    def resolve(self):
        """Itself (solved at once)."""
        return self

    @property
    def rod_energy(self) -> float:
        return self.record.blow.energy_into_rod

    @property
    def efficiency(self) -> float:
        b = self.record.blow
        available = b.energy_at_impact + b.drive_work
        return self.rod_energy / available if available > 0.0 else float("nan")

    @property
    def advance(self) -> float:
        return self.record.blow.shank_displacement

    @property
    def stop_advance(self) -> float:
        return self.advance

    @property
    def peak_force(self) -> float:
        peaks, _ = self.record.blow.peak_forces()
        return float(peaks[0])

    @property
    def peak_rod_stress(self) -> float:
        R = self.record.model.R
        return self.peak_force * (1.0 - R) / (1.0 + R)
