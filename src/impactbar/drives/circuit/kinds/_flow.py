"""What the kinds of :mod:`impactbar.drives.circuit.kinds` that pass a flow between two nodes share:
their first fields (the source and target nodes, the loss's energy slot), the fields of an orifice
whose opening is one piece of a piecewise linear function (a coefficient, the transition pressure
squared, the piece's intercept and slope), the smoothed turbulent orifice law every orifice of the
network passes oil by (:func:`phi`, :func:`dphi`: the kinds', the valve's and the preset's orifices),
and the numba options."""

import numba as nb

from ....dynamics.compiled import CACHE

SOURCE, TARGET, ENERGY = 1, 2, 3
#: an orifice opened by one piece ``intercept + slope x`` of a piecewise linear opening
COEFFICIENT, PTR2, INTERCEPT, SLOPE = range(4, 8)
PIECEWISE = {"source": SOURCE, "target": TARGET, "energy": ENERGY, "coefficient": COEFFICIENT, "ptr2": PTR2,
             "intercept": INTERCEPT, "slope": SLOPE}

JIT = dict(cache=CACHE, nogil=True, error_model="numpy")


@nb.njit(**JIT)
def phi(dp, ptr2):
    """The smoothed turbulent orifice law ``dp (dp^2 + p_tr^2)^(-1/4)`` (theory §11): ``sqrt(|dp|)``
    with the sign of ``dp`` far from 0, laminar (``dp / sqrt(p_tr)``) within the transition pressure
    ``p_tr`` (``ptr2`` its square)."""
    return dp * (dp * dp + ptr2) ** -0.25


@nb.njit(**JIT)
def dphi(dp, ptr2):
    """``phi'(dp)``, the derivative of :func:`phi` in the pressure drop."""
    s = dp * dp + ptr2
    return s ** -0.25 - 0.5 * dp * dp * s ** -1.25
