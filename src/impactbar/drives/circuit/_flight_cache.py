"""The data the oil circuit's compiled kernels read (theory §11, "The integrator"): the parameter
vector of a drive and a bar (:func:`_par_base`), the network's generated code by mode
(:func:`_network_code`), and what every flight in one mode shares (:class:`FlightData`,
:func:`flight_data`), each made once and kept."""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np

from ..._shared.bounded import remember
from ..._shared.wrappers import require_jit
from . import _bar as K

__all__ = ["FlightData", "flight_data"]

#: the most flights' data (:func:`flight_data`) a drive keeps, by model, mode and kind of flight (an
#: orbit's modes are some tens); past it the store starts again
_FLIGHT_DATA_SIZE = 256


class FlightData(NamedTuple):
    """What every flight of a drive with one bar in one mode shares, made once
    (:meth:`HydraulicCircuitDrive._flight_data`; theory §11, "The integrator").

    Attributes
    ----------
    par : numpy.ndarray
        The kernels' parameters: :meth:`HydraulicCircuitDrive._par` with the network after it (model
        units; shared by the flights, never written).
    code : module
        The code generated for the network's topology (:mod:`._netgen`).
    directions : numpy.ndarray of int32
        The events' directions for CVODE's root finding (:meth:`HydraulicCircuitDrive._directions`).
    end_weights, drive_weights : numpy.ndarray
        The bar's ``end_weights`` and ``drive_weights`` (:class:`~impactbar.BarModel`; dimensionless),
        never written.
    """

    par: np.ndarray
    code: object
    directions: np.ndarray
    end_weights: np.ndarray
    drive_weights: np.ndarray


def flight_data(drive, model, mode, variational=False) -> FlightData:
    """What a flight of ``model`` under ``drive`` in ``mode`` reads, made once per drive and kept
    (the drive's ``_flights`` store): the same arrays as the drive's ``_par`` (with the network
    of ``_compiled_network`` after it) and ``_directions`` give, and the bar's weights, without their
    some 60 microseconds a flight.

    Parameters
    ----------
    drive : HydraulicCircuitDrive
    model : BarModel
        The bar (hashable; its end weights and frequencies are read).
    mode : tuple of int
        The drive's mode.
    variational : bool, optional
        A flight with the variational equations.

    Returns
    -------
    FlightData
        Its arrays shared by every flight of the key: never to be written.
    """
    key = (model, tuple(mode), bool(variational))
    store = drive._flights
    data = store.get(key)
    if data is None:
        net, code = drive._compiled_network(mode)
        data = FlightData(np.concatenate((drive._par(model, mode, variational), net)), code,
                          np.asarray(drive._directions(mode), dtype=np.int32), model.end_weights,
                          model.drive_weights)
        remember(store, key, data, _FLIGHT_DATA_SIZE)
    return data


class _RateModel:
    """The little of a uniform bar's model that the drive's ``rate`` needs (the drives sit below
    :class:`~impactbar.BarModel`): the mode count and the ends' weights."""

    def __init__(self, M):
        self.n_modes, self.d, self.s = M - 1, 0.0, 1.0
        n = np.arange(M)
        self.end_weights = np.where(n == 0, 1.0, 2.0 * (-1.0) ** n)
        self.frequencies = np.pi * n
        self.drive_weights = np.where(n == 0, 1.0, 2.0)


@functools.lru_cache(maxsize=64)
def _network_code(drive, mode: tuple):
    """The drive's ``_compiled_network``, kept (the network's composition and the generated module's
    look-up take some 100 microseconds, against a flight's milliseconds)."""
    from . import _netgen

    require_jit("the oil circuit's flight (CVODE's C callbacks, compiled by numba.cfunc)")
    net = drive._network(mode)
    return net, _netgen.generate(net)


@functools.lru_cache(maxsize=16)
def _rate_model(M: int) -> _RateModel:
    """One :class:`_RateModel` per mode count (by identity a key of :func:`_par_base`'s cache,
    built once rather than at every call of the vector field)."""
    return _RateModel(M)


@functools.lru_cache(maxsize=64)
def _par_base(drive, model) -> np.ndarray:
    """The parameter vector of the compiled kernels (:mod:`._bar`) for a drive and a bar (its
    struck end's weights, squared frequencies and driven end's weights: a stepped piston's too)."""
    M = model.n_modes + 1
    d = float(model.d)
    va = drive.valve
    par = np.zeros(K.HEAD + 3 * M)
    par[K.ALPHA] = drive.chambers.area_ratio
    par[K.XOUT] = va.switch_out
    par[K.XIN] = va.switch_in if va.switch_in is not None else -1.0
    par[K.DAMP] = d
    par[K.NM] = float(M)
    par[K.HEAD:K.HEAD + M] = model.end_weights
    par[K.HEAD + M:K.HEAD + 2 * M] = model.frequencies ** 2
    par[K.HEAD + 2 * M:K.HEAD + 3 * M] = model.drive_weights
    par.flags.writeable = False
    return par
