"""Jumps of the piston's fields at impact located from the modal coefficients (theory §4c):
:func:`locate_jumps` (Eckhoff's method) and the Bernoulli functions that carry them exactly
(:class:`impactbar.laws.wave._characteristics._LocatedPiston` builds the fields from them for the
force history)."""

from __future__ import annotations

import math

import numpy as np

from ..._shared.threads import single_threaded_blas

#: the closest two located jumps may lie, in units of 1/N (closer, a jump and its kink are not told
#: from two jumps: the fit degenerates)
GAP = 1.5
#: half the spacings and the centres' offsets, in units of 1/N, of the pairs of jumps tried beside
#: one jump (a narrow pulse: the best of this grid starts the fit)
PAIR = (0.8, 1.0, 1.2, 1.4)
PAIR_CENTRES = (-0.6, -0.3, 0.0, 0.3, 0.6)

# -- jumps located in the fields at impact (theory §4c) ------------------------------------------
# The piston's invariants unfold into one 2-periodic function of y in [-1, 1): W(y) = alpha0(y) for
# y >= 0 and W(y) = beta0(-y) for y < 0 (the free-free modes are its Fourier series,
# c_n = (a_n + i b_n)/2). A jump J of W at y_k, a jump K of W' and a jump L of W'' there are carried
# exactly by the periodic Bernoulli functions -J B1(t) - K B2(t) - (2 L/3) B3(t),
# t = ((y - y_k)/2) mod 1, whose coefficients are
# exp(-i n pi y_k) (J/(2 pi i n) - K/(2 pi^2 n^2) + i L/(2 pi^3 n^3)).


def _bernoulli(t, k):
    """The Bernoulli polynomial ``B_k(t)``, ``k = 1..4``, on ``0 <= t < 1``."""
    if k == 1:
        return t - 0.5
    if k == 2:
        return t * t - t + 1.0 / 6.0
    if k == 3:
        return t * (t - 0.5) * (t - 1.0)
    return t * t * (t - 1.0) ** 2 - 1.0 / 30.0


def _singular_coefficients(N: int, y, jumps) -> np.ndarray:
    """Complex coefficients ``c_n``, ``n = 1..N``, of the Bernoulli functions of ``jumps``
    (``(J, K, L)`` at the positions ``y``)."""
    n = np.arange(1, N + 1)
    z = np.exp(-1j * math.pi * np.outer(n, y))
    J, K, L = (np.asarray(u, dtype=float) for u in jumps)
    return ((z @ J) / (2j * math.pi * n) - (z @ K) / (2.0 * math.pi**2 * n**2)
            + 1j * (z @ L) / (2.0 * math.pi**3 * n**3))


