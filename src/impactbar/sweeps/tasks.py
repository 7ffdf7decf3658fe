"""The work of one chunk of a sweep (orbits, montecarlo, bifurcation), from plain arguments:
no dask, no storage."""

from __future__ import annotations

import contextlib
import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np

from .._shared.schema import Field, Schema
from .._shared.validate import check_int
from ..dynamics.implementations import implementation
from ..laws import get_law
from ..orbits.orbit import ORBIT_FIELDS

if TYPE_CHECKING:
    from .spec import SweepSpec

#: a sweep in the rigid closed forms with fewer grid points than this takes the numpy closed forms
#: (the reference of ``"orbits.rigid_arrays"``) rather than the compiled loop: importing numba and
#: loading the compiled loop from its cache (about 0.45 s; some 3 s to compile it on a new machine)
#: costs more than the numpy closed forms take for the whole sweep (about 300,000 points/s a core)
COMPILED_CLOSED_FORMS_FROM = 100_000


# ------------------------------------------------------------------------------------------------
# chunks and the task functions (plain numbers, no dask)
# ------------------------------------------------------------------------------------------------
def chunk_slices(spec: SweepSpec, chunk: int) -> tuple[slice, ...]:
    """The block of the grid covered by work chunk ``chunk`` (C order over :attr:`chunk_grid`).

    Returns
    -------
    tuple of slice, shape (n_axes,)
    """
    return spec.block(check_int("chunk", chunk, lo=0, hi=spec.n_chunks - 1))



def motion_classes() -> tuple[str, ...]:
    """The ``motion`` coordinate of a ``montecarlo`` store: the classes of
    :func:`impactbar.simulation.experiments.classify` in their report order, and ``"k>8"`` for any longer
    one-impact cycle."""
    from ..simulation.experiments import CLASS_ORDER

    return (*CLASS_ORDER, "k>8")


def point_seed(base_seed: int, flat_index: int) -> int:
    """Seed of the random start(s) at the grid point with C-order index ``flat_index``: from
    ``numpy.random.SeedSequence([base_seed, flat_index])``, independent of chunks and workers."""
    return int(np.random.SeedSequence([base_seed, flat_index]).generate_state(1, np.uint64)[0])


_FAILED = Field("failed", "the computation raised ValueError at this point (e.g. an undamped "
                          "resonance s n pi = k)", "", dtype="b1")
#: the ``orbits`` task's variables under the rod-rock law: figures of each orbit's blow
#: (:class:`impactbar.Blow`, read on ``orbit.contacts[0]``), along ``orbit``
_ROCK = Schema(
    Field("work_on_rock", "work done on the rock per blow (model units: the orbit's blow)", per="orbit"),
    Field("penetration", "permanent penetration per blow (model lengths: the orbit's blow, the rod's "
                         "advance per period)", attr="permanent_penetration", per="orbit"),
    dataclasses.replace(ORBIT_FIELDS["efficiency"], attr=None, views=frozenset(), optional=False,
                        per="orbit"),  # (the orbit's declared field: its name and long name)
    Field("efficiency_with_rebound", "the same with the piston's rebound energy credited", per="orbit"))
_MOTION = "load periods"
_TASK_VARIABLES = {
    "montecarlo": Schema(
        Field("fraction", "fraction of the random starts in each long-run motion", per="motion"),
        Field("interval_mean", "mean interval between main impacts (load periods)", _MOTION),
        Field("interval_std", "std of the intervals between main impacts (load periods)", _MOTION),
        Field("all_interval_mean", "mean interval between any impacts (load periods)", _MOTION),
        Field("all_interval_std", "std of the intervals between any impacts (load periods)", _MOTION),
        Field("run_spread", "median over runs of each run's interval std/mean")),
    "bifurcation": Schema(
        Field("impact_velocity", "velocity of the struck end before each of the last impacts (oldest "
                                 "first)", per="impact"),
        Field("impact_phase", "load phase of each of the last impacts (load periods, in [0, 1))",
              "load periods", per="impact"),
        Field("n_impacts", "impacts in the whole run", "", dtype="i8")),
}


