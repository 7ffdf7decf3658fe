"""Results as tables (private): what the ``to_dataframe()`` / ``to_xarray()`` methods share.

pandas is a dependency of impactbar, imported here only, inside the functions (the result objects'
table views call them); xarray is optional (extra ``data``) and is reached only through
:meth:`pandas.DataFrame.to_xarray`, so the core never imports it. Every column carries a
``long_name`` and ``units`` (``"1"`` for dimensionless numbers, the CF convention), set on the
xarray variables and kept in ``DataFrame.attrs["columns"]``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

__all__ = ["frame", "to_xarray", "XARRAY_HINT"]

#: the one-line hint when xarray is missing
XARRAY_HINT = "to_xarray() needs xarray, which is not installed: pip install 'impactbar[data]'"


def frame(columns: Mapping[str, Sequence], meta: Mapping[str, tuple[str, str]], *,
          index: str | list[str], attrs: Mapping | None = None):
    """A :class:`pandas.DataFrame` with the columns ``columns`` and an index named ``index``.

    Parameters
    ----------
    columns : mapping of str to sequence
        Column name -> values, all of one length; the column named ``index`` becomes the index
        (or, when absent, a range index of that name); a list of names makes a multi-index.
    meta : mapping of str to (str, str)
        Column name -> ``(long_name, units)``; kept in ``DataFrame.attrs["columns"]``.
    attrs : mapping, optional
        More ``DataFrame.attrs`` (the model, the load, ...): plain strings and numbers.
    """
    import pandas as pd

    df = pd.DataFrame(dict(columns))
    if isinstance(index, list) or index in df.columns:
        df = df.set_index(index)
    else:
        df.index.name = index
    df.attrs.update(attrs or {})
    df.attrs["columns"] = {k: {"long_name": long_name, "units": units}
                           for k, (long_name, units) in meta.items()}
    return df


def to_xarray(df):
    """``df.to_xarray()`` with ``long_name`` and ``units`` on every variable and coordinate and the
    frame's other attrs on the dataset.

    Raises
    ------
    ModuleNotFoundError
        xarray is not installed (the message names the extra).
    """
    try:
        ds = df.to_xarray()
    except ImportError as exc:  # pandas' own message names no extra
        raise ModuleNotFoundError(XARRAY_HINT, name="xarray") from exc
    cols = df.attrs.get("columns", {})
    for name in list(ds.data_vars) + list(ds.coords):
        if name in cols:
            ds[name].attrs.update(cols[name])
    ds.attrs.update({k: v for k, v in df.attrs.items() if k != "columns"})
    return ds
