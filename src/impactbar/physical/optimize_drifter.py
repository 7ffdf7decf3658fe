r"""The whole drifter optimised: piston shape, chambers, valve and circuit together, for drilling rate
per hydraulic kilowatt (or drilling rate, work on rock per blow, impact power) under the designer's
constraints (theory §11, "Optimising a drifter").

Each evaluation is the circuit's operating point on the rod and rock: :meth:`CircuitDrifter.orbit`
continued from the nearest design evaluated so far (Newton from its orbit) where that converges, else
the default chain. The search is derivative-free by default (COBYLA, :func:`scipy.optimize.minimize`)
over the variables scaled to :math:`[0, 1]` by their bounds: an operating point changes pattern (the
valve's switch before or after the impact, the relief opening or not) at borders where it is not
smooth, and an evaluation can fail (no orbit, cavitation), which a penalty, not a finite difference,
handles. With ``method="slsqp"`` the search is SLSQP's with the gradients of the objective and of
the constraints by the implicit function theorem on each design's orbit
(:func:`~impactbar.physical.sensitivity.tangent_derivatives`: four flights per variable, no orbit
solved), a key across a border within the step by central differences of orbits continued from the
design's instead.
The reported optimum is the best feasible design evaluated, re-evaluated by a fresh ``orbit()``.

The circuit's ideal limit (``impact_velocity=``): each design is its piston's single blow on the rod
and rock at a given impact velocity, the circuit taken to deliver the piston at it and to cost
nothing, scored as :func:`~impactbar.physical.piston.optimize_piston` scores its designs
(:func:`~impactbar.physical.piston.piston_blow`); the objective the work on the rock per blow, the
constraints the peak incident stress and the piston's mass. Over the piston's diameters, its
lengths and mass held, the optimum is then :func:`~impactbar.physical.optimize_piston`'s (a check
of the search that does not trust it: ``tests/physical/test_optimize_drifter_checks.py``).
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .circuit import CircuitDrifter
from .design_keys import design_bounds
from .display_units import config_quantity, display_unit, written_quantity
from .loader import build, config_value, read_config, with_values
from .optimality import certify_search
from .optimize_cache import OrbitChain, dumps, read_cache, write_cache
from .optimize_failures import failed_record
from .optimize_multistart import check_multistart, multistart_search
from .optimize_outputs import constraint_output, piston_and_multipliers, shank_stress
from .optimize_population import check_population, penalised, population_search
from .optimize_progress import DesignProgress
from .outputs import Reading, outputs
from .sensitivity import default_step, tangent_derivatives
from .units import to_si

__all__ = ["OBJECTIVES", "DEFAULT_CONSTRAINTS", "IDEAL_CONSTRAINTS", "FEASIBILITY_TOLERANCE",
           "optimize_drifter", "evaluate_design", "evaluate_blow", "DrifterOptimum"]

#: The objectives (all maximised): name to (the figure, its unit, what it is), the outputs that name
#: an objective (:attr:`~impactbar.physical.outputs.Output.objective`).
OBJECTIVES = {o.objective: (o.key, o.unit, o.long_name) for o in outputs() if o.objective}

#: The constraints and their default limits (SI): ``peak_incident_stress`` (Pa, the largest stress in
#: the shank adapter before the rock's first reflection is back at it, or over the piston's first
#: contact where that lasts longer: the peak of the incident wave; ``None``: not constrained),
#: ``max_multiplier`` (the largest Floquet multiplier's modulus), ``min_pressure`` (Pa absolute: no
#: cavitation at 0),
#: ``mean_supply_pressure`` (Pa; ``"relief"``: the relief valve's setting), ``peak_supply_pressure``
#: (Pa; ``None``: not constrained), ``min_chamber_volume`` (m^3, the smallest volume of either chamber
#: over the period must lie above it), ``min_drilling_rate`` (m/min; ``None``: not constrained; a
#: design that drills per kilowatt more by drilling slower is then kept from the optimum),
#: ``piston_mass`` (kg, the piston's mass at most; ``None``: not constrained).
DEFAULT_CONSTRAINTS = {"peak_incident_stress": None, "max_multiplier": 0.95, "min_pressure": 0.0,
                       "mean_supply_pressure": "relief", "peak_supply_pressure": None,
                       "min_chamber_volume": 0.0, "min_drilling_rate": None, "piston_mass": None}

#: The constraints of the circuit's ideal limit (``optimize_drifter(..., impact_velocity=...)``): the
#: blow's and the piston's.
IDEAL_CONSTRAINTS = ("peak_incident_stress", "piston_mass")

#: How far a constraint may be missed and count as met, relative to its scale (the limit, or where
#: the limit is 0 the margin's fixed scale: 1 MPa of pressure, 0.1 L of volume): the operating
#: point's own accuracy, its periodic orbit to 1e-8 (the circuit's flights at ``rtol = 1e-10``,
#: :mod:`impactbar.drives.circuit.flight`). A continued and a fresh orbit of one design differ by
#: some 1e-9 (the mean supply pressure on the preset by up to 4e-9); SLSQP walks along an active
#: limit at about that distance from it. The reported optimum's fresh orbit meets it too.
FEASIBILITY_TOLERANCE = 1e-8


def _fingerprint(config: dict, vary: dict, objective: str, constraints: dict) -> str:
    text = json.dumps([config, {k: list(v) for k, v in vary.items()}, objective, constraints], sort_keys=True,
                      default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _better_missed(history: list, best: dict, fkey: str) -> str:
    """Why no design of a larger objective was kept: how many missed a constraint, and the nearest
    miss (``""`` where none)."""
    better = [r for r in history if r.get("ok") and not r["feasible"] and r["objectives"][fkey] >
              best["objectives"][fkey]]
    if not better:
        return ""
    nearest = [min(r["constraints"].items(), key=lambda kv: kv[1]["scaled"]) for r in better]
    name, c = max(nearest, key=lambda kv: kv[1]["scaled"])
    scale, unit = display_unit(c["unit"])
    return (f"; {len(better)} design(s) of a larger objective missed a constraint, the nearest {name} by "
            f"{-c['margin'] * scale:.4g}{' ' + unit if unit else ''} ({-c['scaled']:.2g} of its scale, "
            f"above the tolerance {FEASIBILITY_TOLERANCE:g})")


def evaluate_design(drifter: CircuitDrifter, constraints: dict | None = None,
                    guess=None) -> tuple[dict, object]:
    """A design's figures: its operating point's objectives and constraints with their margins.

    Parameters
    ----------
    drifter : CircuitDrifter
        With a drill string and the rock (``[rock]``) for the drilling figures.
    constraints : dict, optional
        Limits by name (:data:`DEFAULT_CONSTRAINTS`, SI or with units); the defaults where left out.
    guess : CircuitDrifterOrbit, optional
        The operating point of a nearby design: Newton starts there; where it does not converge the
        default chain (``orbit()``) is used.

    Returns
    -------
    record : dict
        ``objectives`` (:data:`OBJECTIVES`' figures), ``constraints`` (name to ``value``, ``limit``,
        ``margin`` in the value's unit, positive where met, and ``scaled`` margin), ``feasible``,
        ``continued`` (whether Newton from ``guess`` converged), ``seconds``.
    orbit : CircuitDrifterOrbit

    Raises
    ------
    ValueError
        No operating point (the default chain's reason).
    """
    limits = _limits(constraints, drifter)
    t0 = time.perf_counter()
    orbit, continued = _operating_point(drifter, guess)
    rec = _figures(orbit, limits)
    rec["continued"] = continued
    rec["seconds"] = time.perf_counter() - t0
    return rec, orbit


def _operating_point(drifter: CircuitDrifter, guess) -> tuple[object, bool]:
    """The design's orbit: Newton from ``guess`` where given and it converges, else the default
    chain; and whether it was continued."""
    if guess is not None:
        try:
            return drifter.orbit(guess=guess), True
        except (ValueError, np.linalg.LinAlgError, ArithmeticError):
            pass
    return drifter.orbit(), False


def evaluate_blow(drifter: CircuitDrifter, impact_velocity: float, constraints: dict | None = None) -> dict:
    """A design in the circuit's ideal limit: its piston's blow on the rod and rock at
    ``impact_velocity`` (:func:`~impactbar.physical.piston.piston_blow`), the circuit taken to
    deliver the piston at it and to cost nothing.

    Parameters
    ----------
    drifter : CircuitDrifter
        With a drill string and the rock (``[rock]``).
    impact_velocity : float
        The piston's velocity at impact (m/s), ``> 0``.
    constraints : dict, optional
        Limits of :data:`IDEAL_CONSTRAINTS` (SI or with units); the others are the circuit's.

    Returns
    -------
    dict
        As :func:`evaluate_design`'s: ``objectives`` (``work_on_rock_J``, ``impact_energy_J``,
        ``blow_efficiency``), ``constraints``, ``feasible``, ``seconds``.

    Raises
    ------
    ValueError
        No drill string, a constraint of the circuit, ``impact_velocity`` not positive.

    Examples
    --------
    >>> from impactbar.physical import build, read_config
    >>> from impactbar.physical.optimize_drifter import evaluate_blow
    >>> evaluate_blow(build(read_config("circuit-drifter")[0]), 10.0)
    Traceback (most recent call last):
    ...
    ValueError: the ideal limit (impact_velocity) needs the drill string and the rock ([rock] in the config)
    """
    from .piston import piston_blow

    if drifter.drill is None:
        raise ValueError("the ideal limit (impact_velocity) needs the drill string and the rock ([rock] in "
                         "the config)")
    limits = _limits(constraints, drifter, ideal=True)
    t0 = time.perf_counter()
    bar, drill = drifter.bar, drifter.drill
    blow = piston_blow(drill.segments, (drill.rock_k_N_m, drill.rock_k_u_N_m),
                       lengths=list(getattr(bar, "lengths_m", [bar.length_m])),
                       areas=list(getattr(bar, "areas_m2", [bar.area_m2])), impact_velocity=impact_velocity,
                       E=bar.E_Pa, density=bar.density_kg_m3, bit_mass=drill.bit_mass_kg, feed=drill.feed_N)
    blow = dict(blow, piston_mass_kg=bar.mass_kg)
    obj = {o.key: o.blow(blow) for o in outputs("record") if o.blow is not None}
    values = {name: constraint_output(name)[0].blow(blow) for name in IDEAL_CONSTRAINTS}
    rec = _constrained(obj, values, limits)
    rec["seconds"] = time.perf_counter() - t0
    return rec


def _limits(constraints, drifter, ideal: bool = False) -> dict:
    if constraints is not None and not isinstance(constraints, dict):
        raise ValueError(f"constraints must be a dict of limits or None; got {constraints!r}")
    given = dict(constraints or {})
    unknown = sorted(k for k in given if not isinstance(k, str) or constraint_output(k) is None)
    if unknown:
        raise ValueError(f"constraints: unknown constraint {unknown[0]!r}; one of "
                         f"{', '.join(DEFAULT_CONSTRAINTS)}, or an output's name (at most the limit; "
                         "min_<name>: at least)")
    circuit = sorted(set(given) - set(IDEAL_CONSTRAINTS)) if ideal else []
    if circuit:
        raise ValueError(f"constraints: {circuit[0]!r} is the circuit's; in its ideal limit "
                         f"(impact_velocity) only {', '.join(IDEAL_CONSTRAINTS)}")
    out = {}
    for name, default in {**DEFAULT_CONSTRAINTS, **given}.items():
        if ideal and name not in IDEAL_CONSTRAINTS:
            continue
        v = given.get(name, default)
        if v is None:
            continue
        if constraint_output(name)[0].rock and drifter.drill is None:
            raise ValueError(f"constraints: {name!r} needs the drill string and the rock ([rock] in the "
                             "config)")
        if v == "relief":
            v = drifter.si["relief_pressure_Pa"]
            if not math.isfinite(v):
                continue
        unit = constraint_output(name)[3]
        if isinstance(v, int | float) and not isinstance(v, bool):  # a bare number: SI
            out[name] = float(v)
            continue
        example = {"Pa": "'400 MPa'", "kg": "'5.6 kg'", "m**3": "'0.01 L'",
                   "m/min": "'2 m/min'"}.get(unit, "0.95")
        out[name] = to_si(f"constraints[{name!r}]", v, unit, example)
    return out


def _figures(orbit, limits: dict) -> dict:
    """An operating point's record: the outputs of the view ``"record"`` (by key) and the value of
    every constraint, the defaults' and those of ``limits``."""
    r = Reading(orbit)
    obj = {o.key: o.of(r) for o in outputs("record", "circuit", rock=orbit.drifter.drill is not None)
           if o.of is not None}
    values = {name: float(constraint_output(name)[0].of(r)) for name in {**DEFAULT_CONSTRAINTS, **limits}}
    return _constrained(obj, values, limits)


def _constrained(obj: dict, values: dict, limits: dict) -> dict:
    """A design's record: its objectives ``obj`` and the constraints' ``values`` against ``limits``."""
    cons = {}
    for name, limit in limits.items():
        _, sense, scale, unit = constraint_output(name)
        value = values[name]
        margin = (limit - value) if sense > 0 else (value - limit)
        scale = scale if scale is not None else abs(limit) or 1.0
        cons[name] = {"value": value, "limit": limit, "margin": margin, "unit": unit,
                      "scaled": margin / scale if math.isfinite(margin) else -1.0}
    feasible = all(c["scaled"] >= -FEASIBILITY_TOLERANCE for c in cons.values())
    return {"ok": True, "objectives": obj, "constraints": cons, "feasible": feasible,
            "figures": {k: v for k, v in values.items()}}


@dataclass
class DrifterOptimum:
    """The result of :func:`optimize_drifter`: the baseline and the optimum side by side.

    Attributes
    ----------
    objective : str
        The objective maximised (a key of :data:`OBJECTIVES`).
    vary : dict
        Dotted key to its ``(low, high)`` bounds in SI and ``unit``.
    baseline, optimum : dict
        Each design's record (:func:`evaluate_design`) with ``values`` (dotted key to SI value) and
        ``changes`` (dotted key to the config value, for :func:`~impactbar.physical.with_values`).
        The optimum is the best feasible design evaluated, re-evaluated by a fresh ``orbit()``
        (``continued_vs_fresh``: the largest relative difference of its figures from the search's).
    evaluations : int
        Designs evaluated by this run (not counting those read from the cache).
    cached : int
        Designs read from the cache file.
    gradients : int
        Gradients computed (``method="slsqp"``; each four flights per variable, or two continued
        orbits for a variable whose step meets a border).
    seconds : float
        Wall time of the run (s).
    history : list of dict
        Every design's record in the order evaluated.
    message : str
        The optimiser's.
    certificate : OptimalityCertificate
        The optimum's first-order (KKT) certificate (:mod:`~impactbar.physical.optimality`); the table
        says "optimum" only where it is ``"converged"``.
    found : list of dict
        ``method="multistart"``: each local search's start and best design, best first
        (:func:`~impactbar.physical.optimize_multistart.multistart_search`); empty otherwise.
    """

    objective: str
    vary: dict
    baseline: dict
    optimum: dict
    evaluations: int
    cached: int
    seconds: float
    history: list = field(repr=False)
    message: str = ""
    gradients: int = 0
    config: dict = field(default_factory=dict, repr=False)
    certificate: object = None  #: the optimum's OptimalityCertificate (first-order, KKT)
    found: list = field(default_factory=list)

    @property
    def gain(self) -> float:
        """The objective at the optimum over the baseline's, less 1."""
        key = OBJECTIVES[self.objective][0]
        return self.optimum["objectives"][key] / self.baseline["objectives"][key] - 1.0

    def to_dict(self) -> dict:
        """The result as plain data (JSON-ready)."""
        return {"objective": self.objective, "vary": self.vary, "baseline": self.baseline,
                "optimum": self.optimum, "gain": self.gain, "evaluations": self.evaluations,
                "cached": self.cached, "gradients": self.gradients, "seconds": self.seconds,
                "message": self.message, "certificate": self.certificate and self.certificate.to_dict(),
                "found": self.found, "history": self.history}

    def to_json(self, path=None) -> str:
        """The result as JSON (non-finite numbers as null); written to ``path`` if given."""
        text = dumps(self.to_dict())
        if path is not None:
            Path(path).write_text(text)
        return text

    def table(self) -> str:
        """Baseline and optimum side by side: the variables, every objective, every constraint with
        its limit and margin."""
        word = "optimum" if self.certificate is not None and self.certificate.converged else "best found"
        rows = [f"{'':34s}{'baseline':>14s}{word:>14s}"]
        for key, b in self.vary.items():
            scale, unit = display_unit(b["unit"])
            rows.append(f"{key:34s}{self.baseline['values'][key] * scale:14.5g}"
                        f"{self.optimum['values'][key] * scale:14.5g} {unit}")
        for name, (key, unit, _) in OBJECTIVES.items():
            if key in self.baseline["objectives"]:
                mark = " *" if name == self.objective else ""
                rows.append(f"{name + mark:34s}{self.baseline['objectives'][key]:14.5g}"
                            f"{self.optimum['objectives'][key]:14.5g} {unit}")
        for key in self.baseline["objectives"]:
            if key not in {k for k, _, _ in OBJECTIVES.values()}:
                rows.append(f"{key:34s}{self.baseline['objectives'][key]:14.5g}"
                            f"{self.optimum['objectives'][key]:14.5g}")
        for name, c in self.baseline["constraints"].items():
            o = self.optimum["constraints"][name]
            scale, unit = display_unit(c["unit"])
            label = f"{name} (limit {c['limit'] * scale:.4g})"
            rows.append(f"{label:34s}"
                        f"{c['value'] * scale:14.5g}{o['value'] * scale:14.5g} {unit}"
                        f"  margin {c['margin'] * scale:.4g} -> {o['margin'] * scale:.4g}")
        grads = f" and {self.gradients} gradients" if self.gradients else ""
        slowest = max((r["seconds"] for r in self.history if "seconds" in r), default=0.0)
        rows.append(f"gain in {self.objective}: {self.gain * 100:+.2f} % after {self.evaluations} "
                    f"evaluations{grads} ({self.cached} from the cache) in {self.seconds:.0f} s, the "
                    f"slowest design {slowest:.1f} s")
        if self.certificate is not None:
            rows.append(f"{word}: {self.certificate}")
        return "\n".join(rows)

    def plot(self, axes=None):
        """The piston drawn to scale before and after, the shank's stress over the blow (where the
        orbit gives it) and the multipliers in the unit circle (matplotlib imported on this call).

        Returns
        -------
        numpy.ndarray of matplotlib.axes.Axes, shape (3,)
        """
        import matplotlib.pyplot as plt

        if axes is None:
            _, axes = plt.subplots(1, 3, figsize=(13, 3.8))
        axes = np.asarray(axes).ravel()
        ax = axes[0]
        for y0, rec, colour in ((0.0, self.baseline, "0.6"), (-0.1, self.optimum, "C0")):
            x = 0.0
            for le, d in zip(rec["piston"]["lengths_m"], rec["piston"]["diameters_m"], strict=True):
                ax.add_patch(plt.Rectangle((x * 1e3, (y0 - d / 2) * 1e3), le * 1e3, d * 1e3, fc=colour,
                                           ec="k"))
                x += le
        ax.set_xlim(-10, 1e3 * max(sum(r["piston"]["lengths_m"]) for r in (self.baseline, self.optimum)) + 10)
        ax.set_ylim(-160, 50)
        ax.set_aspect("equal")
        ax.set_xlabel("mm (driven end left; baseline grey, optimum blue)")
        ax.set_title("piston to scale")
        ax = axes[1]
        for rec, colour, label in ((self.baseline, "0.5", "baseline"), (self.optimum, "C0", "optimum")):
            wave = rec.get("shank_stress")
            if wave is not None:  # the stress in the shank over the blow
                ax.step(np.asarray(wave["t_s"]) * 1e6, np.asarray(wave["stress_Pa"]) / 1e6, where="post",
                        color=colour, label=label)
            else:  # no rock: the objective
                ax.bar(label, rec["objectives"].get(OBJECTIVES[self.objective][0], np.nan), color=colour)
        if self.baseline.get("shank_stress") is not None:
            ax.set_xlabel("time from impact (us)")
            ax.set_ylabel("shank stress (MPa)")
            ax.legend()
        else:
            ax.set_ylabel(f"{self.objective} ({OBJECTIVES[self.objective][1]})")
        ax = axes[2]
        t = np.linspace(0, 2 * np.pi, 200)
        ax.plot(np.cos(t), np.sin(t), "k", lw=0.8)
        for rec, colour, label in ((self.baseline, "0.5", "baseline"), (self.optimum, "C0", "optimum")):
            mu = np.asarray(rec["multipliers_re"]) + 1j * np.asarray(rec["multipliers_im"])
            ax.plot(mu.real, mu.imag, "o", color=colour, label=label, mfc="none")
        ax.set_aspect("equal")
        ax.legend(loc="lower left")
        ax.set_title("Floquet multipliers")
        return axes


def optimize_drifter(config, vary: dict, objective: str = "drilling_rate_per_kW",
                     constraints: dict | None = None,
                     *, max_evaluations: int = 60, cache=None, progress: bool = True, rhobeg: float = 0.2,
                     tol: float = 2e-3, method: str = "cobyla", impact_velocity=None, workers=None,
                     popsize: int = 5, seed: int = 0, sample: int = 64,
                     local_starts: int = 3) -> DrifterOptimum:
    r"""The design of a drifter with its oil circuit that maximises ``objective`` under
    ``constraints``, the variables any of its dotted config keys within bounds.

    Parameters
    ----------
    config : str, os.PathLike or dict
        A drifter with its oil circuit (``[chambers]``), on a drill string and the rock for the
        drilling objectives: a TOML file, a preset's name or the config itself
        (:func:`~impactbar.physical.read_config`).
    vary : dict
        Dotted key (``"piston.collar_diameter"``, ``"chambers.rear_volume"``, ``"valve.switch_out"``,
        ``"accumulator.precharge"``, ``"stop.restitution"``: any key the config gives that a design
        map sweeps, :func:`~impactbar.physical.design_keys.design_bounds`) to ``(low, high)`` with
        units (``("46 mm", "52 mm")``, a number for a dimensionless key); the config's own value,
        the start, must lie within.
    objective : str
        One of :data:`OBJECTIVES` (maximised): ``"drilling_rate_per_kW"`` (default),
        ``"drilling_rate"``, ``"work_on_rock_per_blow"``, ``"impact_power"``.
    constraints : dict, optional
        Limits of :data:`DEFAULT_CONSTRAINTS` (with units or SI; ``None`` drops one), e.g.
        ``{"peak_incident_stress": "260 MPa"}``.
    max_evaluations : int
        The most designs the search evaluates (besides the baseline's and the optimum's fresh
        re-evaluation); for SLSQP the most iterations, each its line search's designs (one where its
        full step is accepted; 252 designs for 30 on the example rock drifter).
    cache : str or os.PathLike, optional
        A JSON file of the designs evaluated: read first (a run stopped part-way resumes from it, the
        search visiting the same designs), written after every evaluation. Keyed by the problem (the
        config, the variables and bounds, the objective, the constraints): a cache of another
        problem is not reused, and is overwritten. A resumed run visits the designs of a run never
        stopped, with the same figures to the bit: a design read from it carries its figures, not
        its orbit, and where a new design continues from one, that orbit is solved again as the first
        run solved it, along the designs' recorded guesses
        (:class:`~impactbar.physical.optimize_cache.OrbitChain`; the population search's designs are
        each a fresh orbit).
    progress : bool
        A progress bar (tqdm) on stderr where it is a terminal, none where it is not: the designs
        evaluated, the last one's seconds and the slowest one's
        (:class:`~impactbar.physical.optimize_progress.DesignProgress`).
    rhobeg, tol : float
        COBYLA's first and last step in the scaled variables (each bound's span is 1), ``rhobeg`` in
        ``(0, 1]``, ``tol`` in ``(0, rhobeg]`` (other methods: ``(0, 1]``); for SLSQP
        its ``ftol`` is ``tol ** 3`` (on the objective over the start's: 8e-9 by default, above
        the orbits' own accuracy, about 1e-9) and ``rhobeg`` is not used; a population stops once
        its scores spread below ``tol ** 2``.
    method : {"cobyla", "slsqp", "differential_evolution", "multistart"}
        The search: derivative-free (COBYLA), SLSQP with the implicit function theorem's
        gradients (module docstring; ``max_evaluations`` then bounds its iterations; where a border
        of the operating point lies along an active constraint, as the blow's on the example rock
        drifter, its line search backtracks at every step: there COBYLA), or a
        population's (:mod:`~impactbar.physical.optimize_population`: the constraints a penalty, each
        generation's designs evaluated together on ``workers``, each by a fresh ``orbit()``;
        ``max_evaluations`` bounds its generations, at least two), or COBYLA from the best feasible
        designs of a Sobol sample evaluated together (:mod:`~impactbar.physical.optimize_multistart`).
    workers : None, int or distributed.Client
        Where a population's or a sample's designs are evaluated (those two methods only):
        ``None`` this process, an integer (at least 1) a local dask cluster of that many processes
        (started and closed by the call), or a client's cluster; the same records either way.
    popsize, seed : int
        The population per variable (at least 2) and the random seed (at least 0) of
        ``method="differential_evolution"`` (``"multistart"``: the sample's seed).
    sample, local_starts : int
        ``method="multistart"``: the sample's designs (a power of two) and the local searches (in
        ``[1, sample]``), each ``(max_evaluations - sample) // local_starts`` designs at most.
    impact_velocity : float or str, optional
        The circuit's ideal limit (m/s, or with units, ``> 0``): each design is its piston's blow on
        the rod and rock at this impact velocity alone (:func:`evaluate_blow`), the circuit taken to
        deliver the piston at it; the objective ``"work_on_rock_per_blow"``, the constraints those of
        :data:`IDEAL_CONSTRAINTS` (the circuit's are not computed), the method COBYLA. Over the
        piston's diameters at held lengths and mass (``{"piston_mass": ...}``, active at the
        optimum: more mass, more work) its optimum is :func:`~impactbar.physical.optimize_piston`'s.

    Returns
    -------
    DrifterOptimum

    Raises
    ------
    ValueError
        A variable that is not a parameter or not in the config, bounds of the wrong unit or outside
        the key's range, a start outside its bounds, an unknown objective or constraint, an
        objective the config cannot give (no ``[rock]``), a start without an operating point or an
        infeasible start (the constraint named, with how far it is missed): each in one line.

    Examples
    --------
    >>> from impactbar.physical import optimize_drifter
    >>> optimize_drifter("circuit-drifter", {"valve.switch_out": ("20 mm", "23 mm")}, objective="speed")
    Traceback (most recent call last):
    ...
    ValueError: objective must be one of impact_power, work_on_rock_per_blow, drilling_rate,
    drilling_rate_per_kW; got 'speed'
    """
    from scipy.optimize import minimize

    t_start = time.perf_counter()
    if not isinstance(objective, str) or objective not in OBJECTIVES:
        raise ValueError(f"objective must be one of {', '.join(OBJECTIVES)}; got {objective!r}")
    cfg, folder = read_config(config)
    base = build(cfg, folder, where="config" if folder is None else str(config))  # (the file named)
    if not isinstance(base, CircuitDrifter):
        raise ValueError("config must describe a drifter with its oil circuit (a [chambers] section)")
    if base.drill is None and objective != "impact_power":
        raise ValueError(f"objective {objective!r} needs the drill string and the rock ([rock] in the "
                         "config); "
                         "without them only 'impact_power'")
    if method not in ("cobyla", "slsqp", "differential_evolution", "multistart"):
        raise ValueError(f"method must be 'cobyla', 'slsqp', 'differential_evolution' or 'multistart'; got "
                         f"{method!r}")
    if not (isinstance(rhobeg, int | float) and not isinstance(rhobeg, bool) and 0.0 < rhobeg <= 1.0):
        raise ValueError(f"rhobeg must be a number in (0, 1] (COBYLA's first step in the variables scaled "
                         f"by their bounds); got {rhobeg!r}")
    top, name = (rhobeg, f"rhobeg] = (0, {rhobeg:g}]") if method in ("cobyla", "multistart") else (1.0, "1]")
    if not (isinstance(tol, int | float) and not isinstance(tol, bool) and 0.0 < tol <= top):
        raise ValueError(f"tol must be a number in (0, {name} (the search's last step in the scaled "
                         f"variables); got {tol!r}")
    if workers is not None and method not in ("differential_evolution", "multistart"):
        raise ValueError(f"workers: only with method='differential_evolution'/'multistart', not {method!r}")
    ideal = impact_velocity is not None
    if ideal:
        V = (float(impact_velocity) if isinstance(impact_velocity, int | float)
             and not isinstance(impact_velocity, bool) else
             to_si("impact_velocity", impact_velocity, "m/s", "'10 m/s'"))
        if not (math.isfinite(V) and V > 0.0):
            raise ValueError(f"impact_velocity must be a positive speed, e.g. '10 m/s'; got "
                             f"{impact_velocity!r}")
        if objective != "work_on_rock_per_blow":
            raise ValueError(f"in the circuit's ideal limit (impact_velocity) the objective is "
                             f"'work_on_rock_per_blow'; got {objective!r}")
        if method != "cobyla":
            raise ValueError("in the circuit's ideal limit (impact_velocity) the method is 'cobyla' (SLSQP's "
                             f"gradients come from the circuit's orbits); got {method!r}")
    limits = _limits(constraints, base, ideal=ideal)
    kept = dict.fromkeys(DEFAULT_CONSTRAINTS) | limits  # for evaluate_design: a dropped one stays dropped
    spec = design_bounds(cfg, vary, folder)
    keys = list(spec)
    if not (isinstance(max_evaluations, int) and max_evaluations >= len(keys) + 2):
        raise ValueError(f"max_evaluations must be an integer of at least the variables' number + 2 "
                         f"({len(keys) + 2}); got {max_evaluations!r}")
    if method == "differential_evolution":
        maxiter = check_population(workers, popsize, seed, max_evaluations, len(keys))
    elif method == "multistart":
        budget = check_multistart(workers, sample, local_starts, seed, max_evaluations, len(keys))
    lo = np.array([spec[k]["low"] for k in keys])
    span = np.array([spec[k]["high"] - spec[k]["low"] for k in keys])
    fkey = OBJECTIVES[objective][0]
    tag = _fingerprint(cfg, {k: (spec[k]["low"], spec[k]["high"]) for k in keys}, objective,
                       dict(limits, impact_velocity=V) if ideal else limits)

    cache_path = Path(cache) if cache is not None else None
    store = read_cache(cache_path, tag)
    n_cached = 0
    near: list[tuple[np.ndarray, str]] = []  # the designs with an orbit: their scaled variables, ids
    history: list[dict] = []
    counter = {"new": 0, "gradients": 0}
    # each design's orbit by its id (a stored design's solved again along its guesses where needed)
    chain = OrbitChain(store, lambda c, g: _operating_point(build(with_values(cfg, c), folder), g)[0])
    gradients: dict[str, tuple] = {}
    found: list = []  # the multistart's local searches

    def changes_of(values: dict) -> dict:
        return {k: written_quantity(values[k], spec[k]["unit"], config_value(cfg, k)) for k in keys}

    def design_of(u: np.ndarray) -> tuple[str, dict, dict]:
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        x = np.where(u == u0, start, lo + span * u)  # the start exactly as the config gives it
        values = {k: float(v) for k, v in zip(keys, x, strict=True)}
        changes = changes_of(values)
        changes.update({k: config_value(cfg, k) for k, at in zip(keys, u == u0, strict=True) if at})
        return json.dumps([repr(values[k]) for k in keys]), values, changes

    def evaluate(u: np.ndarray, done: dict | None = None) -> dict:
        nonlocal n_cached
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        rid, values, changes = design_of(u)
        t0, drifter = time.perf_counter(), None
        if rid in store:
            rec = store[rid]
            if not any(r is rec for r in history):
                n_cached += 1
                history.append(rec)
                if rec.get("ok") and "u" in rec:  # a guess for the designs after it, as in the first run
                    near.append((np.asarray(rec["u"], dtype=float), rid))
            return rec
        try:
            if done is not None:  # computed by the population's map
                rec = done
            else:
                drifter = build(with_values(cfg, changes), folder)
                if ideal:
                    rec, orbit = evaluate_blow(drifter, V, limits), None
                else:
                    guess = min(near, key=lambda p: float(np.sum((p[0] - u) ** 2)))[1] if near else None
                    rec, orbit = evaluate_design(drifter, kept, None if guess is None else chain.orbit(guess))
                    rec.update(guess=guess, u=u.tolist())
                    near.append((u.copy(), rid))
                    chain.add(rid, orbit)
                rec.update(piston_and_multipliers(drifter, orbit))
        except (ValueError, np.linalg.LinAlgError, ArithmeticError) as exc:
            rec = failed_record(exc, time.perf_counter() - t0, None if ideal else drifter)
        rec.update(id=rid, values=values, changes=changes)
        store[rid] = rec
        history.append(rec)
        counter["new"] += 1
        if cache_path is not None:
            write_cache(cache_path, tag, store)
        bar.design(rec["seconds"])
        return rec

    # COBYLA's budget counts its designs, the start among them; SLSQP's its iterations
    bar = DesignProgress(None if method == "slsqp" else max_evaluations, progress)
    start = np.array([spec[k]["start"] for k in keys])
    u0 = (start - lo) / span
    try:
        first = evaluate(u0)
        if not first["ok"]:
            raise ValueError(f"the start has no operating point: {first['error']}")
        if not first["feasible"]:
            name, c = min(first["constraints"].items(), key=lambda kv: kv[1]["scaled"])
            scale, unit = display_unit(c["unit"])
            u = f" {unit}" if unit else ""
            raise ValueError(f"infeasible start: constraint {name} = {c['value'] * scale:.6g}{u} misses its "
                             f"limit {c['limit'] * scale:.6g}{u} by {-c['margin'] * scale:.4g}{u}")
        ref = abs(first["objectives"][fkey]) or 1.0

        def f(u):
            rec = evaluate(u)
            return -rec["objectives"][fkey] / ref if rec["ok"] else 1.0

        def g(u):
            rec = evaluate(u)
            if not rec["ok"]:
                return -np.ones(len(limits))
            return np.array([c["scaled"] for c in rec["constraints"].values()])

        def derivative(u):
            rec = evaluate(u)
            if rec["id"] not in gradients:
                orbit = chain.orbit(rec["id"]) if rec["ok"] and "u" in rec else None
                gradients[rec["id"]] = _design_gradient(cfg, folder, rec, orbit, spec, limits, fkey, span)
                counter["gradients"] += 1
            return gradients[rec["id"]]

        if method == "differential_evolution":
            res = population_search(lambda u: penalised(evaluate(u), fkey, ref),
                                    lambda u: design_of(u)[::2], store, evaluate, _design_record,
                                    {"config": cfg, "folder": folder, "limits": kept}, u0, popsize=popsize,
                                    maxiter=maxiter, seed=seed, workers=workers, atol=tol ** 2)
        elif method in ("cobyla", "multistart"):
            def cobyla(u, most=max_evaluations):
                return minimize(f, u, method="COBYLA", constraints=[{"type": "ineq", "fun": g}], bounds=[(
                    0.0, 1.0)] * len(keys), options={"rhobeg": rhobeg, "tol": tol, "maxiter": most})
            res, found = (cobyla(u0), []) if method == "cobyla" else multistart_search(
                evaluate, lambda u: design_of(u)[::2], store, _design_record,
                {"config": cfg, "folder": folder, "limits": kept}, lambda u: cobyla(u, budget), fkey,
                sample=sample, local_starts=local_starts, seed=seed, workers=workers, n_variables=len(keys))
        else:
            res = minimize(f, u0, jac=lambda u: -derivative(u)[0] / ref, method="SLSQP",
                           constraints=[{"type": "ineq", "fun": g, "jac": lambda u: derivative(u)[1]}],
                           bounds=[(0.0, 1.0)] * len(keys),
                           options={"ftol": tol ** 3, "maxiter": max_evaluations})
        message = str(res.message)
        bar.finish()
    finally:
        bar.close()
    # the reported optimum (and the baseline) by a fresh orbit(): no continuation, no cache; the best
    # feasible design whose fresh orbit meets the constraints too (a continued orbit's figures can lie
    # some 1e-9 from the fresh one's, a design at an active limit on its other side)
    fresh = {}
    for name, rec in [("baseline", first)] + [("optimum", r) for r in sorted(
            (r for r in history if r.get("feasible")), key=lambda r: r["objectives"][fkey], reverse=True)]:
        if "optimum" in fresh and fresh["optimum"]["feasible"]:
            break
        best = rec
        drifter = build(with_values(cfg, rec["changes"]), folder)
        out, orbit = (evaluate_blow(drifter, V, limits), None) if ideal else evaluate_design(drifter, kept)
        out.update(piston_and_multipliers(drifter, orbit), values=rec["values"], changes=rec["changes"],
                   shank_stress=None if ideal else shank_stress(drifter, orbit))
        out["continued_vs_fresh"] = max(abs(out["objectives"][k] / rec["objectives"][k] - 1.0)
                                        for k in rec["objectives"] if rec["objectives"][k] != 0.0)
        if name == "optimum" and "optimum" in fresh:
            message += "; the best design's fresh orbit missed a constraint, the next best kept"
        fresh[name] = out
    message += _better_missed(history, best, fkey)
    certificate = certify_search(fresh["optimum"], history, keys, (lo, span), res, tol, fkey, (lambda v: (
        evaluate_blow(build(with_values(cfg, design_of(v)[2]), folder), V, limits))) if ideal else None,
        lambda: _design_gradient(cfg, folder, fresh["optimum"], None, spec, limits, fkey, span))
    return DrifterOptimum(objective=objective,
                          vary={k: {"low": spec[k]["low"], "high": spec[k]["high"], "unit": spec[k]["unit"]}
                                for k in keys},
                          baseline=fresh["baseline"], optimum=fresh["optimum"], evaluations=counter["new"],
                          cached=n_cached, seconds=time.perf_counter() - t_start, history=history,
                          message=message, config=with_values(cfg, best["changes"]),
                          gradients=counter["gradients"], certificate=certificate, found=found)


def _design_record(changes: dict, config: dict, folder, limits: dict) -> dict:
    """A design's record by a fresh ``orbit()`` (a worker's task in the population search)."""
    t0, drifter = time.perf_counter(), None
    try:
        drifter = build(with_values(config, changes), folder)
        rec, orbit = evaluate_design(drifter, limits)
        rec.update(piston_and_multipliers(drifter, orbit))
    except (ValueError, np.linalg.LinAlgError, ArithmeticError) as exc:
        rec = failed_record(exc, time.perf_counter() - t0, drifter)
    return rec


def _design_gradient(cfg: dict, folder, rec: dict, orbit, spec: dict, limits: dict, fkey: str,
                     span: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The gradients of a design's objective and of its constraints' scaled margins in the scaled
    variables: per variable by :func:`~impactbar.physical.sensitivity.tangent_derivatives` from the
    design's orbit, or where its step meets a border (or a design read from the cache, without its
    orbit) by central differences of orbits continued from the design's; zeros for a design
    without an orbit."""
    keys, names = list(spec), list(limits)
    dobj, dcon = np.zeros(len(keys)), np.zeros((len(names), len(keys)))
    if not rec["ok"]:
        return dobj, dcon
    design = with_values(cfg, rec["changes"])
    values, units = rec["values"], {k: spec[k]["unit"] for k in keys}

    def read(point) -> dict:
        r = _figures(point, limits)
        return {"objective": r["objectives"][fkey], **{n: r["constraints"][n]["scaled"] for n in names}}

    if orbit is None:
        orbit = build(design, folder).orbit()
    step = default_step(orbit.drifter)
    for j, key in enumerate(keys):
        try:
            col = {n: d[key] for n, d in tangent_derivatives(design, folder, orbit, [key], values, units,
                                                             step, "max_multiplier" in limits,
                                                             read)[2].items()}
        except ValueError:  # a border within the step: the secant of two continued orbits
            h = step * abs(values[key])
            try:
                ends = [read(build(with_values(design, {key: config_quantity(values[key] + s * h,
                                                                             units[key])}),
                                   folder).orbit(guess=orbit)) for s in (1.0, -1.0)]
            except (ValueError, np.linalg.LinAlgError, ArithmeticError):
                continue
            col = {n: (ends[0][n] - ends[1][n]) / (2.0 * h) for n in ends[0]}
        dobj[j] = col["objective"] * span[j]
        dcon[:, j] = [col[n] * span[j] for n in names]
    return dobj, dcon

