"""A rod's two waves at an end against a linear spring (a rock's loading stiffness), in closed form."""

import numpy as np

C = 5000.0  # m/s
EA = 200e9 * 1e-3  # N
K = 4e8  # N/m, the spring at the end
T = 200e-6  # s, the incident half-sine's length (a pulse 1 m long: it overlaps its echo at the gauges)
AMP = 5e-4  # its strain amplitude (compressive)


def toward(t):
    """The incident wave at the end: a compressive half sine."""
    t = np.asarray(t, dtype=float)
    return np.where((t >= 0) & (t <= T), -AMP * np.sin(np.pi * np.clip(t, 0, T) / T), 0.0)


def _u(t):
    """The end's displacement: u' + beta u = -2 c a, u(0) = 0, with beta = k c / EA (exact)."""
    t = np.asarray(t, dtype=float)
    beta, w = K * C / EA, np.pi / T

    def integral(s):  # int_0^s exp(-beta (s - r)) sin(w r) dr
        return (beta * np.sin(w * s) - w * np.cos(w * s) + w * np.exp(-beta * s)) / (beta ** 2 + w ** 2)

    inside = integral(np.clip(t, 0, T))
    after = integral(T) * np.exp(-beta * np.clip(t - T, 0, None))
    return np.where(t < 0, 0.0, 2 * C * AMP * np.where(t <= T, inside, after))


def away(t):
    """The reflected wave at the end: F = k u with F = -EA (a + b)."""
    return -toward(t) - K * _u(t) / EA


def gauge(time, station):
    """The strain a gauge at ``station`` (m from the end) records (d'Alembert)."""
    return toward(time + station / C) + away(time - station / C)
