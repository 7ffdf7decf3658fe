"""How many numba kernels a first call compiles, counted (not timed) in a fresh process with an
empty numba cache: each compile is CPU time a designer waits for once (``bench_first_call.py``
times them). A kernel that compiles for a second signature (the same arrays with another layout, a
literal flag) is a compile no result needs."""

import functools
import json
import os
import subprocess
import sys
from collections import Counter

import numpy as np
import pytest

#: a child's preamble: ``compiled`` lists each numba compile's function, in order
_COUNT = """
import json
import numpy as np
from numba.core import event

compiled = []


class Count(event.Listener):
    def on_start(self, ev):
        pass

    def on_end(self, ev):
        fn = ev.data["dispatcher"].py_func
        compiled.append(fn.__module__ + "." + fn.__qualname__)


event.register("numba:compile", Count())
"""

_RIGID = _COUNT + """
from impactbar import BarModel, CosineLoad, InitialState, simulate

simulate(BarModel(5.0, 0.1, 0.5, 0), CosineLoad(0.6, 1.0), InitialState.rigid(-0.2, 0.0), 30.0)
print(json.dumps(compiled))
"""


def _first_call(script, tmp_path):
    """The last line of ``script``'s output, read as JSON, run in a fresh process with the empty numba
    cache ``tmp_path``."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), NUMBA_CACHE_DIR=str(tmp_path),
               OMP_NUM_THREADS="1", IMPACTBAR_TIERED="0")
    env.pop("NUMBA_DISABLE_JIT", None)
    done = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True,
                          check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_rigid_simulate_compiles_each_kernel_once_and_no_more_than_15d5b20(tmp_path):
    """A rigid ``simulate`` under a cosine load compiles each of impactbar's kernels for one
    signature, 32 compiles in all (numba's own helpers included) as in release 15d5b20: the crossing
    search's scratch rows are C arrays, as the arrays Python passes it, not the 'A' arrays of an
    unpacked block that made the search and six flight kernels compile twice (39 compiles)."""
    compiled = _first_call(_RIGID, tmp_path)
    twice = {k: n for k, n in Counter(compiled).items() if k.startswith("impactbar.") and n > 1}
    assert twice == {}
    assert 20 <= len(compiled) <= 32


#: the README's first exact blow and a bit with mass on two segments (complex exponents): ``records``
_BLOWS = """
from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow

law = RodRock(segments=[RodSegment(length=40.0, impedance=1.0)], rock=BilinearRock(k=2.5, k_u=25.0))
first = single_blow(BarModel(s=2.0, d=0.0, R=0.0, n_modes=0, impact=law), 1.0, t_max=39.0)
mass = RodRock(segments=[RodSegment(2.0, 1.0), RodSegment(1.0, 0.6)], rock=BilinearRock(1.0, 5.0),
               bit_mass=0.3)
second = single_blow(BarModel(s=1.0, d=0.0, R=0.0, n_modes=0, impact=mass), 1.0)
records = [[b.junction_forces.tobytes().hex(), b.bit_forces.tobytes().hex(), b.penetrations.tobytes().hex()]
           for b in (first, second)]
"""


@pytest.mark.slow
def test_the_first_exact_blow_compiles_each_kernel_once_and_samples_its_record_interpreted(tmp_path):
    """The README's first exact blow (and a second one, a bit with mass on two segments: complex
    exponents), with an empty numba cache: each of impactbar's kernels compiles for one signature,
    and the record's history evaluators (``eval_histories``, ``eval_bit`` and their callee
    ``_eval_into``, some 1 s of compiling) not at all: their interpreted twins sample the histories,
    to the machine code's bits (compared here with the machine code of this process). (Since the
    blow's run has its twin too, none of the blow's kernels compiles there: a test below.)"""
    from impactbar.dynamics import _tiers

    out = _first_call(_COUNT + _BLOWS + "print(json.dumps({'compiled': compiled, 'records': records}))",
                      tmp_path)
    twice = {k: n for k, n in Counter(out["compiled"]).items() if k.startswith("impactbar.") and n > 1}
    assert twice == {}
    history = [k for k in out["compiled"] if k.startswith("impactbar.laws.rodrock._exacthistory.")]
    assert history == []  # (on f29151a3: eval_histories, eval_bit, _eval_into)
    assert len(out["compiled"]) <= 80  # (88 on f29151a3)
    eager = _tiers._PROCESS.eager
    _tiers._PROCESS.eager = True  # here: the machine code
    here = {}
    try:
        exec(_BLOWS, here)
    finally:
        _tiers._PROCESS.eager = eager
    assert out["records"] == here["records"]


#: the README's rod and rock on the lattice (a bit with mass): each compile's function, argument
#: types and whether it made machine code of its own (else link-only, compiled into its callers'),
#: and the blow's record
_LATTICE = """
import json
from numba.core import event
from impactbar.laws.rodrock.blow import rod_rock_blow

