"""The first longitudinal mode of a round bar: its phase velocity against the original complex form
of the Pochhammer-Chree equation, Rayleigh's correction at long waves and the Rayleigh surface wave
at short ones; a wave carried along the bar and back is the wave, a long wave is merely delayed."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import jv

from impactbar.measure import Bar
from impactbar.measure.dispersion import _first_mode, disperse, phase_velocity

NU = 0.29


def _pochhammer(c, k, nu):
    """Graff's eq. 8.1.25, radius 1, c0 1, in complex arithmetic as written (alpha, beta imaginary
    where the wave is slower than the dilatational or the shear wave)."""
    c1 = math.sqrt((1 - nu) / ((1 + nu) * (1 - 2 * nu)))
    c2 = 1 / math.sqrt(2 * (1 + nu))
    w = c * k
    a = np.sqrt(complex(w * w / c1 ** 2 - k * k))
    b = np.sqrt(complex(w * w / c2 ** 2 - k * k))
    return (2 * a * (b * b + k * k) * jv(1, a) * jv(1, b) - (b * b - k * k) ** 2 * jv(0, a) * jv(1, b)
            - 4 * k * k * a * b * jv(1, a) * jv(0, b))


@pytest.mark.parametrize("k", [0.3, 1.0, 2.0, 3.5, 6.0])
@pytest.mark.parametrize("nu", [0.25, 0.29, 0.33])
def test_the_root_solves_the_complex_equation_and_changes_its_sign(k, nu):
    c = _first_mode(k, nu)
    at, lo, hi = (_pochhammer(x, k, nu) for x in (c, c * (1 - 1e-6), c * (1 + 1e-6)))
    part = np.real if abs(lo.real) > abs(lo.imag) else np.imag  # (the equation is real or imaginary)
    assert abs(at) < 1e-6 * max(abs(lo), abs(hi))
    assert part(lo) * part(hi) < 0
    # and no slower root: the first mode is the slowest (checked on the root's side of the shear
    # speed c2, where the equation keeps its real or imaginary form)
    c2 = 1 / math.sqrt(2 * (1 + nu))
    grid = np.linspace(0.3 if c < c2 else c2 * (1 + 1e-9), c * (1 - 1e-4), 400)
    values = np.array([part(_pochhammer(x, k, nu)) for x in grid])
    assert np.all(np.sign(values) == np.sign(values[0]))


def test_long_waves_follow_rayleighs_correction():
    """c / c0 = 1 - nu^2 (k a)^2 / 4 + O((k a)^4)."""
    for k in (0.01, 0.03, 0.1):
        err = _first_mode(k, NU) - (1 - NU ** 2 * k ** 2 / 4)
        assert abs(err) < 0.05 * NU ** 2 * k ** 4


def test_short_waves_tend_to_the_rayleigh_surface_wave():
    c1 = math.sqrt((1 - NU) / ((1 + NU) * (1 - 2 * NU)))
    c2 = 1 / math.sqrt(2 * (1 + NU))

    def rayleigh(c):
        x, y = c * c / c1 ** 2, c * c / c2 ** 2
        return (2 - y) ** 2 - 4 * math.sqrt(1 - x) * math.sqrt(1 - y)

    cr = brentq(rayleigh, 0.5 * c2, 0.999 * c2)
    gaps = [abs(_first_mode(k, NU) - cr) for k in (20.0, 40.0, 80.0)]
    assert gaps[2] < 2e-3 and gaps[0] > gaps[1] > gaps[2]


BAR = Bar(200e9, 7850.0, math.pi * 0.01 ** 2)


def test_phase_velocity_reads_the_table():
    f = np.array([0.0, 20e3, 80e3])
    c = phase_velocity(f, 0.01, BAR, NU)
    for fi, ci in zip(f[1:], c[1:], strict=True):  # k a = omega a / c
        assert _first_mode(2 * math.pi * fi * 0.01 / ci, NU) == pytest.approx(ci / BAR.wave_speed, abs=1e-6)
    assert c[0] == BAR.wave_speed


def test_a_wave_carried_there_and_back_is_the_wave():
    t = np.arange(4096) * 2e-7
    pulse = np.exp(-((t - 1e-4) / 4e-6) ** 2)
    there = disperse(t, pulse, 0.5, 0.01, BAR, NU)
    back = disperse(t, there, -0.5, 0.01, BAR, NU)
    assert np.max(np.abs(back - pulse)) < 1e-5  # (a tail of 1e-5 past the record's end is cut)
    assert np.max(np.abs(there - np.interp(t - 0.5 / BAR.wave_speed, t, pulse))) > 0.05  # (dispersed)


def test_a_long_wave_is_merely_delayed():
    """A pulse 400 us wide in a 2 mm bar (k a < 1e-3): the plain delay to 1e-6."""
    t = np.arange(8192) * 5e-7
    pulse = np.exp(-((t - 1.5e-3) / 4e-4) ** 2)
    moved = disperse(t, pulse, 1.0, 0.001, BAR, NU)
    assert np.max(np.abs(moved - np.exp(-((t - 1.5e-3 - 1.0 / BAR.wave_speed) / 4e-4) ** 2))) < 1e-6


@pytest.mark.parametrize(("args", "match"), [
    (([1e3], -0.01, BAR, NU), "radius"),
    (([1e3], 0.01, BAR, 0.5), "poisson"),
    (([-1.0], 0.01, BAR, NU), "frequency must be finite and >= 0"),
    (([1e6], 0.01, BAR, NU), r"f a / c0 must be at most 1"),
])
def test_phase_velocity_refuses_what_it_cannot_give(args, match):
    with pytest.raises(ValueError, match=match):
        phase_velocity(*args)


def test_disperse_refuses_uneven_times():
    t = np.array([0.0, 1.0, 3.0, 4.0])
    with pytest.raises(ValueError, match="equally spaced"):
        disperse(t, np.zeros(4), 0.1, 0.01, BAR, NU)
