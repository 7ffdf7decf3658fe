"""The wave impact law (theory §4b): the stop is a long rod, the contact lasts ``2/s`` and is
solved by characteristics with the drive acting.

The orbit machinery is :mod:`impactbar.laws.wave.periodic` (phase equation, states, the impact map's
Jacobian, the existence edge); the characteristics solver is :mod:`impactbar.laws.wave.impact`
(:class:`~impactbar.WaveImpact`) with its compiled kernels, the sustained contact
:mod:`impactbar.laws.wave.sustained`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..abilities import BlowRecords, CoupledBlow, PhaseEquation
from ..base import ContactLaw, LawTraits

__all__ = ["PressedContact", "WaveLaw"]

_GL20_X, _GL20_W = np.polynomial.legendre.leggauss(20)


@dataclass(frozen=True)
class WaveLaw(ContactLaw, PhaseEquation, BlowRecords, CoupledBlow):
    """The stop as a long rod of the same material with area ratio ``A_s/A = (1 + R)/(1 - R)``;
    the contact, lasting ``2/s``, is solved by characteristics with the drive acting (theory §4b).
    Without drive and separation the velocity and strain fields leave multiplied by ``-R``; each
    blow advances the rod end, and positions stay measured from it. Per blow:
    :class:`~impactbar.WaveImpact` (force wave, rod energy, peak stresses, efficiency, advance).
    """

    # the declarations where the law differs from ContactLaw's defaults
    name = "wave"
    traits = LawTraits(restitution_in_kernel=False, open_ended=True)

    def window(self, model) -> float:
        """``2/s``: the wave's return trip along the bar."""
        return 2.0 / model.s

    def impact_map(self, model, load, t, y_minus):
        """Contact held for the whole window: ``(q_n, q_n') -> -R (q_n, q_n') + (g_n, h_n)(t)`` for
        ``n >= 1``, ``q_0' -> -R q_0' + h_0``, with the drive part of
        :func:`impactbar.laws.wave.impact.window_drive`, and ``q_0`` set by contact with the
        (advanced) rod end at the window's end; ``d(g, h)/dt`` is the drive's rate. Whether the
        contact really holds is decided on the orbit (``"separates"``)."""
        from .impact import window_drive
        from .periodic import window_map

        M = model.n_modes + 1
        g, h, dg, dh = window_drive(model.s, model.R, model.n_modes, load, float(t), derivative=True)
        y_plus = window_map(model, y_minus, g, h)
        c = model.end_weights
        jac = -model.R * np.eye(2 * M)
        jac[0, :] = 0.0
        jac[0, 1:M] = model.R * c[1:]
        jt = np.concatenate((dg, dh))
        jt[0] = -float(c[1:] @ dg[1:])
        return y_plus, jac, jt

    def phase_roots(self, model, load):
        """:func:`impactbar.laws.wave.periodic.wave_phase_roots`."""
        from .periodic import wave_phase_roots  # here: it loads scipy.optimize and numba

        return wave_phase_roots(model, load)

    def phase_families(self, model, load):
        """:func:`impactbar.laws.wave.periodic.wave_phase_families`."""
        from .periodic import wave_phase_families

        return wave_phase_families(model, load)

    def orbit_state(self, model, load, phase):
        """Contact over ``[0, 2/s]``, flight over ``[2/s, 2 pi]``, with the contact's
        :class:`~impactbar.WaveImpact` (theory §4b; :func:`impactbar.laws.wave.periodic.orbit_state`)."""
        from .periodic import orbit_state

        return orbit_state(model, load, phase)

    def multipliers(self, model, load, phase):
        """Eigenvalues of :func:`impactbar.laws.wave.periodic.wave_impact_map_jacobian`."""
        from ..._shared.threads import single_threaded_blas
        from ...dynamics.monodromy import sort_multipliers
        from .periodic import wave_impact_map_jacobian, wave_orbit_states

        _, y_end, y_minus, rate = wave_orbit_states(model, load, phase)
        with single_threaded_blas():
            return sort_multipliers(np.linalg.eigvals(
                wave_impact_map_jacobian(model, load, phase, y_end, y_minus, rate)))

    def existence_edge(self, model, k: int = 1) -> float:
        """:func:`impactbar.laws.wave.periodic.wave_existence_edge`."""
        from .periodic import wave_existence_edge

        return wave_existence_edge(model, k)

    def blow(self, model, load, t, y_minus):
        """The contact by characteristics (:func:`~impactbar.laws.wave.impact.wave_impact`) of an
        arrival in state ``y_minus`` at ``t``."""
        from .impact import wave_impact

        M = model.n_modes + 1
        c = model.end_weights
        qm = y_minus[:M].copy()
        qm[0] -= float(c @ qm)  # the end exactly on the rod end (rounding)
        return wave_impact(model, load, t, qm, y_minus[M:])

    def contact(self, model, load, t, q_minus, v_minus, *, kernel=None, t_end=None):
        """The window ``[t, t + 2/s]``: by the compiled kernels when ``kernel`` is given (the
        :class:`~impactbar.WaveImpact` then solved on first use), else by
        :func:`~impactbar.laws.wave.impact.wave_impact`. A window that ends with the struck end
        still moving into the rod goes on as the sustained contact
        (:class:`~impactbar.laws.wave.sustained.SustainedContact`, theory §4b) until the interface
        force would turn tensile, or until ``t_end`` (default: two load periods after the window,
        where a contact still pressed resumes as a new arrival); the record then is a
        :class:`PressedContact`."""
        q, v, t_release, imp = self._window(model, load, t, q_minus, v_minus, kernel)
        c = model.end_weights
        ends = float(c @ v)
        scale = max(float(np.abs(c) @ np.abs(q)), 1e-300)
        if model.R < 1.0 and ends > 0.0 and abs(float(c @ q)) <= 1e-12 * scale + 1e-300:
            from .sustained import sustained_contact

            horizon = t_release + 4.0 * np.pi if t_end is None else max(float(t_end), t_release)
            if horizon > t_release:
                q = q.copy()
                q[0] -= float(c @ q)  # the end exactly on the rod end (rounding)
                sc = sustained_contact(model, load, t_release, q, v, horizon)
                q, v = sc.q_after.copy(), sc.v_after.copy()
                if sc.released:  # the end at rest on the rod end (rounding must not push it in)
                    q[0] -= float(c @ q)
                    v[0] -= max(float(c @ v), 0.0)
                imp = PressedContact(imp, sc)
                t_release = sc.t0 + sc.duration
        return q, v, t_release, imp

    def driven_contact(self, model, drive, state, t, q_minus, v_minus, *, settings=None):
        """The window with a drive that has state (the oil circuit): the drive's state over the
        window in one integration, the driven end moved by the invariant the window sends it, then
        the window by characteristics with the drive's force
        (:func:`impactbar.laws.wave.coupled.driven_wave_contact`; theory §11, "The coupled blow").

        Returns
        -------
        DrivenContact
            Its record a :class:`~impactbar.WaveImpact`.
        """
        from .coupled import driven_wave_contact

        return driven_wave_contact(model, drive, state, float(t), q_minus, v_minus, settings)

    def _window(self, model, load, t, q_minus, v_minus, kernel):
        from .impact import wave_impact

        ti, qm, vm = float(t), q_minus, v_minus
        t_release = ti + 2.0 / model.s
        if kernel is None:
            imp = wave_impact(model, load, ti, qm, vm)
            return imp.q_after.copy(), imp.v_after.copy(), t_release, imp
        from ...dynamics.implementations import use_fast
        from . import _separation as WK
        from . import _window as KW

        c = kernel.c
        D = kernel.data
        ks = D.ks
        rate = float(np.max(ks)) / model.s if D.kind == 0 and ks.size else 0.0
        contact = np.empty((WK.MAX_INTERVALS, 2))  # the contact intervals of a separating window
        q, v = np.empty_like(qm), np.empty_like(vm)
        if KW.wave_window(tuple(D), model.s, model.R, c, rate, ti, qm, vm, _GL20_X, _GL20_W, q, v):
            imp = _Window(model, load, ti, qm, vm, q.copy(), v.copy())  # solved when asked
        elif use_fast("simulate.wave_separation") and WK.wave_contact(
                tuple(D), model.s, model.R, rate, ti, qm, vm, _GL20_X, _GL20_W, q, v, contact) >= 0:
            # contact lost inside the window (the compiled characteristics solver; its reference,
            # the Python solver wave_impact, is the branch below)
            imp = _Window(model, load, ti, qm, vm, q.copy(), v.copy())
        else:  # the full characteristics solution in Python
            imp = wave_impact(model, load, ti, qm, vm)
            q, v = imp.q_after.copy(), imp.v_after.copy()
        return q, v, t_release, imp


