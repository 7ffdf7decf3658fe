"""Operations whose machine code is numba's own and whose interpreted form is a kernel's twin's:
arithmetic that the twin rounds as the machine code does, and a checkpoint at which a twin that has
run past its CPU budget is abandoned.

A kernel's twin (:mod:`impactbar.dynamics._tiers`: the kernel's own Python source, run before it is
compiled) does IEEE double arithmetic in the kernel's order and gets the machine code's bits, but
for two operators on the numpy scalars it reads from arrays: numpy divides a ``complex128`` by
multiplying with the reciprocal of the denominator, where numba compiles CPython's algorithm
(``_Py_c_quot``: a ratio of the denominator's parts, then two divisions), an ulp apart in some
40 % of quotients; and numpy raises a float to an integer power with the C library's ``pow``, where
numba multiplies by repeated squaring. A kernel writes such an operation as :func:`quot` or
:func:`ipow`: compiled, each is exactly numba's ``a / b`` or ``x ** n`` (numba's own lowering of the
operator, typed as the operator; no function of its own to compile); interpreted, each is computed
as numba's machine code computes it.

A kernel's loop may call :func:`checkpoint` once a pass (the exact blow's window): compiled, nothing;
interpreted, it raises :class:`OverBudget` once this thread's twin has run past the CPU time
:func:`deadline` set (:mod:`impactbar.dynamics._tiers` then puts the arguments back and runs the
machine code from the start: a long computation loses the budget, not its interpreted run).

With numba's JIT disabled (``NUMBA_DISABLE_JIT=1``: every kernel runs as Python) they are the Python
functions, so that such a run, too, rounds as the compiled code.
"""

from __future__ import annotations

import math
import operator
import threading
import time

from .wrappers import jit_disabled

__all__ = ["quot", "ipow", "checkpoint", "python_form", "deadline", "OverBudget"]

_LOCAL = threading.local()  # .at: this thread's twin's deadline in CPU seconds (process_time)


class OverBudget(Exception):
    """A twin ran past the CPU time its :func:`deadline` allowed (raised at a :func:`checkpoint`)."""


def deadline(at: float) -> float:
    """Set this thread's deadline for interpreted checkpoints.

    Parameters
    ----------
    at : float
        The ``time.process_time()`` past which an interpreted :func:`checkpoint` raises
        :class:`OverBudget` (``math.inf``: never).

    Returns
    -------
    float
        The deadline it replaces (``math.inf`` where none was set).

    Raises
    ------
    ValueError
        If ``at`` is not a number.
    """
    if at != at:
        raise ValueError(f"at must be a CPU time or inf, not {at!r}")
    old = getattr(_LOCAL, "at", math.inf)
    _LOCAL.at = at
    return old


def _checkpoint():
    """A twin's checkpoint (:func:`checkpoint`): nothing before this thread's :func:`deadline`.

    Raises
    ------
    OverBudget
        Once ``time.process_time()`` is past the deadline.
    """
    if time.process_time() > getattr(_LOCAL, "at", math.inf):
        raise OverBudget("the twin ran past its CPU budget")


def _quot(a, b):
    """``a / b`` as numba's machine code computes it (:func:`quot`).

    Parameters
    ----------
    a, b : int, float or complex
        Scalars (numpy's or Python's), as the kernel divides them.

    Returns
    -------
    float or complex
        For a complex operand CPython's quotient of ``complex(a)`` by ``complex(b)`` (the algorithm
        numba compiles), else IEEE's quotient.

    Raises
    ------
    ZeroDivisionError
        Where ``b`` is zero, as the machine code raises.
    """
    if isinstance(a, complex) or isinstance(b, complex):  # (numpy's complex128 is a complex)
        return complex(a) / complex(b)
    return a / b


def _ipow(x, n):
    """``x ** n`` as numba's machine code computes it (:func:`ipow`).

    Parameters
    ----------
    x : float
        The base.
    n : int
        The exponent.

    Returns
    -------
    float
        numba's ``int_power``: repeated squaring (the C library's ``pow`` beyond ``|n| = 65536``).

    Raises
    ------
    ZeroDivisionError
        Where ``x`` is zero and ``n`` negative, as the machine code raises.
    """
    r = 1.0
    a = float(x)
    e = -n if n < 0 else n
    if e > 0x10000:
        return math.pow(a, float(n))
    while e != 0:
        if e & 1:
            r *= a
        e >>= 1
        a *= a
    return 1.0 / r if n < 0 else r


def _named(out, python):
    """The intrinsic ``out``, its Python form ``python`` (and that one's docstring)."""
    out._impactbar_python = python
    out.__doc__ = python.__doc__
    return out


def _operator_intrinsic(op, python, name):
    """An intrinsic that a kernel calls as ``name(a, b)`` for numba's lowering of ``op`` on ``a, b``
    (typed, cast and lowered as the binary operator is), whose Python form is ``python``."""
    from numba.extending import intrinsic

    def typer(typingctx, a, b):
        sig = typingctx.resolve_function_type(op, (a, b), {})
        if sig is None:  # (numba's own message, as for the operator)
            return None

        def codegen(context, builder, signature, args):
            cast = [context.cast(builder, v, t, u) for v, t, u in zip(args, signature.args, sig.args,
                                                                        strict=True)]
            out = context.get_function(op, sig)(builder, cast)
            return context.cast(builder, out, sig.return_type, signature.return_type)

        return sig.return_type(a, b), codegen

    typer.__name__ = typer.__qualname__ = name
    return _named(intrinsic(typer), python)


def _nothing_intrinsic(python, name):
    """An intrinsic that a kernel calls as ``name()`` and that compiles to nothing (it returns
    ``None``), whose Python form is ``python``."""
    from numba.core import types
    from numba.extending import intrinsic

    def typer(typingctx):
        def codegen(context, builder, signature, args):
            return context.get_dummy_value()

        return types.none(), codegen

    typer.__name__ = typer.__qualname__ = name
    return _named(intrinsic(typer), python)


def python_form(obj):
    """The Python function that a kernel's twin calls in place of ``obj``: the Python forms of
    :func:`quot`, :func:`ipow` and :func:`checkpoint` for them, ``None`` for anything else.

    Parameters
    ----------
    obj : object
        A global of a kernel's module.

    Returns
    -------
    callable or None
        The Python form, or ``None`` where ``obj`` is not one of this module's operators.
    """
    return getattr(obj, "_impactbar_python", None)


if jit_disabled():  # (the kernels are Python functions: they call the Python forms)
    quot, ipow, checkpoint = _quot, _ipow, _checkpoint
else:
    quot = _operator_intrinsic(operator.truediv, _quot, "quot")
    ipow = _operator_intrinsic(operator.pow, _ipow, "ipow")
    checkpoint = _nothing_intrinsic(_checkpoint, "checkpoint")
