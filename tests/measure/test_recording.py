"""Recordings in: the bridges' formula, the Tektronix CSV, arrays and frames, and bad input refused."""

import numpy as np
import pandas as pd
import pytest

from impactbar.measure import Bar, Gauge, Recording, read_tektronix_csv


@pytest.mark.parametrize("bridge, arms", [("quarter", 1.0), ("half", 2.0), ("half-poisson", 1.3),
                                          ("full", 4.0), ("full-poisson", 2.6)])
def test_strain_of_each_bridge(bridge, arms):
    """epsilon = 4 V / (G Vex GF n): a 1 mV bridge output (x 100 gain = 0.1 V), 5 V excitation, GF 2."""
    g = Gauge("bar", 0.1, bridge=bridge, gauge_factor=2.0, excitation=5.0, gain=100.0, poisson=0.3)
    assert g.strain(0.1) == pytest.approx(4 * 1e-3 / 5.0 / (2.0 * arms), rel=1e-14)


def test_the_half_bridge_is_hopp_py_bars_formula():
    """HopPyBar (LANL) converts its mini-bar's channels by strain = V (2 / GF) / (gain excitation)."""
    g = Gauge("incident", 0.10202, bridge="half", gauge_factor=2.1, excitation=10.0, gain=100.0)
    assert g.strain(-1.35) == pytest.approx(-1.35 * (2 / 2.1) / (100.0 * 10.0), rel=1e-14)
    assert Gauge("x", 0.0, polarity=-1).strain(1.0) == -Gauge("x", 0.0).strain(1.0)


def test_bar_wave_speed_and_impedance():
    bar = Bar(71.7e9, 2810.0, 2.11e-3 ** 2)
    assert bar.wave_speed == pytest.approx((71.7e9 / 2810.0) ** 0.5, rel=1e-15)
    assert bar.impedance == pytest.approx(2.11e-3 ** 2 * (71.7e9 * 2810.0) ** 0.5, rel=1e-14)


def test_read_a_tektronix_csv(tmp_path):
    """The format of the PMMA-13 channels: six header rows in columns 1-3, time and volts in 4 and 5."""
    header = ['"Record Length",8,"Points"', '"Sample Interval",8.0e-09,s', '"Trigger Point",2,"Samples"',
              '"Trigger Time",7.8e-09,s', '"",,', '"Horizontal Offset",-1.6e-08,s', ",,", ",,"]
    volts = [0.01, -0.02, 0.5, 1.0, 0.5, 0.0, -0.01, 0.02]
    rows = enumerate(zip(header, volts, strict=True))
    lines = [f"{h},{-1.6e-8 + 8e-9 * k:.8e},{v:.8e}" for k, (h, v) in rows]
    (tmp_path / "ch1.csv").write_text("\n".join(lines) + "\n")
    t, v = read_tektronix_csv(tmp_path / "ch1.csv")
    np.testing.assert_allclose(t, -1.6e-8 + 8e-9 * np.arange(8), rtol=0, atol=1e-20)
    np.testing.assert_array_equal(v, volts)
    rec = Recording.from_tektronix({"a": tmp_path / "ch1.csv", "b": tmp_path / "ch1.csv"})
    assert rec.dt == pytest.approx(8e-9) and sorted(rec.channels) == ["a", "b"]


def test_a_frame_and_arrays_give_one_recording():
    t = np.arange(16) * 1e-6
    frame = pd.DataFrame({"time": t, "ch1": np.sin(t * 1e5), "ch2": np.cos(t * 1e5)})
    a, b = Recording.from_frame(frame), Recording.from_arrays(t, ch1=np.sin(t * 1e5), ch2=np.cos(t * 1e5))
    assert a.channels.keys() == b.channels.keys()
    for k in a.channels:
        np.testing.assert_array_equal(a.channels[k], b.channels[k])


@pytest.mark.parametrize("channels, match", [
    (dict(ch1=np.zeros(15)), "channel 'ch1' has 15 samples where the time has 16"),
    (dict(ch1=np.r_[np.arange(7) * 1e-3, np.full(9, 2.5)]),
     "channel 'ch1' is saturated: it stays at"),
    (dict(ch1=np.r_[np.zeros(15), np.nan]), "not finite"),
    ({}, "at least one channel"),
])
def test_bad_channels_are_refused(channels, match):
    with pytest.raises(ValueError, match=match):
        Recording(np.arange(16) * 1e-6, channels)


def test_a_channel_at_full_scale_is_saturated():
    with pytest.raises(ValueError, match="reaches 5 V, the full scale 5 V"):
        Recording.from_arrays(np.arange(16) * 1e-6, full_scale=5.0, ch3=np.r_[np.zeros(15), 5.0])


@pytest.mark.parametrize("kwargs, match", [
    (dict(bridge="third"), "bridge must be one of"),
    (dict(station=-0.1), "station must be"),
    (dict(gauge_factor=0.0), "gauge_factor must be"),
    (dict(polarity=2), "polarity must be"),
])
def test_bad_gauges_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Gauge(**{"bar": "incident", "station": 0.1, **kwargs})


@pytest.mark.parametrize(("ratio", "offset"), [(2.0, 0.0), (1.5, 0.0), (0.5, 0.0), (1.0, 0.37)])
def test_channels_on_other_rates_and_starts_are_resampled_to_a_sinusoid(ratio, offset):
    """A sinusoid at 0.6 of the coarser channel's Nyquist frequency on a 1 us channel and on another of
    ``ratio`` us: resampled onto the finer channel's times by the polyphase filter, each within 2e-5
    of the closed form (the filter's: Kaiser beta 10); a channel starting ``offset`` us later, off
    the grid, by linear interpolation, within its error ``(w dt)^2 / 8`` (a sinusoid at 0.05 of the
    Nyquist frequency: 3.1e-3; nearest samples would miss it by 0.08)."""
    dt, other = 1e-6, ratio * 1e-6
    # (0.6 of the coarser Nyquist frequency; off the grid, 0.05: the linear interpolation's bound small)
    w = (0.6 if offset == 0.0 else 0.05) * np.pi / max(dt, other)
    t1 = np.arange(2000) * dt
    t2 = offset * dt + np.arange(int(2000 / ratio)) * other
    rec = Recording.from_channels({"a": (t1, np.sin(w * t1)), "b": (t2, np.sin(w * t2))})
    assert rec.dt == pytest.approx(min(dt, other), rel=1e-12)
    assert rec.time[0] >= max(t1[0], t2[0]) and rec.time[-1] <= min(t1[-1], t2[-1])
    assert rec.time.size > 0.9 * min(t1[-1], t2[-1]) / rec.dt  # (only the filter's ends left out)
    bound = 2e-5 + (w * dt) ** 2 / 8 * (offset != 0.0)
    for name in ("a", "b"):
        assert np.max(np.abs(rec.channels[name] - np.sin(w * rec.time))) < bound, name
