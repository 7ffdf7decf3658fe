"""A split-Hopkinson (Kolsky) bar test from its recording to the specimen's stress-strain curve.

The steps a test engineer checks, each reported rather than hidden: the channels converted to strain
(:mod:`impactbar.measure.recording`); the gauges of one bar compared; the incident, reflected and
transmitted pulses found where the bars' strain leaves its noise band (no hand-picked windows), and
their feet compared with the times the wave speed predicts, and the delay of the reflection after
the incident pulse fitted (:func:`~impactbar.measure.fit_reflection`: the incident bar's wave speed
from the reflection time, with its standard error, its ratio and its misfit: the specimen's face is
no free end, and the reflection no copy of the pulse); the waves shifted to the specimen's
faces (one-point separation, :mod:`impactbar.measure.waves`); the striker's impact velocity, the
waves' energies, the specimen's one-, two- and three-wave stress, strain and strain rate and the
force balance on its faces (:mod:`impactbar.measure.results`); and the spectrum of the pre-trigger
noise, where a pickup shows as a peak.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .recording import Bar, Recording
from .reflection import fit_reflection
from .results import end_history, impact_velocity, specimen_response, wave_energy
from .waves import Waves, Window, find_pulses, separate_one_point, shift

__all__ = ["KolskyTest", "analyse_kolsky"]

#: a pulse counts when its peak is at least this fraction of the largest pulse on its bar
SIGNIFICANT = 0.25


@dataclass(frozen=True)
class KolskyTest:
    """What :func:`analyse_kolsky` found: ``report`` (a dict of plain numbers, JSON-ready), the
    waves at the specimen's faces (``time`` (s) from the incident wave's arrival, strains tension
    positive), the specimen's response, and the bars' strains on the record's time base
    (``record_time``, ``bar_strain`` by bar) with the pulses' ``windows``."""

    report: dict
    time: np.ndarray
    incident: np.ndarray
    reflected: np.ndarray
    transmitted: np.ndarray
    specimen: object
    record_time: np.ndarray
    bar_strain: dict
    windows: dict

    def plot(self, path=None):
        """The bars' strains with the windows found, the waves at the specimen and the stress-strain
        curves (:func:`~impactbar.measure.figures.plot_kolsky`)."""
        from .figures import plot_kolsky

        return plot_kolsky(self, path)


def _bar_strains(recording: Recording, gauges: dict, bars: dict, baseline: slice) -> dict:
    """Each bar's channels as strains, their pre-trigger medians removed."""
    on = {name: [] for name in bars}
    for channel, gauge in gauges.items():
        if channel not in recording.channels:
            raise ValueError(f"channel {channel!r} is not in the recording (it has "
                             f"{sorted(recording.channels)})")
        if gauge.bar not in bars:
            raise ValueError(f"channel {channel!r} sits on bar {gauge.bar!r}, which the bars do not name "
                             f"(they are {sorted(bars)})")
        volts = recording.channels[channel]
        on[gauge.bar].append((channel, gauge.strain(volts - np.median(volts[baseline]))))
    for name, chans in on.items():
        if not chans:
            raise ValueError(f"no channel sits on the {name} bar: each bar needs a gauge station")
        stations = {gauges[c].station for c, _ in chans}
        if len(stations) > 1:
            raise ValueError(f"the gauges on the {name} bar sit at different stations {sorted(stations)}: "
                             "a one-point analysis averages gauges at one station")
    return on


def _compare_gauges(chans, window: Window) -> dict | None:
    """Two gauges on one bar over a pulse: the second's least-squares scale on the first, and their
    r.m.s. difference relative to the pulse's peak."""
    if len(chans) < 2:
        return None
    (n1, s1), (n2, s2) = chans[:2]
    a, b = s1[window.start:window.stop], s2[window.start:window.stop]
    return {"channels": [n1, n2], "scale": float(a @ b / (a @ a)),
            "rms_difference": float(np.sqrt(np.mean((a - b) ** 2)) / np.max(np.abs(a)))}


def _pulses(time, strain, name, threshold, cutoff, baseline) -> list[Window]:
    found = find_pulses(time, strain, threshold=threshold, cutoff=cutoff, baseline=baseline,
                        name=f"the {name} bar")
    biggest = max(abs(w.peak) for w in found)
    return [w for w in found if abs(w.peak) >= SIGNIFICANT * biggest]


def _noise_peak(volts, dt: float, baseline: slice, band=(2e5, 5e6)) -> dict:
    """The pre-trigger noise's strongest line (Welch's periodogram) in ``band`` (Hz), and how far it
    stands above the band's median."""
    from scipy.signal import welch

    quiet = volts[baseline]
    f, pxx = welch(quiet - quiet.mean(), fs=1.0 / dt, nperseg=min(1024, quiet.size))
    sel = (f >= band[0]) & (f <= band[1])
    k = np.argmax(pxx[sel])
    return {"frequency_MHz": round(float(f[sel][k]) / 1e6, 3),
            "above_median": round(float(pxx[sel][k] / np.median(pxx[sel])), 1)}