def _bar_variables(spec: SweepSpec) -> Schema:
    """The variables of a task of the dimensionless bar (:meth:`SweepSpec.variables`); an ``orbits``
    sweep stores the orbit's fields in the view ``"sweep"`` (:data:`~impactbar.orbits.orbit.ORBIT_FIELDS`)
    along ``orbit``."""
    if spec.task == "orbits":
        orbit = Schema(*(dataclasses.replace(f, per="orbit") for f in ORBIT_FIELDS.select("sweep")))
        count = Field("n_orbits", "number of one-impact orbits", "", dtype="i4")
        return orbit + Schema(count) + (_ROCK if spec.rock is not None else Schema()) + Schema(_FAILED)
    return _TASK_VARIABLES[spec.task] + Schema(_FAILED)


def compute_chunk(spec: SweepSpec, chunk: int) -> dict[str, np.ndarray]:
    """Compute one work chunk; this is what runs on a worker. No dask, no storage.

    Parameters
    ----------
    spec : SweepSpec
    chunk : int
        Chunk number, ``0 <= chunk < spec.n_chunks``.

    Returns
    -------
    dict of str to numpy.ndarray
        Every variable of the task (see the module docstring), each of shape ``block`` or
        ``block + (extra,)`` where ``block`` is the chunk's part of the grid.

    Raises
    ------
    RuntimeError
        If an ``orbits`` point has more than ``max_orbits`` orbits (the default cannot be exceeded).
        A ``ValueError`` from the library at one point (e.g. an undamped resonance) only sets
        ``failed`` there.
    """
    return spec.space.compute_chunk(spec, chunk)


def _blank_chunk(spec: SweepSpec, chunk: int) -> tuple:
    """A work chunk's slices of the grid, its block's shape and every variable filled with its fill
    (those along the task's extra dimension with it)."""
    slices = chunk_slices(spec, chunk)
    block = tuple(s.stop - s.start for s in slices)
    extra = (spec.extra_size,)
    return slices, block, {f.name: np.full(block + (extra if f.per else ()), f.fill, dtype=f.dtype)
                           for f in spec.variables()}


def _bar_chunk(spec: SweepSpec, chunk: int) -> dict[str, np.ndarray]:
    """One work chunk of a task of the dimensionless bar (:func:`compute_chunk`)."""
    from .._shared.threads import single_threaded_blas

    slices, block, out = _blank_chunk(spec, chunk)
    variables = spec.variables()
    one = {"orbits": _orbits_point, "montecarlo": _montecarlo_point, "bifurcation": _bifurcation_point}
    todo = None
    if spec.task == "orbits":
        todo = _rigid_chunk(spec, slices, block, out)
    with single_threaded_blas():
        for local in np.ndindex(*block) if todo is None else todo:
            index = tuple(s.start + i for s, i in zip(slices, local, strict=True))
            flat = int(np.ravel_multi_index(index, spec.shape))
            try:
                model, load = spec.point(index)
                one[spec.task](spec, model, load, flat, out, local)
            except ValueError:
                for f in variables:
                    out[f.name][local] = f.fill
                out["failed"][local] = True
    return out


def _chunk_parameters(spec: SweepSpec, slices, block) -> dict:
    """Every model and load field over the chunk's block of the grid, as arrays of shape ``block``."""
    grids = np.meshgrid(*(np.asarray(a.values[s]) for a, s in zip(spec.axes, slices, strict=True)),
                        indexing="ij")
    par = {name: np.full(block, value) for name, value in (*spec.model.items(), *spec.load.items())
           if name != "kind"}
    for a, g in zip(spec.axes, grids, strict=True):
        par[a.name] = g
    return par


