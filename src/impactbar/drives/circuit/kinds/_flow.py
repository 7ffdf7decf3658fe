"""What the kinds of :mod:`impactbar.drives.circuit.kinds` that pass a flow between two nodes share:
their first fields (the source and target nodes, the loss's energy slot), the fields of an orifice
whose opening is one piece of a piecewise linear function (a coefficient, the transition pressure
squared, the piece's intercept and slope), and the numba options."""

from ....dynamics.compiled import CACHE

SOURCE, TARGET, ENERGY = 1, 2, 3
#: an orifice opened by one piece ``intercept + slope x`` of a piecewise linear opening
COEFFICIENT, PTR2, INTERCEPT, SLOPE = range(4, 8)
PIECEWISE = {"source": SOURCE, "target": TARGET, "energy": ENERGY, "coefficient": COEFFICIENT, "ptr2": PTR2,
             "intercept": INTERCEPT, "slope": SLOPE}

JIT = dict(cache=CACHE, nogil=True, error_model="numpy")
