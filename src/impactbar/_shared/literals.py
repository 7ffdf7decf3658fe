"""numba kernels typed on their arguments' types, not on the constants a caller passes.

A kernel called from another kernel with a constant argument (``_emit(ws, c, a, B_OUT, ...)``, ``B_OUT``
a module-level int) is compiled by numba for that constant's literal type (``Literal[int](4)``): a
separate machine code, and its callees' with it, for every constant at every call site. The exact
blow's kernels compiled 116 times, 32 of them such copies. :func:`plain_literals` makes a module's
kernels try the plain types first (``int64``), as numba does for a call from Python, and keep the
literal only where the plain types do not type (a kernel that needs the constant to choose its
types). The machine code computes the same numbers: a constant is only a value passed at run time.
"""

from __future__ import annotations

import types as _pytypes

__all__ = ["plain_literals", "module_kernels"]


def module_kernels(namespace: dict) -> dict:
    """The numba kernels (dispatchers) of a module's ``globals()`` whose Python function was defined
    in that module (not those it imported), by name."""
    from numba.core.dispatcher import Dispatcher

    name = namespace.get("__name__")
    return {k: v for k, v in namespace.items()
            if isinstance(v, Dispatcher) and getattr(v.py_func, "__module__", None) == name}


def _get_call_template(self, args, kws):
    """``Dispatcher.get_call_template`` with literal argument types made plain first."""
    from numba.core import errors, types

    plain = tuple(types.unliteral(a) for a in args)
    plain_kws = {k: types.unliteral(v) for k, v in kws.items()}
    if plain != tuple(args) or plain_kws != kws:
        try:
            return type(self).get_call_template(self, plain, plain_kws)
        except errors.TypingError:
            pass
    return type(self).get_call_template(self, args, kws)


def plain_literals(namespace: dict) -> int:
    """Make every numba kernel defined in a module compile once per plain argument types.

    Parameters
    ----------
    namespace : dict
        The module's ``globals()``; the kernels (numba dispatchers) whose Python function was defined
        in that module are changed, those it imported are not.

    Returns
    -------
    int
        How many kernels were changed.

    Examples
    --------
    >>> import numba
    >>> @numba.njit
    ... def twice(x):
    ...     return 2 * x
    >>> @numba.njit
    ... def caller():
    ...     return twice(3) + twice(4)
    >>> plain_literals({"__name__": twice.py_func.__module__, "twice": twice})
    1
    >>> caller()
    14
    >>> len(twice.signatures)  # one machine code for both constants (without: two)
    1
    """
    kernels = module_kernels(namespace)
    for obj in kernels.values():
        obj.get_call_template = _pytypes.MethodType(_get_call_template, obj)
    return len(kernels)
