r"""Sensitivities of a drifter's operating point to its design keys by the implicit function theorem
(theory §11): the derivatives of the blow frequency, the impact velocity, the supply pressure, the
pump's power and the drilling figures with respect to dotted config keys (``accumulator.precharge``,
``valve.switch_out``, ``piston.collar_diameter``, ...), without solving an orbit again.

The operating point is a root :math:`X^*(p)` of the shooting residual :math:`r(X; p) = P(X; p) - X`
(:class:`~impactbar.orbits.driven.ShootingProblem`: the state after the impact, flown to the next
impact). Where :math:`r` is smooth in :math:`(X, p)` and its Jacobian :math:`J_X = \Phi - I`
(:math:`\Phi` the return map's monodromy, a by-product of the orbit's last variational flight) is
regular (no multiplier at 1),

.. math:: \frac{dX^*}{dp} = -J_X^{-1} J_p, \qquad J_p = \frac{\partial r}{\partial p},

:math:`J_p` by a central difference of the residual: two plain flights from :math:`X^*` at
:math:`p \pm h`, no orbit solved. A figure :math:`F(X, p)` of the designer (the SI outputs of
:class:`~impactbar.physical.CircuitDrifterOrbit`) has the total derivative :math:`F_X\,dX^*/dp +
F_p`, taken as one central difference along the tangent: :math:`F` at :math:`(X^* \pm h\,dX^*/dp,
p \pm h)`. Along the tangent the residual vanishes to first order, so every figure, whether it reads
the unknowns or the end of their flight, gets the same derivative.

Where a key does not enter smoothly, at a border collision (the valve's switch and the impact
changing order, the relief valve starting to open, the accumulator emptying), the derivative does
not exist: the flights at :math:`p \pm h` then go through another sequence of the drive's events
than the orbit's (:meth:`~impactbar.orbits.driven.ShootingProblem.event_pattern`), and the key is
refused. The borders' margins (:meth:`~impactbar.drives.circuit.HydraulicCircuitDrive.border_tests`)
and their derivatives say how far the key may move before one is met (to first order).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from .circuit import CircuitDrifter, CircuitDrifterOrbit
from .display_units import config_quantity, display_unit, format_key
from .loader import build, config_value, read_config, with_values
from .outputs import output_values, outputs
from .tree import FIELDS, real_keys
from .units import to_si

__all__ = ["operating_point_sensitivities", "OperatingPointSensitivities", "RESIDUAL_STEP", "FLEXIBLE_STEP",
           "default_step", "FIGURE_UNITS"]


#: The relative step ``h / |p|`` of both central differences: their error is
#: :math:`O(h^2)` (truncation) plus :math:`O(\epsilon / h)` (the flights' noise, :math:`\epsilon
#: \approx 10^{-9}` relative at the circuit's ``rtol = 1e-10``), balanced near
#: :math:`h \approx \epsilon^{1/3} = 10^{-3}`; on the preset the blow frequency's derivative by
#: the switch point is off by 5e-5, 2e-7 and 2e-6 (relative) at ``1e-2``, ``1e-3`` and ``1e-4``.
RESIDUAL_STEP = 1e-3

#: The relative step with a flexible piston (``model.n_modes`` above 0): the modes ring, so the end's
#: velocity at impact curves fast with a key and the truncation grows (with two modes on the preset, the
#: impact velocity's derivative by the switch point is 3 % off at ``1e-3``, 0.4 % at ``3e-4``, against
#: central differences of continued orbits that agree with themselves from ``3e-4`` to ``1e-5``), while
#: below ``1e-4`` the flights' noise, larger with the modes (about 1e-8), grows (the rear volume's:
#: 2 % off at ``1e-4``, 11 % at ``1e-5``).
FLEXIBLE_STEP = 3e-4


def default_step(drifter: CircuitDrifter) -> float:
    """The relative step of the differences for ``drifter``: :data:`RESIDUAL_STEP` for a rigid
    piston, :data:`FLEXIBLE_STEP` for a flexible one."""
    return RESIDUAL_STEP if drifter.n_modes == 0 else FLEXIBLE_STEP

#: The figures differentiated and their units (those of the rock with a ``[rock]`` section only):
#: the outputs of the view ``"figure"`` (:mod:`~impactbar.physical.outputs`) by key, as the library
#: declares them (an output added by :func:`~impactbar.physical.outputs.register_output` is
#: differentiated too).
FIGURE_UNITS = {o.key: o.unit for o in outputs("figure", "circuit")}


def _key_unit(key: str, drifter: CircuitDrifter) -> str:
    """The SI unit of a variable's dotted key (a real key of the parameter tree,
    :func:`~impactbar.physical.tree.real_keys`, or a field of a part the drifter has), or a
    one-line refusal."""
    real = real_keys()
    if isinstance(key, str) and key in real:
        return FIELDS[key].unit
    if drifter.key_field(key) is not None:  # (a part's, parts.<name>.<field>)
        return drifter.key_field(key).unit
    raise ValueError(f"vary: {key!r} is not a parameter the optimiser varies; one of "
                     f"{', '.join(sorted(real))}")


def _config_of(drifter: CircuitDrifter) -> dict:
    """The configuration a drifter was read from, where it builds that drifter again."""
    if drifter.config is None or build(drifter.config) != drifter:
        raise ValueError("config: this CircuitDrifter was not read from a configuration, or was changed "
                         "after (dataclasses.replace): give its configuration, whose keys the derivatives "
                         "change")
    return drifter.config



@dataclass(frozen=True)
class OperatingPointSensitivities:
    """The result of :func:`operating_point_sensitivities`.

    Attributes
    ----------
    keys : tuple of str
        The dotted config keys, in order.
    units : dict
        Key to its SI unit (``"Pa"``, ``"m"``, ``"m**3"``, ...).
    values, steps : dict
        Key to its value at the design and the step ``h`` of the differences (SI).
    figures : dict
        Figure to its value at the design (:data:`FIGURE_UNITS`).
    derivatives : dict
        Figure to ``{key: dF/dp}`` (the figure's unit per the key's SI unit).
    state : numpy.ndarray, shape (n, len(keys))
        :math:`dX^*/dp`: the dimensionless unknowns (the bar's state after the impact in the model's
        units, the circuit's pressures in 10 MPa and the valve's opening) per SI unit of each key.
    borders : dict
        Border (``"accumulator"``: the least supply pressure less the pre-charge; ``"relief"``: the
        relief pressure less the greatest supply pressure) to ``{"margin_Pa": ..., "derivatives":
        {key: Pa per unit}}``; positive margins mean the border is not reached.
    orbit : CircuitDrifterOrbit
        The operating point.
    flights : int
        Flights flown besides the orbit's own (four per key).
    seconds : float
        Wall time (s), the orbit's solve included where it was not given.
    config : dict
        The configuration the keys were read from (their values as written: the units
        :meth:`distance_to_border` shows with ``shown=True``).
    """

    keys: tuple
    units: dict
    values: dict
    steps: dict
    figures: dict
    derivatives: dict
    state: np.ndarray = field(repr=False)
    borders: dict
    orbit: CircuitDrifterOrbit = field(repr=False)
    flights: int = 0
    seconds: float = 0.0
    config: dict = field(default_factory=dict, repr=False, compare=False)

    def elasticities(self) -> dict:
        r"""The relative derivatives :math:`(p / F)\,dF/dp`: the figure's change in per cent per per
        cent of the key (``nan`` where the figure is 0).

        Returns
        -------
        dict
            Figure to ``{key: elasticity}``.
        """
        return {name: {k: (d * self.values[k] / self.figures[name] if self.figures[name] != 0.0 else math.nan)
                       for k, d in der.items()} for name, der in self.derivatives.items()}

    def distance_to_border(self, shown: bool = False) -> dict:
        """The change of each key that brings each border's margin to 0, to first order
        (``-margin / (d margin / dp)``; ``inf`` where the margin does not move with the key).

        Parameters
        ----------
        shown : bool
            ``False``: the changes in SI (floats); ``True``: as a person reads them, strings in
            the unit the config writes the key in, else the key table's display unit
            (``'+5.48 L/min'``).

        Returns
        -------
        dict
            Border to ``{key: change}``.
        """
        out = {name: {k: (-b["margin_Pa"] / d if d != 0.0 else math.inf)
                      for k, d in b["derivatives"].items()} for name, b in self.borders.items()}
        if shown:
            out = {name: {k: ("+" if v > 0.0 else "") + format_key(v, self.units[k], self.config, k, 4)
                          for k, v in change.items()} for name, change in out.items()}
        return out

    def table(self) -> str:
        """The figures and their derivatives, one row per figure, in a designer's units per key
        (MPa, mm, L, ... of the key: the figure's change per unit of the key as the table shows it)."""
        factor, unit_name = {}, {}  # each key's display unit
        for k, u in self.units.items():
            factor[k], unit_name[k] = display_unit(u)
        head = f"{'':30s}{'value':>13s}" + "".join(f"{f'd/d {k} [{unit_name[k]}]':>36s}" for k in self.keys)
        rows = [head]
        for name, value in self.figures.items():
            rows.append(f"{name:30s}{value:13.6g}" + "".join(
                f"{self.derivatives[name][k] / factor[k]:36.6g}" for k in self.keys))
        for name, b in self.borders.items():
            rows.append(f"{name + '_margin_Pa':30s}{b['margin_Pa']:13.6g}" + "".join(
                f"{b['derivatives'][k] / factor[k]:36.6g}" for k in self.keys))
        return "\n".join(rows)


def _figures(point: CircuitDrifterOrbit) -> dict:
    """The designer's figures of an operating point (:data:`FIGURE_UNITS`: the outputs of the view
    ``"figure"``, the rock's where the drifter has one; an optional one left out where NaN)."""
    shown = outputs("figure", "circuit", rock=point.drifter.drill is not None)
    values = output_values(point, shown)
    return {o.key: float(values[o.name]) for o in shown
            if not (o.optional and math.isnan(values[o.name]))}


def operating_point_sensitivities(config, keys, *, orbit: CircuitDrifterOrbit | None = None,
                                  relative_step: float | None = None,
                                  multipliers: bool = True) -> OperatingPointSensitivities:
    r"""The derivatives of a drifter's operating point (its orbit and the designer's figures) with
    respect to design keys, by the implicit function theorem on the orbit's shooting system
    (module docstring).

    Per key: two plain flights for :math:`J_p = \partial r / \partial p` (central difference,
    truncation error :math:`O(h^2)`, noise :math:`O(\epsilon/h)` with :math:`\epsilon \approx
    10^{-9}` the flights' relative accuracy), one linear solve with the orbit's own :math:`J_X`
    (exact to the variational flight's accuracy), then the figures at
    :math:`(X^* \pm h\,dX^*/dp,\ p \pm h)` (another central difference, the same orders; each a
    flight with its variational equations where ``multipliers``). No orbit is solved for the keys:
    four flights each, against two solves of an orbit (each tens of flights from rest, a few
    continued from a neighbour) for central differences of orbits. On the rigid preset 0.09 s per
    key (0.04 s without ``multipliers``) against 0.5 s for two fresh orbits (0.28 s for two
    continued); on the example drifter on the rock (``examples/circuit_drifter_rock_piston.toml``, as
    measured: on its lattice's step setting), whose blows' Jacobians are central differences, 4.5 s
    per key (0.7 s without ``multipliers``) against 12 to 16 s for two continued orbits
    (``benchmarks/bench_sensitivity.py``).

    Parameters
    ----------
    config : str, os.PathLike, dict or CircuitDrifter
        A drifter with its oil circuit (``[chambers]``): a TOML file, a preset's name or the
        config itself (:func:`~impactbar.physical.read_config`), or the
        :class:`~impactbar.physical.CircuitDrifter` built from one (as
        :func:`~impactbar.physical.continue_circuit` takes it: the same as its config); with
        ``[rock]`` also the drilling figures.
    keys : sequence of str
        Dotted keys the config gives, each a real key of the parameter tree
        (:func:`~impactbar.physical.tree.real_keys`: the circuit's, the piston's shape
        ``piston.collar_diameter``, ...), with a value other than 0.
    orbit : CircuitDrifterOrbit, optional
        The config's operating point, if already solved (else :meth:`CircuitDrifter.orbit`).
    relative_step : float, optional
        :math:`h / |p|`, in ``(0, 0.1]``; default :func:`default_step` (:data:`RESIDUAL_STEP` for a
        rigid piston, :data:`FLEXIBLE_STEP` for a flexible one, whose derivatives are good to about
        half a per cent, not to the rigid piston's 1e-4).
    multipliers : bool
        Whether to differentiate the largest multiplier's modulus (``max_multiplier``): a flight with
        its variational equations at each of the figures' two points, most of the cost where the
        blows are coupled to the rock.

    Returns
    -------
    OperatingPointSensitivities
        The figures (:data:`FIGURE_UNITS`) and their derivatives per key (the figure's unit per the
        key's SI unit: Hz/Pa, m/s/m, ...), :math:`dX^*/dp`, the borders' margins and their
        derivatives.

    Raises
    ------
    ValueError
        A config without an oil circuit, an unknown key or one the config leaves out or gives as 0,
        a step out of range or one that takes a key out of its range, an orbit of another design,
        a multiplier at 1 (:math:`J_X` singular: a fold of the operating point), or a key that does
        not enter smoothly: within :math:`\pm h` the flights' sequence of the drive's events
        changes (a border collision: the relief valve opening, the accumulator emptying, the switch
        and the impact changing order; the border and the step named).

    Examples
    --------
    >>> from impactbar.physical import operating_point_sensitivities
    >>> s = operating_point_sensitivities("circuit-drifter", ["valve.switch_out"])
    >>> round(s.derivatives["blow_frequency_Hz"]["valve.switch_out"] * 1e-3, 2)  # Hz per mm
    -1.0
    """
    t0 = time.perf_counter()
    if not isinstance(multipliers, bool):
        raise ValueError(f"multipliers must be True or False; got {multipliers!r}")
    if relative_step is not None and not (isinstance(relative_step, float | int)
                                          and 0.0 < relative_step <= 0.1):
        raise ValueError(f"relative_step must be in (0, 0.1]; got {relative_step!r}")
    if isinstance(keys, str) or not keys:
        raise ValueError(f"keys must be a non-empty sequence of dotted config keys; got {keys!r}")
    keys = tuple(keys)
    if len(set(keys)) != len(keys):
        raise ValueError(f"keys must be distinct; got {keys!r}")
    cfg, folder = read_config(_config_of(config) if isinstance(config, CircuitDrifter) else config)
    drifter = build(cfg, folder)
    if not isinstance(drifter, CircuitDrifter):
        raise ValueError("config must describe a drifter with its oil circuit (a [chambers] section)")
    if relative_step is None:
        relative_step = default_step(drifter)
    units, values = {}, {}
    for key in keys:
        units[key] = _key_unit(key, drifter)
        values[key] = to_si(key, config_value(cfg, key), units[key], "'1 ...'")
        if values[key] == 0.0:
            raise ValueError(f"{key} is 0 in the config: its step is relative, give a value other than 0")
    point = drifter.orbit() if orbit is None else orbit
    if not isinstance(point, CircuitDrifterOrbit) or point.drifter != drifter:
        raise ValueError("orbit must be the config's own operating point (a CircuitDrifterOrbit of the "
                         "drifter the config builds)")
    def read(pt):
        return {**_figures(pt), **{f"border.{k}": v for k, v in pt.border_margins_Pa.items()}}

    F0, B0 = _figures(point), point.border_margins_Pa
    if not multipliers:
        F0.pop("max_multiplier", None)
    state, steps, der = tangent_derivatives(cfg, folder, point, keys, values, units, relative_step,
                                            multipliers, read)
    derivatives = {name: der[name] for name in F0}
    borders = {name: {"margin_Pa": m, "derivatives": der[f"border.{name}"]} for name, m in B0.items()}
    return OperatingPointSensitivities(keys=keys, units=units, values=values, steps=steps, figures=F0,
                                       derivatives=derivatives, state=state, borders=borders, orbit=point,
                                       flights=4 * len(keys), seconds=time.perf_counter() - t0, config=cfg)


def tangent_derivatives(cfg: dict, folder, point: CircuitDrifterOrbit, keys, values: dict, units: dict,
                        relative_step: float, multipliers: bool, read) -> tuple:
    r"""The implicit function theorem's derivatives of any smooth function ``read`` of an operating
    point (a :class:`CircuitDrifterOrbit` to a dict of floats): :math:`dX^*/dp = -J_X^{-1} J_p`
    per key, then ``read`` at :math:`(X^* \pm h\,dX^*/dp, p \pm h)` (:func:`operating_point_sensitivities`
    with its checks done; for :func:`~impactbar.physical.optimize_drifter`'s gradients).

    Returns
    -------
    state : numpy.ndarray, shape (n, len(keys))
    steps : dict
        Key to ``h`` (SI).
    derivatives : dict
        Each name ``read`` gives to ``{key: derivative}``.

    Raises
    ------
    ValueError
        As :func:`operating_point_sensitivities` (a singular Jacobian, a step out of a key's range, a
        border collision within the step).
    """
    so = point.orbit
    problem = so.problem
    X = problem.unknowns(so)
    Phi = so._monodromy
    if Phi is not None and Phi.shape[0] == X.size:
        Jx = Phi - np.eye(X.size)
    else:
        _, Jx = problem.residual(X)
    cond = np.linalg.cond(Jx)
    if not cond < 1e10:
        raise ValueError(f"the orbit's Newton Jacobian is singular (condition {cond:.3g}: a multiplier at 1, "
                         "a fold of the operating point): its derivatives do not exist")
    pattern = problem.event_pattern(X)
    state = np.empty((X.size, len(keys)))
    derivatives: dict = {}
    steps = {}
    for j, key in enumerate(keys):
        p, unit = values[key], units[key]
        h = relative_step * abs(p)
        steps[key] = h
        sides = []
        for s in (1.0, -1.0):
            try:
                d = build(with_values(cfg, {key: config_quantity(p + s * h, unit)}), folder)
            except ValueError as exc:
                raise ValueError(f"{key} at {p + s * h:.6g} {unit} (the step {relative_step:g} of its value) "
                                 f"is out of its range: {str(exc).splitlines()[0]}") from exc
            pr = _problem(d, problem)
            _same_pattern(pr, X, pattern, key, s * h, unit)
            sides.append((d, pr, pr.value(X)))
        (_, _, value_plus), (_, _, value_minus) = sides  # (s = 1, then -1)
        Jp = (value_plus - value_minus) / (2.0 * h)
        Xp = -np.linalg.solve(Jx, Jp)
        state[:, j] = Xp
        F = []
        for (d, pr, _), s in zip(sides, (1.0, -1.0), strict=True):
            Xs = X + s * h * Xp
            _same_pattern(pr, Xs, pattern, key, s * h, unit)
            F.append(read(_point(d, pr, Xs, multipliers)))
        for name in F[0]:
            derivatives.setdefault(name, {})[key] = (F[0][name] - F[1][name]) / (2.0 * h)
    return state, steps, derivatives


def _problem(drifter: CircuitDrifter, near):
    """The shooting problem of ``drifter`` with the blocks of ``near`` (another design's)."""
    from ..orbits.driven import orbit_problem

    return orbit_problem(drifter.model(), drifter.drive(), near.impacts,
                         getattr(near, "settings", None)).adopt(near)


def _point(drifter: CircuitDrifter, problem, X, multipliers: bool) -> CircuitDrifterOrbit:
    """The operating point read at unknowns ``X`` (not necessarily a root) of ``problem``."""
    from ..orbits.driven import orbit_of

    return CircuitDrifterOrbit(drifter, orbit_of(problem, X, multipliers=multipliers))


def _same_pattern(problem, X, pattern: tuple, key: str, step: float, unit: str) -> None:
    """Refuse a key whose step changes the period's sequence of the drive's events."""
    other = problem.event_pattern(X)
    if other == pattern:
        return
    names = [name for name, *_ in pattern]
    changed = [name for name, *_ in other]
    raise ValueError(f"{key} does not enter smoothly here: a step of {step:+.4g} {unit} changes the drive's "
                     f"events over the period from {', '.join(names)} to {', '.join(changed)} (a border "
                     "collision: the relief valve opening, the accumulator emptying or a switch changing "
                     "order); no derivative")
