r"""The circuit during a blow driven by CVODE from compiled code (theory §11, "The coupled blow"): the
vector field, Jacobian and events of :mod:`._endkernel` as compiled C callbacks, flown by
:func:`._cvode.fly`, so that no Python runs between a stretch's start and its end.

CVODE's user data is one array ``(len(par), a, 1/Z, par...)``: the wave ``a`` arriving at the driven
end, constant over the stretch (the lattice's steps), the driven end's admittance ``1/Z`` and the
kernels' parameters. A stretch whose ``a`` varies within it (a callable) goes through scikit-sundae's
Python interface instead (:func:`.endflight.circuit_end_flight`). The options are those of
:class:`._cvode.Workspace` (scikit-sundae's defaults), so either way takes the same steps.
"""

from __future__ import annotations

import numba as nb
import numpy as np

from ...dynamics.kernels import CACHE
from . import _cvode as CV
from . import _endkernel as EK
from ._cvode import _c, _d, _dp, _p

__all__ = ["CALLBACKS", "user_data", "fly"]

_HEAD = 3  # len(par), a, 1/Z


@nb.cfunc(_c(_d, _p, _p, _dp), cache=CACHE)
def _rhs_c(t, y, yp, user_data):
    """CVODE's ``CVRhsFn``: :func:`._endkernel.rhs`."""
    n = int(nb.carray(user_data, 1)[0])
    ud = nb.carray(user_data, _HEAD + n)
    EK.rhs(nb.carray(CV._nv_data(y), EK.N_STATE), nb.carray(CV._nv_data(yp), EK.N_STATE), ud[_HEAD:],
           ud[1:_HEAD])
    return 0


@nb.cfunc(_c(_d, _p, _p, _p, _dp, _p, _p, _p), cache=CACHE)
def _jac_c(t, y, fy, J, user_data, tmp1, tmp2, tmp3):
    """CVODE's ``CVLsJacFn``: :func:`._endkernel.jac` into the dense matrix (stored by columns)."""
    n = int(nb.carray(user_data, 1)[0])
    ud = nb.carray(user_data, _HEAD + n)
    JJ = nb.carray(CV._dense_data(J), (EK.N_STATE, EK.N_STATE)).T
    EK.jac(nb.carray(CV._nv_data(y), EK.N_STATE), JJ, ud[_HEAD:], ud[1:_HEAD])
    return 0


@nb.cfunc(_c(_d, _p, _dp, _dp), cache=CACHE)
def _events_c(t, y, g, user_data):
    """CVODE's ``CVRootFn``: :func:`._endkernel.events`."""
    n = int(nb.carray(user_data, 1)[0])
    ud = nb.carray(user_data, _HEAD + n)
    EK.events(nb.carray(CV._nv_data(y), EK.N_STATE), nb.carray(g, EK.N_EVENTS), ud[_HEAD:])
    return 0


#: the callbacks of :func:`._cvode.workspace` for the circuit during a blow
CALLBACKS = (_rhs_c, _jac_c, _events_c, EK.N_EVENTS)


def user_data(par: np.ndarray, a: float, impedance: float) -> np.ndarray:
    """The user data of the callbacks: ``(len(par), a, 1/Z, par...)``, shape ``(3 + len(par),)``."""
    return np.concatenate(([float(par.size), float(a), 1.0 / float(impedance)], par))


def fly(t0: float, y0: np.ndarray, t_end: float, rtol: float, atol: float, directions, data: np.ndarray,
        max_steps: int):
    """One stretch from ``y0`` at ``t0`` to the first event in ``directions`` (int32, one per event)
    or ``t_end``: what :func:`._cvode.fly` returns, every component kept."""
    ws = CV.workspace(EK.N_STATE, 0, CALLBACKS)
    return CV.fly(ws.mem, ws.y, t0, y0, t_end, rtol, atol, directions, data, EK.N_STATE, max_steps)
