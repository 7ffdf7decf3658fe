"""What every layer shares, below all of them: argument checks (``validate``), the status enums
with their messages (``status``, re-exported as :class:`impactbar.Admissibility` and its kin),
results as tables (``tables``: pandas and xarray imported lazily) and BLAS on one thread
(``threads``). Private: the public names are re-exported by :mod:`impactbar`."""
