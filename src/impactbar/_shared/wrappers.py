"""numba kernels that only other kernels call: compiled into their callers, with no code of their own.

numba compiles every kernel into a library of its own: its LLVM module, with the modules of the
kernels it calls linked in, optimised as a whole and turned into machine code; and, with it, two
wrappers (one that Python calls, unboxing the arguments, and a C one). A caller's library holds the
machine code of all its callees again, so that a kernel deep in a tree of calls was optimised and
turned into machine code once for itself and once for each kernel above it: the exact blow's kernels
spent about half of their compile there (the wrappers included), for machine code that only the top
kernel's library runs. :func:`internal_kernels` compiles a module's kernels that only kernels call
*link-only*: their LLVM module (optimised function by function) is kept for their callers, which
optimise it with their own and make its machine code; they get no machine code, no wrappers and no
cache entry of their own (a cached caller holds their machine code; a caller compiled later compiles
them again). The kernels Python calls keep their Python wrapper and their cache entry. A link-only
kernel cannot be called from Python: such a call raises :class:`TypeError`; or, with
``from_python="compile"``, it compiles the kernel again as a whole kernel of its own (its machine code,
wrappers and cache entry), once, and calls that: for kernels that Python calls only outside the paths
that compile them for their callers (tests, benchmarks, a rarely taken branch).

All of a module's kernels also count references *leanly*: numba increments and decrements the
reference counts of an array, a tuple of arrays, ... by walking every field of the value and reading
each one (an array's pointers, sizes, shape and strides), to call the runtime on the few that hold a
memory block; for the exact blow's workspace, a tuple of 26 arrays, some 300 LLVM instructions per
count, about a third of its kernels' LLVM IR, all dead (LLVM deletes them). The lean lowering reads
only the fields that hold a memory block, on the same path: the same calls to the runtime, in the
same order, from less IR to build, print, parse and optimise.

With numba's JIT disabled (``NUMBA_DISABLE_JIT=1``, numba's way to run jitted code as Python: its
``njit`` then returns the plain function, as numba's own decorators do) there are no kernels to
change: :func:`internal_kernels`, :func:`link_only` and :func:`internal_jitable` leave the functions
as they are, and Python calls them all.
"""

from __future__ import annotations

import types as _pytypes

from .literals import module_kernels

__all__ = ["internal_kernels", "link_only", "internal_jitable", "jit_disabled", "require_jit"]

_GUARDED: dict = {}
_CLASSES: dict = {}


def jit_disabled() -> bool:
    """Whether numba's JIT is disabled (``NUMBA_DISABLE_JIT=1``): its ``njit`` then returns the plain
    Python function, and nothing compiles.

    Returns
    -------
    bool
        numba's ``config.DISABLE_JIT``, read when asked.
    """
    from numba.core import config

    return bool(config.DISABLE_JIT)


def require_jit(what: str) -> None:
    """Refuse, with numba's JIT disabled, a computation that cannot run as Python.

    Parameters
    ----------
    what : str
        The computation and what it compiles, as the message names them.

    Raises
    ------
    RuntimeError
        Where ``NUMBA_DISABLE_JIT=1``: the message names ``what`` and the setting.
    """
    if jit_disabled():
        raise RuntimeError(f"{what} needs compiled code, which NUMBA_DISABLE_JIT=1"
                           " turns off: run it with NUMBA_DISABLE_JIT unset or 0")


def _guarded_class(cls, compile_for_python: bool = False):
    """A subclass of the dispatcher class ``cls`` whose instances refuse a call from Python, or, with
    ``compile_for_python``, call their whole kernel (:func:`_whole_kernel`)."""
    key = (cls, compile_for_python)
    if key not in _GUARDED:
        if compile_for_python:
            def __call__(self, *args, **kwargs):
                return _whole_kernel(self)(*args, **kwargs)
        else:
            def __call__(self, *args, **kwargs):
                raise TypeError(f"{self.py_func.__module__}.{self.py_func.__name__} is a numba kernel "
                                "compiled without its Python wrapper: call it from another kernel")

        prefix = "PythonCompiled" if compile_for_python else "Internal"
        _GUARDED[key] = type(prefix + cls.__name__, (cls,), {"__call__": __call__, "__module__": __name__})
    return _GUARDED[key]


def _compiles_for_python(from_python: str) -> bool:
    """Whether ``from_python`` (:func:`internal_kernels`'s) says a call from Python compiles the kernel
    (``"compile"``) rather than raising (``"raise"``); ``ValueError`` for anything else."""
    if from_python not in ("raise", "compile"):
        raise ValueError(f"from_python must be 'raise' or 'compile', not {from_python!r}")
    return from_python == "compile"


