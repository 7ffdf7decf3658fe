"""Waves separated at one or two gauges, against waves known in closed form (a rod's end on a spring)."""

import numpy as np
import pytest
from spring_end_waves import AMP, C, away, gauge, toward

from impactbar.measure import Bar, Window, find_pulses, separate_one_point, separate_two_point

BAR = Bar(200e9, 8000.0, 1e-3, wave_speed=C)
DT = 1e-6
TIME = np.arange(-150, 1500) * DT  # quiet before the incident wave reaches the far gauge


def _error(w):
    return max(np.max(np.abs(w.toward - toward(w.time))), np.max(np.abs(w.away - away(w.time)))) / AMP


def test_two_point_separation_recovers_the_waves_at_a_spring_end_exactly():
    """The incident pulse (1 m long) overlaps its reflection at both gauges (0.2 m and 0.25 m from
    the end): one-point separation cannot part them, two-point recovers both at the end to rounding."""
    w = separate_two_point(TIME, gauge(TIME, 0.2), gauge(TIME, 0.25), 0.2, 0.25, BAR)
    assert _error(w) < 1e-9
    assert w.time[-1] == pytest.approx(TIME[-1] - 0.2 / C, abs=1.5 * DT)  # b known to x_A / c before the end


def test_two_point_separation_between_samples_is_exact_to_the_interpolation():
    """A gauge spacing of a fraction of a sample's travel (10.48 samples): each step of the march
    interpolates linearly, and its errors add up over the record's 75 steps to 0.4 % of the peak."""
    w = separate_two_point(TIME, gauge(TIME, 0.2), gauge(TIME, 0.2524), 0.2, 0.2524, BAR)
    assert _error(w) < 1e-2


def test_two_point_separation_with_one_percent_noise_stays_within_its_bound():
    """1 % white noise on each gauge (sigma 1 % of the peak strain, 1 MHz sampling, 50 mm apart):
    marched raw, the noise at the failing frequencies n c / (2 dx) (n 50 kHz) piles up to some 35 %
    of the peak over the 1.6 ms record; low-passed at 0.8 of the first (40 kHz) the waves stay
    within 10 % of the peak (6 % the worst of 10 seeds)."""
    rng = np.random.default_rng(1)
    raw, filtered = [], []
    for _ in range(10):
        a = gauge(TIME, 0.2) + 0.01 * AMP * rng.standard_normal(TIME.size)
        b = gauge(TIME, 0.25) + 0.01 * AMP * rng.standard_normal(TIME.size)
        raw.append(_error(separate_two_point(TIME, a, b, 0.2, 0.25, BAR)))
        filtered.append(_error(separate_two_point(TIME, a, b, 0.2, 0.25, BAR, cutoff=0.8 * C / (2 * 0.05))))
    assert max(filtered) < 0.10
    assert min(raw) > 2 * max(filtered)


def test_a_leak_bounds_the_drift_of_an_offset():
    """An offset on one gauge is the pole at zero frequency: the exact march drifts by it every 2 tau
    (linearly), a leak lambda bounds the drift by offset / (1 - lambda) (the separation is linear:
    this is what the offset adds to any waves)."""
    offset = 1e-2 * AMP
    a, b = np.full(TIME.size, offset), np.zeros(TIME.size)
    exact = separate_two_point(TIME, a, b, 0.2, 0.25, BAR)
    leaky = separate_two_point(TIME, a, b, 0.2, 0.25, BAR, leak=0.9)
    assert np.abs(exact.toward[-1]) > 75 * offset  # 1600 us in 20 us steps of one offset each
    assert np.max(np.abs(leaky.toward)) <= offset / (1 - 0.9) * (1 + 1e-12)


def test_one_point_separation_of_pulses_apart():
    """A short incident pulse and its reflection apart at the gauge: each shifted to the end."""
    t = np.arange(0, 400) * DT
    short = lambda s: np.where((s > 120e-6) & (s < 160e-6), -AMP, 0.0)  # noqa: E731
    echo = lambda s: -0.5 * short(s - 5e-6)  # noqa: E731
    x = 0.2  # 40 us: the pulses pass the gauge at 80-120 us and 165-205 us
    strain = short(t + x / C) + echo(t - x / C)
    pulses = find_pulses(t, strain + 1e-6 * np.sin(3e5 * t))
    assert [p.sign for p in pulses] == [-1, 1]
    w = separate_one_point(t, strain, pulses[0], pulses[1], x, BAR)
    assert np.max(np.abs(w.toward - short(t))) < 1e-12 * AMP
    assert np.max(np.abs(w.away - echo(t))) < 1e-12 * AMP


def test_one_point_separation_refuses_overlapping_pulses():
    w1 = Window(10, 50, 10e-6, 49e-6, -1, -1.0)
    w2 = Window(40, 80, 40e-6, 79e-6, 1, 1.0)
    with pytest.raises(ValueError, match="overlap at the gauge.*two-point"):
        separate_one_point(TIME, np.zeros_like(TIME), w1, w2, 0.1, BAR)


def test_find_pulses_refuses_a_recording_with_no_pulse():
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match="no pulse in ch9"):
        find_pulses(TIME, rng.standard_normal(TIME.size), name="ch9")


def test_find_pulses_finds_the_foot_within_the_noise():
    """A trapezoid pulse in 1 % noise: its window starts within a few samples of the foot."""
    rng = np.random.default_rng(2)
    t = np.arange(2000) * 1e-8
    pulse = np.interp(t, [5e-6, 6e-6, 12e-6, 13e-6], [0.0, 1.0, 1.0, 0.0])
    (w,) = find_pulses(t, pulse + 0.01 * rng.standard_normal(t.size))
    assert abs(w.t_start - 5e-6) < 0.1e-6 and abs(w.t_stop - 13e-6) < 0.1e-6


@pytest.mark.parametrize("kwargs, match", [
    (dict(station_near=0.25, station_far=0.2), "station_far - station_near"),
    (dict(station_near=0.2, station_far=0.25, leak=1.5), "leak must lie"),
])
def test_two_point_refuses_bad_input(kwargs, match):
    a = gauge(TIME, 0.2)
    with pytest.raises(ValueError, match=match):
        separate_two_point(TIME, a, a, bar=BAR, **kwargs)


def test_two_point_refuses_a_channel_of_another_length():
    a = gauge(TIME, 0.2)
    with pytest.raises(ValueError, match="near and far must have"):
        separate_two_point(TIME, a, a[:-1], 0.2, 0.25, BAR)
