"""The start of a simulation: the free-free bar's modal state (theory §2, §8)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._shared.validate import check_int, check_real
from ..model import MAX_MODES, BarModel


# --------------------------------------------------------------------------------------------------
# initial state
# --------------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class InitialState:
    r"""Modal state of the free-free bar (theory §2).

    :math:`u(x) = q_0 + 2 \sum_{n \ge 1} q_n \cos(n \pi x)` and the same for the velocity field.

    Parameters
    ----------
    modal_displacement : array_like, shape (N + 1,)
        ``q_0..q_N`` (dimensionless).
    modal_velocity : array_like, shape (N + 1,)
        ``q_0'..q_N'``.

    Raises
    ------
    ValueError
        If the arrays are not 1-d, of different lengths, empty, or not finite.

    Examples
    --------
    >>> from impactbar import InitialState
    >>> start = InitialState.rigid(end_displacement=-0.01, velocity=0.0, n_modes=2)
    >>> start.modal_displacement, start.modal_velocity
    (array([-0.01,  0.  ,  0.  ]), array([0., 0., 0.]))
    """

    modal_displacement: np.ndarray
    modal_velocity: np.ndarray

    def __post_init__(self) -> None:
        q = _real_vector("modal_displacement", self.modal_displacement)
        v = _real_vector("modal_velocity", self.modal_velocity)
        if q.size != v.size:
            raise ValueError(
                f"modal_velocity must have the length of modal_displacement ({q.size}); "
                f"got {v.size}"
            )
        q.setflags(write=False)
        v.setflags(write=False)
        object.__setattr__(self, "modal_displacement", q)
        object.__setattr__(self, "modal_velocity", v)

    @classmethod
    def _trusted(cls, q: np.ndarray, v: np.ndarray) -> InitialState:
        """A state from arrays the simulator made (finite, 1-d, of one length): no checks, no copy."""
        self = object.__new__(cls)
        q.setflags(write=False)
        v.setflags(write=False)
        self.__dict__.update(modal_displacement=q, modal_velocity=v)  # (a frozen dataclass's fields)
        return self

    @property
    def n_modes(self) -> int:
        """Flexible modes ``N`` the state carries."""
        return self.modal_displacement.size - 1

    @classmethod
    def rigid(cls, end_displacement, velocity, n_modes: int = 0) -> InitialState:
        """An undeformed bar with its struck end at ``end_displacement`` moving at ``velocity``.

        Parameters
        ----------
        end_displacement : float
            ``u(1)``, ``<= 0`` (the stop is at 0).
        velocity : float
            Uniform velocity (positive towards the stop).
        n_modes : int, optional
            Flexible modes to carry (all zero). A one-mode state is also accepted by
            :func:`simulate` for any model and padded with zeros.

        Raises
        ------
        ValueError
            If ``end_displacement > 0`` (the start would penetrate the stop).
        """
        e = check_real("end_displacement", end_displacement, hi=0.0)
        vel = check_real("velocity", velocity)
        n_modes = check_int("n_modes", n_modes, lo=0, hi=MAX_MODES)
        q = np.zeros(n_modes + 1)
        v = np.zeros(n_modes + 1)
        q[0] = e
        v[0] = vel
        return cls(q, v)

    @classmethod
    def from_fields(cls, u0, v0, model: BarModel) -> InitialState:
        r"""Project displacement and velocity fields on the free-free modes (eq. 5).

        Parameters
        ----------
        u0, v0 : callable
            Vectorised functions of ``x`` in ``[0, 1]`` giving ``u(x, t0)`` and ``u_t(x, t0)``.
        model : BarModel
            Gives the number of modes ``N``.

        Returns
        -------
        InitialState
            :math:`q_n = \int_0^1 u_0(x) \cos(n \pi x)\,dx` (Gauss-Legendre, exact for polynomials of
            degree below 64 per panel), ``n = 0..N``.

        Raises
        ------
        ValueError
            If a field is not callable or returns non-finite values, or ``u0(1) > 0``.
        """
        if not isinstance(model, BarModel):
            raise ValueError(f"model must be a BarModel; got {type(model).__name__}")
        for name, f in (("u0", u0), ("v0", v0)):
            if not callable(f):
                raise ValueError(f"{name} must be a callable of x; got {type(f).__name__}")
        panels = max(8, model.n_modes // 4 + 1)
        xg, wg = np.polynomial.legendre.leggauss(32)
        edges = np.linspace(0.0, 1.0, panels + 1)
        half = 0.5 * (edges[1:] - edges[:-1])[:, None]
        x = (half * (xg[None, :] + 1.0) + edges[:-1, None]).ravel()
        w = (half * wg[None, :]).ravel()
        basis = np.cos(np.pi * np.outer(x, np.arange(model.n_modes + 1)))
        out = []
        for name, f in (("u0", u0), ("v0", v0)):
            vals = np.broadcast_to(np.asarray(f(x), dtype=float), x.shape)
            if not np.all(np.isfinite(vals)):
                raise ValueError(f"{name} must return finite values on [0, 1]")
            out.append((w * vals) @ basis)
        end = float(np.asarray(u0(np.array([1.0])), dtype=float).ravel()[0])
        if end > 0.0:
            raise ValueError(f"u0 must keep the struck end off the stop, u0(1) <= 0; got {end}")
        q, v = out
        return cls(q, v)


def _real_vector(name, value) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float, copy=True)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a 1-d array of real numbers; got {value!r}") from exc
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"{name} must be a non-empty 1-d array; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite; got {arr}")
    return arr
