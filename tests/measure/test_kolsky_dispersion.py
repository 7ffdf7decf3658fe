"""The dispersion correction inside the Kolsky bar's analysis: on a recording made by carrying known
waves at the specimen's faces to the gauges in a round bar's first mode (the Pochhammer-Chree
relation, :func:`~impactbar.measure.disperse`), the analysis with the bars' Poisson ratio brings them
back; on a thin bar it changes nothing to the tolerance stated. And on a synthetic recording whose
pulses overlap at the gauge, the one-line refusal that names it."""

import math

import numpy as np
import pytest

from impactbar.measure import Bar, Gauge, Recording, analyse_kolsky, disperse

X = 0.5  # m, both gauges from the specimen
NU = 0.29
T = np.arange(4000) * 1e-7  # 400 us at 0.1 us


def _pulse(t, start, length=60e-6, ramp=10e-6):
    """A trapezoid of unit height with raised-cosine ramps."""
    s = np.clip((t - start) / ramp, 0.0, 1.0)
    e = np.clip((start + length - t) / ramp, 0.0, 1.0)
    return -0.5 * (1 - np.cos(np.pi * s)) * 0.5 * (1 - np.cos(np.pi * e)) * 1e-3


def _test(radius, *, poisson, carried=True):
    """The analysis of a recording whose face waves are known: the incident pulse at the face
    (compressive), the reflected -0.4 of it and the transmitted 0.6, each carried to its gauge in
    the first mode of a steel bar of ``radius`` (or merely delayed where ``carried`` is False)."""
    bar = Bar(200e9, 7850.0, math.pi * radius ** 2)
    arrive = 30e-6 + X / bar.wave_speed
    face = _pulse(T, arrive)
    move = (lambda w, d: disperse(T, w, d, radius, bar, NU)) if carried else \
        (lambda w, d: np.interp(T - d / bar.wave_speed, T, w, left=0.0, right=0.0))
    incident_gauge = move(face, -X) + move(-0.4 * face, X)
    transmitted_gauge = move(0.6 * face, X)
    noise = np.random.default_rng(0).standard_normal((2, T.size)) * 1e-6
    gauges = {"a": Gauge("incident", X, gauge_factor=2.0), "b": Gauge("transmitted", X, gauge_factor=2.0)}
    rec = Recording.from_arrays(T, a=(incident_gauge + noise[0]) / 2.0,
                                b=(transmitted_gauge + noise[1]) / 2.0)
    test = analyse_kolsky(rec, gauges, bar, bar, 5e-3, 1e-4, baseline=slice(0, 200), cutoff=None,
                          poisson=poisson)
    k0 = int(round((test.windows["incident"].t_start + X / bar.wave_speed - T[0]) / 1e-7))
    want = {"incident": face, "reflected": -0.4 * face, "transmitted": 0.6 * face}
    plateau = np.abs(face[k0:k0 + test.time.size]) > 0.5e-3
    return test, {k: float(np.max(np.abs(getattr(test, k) - w[k0:k0 + test.time.size])[plateau]) / 1e-3)
                  for k, w in want.items()}


def test_the_correction_brings_a_thick_bars_waves_back_to_the_faces():
    """A 10 mm bar and 10 us ramps: carried in the first mode, the waves at the faces come back
    within 2 % of the pulse's height where it exceeds half of it (1.5 %: the windows cut the ripple
    outside the pulses); merely delayed by x / c, they miss by more than 4 % (4.8 %)."""
    _, corrected = _test(0.005, poisson=NU)
    _, delayed = _test(0.005, poisson=None)
    assert max(corrected.values()) < 0.02
    assert max(delayed.values()) > 0.04
    for name, error in corrected.items():
        assert error < 0.5 * delayed[name], name


def test_a_thin_bar_is_left_as_it_was():
    """A 2 mm bar (at the ramps' 100 kHz, 1 - c / c0 = 3e-4): with the correction or without,
    the waves at the faces agree within 0.5 % of the pulse's height, the stresses' peaks within
    0.5 %."""
    a, _ = _test(0.001, poisson=NU, carried=False)
    b, _ = _test(0.001, poisson=None, carried=False)
    for name in ("incident", "reflected", "transmitted"):
        assert np.max(np.abs(getattr(a, name) - getattr(b, name))) < 0.005 * 1e-3
    for k in ("1", "2", "3"):
        assert a.report["stress_strain"][k]["peak_stress_MPa"] == pytest.approx(
            b.report["stress_strain"][k]["peak_stress_MPa"], rel=5e-3)


def test_pulses_that_overlap_at_the_gauge_are_refused_in_one_line():
    """A 60 us pulse at a gauge 0.1 m from the specimen: its reflection comes back 40 us after its
    foot, while it still passes; one-point separation cannot part them, and the refusal says so."""
    bar = Bar(200e9, 7850.0, 1e-4)
    c, x = bar.wave_speed, 0.1
    face = _pulse(T, 30e-6 + x / c)
    delayed = lambda w, d: np.interp(T - d / c, T, w, left=0.0, right=0.0)  # noqa: E731
    noise = np.random.default_rng(0).standard_normal((2, T.size)) * 1e-7
    rec = Recording.from_arrays(T, a=(delayed(face, -x) - 0.4 * delayed(face, x)) / 2 + noise[0],
                                b=0.6 * delayed(face, x) / 2 + noise[1])
    gauges = {"a": Gauge("incident", x, gauge_factor=2.0), "b": Gauge("transmitted", x, gauge_factor=2.0)}
    with pytest.raises(ValueError, match=r"^the pulses overlap at the incident bar's gauge: .* use two-point "
                                         r"separation$"):
        analyse_kolsky(rec, gauges, bar, bar, 5e-3, 1e-4, baseline=slice(0, 200), cutoff=None)
