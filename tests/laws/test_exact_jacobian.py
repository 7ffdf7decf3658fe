"""The exact blow map's Jacobian (theory §4d, "the exact blow's Jacobian"): tangent runs of
the exact solver against central differences of the exact blows themselves.

Central differences of the map (steps ``h`` and ``h/2`` in each state component and the impact time,
Richardson-extrapolated: truncation ``O(h^4)``) are an independent estimate of the Jacobian: they
only run the primal solver. The cases were drawn to hold every mechanism of the tangent: re-contacts
(their moving steps carried as impulses), separations and unloadings that such a step sets off,
a bit with mass, a feed, stepped pistons and rods, and the drive's jumps under a square wave (the
impact time's column)."""

import numpy as np
import pytest

import impactbar as ib
from impactbar.laws.rodrock import exactjac as EJ
from impactbar.laws.rodrock.exactmap import ExactBlowMap, initial_waves
from impactbar.laws.rodrock.step import blow_map, map_with_jacobians


def _richardson(bmap, y, t, h):
    """The map's Jacobians by central differences, steps ``h`` and ``h/2`` extrapolated."""

    def column(e, step):
        return (bmap(y + step * e) - bmap(y - step * e)) / (2.0 * step)

    def time_column(step):
        up, down = bmap.shifted([t + step, t - step])
        return (up(y) - down(y)) / (2.0 * step)

    jac = np.empty((y.size, y.size))
    for j in range(y.size):
        e = np.zeros(y.size)
        e[j] = 1.0
        jac[:, j] = (4.0 * column(e, h / 2) - column(e, h)) / 3.0
    return jac, (4.0 * time_column(h / 2) - time_column(h)) / 3.0


def _distance(bmap, y, t, jac, jac_t):
    """The relative distance of ``(jac, jac_t)`` from the central differences, the least over steps
    of ``1e-5`` and ``1e-6`` of the state (a near-grazing re-contact bends the map within ``1e-5``,
    where the differences' truncation is ``1e-7``; measured, the tangent agrees with one of them to
    ``4e-10`` or better)."""
    out = []
    for h in (1e-5, 1e-6):
        ref, ref_t = _richardson(bmap, y, t, h * max(1.0, float(np.max(np.abs(y)))))
        size = float(np.max(np.abs(ref)))
        out.append(max(float(np.max(np.abs(jac - ref))), float(np.max(np.abs(jac_t - ref_t)))) / size)
    return min(out)


#: (s, modes, rod segments (length, impedance), k, k_u, bit mass, feed, piston's head area or None,
#: load): drawn at random, each holding the mechanisms named
CASES = {
    "no re-contact": (9.993, 2, [(2.077, 1.482), (0.929, 0.513)], 7.976, 38.241, 0.0, 0.0, None, "cosine"),
    "a re-contact, stepped piston": (2.148, 2, [(2.235, 0.535)], 13.744, 121.728, 0.0, 0.0, 2.244,
                                     "fourier"),
    "separations set off by moving steps": (5.21, 2, [(1.869, 1.686), (2.37, 2.483)], 14.612, 121.54,
                                            0.0, 0.0, 2.195, "cosine"),
    "bit mass, the drive's jump": (9.425, 1, [(0.534, 2.215), (0.913, 1.339)], 1.617, 1.979, 0.2, 0.0,
                                   None, "square"),
    "feed, re-contacts, the drive's jump": (4.195, 1, [(0.444, 0.804)], 13.72, 77.032, 0.0, 0.1, None,
                                            "square"),
    "an unloading set off by a moving step": (3.951, 0, [(1.434, 0.544)], 11.966, 33.565, 0.0, 0.0,
                                              1.676, "cosine"),
    "both set off, square wave": (6.176, 0, [(2.493, 2.285), (2.057, 1.098)], 11.871, 75.356, 0.0, 0.0,
                                  1.542, "square"),
}
LOADS = {"cosine": ib.CosineLoad(0.3, 1.0), "square": ib.SquareWaveLoad(0.3, 1.0),
         "fourier": ib.FourierLoad(0.3, [1.0, 0.0, 0.3j])}


def _model(s, n, segs, k, k_u, m, feed, area):
    law = ib.RodRock(segments=[ib.RodSegment(length=a, impedance=b) for a, b in segs],
                     rock=ib.BilinearRock(k=k, k_u=k_u), bit_mass=m, feed=feed)
    piston = None if area is None else ib.SteppedPiston([0.6, 0.4], [1.0, area])
    return ib.BarModel(s=s, d=0.2, R=0.0, n_modes=n, impact=law, piston=piston)


def _mechanisms(bmap, y):
    """What the tangent runs of one blow met: re-contacts, separations and unloadings a moving step
    set off, the drive's jumps."""
    n = bmap.basis.omega.size
    q = y[:n].copy()
    q[0] -= float(bmap.basis.end_weights @ q)
    ws, scale = EJ._primal(bmap, q, y[n:].copy())
    RD = ws[22]
    codes = [int(RD[i, 1].real) for i in range(1, int(RD[0, 0].real) + 1)]
    directions = np.eye(2 * n)[1:]
    _, _, set_off = EJ.tangents(bmap, ws, scale, initial_waves(bmap.basis, directions[:, :n],
                                                                directions[:, n:], np.zeros(2 * n - 1)))
    return {"re-contact": codes.count(2) > 0, "separation set off": bool(set_off[:, 0].any()),
            "unloading set off": bool(set_off[:, 1].any()), "drive jump": bool(EJ._time_direction(bmap)[1])}