with event.install_recorder("numba:compile") as recorder:
    blow = rod_rock_blow(2.0, 1.0, [40.0], [1.0], [1.0], 2.5, 25.0, 0.2, 0.0, t_max=39.0)
compiled = [[d.py_func.__module__ + "." + d.py_func.__qualname__, str(ev.data["args"]),
             d._compiler.pipeline_class.__name__ != "LinkOnlyCompiler"]
            for _, ev in recorder.buffer if ev.is_end for d in [ev.data["dispatcher"]]]
print(json.dumps({"compiled": compiled, "forces": blow.bit_forces.tolist(), "efficiency": blow.efficiency}))
"""


def test_the_lattice_blows_helpers_are_compiled_into_its_loop_and_numbas_overloads_once(tmp_path):
    """A first blow on the lattice (a bit with mass: every helper of the bit's step reached), with an
    empty numba cache: each of impactbar's kernels compiles once, and only the loop and the test of
    the piston free for good, which Python calls, make machine code and wrappers of their own (the
    bit's and the contact's helpers are link-only: 19 of them made their own on c5645d83); numba's
    own overloads (``max``, ``min``, ``np.empty``) compile once for each argument types, not again
    for the link-only kernels' options. The record is the numpy loop's (the reference of
    ``"rock.blow"``), the same arithmetic step for step."""
    from impactbar.dynamics.implementations import use_reference
    from impactbar.laws.rodrock.blow import rod_rock_blow

    out = _first_call(_LATTICE, tmp_path)
    names = Counter(name for name, _, _ in out["compiled"])
    assert {k: n for k, n in names.items() if k.startswith("impactbar.") and n > 1} == {}
    rock = {name: own for name, _, own in out["compiled"] if name.startswith("impactbar.laws.rodrock.")}
    assert len(rock) >= 19
    assert sorted(k for k, own in rock.items() if own) == ["impactbar.laws.rodrock._rockloop.blow_loop",
                                                            "impactbar.laws.rodrock._rockloop.piston_free"]
    overloads = Counter((name, args) for name, args, _ in out["compiled"] if name.startswith("numba."))
    assert overloads and {k: n for k, n in overloads.items() if n > 1} == {}
    with use_reference("rock.blow"):
        ref = rod_rock_blow(2.0, 1.0, [40.0], [1.0], [1.0], 2.5, 25.0, 0.2, 0.0, t_max=39.0)
    np.testing.assert_allclose(out["forces"], ref.bit_forces, rtol=1e-10, atol=1e-12 * max(ref.bit_forces))
    assert out["efficiency"] == pytest.approx(ref.efficiency, rel=1e-10)


#: exact blows, each record's every float hashed: ``digests`` (the README's, three rods of
#: ``bench_exact_blow.py``, a bit with mass, then Lundberg's 40-long rod, whose twin runs past its budget)
_EXACT_BLOWS = """
import dataclasses, hashlib
import numpy as np
from impactbar import BarModel, BilinearRock, RodRock, RodSegment, single_blow


def digest(x, h):
    if dataclasses.is_dataclass(x):
        for f in dataclasses.fields(x):
            if f.name == "_hist":  # (the pool's pieces and terms written, not its capacity's rest)
                scale, (PF, PI, TK, TC, *rest), *more = x._hist
                n, t = x.pieces, x.diagnostics["terms"]
                digest((scale, PF[:n], PI[:n], TK[:t], TC[:t], rest, more), h)
            else:
                digest(getattr(x, f.name), h)
    elif isinstance(x, dict):
        for k in sorted(x, key=str):
            digest(x[k], h)
    elif isinstance(x, (list, tuple)):
        for y in x:
            digest(y, h)
    elif isinstance(x, np.ndarray) and x.dtype != object:
        h.update(np.ascontiguousarray(x).tobytes())
    elif isinstance(x, (float, int, complex, np.number)):
        h.update(np.asarray(x).tobytes())
    elif isinstance(x, str):
        h.update(x.encode())
    return h


def blow(segments, k, k_u, s=1.0, bit_mass=0.0, **kw):
    law = RodRock(segments=[RodSegment(a, z) for a, z in segments], rock=BilinearRock(k, k_u),
                  bit_mass=bit_mass)
    out = single_blow(BarModel(s=s, d=0.0, R=0.0, n_modes=0, impact=law), 1.0, **kw)
    return digest(out, hashlib.sha256()).hexdigest()


digests = [blow([(40.0, 1.0)], 2.5, 25.0, s=2.0, t_max=39.0), blow([(1.0, 1.0)], 1.0, 5.0),
           blow([(1.0, 1.0), (0.5, 0.5), (2.0, 1.0)], 0.5, 1.0),
           blow([(2.0, 1.0), (1.0, 0.6)], 1.0, 5.0, bit_mass=0.3)]
"""
_LUNDBERG = """
digests.append(blow([(40.0, 1.0)], 2.5, 2.5e9, s=2.0))
"""


@pytest.mark.slow
def test_the_first_exact_blows_run_their_twin_to_the_machine_codes_bits(tmp_path):
    """A process's first exact blows (the README's, three rods of ``bench_exact_blow.py`` with a bit
    with mass among them), with an empty numba cache, compile none of the exact blow's kernels (75
    compiles, some 17 s of CPU on 8a4f9cae): they run the blow's interpreted twin, whose records are
    the machine code's to the bit (every float of each record hashed, against the machine code of
    this process). Lundberg's 40-long rod after them runs its twin past its budget (1 s of CPU): the
    machine code takes the blow over from its start (compiled then), the same bits."""
    from impactbar.dynamics import _tiers

    out = _first_call(_COUNT + _EXACT_BLOWS + "first = list(compiled)" + _LUNDBERG
                      + "print(json.dumps({'first': first, 'compiled': compiled, 'digests': digests}))",
                      tmp_path)
    exact = [k for k in out["first"] if k.startswith("impactbar.laws.rodrock._exact")]
    assert exact == []  # (on 8a4f9cae: every one of the blow's 66 kernels)
    assert "impactbar.laws.rodrock._exactloop.run" in out["compiled"]  # (the twin past its budget)
    eager = _tiers._PROCESS.eager
    _tiers._PROCESS.eager = True  # here: the machine code
    here = {}
    try:
        exec(_EXACT_BLOWS + _LUNDBERG, here)
    finally:
        _tiers._PROCESS.eager = eager
    assert out["digests"] == here["digests"]


@pytest.mark.slow
def test_the_exact_blows_twin_gives_the_machine_codes_bits_on_a_seeded_sample_of_rods():
    """The exact blow's twin against its machine code on 200 blows drawn over the exact method's
    parameters (1 to 3 segments of lengths 0.3 to 4 and impedances 0.3 to 2, the piston's impedance
    0.5 to 3, the rock's k 0.1 to 10 and gamma 1.6 to 100, a third with a bit's mass, the impact
    velocity 0.3 to 3, to a t_max of 1 to 6): every float of each record the same (8a4f9cae's twin,
    numpy's complex quotients and powers in the blow, differed on 64 of 100 blows of such a sample,
    36 of them in the record's forces or energies, the rest in the pool's pieces)."""
    from impactbar.dynamics import _tiers
    from impactbar.laws.rodrock import _exactloop as K

    ns: dict = {}
    exec(_EXACT_BLOWS.split("digests = [")[0], ns)
    machine, rng = K.run, np.random.default_rng(2026)
    eager = _tiers._PROCESS.eager
    _tiers._PROCESS.eager = True  # (run_kernel takes K.run as it is)
    twins = []

    def twin(*a):
        twins.append(a)
        return _tiers.twin(machine)(*a)

    try:
        for _ in range(200):
            n = rng.choice([1, 1, 2, 2, 3])
            segments = [(rng.uniform(0.3, 4.0), rng.uniform(0.3, 2.0)) for _ in range(n)]
            k = 10.0 ** rng.uniform(-1.0, 1.0)
            args = (segments, k, k * 10.0 ** rng.uniform(0.2, 2.0))
            kw = dict(s=rng.uniform(0.5, 3.0), bit_mass=rng.choice([0.0, 0.0, rng.uniform(0.05, 1.0)]),
                      t_max=rng.uniform(1.0, 6.0))
            v = rng.uniform(0.3, 3.0)
            ns["single_blow"] = functools.partial(_impact_at, v)
            K.run, twins[:] = twin, []
            try:
                with np.errstate(all="raise", under="ignore"):
                    interpreted = ns["blow"](*args, **kw)
            finally:
                K.run = machine
            assert twins and ns["blow"](*args, **kw) == interpreted, (args, kw, v)
    finally:
        _tiers._PROCESS.eager = eager


def _impact_at(v, model, _velocity, **kw):
    """``single_blow`` at the impact velocity ``v``."""
    from impactbar import single_blow

    return single_blow(model, v, **kw)


_CIRCUIT_HELPERS = _COUNT + """
from impactbar.drives.circuit import _sundials
if _sundials.bind():
    from impactbar.drives.circuit import _cvode  # noqa: F401  (its C callbacks compile at import)
