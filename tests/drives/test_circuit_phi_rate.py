"""The variational equations' rate ``Phi' = A Phi`` (``_bar.phi_rate``, in every variational flight's
right-hand side by CVODE): each entry the sum over its row's nonzeros of ``A``, from 0 in increasing
column, to the bit (a plain Python sum in that order), and ``A @ Phi`` to rounding; the state's and
the energies' components of ``yp`` not written."""

import numpy as np
import pytest

from impactbar.drives.circuit._bar import phi_rate


def _ordered(A, Phi):
    n = A.shape[0]
    out = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            s = 0.0
            for k in range(n):
                if A[i, k] != 0.0:
                    s += A[i, k] * Phi[k, j]
            out[i, j] = s
    return out


@pytest.mark.parametrize("n", [6, 10, 19])
def test_phi_rate_is_the_ordered_sum_over_the_nonzeros(n):
    rng = np.random.default_rng(n)
    A = rng.standard_normal((n, n)) * (rng.random((n, n)) < 0.4)
    A[0, :] = 0.0  # (a held pressure's row)
    A[1, 2] = -0.0
    off = n + 8
    y = rng.standard_normal(off + n * n)
    y[off + 5] = -0.0
    Phi = y[off:].reshape(n, n).T  # (stored by columns)
    yp = np.full(y.size, np.nan)
    phi_rate(A, y, yp, off)
    got = yp[off:].reshape(n, n).T
    assert np.isnan(yp[:off]).all()
    assert np.array_equal(got.view(np.int64), _ordered(A, Phi).view(np.int64))  # (signed zeros too)
    assert np.allclose(got, A @ Phi, rtol=1e-13, atol=1e-13 * np.abs(A).sum() * np.abs(Phi).max())
