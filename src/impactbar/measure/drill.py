r"""A drill rod's blow from two gauges: the waves at the bit, its force-penetration curve and the rock.

On a drill rod the pulse is longer than the distance from a gauge to the bit, so the wave going down
and the one coming back overlap at every gauge. Two gauges part them (Lundberg and Henchoz's
two-point separation, :func:`~impactbar.measure.separate_two_point`), low-passed below the first
frequency where it fails, :math:`c / (2 (x_B - x_A))`; the waves at the bit give its force, velocity,
penetration and the energy that passed into it (:func:`~impactbar.measure.end_history`), the
force-penetration curve the rock's loading and unloading stiffnesses
(:func:`~impactbar.measure.fit_bilinear_rock`, the steps where the force exceeds a tenth of its peak:
in contact), and, where the spec describes the piston and the rod, the model's blow fitted to the
gauges' strains (:func:`~impactbar.measure.fit_blow`, the recording's time taken from the impact).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .recording import Bar, Recording
from .results import end_history
from .rock import fit_bilinear_rock
from .waves import separate_two_point

__all__ = ["DrillRodTest", "analyse_drill_rod"]

#: the rock's fit reads the steps where the bit's force exceeds this fraction of its peak
CONTACT = 0.1


@dataclass(frozen=True)
class DrillRodTest:
    """What :func:`analyse_drill_rod` found: ``report`` (plain numbers, JSON-ready), the gauges'
    strains (``record_time`` (s), ``gauge_strain`` by channel), the waves at the bit (``waves``), its
    :class:`~impactbar.measure.EndHistory` (``bit``) and the model's fit (``fit``, a
    :class:`~impactbar.measure.BlowFit`, or None)."""

    report: dict
    record_time: np.ndarray
    gauge_strain: dict
    waves: object
    bit: object
    fit: object = None

    def plot(self, path=None):
        """The gauges' strains, the waves at the bit, its force-penetration curve and, with a fit,
        the model against the measurement (:func:`~impactbar.measure.figures.plot_drill_rod`)."""
        from .figures import plot_drill_rod

        return plot_drill_rod(self, path)


def analyse_drill_rod(recording: Recording, gauges: dict, rod: Bar, *, cutoff: float | None = None,
                      leak: float = 1.0, baseline: slice | None = None, model: dict | None = None
                      ) -> DrillRodTest:
    """Analyse a blow recorded by two gauges on a drill rod (the module's steps).

    Parameters
    ----------
    recording : Recording
        Its time from the impact where ``model`` is given.
    gauges : dict of str to Gauge
        Two channels' gauges, their stations (m) measured from the bit, at two stations.
    rod : Bar
        The rod where the gauges sit.
    cutoff : float (Hz), optional
        The channels' low-pass, below the first failing frequency (default 0.8 of it).
    leak : float
        The march's leak (:func:`~impactbar.measure.separate_two_point`).
    baseline : slice, optional
        The quiet samples before the wave (default: the first tenth).
    model : dict, optional
        :func:`~impactbar.measure.fit_blow`'s keyword arguments but the time and strains (``rod`` as
        RodPiece, ``piston_lengths``, ``piston_areas``, ``values``, ``vary``), with the stations from
        the rod's struck end taken as its length less the gauges'.

    Returns
    -------
    DrillRodTest

    Raises
    ------
    ValueError
        Not two gauges, two at one station, a channel not in the recording, a cutoff at or above the
        first failing frequency, and every refusal of the functions it calls.
    """
    if len(gauges) != 2:
        raise ValueError(f"a drill rod's two-point separation needs two channels, got {len(gauges)} "
                         f"({sorted(gauges)})")
    for channel in gauges:
        if channel not in recording.channels:
            raise ValueError(f"channel {channel!r} is not in the recording (it has "
                             f"{sorted(recording.channels)})")
    (near, g_near), (far, g_far) = sorted(gauges.items(), key=lambda kv: kv[1].station)
    if g_far.station == g_near.station:
        raise ValueError(f"channels {near!r} and {far!r} sit at one station ({g_near.station:g} m): "
                         "two-point separation needs two")
    time, dt = recording.time, recording.dt
    baseline = baseline if baseline is not None else slice(0, max(8, time.size // 10))
    strain = {c: gauges[c].strain(recording.channels[c]) for c in (near, far)}
    failing = rod.wave_speed / (2.0 * (g_far.station - g_near.station))
    cutoff = 0.8 * failing if cutoff is None else float(cutoff)
    if not 0.0 < cutoff < failing:
        raise ValueError(f"cutoff must lie in (0, {failing:.6g}) Hz, below the first frequency where "
                         f"two-point separation fails, c / (2 (x_far - x_near)); got {cutoff!r}")
    waves = separate_two_point(time, strain[near], strain[far], g_near.station, g_far.station, rod, leak=leak,
                               baseline=baseline, cutoff=cutoff)
    bit = end_history(waves, rod)
    rock = fit_bilinear_rock(bit.force, bit.velocity, dt, contact=CONTACT)
    report = {
        "separation": {"channels": [near, far], "stations_m": [g_near.station, g_far.station],
                       "first_failing_Hz": failing, "cutoff_Hz": cutoff, "leak": leak},
        "bit": {"peak_force_kN": float(bit.force.max()) / 1e3,
                "max_penetration_mm": float(bit.displacement.max()) * 1e3,
                "energy_fv_J": float(bit.energy_fv[-1]), "energy_f2_J": float(bit.energy_f2[-1]),
                "incident_energy_J": float(rod.stiffness * rod.wave_speed * np.sum(waves.toward ** 2) * dt)},
        "rock_from_curve": rock,
    }
    fit = None
    if model is not None:
        from .model import fit_blow

        model = dict(model)
        length = sum(p.length_m for p in model["rod"])
        fit = fit_blow(time, {length - gauges[c].station: strain[c] for c in (near, far)}, **model)
        report["model_fit"] = {"values": fit.values, "errors": fit.errors, "misfit": fit.misfit,
                               "evaluations": fit.evaluations}
    return DrillRodTest(report, time, strain, waves, bit, fit)