def _rigid_chunk(spec: SweepSpec, slices, block, out) -> list | None:
    """The ``orbits`` task for the rigid bar under a cosine load or the square wave, the whole
    chunk at once by the closed forms of :mod:`impactbar.orbits.rigid` (the same numbers as
    :func:`impactbar.periodic_orbits`, tested against it). Returns the local indices left to the
    point-by-point path (degenerate orbits, ``kappa = 2``), or ``None`` if the closed forms do not
    apply."""
    from ..orbits.rigid import CLOSED_FORM_KINDS, closed_form_groups

    if spec.rock is not None or spec.law is not None or spec.load is None \
            or spec.load["kind"] not in CLOSED_FORM_KINDS:
        return None
    if not get_law(spec.model.get("impact", "paper")).traits.rigid_closed_forms:
        return None
    par = _chunk_parameters(spec, slices, block)
    if np.any(par["n_modes"] != 0):
        return None
    groups = closed_form_groups(spec.load["kind"], {n: v.ravel() for n, v in par.items()})
    J = spec.options["max_orbits"]
    todo = []
    covered = np.zeros(math.prod(block), dtype=bool)
    for sel, solve, args in groups:
        covered[sel] = True
        with (implementation("orbits.rigid_arrays", "reference") if spec.n_points < COMPILED_CLOSED_FORMS_FROM
              else contextlib.nullcontext()):
            res = solve(*args)
        n = res.n_orbits
        if np.any(n > J):
            i = int(np.argmax(n > J))
            local = np.unravel_index(sel[i], block)
            index = tuple(s.start + j for s, j in zip(slices, local, strict=True))
            at = int(np.ravel_multi_index(index, spec.shape))
            raise RuntimeError(f"{int(n[i])} orbits at grid point {at} exceed [orbits] "
                               f"max_orbits = {J}; raise it in the spec")
        w = min(J, res.phase.shape[1])
        whole = sel.size == covered.size  # one group, every point of the block in order
        idx = np.unravel_index(sel, block)
        out["n_orbits"][idx] = n
        used = res.status[:, :w] >= 0
        for name in ORBIT_FIELDS.select("sweep").names:  # the closed forms give each of them
            values = getattr(res, name)
            target = out[name]
            if whole:  # a view of shape (points, J): no gather and scatter
                col = target.view()
                col.shape = (sel.size, target.shape[-1])
            else:
                col = target[idx]  # (points, J)
            col[:, :w] = np.where(used, values[:, :w], col[:, :w])
            if not whole:
                target[idx] = col
        todo.extend(sel[res.fallback].tolist())
    todo.extend(np.nonzero(~covered)[0].tolist())
    todo = [tuple(int(x) for x in np.unravel_index(p, block)) for p in sorted(todo)]
    for local in todo:  # reset what the point-by-point path will recompute
        for f in spec.variables():
            out[f.name][local] = f.fill
    return todo


def _orbits_point(spec, model, load, flat, out, local) -> None:
    from ..orbits import periodic_orbits

    orbits = periodic_orbits(model, load)
    n = len(orbits)
    if n > spec.options["max_orbits"]:
        raise RuntimeError(f"{n} orbits at grid point {flat} ({model}, {load!r}) exceed [orbits] "
                         f"max_orbits = {spec.options['max_orbits']}; raise it in the spec")
    out["n_orbits"][local] = n
    for j, o in enumerate(orbits):
        at = (*local, j)
        for f in ORBIT_FIELDS.select("sweep"):
            value = f.get(o)  # schur_stable is None (no Schur test) under the rod-rock law
            out[f.name][at] = f.fill if value is None else value
        if spec.rock is not None:
            blow = o.contacts[0]  # the orbit's one blow (a RockContact, read through to its Blow)
            for f in _ROCK:
                out[f.name][at] = f.get(blow)


def _montecarlo_point(spec, model, load, flat, out, local) -> None:
    from ..simulation.experiments import run_experiment

    opt = spec.options
    res = run_experiment(model, load, starts=opt["starts"], periods=opt["periods"],
                         seed=point_seed(opt["seed"], flat), workers=1, keep=0, window=opt["window"])
    classes = motion_classes()
    frac = np.zeros(len(classes))
    for kind, f in res.fractions.items():
        if kind in classes:
            frac[classes.index(kind)] += f
        elif kind.startswith("k="):
            frac[classes.index("k>8")] += f
        else:  # pragma: no cover - a class the experiments module added
            raise RuntimeError(f"unknown motion class {kind!r}; update impactbar.sweeps.spec.motion_classes")
    out["fraction"][local] = frac
    out["interval_mean"][local] = res.interval_mean
    out["interval_std"][local] = res.interval_std
    out["all_interval_mean"][local] = res.all_interval_mean
    out["all_interval_std"][local] = res.all_interval_std
    out["run_spread"][local] = res.run_spread


def _bifurcation_point(spec, model, load, flat, out, local) -> None:
    from ..simulation.experiments import load_period, random_start
    from ..simulation.simulate import simulate

    opt = spec.options
    rng = np.random.default_rng(point_seed(opt["seed"], flat))
    t0, start = random_start(model, load, rng)
    T = load_period(load)
    tr = simulate(model, load, start, t0 + opt["periods"] * T, t0=t0)
    keep = opt["keep"]
    v = tr.impact_velocities[-keep:]
    t = tr.impact_times[-keep:]
    out["impact_velocity"][(*local, slice(0, v.size))] = v
    out["impact_phase"][(*local, slice(0, t.size))] = np.mod(t / T, 1.0)
    out["n_impacts"][local] = tr.n_impacts


