"""The dimensionless bar: wave-speed ratio, damping, restitution, modes kept (theory §1-§2)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar, NamedTuple

import numpy as np

from ._shared.parameters import Parameter, table_of
from ._shared.schema import Field, Schema
from ._shared.validate import check_int, check_real
from .dynamics.stepped import SteppedPiston
from .laws import ContactLaw, get_law, piston_law

__all__ = ["BarModel"]

#: Largest number of flexible modes accepted; beyond it the modal sums gain nothing in double precision.
MAX_MODES = 4096

#: The ranges of the bar's parameters (eq. 2; their names and long names: :attr:`BarModel.parameters`),
#: the records of :meth:`BarModel.parameter_table`; the constructor checks them again.
_MODEL_RANGES = {
    "s": {"low": 0.0, "low_open": True},
    "d": {"low": 0.0},
    "R": {"low": 0.0, "high": 1.0},
    "n_modes": {"low": 0, "high": MAX_MODES, "continuable": False},
}
#: Largest ``s * n_modes`` with flexible modes: the highest mode's phase over a period,
#: ``2 pi^2 s n``, must stay well inside double precision.
MAX_STIFFNESS = 1e12
#: Largest finite double: the modal frequencies ``s n pi`` (with ``n = 1`` for the rigid bar's scale
#: ``s pi``) and the damping's square ``d**2`` (in every mode's decay, eq. 8) must stay below it.
_FLOAT_MAX = float(np.finfo(float).max)




class _Modal(NamedTuple):
    """A stepped piston's modal data, worked out once (:class:`BarModel`)."""

    w: np.ndarray         # the modes' frequencies (the rigid mode's 0 first)
    c: np.ndarray         # the impact coefficients (the struck end's shape times the stop end's)
    modes: object         # the free-free modes (:class:`~impactbar.PistonModes`)
    kappa: np.ndarray     # the struck end's shapes squared
    sticking: object      # the modes with the struck end held


