"""The brute-force bifurcation diagram: long simulations over a range of a parameter (paper
Section 5), to set beside continued branches."""

from __future__ import annotations

import math

import numpy as np

from .._shared.validate import check_real
from ..loads import Load
from ..model import BarModel
from ..simulation.simulate import InitialState, simulate
from .parameters import _check_parameter, with_parameter

__all__ = ["simulated_diagram"]

TWO_PI = 2.0 * math.pi


def simulated_diagram(model: BarModel, load: Load, parameter: str, values, *, transient: float = 100.0,
                      record: float = 20.0, start: InitialState | None = None, t0: float = 0.0) -> dict:
    """Impacts of long simulations at each parameter value, each run started from the end of the
    previous one (so that an attractor is followed as the parameter moves).

    Parameters
    ----------
    model : BarModel
    load : Load
    parameter : str
        One of ``"p0"``, ``"pk"``, ``"q"``, ``"kappa"``, ``"R"``, ``"d"``, ``"s"``.
    values : array_like, shape (V,)
        Parameter values, in the order they are visited.
    transient : float
        Load periods simulated and discarded at each value (``> 0``).
    record : float
        Load periods whose impacts are recorded (``> 0``).
    start : InitialState, optional
        State at the first value; default the bar at rest, its end ``0.01`` from the stop.
    t0 : float
        Load time of ``start``.

    Returns
    -------
    dict
        ``"parameter"``, ``"phase"`` (rad, load phase of each recorded impact), ``"impact_velocity"``
        and ``"time"``: flat arrays of equal length, one entry per recorded impact.

    Raises
    ------
    ValueError
        For a bad argument (named in the message).
    """
    _check_parameter(model, load, parameter)
    values = np.atleast_1d(np.asarray(values, dtype=float))
    if values.ndim != 1 or values.size == 0 or not np.all(np.isfinite(values)):
        raise ValueError("values must be a non-empty 1-d array of finite numbers")
    transient = check_real("transient", transient, lo=0.0, lo_open=True)
    record = check_real("record", record, lo=0.0, lo_open=True)
    state = start if start is not None else InitialState.rigid(-0.01, 0.0, n_modes=model.n_modes)
    t0 = check_real("t0", t0)
    out = {"parameter": [], "phase": [], "impact_velocity": [], "time": []}
    for v in values:
        m, ld = with_parameter(model, load, parameter, float(v))
        t_mid = t0 + TWO_PI * transient
        t_end = t_mid + TWO_PI * record
        tr = simulate(m, ld, state, t_end, t0=t0)
        sel = tr.impact_times > t_mid
        n = int(np.count_nonzero(sel))
        out["parameter"].append(np.full(n, v))
        out["phase"].append(np.mod(tr.impact_times[sel], TWO_PI))
        out["impact_velocity"].append(tr.impact_velocities[sel])
        out["time"].append(tr.impact_times[sel])
        state = tr.final_state
        t0 = tr.t_end
    return {k: np.concatenate(x) if x else np.empty(0) for k, x in out.items()}
