"""A bounded store of computed values: one rule for the library's small caches (a load's transfer
functions, a drive's flight data and fired events), emptied whole when full."""

from __future__ import annotations

__all__ = ["remember"]


def remember(store: dict, key, value, size: int):
    """``store[key] = value``, the store emptied first when it holds ``size`` entries.

    Emptying whole keeps the rule simple and the store bounded; ``dict.clear()`` is atomic, so
    threads sharing a store are safe (a value computed twice is the same value).

    Parameters
    ----------
    store : dict
        The cache.
    key : hashable
    value : object
        What ``key`` computes (shared by every caller: never to be written).
    size : int
        The most entries the store holds, ``>= 1``.

    Returns
    -------
    object
        ``value``.

    Examples
    --------
    >>> store = {}
    >>> [remember(store, k, k * k, 2) for k in range(3)]
    [0, 1, 4]
    >>> store
    {2: 4}
    """
    if len(store) >= size:
        store.clear()
    store[key] = value
    return value
