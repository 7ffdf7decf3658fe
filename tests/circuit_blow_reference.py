r"""The preset oil circuit during a blow written by hand (theory §11, "The coupled blow"): the tests'
reference for the code the library generates for a blow (``impactbar.drives.circuit._endgen``), the
circuit's vector field of ``circuit_field_reference`` with the driven end's motion given by the law
instead of the bar's modes.

Inside a blow the law (the wave law's window, the rod-rock law's lattice) knows the wave ``a(t)``
arriving at the piston's driven end from inside the piston (independent of the drive over a stretch
of time, the round trip to the first change of impedance), and the driven end answers the drive's
force ``p`` as a semi-infinite bar of impedance ``Z``: ``u_t(0, t) = a(t) + p / Z``. The integrated
state is ``Y = (w, p_f, p_r, p_s, x_v, I, E_0..E_7)``: the driven end's displacement ``w = -u(0, t)``
(``w' = -u_t(0)``), the circuit's state, the force's integral ``I = int p dt`` and the eight energy
quadratures of ``circuit_field_reference``. The vector field is its ``_base`` on a one-mode bar whose
driven end is ``q_0 = -w`` moving at ``q_0' = u_t(0)`` (the same equations, one source of them).

``par`` is ``circuit_field_reference.preset_par`` of the drive on a one-mode bar. ``ext = (a, 1/Z)``
is set by the caller on each stretch where ``a`` is constant (the lattice's step) or each evaluation
(the wave law's smooth ``a``).
"""

import numba as nb
import numpy as np

import circuit_field_reference as K
from impactbar.drives.circuit import _bar as B
from impactbar.drives.circuit._endgen import EXT_A, EXT_IZ, EXT_SIZE, Y_CIRCUIT, Y_W  # noqa: F401

#: the size of the integrated state: ``w``, four of the circuit, ``I``, the energies
N_STATE = 6 + B.N_ENERGY
#: the events during a blow: the ramp's end, the supply pressure through the pre-charge and the relief
N_EVENTS = 3
#: their indices among the flight kernel's events (``RAMP_EV``, ``ACC_EV``, ``REL_EV``)
FLIGHT_EVENTS = (B.RAMP_EV, B.ACC_EV, B.REL_EV)
#: the room :func:`rhs_in` and :func:`jac_in` take for their intermediate values
SCRATCH = 6 + B.N_ENERGY + 40
#: where ``circuit_field_reference``'s own parameters of the preset's parts start in ``par`` (its
#: ``preset_par`` on the one-mode bar: ``HEAD + 3 M``, ``M = 1``)
OWN = B.HEAD + 3

_JIT = dict(cache=True, nogil=True, error_model="numpy")


@nb.njit(**_JIT)
def _one_mode(y, par, ext, buf):
    """The one-mode bar state of ``circuit_field_reference._base`` for ``y``: ``(q_0, q_0', p_f, p_r,
    p_s, x_v)`` with ``q_0 = -w``, ``q_0' = u_t(0) = a + p / Z``; returns ``u_t(0)``."""
    p = y[2] - par[OWN + K.ALPHA] * y[1]
    ut = ext[EXT_A] + p * ext[EXT_IZ]
    buf[0] = -y[0]
    buf[1] = ut
    for i in range(4):
        buf[2 + i] = y[1 + i]
    for i in range(B.N_ENERGY):
        buf[6 + i] = 0.0
    return ut


@nb.njit(**_JIT)
def rhs(y, yp, par, ext):
    """``yp = f(y)`` of the state during a blow (module docstring)."""
    rhs_in(y, yp, par, ext, np.empty(SCRATCH))


@nb.njit(**_JIT)
def rhs_in(y, yp, par, ext, work):
    """:func:`rhs` with its intermediate values in ``work`` (shape ``(SCRATCH,)``: the compiled
    callbacks' user data, no allocation a call)."""
    buf = work[:6 + B.N_ENERGY]
    out = work[6 + B.N_ENERGY:2 * (6 + B.N_ENERGY)]
    ut = _one_mode(y, par, ext, buf)
    K._base(buf, par, 1, out)
    yp[0] = -ut
    for i in range(4):
        yp[1 + i] = out[2 + i]
    yp[5] = y[2] - par[OWN + K.ALPHA] * y[1]
    for i in range(B.N_ENERGY):
        yp[6 + i] = out[6 + i]


@nb.njit(**_JIT)
def jac(y, JJ, par, ext):
    """The Jacobian of :func:`rhs` (the energies' rows zero: they feed nothing back), by the chain
    rule from ``circuit_field_reference.jac_base`` on the one-mode bar."""
    jac_in(y, JJ, par, ext, np.empty(SCRATCH))


@nb.njit(**_JIT)
def jac_in(y, JJ, par, ext, work):
    """:func:`jac` with its intermediate values in ``work`` (as :func:`rhs_in`)."""
    n = JJ.shape[0]
    for i in range(n):
        for j in range(n):
            JJ[i, j] = 0.0
    buf = work[:6 + B.N_ENERGY]
    _one_mode(y, par, ext, buf)
    A = work[6 + B.N_ENERGY:6 + B.N_ENERGY + 36].reshape((6, 6))
    K.jac_base(buf, par, 1, A)
    alpha, iz = par[OWN + K.ALPHA], ext[EXT_IZ]
    dut = work[6 + B.N_ENERGY + 36:6 + B.N_ENERGY + 40]  # d u_t(0) / d(p_f, p_r, p_s, x_v)
    dut[0] = -alpha * iz
    dut[1] = iz
    dut[2] = 0.0
    dut[3] = 0.0
    for i in range(4):
        JJ[1 + i, 0] = -A[2 + i, 0]  # q_0 = -w
        for j in range(4):
            JJ[1 + i, 1 + j] = A[2 + i, 2 + j] + A[2 + i, 1] * dut[j]
    for j in range(4):
        JJ[0, 1 + j] = -dut[j]
    JJ[5, 1] = -alpha
    JJ[5, 2] = 1.0


@nb.njit(**_JIT)
def events(y, g, par):
    """The event functions during a blow (their zeros; inactive ones held at 1): the ramp's end, the
    supply pressure through the pre-charge and through the relief pressure (as
    ``circuit_field_reference.events``)."""
    K.circuit_events(y[4], y[3], par, OWN, g, 0)


@nb.njit(**_JIT)
def field_at(ys, par, ext, out):
    """:func:`rhs` at each row of ``ys`` (the pieces' Hermite interpolation); ``ext`` one row per
    row of ``ys``."""
    for r in range(ys.shape[0]):
        rhs(ys[r], out[r], par, ext[r])
