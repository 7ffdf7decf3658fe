r"""Probe: the oil circuit's fundamental matrix ``Phi`` over a flight from the PLAIN flight's steps by a
fourth-order Magnus integrator, against CVODE's variational flight (``Phi`` in the 514-unknown BDF).

On each step ``[t_k, t_k + h]`` of a plain flight (``circuit_flight(variational=False)``: its steps
``t``, states ``y`` and rates ``f``, cubic Hermite between them) the circuit's Jacobian ``A`` is taken
at the two Gauss-Legendre points ``t_k + (1/2 -+ sqrt(3)/6) h`` from the Hermite-interpolated state (the
generated ``jac_base`` of the drive's network, the one the variational flight calls), and

.. math:: \Omega_k = \tfrac h2 (A_1 + A_2) + \tfrac{\sqrt 3 h^2}{12} [A_2, A_1], \qquad
          \Phi_{k+1} = e^{\Omega_k} \Phi_k

(Magnus of order 4), ``expm`` the library's (``_magnus.expm``, Higham 2005: Pade 3, 5, 7, 9 or 13
with scaling and squaring), each ``Omega`` in the coordinates that balance ``A``
(``scipy.linalg.matrix_balance`` once a flight: the modes' ``q' = v, v' = -w^2 q`` make ``||h A||``
some 275 at the plain steps, balanced 0.2).
``--sub S`` splits each plain step in ``S`` equal Magnus steps (``--sub 0.25``: one Magnus step over
four plain steps); ``--sub aTHETA`` takes Magnus' own steps, ``h ||D^-1 A D||_1 = THETA``. The period's
table has the unbalanced Magnus on the plain steps too.

Two comparisons on the preset ``circuit-drifter``'s orbit (rigid, 4 and 8 modes):

* per flight (each smooth piece of the period, between two events, the same start state): ``Phi`` of
  (a) CVODE's variational flight at the drive's ``rtol = 1e-10`` (``sensitivity="cvode"`` of its
  settings), (lib) the library's own (the drive's default: Magnus of order 6 over a plain flight at
  a thousand times the drive's tolerance, :mod:`impactbar.drives.circuit._magnus`), (b) the same
  plain flight + this probe's Magnus of order 4 on the steps asked for, each against a reference
  variational flight of CVODE at ``rtol = 1e-12``; CPU time of each;
* per period: the orbit's multipliers (the problem's own composition across the events and the blow,
  ``ShootingProblem._fly(..., variational=True)``, saltation matrices included) with each flight's
  ``Phi`` from (a), (lib), (b) and the reference.

Run: ``python benchmarks/probes/monodromy_magnus.py --modes 8 4 --sub 1 0.25 a0.5 a1 --rounds 1``
(some 15 minutes on the 2-core machine, most of it the reference flights; numbers in
``benchmarks/HISTORY.md``). Library behaviour is not changed: the Magnus flight is swapped in for
``circuit_flight`` (and ``_MAX_STEPS`` raised for the reference) inside this process only.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time

import numba as nb
import numpy as np

from impactbar.drives.circuit._magnus import expm, unscale  # (the library's, since it takes Phi so)


@nb.njit(cache=True)
def _hermite(y0, f0, y1, f1, h, s, out):
    """The cubic Hermite interpolant at ``t_k + s h`` into ``out``."""
    s2 = s * s
    s3 = s2 * s
    a0 = 2.0 * s3 - 3.0 * s2 + 1.0
    b0 = (s3 - 2.0 * s2 + s) * h
    a1 = -2.0 * s3 + 3.0 * s2
    b1 = (s3 - s2) * h
    for i in range(out.size):
        out[i] = a0 * y0[i] + b0 * f0[i] + a1 * y1[i] + b1 * f1[i]


@nb.njit(cache=True)
def _state_at(t, y, f, tau, k, out):
    """The Hermite interpolant at ``tau`` (in ``[t[k], t[k + 1]]``) into ``out``."""
    h = t[k + 1] - t[k]
    _hermite(y[k], f[k], y[k + 1], f[k + 1], h, (tau - t[k]) / h, out)


@nb.njit(cache=True)
def _step(t, y, f, par, M, t0, hs, k, jac_base, d, A1, A2, ys):
    """``exp(D^-1 Omega D)`` of the Magnus step ``[t0, t0 + hs]`` (``A`` at its Gauss points into ``A1``,
    ``A2``) and the integrator's step ``k`` that holds its second Gauss point (searched from ``k``)."""
    c1 = 0.5 - math.sqrt(3.0) / 6.0
    for c, A in ((c1, A1), (1.0 - c1, A2)):
        tau = t0 + c * hs
        while k < t.size - 2 and t[k + 1] < tau:
            k += 1
        _state_at(t, y, f, tau, k, ys)
        jac_base(ys, par, M, A)
    Om = 0.5 * hs * (A1 + A2) + (math.sqrt(3.0) / 12.0 * hs * hs) * (A2 @ A1 - A1 @ A2)
    n = Om.shape[0]
    for i in range(n):
        for j in range(n):
            Om[i, j] *= d[j] / d[i]
    return expm(Om), k


