"""The simulator's contact step under the rod-and-rock law (theory §4d): the piston's modal state at
impact -> a blow with the drive acting -> the piston's modal state after the blow.

By default the blow is exact (:class:`~impactbar.laws.rodrock.exactmap.ExactBlowMap`, its record an
:class:`~impactbar.laws.rodrock.exactmap.ExactRockContact`: the modal state and the drive as exact
pieces, every wave carried exactly, the projections in closed form;
:func:`~impactbar.laws.rodrock.step.rock_contact` chooses). With ``RodRock(method="lattice")`` or a
``cells_per_piston`` it is solved on the cell grid (:class:`BlowMap`, :class:`RockContact`), as
follows.

1. **Fields at impact.** The piston's modal state ``(q, q')`` (positions from the shank, ``u(1) = 0``)
   gives the Riemann invariants ``alpha = v + N/s``, ``beta = v - N/s`` with the static correction
   that carries the drive's force ``p(t0)`` at ``x = 0`` (theory §4c;
   :mod:`impactbar.dynamics.invariants`); each piston cell gets their exact cell averages, ``F = s alpha/2``,
   ``G = -s beta/2``. A stepped piston (theory §12): its modes' exact cell averages and the static
   correction of the modes it drops, on cells of its segments' impedances (:func:`_stepped_maps`).
2. **The blow** (:func:`~impactbar.laws.rodrock.blow.solve_blow`, the compiled rock kernel): the drive
   acts on the piston's far end as its **average over each step** (a piecewise-constant drive on
   the cell grid, exact in impulse per step; the work booked is the averaged drive's). With the cell
   averages of the fields at impact, the piston's state converges to the exact drive's at second
   order in the cells: against the wave law's exact window on a rod of impedance ``(1+R)/(1-R)``,
   2e-5 relative at 128 cells per piston, four times less per doubling (a test). Damping is
   neglected inside the blow, as in the wave law's window.
3. **The piston after the blow.** Its cells' fields are projected on the ``N + 1`` free-free modes
   exactly (piecewise-constant fields: ``q_n' = int v cos(n pi x)``, ``q_n = int N sin(n pi x) /
   (s^2 n pi)``; a stepped piston's by :func:`_stepped_maps`); the energy the truncation drops is
   a change of basis (the run's ``projection``).
4. **Between blows the rod rests on the rock.** The rod's residual waves and the bit's motion at
   the blow's end are discarded (their energy, ``Blow.rod_energy`` above the static one, is part of
   the energy the piston lost to the rod); the next blow finds the rod at rest under the feed and
   the bit on fresh rock, the shank advanced by the blow's permanent penetration (Lundberg's per-blow
   model). Positions of the next flight are measured from that advanced shank. Against carrying
   the rod's waves and the bit's motion into the next blow (``alpha = 1.25``, ``gamma = 10``, a rod of
   3 piston lengths, feed 0.2, a quarter of the blow's energy left in the rod), the next blow's work
   on rock is low by 2 % when the piston returns within about one time unit and by 15 % after a long
   gap (theory §4d; ``test_rest_between_blows_against_carried_waves``).

The blow lasts a fixed time, :meth:`RodRock.window` (``blow_time``; default ``4/s + 2 sum of the
travel times``: the contact of ``2/s`` and a wave's round trip through piston and rod after it), so
that the contact step is a smooth map of the state at impact wherever the piston does not hit the
shank again inside it (the periodic orbits' impact map); the piston flies inside the blow under the
drive (on the grid, undamped) once separated. A piston still pressed on the shank at the blow's end
leaves the step on the stop and arrives again at once (a new blow).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ...dynamics.invariants import PistonInvariants
from .blow import Blow, blow_end, solve_blow
from .grid import blow_grid, whole_steps

__all__ = ["BlowMap", "RockContact"]


def _drive_averages(load, t0: float, dt: float, n: int) -> np.ndarray:
    """The load averaged over the steps ``[t0 + i dt, t0 + (i + 1) dt]``, ``i < n``: differences of
    its exact integral (the rigid mode's velocity under it), shape ``(n,)``."""
    times = t0 + dt * np.arange(n + 1)
    _, v = load.propagate(np.zeros(1), 0.0, t0, np.zeros(1), np.zeros(1), times)
    return np.diff(np.asarray(v, dtype=float)[0]) / dt


def _drive_averages_at(load, starts, dt: float, n: int) -> list:
    """:func:`_drive_averages` at each of the times ``starts`` (one call of the load's integral)."""
    starts = np.asarray(starts, dtype=float)
    t0 = float(np.min(starts))
    times = (starts[:, None] + dt * np.arange(n + 1)).ravel()
    _, v = load.propagate(np.zeros(1), 0.0, t0, np.zeros(1), np.zeros(1), times)
    v = np.asarray(v, dtype=float)[0].reshape(starts.size, n + 1)
    return [np.diff(row) / dt for row in v]


class RockContact:
    """One blow of the simulator under :class:`~impactbar.RodRock` (theory §4d): the record of
    :meth:`RodRock.contact`, made by :func:`rock_contact`.

    Attributes
    ----------
    t0, duration : float
        Load time of the impact and the blow's length (model time; the next flight starts at
        ``t0 + duration``).
    q_before, v_before : numpy.ndarray, shape (N + 1,)
        Modal state at impact (positions from the shank).
    q_after, v_after : numpy.ndarray, shape (N + 1,)
        Modal state after the blow, positions from the shank's new rest position (advanced by
        :attr:`stop_advance`).
    blow : Blow
        The blow itself: force histories, work on rock, penetrations, the energy account. Its
        attributes are also this record's (``record.work_on_rock``, ``record.efficiency``, ...).
    energy_before : float
        Energy of the piston's fields at impact on the grid (modal energy plus static correction,
        cell-averaged).
    stop_advance : float
        How far the shank's rest position (the stop of the next flight) moved: the blow's
        permanent penetration (model length unit ``L``).
    energy_out : float
        Energy the piston lost to the rod and rock in the blow: ``energy_before + drive_work -
        piston_energy`` (the run's ``impact_loss``), ``work_on_rock + rod_loss``.
    rod_loss : float
        The part of ``energy_out`` the rock did not take.
    """

    sustained = None
    #: Contact losses that make a periodic orbit's verdict ``separates``: none (under this law the
    #: piston's separations and returns inside the blow are part of the blow).
    separations = 0

    def __init__(self, model, load, t0, q, v, F0, G0, drive, grid, params, blow, q_after, v_after):
        self.model, self.load = model, load
        self.t0 = float(t0)
        self.q_before, self.v_before = q, v
        self._F0, self._G0, self._drive, self._grid, self._params = F0, G0, drive, grid, params
        self.blow = blow
        self.duration = blow.duration
        self.q_after, self.v_after = q_after, v_after
        self._partials = {}

    def __repr__(self) -> str:
        b = self.blow
        return (f"RockContact(t0={self.t0!r}, duration={self.duration!r}, work_on_rock="
                f"{b.work_on_rock!r}, efficiency={b.efficiency!r})")

    def __getattr__(self, name):
        # (the blow's figures read as the contact's; a private name, or the blow itself not yet set
        # while unpickled or copied, is not delegated: a subclass's blow may be a property over them)
        if name.startswith("_") or name == "blow":
            raise AttributeError(name)
        return getattr(self.blow, name)

    def resolve(self) -> RockContact:
        """Itself (solved at once)."""
        return self

    @property
    def energy_before(self) -> float:
        return self.blow.energy_at_impact

    @property
    def stop_advance(self) -> float:
        return self.blow.permanent_penetration

    @property
    def energy_out(self) -> float:
        return self.blow.energy_into_rod

    @property
    def rod_loss(self) -> float:
        """``energy_out - work_on_rock``: what the piston lost that the rock did not take, the rod's
        residual energy discarded between blows and the grid's loss, less the feed's work and the
        energy stored under the feed (from the blow's account)."""
        b = self.blow
        return b.rod_energy + b.grid_loss - (b.available_energy - b.energy_at_impact - b.drive_work)

    def _check_tau(self, tau) -> float:
        """``tau`` as a float within the blow (to rounding), else a ``ValueError``."""
        tau = float(tau)
        slack = 1e-12 * self.duration + 8.0 * np.finfo(float).eps * max(1.0, abs(self.t0))
        if not -slack <= tau <= self.duration + slack:
            raise ValueError(f"tau must lie in [0, {self.duration}] (the blow); got {tau}")
        return tau

    def _at(self, tau: float):
        """The blow stopped at the step ending at or before ``tau``: ``"start"`` before the first
        step ends, ``"end"`` from the last, else the :class:`Blow` cut there (solved again)."""
        tau = self._check_tau(tau)
        dt = self._grid.cell_time
        n = int(math.floor(tau / dt + 1e-9))
        if n >= self.blow.shank_forces.size:
            return "end"
        if n == 0:
            return "start"
        if n not in self._partials:
            self._partials[n] = solve_blow(self._grid, self._F0, self._G0, self._drive, *self._params,
                                           t_max=n * dt, n_steps=n)
        return self._partials[n]

    def state_at(self, tau):
        """Modal state ``(q, q')`` at ``tau`` since impact, positions from the shank where it is then
        (``u(1) = -gap``); at the blow's end the state after it. On the lattice the state at the last
        step end (cell time ``dt``); on the exact scheme (``ExactRockContact``) at ``tau`` itself.

        Returns
        -------
        q, v : numpy.ndarray, shape (N + 1,)
        """
        b = self._at(tau)
        if isinstance(b, str) and b == "start":
            return self.q_before.copy(), self.v_before.copy()
        if isinstance(b, str) and b == "end":
            return self.q_after.copy(), self.v_after.copy()
        return self._state_of(b)

    def _state_of(self, b):
        """The modal state at the end of the cut blow ``b`` (of :meth:`_at`)."""
        return _modal(self.model, self._grid.piston_cells, b, -b.gap)

    def account(self, tau) -> tuple[float, float, float]:
        """The piston's energy balance up to ``tau`` (as :meth:`state_at`: on the lattice at the last
        step end): ``energy_before + drive_work = field_energy + energy_out``.

        Returns
        -------
        drive_work, energy_out, field_energy : float
        """
        b = self._at(tau)
        if isinstance(b, str) and b == "start":
            return 0.0, 0.0, self.energy_before
        return self._account_of(b)

    def _account_of(self, b) -> tuple[float, float, float]:
        """:meth:`account` of the cut blow ``b`` (of :meth:`_at`; ``"end"``: the whole blow)."""
        if isinstance(b, str):
            b = self.blow
        return b.drive_work, b.energy_into_rod, b.piston_energy


@functools.lru_cache(maxsize=32)
def _projection(s: float, n_p: int, M: int):
    """Matrices taking the cells' velocity and force to ``q_n'`` and ``q_n`` (``n >= 1``)."""
    xe = np.arange(n_p + 1) / n_p
    npi = math.pi * np.arange(1, M)
    arg = np.multiply.outer(npi, xe)  # (M - 1, n_p + 1)
    Pv = np.diff(np.sin(arg), axis=1) / npi[:, None]
    Pq = -np.diff(np.cos(arg), axis=1) / (s * s * npi * npi)[:, None]
    return Pv, Pq


def _modal(model, n_p: int, blow: Blow, end_position: float):
    """The piston's final cell fields of ``blow`` projected on the model's modes (exactly: the fields
    are constant on cells), ``q_0`` such that the struck end is at ``end_position``."""
    F, G = blow.piston_waves
    return _project(model, n_p, F, G, end_position, model.end_weights)


def _project(model, n_p: int, F, G, end_position: float, c):
    """:func:`_modal` of the piston's waves ``F, G`` (shape ``(n_p,)`` each), ``c`` the model's
    ``end_weights``."""
    M = model.n_modes + 1
    r = _projector(float(model.s), model.piston, n_p, M) @ np.concatenate((F, G))
    q = np.empty(M)
    qv = r[:M].copy()
    q[1:] = r[M:]
    q[0] = end_position - float(c[1:] @ q[1:])
    return q, qv


@functools.lru_cache(maxsize=32)
def _projector(s: float, piston, n_p: int, M: int) -> np.ndarray:
    """The matrix, shape ``(2 M - 1, 2 n_p)``, taking the piston's cell waves ``(F, G)`` to
    ``(q', q_1..q_N)``: ``q_0' = sum (F - G) / (s n_p)`` (the momentum), then the projections of
    the momentum densities ``(F - G)/s`` and the forces ``F + G`` (:func:`_projection`, or
    :func:`_stepped_maps` for a stepped piston)."""
    P = np.zeros((2 * M - 1, 2 * n_p))
    P[0, :n_p], P[0, n_p:] = 1.0 / (s * n_p), -1.0 / (s * n_p)
    if M > 1:
        Pv, Pq = _projection(s, n_p, M) if piston is None else _stepped_maps(s, piston, n_p, M)[2:]
        P[1:M, :n_p], P[1:M, n_p:] = Pv / s, -Pv / s
        P[M:, :n_p], P[M:, n_p:] = Pq, Pq
    P.flags.writeable = False
    return P


@functools.lru_cache(maxsize=32)
def _field_basis(s: float, n_p: int, M: int):
    """The piston's cell waves at impact as an affine map of ``(q, q', p(t0))``: the matrix ``A``
    (``2 n_p`` by ``2 M``) of the modal state and the column ``f`` of the drive's force (the static
    correction), from the wave law's ``PistonInvariants`` (exact cell averages of the invariants)."""
    xe = np.arange(n_p + 1) / n_p

    def waves(q, v, p):
        piston = PistonInvariants(s, q, v, p_end=p)
        return np.concatenate((0.5 * s * np.diff(piston.int_alpha(xe)) * n_p,
                               -0.5 * s * np.diff(piston.int_beta(xe)) * n_p))

    z = np.zeros(M)
    A = np.empty((2 * n_p, 2 * M))
    for k in range(2 * M):
        e = np.zeros(2 * M)
        e[k] = 1.0
        A[:, k] = waves(e[:M], e[M:], 0.0)
    A.flags.writeable = False
    f = waves(z, z, 1.0)
    f.flags.writeable = False
    return A, f


@functools.lru_cache(maxsize=32)
def _stepped_maps(s: float, piston, n_p: int, M: int):
    r"""A stepped piston's maps between its modal state and its cell fields (theory §12), the
    stepped counterparts of :func:`_field_basis` and :func:`_projection`.

    With :math:`u = \sum_n q_n \psi_n`, :math:`\psi_n = \phi_n(0)\phi_n` (the model's
    convention, ``BarModel.shape_functions``), :math:`\kappa_n = \phi_n(0)^2`, the mass per length
    :math:`\mu` of each cell (``Z / s``, piston mass 1) and :math:`EA = s^2 \mu`:

    - at impact, the cell averages :math:`\bar v_i = \sum_n q_n' \int_i \psi_n / \Delta` and
      :math:`\bar N_i = -s^2 \mu_i \sum_{n \ge 1} (q_n - p/\omega_n^2)\,[\psi_n]_i / \Delta
      + p\,(1 - \bar m_i)` with the drive's force :math:`p` at :math:`x = 0`: the modes kept plus the
      static correction of the modes dropped, their inertia-relief strain :math:`-p (1 - m(x)) /
      (s^2 \mu)` (``m`` the mass from the driven end, :math:`\bar m_i` its cell average) less its
      first ``N`` modal terms (as :class:`~impactbar.dynamics.invariants.PistonInvariants` on the
      uniform bar);
      waves ``F = (N + Z v)/2``, ``G = (N - Z v)/2``;
    - after the blow, the exact projections of piecewise-constant fields,
      :math:`q_n' = \sum_i \mu_i v_i \int_i \psi_n / \kappa_n` and (integrating
      :math:`\int \mu u \psi_n` by parts with the mode's equation and its free ends)
      :math:`q_n = -\sum_i N_i [\psi_n]_i / (\kappa_n \omega_n^2)`.

    Each cell takes the expression of the segment holding its middle (a boundary rounded to whole
    cells: ``BlowGrid.length_error``).

    Returns
    -------
    A : numpy.ndarray, shape (2 n_p, 2 M)
        The cell waves ``(F, G)`` of the modal state ``(q, q')``.
    f : numpy.ndarray, shape (2 n_p,)
        Those of a unit drive force at ``x = 0``.
    Pv, Pq : numpy.ndarray, shape (M - 1, n_p)
        ``q_n'`` of the cells' momentum densities ``(F - G)/s`` and ``q_n`` of their forces
        ``F + G``, ``n >= 1``.
    """
    from ._piston import piston_cells

    modes = piston.modes(M - 1)
    k = modes.wavenumbers[1:]
    w2 = (s * k) ** 2
    phi0 = modes.shapes(np.zeros(1))[0, 1:]
    kappa = phi0 * phi0
    xe = np.arange(n_p + 1) / n_p
    _, Z = piston_cells(s, piston.lengths, piston.mass_per_length, n_p)
    mu = Z / s
    seg = np.clip(np.searchsorted(piston.starts, 0.5 * (xe[:-1] + xe[1:]), side="right") - 1, 0,
                  piston.n_segments - 1)
    amp = modes.amplitudes[1:, seg]  # (M - 1, n_p, 2)
    a, b = amp[..., 0] * phi0[:, None], amp[..., 1] * phi0[:, None]
    kk = k[:, None]
    xl = xe[None, :-1] - piston.starts[seg][None, :]
    xr = xl + 1.0 / n_p
    jump = a * (np.cos(kk * xr) - np.cos(kk * xl)) + b * (np.sin(kk * xr) - np.sin(kk * xl))  # [psi]_i
    area = (a * (np.sin(kk * xr) - np.sin(kk * xl)) - b * (np.cos(kk * xr) - np.cos(kk * xl))) / kk
    m_edges = np.concatenate(([0.0], np.cumsum(mu) / n_p))
    m_bar = 0.5 * (m_edges[:-1] + m_edges[1:])
    # the cell averages of v and N as maps of (q, q') and of p
    Vq = np.concatenate((np.ones((n_p, 1)), (area * n_p).T), axis=1)  # (n_p, M), of q'
    Nq = np.concatenate((np.zeros((n_p, 1)), -(s * s) * mu[:, None] * (jump * n_p).T), axis=1)  # of q
    Np = (1.0 - m_bar) - Nq[:, 1:] @ (1.0 / w2)
    A = np.zeros((2 * n_p, 2 * M))
    A[:n_p, :M], A[:n_p, M:] = 0.5 * Nq, 0.5 * Z[:, None] * Vq
    A[n_p:, :M], A[n_p:, M:] = 0.5 * Nq, -0.5 * Z[:, None] * Vq
    f = np.concatenate((0.5 * Np, 0.5 * Np))
    Pv = area / kappa[:, None]
    Pq = -jump / (kappa * w2)[:, None]
    for arr in (A, f, Pv, Pq):
        arr.flags.writeable = False
    return A, f, Pv, Pq


@functools.lru_cache(maxsize=32)
def _grid_for(s, lengths, impedances, speeds, cells_per_piston, piston=None, locate=False, slots=False):
    return blow_grid(s, lengths, impedances, speeds, cells_per_piston, piston, locate, slots)


class BlowMap:
    """The contact step at one impact time as a map of the piston's state at impact (theory §4d):
    the grid, the drive's step averages and the projections are set up once, so that the many
    blows of a finite-difference Jacobian (:meth:`RodRock.impact_map`) share them. The fields at
    impact are affine in ``(q, q')`` and ``p(t0)`` (the static correction), with matrices cached per
    ``(s, cells, modes)``.

    Parameters
    ----------
    model, load, t0, cells_per_piston, duration
        As :func:`rock_contact`.
    averaged : bool, optional
        Whether the drive's step averages are the load's (default); ``False``: zeros, of shape
        ``(n_max,)``, for the caller to fill in place before :meth:`contact` (the coupled blow,
        whose averages come from the drive's state step by step, not from ``load``).
    """

    def __init__(self, model, load, t0, *, cells_per_piston=None, duration=None, averaged=True):
        law = model.law
        self.model, self.load, self.t0 = model, load, float(t0)
        self.s = s = float(model.s)
        segs = law.segments
        if cells_per_piston is None:
            cells_per_piston = law.cells_per_piston
        self.grid = grid = _grid_for(s, tuple(g.length for g in segs), tuple(g.impedance for g in segs),
                                     tuple(g.wave_speed for g in segs), cells_per_piston, model.piston,
                                     law.contact_events == "inside", law.contact_events == "slots")
        self.n_p, dt = grid.piston_cells, grid.cell_time
        self.p_end = float(np.asarray(load(np.array([self.t0])), dtype=float)[0])
        if duration is None:
            duration = law.window(model)
        self.n_max = whole_steps(duration, dt)
        self.drive = _drive_averages(load, self.t0, dt, self.n_max) if averaged else np.zeros(self.n_max)
        self.params = (law.rock.k, law.rock.k_u, law.bit_mass, law.feed)
        self._c = model.end_weights
        #: the last step run to this fraction of it (the slot lattice's coupled blow, ended inside it)
        self.end_fraction = 1.0

    def shifted(self, t0s):
        """Copies of this map at the load times ``t0s`` (the grid and projections shared; the
        drive's step averages of all of them from one call of the load's integral): the impact
        map's time derivative (:meth:`RodRock.impact_map`)."""
        import copy

        drives = _drive_averages_at(self.load, t0s, self.grid.cell_time, self.n_max)
        ends = np.asarray(self.load(np.asarray(t0s, dtype=float)), dtype=float)
        out = []
        for t0, drive, p_end in zip(t0s, drives, ends, strict=True):
            m = copy.copy(self)
            m.t0, m.drive, m.p_end = float(t0), drive, float(p_end)
            out.append(m)
        return out

    def fields(self, q, v):
        """The piston's waves at impact on the grid, ``(F, G)`` of shape ``(cells,)`` each (the rod's
        zero): the modal sums plus the static correction, cell-averaged (:func:`_field_basis`)."""
        n_p = self.n_p
        if self.model.piston is None:
            A, f = _field_basis(self.s, n_p, self.model.n_modes + 1)
        else:
            A, f = _stepped_maps(self.s, self.model.piston, n_p, self.model.n_modes + 1)[:2]
        w = self.p_end * f + A @ np.concatenate((q, v))
        F = np.zeros(self.grid.Z.size)
        G = np.zeros(self.grid.Z.size)
        F[:n_p], G[:n_p] = w[:n_p], w[n_p:]
        return F, G

    def contact(self, q, v) -> RockContact:
        """The blow of an arrival in state ``(q, q')`` (the end on the shank) and its record."""
        model = self.model
        q = np.array(q, dtype=float)
        v = np.array(v, dtype=float)
        F, G = self.fields(q, v)
        dt = self.grid.cell_time
        blow = solve_blow(self.grid, F, G, self.drive, *self.params, t_max=self.n_max * dt,
                          n_steps=self.n_max, end_fraction=self.end_fraction)
        # the next flight's positions are from the shank's new rest position
        end = blow.shank_displacement - blow.gap - blow.permanent_penetration
        qa, va = _modal(model, self.n_p, blow, end)
        c = model.end_weights
        over = float(c @ qa)
        if over > 0.0:  # the end beyond the new rest position (pressed on at the end): on the stop
            qa[0] -= over
        return RockContact(model, self.load, self.t0, q, v, F, G, self.drive, self.grid, self.params,
                           blow, qa, va)

    def __call__(self, y):
        """The state after the blow, ``(q_after, q'_after)`` as one vector of shape ``(2 N + 2,)``,
        from the arrival state ``y`` (its end moved onto the shank first): the numbers of
        :meth:`contact`'s record, without the record (:func:`~impactbar.laws.rodrock.blow.blow_end`;
        the impact map's Jacobian flies ``4 N + 6`` of them)."""
        model = self.model
        M = model.n_modes + 1
        c = self._c
        q = np.array(y[:M], dtype=float)
        q[0] -= float(c @ q)
        F, G = self.fields(q, np.asarray(y[M:], dtype=float))
        Fp, Gp, gap, shank, perm = blow_end(self.grid, F, G, self.drive, *self.params, self.n_max)
        qa, va = _project(model, self.n_p, Fp, Gp, shank - gap - perm, c)
        over = float(c @ qa)
        if over > 0.0:  # as in contact: on the stop
            qa[0] -= over
        return np.concatenate((qa, va))
