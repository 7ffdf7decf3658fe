r"""The simulator's blow on the exact scheme (theory §4d, "in the simulator"): the piston's modal
state at impact becomes its waves as exact pieces, the drive's force on its far end exact pieces too,
the blow runs on the exact solver (:func:`~impactbar.laws.rodrock.exact.exact_blow`) for the law's
fixed duration, and the piston's waves at its end are projected on the modes in closed form.

**The piston's waves at impact.** On a segment :math:`i` of the piston (impedance
:math:`Z_i = s \mu_i`, :math:`\mu_i` its mass per length, travel time :math:`T_i = \ell_i/s`, the mass
:math:`m_i` before it), at the travel time :math:`\theta` from its driven-side end
(:math:`x - x_i = s\theta`), the modal state :math:`(q, q')` and the drive's force :math:`p` at
:math:`x = 0` give

.. math::

    v = q_0' + \sum_{n \ge 1} q_n' \psi_n, \qquad
    N = -s^2 \mu_i \sum_{n \ge 1} \Bigl(q_n - \frac{p}{\omega_n^2}\Bigr) \psi_n'
        + p\,(1 - m_i - \mu_i s\theta),

the modes kept and the static correction of those dropped (theory §4c; for a uniform piston
:math:`\psi_n = 2\cos(n\pi x)`, :math:`\omega_n = s n\pi`; a stepped piston's
:math:`\psi_n = \phi_n(0)\phi_n`, theory §12), and the waves :math:`F = (N + Z_i v)/2`,
:math:`G = (N - Z_i v)/2`: constants, a linear term and :math:`e^{\pm i\omega_n\theta}` in the
travel time, exact pieces of the exact solver. The drive :math:`p(t_0 + t)` is exact pieces too: a
Fourier load's harmonics :math:`e^{\pm i k t}`, a piecewise-constant load's levels between its jumps.

**The piston's modal state after the blow** (its waves in flight at the end, :math:`F_i(\theta)`,
:math:`G_i(\theta)`): with :math:`\kappa_n = \phi_n(0)^2`, the mass-weighted projections

.. math::

    q_0' = \sum_i \int_0^{T_i} (F - G)\,d\theta, \qquad
    \kappa_n q_n' = \sum_i \int_0^{T_i} (F - G)\,\psi_n\,d\theta, \qquad
    \kappa_n \omega_n^2 q_n = -s \sum_i \int_0^{T_i} (F + G)\,\psi_n'\,d\theta,

in closed form piece by piece (the lattice's projections of cell averages are their first-order
counterparts), and :math:`q_0` from the struck end's position.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np

from ._exactmodal import piston_integrals
from ._piston import piston_segments
from ._records import (  # the records' slots
    BI_NEP,
    BS_PPERM,
    CHI_HEAD,
    CNT_PIECES,
    CNT_TERMS,
    CT_T,
    NSF_GAP,
    NSF_SHANK,
    OUT_F,
    OUT_G,
    WS_BI,
    WS_BS,
    WS_CNT,
    WS_CT,
    WS_NSF,
)
from .contact import RockContact

__all__ = ["ExactBlowMap", "ExactRockContact", "ModalBasis", "RodSpec", "drive_pieces", "initial_waves",
           "project", "rod_spec"]


class ModalBasis:
    """A piston's segments and modes as the exact blow needs them (theory §4d, §12).

    Attributes
    ----------
    s : float
        The model's wave-speed ratio.
    travel, impedance, mu, mass_before : numpy.ndarray, shape (P,)
        Each segment's travel time ``l_i / s``, impedance ``s mu_i``, mass per length and the mass
        between the driven end and its start.
    omega : numpy.ndarray, shape (N + 1,)
        ``omega_n = s k_n`` (``omega_0 = 0``).
    a, b : numpy.ndarray, shape (N + 1, P)
        ``psi_n = a cos(k_n (x - x_i)) + b sin(k_n (x - x_i))`` on segment ``i`` (``psi_0 = 1``).
    kappa : numpy.ndarray, shape (N + 1,)
        ``phi_n(0)^2`` (``kappa_0 = 1``): ``kappa_n q_n'`` is the mass-weighted projection.
    end_weights : numpy.ndarray, shape (N + 1,)
        ``psi_n(1)``: the model's ``end_weights``.
    """

    def __init__(self, s: float, piston, n_modes: int):
        self.s = s = float(s)
        lengths, mu = piston_segments(piston)
        self.travel = lengths / s
        self.mu = np.asarray(mu, dtype=float)
        self.impedance = s * self.mu
        masses = self.mu * lengths
        self.mass_before = np.concatenate(([0.0], np.cumsum(masses)[:-1]))
        M = n_modes + 1
        P = lengths.size
        if piston is None:
            k = math.pi * np.arange(M)
            self.a = np.full((M, P), 2.0)
            self.b = np.zeros((M, P))
            self.kappa = np.full(M, 2.0)
        else:
            modes = piston.modes(n_modes)
            k = modes.wavenumbers
            phi0 = modes.shapes(np.zeros(1))[0]
            self.a = modes.amplitudes[..., 0] * phi0[:, None]
            self.b = modes.amplitudes[..., 1] * phi0[:, None]
            self.kappa = phi0 * phi0
        self.a[0], self.b[0], self.kappa[0] = 1.0, 0.0, 1.0
        self.k = k
        self.omega = s * k
        kl = k * lengths[-1]  # psi_n at the struck end: the model's end weights
        self.end_weights = self.a[:, -1] * np.cos(kl) + self.b[:, -1] * np.sin(kl)
        self.end_weights[0] = 1.0
        for arr in (self.travel, self.mu, self.impedance, self.mass_before, self.omega, self.a, self.b,
                    self.kappa, self.k, self.end_weights):
            arr.flags.writeable = False


@functools.lru_cache(maxsize=64)
def modal_basis(s: float, piston, n_modes: int) -> ModalBasis:
    """:class:`ModalBasis`, cached per ``(s, piston, n_modes)``."""
    return ModalBasis(s, piston, n_modes)


def initial_waves(basis: ModalBasis, q, v, p) -> list:
    """The piston's waves at impact as the exact solver's pieces (``initial`` of
    :func:`~impactbar.laws.rodrock.exact.exact_blow`; the module's text gives the fields).

    Parameters
    ----------
    basis : ModalBasis
    q, v : array_like, shape (..., N + 1)
        The modal state at impact (or a batch of them, the tangent's directions).
    p : float or array_like, shape (...)
        The drive's force at ``x = 0`` at impact (its static correction).

    Returns
    -------
    list of 2 P tuples ``(exps, degs, coefs)``
        Per segment, the right-going wave emitted at its driven-side end and the left-going one
        emitted at its struck-side end over ``[-T_i, 0)``, as functions of ``tau = t + T_i``
        (``coefs`` of shape ``(..., K)`` for a batch).

    The waves are linear in ``(q, q', p)``: their coefficients are one product with the basis's
    matrix (:func:`_wave_matrix`, made once per basis from :func:`_waves_of`, the fields' formulas).
    """
    q = np.asarray(q, dtype=float)
    x = np.concatenate((q, np.asarray(v, dtype=float), np.asarray(p, dtype=float)[..., None]), axis=-1)
    exps, degs, W, bounds = _wave_matrix(basis)
    coefs = x @ W
    return [(exps[i], degs[i], coefs[..., a:b]) for i, (a, b) in enumerate(bounds)]


@functools.lru_cache(maxsize=64)
def _wave_matrix(basis: ModalBasis):
    """The waves' exponents and degrees per piece, the matrix ``W`` (shape ``(2 N + 3, n)``, complex)
    of their coefficients from ``(q, q', p)``, and each piece's columns."""
    M = basis.omega.size
    unit = np.eye(2 * M + 1)
    pieces = _waves_of(basis, unit[:, :M], unit[:, M:2 * M], unit[:, 2 * M])
    W = np.concatenate([c for _, _, c in pieces], axis=-1)
    stops = np.cumsum([0] + [c.shape[-1] for _, _, c in pieces])
    W.flags.writeable = False
    return ([e for e, _, _ in pieces], [d for _, d, _ in pieces], W,
            [(int(a), int(b)) for a, b in zip(stops[:-1], stops[1:], strict=True)])


def _waves_of(basis: ModalBasis, q, v, p) -> list:
    """:func:`initial_waves` by the fields' formulas (the module's text), for states of shape
    ``(..., N + 1)``."""
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    p = np.asarray(p, dtype=float)[..., None]  # (a batch of states: leading axes, coefs alike)
    s = basis.s
    w = basis.omega[1:]
    Q = q[..., 1:] - p / (w * w) if w.size else q[..., 1:]
    out = []
    for i in range(basis.travel.size):
        T, Z, mu = basis.travel[i], basis.impedance[i], basis.mu[i]
        a, b = basis.a[1:, i], basis.b[1:, i]
        Vn = v[..., 1:] * (a - 1j * b)  # v = v0 + sum Re(Vn e^{i w theta})
        Nn = -(s * s) * mu * basis.k[1:] * Q * (b + 1j * a)  # the modes' part of N
        c_lin = p * (1.0 - basis.mass_before[i])  # N's static part p (1 - m_i) - p mu s theta
        slope = p * mu * s
        for sign in (1.0, -1.0):  # F = (N + Z v)/2, G = (N - Z v)/2
            A = 0.5 * (Nn + sign * Z * Vn)
            const = 0.5 * (c_lin + sign * Z * v[..., :1])
            if sign > 0.0:  # F: theta = T - tau
                C = A * np.exp(1j * w * T)  # Re(C e^{-i w tau})
                exps = np.concatenate(([0.0, 0.0], -1j * w, 1j * w))
                coefs = np.concatenate((const - 0.5 * slope * T, 0.5 * slope, 0.5 * C, 0.5 * np.conj(C)),
                                       axis=-1)
            else:  # G: theta = tau
                exps = np.concatenate(([0.0, 0.0], 1j * w, -1j * w))
                coefs = np.concatenate((const, -0.5 * slope, 0.5 * A, 0.5 * np.conj(A)), axis=-1)
            degs = np.concatenate(([0, 1], np.zeros(2 * w.size, dtype=np.int64)))
            out.append((exps, degs, coefs.astype(complex)))
    return out


def drive_pieces(load, t0: float, horizon: float, lead: float):
    """The drive ``p(t0 + t)`` for ``-lead <= t <= horizon`` as the exact solver's pieces (``drive`` of
    :func:`~impactbar.laws.rodrock.exact.exact_blow`).

    A Fourier load (a cosine's too) is one piece of its harmonics ``e^{+-i k t}``; a piecewise-constant
    one (a square wave's) a piece per level between its jumps; any other load, continuous, polynomial
    pieces (:func:`_polynomial_pieces`: its Chebyshev interpolants to ``1e-14`` of its sup).

    Raises
    ------
    ValueError
        A load of no known form that is not smooth enough for its polynomial pieces.
    """
    from ...dynamics.compiled_views import FOURIER, PIECEWISE
    from ...loads.abilities import compiled_kind

    abilities = load.abilities
    kind = compiled_kind(load, "__call__")
    s0 = -float(lead)
    if kind == FOURIER:
        ks = np.asarray(abilities.orders, dtype=float)
        pk = np.asarray(abilities.amplitudes, dtype=complex) * np.exp(1j * ks * (t0 + s0))
        exps = np.concatenate(([0.0], 1j * ks, -1j * ks))
        coefs = np.concatenate(([load.p0], 0.5 * pk, 0.5 * np.conj(pk)))
        return np.array([s0]), [(exps, np.zeros(exps.size, dtype=np.int64), coefs)]
    if kind == PIECEWISE:
        breaks, levels = abilities.pieces
        two_pi = 2.0 * math.pi
        lo, hi = t0 + s0, t0 + horizon
        m0 = math.floor(lo / two_pi) - 1
        m1 = math.ceil(hi / two_pi) + 1
        jumps = (breaks[None, :] + two_pi * np.arange(m0, m1 + 1)[:, None]).ravel()
        lev = np.tile(levels, m1 - m0 + 1)
        inside = (jumps > lo) & (jumps < hi)
        starts = np.concatenate(([s0], jumps[inside] - t0))
        values = np.concatenate((load(np.array([lo])), lev[inside]))
        pieces = [(np.zeros(1), np.zeros(1, dtype=np.int64), np.array([x])) for x in values]
        return starts, pieces
    return _polynomial_pieces(load, t0, s0, horizon)


#: Chebyshev degree and the largest interval of the polynomial pieces of a load the exact solver
#: knows no form of, and the accuracy they must reach (relative to the load's sup)
POLY_DEGREE, POLY_SPAN, POLY_TOL = 20, 0.25, 1e-14


def _polynomial_pieces(load, t0, s0, horizon):
    """A continuous load without a known form as polynomial pieces: Chebyshev interpolants of degree
    ``POLY_DEGREE`` on intervals of at most ``POLY_SPAN``, as monomials from each interval's start,
    each checked on a finer grid to ``POLY_TOL`` of the load's sup (halved while not)."""
    from numpy.polynomial import Chebyshev, Polynomial

    sup = max(float(load.sup_abs), 1e-300)
    n = max(1, math.ceil((horizon - s0) / POLY_SPAN))
    edges = list(s0 + (horizon - s0) * np.arange(n + 1) / n)
    starts, pieces = [], []
    i = 0
    while i < len(edges) - 1:
        a, b = edges[i], edges[i + 1]
        cheb = Chebyshev.interpolate(lambda x, a=a: load(t0 + a + x), POLY_DEGREE, domain=[0.0, b - a])
        mono = cheb.convert(kind=Polynomial, domain=[0.0, b - a], window=[0.0, b - a]).coef
        x = np.linspace(0.0, b - a, 4 * POLY_DEGREE + 1)
        err = float(np.max(np.abs(Polynomial(mono)(x) - load(t0 + a + x))))
        if err > POLY_TOL * sup:
            if b - a < 1e-9 * POLY_SPAN:
                raise ValueError(f"the exact blow cannot take this load ({type(load).__name__}): it is "
                                 "not a smooth function of time (a jump?) near load time "
                                 f"{t0 + a:.6g}; use RodRock(method='lattice')")
            edges.insert(i + 1, 0.5 * (a + b))
            continue
        starts.append(a)
        pieces.append((np.zeros(mono.size), np.arange(mono.size), mono.astype(complex)))
        i += 1
    return np.array(starts), pieces


def project(basis: ModalBasis, hist, t: float, end_position: float, heads=None):
    """The piston's modal state ``(q, q')`` at time ``t`` of an exact blow: the closed-form
    projections of the module's text, ``q_0`` such that the struck end is at ``end_position``.

    Parameters
    ----------
    basis : ModalBasis
    hist : tuple
        The blow's pieces, ``ExactBlow._hist`` (``(scale, (PF, PI, TK, TC, CHI, lam, ...), ...)``).
    t : float
        At most the blow's end; before it, ``heads`` must be the channels' first pieces (``None``:
        the receivers' cursors at the end, valid at the end only).
    end_position : float
        The struck end's position (model length unit).
    heads : array_like of int, optional

    Returns
    -------
    q, v : numpy.ndarray, shape (N + 1,)
    """
    scale, pools, *_ = hist
    PF, PI, TK, TC, CHI, lam, _ = pools
    P = basis.travel.size
    if heads is None:
        heads = CHI[: 2 * P, CHI_HEAD].copy()
    out = np.zeros((P, basis.omega.size, 2), dtype=complex)
    from .exact import _binomials

    piston_integrals((PF, PI, TK, TC, lam, _binomials()), np.asarray(heads, dtype=np.int64),
                     np.ascontiguousarray(basis.travel), float(t), np.ascontiguousarray(basis.omega), out)
    out *= scale
    return modal_state(basis, out, end_position)


def modal_state(basis: ModalBasis, out, end_position):
    """The modal state ``(q, q')`` from the piston's wave integrals ``out`` (shape ``(..., P, N + 1,
    2)``: ``int F e^{i omega_n theta}`` and ``int G e^{i omega_n theta}`` per segment, as
    :func:`~impactbar.laws.rodrock._exactmodal.piston_integrals` gives them) and the struck end's
    position (shape ``(...)``): the projections of the module's text, each of shape ``(..., N + 1)``.
    They are linear in both: one product with the basis's matrix (:func:`_projection_matrix`, made
    once per basis from :func:`_modal_of`, the projections' formulas)."""
    out = np.asarray(out)
    lead = out.shape[:-3]
    x = np.concatenate((out.real.reshape(lead + (-1,)), out.imag.reshape(lead + (-1,))), axis=-1)
    M = basis.omega.size
    qv = x @ _projection_matrix(basis)
    q, v = qv[..., :M], qv[..., M:]
    q[..., 0] += end_position
    return q, v


@functools.lru_cache(maxsize=64)
def _projection_matrix(basis: ModalBasis):
    """The matrix (shape ``(4 P (N + 1), 2 N + 2)``) of :func:`modal_state` from the real and the
    imaginary parts of the integrals ``out``, the end at 0."""
    P, M = basis.travel.size, basis.omega.size
    n = P * M * 2
    unit = np.eye(2 * n)
    q, v = _modal_of(basis, (unit[:, :n] + 1j * unit[:, n:]).reshape(2 * n, P, M, 2), 0.0)
    R = np.concatenate((q, v), axis=-1)
    R.flags.writeable = False
    return R


def _modal_of(basis: ModalBasis, out, end_position):
    """:func:`modal_state` by the projections' formulas (the module's text)."""
    Im = out[..., OUT_F] - out[..., OUT_G]  # int (F - G) e^{i w theta}, shape (..., P, M)
    Ip = out[..., OUT_F] + out[..., OUT_G]  # int (F + G) e^{i w theta}
    a, b = basis.a.T, basis.b.T  # (P, M)
    M = basis.omega.size
    v = np.empty(out.shape[:-3] + (M,))
    q = np.empty_like(v)
    v[..., 0] = np.sum(Im[..., 0].real, axis=-1)
    if M > 1:
        v[..., 1:] = np.sum(a[:, 1:] * Im[..., 1:].real + b[:, 1:] * Im[..., 1:].imag,
                            axis=-2) / basis.kappa[1:]
        proj = np.sum(b[:, 1:] * Ip[..., 1:].real - a[:, 1:] * Ip[..., 1:].imag, axis=-2)  # int N psi'/k
        w = basis.omega[1:]
        q[..., 1:] = -basis.s * basis.k[1:] * proj / (basis.kappa[1:] * w * w)
    c = basis.end_weights
    q[..., 0] = end_position - q[..., 1:] @ c[1:]
    return q, v


class RodSpec(NamedTuple):
    """The struck rod of an exact blow map: its segments' travel times and impedances (model
    units, shape ``(J,)`` each), the rock's and bit's parameters of
    :func:`~impactbar.laws.rodrock.exact.exact_blow` (``k``, ``k_u``, ``bit_mass``, ``feed``), the
    segments' lengths (piston lengths),
    whether the bit's reflection leaves (a semi-infinite rod), and whether the next flight's stop is
    the shank's rest position on the rock (else the rod's end where the blow left it)."""

    times: np.ndarray
    impedances: np.ndarray
    params: dict
    lengths: np.ndarray
    semi_infinite: bool = False
    on_rock: bool = True


def rod_spec(model) -> RodSpec:
    """The rod and rock of a model under :class:`~impactbar.RodRock` as a :class:`RodSpec` (a bit
    negligible as :func:`~impactbar.single_blow` decides taken as massless)."""
    from ._choice import _bit_is_negligible

    law = model.law
    s = float(model.s)
    bit = 0.0 if _bit_is_negligible(model, law) else law.bit_mass
    return RodSpec(np.array([g.travel_time(model) for g in law.segments]),
                   s * np.array([g.impedance for g in law.segments]),
                   dict(k=law.rock.k, k_u=law.rock.k_u, bit_mass=bit, feed=law.feed),
                   np.array([g.length for g in law.segments]))


class ExactBlowMap:
    """The contact step on the exact scheme at one impact time, as a map of the piston's modal state
    at impact (theory §4d; the module's text): the rod's segments, the piston's modal basis and the
    drive's pieces set up once.

    Parameters
    ----------
    model : BarModel
        Under :class:`~impactbar.RodRock`, uniform or stepped piston.
    load : Load
        The drive at ``x = 0``.
    t0 : float
        Load time of the impact.
    duration : float, optional
        The blow's length (model time); default the law's ``window``.
    rod : RodSpec, optional
        The struck rod; default the model's :class:`~impactbar.RodRock` law's (:func:`rod_spec`).
    """

    def __init__(self, model, load, t0, *, duration=None, rod=None):
        self.model, self.load, self.t0 = model, load, float(t0)
        self.basis = modal_basis(float(model.s), model.piston, model.n_modes)
        self.rod = rod = rod_spec(model) if rod is None else rod
        self.rod_times, self.rod_impedances, self.params = rod.times, rod.impedances, rod.params
        self.duration = float(model.law.window(model) if duration is None else duration)
        self.p_end = float(np.asarray(load(np.array([self.t0])), dtype=float)[0])
        h = float(min(self.basis.travel.min(), self.rod_times.min()))
        self.drive = drive_pieces(load, self.t0, self.duration, lead=h)

    def solve(self, q, v, *, t_max=None, record=False, lean=False, log=0, energies=True, certified=False,
              defer=False, keep=None):
        """The :class:`~impactbar.laws.rodrock.exact.ExactBlow` of an arrival in state ``(q, q')``
        (the end on the shank), run to ``t_max`` (default the blow's duration), with ``certified``
        only until its end is certified (the solver's certificate under a drive: the coupled blow's,
        :mod:`~impactbar.laws.rodrock.coupled_exact`) if that comes first; with ``lean`` only
        the solver's workspace and scale (:func:`~impactbar.laws.rodrock.exact.exact_blow`), with
        ``log`` rows of its switch log (:mod:`~impactbar.laws.rodrock.exactjac`); without
        ``energies`` its energies (and those derived from them) NaN, not accounted (the histories
        alone wanted); with ``defer`` a pair: the blow's histories alone (its energies not those of
        its end, its pieces on the solver's arrays until this thread's next blow) and a callable
        giving the whole blow (the coupled blow's iterates, of which the last is kept); ``keep``: the
        snapshots a blow goes on from and takes (:func:`~impactbar.laws.rodrock.exact.exact_blow`'s
        ``_keep``: the coupled blow's iterates, each the same as the last up to where their drives
        part)."""
        from ._exactdata import _Drive
        from .exact import exact_blow

        init = initial_waves(self.basis, q, v, self.p_end)
        horizon = self.duration if t_max is None else float(t_max)
        # the drive checked once per map (its many blows: a Jacobian's, the chord method's), the
        # waves of a finite state trusted (a state that is not finite: checked, and refused, there)
        trusted = bool(np.all(np.isfinite(q)) and np.all(np.isfinite(v)) and math.isfinite(self.p_end))
        drive = self.drive
        if trusted and drive is not None:
            checked, wrapped = getattr(self, "_checked_drive", (None, None))
            if checked is not drive:
                wrapped = _Drive(drive)
                self._checked_drive = (drive, wrapped)
            drive = wrapped
        out = exact_blow(self.basis.travel, self.basis.impedance, self.rod_times, self.rod_impedances,
                         initial=init, drive=drive, fixed_horizon=not certified,
                         t_max=horizon, record=record,
                         lean=lean, semi_infinite=self.rod.semi_infinite, _trusted=trusted, _log=log,
                         _pool=self._pool_for(horizon), _energies=energies, _defer=defer, _keep=keep,
                         **self.params)
        # the pool this blow filled, for the map's next (its many blows alike: a first one grows its
        # pool, run again, and the next start there)
        if lean:
            ws, _ = out  # (the workspace, its scale)
            used = (ws[WS_CNT][CNT_PIECES], ws[WS_CNT][CNT_TERMS], ws[WS_BI][BI_NEP])
        else:
            ex, _ = out if defer else (out, None)  # (the blow's first result, its finisher)
            used = (ex.pieces, ex.diagnostics["terms"], ex.loadings.shape[0])
        self._pool = (*(int(x) for x in used), horizon)
        return out

    def _pool_for(self, t_max):
        """The pool to start a blow to ``t_max`` on: twice what the last blow filled, its pieces
        grown as the square of the horizon, its terms as the cube (the waves' breaks multiply, and
        each piece's terms), where this one runs longer."""
        last = getattr(self, "_pool", None)
        if last is None:
            return None
        pieces, terms, episodes, horizon = last
        grow = max(t_max / horizon, 1.0)
        return 2 * pieces * grow ** 2 + 16, 2 * terms * grow ** 3 + 16, 2 * episodes * grow + 16

    def _end(self, shank, gap, permanent):
        """The struck end's position after the blow from the stop of the next flight: the shank's
        new rest position (on the rock, its permanent penetration) or the long rod's end."""
        return shank - gap - (permanent if self.rod.on_rock else shank)

    def state_after(self, ex, on_stop=False):
        """The modal state at the end of ``ex``, positions from the stop of the next flight (the
        shank's new rest position, or the long rod's end; the end pressed beyond it put on it); with
        ``on_stop`` a third value: whether it was (the tangent's, :func:`~.exactjac.tangents`)."""
        end = self._end(ex.shank_displacement, ex.gap, ex.permanent_penetration)
        qa, va = project(self.basis, ex._hist, ex.duration, end)
        qa, over = self._on_stop(qa)
        return (qa, va, over) if on_stop else (qa, va)

    def _on_stop(self, qa):
        """``qa`` (the modal positions after a blow) with the end put on the stop where it is pressed
        beyond it (in place), and whether it was."""
        over = float(self.basis.end_weights @ qa)
        if over > 0.0:
            qa[0] -= over
        return qa, over > 0.0

    def __call__(self, y):
        """The state after the blow as one vector of shape ``(2 N + 2,)`` from the arrival state
        ``y`` (its end moved onto the shank first): the numbers of :meth:`contact`'s record, without
        the record and the energies."""
        M = self.model.n_modes + 1
        c = self.basis.end_weights
        q = np.array(y[:M], dtype=float)
        q[0] -= float(c @ q)
        ws, scale = self.solve(q, np.asarray(y[M:], dtype=float), lean=True)
        qa, va, _ = self.after_run(ws, scale)
        return np.concatenate((qa, va))

    def after_run(self, ws, scale):
        """The state after a lean run of the blow (:meth:`solve` with ``lean=True``: its workspace
        ``ws`` and force scale ``scale``), as :meth:`__call__` and the tangents
        (:mod:`~impactbar.laws.rodrock.exactjac`) take it: ``(qa, va, on_stop)``, the modal positions
        from the next flight's stop (the end put on it where pressed beyond), shape ``(N + 1,)``, the
        velocities, and whether the end was put on the stop."""
        PF, PI, TK, TC, CNT, CHI, CH_T, CH_TOL, lam = ws[:9]
        NSF, BS = ws[WS_NSF], ws[WS_BS]
        n_p = self.basis.travel.size
        end = self._end(scale * NSF[n_p, NSF_SHANK], scale * NSF[n_p, NSF_GAP], scale * BS[BS_PPERM])
        qa, va = project(self.basis, (scale, (PF, PI, TK, TC, CHI, lam, None)), float(ws[WS_CT][CT_T]), end)
        qa, on_stop = self._on_stop(qa)
        return qa, va, on_stop

    def shifted(self, t0s):
        """Copies of this map at the load times ``t0s`` (the bases shared): the impact map's time
        derivative (:meth:`RodRock.impact_map`)."""
        import copy

        out = []
        h = float(min(self.basis.travel.min(), self.rod_times.min()))
        for t0 in t0s:
            m = copy.copy(self)
            m.t0 = float(t0)
            m.p_end = float(np.asarray(self.load(np.array([m.t0])), dtype=float)[0])
            m.drive = drive_pieces(self.load, m.t0, self.duration, lead=h)
            out.append(m)
        return out

    def contact(self, q, v):
        """The blow of an arrival in state ``(q, q')`` (the end on the shank) and its record, an
        :class:`ExactRockContact`."""
        q = np.array(q, dtype=float)
        v = np.array(v, dtype=float)
        ex = self.solve(q, v, record=True)
        qa, va = self.state_after(ex)
        return ExactRockContact(self, q, v, ex, qa, va)


class ExactRockContact(RockContact):
    """One blow of the simulator under :class:`~impactbar.RodRock` on the exact scheme (theory §4d;
    :mod:`impactbar.laws.rodrock.exactmap`): the record of :meth:`RodRock.contact`, with the attributes
    of :class:`RockContact`; its :attr:`blow` the :class:`~impactbar.laws.rodrock.blow.Blow` of the
    exact solution (``method = "exact"``, ``grid_loss = 0``), and :meth:`state_at` and :meth:`account`
    exact at any ``tau``.

    Its :attr:`blow`'s histories are sampled when it is first read (an orbit's Newton iterates read
    only the state after their blows: some 0.05 s of CPU a blow on
    ``examples/circuit_drifter_rock.toml`` not spent), from the blow's own copies of its pieces: the
    same numbers whenever it is read.
    """

    def __init__(self, bmap, q, v, ex, q_after, v_after):
        model = bmap.model
        self.model, self.load = model, bmap.load
        self.t0 = bmap.t0
        self.q_before, self.v_before = q, v
        self._map, self.exact = bmap, ex
        self._blow, self._apart = None, False  # (the blow sampled when first read: blow)
        self._blow_of = (float(model.s), bmap.rod.lengths, bmap.rod_times, bmap.basis.travel * float(model.s))
        self.duration = ex.duration
        self.q_after, self.v_after = q_after, v_after
        self._partials = {}
        #: under a drive: what the drive met over the blow (its tangent's data, a
        #: :class:`~impactbar.laws.rodrock.coupled_exact.Coupling`)
        self.coupling = None
        #: under a drive, marching: ``(kept, on_stop)``, the blow's switch log as
        #: :func:`~impactbar.laws.rodrock.exactjac.kept_primal` keeps it (None where it did not) and
        #: whether the end was put on the stop (its tangent's, without solving the blow again)
        self.switch_log = None

    @property
    def blow(self):
        """The :class:`~impactbar.laws.rodrock.blow.Blow` of the exact solution
        (:func:`~impactbar.laws.rodrock.exactrecord.blow_from_exact`), sampled when first read."""
        if self._blow is None:
            from .exactrecord import blow_from_exact

            self._blow = blow_from_exact(self.exact, *self._blow_of)
            if self._apart:
                self._blow = self._blow.with_stored_apart()
        return self._blow

    @blow.setter
    def blow(self, value):
        self._blow = value

    def stored_apart(self) -> None:
        """Its :attr:`blow` with ``stored_apart``
        (:meth:`~impactbar.laws.rodrock.blow.Blow.with_stored_apart`: the work on rock the work
        dissipated in the rock), now or when it is sampled."""
        self._apart = True
        if self._blow is not None:
            self._blow = self._blow.with_stored_apart()

    def _at(self, tau: float):
        """The exact blow solved again up to ``tau`` (cached)."""
        tau = self._check_tau(tau)
        if tau <= 0.0:
            return "start"
        if tau >= self.duration:
            return "end"
        if tau not in self._partials:
            self._partials[tau] = self._map.solve(self.q_before, self.v_before, t_max=tau)
        return self._partials[tau]

    def _state_of(self, b):
        """The modal state at the end of the blow ``b`` solved up to ``tau`` (of :meth:`_at`)."""
        return project(self._map.basis, b._hist, b.duration, -b.gap)

    def _account_of(self, b) -> tuple[float, float, float]:
        """:meth:`account` of the blow ``b`` solved up to ``tau`` (``"end"``: the whole blow)."""
        if isinstance(b, str):
            b = self.exact
        return b.drive_work, b.energy_at_impact + b.drive_work - b.piston_energy, b.piston_energy
