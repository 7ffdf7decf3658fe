r"""The wave law's contact window with a drive that has state (theory §11, "The coupled blow"; §4b).

Over the window ``theta = s (t - t0)`` in ``[0, 2]`` the invariant arriving at the driven end is
``beta(0, theta)``: the piston's field at impact for ``theta <= 1``, and for ``theta > 1`` what the rod
end sent back at ``theta - 1 < 1``, which the drive's waves (entering at ``x = 0``, reaching the rod at
``theta >= 1``) have not touched. The driven end therefore moves at ``u_t(0) = beta(0, theta) + p/s``
with ``beta(0, .)`` known in advance (from the piston's state and the drive's force at impact, the
static correction of theory §4c): the drive's state over the whole window is one integration
(its ability ``end_flight``), exact to the integrator's tolerance, without iteration; the
window is then solved by characteristics (:func:`~impactbar.laws.wave.impact.wave_impact`) with that
force, its cubic Hermite interpolant between the integrator's steps (whose steps the window's
quadratures split at: exact for the interpolant).
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from ...loads.abilities import LoadAbilities
from ..base import DrivenContact, LawNotSupported

__all__ = ["driven_wave_contact", "DriveHistory"]


class DriveHistory:
    """The drive's force over a window, from its pieces, as the window's solver takes a load: its
    values (``__call__``), its integral (``propagate``'s rigid velocity), a bound (``sup_abs``) and
    the pieces' steps as the points where the solver's quadratures split (its abilities' ``jumps``,
    :func:`impactbar.loads.abilities.jumps`); neither a load of harmonics nor one of constant pieces,
    nor one compiled code knows. The drive's pieces are ``flights``."""

    def __init__(self, pieces):
        self.flights = list(pieces)
        self.starts = np.array([p.t0 for p in self.flights])
        self.steps = np.unique(np.concatenate([p.t for p in self.flights]))
        impulses = [p.impulse_at([p.t_end])[0] for p in self.flights]
        self.cumulative = np.concatenate(([0.0], np.cumsum(impulses)))
        self.sup_abs = float(max(np.max(np.abs(p.force(p.t))) for p in self.flights))

    def _index(self, t):
        return np.clip(np.searchsorted(self.starts, t, side="right") - 1, 0, len(self.flights) - 1)

    def __call__(self, t):
        shape = np.shape(t)
        t = np.atleast_1d(np.asarray(t, dtype=float)).ravel()
        idx = self._index(t)
        out = np.empty(t.shape)
        for j in np.unique(idx):
            sel = idx == j
            out[sel] = self.flights[j].force(t[sel])
        return out.reshape(shape)

    def integral(self, t):
        """``int p dt`` from the first piece's start to the times ``t``."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        idx = self._index(t)
        out = np.empty(t.shape)
        for j in np.unique(idx):
            sel = idx == j
            out[sel] = self.cumulative[j] + self.flights[j].impulse_at(t[sel])
        return out

    @cached_property
    def abilities(self) -> LoadAbilities:
        """Its steps, where the window's quadratures split (nothing else a load may declare)."""
        return LoadAbilities(jumps=lambda t0, t1: self.steps[(self.steps > t0) & (self.steps < t1)])

    def propagate(self, w2, d, t0, q0, v0, t):
        """The rigid mode's velocity ``int_{t0}^t p`` (what the window's solver asks of a load
        without closed forms; ``w2``, ``d`` and the start at rest as it asks), shape ``(1, T)``."""
        v = self.integral(t) - self.integral([t0])[0]
        return np.zeros((1, v.size)), v[None, :]


def _incoming(sol, s):
    """``beta(0, theta)`` of the window ``sol`` as a function of the time (module docstring)."""
    piston, R, t0 = sol.piston, sol.R, sol.p.t0
    contact = sol.contact

    def beta(t):
        th = s * (t - t0)
        if th <= 1.0:
            return piston.beta1(max(th, 0.0))
        u = min(th - 1.0, 1.0)
        A = piston.alpha1(1.0 - u)
        held = any(a <= u <= b for a, b in contact)
        return -R * A if held else A

    return beta


def driven_wave_contact(model, drive, state, t0: float, q, v, settings=None) -> DrivenContact:
    """The window of a piston arriving at the rod end in modal state ``(q, q')`` at ``t0`` with the
    drive in ``state`` (as it arrives), solved together (module docstring; theory §11, "The coupled
    blow").

    Parameters
    ----------
    model : BarModel
        Under the wave law (its ``s``, ``R`` and modes; damping neglected in the window).
    drive : Drive
        A drive with state that follows a blow (its ability ``end_flight``).
    state : DriveState
    t0 : float
        Time of the arrival (model units).
    q, v : array_like, shape (N + 1,)
        Modal state at arrival, positions from the rod end (``u(1) = 0``).
    settings : FlightSettings, optional
        The drive's integrator (default the drive's).

    Returns
    -------
    DrivenContact
        Its record a :class:`~impactbar.WaveImpact` of the drive's force.

    Raises
    ------
    ValueError
        A drive that cannot follow a blow; a window that ends with the struck end still moving into
        the rod (the sustained contact is not coupled to a drive with state).
    """
    from ...loads import FourierLoad
    from ._characteristics import _Contact
    from .impact import wave_impact

    s, R = float(model.s), float(model.R)
    q = np.array(q, dtype=float)
    v = np.array(v, dtype=float)
    p0 = float(drive.force(state.mode, state.z, q, v))
    probe = _Contact(s, R, q, v, FourierLoad(p0, []), t0).solve()
    sw = probe.switches()
    theta = np.unique(np.concatenate(([0.0, 1.0, 2.0], 1.0 + sw[sw < 1.0])))
    breaks = t0 + theta / s
    beta = _incoming(probe, s)
    w = -float(model.drive_weights @ q)
    follow = drive.abilities.end_flight
    if follow is None:
        raise LawNotSupported(f"the drive {type(drive).__name__} has state but cannot follow a blow "
                              "(no end_flight in its abilities); it runs under an instantaneous impact law "
                              "only")
    fl = follow(model, state, breaks, w, [beta] * (breaks.size - 1), s, settings)
    history = DriveHistory(fl.pieces)
    rec = wave_impact(model, history, t0, q, v)
    c = model.end_weights
    qa, va = rec.q_after.copy(), rec.v_after.copy()
    scale = max(float(np.abs(c) @ np.abs(qa)), 1e-300)
    if R < 1.0 and float(c @ va) > 0.0 and abs(float(c @ qa)) <= 1e-12 * scale + 1e-300:
        raise ValueError(f"the wave law's window from t = {t0:.6g} ends with the struck end still moving "
                         "into the rod under the drive: the sustained contact that follows is not coupled "
                         "to a drive with state (use the paper's or the rod-rock law, or R > 0)")
    work = float(sum(p.piston_work() for p in fl.pieces))
    gaps = _rigid_gaps(rec, history, q, v, t0, s)
    return DrivenContact(qa, va, t0 + 2.0 / s, rec, fl.state, fl.pieces, fl.events, work, gaps)


def _rigid_gaps(rec, history, q, v, t0, s, points=65):
    """The piston's rigid coordinate ``-q_0`` over the window (from the rod end at impact), sampled:
    its momentum changes by the drive's impulse less the contact's (trapezoidal rule in between)."""
    th = np.linspace(0.0, 2.0, points)
    t = t0 + th / s
    sol = rec._solver
    contact = np.array([sol.impulse(x) for x in th])
    vel = float(v[0]) + history.integral(t) - history.integral([t0])[0] - contact
    pos = float(q[0]) + np.concatenate(([0.0], np.cumsum(0.5 * (vel[:-1] + vel[1:]) * np.diff(t))))
    return np.vstack((t, -pos))
