"""A fingerprint of the library's results: orbits, runs, branches, a sweep and SI tables, every
number at full precision, to show that a refactoring changed no result (to the bit) or which changed
and by how much.

Run: ``python benchmarks/fingerprint.py [--out FILE.json]`` writes the numbers (JSON, floats as
``repr``) and prints one sha256 per group; ``--against REF`` also runs this script on the tree of the
git ref ``REF`` (exported to a fixed folder under the temporary directory, so that its numba cache
survives between runs) in a subprocess, and prints, group by group, "same" or the largest relative
difference and where. ``--only GROUP ...`` restricts the groups.

Each number is kept with its path (the dict keys and list indices that lead to it); the two trees'
numbers are compared path by path, an older tree's keys read under their names now where the library
knows the old name (``impactbar.physical.outputs.renamed_key``: the outputs' ``RENAMED_OUTPUTS``, a key in
another unit divided by the factor; the result attributes renamed by ``renamed_attribute``), so that
a renamed key, which moves its number in the sorted order the sha is taken in, says "same (bitwise;
keys renamed: a -> b)" where every number is the same.

The groups: ``orbits`` (``periodic_orbits`` under a cosine and a square-wave load, the wave law;
phases, impact velocities, multipliers), ``find_orbit`` (the valve drive, the oil circuit rigid and
with 2 modes, the rod-rock law's orbit), ``simulate`` (a cosine-loaded run, a valve drifter's run, the
circuit's run: impact times and velocities, energy accounts), ``continuation`` (a branch in ``p0`` and
one of the circuit in its pre-charge), ``sweep`` (the orbits task on a 3x2 grid), ``si`` (summaries of
the presets and examples in SI), ``exact`` (the exact blows on rod and rock: the example rock drifter's
piston on its rod at three impact velocities, once with a bit of a tenth of the piston's mass, every
number of the blow's record and its sampled forces; and the circuit on rock's orbit with exact blows).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

GROUPS = ("orbits", "find_orbit", "simulate", "continuation", "sweep", "si", "exact")
ROOT = Path(__file__).resolve().parents[1]


def _flat(x, path=()):
    """Numbers of a result as a flat list of ``(path, float)`` (complex as two, ``re`` and ``im``),
    in the order of the sha (a dict's keys sorted); a path is the dict keys and list indices that
    lead to the number."""
    if isinstance(x, dict):
        return [v for k in sorted(x)
                for v in _flat(x[k], (*path, k if isinstance(k, (str, int)) else str(k)))]
    if isinstance(x, (list, tuple)):
        return [v for i, e in enumerate(x) for v in _flat(e, (*path, i))]
    if isinstance(x, np.ndarray):
        return _flat(x.tolist(), path)
    if isinstance(x, (bool, np.bool_)):
        return [(path, float(x))]
    if isinstance(x, (int, float, np.integer, np.floating)):
        return [(path, float(x))]
    if isinstance(x, (complex, np.complexfloating)):
        return [((*path, "re"), float(x.real)), ((*path, "im"), float(x.imag))]
    return []  # text (statuses, names) is not a number


def _orbit_numbers(o):
    return {"phase": o.phase, "v": o.impact_velocity, "mult": np.asarray(o.multipliers)}


def group_orbits():
    import impactbar as ib

    out = {}
    bar = ib.BarModel(s=5.0, d=0.1, R=0.5, n_modes=8)
    out["cosine"] = [_orbit_numbers(o) for o in ib.periodic_orbits(bar, ib.CosineLoad(p0=0.6, pk=1.0))]
    out["square"] = [_orbit_numbers(o) for o in ib.periodic_orbits(bar, ib.SquareWaveLoad(q=0.6, kappa=1.5))]
    wave = ib.BarModel(s=5.0, d=0.1, R=0.5, n_modes=8, impact="wave")
    out["wave"] = [_orbit_numbers(o) for o in ib.periodic_orbits(wave, ib.CosineLoad(p0=0.6, pk=1.0))]
    return out


def group_find_orbit():
    import impactbar as ib
    from impactbar.physical import circuit_preset, drifter_preset, load

    out = {}
    d = drifter_preset("hydraulic-drifter").orbit()
    out["valve"] = [d.period_s, d.impact_velocity_m_s, np.asarray(d.multipliers)]
    c = circuit_preset("circuit-drifter")
    o = c.orbit()
    out["circuit_rigid"] = [o.period_s, o.impact_velocity_m_s, np.asarray(o.multipliers),
                            o.mean_supply_pressure_Pa, o.hydraulic_efficiency]
    m = ib.find_orbit(c.model().with_(n_modes=2), c.drive())
    out["circuit_2_modes"] = [m.period, m.impact_velocity, np.asarray(m.multipliers)]
    r = load(ROOT / "examples" / "drifter_rock.toml").orbit()
    out["valve_rock"] = [r.period_s, r.impact_velocity_m_s, np.asarray(r.multipliers)]
    return out


def _run_numbers(run):
    return {"t": np.asarray(run.impact_times), "v": np.asarray(run.impact_velocities),
            "energy": [run.energy.work, run.energy.final, run.energy.impact_loss,
                                                          run.energy.damping_loss]}


def _si_run(x):
    if hasattr(x, "impact_times"):
        return _run_numbers(x)
    if isinstance(x, dict):
        return {k: v for k, v in x.items() if isinstance(v, (np.ndarray, float))}
    return x if isinstance(x, (float, np.ndarray)) else []


def group_simulate():
    import impactbar as ib
    from impactbar.physical import circuit_preset, drifter_preset

    out = {}
    bar = ib.BarModel(s=5.0, d=0.1, R=0.5, n_modes=8)
    run = ib.simulate(bar, ib.CosineLoad(p0=0.6, pk=1.0), ib.InitialState.rigid(-0.1, 0.0, n_modes=8), 60.0)
    out["cosine"] = _run_numbers(run)
    d = drifter_preset("hydraulic-drifter")
    out["valve"] = [_si_run(x) for x in d.simulate(0.2)]
    c = circuit_preset("circuit-drifter")
    out["circuit"] = [_si_run(x) for x in c.simulate(0.1)]
    return out


def group_continuation():
    import impactbar as ib
    from impactbar.physical import circuit_preset, continue_circuit

    out = {}
    bar = ib.BarModel(s=5.0, d=0.1, R=0.5, n_modes=8)
    start = ib.periodic_orbits(bar, ib.CosineLoad(p0=0.6, pk=1.0))[0]
    br = ib.continue_orbit(start, "p0", 0.8, max_points=30)
    out["p0"] = [np.asarray(br.phases), np.asarray(br.impact_velocities), np.asarray(br.multipliers)]
    cb = continue_circuit(circuit_preset("circuit-drifter"), "accumulator.precharge", "11 MPa", max_points=8)
    out["precharge"] = [np.asarray(cb.values)]
    return out


def group_sweep():
    from impactbar.sweeps import compute_chunk, parse_spec

    spec = parse_spec({"task": "orbits", "model": {"s": 5.0, "d": 0.1, "R": 0.5, "n_modes": 8},
                       "load": {"kind": "cosine", "p0": 0.6, "pk": 1.0, "k": 1},
                       "axes": {"p0": {"start": 0.4, "stop": 0.8, "num": 3}, "R": {"values": [0.3, 0.5]}}})
    return {str(c): {k: np.asarray(v) for k, v in compute_chunk(spec, c).items()
                     if np.asarray(v).dtype.kind in "fcib"} for c in range(spec.n_chunks)}


def group_si():
    from impactbar.physical import circuit_preset, drifter_preset, load, orbits, preset

    out = {"hammer": [o.to_dict() for o in orbits(preset("pneumatic-drill"))]}
    out["drifter"] = drifter_preset("hydraulic-drifter").orbit().summary()
    out["circuit"] = circuit_preset("circuit-drifter").orbit().summary()
    out["circuit_rock"] = load(ROOT / "examples" / "circuit_drifter_rock.toml").orbit().summary()
    return out


def group_exact():
    import dataclasses

    import impactbar as ib
    from impactbar.physical import load

    out = {}
    drifter = load(ROOT / "examples" / "circuit_drifter_rock.toml")
    model = drifter.model()
    exact = model.with_(impact=dataclasses.replace(model.law, method="exact"))
    heavy = model.with_(impact=dataclasses.replace(model.law, method="exact", bit_mass=0.1))
    for name, m, speeds in (("blows", exact, (0.5, 1.0, 1.5)), ("bit_mass", heavy, (1.0,))):
        blows = [ib.single_blow(m, v) for v in speeds]
        out[name] = [[b.to_dict(), b.times, b.shank_forces, b.bit_forces, b.penetrations] for b in blows]
    o = ib.find_orbit(exact, drifter.drive())
    out["orbit"] = [o.period, o.impact_velocity, np.asarray(o.multipliers)]
    return out


def fingerprint(groups):
    """``{group: (list of (path, float), seconds)}`` of the named groups."""
    import warnings

    out = {}
    for g in groups:
        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                numbers = _flat(globals()[f"group_{g}"]())
            except Exception as exc:  # noqa: BLE001 - reported as the group's outcome
                numbers = [((), f"{type(exc).__name__}: {exc}")]
        out[g] = (numbers, time.perf_counter() - t)
    return out


def _digest(numbers) -> str:
    return hashlib.sha256(json.dumps([repr(x) for x in numbers]).encode()).hexdigest()[:16]


def _renames():
    """``key -> [(key now, factor)]``: the library's old names of its outputs and results
    (``impactbar.physical.outputs.renamed_key``, the attributes ``renamed_attribute`` gave a new name;
    a value stored under the old key divided by the factor is the new key's), as far as the library
    has them; a function of the key."""
    try:
        from impactbar._shared.renamed import RENAMED_ATTRIBUTES
        from impactbar.physical.outputs import renamed_key
    except ImportError:  # (a library without them: no key is translated)
        return lambda key: []

    def candidates(key):
        if not isinstance(key, str):
            return []
        out = []
        new, factor = renamed_key(key)
        if new != key:
            out.append((new, factor))
        out += [(n, 1.0) for n in RENAMED_ATTRIBUTES.get(key, ()) if n not in {c for c, _ in out}]
        return out

    return candidates


def _translate(mine, theirs):
    """``theirs`` (``(path, number)``) with each path that ``mine`` lacks under its names now: one
    key of it replaced by a name now (:func:`_renames`) that gives a path of ``mine`` that ``theirs``
    does not hold, its number divided by the factor; with the renames made (``"a -> b"``)."""
    here = {tuple(p) for p, _ in mine}
    only_here = here - {tuple(p) for p, _ in theirs}  # (the paths a rename may lead to)
    candidates = _renames()
    out, renamed = [], []
    for path, x in theirs:
        path = tuple(path)
        if path not in here:
            for i, key in enumerate(path):
                hit = next(((new, f) for new, f in candidates(key)
                            if (*path[:i], new, *path[i + 1:]) in only_here), None)
                if hit is not None:
                    new, f = hit
                    path = (*path[:i], new, *path[i + 1:])
                    x = x / f if f != 1.0 and isinstance(x, float) else x
                    said = f"{key} -> {new}" + (f" (/{f:g})" if f != 1.0 else "")
                    if said not in renamed:
                        renamed.append(said)
                    break
        out.append((path, x))
    return out, renamed


def _compare(mine, theirs) -> str:
    """"same (bitwise)" or where the largest relative difference is: number by number where both
    sides name their numbers by the same paths (an older tree's keys under their names now,
    :func:`_translate`), else in order."""
    renamed = []
    if theirs and theirs[0][0] is not None:  # (their numbers with paths: compared by path)
        theirs, renamed = _translate(mine, theirs)
        by_path = dict(theirs)
        if len(by_path) == len(theirs) == len(mine) and all(tuple(p) in by_path for p, _ in mine):
            theirs = [(p, by_path[tuple(p)]) for p, _ in mine]
        else:
            renamed = []
    a, b = [x for _, x in mine], [x for _, x in theirs]
    if len(a) != len(b):
        return f"DIFFERENT COUNT {len(a)} vs {len(b)}"
    if any(isinstance(x, str) for x in (*a, *b)):
        return "same" if a == b else f"ERROR here {a[:1]} / there {b[:1]}"
    worst, where = 0.0, -1
    for i, (x, y) in enumerate(zip(a, b, strict=True)):
        if x == y or (math.isnan(x) and math.isnan(y)):
            continue
        rel = abs(x - y) / max(abs(x), abs(y), 1e-300)
        if rel > worst:
            worst, where = rel, i
    keys = f"; keys renamed: {', '.join(renamed)}" if renamed else ""
    if where < 0:
        return f"same (bitwise{keys})"
    at = "/".join(str(k) for k in mine[where][0])
    return f"differs: largest relative {worst:.2e} at number {where}" + (f" ({at}{keys})" if at else "")


def _read_numbers(stored) -> list:
    """A group's ``(path, number)`` as ``--out`` wrote them (the path ``None`` where a file of an
    older script holds the numbers alone)."""
    numbers = stored["numbers"] if isinstance(stored, dict) else stored
    paths = stored["paths"] if isinstance(stored, dict) else [None] * len(numbers)
    return [(None if p is None else tuple(p), float(x) if not x.startswith(("'", '"')) else x)
            for p, x in zip(paths, numbers, strict=True)]


def _export(ref: str) -> Path:
    """The tree of ``ref`` under a fixed folder of this checkout's own (named by its path's hash, so
    that two worktrees or sessions never export into one folder at once), files whose content is
    unchanged left as they are (numba keys its cache on a source file's time and size: a new ref
    recompiles only what changed)."""
    sha = subprocess.run(["git", "rev-parse", ref], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout.strip()
    owner = hashlib.sha256(str(ROOT.resolve()).encode()).hexdigest()[:12]
    dest = Path(tempfile.gettempdir()) / f"impactbar-against-{owner}"
    stamp = dest / ".ref"
    if stamp.exists() and stamp.read_text() == sha:
        return dest
    dest.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        archive = subprocess.run(["git", "archive", sha], cwd=ROOT, capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", tmp], input=archive, check=True)
        new = {p.relative_to(tmp) for p in Path(tmp).rglob("*") if p.is_file()}
        for rel in new:
            data = (Path(tmp) / rel).read_bytes()
            target = dest / rel
            if not (target.is_file() and target.read_bytes() == data):
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(data)
        for old in [p for p in dest.rglob("*.py") if p.relative_to(dest) not in new]:
            old.unlink()
    stamp.write_text(sha)
    return dest


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", help="write the numbers as JSON")
    ap.add_argument("--against", metavar="REF", help="compare with the tree of this git ref")
    ap.add_argument("--only", nargs="+", choices=GROUPS, default=list(GROUPS))
    args = ap.parse_args(argv)
    expect = os.environ.get("FINGERPRINT_TREE")
    if expect:  # the child of --against: its library must be that tree's
        import impactbar

        if not Path(impactbar.__file__).resolve().is_relative_to(Path(expect).resolve()):
            raise SystemExit(f"imported {impactbar.__file__}, not the tree at {expect}")
    mine = fingerprint(args.only)
    if args.out:  # (each group's numbers as repr, and their paths)
        Path(args.out).write_text(json.dumps({g: {"numbers": [repr(x) for _, x in n],
                                                  "paths": [list(p) for p, _ in n]}
                                              for g, (n, _) in mine.items()}))
    theirs = None
    if args.against:
        tree = _export(args.against)
        with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
            path = f.name
        env = dict(os.environ, PYTHONPATH=str(tree / "src"), FINGERPRINT_TREE=str(tree))
        subprocess.run([sys.executable, str(Path(__file__).resolve()), "--out", path, "--only", *args.only],
                       env=env, check=True, stdout=subprocess.DEVNULL)
        theirs = {g: _read_numbers(v) for g, v in json.loads(Path(path).read_text()).items()}
    for g, (numbers, secs) in mine.items():
        line = f"{g:14s} {len(numbers):6d} numbers  {_digest([x for _, x in numbers])}  ({secs:.1f} s)"
        if theirs is not None:
            line += f"  against {args.against}: {_compare(numbers, theirs[g])}"
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