class PressedContact:
    """A contact window followed by the sustained contact (theory §4b): the record of
    :meth:`WaveLaw.contact` when the window ends with the end still moving into the rod. The blow's
    own outputs (force wave, peak stresses) are the window's; the energies, the efficiency and the
    advance cover the whole contact.

    Attributes
    ----------
    t0, duration : float
        Start (load time) and length of the whole contact, window and sustained phase.
    window : WaveImpact
        The window of ``2/s``; attributes not listed here are the window's.
    sustained : SustainedContact
        The piston pressed on the rod from the window's end to the release.
    q_after, v_after : numpy.ndarray, shape (N + 1,)
        State at the release.
    rod_energy, drive_work, advance : float
        Over the whole contact: the energy sent into the rod, the drive's work, the rod end's
        advance.
    efficiency : float
        ``rod_energy / (energy_before + drive_work)`` over the whole contact: the share of the
        energy available to the blow that the rod carries away (at most 1).
    """

    def __init__(self, window, sustained):
        self.window, self.sustained = window, sustained
        self.t0 = window.t0
        self.duration = window.duration + sustained.duration
        self.q_after, self.v_after = sustained.q_after, sustained.v_after

    def resolve(self):
        """Itself, with the window solved."""
        self.window = self.window.resolve()
        return self

    def __repr__(self) -> str:
        return f"PressedContact(t0={self.t0!r}, duration={self.duration!r}, window={self.window!r})"

    @property
    def rod_energy(self) -> float:
        _, rod, *_ = self.sustained.account(self.sustained.duration)
        return self.window.rod_energy + rod

    @property
    def drive_work(self) -> float:
        work, *_ = self.sustained.account(self.sustained.duration)
        return self.window.drive_work + work

    @property
    def advance(self) -> float:
        return self.window.advance + self.sustained.advance

    @property
    def efficiency(self) -> float:
        available = self.window.energy_before + self.drive_work
        return self.rod_energy / available if available > 0.0 else float("nan")

    def state_at(self, tau):
        """Modal state at ``tau`` since the contact started (positions from the rod end)."""
        wd = self.window.duration
        if tau <= wd:
            return self.window.state_at(tau)
        return self.sustained.state_at(tau - wd)

    def account(self, tau):
        """``(drive_work, rod_energy, field_energy)`` up to ``tau``: ``energy_before + drive_work
        = field_energy + rod_energy + damping(tau)``; ``field_energy`` carries the window's
        projection on the modes kept (the sustained phase starts from the projected state)."""
        wd = self.window.duration
        if tau <= wd:
            return self.window.account(tau)
        w1, r1, f1 = self.window.account(wd)
        w2, r2, _, f2 = self.sustained.account(tau - wd)
        from .impact import modal_energy

        proj = f1 - modal_energy(self.sustained.model.s, self.window.q_after, self.window.v_after)
        return w1 + w2, r1 + r2, f2 + proj

    def damping(self, tau) -> float:
        """Energy lost to the damping ``d`` up to ``tau`` (none inside the window)."""
        wd = self.window.duration
        if tau <= wd:
            return 0.0
        _, _, damp, *_ = self.sustained.account(tau - wd)
        return damp

    def __getattr__(self, name):
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.__dict__["window"], name)


class _Window:
    """A contact window the compiled kernel found without separation: its post-contact state is
    known; the full :class:`~impactbar.WaveImpact` (force wave, energies) is solved on first use."""

    sustained = None  # no sustained contact follows (asking must not solve the window)

    def __init__(self, model, load, t0, q, v, q_after, v_after):
        self._args = (model, load, t0, q, v)
        self._impact = None
        self.t0 = t0
        self.duration = 2.0 / model.s
        self.q_after, self.v_after = q_after, v_after

    def resolve(self):
        from .impact import wave_impact

        if self._impact is None:
            self._impact = wave_impact(*self._args)
        return self._impact

    def __getattr__(self, name):
        return getattr(self.resolve(), name)
