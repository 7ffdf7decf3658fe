"""The result of the whole-drifter optimiser (:func:`~impactbar.physical.optimize_drifter`): the
baseline and the reported design side by side, with every design evaluated, the search's message and
the design's first-order certificate; as a table, plain data, JSON and a figure.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .display_units import display_unit
from .optimize_cache import dumps
from .optimize_failures import failures_table
from .optimize_problem import FEASIBILITY_TOLERANCE, objectives

__all__ = ["DrifterOptimum"]


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


@dataclass
class DrifterOptimum:
    """The result of :func:`~impactbar.physical.optimize_drifter`: the baseline and the optimum side by
    side.

    Attributes
    ----------
    objective : str
        The objective maximised (a key of :data:`~impactbar.physical.optimize_problem.OBJECTIVES`).
    vary : dict
        Dotted key to its ``(low, high)`` bounds in SI and ``unit``.
    baseline, optimum : dict
        Each design's record (:func:`~impactbar.physical.optimize_problem.evaluate_design`) with
        ``values`` (dotted key to SI value) and ``changes`` (dotted key to the config value, for
        :func:`~impactbar.physical.with_values`).
        The optimum is the best feasible design evaluated, re-evaluated by a fresh ``orbit()``
        (``continued_vs_fresh``: the largest relative difference of its figures from the search's).
    evaluations : int
        Designs evaluated by this run (not counting those read from the cache).
    cached : int
        Designs read from the cache file.
    gradients : int
        Gradients computed (``method="slsqp"``; each four flights per variable, or two continued
        orbits for a variable whose step meets a border).
    cached_gradients : int
        Gradients read from the cache file, where a run started again would have computed them.
    seconds : float
        Wall time of the run (s).
    history : list of dict
        Every design's record in the order evaluated; of the designs without a one-impact orbit,
        those the table lists have their motion classified, the others' records say they have not
        (:data:`~impactbar.physical.optimize_failures.NOT_CLASSIFIED`;
        :func:`~impactbar.physical.optimize_failures.classify_failed` classifies one).
    message : str
        The optimiser's.
    certificate : OptimalityCertificate
        The optimum's first-order (KKT) certificate (:mod:`~impactbar.physical.optimality`); the table
        says "optimum" only where it is ``"converged"``.
    found : list of dict
        ``method="multistart"``: each local search's start and best design, best first
        (:func:`~impactbar.physical.optimize_multistart.multistart_search`); empty otherwise.
    kind : {"circuit", "drifter"}
        The machine: the drifter with its oil circuit, or the valve drifter (its objectives,
        :func:`~impactbar.physical.optimize_problem.objectives`).
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
    cached_gradients: int = 0
    config: dict = field(default_factory=dict, repr=False)
    certificate: object = None  #: the optimum's OptimalityCertificate (first-order, KKT)
    found: list = field(default_factory=list)
    kind: str = "circuit"

    @property
    def objective_key(self) -> str:
        """The figure of the records' ``objectives`` that is maximised (``"drilling_rate_per_kW"``,
        ``"impact_power_kW"`` for ``"impact_power"``, a valve drifter's too)."""
        return objectives(self.kind)[self.objective].key

    @property
    def gain(self) -> float:
        """The objective at the optimum over the baseline's, less 1."""
        key = self.objective_key
        return self.optimum["objectives"][key] / self.baseline["objectives"][key] - 1.0

    def to_dict(self) -> dict:
        """The result as plain data (JSON-ready)."""
        return {"objective": self.objective, "vary": self.vary, "baseline": self.baseline,
                "optimum": self.optimum, "gain": self.gain, "evaluations": self.evaluations,
                "cached": self.cached, "gradients": self.gradients,
                "cached_gradients": self.cached_gradients, "seconds": self.seconds,
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
        its limit and margin; then the designs without an operating point, why and what the drill does
        there (:func:`~impactbar.physical.optimize_failures.failures_table`)."""
        word = ("optimum" if self.certificate is not None and self.certificate.converged else
                "infeasible" if not self.optimum.get("feasible", True) else "best found")
        rows = [f"{'':34s}{'baseline':>14s}{word:>14s}"]
        for key, b in self.vary.items():
            scale, unit = display_unit(b["unit"])
            rows.append(f"{key:34s}{self.baseline['values'][key] * scale:14.5g}"
                        f"{self.optimum['values'][key] * scale:14.5g} {unit}")
        named = objectives(self.kind)
        for name, (key, unit, _) in named.items():
            if key in self.baseline["objectives"]:
                mark = " *" if name == self.objective else ""
                rows.append(f"{name + mark:34s}{self.baseline['objectives'][key]:14.5g}"
                            f"{self.optimum['objectives'][key]:14.5g} {unit}")
        for key in self.baseline["objectives"]:
            if key not in {k for k, _, _ in named.values()}:
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
        from_cache = (f"{self.cached} designs and {self.cached_gradients} gradients" if self.cached_gradients
                      else f"{self.cached}")
        slowest = max((r["seconds"] for r in self.history if "seconds" in r), default=0.0)
        rows.append(f"gain in {self.objective}: {self.gain * 100:+.2f} % after {self.evaluations} "
                    f"evaluations{grads} ({from_cache} from the cache) in {self.seconds:.0f} s, the "
                    f"slowest design {slowest:.1f} s")
        if self.certificate is not None:
            rows.append(f"{word}: {self.certificate}")
        failed = failures_table(self.history, self.vary)
        if failed:
            rows.append(failed)
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
                ax.bar(label, rec["objectives"].get(self.objective_key, np.nan), color=colour)
        if self.baseline.get("shank_stress") is not None:
            ax.set_xlabel("time from impact (us)")
            ax.set_ylabel("shank stress (MPa)")
            ax.legend()
        else:
            ax.set_ylabel(f"{self.objective} ({objectives(self.kind)[self.objective].unit})")
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