from impactbar.drives.circuit._dop853 import keep_row
T, Y = keep_row(np.zeros(2), np.ones((2, 3)), 2, 5.0, np.arange(4.0))  # (full: doubled)
print(json.dumps([compiled, T.tolist(), Y.tolist()]))
"""


def test_the_circuits_flight_helpers_compile_once_and_without_a_shape_error_message(tmp_path):
    """The oil circuit's flight helpers (CVODE's block solve behind its C callback, the kept rows'
    growth that the explicit and CVODE's flights share) compile one signature each and copy arrays
    element by element: numba's slice assignment compiles, per caller's options and per dimension, a
    shape-mismatch message built from strings (``raise_with_shape_context`` and numba's string
    routines: 89 of the 178 compiles of the circuit's first ``orbit()`` before); the block solve's
    plain flight passed a constant and compiled a second time. The rows are the same (kept, doubled,
    the new one set)."""
    compiled, T, Y = _first_call(_CIRCUIT_HELPERS, tmp_path)
    assert [k for k in compiled if "shape_context" in k or "unicode" in k] == []
    assert {k: n for k, n in Counter(compiled).items() if k.startswith("impactbar.") and n > 1} == {}
    assert "impactbar.drives.circuit._dop853.keep_row" in compiled
    assert len(T) == len(Y) == 4 and T[:3] == [0.0, 0.0, 5.0]
    assert Y[:3] == [[1.0] * 3, [1.0] * 3, [0.0, 1.0, 2.0]]