def locate_jumps(a, b, scale: float, max_jumps: int = 16):
    """Jumps of the unfolded fields ``W(y)`` (and of ``W'`` there) located from their Fourier
    coefficients (Eckhoff's method: K. S. Eckhoff, Math. Comp. 64 (1995) 671-690; the candidates
    from a concentration sum, A. Gelb and E. Tadmor, Appl. Comput. Harmon. Anal. 7 (1999) 101-135).

    With ``h_n = 2 pi i n c_n``, jumps ``J`` of ``W`` and ``K`` of ``W'`` at ``y_k`` give
    ``h_n = sum_k exp(-i n pi y_k) (J_k - i K_k/(pi n)) + O(n^-2)``. The jumps are taken one at a
    time (matching pursuit): the largest peak of the concentration sum
    ``|sum sin(pi n/(N + 1)) r_n exp(i n pi y)|`` of what the jumps found so far leave unexplained
    (``r = h`` at first, so that a side lobe is never taken for a jump), after which all positions
    are fitted to ``h_n`` for ``N/4 <= n <= N`` by Levenberg-Marquardt on the variable projection
    (the sizes linear), with a jump of ``W'`` at ``y = 0`` always included (the drive end, whose
    jump of ``W`` the static correction carries). At each peak a pair of jumps about ``2/N`` apart
    (a narrow pulse: a release closely followed by a re-contact) is tried beside one jump, started
    from the best of a small grid of centres and spacings, and kept where it leaves less than half
    of what one jump leaves unexplained. A candidate is refused when it comes within
    ``0.75/N`` of another (two such jumps are not told apart), fits a jump larger than the fields'
    variation or below ``1e-3`` of the largest, or lowers the residual by less than 2 %. A jump is
    kept when the upper two thirds of the band give it within 10 %; the whole location is
    dropped (no jumps) when ``N < 32`` or when the jumps leave more than a quarter of ``h``
    unexplained (a smooth field, a truncated series that is the field itself, or jumps closer than
    about ``1/N``: the fields then stay the modal series, with their Gibbs overshoot).

    Parameters
    ----------
    a, b : numpy.ndarray, shape (N + 1,)
        Cosine coefficients of the velocity and sine coefficients of ``s u_x`` (:class:`PistonInvariants`,
        the static correction's tail already in ``b``).
    scale : float
        Size of the fields (a jump below ``1e-12 scale`` is none).
    max_jumps : int
        Most candidates.

    Returns
    -------
    y : numpy.ndarray, shape (k + 1,)
        Positions in ``[-1, 1)``; the last is the drive end ``y = 0``.
    jumps : tuple of numpy.ndarray, shape (k + 1,)
        ``(J, K, L)``, the jumps of ``W, W', W''`` (``J = 0`` at the drive end; ``L = 0``: the
        Bernoulli functions of :class:`_LocatedPiston` take it, the fit does not).
    """
    N = a.size - 1
    none = np.zeros(1), (np.zeros(1), np.zeros(1), np.zeros(1))
    if N < 32:  # too few coefficients to tell a jump from a smooth feature
        return none
    n = np.arange(1, N + 1)
    h = 1j * math.pi * n * (a[1:] + 1j * b[1:])
    w = np.sin(math.pi * n / (N + 1))
    M = 16 * N  # the concentration sum on y_j = -1 + 2 j/M, by one FFT
    yg = np.linspace(-1.0, 1.0, M, endpoint=False)
    sign = (-1.0) ** n

    def concentration(hr):
        cf = np.zeros(M, dtype=complex)
        cf[1:N + 1] = w * hr * sign
        return np.abs(np.fft.ifft(cf).real) * (M / float(np.sum(w)))

    lo = max(1, N // 4) - 1
    nn = n[lo:]
    rhs_c = h[lo:]
    rhs = np.concatenate((rhs_c.real, rhs_c.imag))
    inv = 1.0 / (math.pi * nn)

    def columns(yk, k_n):
        z = np.exp(-1j * math.pi * np.outer(k_n, np.append(yk, 0.0)))
        return z, np.concatenate((z[:, :-1], z * (-1j / (math.pi * k_n))[:, None]), axis=1)

    def fit(yk, start=0):
        z, m = columns(yk, nn[start:])
        m = np.concatenate((m.real, m.imag))
        Q, Rm = np.linalg.qr(m)
        b_ = np.concatenate((rhs_c[start:].real, rhs_c[start:].imag))
        coef = np.linalg.solve(Rm, Q.T @ b_)
        return coef, m @ coef - b_, z, Q

    def normal(yk):  # the variable projection's normal equations (Kaufman's Jacobian)
        coef, r, z, Q = fit(yk)
        k = yk.size
        d = (-1j * math.pi * nn)[:, None] * z[:, :k] * (coef[:k] - 1j * coef[k:2 * k] * inv[:, None])
        d = np.concatenate((d.real, d.imag))
        d -= Q @ (Q.T @ d)
        return d.T @ d, -(d.T @ r), float(r @ r)

    def min_gap(yk):  # the closest two jumps (two closer than about 1/N are not told apart)
        if yk.size < 2:
            return math.inf
        g = np.abs((yk[:, None] - yk[None, :] + 1.0) % 2.0 - 1.0)
        return float((g + 2.0 * np.eye(yk.size)).min())

    def refine(yk, iters):  # Levenberg-Marquardt on the positions, each within 1.5/N of its start
        y0, lam = yk.copy(), 1e-3
        for _ in range(iters if yk.size else 0):
            H, g, cost = normal(yk)
            dH = np.diag(H).copy()
            dH[dH <= 0.0] = 1.0
            for _ in range(20):
                dy = np.linalg.solve(H + lam * np.diag(dH), g)
                trial = np.clip(yk + dy, y0 - 1.5 / N, y0 + 1.5 / N)
                _, r_t, _, _ = fit(trial)
                if float(r_t @ r_t) <= cost and min_gap(trial) >= GAP / N:
                    lam = max(lam / 3.0, 1e-9)
                    break
                lam *= 4.0
            else:
                break
            yk = trial
            if np.max(np.abs(dy)) < 1e-10 / N:
                break
        return yk

    def strong(yk):  # the jumps that matter (a weak one has no position)
        coef, *_ = fit(yk)
        J = np.abs(coef[:yk.size])
        return yk[J >= max(1e-3 * (J.max() if J.size else 0.0), 1e-12 * scale)]

    def consistent(yk):  # the jumps that the upper two thirds of the band confirm (within 10 %)
        coef1, *_ = fit(yk)
        coef2, *_ = fit(yk, nn.size // 3)
        J1, J2 = coef1[:yk.size], coef2[:yk.size]
        return yk[np.abs(J1 - J2) <= 0.1 * np.abs(J1)]

    def _pair_start(yk, yc):  # the best pair on a small grid of centres and spacings about yc
        best_cost, best_pair = None, None
        for dc in PAIR_CENTRES:
            for p in PAIR:
                pair = [yc + (dc - p) / N, yc + (dc + p) / N]
                _, r, _, _ = fit(np.append(yk, pair))
                if best_cost is None or float(r @ r) < best_cost:
                    best_cost, best_pair = float(r @ r), pair
        return best_pair

    with single_threaded_blas():  # small dense problems
        # matching pursuit: the largest peak of the concentration sum of what the jumps found so
        # far leave unexplained (so that a side lobe is never taken for a jump), all refitted
        yk = np.empty(0)
        S = concentration(h)
        thr = max(1e-12 * scale, 2e-3 * float(S.max()))
        cap = 4.0 * float(S.max())  # no jump is larger than the fields' whole variation
        banned = np.zeros(M, dtype=bool)
        cost = float(rhs @ rhs)
        for _ in range(2 * max_jumps):
            if yk.size >= max_jumps:
                break
            near = np.abs((yg[:, None] - np.append(yk, 0.0) + 1.0) % 2.0 - 1.0).min(axis=1) < GAP / N
            i = int(np.argmax(np.where(near | banned, -1.0, S)))
            if S[i] < thr:
                break
            found, found_cost = None, None
            # one jump there, or a pair of jumps about 2/N apart (a narrow pulse, or a release
            # followed closely by a re-contact: its concentration sum is one blob), the pair where
            # it leaves less than half of what the one jump leaves unexplained
            for new in ([yg[i]], _pair_start(yk, yg[i])):
                trial = refine(np.append(yk, new), 12)
                coef, r = fit(trial)[:2]
                Jt = np.abs(coef[:trial.size])
                if not (min_gap(trial) < GAP / N or Jt.max() > cap or float(r @ r) > 0.98 * cost
                        or Jt[-len(new):].min() < 1e-3 * Jt.max()):
                    if found is None or float(r @ r) < 0.5 * found_cost:
                        found_cost = float(r @ r)
                        found = trial, found_cost, coef
            if found is None:
                banned |= np.abs((yg - yg[i] + 1.0) % 2.0 - 1.0) < 1.0 / N  # unresolved: not a jump
                continue
            yk, cost, coef = found
            _, cols = columns(yk, n)
            S = concentration(h - cols @ coef)
        yk = refine(yk, 40)
        yk = strong(consistent(yk))
        coef, r = fit(yk)[:2]
    if not np.all(np.isfinite(coef)) or np.linalg.norm(r) > 0.25 * np.linalg.norm(rhs):
        return none  # the jumps do not explain the coefficients: a smooth field, or too few modes
    k = yk.size
    y = (np.append(yk, 0.0) + 1.0) % 2.0 - 1.0
    return y, (np.append(coef[:k], 0.0), coef[k:], np.zeros(k + 1))