def _whole_kernel(disp):
    """The link-only kernel ``disp``'s function as a whole kernel of its own (made once): its options,
    with its Python wrapper, machine code and (where ``disp`` had one) cache entry; its callees are
    ``disp``'s (link-only ones linked into its library)."""
    whole = disp.__dict__.get("_impactbar_whole")
    if whole is None:
        import numba

        options = {k: v for k, v in disp.targetoptions.items() if k != "nopython"}  # (njit's own)
        whole = numba.njit(cache=disp.__dict__["_impactbar_cached"], **options)(disp.py_func)
        whole._compiler.pipeline_class = _link_only_classes()["lean"]
        disp._impactbar_whole = whole
    return whole


class _NoEnv:
    """A kernel's code generator, less the setting of the kernel's environment in machine code it
    does not have (a link-only library's ``codegen``)."""

    def __init__(self, codegen):
        self._codegen = codegen

    def set_env(self, env_name, env):
        pass

    def __getattr__(self, name):
        return getattr(self._codegen, name)


def _lean_compiler():
    """numba's compiler with the lean counting of references: its lowering pass's lowering reads
    only the fields of a value that hold a memory block to increment or decrement their counts."""
    import contextlib

    from numba.core import debuginfo, lowering, typed_passes
    from numba.core.compiler import Compiler
    from numba.core.compiler_machinery import register_pass
    from numba.core.runtime.context import NRTContext

    suspend = getattr(debuginfo, "suspend_emission", lambda builder: contextlib.nullcontext())

    class LeanNRT(NRTContext):
        """numba's runtime calls, the memory blocks inside a value found without reading its other
        fields."""

        def get_meminfos(self, builder, ty, val):
            dmm = self._context.data_model_manager
            model = dmm[ty]
            found = [(ty, model.get_nrt_meminfo(builder, val))] if model.has_nrt_meminfo() else []
            for mty, getter in model.traverse(builder):
                if dmm[mty].contains_nrt_meminfo():  # (the others: no block, nothing to read)
                    found.extend(self.get_meminfos(builder, mty, getter(val)))
            return found

    class LeanLower(lowering.Lower):
        """numba's lowering, its reference counts through :class:`LeanNRT`."""

        def incref(self, typ, val):
            if self.context.enable_nrt:
                LeanNRT(self.context, True).incref(self.builder, typ, val)

        def decref(self, typ, val):
            if self.context.enable_nrt:
                with suspend(self.builder):  # (as numba's: no line of its own for a decref)
                    LeanNRT(self.context, True).decref(self.builder, typ, val)

    @register_pass(mutates_CFG=True, analysis_only=False)
    class LeanNativeLowering(typed_passes.NativeLowering):
        """numba's lowering pass with :class:`LeanLower`."""

        _name = "impactbar_lean_native_lowering"

        @property
        def lowering_class(self):
            return LeanLower

        def run_pass(self, state):
            # the wrappers left out here, after typing, not by the kernel's options: numba keys the
            # implementations of its own overloads (``max``, ``np.empty``, ...) on the options of the
            # kernel that types them, and would compile them again for each set
            state.flags.no_cfunc_wrapper = True
            if getattr(state.library, "link_only", False):
                state.flags.no_cpython_wrapper = True
            return super().run_pass(state)

    class LeanCompiler(Compiler):
        """numba's compiler, its lowering pass :class:`LeanNativeLowering`."""

        def define_pipelines(self):
            pms = super().define_pipelines()
            for pm in pms:
                pm.passes = [(LeanNativeLowering if p is typed_passes.NativeLowering else p, d)
                             for p, d in pm.passes]
                pm.finalize()
            return pms

    return LeanCompiler


def _link_only_classes():
    """The compiler pipelines of a module's kernels: the lean one (:func:`_lean_compiler`), and the
    one that gives a kernel a link-only library, with that library's class (numba's JIT library that
    keeps its LLVM module for its callers and makes no machine code)."""
    if not _CLASSES:
        from numba.core.codegen import JITCodeLibrary

        Compiler = _lean_compiler()

        class LinkOnlyLibrary(JITCodeLibrary):
            """The LLVM module of a kernel that only other kernels call: linked into theirs, which
            optimise it with their own and make its machine code; none of its own."""

            link_only = True  # (its kernel's lowering leaves out the wrappers)

            def _optimize_final_module(self):
                pass  # (each caller optimises it with its own module)

            def _finalize_final_module(self):
                self._finalize_dynamic_globals()
                self._verify_declare_only_symbols()
                self._finalized = True  # (not added to the JIT engine: no machine code)

            def get_pointer_to_function(self, name):
                self._ensure_finalized()
                return 0

            @property
            def codegen(self):
                return _NoEnv(self._codegen)

        class LinkOnlyCompiler(Compiler):
            """numba's compiler, its kernel's library a :class:`LinkOnlyLibrary`."""

            def __init__(self, typingctx, targetctx, library, args, return_type, flags, locals):
                if library is None:
                    library = targetctx.codegen().create_library(self.__module__)
                    library.__class__ = LinkOnlyLibrary
                super().__init__(typingctx, targetctx, library, args, return_type, flags, locals)

        _CLASSES.update(library=LinkOnlyLibrary, compiler=LinkOnlyCompiler, lean=Compiler)
    return _CLASSES