@nb.njit(cache=True)
def magnus_phi(t, y, f, par, M, n, grid, jac_base, d):
    """``Phi`` over the Magnus steps ``grid`` (times within ``[t[0], t[-1]]``, ``t``'s first and last
    included) by Magnus of order 4, ``A`` at the Gauss points from the Hermite interpolant of the
    integrator's steps ``t`` (states ``y``, rates ``f``); each ``Omega`` taken in the coordinates
    scaled by ``d`` (``D^-1 Omega D``, ``D = diag(d)``, powers of 2: exact), where its norm is small
    (the modes' ``q' = v, v' = -w^2 q`` unscaled make it large: Pade 13 and squarings)."""
    Phi = np.eye(n)
    A1 = np.empty((n, n))
    A2 = np.empty((n, n))
    ys = np.empty(y.shape[1])
    k = 0
    for m in range(grid.size - 1):
        E, k = _step(t, y, f, par, M, grid[m], grid[m + 1] - grid[m], k, jac_base, d, A1, A2, ys)
        Phi = E @ Phi
    return unscale(Phi, d)


@nb.njit(cache=True)
def magnus_phi_adaptive(t, y, f, par, M, n, theta, jac_base, d):
    """:func:`magnus_phi` on its own steps: each as long as ``theta / ||D^-1 A D||_1`` (``A`` at the
    previous step's second Gauss point, the first step's at ``t[0]``), the piece's end the last; the
    count of steps with it."""
    Phi = np.eye(n)
    A1 = np.empty((n, n))
    A2 = np.empty((n, n))
    ys = np.empty(y.shape[1])
    jac_base(y[0], par, M, A2)
    t0, tend, k, steps = t[0], t[-1], 0, 0
    while t0 < tend:
        nrm = 0.0
        for j in range(n):
            s = 0.0
            for i in range(n):
                s += abs(A2[i, j]) * d[j] / d[i]
            nrm = max(nrm, s)
        hs = theta / nrm if nrm > 0.0 else tend - t0
        last = t0 + 1.25 * hs >= tend
        if last:
            hs = tend - t0
        E, k = _step(t, y, f, par, M, t0, hs, k, jac_base, d, A1, A2, ys)
        Phi = E @ Phi
        t0 = tend if last else t0 + hs
        steps += 1
    return unscale(Phi, d), steps


def magnus_grid(t, sub):
    """The Magnus steps: each integrator step split in ``sub`` (an integer >= 1), or with ``sub = 1/G``
    (``G`` an integer) every ``G`` integrator steps taken as one (the last step the remainder)."""
    if sub >= 1:
        s = int(round(sub))
        return np.concatenate((t[0] + 0.0 * t[:1],
                               (t[:-1, None] + np.diff(t)[:, None] * (np.arange(1, s + 1) / s)).ravel()))
    G = int(round(1.0 / sub))
    g = t[::G]
    return g if g[-1] == t[-1] else np.append(g, t[-1])