@pytest.mark.parametrize("name", list(CASES))
def test_the_tangent_runs_are_the_central_differences_of_the_blows(name):
    *params, load_name = CASES[name]
    model = _model(*params)
    load = LOADS[load_name]
    n = model.n_modes
    run = ib.simulate(model, load, ib.InitialState.rigid(-0.1, 0.0, n_modes=n), 60.0)
    seen = dict.fromkeys(("re-contact", "separation set off", "unloading set off", "drive jump"), False)
    checked = 0
    for imp in run.impacts[-4:]:
        y = np.concatenate((imp.q_before, imp.v_before))
        bmap = blow_map(model, load, imp.t0)
        assert isinstance(bmap, ExactBlowMap)
        out = EJ.exact_impact_map(bmap, y, imp.t0)
        assert out is not None
        y_plus, jac, jac_t = out
        np.testing.assert_array_equal(y_plus, bmap(y))  # the primal is the map's own blow
        assert _distance(bmap, y, imp.t0, jac, jac_t) <= 2e-8
        for key, value in _mechanisms(bmap, y).items():
            seen[key] |= value
        checked += 1
    assert checked == min(4, len(run.impacts)) >= 2
    wanted = {"no re-contact": (), "a re-contact, stepped piston": ("re-contact",),
              "separations set off by moving steps": ("re-contact", "separation set off"),
              "bit mass, the drive's jump": ("drive jump",),
              "feed, re-contacts, the drive's jump": ("re-contact", "separation set off", "drive jump"),
              "an unloading set off by a moving step": ("re-contact", "unloading set off"),
              "both set off, square wave": ("re-contact", "separation set off", "unloading set off")}
    assert all(seen[w] for w in wanted[name]), seen


def test_the_tangent_along_the_blows_own_data_is_the_blow():
    """Without a feed the blow is homogeneous of degree one in its data (the piston's waves and the
    drive) with its switches in place: the tangent run along the data itself is the map's value, to
    rounding (every switch, re-contacts included, stays where it was)."""
    model = _model(*CASES["separations set off by moving steps"][:-1])
    load = LOADS["cosine"]
    run = ib.simulate(model, load, ib.InitialState.rigid(-0.1, 0.0, n_modes=2), 60.0)
    for imp in run.impacts[-3:]:
        bmap = blow_map(model, load, imp.t0)
        n = model.n_modes + 1
        q, v = imp.q_before.copy(), imp.v_before.copy()
        q[0] -= float(bmap.basis.end_weights @ q)
        ws, scale = EJ._primal(bmap, q, v)
        qa, va, on_stop = bmap.after_run(ws, scale)
        starts, pieces = bmap.drive
        drive = (starts, [(e, d, c[None]) for e, d, c in pieces])
        dq, dv, _ = EJ.tangents(bmap, ws, scale, initial_waves(bmap.basis, q[None], v[None],
                                                               np.array([bmap.p_end])), drive, None, on_stop)
        dq, dv = dq[0], dv[0]
        size = float(np.max(np.abs(np.concatenate((qa, va)))))
        np.testing.assert_allclose(np.concatenate((dq, dv)), np.concatenate((qa, va)), rtol=0.0,
                                   atol=1e-12 * size)
        assert n == qa.size


def test_the_wave_laws_stepped_piston_takes_the_exact_jacobian():
    """The wave law's stepped piston (its blows exact on a semi-infinite rod): the same tangent runs,
    against central differences."""
    model = ib.BarModel(s=5.0, d=0.1, R=0.5, n_modes=2, impact="wave",
                        piston=ib.SteppedPiston([0.6, 0.4], [1.0, 1.8]))
    load = LOADS["cosine"]
    run = ib.simulate(model, load, ib.InitialState.rigid(-0.1, 0.0, n_modes=2), 40.0)
    law = model.law
    imp = run.impacts[-1]
    y = np.concatenate((imp.q_before, imp.v_before))
    bmap = law._map(model, load, imp.t0)
    y_plus, jac, jac_t = law.impact_map(model, load, imp.t0, y)
    np.testing.assert_array_equal(y_plus, bmap(y))
    assert _distance(bmap, y, imp.t0, jac, jac_t) <= 2e-8


def test_a_map_without_a_derivative_falls_back_on_central_differences(monkeypatch):
    """Where the tangent cannot be had (a re-contact at zero closing speed), the map's Jacobians are
    central differences of the blows, as before."""
    *params, load_name = CASES["no re-contact"]
    model = _model(*params)
    load = LOADS[load_name]
    run = ib.simulate(model, load, ib.InitialState.rigid(-0.1, 0.0, n_modes=2), 60.0)
    imp = run.impacts[-1]
    y = np.concatenate((imp.q_before, imp.v_before))
    exact = model.law.impact_map(model, load, imp.t0, y)
    monkeypatch.setattr(EJ, "exact_impact_map", lambda *a: None)
    fd = map_with_jacobians(blow_map(model, load, imp.t0), y, imp.t0)
    np.testing.assert_array_equal(fd[0], exact[0])
    np.testing.assert_allclose(fd[1], exact[1], rtol=0.0, atol=1e-6 * float(np.max(np.abs(exact[1]))))
    assert not np.array_equal(fd[1], exact[1])  # (they are two computations)