def internal_kernels(namespace: dict, python=(), from_python: str = "raise") -> int:
    """Compile a module's numba kernels that only kernels call link-only, the others without a C wrapper,
    all with the lean counting of references.

    Parameters
    ----------
    namespace : dict
        The module's ``globals()``; the kernels (numba dispatchers) whose Python function was defined
        in that module are changed, those it imported are not. Call it before any of them compiles.
    python : iterable of str, optional
        The names of the module's kernels that Python calls: they keep their Python wrapper, machine
        code and cache entry. The others are link-only (no machine code, wrappers or cache entry of
        their own), and a call of one from Python does as ``from_python`` says.
    from_python : {"raise", "compile"}, optional
        What a call of a link-only kernel from Python does: raise :class:`TypeError` (the default),
        or compile the kernel's function again as a kernel of its own, once (its wrappers, machine
        code and cache entry), and call that, with the same numbers.

    Returns
    -------
    int
        How many kernels were made link-only (none where numba's JIT is disabled).

    Raises
    ------
    ValueError
        If ``python`` names something that is not one of the module's kernels, or ``from_python`` is
        neither ``"raise"`` nor ``"compile"``.

    Examples
    --------
    A helper ``square`` kept only for the kernel ``area`` that calls it:

    >>> from numba import njit
    >>> square = njit(lambda x: x * x)
    >>> area = njit(lambda a, b: square(a) + square(b))
    >>> internal_kernels({"__name__": square.py_func.__module__, "square": square, "area": area},
    ...                  python=("area",))
    1
    >>> area(3, 4)
    25
    >>> square(3)
    Traceback (most recent call last):
    ...
    TypeError: ... is a numba kernel compiled without its Python wrapper: call it from another kernel
    """
    _compiles_for_python(from_python)  # (refused before any kernel is changed)
    name = namespace.get("__name__")
    ours = module_kernels(namespace)
    if jit_disabled():  # (njit gave the module's plain functions: nothing to change, Python calls them)
        ours = {k: v for k, v in namespace.items()
                if isinstance(v, _pytypes.FunctionType) and v.__module__ == name}
    python = set(python)
    unknown = python - set(ours)
    if unknown:
        raise ValueError(f"python names no kernel of {name}: {sorted(unknown)}")
    if jit_disabled():
        return 0
    n = 0
    for k, disp in ours.items():
        if k in python:
            disp._compiler.pipeline_class = _link_only_classes()["lean"]  # (no C wrapper)
        else:
            link_only(disp, from_python)
            n += 1
    return n


def link_only(disp, from_python: str = "raise"):
    """Compile one numba kernel that only kernels call link-only, with the lean counting of references
    (:func:`internal_kernels` for a kernel made from a function of another module).

    Parameters
    ----------
    disp : numba dispatcher
        The kernel, not yet compiled.
    from_python : {"raise", "compile"}, optional
        What a call of it from Python does (:func:`internal_kernels`'s ``from_python``).

    Returns
    -------
    numba dispatcher
        ``disp``, changed in place: no machine code, wrappers or cache entry of its own; a call of it
        from Python raises :class:`TypeError` or, with ``from_python="compile"``, compiles it once
        as a whole kernel and calls that.

    Raises
    ------
    ValueError
        If ``from_python`` is neither ``"raise"`` nor ``"compile"``.
    """
    from numba.core.caching import NullCache

    if jit_disabled():  # (njit gave the plain function: Python calls it)
        _compiles_for_python(from_python)
        return disp
    disp._compiler.pipeline_class = _link_only_classes()["compiler"]  # (no wrappers)
    disp._impactbar_cached = not isinstance(disp._cache, NullCache)
    disp._cache = NullCache()
    disp.__class__ = _guarded_class(type(disp), _compiles_for_python(from_python))
    return disp


def internal_jitable(fn):
    """numba's ``register_jitable``, its implementation compiled link-only with the lean counting of
    references: a plain Python function that Python calls as it is and kernels compile into their own
    code (its machine code is theirs; it has no wrappers of its own).

    Parameters
    ----------
    fn : function
        A Python function that numba can compile.

    Returns
    -------
    function
        ``fn`` itself, registered for kernels.
    """
    from numba.extending import register_jitable

    if jit_disabled():  # (no kernels to compile it into: Python calls it)
        return fn
    # (the options of the rod and rock's kernels, which call them: numba's overloads that they call
    # are then compiled once for both)
    return register_jitable(pipeline_class=_link_only_classes()["compiler"], no_cpython_wrapper=False,
                            nogil=True)(fn)
