r"""The SUNDIALS libraries that scikit-sundae ships, bound for compiled code (theory §11).

scikit-sundae (a dependency) calls CVODE through Cython and every call of the vector field, its
Jacobian and the event functions through Python: on the circuit's flights (some 400 steps each at
``rtol = 1e-10``) those calls and their wrapping cost ten times CVODE's own work. This module finds
the SUNDIALS 7 libraries that scikit-sundae's wheels carry (``scikit_sundae.libs`` beside the
package on Linux and Windows, ``sksundae/.dylibs`` on macOS; else a system SUNDIALS that
``ctypes.util.find_library`` finds), checks them (major version 7, double precision) and makes
their functions known to numba's linker under the prefix ``impactbar_`` (:func:`bind`), so that
:mod:`._cvode` drives CVODE from compiled code with compiled callbacks. Where they cannot be bound,
:func:`available` is ``False`` and the flights go through scikit-sundae's Python interface as
before (:mod:`.flight`).

Only functions are used, never a structure's layout; the index type (32 or 64 bits) does not
matter for the arguments passed (each in a register of its own).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import glob
import os
import threading
from typing import NamedTuple

__all__ = ["available", "reason", "bind", "function", "PREFIX"]

#: the prefix of the symbols registered with numba's linker
PREFIX = "impactbar_"

#: the libraries, by stem
STEMS = ("sundials_core", "sundials_nvecserial", "sundials_sunmatrixdense", "sundials_sunlinsoldense",
         "sundials_sunmatrixband", "sundials_sunlinsolband", "sundials_cvode")

_vp, _int, _dbl, _long = ctypes.c_void_p, ctypes.c_int, ctypes.c_double, ctypes.c_long
_i64 = ctypes.c_int64  # sunindextype (int or int64_t: passed in a register, either reads it)

#: name: (library stem, result type, argument types) of every function used (from Python by
#: ctypes, from compiled code through the registered symbol)
FUNCTIONS = {
    "SUNDIALSGetVersionNumber": ("sundials_core", _int,
                                 (ctypes.POINTER(_int),) * 3 + (ctypes.c_char_p, _int)),
    "SUNContext_Create": ("sundials_core", _int, (_int, ctypes.POINTER(_vp))),
    "SUNContext_Free": ("sundials_core", _int, (ctypes.POINTER(_vp),)),
    "SUNContext_ClearErrHandlers": ("sundials_core", _int, (_vp,)),
    "N_VGetArrayPointer": ("sundials_core", ctypes.POINTER(_dbl), (_vp,)),
    "N_VDestroy": ("sundials_core", None, (_vp,)),
    "N_VConst": ("sundials_core", None, (_dbl, _vp)),
    "SUNMatDestroy": ("sundials_core", None, (_vp,)),
    "SUNLinSolFree": ("sundials_core", _int, (_vp,)),
    "N_VNew_Serial": ("sundials_nvecserial", _vp, (_i64, _vp)),
    "SUNDenseMatrix": ("sundials_sunmatrixdense", _vp, (_i64, _i64, _vp)),
    "SUNDenseMatrix_Data": ("sundials_sunmatrixdense", ctypes.POINTER(_dbl), (_vp,)),
    "SUNLinSol_Dense": ("sundials_sunlinsoldense", _vp, (_vp, _vp, _vp)),
    "SUNBandMatrix": ("sundials_sunmatrixband", _vp, (_i64, _i64, _i64, _vp)),
    "SUNBandMatrix_Data": ("sundials_sunmatrixband", ctypes.POINTER(_dbl), (_vp,)),
    "SUNBandMatrix_LDim": ("sundials_sunmatrixband", _i64, (_vp,)),
    "SUNBandMatrix_StoredUpperBandwidth": ("sundials_sunmatrixband", _i64, (_vp,)),
    "SUNBandMatrix_LowerBandwidth": ("sundials_sunmatrixband", _i64, (_vp,)),
    "SUNBandMatrix_UpperBandwidth": ("sundials_sunmatrixband", _i64, (_vp,)),
    "SUNBandMatrix_Columns": ("sundials_sunmatrixband", _i64, (_vp,)),
    "SUNLinSol_Band": ("sundials_sunlinsolband", _vp, (_vp, _vp, _vp)),
    "SUNLinSolSetup_Band": ("sundials_sunlinsolband", _int, (_vp, _vp)),
    "SUNLinSolSolve_Band": ("sundials_sunlinsolband", _int, (_vp, _vp, _vp, _vp, _dbl)),
    "CVodeCreate": ("sundials_cvode", _vp, (_int, _vp)),
    "CVodeInit": ("sundials_cvode", _int, (_vp, _vp, _dbl, _vp)),
    "CVodeReInit": ("sundials_cvode", _int, (_vp, _dbl, _vp)),
    "CVodeSStolerances": ("sundials_cvode", _int, (_vp, _dbl, _dbl)),
    "CVodeSVtolerances": ("sundials_cvode", _int, (_vp, _dbl, _vp)),
    "CVodeSetLinearSolver": ("sundials_cvode", _int, (_vp, _vp, _vp)),
    "CVodeSetJacFn": ("sundials_cvode", _int, (_vp, _vp)),
    "CVodeRootInit": ("sundials_cvode", _int, (_vp, _int, _vp)),
    "CVodeSetRootDirection": ("sundials_cvode", _int, (_vp, _vp)),
    "CVodeSetUserData": ("sundials_cvode", _int, (_vp, _vp)),
    "CVodeSetMaxNumSteps": ("sundials_cvode", _int, (_vp, _long)),
    "CVodeSetMaxHnilWarns": ("sundials_cvode", _int, (_vp, _int)),
    "CVodeSetStopTime": ("sundials_cvode", _int, (_vp, _dbl)),
    "CVodeClearStopTime": ("sundials_cvode", _int, (_vp,)),
    "CVode": ("sundials_cvode", _int, (_vp, _dbl, _vp, ctypes.POINTER(_dbl), _int)),
    "CVodeGetRootInfo": ("sundials_cvode", _int, (_vp, _vp)),
    "CVodeFree": ("sundials_cvode", None, (ctypes.POINTER(_vp),)),
    "CVodeGetNumSteps": ("sundials_cvode", _int, (_vp, ctypes.POINTER(_long))),
    "CVodeGetNumRhsEvals": ("sundials_cvode", _int, (_vp, ctypes.POINTER(_long))),
    "CVodeGetNumErrTestFails": ("sundials_cvode", _int, (_vp, ctypes.POINTER(_long))),
    "CVodeGetNumNonlinSolvIters": ("sundials_cvode", _int, (_vp, ctypes.POINTER(_long))),
    "CVodeGetNumNonlinSolvConvFails": ("sundials_cvode", _int, (_vp, ctypes.POINTER(_long))),
    "CVodeGetNumJacEvals": ("sundials_cvode", _int, (_vp, ctypes.POINTER(_long))),
    "CVodeGetNumLinSolvSetups": ("sundials_cvode", _int, (_vp, ctypes.POINTER(_long))),
    "CVodeGetNumGEvals": ("sundials_cvode", _int, (_vp, ctypes.POINTER(_long))),
}

_LOCK = threading.Lock()


class _Binding(NamedTuple):
    """What :func:`bind` found, once per process: ``ok`` whether the libraries are bound, their
    ``paths``, ``libs`` and ctypes ``funcs`` (empty where not), and ``reason`` why not."""

    ok: bool
    paths: object = None
    libs: object = None
    funcs: dict | None = None
    reason: str = ""


#: the binding, once :func:`bind` has run (``None`` before)
_BINDING: _Binding | None = None


def _candidates():
    """Directories that may hold the libraries: scikit-sundae's wheels' folders first."""
    try:
        import sksundae
    except ImportError:  # pragma: no cover - a dependency
        return []
    pkg = os.path.dirname(os.path.abspath(sksundae.__file__))
    return [os.path.join(os.path.dirname(pkg), "scikit_sundae.libs"), os.path.join(pkg, ".dylibs"), pkg]


def _find(folder, stem):
    """The one file of library ``stem`` in ``folder`` (``libsundials_cvode-1a2b.so.7.9.0``,
    ``libsundials_cvode.7.dylib``, ``sundials_cvode-1a2b.dll``), or None."""
    hits = []
    for prefix in ("lib", ""):
        for sep in ("-", "."):
            hits += glob.glob(os.path.join(folder, f"{prefix}{stem}{sep}*"))
    hits = sorted({h for h in hits if not h.endswith((".a", ".lib", ".la"))})
    return hits[0] if hits else None


def _paths():
    """Paths of all :data:`STEMS` from one place, or None."""
    for folder in _candidates():
        paths = {s: _find(folder, s) for s in STEMS}
        if all(paths.values()):
            return paths
    paths = {s: ctypes.util.find_library(s) for s in STEMS}
    return paths if all(paths.values()) else None


def _load():
    paths = _paths()
    if paths is None:
        raise OSError("the SUNDIALS libraries (CVODE, serial vectors, dense and band matrices and solvers) "
                      "were not found beside scikit-sundae nor on the system")
    libs = {s: ctypes.CDLL(p) for s, p in paths.items()}
    funcs = {}
    for name, (stem, res, args) in FUNCTIONS.items():
        f = getattr(libs[stem], name)
        f.restype, f.argtypes = res, list(args)
        funcs[name] = f
    major, minor, patch = _int(), _int(), _int()
    label = ctypes.create_string_buffer(32)
    funcs["SUNDIALSGetVersionNumber"](ctypes.byref(major), ctypes.byref(minor), ctypes.byref(patch), label,
                                      32)
    if major.value != 7:
        raise OSError(f"SUNDIALS {major.value}.{minor.value}.{patch.value} found; the compiled driver "
                      "binds SUNDIALS 7")
    # double precision: a vector set to 1.5 through a double argument reads 1.5 as doubles
    ctx = _vp()
    if funcs["SUNContext_Create"](0, ctypes.byref(ctx)) != 0:
        raise OSError("SUNContext_Create failed")
    try:
        v = funcs["N_VNew_Serial"](3, ctx)
        if not v:
            raise OSError("N_VNew_Serial failed")
        funcs["N_VConst"](1.5, v)
        ok = [funcs["N_VGetArrayPointer"](v)[i] for i in range(3)] == [1.5] * 3
        funcs["N_VDestroy"](v)
        if not ok:
            raise OSError("the SUNDIALS libraries found are not built in double precision")
    finally:
        funcs["SUNContext_Free"](ctypes.byref(ctx))
    return paths, libs, funcs


def bind() -> bool:
    """Load and check the libraries once and register their functions with numba's linker (as
    ``impactbar_<name>``); whether that succeeded (:func:`reason` says why not)."""
    global _BINDING
    with _LOCK:
        if _BINDING is None:
            try:
                paths, libs, funcs = _load()
                import llvmlite.binding as llvm

                for name, f in funcs.items():
                    llvm.add_symbol(PREFIX + name, ctypes.cast(f, _vp).value)
                _BINDING = _Binding(True, paths, libs, funcs)
            except (OSError, AttributeError) as err:  # not found, a symbol missing, another version
                _BINDING = _Binding(False, reason=str(err))
        return _BINDING.ok


def available() -> bool:
    """Whether CVODE can be driven from compiled code in this process (:func:`bind`)."""
    return bind()


def reason() -> str:
    """Why :func:`available` is ``False`` (empty where it is ``True``)."""
    bind()
    return _BINDING.reason


def function(name: str):
    """The ctypes function ``name`` of :data:`FUNCTIONS` (after a successful :func:`bind`)."""
    return _BINDING.funcs[name]