def _carried(time, strain, window: Window, distance: float, bar: Bar, poisson: float) -> np.ndarray:
    """The pulse in ``window`` carried ``distance`` along a round bar of the bar's area (its first
    mode, :func:`~impactbar.measure.disperse`)."""
    from .dispersion import disperse

    alone = np.zeros_like(strain)
    alone[window.start:window.stop] = strain[window.start:window.stop]
    return disperse(time, alone, distance, float(np.sqrt(bar.area / np.pi)), bar, poisson)


def analyse_kolsky(recording: Recording, gauges: dict, incident_bar: Bar, transmitted_bar: Bar,
                   specimen_length: float, specimen_area: float, *, striker_length: float | None = None,
                   striker: Bar | None = None, threshold: float = 10.0, cutoff: float | None = 1e6,
                   baseline: slice | None = None, curve_points: int = 40, poisson: float | None = None
                   ) -> KolskyTest:
    r"""Analyse a Kolsky bar test.

    Parameters
    ----------
    recording : Recording
    gauges : dict of str to Gauge
        The channels' gauges, each on the bar ``"incident"`` or ``"transmitted"`` (the gauges of one
        bar at one station; two of them are compared and averaged).
    incident_bar, transmitted_bar : Bar
    specimen_length, specimen_area : float (m, m^2)
    striker_length : float (m), optional
        For the striker's kinetic energy beside the incident wave's.
    striker : Bar, optional
        The striker's material and section, by default the incident bar's.
    threshold, cutoff : float
        The pulse detection's level (noise standard deviations) and low-pass (Hz; None for none).
    baseline : slice, optional
        The quiet (pre-trigger) samples, by default the first tenth.
    curve_points : int
        How many points of the stress-strain curves the report holds.
    poisson : float, optional
        The bars' Poisson ratio: where given, each wave is carried between the gauge and the
        specimen in a round bar's first longitudinal mode (:func:`~impactbar.measure.disperse`, the
        radius :math:`\sqrt{A/\pi}` of the bar's area, components above :math:`f a / c_0 = 1`
        dropped) instead of delayed by :math:`x/c`.

    Returns
    -------
    KolskyTest

    Raises
    ------
    ValueError
        A channel not in the recording, a gauge on a bar not named, a bar without a gauge, a bar
        with no pulse, an incident pulse that overlaps its reflection at the gauge, no reflected
        pulse after the incident one.
    """
    time, dt = recording.time, recording.dt
    baseline = baseline if baseline is not None else slice(0, max(8, time.size // 10))
    bars = {"incident": incident_bar, "transmitted": transmitted_bar}
    on = _bar_strains(recording, gauges, bars, baseline)
    strain = {name: np.mean([s for _, s in chans], axis=0) for name, chans in on.items()}
    station = {name: gauges[first].station for name, ((first, _), *_) in on.items()}

    inc_pulses = _pulses(time, strain["incident"], "incident", threshold, cutoff, baseline)
    w_inc = inc_pulses[0]
    due = w_inc.t_start + 2 * station["incident"] / incident_bar.wave_speed
    if w_inc.t_stop > due:
        raise ValueError(f"the pulses overlap at the incident bar's gauge: the incident one lasts to "
                         f"{w_inc.t_stop * 1e6:.2f} us, its reflection is due from {due * 1e6:.2f} us "
                         f"(2 x {station['incident']:g} m / {incident_bar.wave_speed:.6g} m/s after its "
                         "foot); one-point separation needs them apart: use two-point separation")
    later = [w for w in inc_pulses if w.start >= w_inc.stop and w.sign == -w_inc.sign]
    if not later:
        raise ValueError("no reflected pulse on the incident bar after the incident one "
                         f"(ending at {w_inc.t_stop * 1e6:.2f} us)")
    w_ref = later[0]
    w_tra = _pulses(time, strain["transmitted"], "transmitted", threshold, cutoff, baseline)[0]
    echo = fit_reflection(time, strain["incident"], station["incident"], w_inc, w_ref, cutoff=cutoff)

    ci, ct = incident_bar.wave_speed, transmitted_bar.wave_speed
    xi, xt = station["incident"], station["transmitted"]
    t_ref_computed = w_inc.t_start + 2 * xi / ci
    t_tra_computed = w_inc.t_start + xi / ci + xt / ct

    front = separate_one_point(time, strain["incident"], w_inc, w_ref, xi, incident_bar)
    # the transmitted bar carries one wave, away from the specimen: shifted back to its face
    transmitted_face = np.zeros_like(time)
    transmitted_face[w_tra.start:w_tra.stop] = strain["transmitted"][w_tra.start:w_tra.stop]
    if poisson is None:
        transmitted_face = shift(time, transmitted_face, -xt / ct)
    else:  # each wave carried in the first mode: the incident on, the two others back
        front = Waves(time, _carried(time, strain["incident"], w_inc, xi, incident_bar, poisson),
                      _carried(time, strain["incident"], w_ref, -xi, incident_bar, poisson))
        transmitted_face = _carried(time, strain["transmitted"], w_tra, -xt, transmitted_bar, poisson)
    t_arrive = w_inc.t_start + xi / ci
    k0 = int(round((t_arrive - time[0]) / dt))
    n = int(round(w_inc.duration / dt)) + 1
    if k0 + n > time.size:
        raise ValueError("the record ends before the incident pulse has passed the specimen")
    eI, eR, eT = (w[k0:k0 + n] for w in (front.toward, front.away, transmitted_face))
    resp = specimen_response(eI, eR, eT, dt, incident_bar, transmitted_bar, specimen_length, specimen_area)

    # the striker: from the bar's mean and from each gauge
    incident_alone = strain["incident"][w_inc.start:w_inc.stop]
    v = impact_velocity(incident_alone, incident_bar, striker=striker)
    per_gauge = [impact_velocity(s[w_inc.start:w_inc.stop], incident_bar, striker=striker)["velocity"]
                 for _, s in on["incident"]]
    half_spread = 0.5 * (max(per_gauge) - min(per_gauge))
    v["per_gauge"] = per_gauge
    v["uncertainty"] = float(np.hypot(v["velocity_std"], half_spread))

    energies = {name: wave_energy(strain[bar][w.start:w.stop], dt, bars[bar])
                for name, bar, w in (("incident", "incident", w_inc), ("reflected", "incident", w_ref),
                                     ("transmitted", "transmitted", w_tra))}
    energies["absorbed"] = energies["incident"] - energies["reflected"] - energies["transmitted"]
    history = end_history(Waves(time, front.toward, front.away), incident_bar)
    energies["force_velocity_at_specimen"] = float(history.energy_fv[-1])
    if striker_length is not None:
        s = striker if striker is not None else incident_bar
        energies["striker_kinetic"] = 0.5 * s.density * s.area * striker_length * v["velocity"] ** 2

    f1, f2 = resp.front_force, resp.back_force
    mean_force = 0.5 * (f1 + f2)
    loaded = mean_force > 0.3 * mean_force.max()
    balance = 2 * (f1 - f2)[loaded] / (f1 + f2)[loaded]

    summary = {}
    for k in ("1", "2", "3"):
        stress, strain_k, rate = resp.stress[k], resp.strain[k], resp.strain_rate[k]
        i = int(np.argmax(stress))
        steady = rate > 0.5 * rate.max()
        pick = np.linspace(0, stress.size - 1, curve_points).round().astype(int)
        summary[k] = {"peak_stress_MPa": float(stress[i] / 1e6), "strain_at_peak": float(strain_k[i]),
                      "final_strain": float(strain_k[-1]), "mean_strain_rate": float(rate[steady].mean()),
                      "curve": {"strain": strain_k[pick].tolist(),
                                "stress_MPa": (stress[pick] / 1e6).tolist()}}

    report = {
        "windows": {"incident": w_inc.to_dict(), "reflected": w_ref.to_dict(),
                    "transmitted": w_tra.to_dict()},
        "arrivals": {"reflected_computed_us": t_ref_computed * 1e6,
                     "reflected_early_us": (t_ref_computed - w_ref.t_start) * 1e6,
                     "transmitted_computed_us": t_tra_computed * 1e6,
                     "transmitted_late_us": (w_tra.t_start - t_tra_computed) * 1e6,
                     "incident_bar_wave_speed_from_reflection": 2 * xi / (w_ref.t_start - w_inc.t_start),
                     "reflection_fit": echo.to_dict()},
        "impact_velocity": v,
        "energies_J": energies,
        "stress_strain": summary,
        "diagnostics": {
            "gauges": {bar: _compare_gauges(chans, w_inc if bar == "incident" else w_tra)
                       for bar, chans in on.items()},
            "force_balance": {"median_abs": float(np.median(np.abs(balance))),
                              "max_abs": float(np.max(np.abs(balance))),
                              "about": "2 (F_front - F_back) / (F_front + F_back) where the mean force "
                                       "exceeds 30 % of its peak"},
            "noise_lines": {c: _noise_peak(recording.channels[c], dt, baseline) for c in gauges},
            "wave_speeds": {"incident": ci, "transmitted": ct},
        },
    }
    return KolskyTest(report, resp.time, eI, eR, eT, resp, time, strain,
                      {"incident": w_inc, "reflected": w_ref, "transmitted": w_tra})