@dataclass(frozen=True)
class BarModel:
    r"""An elastic bar driven at :math:`x = 0` and striking a rigid stop at :math:`x = 1`.

    Field equation (paper eq. 3, theory §1), dimensionless:

    .. math:: u_{tt} + d\,u_t - s^2 u_{xx} = 0, \quad 0 < x < 1,

    with :math:`s^2 u_x(0,t) = -p(t)`, :math:`u_x(1,t) = 0` between impacts (eq. 4) and the impact
    law :math:`u(x,0^+) = u(x,2\pi^-)`, :math:`u_t(x,0^+) = -R\,u_t(x,2\pi^-)` (eqs. 10, 11). The finite
    cosine transform (eqs. 5, 6) turns it into the modal oscillators

    .. math:: q_n'' + d q_n' + (s n \pi)^2 q_n = p(t), \quad n = 0..N.

    Parameters
    ----------
    s : float
        Wave-speed ratio :math:`C/(L\Omega)` (dimensionless, eq. 2), :math:`s > 0`.
    d : float
        Damping :math:`D/(M\Omega)` (dimensionless, eq. 2), :math:`d \ge 0`.
    R : float
        Restitution coefficient, :math:`0 \le R \le 1` (eq. 10).
    n_modes : int
        Flexible modes kept, :math:`N \ge 0`; ``0`` is the rigid bar. At most 4096, and with
        :math:`s N \le 10^{12}` (beyond, the modes' phases over a period are lost in rounding);
        for the rigid bar :math:`s\pi` must be finite (:math:`s \le 5.7 \cdot 10^{307}`), and
        :math:`d^2` (:math:`d \le 1.3 \cdot 10^{154}`).
    impact : {"paper", "wave"} or ContactLaw
        The impact law, by its name in :data:`impactbar.laws.LAWS` or as a law object
        (:class:`impactbar.laws.ContactLaw`; the attribute then holds its name, :attr:`law` the
        object). ``"paper"`` (default): eq. 10, the velocity field reversed and scaled by
        :math:`-R` at an instant impact, the displacement kept. ``"wave"``: the stop is a long rod of
        the same material with area ratio :math:`A_s/A = (1 + R)/(1 - R)` and the contact, lasting
        :math:`2/s`, is solved by characteristics with the drive acting (theory §4b); velocity and strain
        fields leave multiplied by :math:`-R` when the drive is absent.

    Raises
    ------
    ValueError
        If a parameter is of the wrong type, not finite, or outside its range; the message names it;
        or if ``piston`` is given under a law other than the paper's.

    Examples
    --------
    >>> from impactbar import BarModel, SteppedPiston
    >>> BarModel(s=10.0, d=0.0, R=0.5, n_modes=8).frequencies[:2]
    array([ 0.        , 31.41592654])
    >>> stepped = BarModel(10.0, 0.0, 0.5, 2, piston=SteppedPiston([0.3, 0.7], [2.0, 1.0]))
    >>> stepped.frequencies.round(4)  # s k_n, k_n the stepped bar's wavenumbers
    array([ 0.    , 28.3478, 64.6044])
    """

    s: float
    d: float
    R: float
    n_modes: int
    impact: str = "paper"
    piston: SteppedPiston | None = None
    _law: ContactLaw = field(default=None, init=False, repr=False)
    _modal: tuple = field(default=None, init=False, repr=False, compare=False)

    #: the numbers of a model, with their long names (tables, a sweep's axes)
    parameters: ClassVar[Schema] = Schema(
        Field("s", "wave-speed ratio C/(L Omega), eq. 2"), Field("d", "damping D/(M Omega), eq. 2"),
        Field("R", "restitution coefficient"), Field("n_modes", "flexible modes kept", dtype="i8"))

    def __post_init__(self) -> None:
        object.__setattr__(self, "s", check_real("s", self.s, lo=0.0, lo_open=True))
        object.__setattr__(self, "d", check_real("d", self.d, lo=0.0))
        object.__setattr__(self, "R", check_real("R", self.R, lo=0.0, hi=1.0))
        object.__setattr__(self, "n_modes", check_int("n_modes", self.n_modes, lo=0, hi=MAX_MODES))
        law = get_law(self.impact)  # ValueError listing the names
        object.__setattr__(self, "_law", law)
        if self.impact is not law.name:
            object.__setattr__(self, "impact", law.name)
        self._set_piston()
        if self.n_modes and self.s * self.n_modes > MAX_STIFFNESS:
            raise ValueError(
                f"s * n_modes must be at most {MAX_STIFFNESS:g} (got s = {self.s:g}, n_modes = "
                f"{self.n_modes}): beyond it a mode's phase over one period, 2 pi s n pi, is lost "
                "in rounding; a bar that stiff moves as a rigid one (n_modes = 0)")
        if not math.isfinite(self.s * math.pi * (self.n_modes or 1)):  # no numpy overflow error
            top = _FLOAT_MAX / (np.pi * max(self.n_modes, 1))
            raise ValueError(
                f"s must be in (0, {top:.6g}] with n_modes = {self.n_modes} (got s = {self.s:g}): "
                "beyond it the modal frequencies s n pi (s pi for the rigid bar) are not finite")
        if not math.isfinite(self.d * self.d):
            raise ValueError(
                f"d must be in [0, {np.sqrt(_FLOAT_MAX):.6g}] (got d = {self.d:g}): beyond it d**2, "
                "which enters every mode's decay (eq. 8), is not finite")

    def __repr__(self) -> str:
        text = (f"BarModel(s={self.s!r}, d={self.d!r}, R={self.R!r}, n_modes={self.n_modes!r}, "
                f"impact={self.impact!r}")
        return text + (")" if self.piston is None else f", piston={self.piston!r})")

    def _set_piston(self) -> None:
        piston = self.piston
        if piston is not None and not isinstance(piston, SteppedPiston):
            raise ValueError(f"piston must be a SteppedPiston or None; got {type(piston).__name__}")
        if piston is not None and piston.n_segments == 1:  # the uniform bar, exactly
            object.__setattr__(self, "piston", piston := None)
        # (the wave law's long rod struck by a stepped piston: the exact blow, theory §4b, §12)
        object.__setattr__(self, "_law", piston_law(self._law, piston is not None))
        if piston is None:
            return
        self._law.check_model(self)
        if not self._law.traits.stepped_piston:
            raise ValueError(
                f"piston: a stepped piston's modes are supported under the paper's, the wave and the "
                f"rod-rock laws (got impact = {self._law.name!r})")
        sticking = piston.sticking_basis(self.n_modes)
        modes = sticking.free
        ends = modes.shapes(np.array([0.0, 1.0]))  # (2, N + 1)
        w = self.s * modes.wavenumbers
        c = ends[1] * ends[0]
        c[0] = 1.0
        kappa = ends[0] * ends[0]
        kappa[0] = 1.0
        for a in (w, c, kappa):
            a.flags.writeable = False
        object.__setattr__(self, "_modal", _Modal(w, c, modes, kappa, sticking))

    @property
    def modes(self):
        """The stepped piston's free-free modes (:class:`~impactbar.PistonModes`),
        or ``None`` for the uniform bar."""
        return None if self._modal is None else self._modal.modes

    @property
    def sticking(self):
        """The stepped piston held on the stop (:class:`~impactbar.StickingBasis`:
        its fixed-free modes and their maps to the free ones), or ``None`` for the uniform bar."""
        return None if self._modal is None else self._modal.sticking

    @property
    def drive_weights(self) -> np.ndarray:
        r"""Weights :math:`\kappa` with :math:`u_t(0, t) = \kappa \cdot q'`: :math:`(1, 2, \dots,
        2)`, or :math:`\phi_n(0)^2` with a stepped piston; also the energy's,
        :math:`E = \tfrac12 \sum_n \kappa_n (q_n'^2 + \omega_n^2 q_n^2)` (theory §2, §12),
        shape ``(N + 1,)``."""
        if self._modal is not None:
            return self._modal.kappa.copy()
        return np.where(np.arange(self.n_modes + 1) == 0, 1.0, 2.0)

    @property
    def law(self) -> ContactLaw:
        """The impact law as an object (:class:`impactbar.laws.ContactLaw`)."""
        if self._law.name != self.impact:  # a name set past the validation: looked up again
            return get_law(self.impact)
        return self._law

    @property
    def frequencies(self) -> np.ndarray:
        r"""Undamped modal frequencies :math:`s n \pi` for :math:`n = 0..N`, shape ``(N + 1,)`` (eq. 6);
        :math:`s k_n` with a stepped piston (theory §12)."""
        if self._modal is not None:
            return self._modal.w.copy()
        return self.s * np.pi * np.arange(self.n_modes + 1, dtype=float)

    @property
    def end_weights(self) -> np.ndarray:
        r"""Weights :math:`c` with :math:`u(1, t) = c \cdot q`: :math:`(1, 2(-1)^1, \dots, 2(-1)^N)`,
        shape ``(N + 1,)`` (eq. 15 at :math:`x = 1`); :math:`(1, \phi_1(0)\phi_1(1), \dots)` with a
        stepped piston's mass-orthonormal modes :math:`\phi_n` (theory §12)."""
        if self._modal is not None:
            return self._modal.c.copy()
        c = 2.0 * (-1.0) ** np.arange(self.n_modes + 1)
        c[0] = 1.0
        return c

    def shape_functions(self, x) -> np.ndarray:
        r"""Mode shapes at :math:`x` for the inverse transform (eq. 15).

        Parameters
        ----------
        x : array_like, shape (...)
            Positions along the bar, :math:`0 \le x \le 1` (dimensionless).

        Returns
        -------
        numpy.ndarray, shape (..., N + 1)
            :math:`1` for :math:`n = 0` and :math:`2 \cos(n \pi x)` for :math:`n \ge 1`; with a
            stepped piston :math:`\phi_n(0)\,\phi_n(x)` (theory §12).

        Raises
        ------
        ValueError
            If any ``x`` is outside ``[0, 1]`` or not finite.
        """
        x = np.asarray(x, dtype=float)
        if not np.all(np.isfinite(x)) or np.any((x < 0.0) | (x > 1.0)):
            raise ValueError("x must lie in [0, 1]")
        if self._modal is not None:
            modes = self._modal.modes
            phi = modes.shapes(x) * modes.shapes(np.zeros(1))[0]
            phi[..., 0] = 1.0
            return phi
        n = np.arange(self.n_modes + 1)
        phi = 2.0 * np.cos(np.pi * x[..., None] * n)
        phi[..., 0] = 1.0
        return phi

    def parameter_table(self) -> tuple[Parameter, ...]:
        """The bar's parameters (eq. 2) and its impact law's own
        (:meth:`~impactbar.laws.ContactLaw.parameter_table`), for :func:`impactbar.parameters.parameters`.

        Returns
        -------
        tuple of Parameter
            ``s``, ``d``, ``R``, ``n_modes`` (an integer: not continuable), then the law's.

        Examples
        --------
        >>> [p.name for p in BarModel(s=10.0, d=0.0, R=0.5, n_modes=2).parameter_table()]
        ['s', 'd', 'R', 'n_modes']
        """
        own = tuple(Parameter(f.name, getattr(self, f.name), description=f.long_name,
                              integer=f.dtype.startswith("i"), **_MODEL_RANGES[f.name])
                    for f in self.parameters)
        return own + tuple(table_of(self._law, self).values())

    def with_parameter(self, name: str, value) -> BarModel:
        """A copy with one parameter of :meth:`parameter_table` changed (validated again): a field
        of the bar, or one of its impact law's own.

        Parameters
        ----------
        name : str
        value : float or int

        Returns
        -------
        BarModel

        Raises
        ------
        ValueError
            For another name (the allowed ones listed) or a value a constructor refuses.
        """
        return self.with_parameters({name: value})

    def with_parameters(self, changes: dict) -> BarModel:
        """A copy with several parameters of :meth:`parameter_table` changed at once: ``changes``
        (dict of name to value) applied together, the result validated once whatever their order
        (a ``ValueError`` as :meth:`with_parameter`)."""
        own = {k: v for k, v in changes.items() if k in _MODEL_RANGES}
        law = {k: v for k, v in changes.items() if k not in _MODEL_RANGES}
        if law:
            names = table_of(self._law, self)
            bad = [k for k in law if k not in names]
            if bad:
                raise ValueError(f"parameter must be one of "
                                 f"{tuple(p.name for p in self.parameter_table())}; got {bad[0]!r}")
            own["impact"] = self._law.with_parameters({k: float(v) for k, v in law.items()})
        return self.with_(**own)

    def with_(self, **changes) -> BarModel:
        """A copy with some fields changed (validated again)."""
        fields = {"s": self.s, "d": self.d, "R": self.R, "n_modes": self.n_modes, "impact": self._law,
                  "piston": self.piston}
        unknown = set(changes) - set(fields)
        if unknown:
            raise ValueError(f"unknown BarModel field(s): {sorted(unknown)}; allowed: {sorted(fields)}")
        fields.update(changes)
        return BarModel(**fields)