def piece_phi(drive, model, mode, piece, sub=1, balance=True):
    """``Phi`` over a plain flight's ``piece`` (a ``CircuitPiece``) by :func:`magnus_phi` on
    :func:`magnus_grid`'s steps; with ``balance`` in the coordinates that balance ``A`` at the piece's
    middle step (``scipy.linalg.matrix_balance``, no permutation), else unscaled."""
    M = piece.M
    n = piece.layout.size(M)
    net, code = drive._compiled_network(mode)
    par = np.concatenate((drive._par(model, mode, False), net))
    d = np.ones(n)
    if balance:
        from scipy.linalg import matrix_balance

        A = np.empty((n, n))
        code.jac_base(np.ascontiguousarray(piece.y[piece.t.size // 2]), par, M, A)
        d = matrix_balance(A, permute=False, separate=True)[1][0]
    f = np.ascontiguousarray(piece.f)
    if isinstance(sub, str):  # "a<theta>": the adaptive steps
        return magnus_phi_adaptive(piece.t, piece.y, f, par, M, n, float(sub[1:]), code.jac_base, d)[0]
    return magnus_phi(piece.t, piece.y, f, par, M, n, magnus_grid(piece.t, float(sub)), code.jac_base, d)


def cpu_best(fn, rounds=3):
    best, out = math.inf, None
    for _ in range(rounds):
        t0 = time.process_time()
        out = fn()
        best = min(best, time.process_time() - t0)
    return best, out


def matched(mu, ref):
    """The largest ``|mu_i - ref_j|`` over the best one-to-one matching."""
    from scipy.optimize import linear_sum_assignment

    C = np.abs(np.asarray(mu)[:, None] - np.asarray(ref)[None, :])
    r, c = linear_sum_assignment(C)
    return float(C[r, c].max()), r, c


def rel(P, R) -> float:
    return float(np.max(np.abs(P - R)) / np.max(np.abs(R)))


def eig_err(P, R) -> float:
    """The eigenvalues' largest error over the best matching, relative to the largest modulus."""
    e, r = np.linalg.eigvals(P), np.linalg.eigvals(R)
    return matched(e, r)[0] / float(np.max(np.abs(r)))


def multipliers(problem, X, D):
    """The orbit's multipliers from a period's Jacobian ``D`` (as ``ShootingProblem.orbit``)."""
    from impactbar.drives.orbitproblem import sorted_multipliers

    n, M = problem.n, problem.M
    a = np.concatenate((problem.model.end_weights, np.zeros(M + problem.k)))
    Q, _ = np.linalg.qr(np.column_stack((a / np.linalg.norm(a), np.eye(n))))
    B = Q[:, 1:n]
    return sorted_multipliers(np.linalg.eigvals(B.T @ D @ B))


def case(modes, subs, rounds):
    import impactbar.drives.circuit.flight as FM
    from impactbar import find_orbit
    from impactbar.drives.base import FlightSettings
    from impactbar.drives.circuit.settings import circuit_settings
    from impactbar.physical import circuit_preset

    d = circuit_preset("circuit-drifter")
    drive, model = d.drive(), d.model().with_(n_modes=modes)
    t0 = time.process_time()
    orbit = find_orbit(model, drive)
    print(f"\n== {modes} modes: find_orbit {time.process_time() - t0:.1f} s CPU, period {orbit.period:.6f}")
    problem, X = orbit._problem, np.asarray(orbit._unknowns, dtype=float)
    assert problem.impacts == 1
    tau, mode0 = problem.blocks[0]
    ref_set = FlightSettings(method="CVODE", rtol=1e-12, atol=1e-14)
    FM._MAX_STEPS = 2_000_000  # (this process only: the 8-mode reference flights need more than 200,000)
    orig = FM.circuit_flight
    starts = []
    sub_now = [1, True]  # (Magnus steps a plain step, balanced)

    def cvode_flight(drive, model, state, t, q, v, t_stop, settings=None, variational=False, **kw):
        # (CVODE's variational flights: the settings' default is Magnus)
        settings = dataclasses.replace(circuit_settings(settings), sensitivity="cvode")
        return orig(drive, model, state, t, q, v, t_stop, settings, variational, **kw)

    def magnus_flight(drive, model, state, t, q, v, t_stop, settings=None, variational=False, **kw):
        if variational:
            starts.append((state, t, np.array(q), np.array(v), t_stop))
        # (the state of the library's Magnus flights: a thousand times the drive's tolerance)
        fl = orig(drive, model, state, t, q, v, t_stop, drive.variational_state_settings(model, settings),
                  False, **kw)
        if not variational:
            return fl
        return fl._replace(sensitivity=piece_phi(drive, model, state.mode, fl.piece, *sub_now))

    def period(settings=None, magnus=None, balance=True, cvode=False):
        problem._last = None
        if magnus is not None:
            sub_now[:] = magnus, balance
            FM.circuit_flight = magnus_flight
        elif cvode:
            FM.circuit_flight = cvode_flight
        try:
            return problem._fly(tau, mode0, X[:problem.n], False, True, settings)[6]
        finally:
            FM.circuit_flight = orig

    # -- per period: the multipliers --------------------------------------------------------------
    D_ref = period(ref_set, cvode=True)
    mu_ref = multipliers(problem, X, D_ref)
    ta, D_a = cpu_best(lambda: period(cvode=True), 1)
    mu_a = multipliers(problem, X, D_a)
    tl, D_l = cpu_best(lambda: period(), 1)
    rows = [("CVODE variational rtol 1e-10", ta, D_a, mu_a),
            ("the library's Magnus (default)", tl, D_l, multipliers(problem, X, D_l))]
    for s, bal in [(1.0, False)] + [(s, True) for s in subs]:
        period(magnus=s, balance=bal)  # (compile)
        starts.clear()
        tb, D_b = cpu_best(lambda s=s, bal=bal: period(magnus=s, balance=bal), 1)
        rows.append((f"plain + Magnus-4, sub {s}" + ("" if bal else " unbal."), tb, D_b,
                     multipliers(problem, X, D_b)))
    print(f"period: |mu| largest (ref) {np.abs(mu_ref[:3])}")
    print(f"{'period Jacobian by':32s} {'CPU s':>8s} {'D rel err':>10s} {'mu abs err':>11s}")
    for name, tt, D, mu in rows:
        print(f"{name:32s} {tt:8.3f} {rel(D, D_ref):10.2e} {matched(mu, mu_ref)[0]:11.2e}")
    # -- per piece ----------------------------------------------------------------------------------
    seen = list(starts)  # (the flights of the last Magnus period)
    print(f"pieces of the period: {len(seen)}")
    print(f"{'piece':>5s} {'steps a/plain/ref':>22s} {'a: CPU ms':>10s} {'a: rel':>9s} {'a: eig':>9s}"
          f" {'lib: CPU ms':>11s} {'lib: rel':>9s} {'lib: eig':>9s}"
          + "".join(f" {f'b{s}: CPU ms':>11s} {f'b{s}: rel':>9s} {f'b{s}: eig':>9s}" for s in subs))
    totals = np.zeros(2 + len(subs))
    state_set = drive.variational_state_settings(model)
    for i, start in enumerate(seen):
        state, t, q, v, t_stop = start
        fr = cvode_flight(drive, model, *start, ref_set, True)
        ta, fa = cpu_best(lambda start=start: cvode_flight(drive, model, *start, None, True), rounds)
        tl, fl = cpu_best(lambda start=start: orig(drive, model, *start, None, True), rounds)
        fp = orig(drive, model, *start, None, False)
        line = f"{i:5d} {fa.piece.t.size - 1:7d}/{fp.piece.t.size - 1:6d}/{fr.piece.t.size - 1:7d} " \
               f"{1e3 * ta:10.2f} {rel(fa.sensitivity, fr.sensitivity):9.1e} " \
               f"{eig_err(fa.sensitivity, fr.sensitivity):9.1e}"
        line += f" {1e3 * tl:11.2f} {rel(fl.sensitivity, fr.sensitivity):9.1e} " \
                f"{eig_err(fl.sensitivity, fr.sensitivity):9.1e}"
        totals[:2] += ta, tl
        for j, s in enumerate(subs):
            tb, Pb = cpu_best(lambda s=s, start=start: piece_phi(
                drive, model, start[0].mode, orig(drive, model, *start, state_set, False).piece, s), rounds)
            totals[2 + j] += tb
            line += f" {1e3 * tb:11.2f} {rel(Pb, fr.sensitivity):9.1e} {eig_err(Pb, fr.sensitivity):9.1e}"
        print(line + f"   (t {fr.t - t:.3e}, ends {fa.end})")
    print("sum of the pieces' CPU (s): a " + f"{totals[0]:.3f}, lib {totals[1]:.3f}"
          + "".join(f", b sub {s} {totals[2 + j]:.3f}" for j, s in enumerate(subs)))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--modes", type=int, nargs="+", default=[0, 4, 8])
    p.add_argument("--sub", nargs="+", default=["1", "0.5", "a0.5"],
                   help="Magnus steps a plain step (0.5: one Magnus step per two plain steps); aTHETA: "
                        "Magnus' own steps, each h ||D^-1 A D||_1 = THETA")
    p.add_argument("--rounds", type=int, default=3, help="best of ROUNDS for each piece's CPU time")
    args = p.parse_args(argv)
    for m in args.modes:
        case(m, [x if x.startswith("a") else float(x) for x in args.sub], args.rounds)


if __name__ == "__main__":
    main()
