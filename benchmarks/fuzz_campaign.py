"""Rerun of the fuzzing campaign, scaled down: every category, with counts.

Categories: constructor inputs, ``periodic_orbits`` calls (NaN, non-ValueError, the rigid-mode
impact velocity ``2 pi p0 / (1 + R)``, scale invariance of every verdict under ``load * L``),
``simulate`` runs (energy balance, penetration, non-ValueError, time), grazing runs against scipy,
SIGKILL and damage trials of sweeps, physical configurations and unit strings; and the
newer paths: the wave law (``periodic_orbits``, ``find_orbit``, ``simulate`` from 0 to 256 modes
and stiff bars), ``find_orbit`` with bad and extreme sizes, guesses, ``tol`` and ``max_iter``,
``continue_orbit`` with bad parameters and settings, sweep specs with bad values in every key,
every CLI subcommand with bad options and output locations (in-process: a traceback escaping
``main`` or an exit status other than 0, 1, 2 is bad), the rod-rock law and ``single_blow``, and
the position-switched drive; and (``fuzz_circuit.py``) the oil circuit's configs, the exact blow
with a bit mass and a feed, stepped pistons and ``optimize_piston``; and (``fuzz_maps.py``) design
maps' stores damaged and resumed, integer axes and grid sizes; and (``fuzz_design.py``) sets of
parameter changes in either order and the optimiser's arguments.

Usage: ``python benchmarks/fuzz_campaign.py [--scale 1.0] [--seed 0] [--only CATEGORY ...]``.
A count of "bad" outcomes per category is printed; ``--scale`` multiplies the number of cases.
Each case runs in a forked child with a time limit (``--slow`` seconds); a case past it counts as a
hang and is killed. Outcomes: "ok", "ValueError" (a clear refusal), or "BAD ..." (an exception of
another type, a hang, NaN, a violated invariant, a verdict that changes with the load's scale).
"""

from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import warnings
from collections import Counter
from pathlib import Path

import numpy as np

import impactbar as ib

sys.path.insert(0, str(Path(__file__).resolve().parent))
import fuzz_circuit as fz  # noqa: E402
import fuzz_design as fd  # noqa: E402
import fuzz_maps as fm  # noqa: E402

TWO_PI = 2.0 * math.pi
WEIRD = [0, -1, 1, 0.5, 5e-324, 1e-300, 1e308, 10**400, -(10**400), math.nan, math.inf, -math.inf,
         True, "1", None, 2**63, 4096, 4097, 10**14, 1.999999, 2.0, 1e-12, 1e12, np.float32(0.3),
         np.int64(3), [1.0], 1 + 1j]


#: Whether ``case`` notes a case that took more than a third of its limit (``--note-slow``).
SLOW_NOTE = False
#: A file to which ``case`` appends each bad case's arguments in full (``--bad-log``).
BAD_LOG = None


def _child(fn, conn):
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            labels = fn() or ["ok"]
    except ValueError:
        labels = ["ValueError"]
    except Exception as exc:  # noqa: BLE001 - what the campaign counts
        labels = [f"BAD {type(exc).__name__}: {str(exc)[:120]}"]
    conn.send(labels)
    conn.close()


def case(counter, fn, limit):
    """Run ``fn`` (returning a list of outcome labels) in a forked child with a time limit; count
    its labels, or "BAD hang" when it runs past ``limit`` seconds (the child is then killed)."""
    ctx = mp.get_context("fork")
    r, w = ctx.Pipe(duplex=False)
    p = ctx.Process(target=_child, args=(fn, w))
    t0 = time.perf_counter()
    p.start()
    w.close()
    try:
        labels = r.recv() if r.poll(limit) else [f"BAD hang (> {limit:g} s)"]
    except EOFError:
        labels = ["BAD child died"]
    p.kill()
    p.join()
    if SLOW_NOTE and time.perf_counter() - t0 > limit / 3 and not labels[-1].startswith("BAD"):
        print(f"  slow ({time.perf_counter() - t0:.1f} s, {labels[-1][:40]}): {fn.__defaults__!r}"[:300],
              file=sys.stderr, flush=True)
    for lab in labels:
        counter[lab] += 1
    if any(lab.startswith("BAD") for lab in labels):  # the reproducer: the case's bound arguments
        print(f"  {labels[-1]}: {fn.__defaults__!r}"[:600], file=sys.stderr, flush=True)
        if BAD_LOG:  # (in full)
            with open(BAD_LOG, "a") as fh:
                fh.write(f"{labels[-1]}\t{fn.__defaults__!r}\n")
    return labels


def constructors(rng, n, slow):
    c = Counter()
    makers = [
        lambda a, b, e, f: ib.BarModel(a, b, e, f),
        lambda a, b, e, f: ib.CosineLoad(a, b, f),
        lambda a, b, e, f: ib.SquareWaveLoad(a, b),
        lambda a, b, e, f: ib.FourierLoad(a, [b, e]),
        lambda a, b, e, f: ib.PiecewiseConstantLoad([0.0, b], [a, e]),
        lambda a, b, e, f: ib.InitialState.rigid(a, b, f),
    ]
    for _ in range(n):
        mk = makers[rng.integers(len(makers))]
        args = [WEIRD[rng.integers(len(WEIRD))] if rng.random() < 0.5 else float(rng.uniform(-1, 2))
                for _ in range(3)]
        args.append(WEIRD[rng.integers(len(WEIRD))] if rng.random() < 0.5 else int(rng.integers(0, 9)))
        case(c, lambda mk=mk, args=args: (mk(*args), ["ok"])[1], slow)
    return c


def random_model(rng, modes=(0, 0, 1, 2, 4)):
    s = float(10 ** rng.uniform(-1, 2))
    d = [0.0, 5e-324, float(rng.uniform(0, 0.5)), float(rng.uniform(0, 3))][rng.integers(4)]
    R = float(rng.uniform(0, 1))
    if rng.random() < 0.3:
        R = [0.0, 1.0, R][rng.integers(3)]
    return ib.BarModel(s, d, R, int(modes[rng.integers(len(modes))]))


def random_load(rng, L=1.0):
    kind = rng.integers(3)
    if kind == 0:
        return ib.CosineLoad(float(rng.uniform(-0.5, 2.0)), float(rng.uniform(0.1, 2.0)),
                             int(rng.integers(1, 3)))
    if kind == 1:
        kappa = float(rng.uniform(1, 2))
        if rng.random() < 0.2:
            kappa = [1.0, 2.0 - 1e-6, kappa][rng.integers(3)]
        return ib.SquareWaveLoad(float(rng.uniform(0.2, 2.0)), kappa)
    return ib.FourierLoad(float(rng.uniform(-0.5, 2.0)), rng.normal(size=3) + 1j * rng.normal(size=3))


def scaled(load, L):
    if isinstance(load, ib.SquareWaveLoad):
        return ib.SquareWaveLoad(load.q * L, load.kappa)
    if isinstance(load, ib.CosineLoad):
        return ib.CosineLoad(load.p0 * L, load.pk * L, load.k)
    if isinstance(load, ib.FourierLoad):
        return ib.FourierLoad(load.p0 * L, load.harmonics() * L)
    return ib.PiecewiseConstantLoad(load.breaks, load.levels * L)


def verdicts(orbits):
    return [(o.admissibility, bool(o.stable), bool(o.schur_stable)) for o in orbits]


def orbits_calls(rng, n, slow):
    c = Counter()
    for _ in range(n):
        m = random_model(rng)
        ld = random_load(rng)

        def one(m=m, ld=ld):
            res = ib.periodic_orbits(m, ld)
            labels = ["ok"]
            for o in res:
                arrays = [o.phase, o.impact_velocity, o.clearance, o.schur_roots, o.multipliers]
                if any(np.any(np.isnan(np.asarray(a, dtype=complex))) for a in arrays):
                    labels.append("BAD nan")
                if m.n_modes == 0 and o.admissible:
                    ref = TWO_PI * ld.p0 / (1.0 + m.R)
                    if abs(o.impact_velocity - ref) > 1e-8 * max(1.0, abs(ref)):
                        labels.append("BAD rigid impact velocity")
            for L in (1e-12, 1e12):
                try:
                    res2 = ib.periodic_orbits(m, scaled(ld, L))
                except Exception:  # noqa: BLE001
                    res2 = None
                if res2 is None or verdicts(res2) != verdicts(res):
                    labels.append("BAD scale-dependent verdict")
            return labels

        case(c, one, slow)
    return c


def max_penetration(tr):
    t = np.linspace(tr.t0, tr.t_end, 4001)
    return float(np.max(tr.end_displacement(t)))


def simulate_runs(rng, n, slow):
    c = Counter()
    for _ in range(n):
        m = random_model(rng, modes=(0, 1, 2, 4, 8))
        ld = random_load(rng)
        init = ib.InitialState.rigid(-float(rng.uniform(0, 1)), float(rng.uniform(-1, 1)), m.n_modes)
        t_end = float(rng.uniform(10, 60))

        def one(m=m, ld=ld, init=init, t_end=t_end):
            tr = ib.simulate(m, ld, init, t_end)
            labels = ["ok"]
            try:
                if not tr.energy.relative_residual < 1e-8:
                    labels.append("BAD energy residual")
            except ValueError:
                labels.append("energy refused")
            if max_penetration(tr) > 0.0:
                labels.append("BAD u(1,t) > 0")
            return labels

        case(c, one, slow)
    return c


def grazing_vs_scipy(rng, n, slow):
    """A rigid bar (and one mode) from rest near the stop, against solve_ivp with an event."""
    from scipy.integrate import solve_ivp

    c = Counter()
    for _ in range(n):
        N = int(rng.integers(0, 2))
        s = float(rng.uniform(2, 10))
        d = float(rng.uniform(0, 0.3))
        m = ib.BarModel(s, d, 0.5, N)
        p0 = float(rng.uniform(0.05, 1))
        ld = ib.CosineLoad(p0, float(rng.uniform(0.5, 2)))
        e = -float(10 ** rng.uniform(-6, -1))
        init = ib.InitialState.rigid(e, 0.0, N)
        T = 8.0
        def one(m=m, ld=ld, init=init, N=N, s=s, d=d, e=e, T=T):
            tr = ib.simulate(m, ld, init, T, max_impacts=1)
            w2 = (s * np.pi * np.arange(N + 1)) ** 2
            cw = m.end_weights

            def rhs(t, y):
                q, v = y[:N + 1], y[N + 1:]
                return np.concatenate((v, float(ld(t)) - d * v - w2 * q))

            def ev(t, y):
                return float(cw @ y[:N + 1])
            ev.terminal = True
            ev.direction = 1
            y0 = np.concatenate((init.modal_displacement, init.modal_velocity))
            sol = solve_ivp(rhs, (0, T), y0, events=ev, rtol=1e-12, atol=1e-15 * max(1.0, abs(e)),
                            method="DOP853")
            t_ref = sol.t_events[0][0] if sol.t_events[0].size else None
            if (t_ref is None) != (tr.n_impacts == 0):
                return ["BAD missed or extra impact"]
            if t_ref is not None and abs(tr.impact_times[0] - t_ref) > 1e-6:
                return ["BAD impact time"]
            return ["ok"]

        case(c, one, slow)
    return c


SPEC = """task = "orbits"
chunk_points = 5
[model]
s = 100.0
d = 0.0
R = 0.5
n_modes = 0
[load]
kind = "cosine"
p0 = 0.3
pk = 1.0
k = 1
[axes.R]
start = 0.0
stop = 0.9
num = 40
[axes.p0]
values = [0.2, 0.3]
"""


def sweeps(rng, n, slow):
    """SIGKILL trials and damaged stores: the resumed store must equal an uninterrupted one."""
    import xarray as xr

    c = Counter()
    tmp = Path(tempfile.mkdtemp(prefix="ib-campaign-"))
    try:
        spec = tmp / "spec.toml"
        spec.write_text(SPEC)

        def cli(out, *extra, timeout=120):
            return subprocess.run([sys.executable, "-m", "impactbar.cli", "sweep", str(spec), "--out",
                                   str(out), "--workers", "1", "--no-progress", *extra],
                                  capture_output=True, text=True, timeout=timeout)

        ref_path = tmp / "ref.zarr"
        cli(ref_path)
        ref = xr.open_zarr(ref_path).load()
        def check(out, label):
            r = cli(out)
            if r.returncode != 0:
                last = r.stderr.strip().splitlines()[-1][:60] if r.stderr.strip() else ""
                c[f"BAD {label}: resume failed: {last}"] += 1
                return
            try:
                got = xr.open_zarr(out).load()
                same = all(np.array_equal(got[v].values, ref[v].values, equal_nan=got[v].dtype.kind == "f")
                           for v in ref.data_vars if v != "chunk_checksum")
            except Exception as exc:  # noqa: BLE001
                c[f"BAD {label}: unreadable after resume {type(exc).__name__}"] += 1
                return
            c["ok" if same else f"BAD {label}: silent loss"] += 1

        def chunk_files(out, var=None):
            return sorted(p for p in out.rglob("*") if p.is_file() and "c" in p.relative_to(out).parts
                          and (var is None or p.relative_to(out).parts[0] == var))

        for trial in range(n):
            # SIGKILL at a random moment, then resume
            out = tmp / f"k{trial}.zarr"
            proc = subprocess.Popen([sys.executable, "-m", "impactbar.cli", "sweep", str(spec), "--out",
                                     str(out), "--workers", "1", "--no-progress"],
                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                    start_new_session=True)
            time.sleep(float(rng.uniform(3, 8)))
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
            check(out, "SIGKILL")
            # a finished store damaged afterwards: a deleted chunk, a corrupted one, an empty flag file
            for label in ("deleted chunk", "corrupted chunk", "empty flag file"):
                out = tmp / f"d{trial}-{label.replace(' ', '_')}.zarr"
                shutil.copytree(ref_path, out)
                data = [p for p in chunk_files(out, "phase")]
                victim = data[rng.integers(len(data))]
                if label == "deleted chunk":
                    victim.unlink()
                elif label == "corrupted chunk":
                    victim.write_bytes(b"garbage")
                else:
                    chunk_files(out, "chunk_done")[0].write_bytes(b"")
                check(out, label)
        # refusals: one line, nothing left behind
        (tmp / "afile").write_text("x")
        cases = {"existing file": [tmp / "afile"], "file as parent": [tmp / "afile" / "x.zarr"],
                 "dead scheduler": [tmp / "dead.zarr", "--scheduler", "tcp://127.0.0.1:1"]}
        for name, args in cases.items():
            before = sorted(p.name for p in tmp.iterdir())
            r = subprocess.run([sys.executable, "-m", "impactbar.cli", "sweep", str(spec), "--out",
                                *map(str, args), "--no-progress"], capture_output=True, text=True,
                               timeout=120)
            after = sorted(p.name for p in tmp.iterdir())
            err = r.stderr.strip().splitlines()
            one_line = r.returncode == 2 and err and "Traceback" not in r.stderr
            c["ok" if one_line and before == after else f"BAD {name}"] += 1
        r = subprocess.run([sys.executable, "-m", "impactbar.cli", "plot", str(ref_path), "--out",
                            str(tmp / "p.png"), "--select", "R=nan"], capture_output=True, text=True)
        c["ok" if r.returncode == 2 and "Traceback" not in r.stderr else "BAD plot --select R=nan"] += 1
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return c


def physical(rng, n, slow):
    from impactbar import physical as ph

    c = Counter()
    names = list(ph.PRESETS)
    units = ["200 mm", "200 mm # x", "200 mm;", "0.2 m", "200", "2,5 mm", "1e400 mm", "nan mm",
             "200 mm + 1 m", "200 mm)", "20 kg", "-5 mm", "200 rad"]
    for _ in range(n):
        base = ph.PRESETS[names[rng.integers(len(names))]]
        cfg = {k: dict(v) if isinstance(v, dict) else v for k, v in base.items()}
        if rng.random() < 0.7 and "bar" in cfg:
            cfg["bar"]["length"] = units[rng.integers(len(units))]
        def one(cfg=cfg):
            ph.orbits(ph.Hammer.from_config(cfg))
            if cfg.get("bar", {}).get("length") in ("200 mm # x", "200 mm;"):
                return ["BAD malformed unit accepted"]
            return ["ok"]

        case(c, one, slow)
    return c


def _nan_in(*arrays) -> bool:
    return any(np.any(np.isnan(np.asarray(a, dtype=complex))) for a in arrays)


def _orbit_labels(orbits):
    labels = ["ok"]
    for o in orbits:
        if _nan_in(o.impact_times, o.impact_velocities, o.clearance, o.multipliers):
            labels.append("BAD nan")
    return labels


def wave_law(rng, n, slow):
    """periodic_orbits, find_orbit and short runs under the wave law, from 0 to 256 modes, s from
    0.2 to 1e5 (windows longer than the period included)."""
    c = Counter()
    for _ in range(n):
        N = int([0, 1, 2, 8, 64, 256][rng.integers(6)])
        s = float(10 ** rng.uniform(-0.7, 5 if N <= 1 else 1.5))
        m = ib.BarModel(s, float([0.0, rng.uniform(0, 0.3)][rng.integers(2)]),
                        float([0.0, 1.0, rng.uniform(0, 1)][rng.integers(3)]), N, impact="wave")
        ld = random_load(rng)
        what = rng.integers(3)

        def one(m=m, ld=ld, what=what):
            if what == 0:
                return _orbit_labels(ib.periodic_orbits(m, ld))
            if what == 1:
                return _orbit_labels([ib.find_orbit(m, ld)])
            # (a sustained contact costs O(N^2) per unit time at N modes: shorter runs at many modes)
            t_end = 20.0 if m.n_modes <= 8 else 2.0
            tr = ib.simulate(m, ld, ib.InitialState.rigid(-0.1, 0.0, m.n_modes), t_end)
            return ["BAD nan"] if _nan_in(tr.impact_times, tr.impact_velocities) else ["ok"]

        case(c, one, slow)
    return c


def find_orbit_calls(rng, n, slow):
    """find_orbit with weird sizes, guesses, tolerances and iteration counts."""
    c = Counter()
    for _ in range(n):
        m = random_model(rng, modes=(0, 1, 4, 16))
        ld = random_load(rng)
        kw = {}
        for key in ("impacts", "periods", "tol", "max_iter"):
            if rng.random() < 0.4:
                kw[key] = WEIRD[rng.integers(len(WEIRD))]
        g = rng.integers(4)
        M = m.n_modes + 1
        k = kw.get("impacts", 1) if type(kw.get("impacts", 1)) is int else 1  # (not True, not 1e400)
        k = min(max(k, 1), 64)
        guess = [None, (np.sort(rng.uniform(0, 7, k)), rng.normal(0, 10, (k, 2 * M))),
                 (np.full(k, np.nan), np.zeros((k, 2 * M))), "x"][g]

        def one(m=m, ld=ld, kw=kw, guess=guess):
            return _orbit_labels([ib.find_orbit(m, ld, guess=guess, **kw)])

        case(c, one, slow)
    return c


def continuation_calls(rng, n, slow):
    """continue_orbit from an orbit, with bad parameter names, targets and settings."""
    c = Counter()
    for _ in range(n):
        m = random_model(rng, modes=(0, 1, 4))
        ld = ib.CosineLoad(float(rng.uniform(0.1, 1.0)), 1.0)
        par = ["p0", "pk", "R", "d", "s", "x", "n_modes", ""][rng.integers(8)]
        to = [float(rng.uniform(0, 2)), WEIRD[rng.integers(len(WEIRD))]][rng.integers(2)]
        kw = {}
        for key in ("step", "max_step", "min_step", "max_points", "tol"):
            if rng.random() < 0.25:
                kw[key] = WEIRD[rng.integers(len(WEIRD))]

        def one(m=m, ld=ld, par=par, to=to, kw=kw):
            orbits = ib.periodic_orbits(m, ld)
            if not orbits:
                return ["ok"]
            b = ib.continue_orbit(orbits[0], par, to, **kw)
            return ["BAD nan"] if _nan_in(b.values) else ["ok"]

        case(c, one, slow)
    return c


def spec_values(rng, n, slow):
    """Sweep specs with one weird value put into one key (parse only: nothing is computed)."""
    from impactbar.sweeps.spec import parse_spec

    c = Counter()
    weird = [*WEIRD, [1, 2], {"a": 1}, "", "cosine", [[1.0, 0.0]], {"values": []},
             {"start": 0, "stop": 1, "num": 10**9}, {"values": [1.0] * 3}]
    paths = [("task",), ("model", "s"), ("model", "n_modes"), ("model", "impact"), ("load", "kind"),
             ("load", "p0"), ("load", "k"), ("axes", "R"), ("axes", "p0"), ("axes", "n_modes"),
             ("chunk_points",), ("orbits", "max_orbits"), ("orbits",)]
    for _ in range(n):
        doc = {"task": "orbits", "model": {"s": 10.0, "d": 0.01, "R": 0.5, "n_modes": 0},
               "load": {"kind": "cosine", "p0": 0.5, "pk": 1.0, "k": 1},
               "axes": {"R": {"values": [0.2, 0.5]}}, "orbits": {}}
        for _ in range(int(rng.integers(1, 3))):
            path = paths[rng.integers(len(paths))]
            node = doc
            for key in path[:-1]:
                node = node.setdefault(key, {}) if isinstance(node.get(key, {}), dict) else {}
            node[path[-1]] = weird[rng.integers(len(weird))]

        def one(doc=doc):
            parse_spec(doc)
            return ["ok"]

        case(c, one, slow)
    return c


def _cli_case(argv):
    """Run ``impactbar argv`` in this (forked) process: a traceback escaping ``main``, or an exit
    status other than 0, 1, 2, is bad."""
    import contextlib
    import io

    from impactbar.cli import main as cli_main

    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            rc = cli_main(argv)
    except SystemExit as exc:  # argparse's own usage errors
        rc = exc.code
    if rc not in (0, 1, 2, None):
        return [f"BAD exit status {rc}"]
    if "Traceback" in err.getvalue():
        return ["BAD traceback on stderr"]
    return ["ok" if rc in (0, None) else "ValueError"]


def cli_calls(rng, n, slow):
    """Every subcommand with a weird option value or output location."""
    c = Counter()
    tmp = Path(tempfile.mkdtemp(prefix="ib-campaign-cli-"))
    try:
        (tmp / "afile").write_text("x")
        outs = [str(tmp / "o"), str(tmp / "afile"), str(tmp / "afile" / "x"), "/proc/x", "",
                str(tmp / ("n" * 300)), str(tmp / "missing" / "deeper" / "f.png")]
        bad = ["nan", "-1", "0", "1e400", "x", "", "10 mm", "inf", "1e-300", "-0", "1e12"]
        ok = ["3", "0.5", "20"]
        commands = [  # (argv, values): the valid values only where the run stays short
            (["orbits", "--s", "{v}", "--n-modes", "{v}"], bad + ok),
            (["orbits", "--impact", "wave", "--p0", "{v}"], bad + ok),
            (["orbits", "--preset", "pneumatic-drill", "--json"], ok),
            (["simulate", "--preset", "pneumatic-drill", "--out", "{o}", "--periods", "{v}", "--quiet"],
             bad + ok),
            (["simulate", "--preset", "hydraulic-drill", "--out", "{o}", "--gap", "{v}", "--quiet",
              "--periods", "3"], bad + ["2 mm", "0 m"]),
            (["plot", "{o}", "--out", "{o}"], ok),
            (["paper", "--out", "{o}", "--dpi", "{v}", "--quiet"], bad + ["100000"]),
            (["experiment", "--preset", "pneumatic-drill", "--out", "{o}", "--starts", "{v}", "--quiet"],
             bad),
            (["continue", "--out", "{o}"], ok),
            (["sweep", "{o}", "--out", "{o}", "--quiet"], ok),
        ]
        for _ in range(n):
            cmd, vals = commands[rng.integers(len(commands))]
            argv = [a.format(v=vals[rng.integers(len(vals))], o=outs[rng.integers(len(outs))]) for a in cmd]
            case(c, lambda argv=argv: (os.chdir(tmp), _cli_case(argv))[1], slow)  # (relative outs in tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return c


def rodrock_calls(rng, n, slow):
    """RodRock laws with random segments, rock, bit mass and feed; single_blow and simulate."""
    c = Counter()
    for _ in range(n):
        def r():
            return WEIRD[rng.integers(len(WEIRD))] if rng.random() < 0.2 else float(10 ** rng.uniform(-2, 2))

        args = {"segs": [(r(), r(), r()) for _ in range(int(rng.integers(1, 4)))], "k": r(), "k_u": r(),
                "bit": [0.0, r()][rng.integers(2)], "feed": [0.0, r()][rng.integers(2)],
                "s": float(10 ** rng.uniform(-0.5, 1.5)), "v": [1.0, r()][rng.integers(2)],
                "what": int(rng.integers(2))}

        def one(a=args):
            law = ib.RodRock(segments=[ib.RodSegment(*g) for g in a["segs"]],
                             rock=ib.BilinearRock(k=a["k"], k_u=a["k_u"]), bit_mass=a["bit"], feed=a["feed"])
            m = ib.BarModel(a["s"], 0.0, 0.0, 0, impact=law)
            if a["what"] == 0:
                b = ib.single_blow(m, a["v"])
                return ["BAD nan"] if _nan_in(b.efficiency) else ["ok"]
            tr = ib.simulate(m, ib.CosineLoad(0.6, 1.0), ib.InitialState.rigid(-0.1, 0.0), 20.0)
            return ["BAD nan"] if _nan_in(tr.impact_times, tr.impact_velocities) else ["ok"]

        case(c, one, slow)
    return c


def drive_calls(rng, n, slow):
    """PositionSwitchedDrive with random levels, switch position and delay: simulate, find_orbit,
    and the time-periodic functions that must refuse it."""
    c = Counter()
    for _ in range(n):
        def r():
            return WEIRD[rng.integers(len(WEIRD))] if rng.random() < 0.2 else float(rng.uniform(-0.5, 2))

        a = {"stroke": r(), "ret": r(), "switch_out": r(), "delay": [0.0, r()][rng.integers(2)],
             "N": int([0, 1, 4][rng.integers(3)]), "what": int(rng.integers(3))}

        def one(a=a):
            drive = ib.PositionSwitchedDrive(stroke=a["stroke"], ret=a["ret"], switch_out=a["switch_out"],
                                             delay=a["delay"])
            m = ib.BarModel(5.0, 0.05, 0.5, a["N"])
            if a["what"] == 0:
                tr = ib.simulate(m, drive, ib.InitialState.rigid(-0.1, 0.0, a["N"]), 30.0)
                return ["BAD nan"] if _nan_in(tr.impact_times, tr.impact_velocities) else ["ok"]
            if a["what"] == 1:
                o = ib.find_orbit(m, drive)
                return ["BAD nan"] if _nan_in(o.impact_velocity, o.multipliers) else ["ok"]
            ib.periodic_orbits(m, drive)
            return ["BAD periodic_orbits accepted a switched drive"]

        case(c, one, slow)
    return c


# --------------------------------------------------------------------------------------------------
# the rod-rock blow, the valve and sustained contact, with invariants that do not trust the library
# --------------------------------------------------------------------------------------------------
def _one_line(fn):
    """``fn`` with a refusal that spans lines counted as bad (an error is one line)."""
    def run():
        try:
            return fn()
        except ValueError as exc:
            if "\n" in str(exc).strip():
                return [f"BAD multi-line error: {str(exc)[:80]!r}"]
            raise
    run.__defaults__ = getattr(fn, "__defaults__", None)
    return run


def _draw(rng, lo, hi, weird):
    """A weird value with probability ``weird``, else ``10^U(lo, hi)``."""
    return WEIRD[rng.integers(len(WEIRD))] if rng.random() < weird else float(10 ** rng.uniform(lo, hi))


def _power_of_two(rng, k):
    """A scale ``2^j``, ``|j| <= k``, ``j != 0``: scaling by it is exact in floating point, so a result
    that changes with it depends on the scale itself (an absolute tolerance, a fixed step), not on
    rounding (a chaotic Newton path or a grazing re-contact decided at 1e-16 would do so at 10^x)."""
    j = int(rng.integers(1, k + 1))
    return float(2.0 ** (j if rng.random() < 0.5 else -j))


def _close(a, b, rel, abs_=0.0):
    return abs(a - b) <= rel * max(abs(a), abs(b)) + abs_


def _blow_labels(b, tol=1e-9):
    out = []
    nums = [b.efficiency, b.efficiency_with_rebound, b.work_on_rock, b.max_penetration,
            b.permanent_penetration, b.rebound_velocity, b.rock_dissipated, b.rock_stored_energy]
    if not np.all(np.isfinite(nums)):
        return ["BAD not finite"]
    if not -tol <= b.efficiency <= 1.0 + tol or not -tol <= b.efficiency_with_rebound <= 1.0 + tol:
        out.append("BAD efficiency outside [0, 1]")
    if b.energy_error > 1e-9:
        out.append("BAD blow's energy account")
    if b.permanent_penetration > b.max_penetration * (1 + tol) + tol * abs(b.max_penetration):
        out.append("BAD permanent > max penetration")
    scale = max(b.available_energy, 1e-300)
    if b.rock_dissipated < -tol * scale or b.rock_dissipated > b.work_on_rock + tol * scale:
        out.append("BAD dissipated work outside [0, work on rock]")
    return out


def rock_invariants(rng, n, slow):
    """single_blow under random rod-rock laws (one to three segments, rock, bit mass, feed; one in
    thirty arguments weird): efficiencies in [0, 1], the blow's account, permanent <= max penetration,
    0 <= dissipated <= work on rock; the blow homogeneous in (V, feed) (same efficiency, penetrations
    scaled); a bit mass of 1e-12 within 1e-6 of the massless bit; refusals one line."""
    c = Counter()
    for _ in range(n):
        def u(lo, hi):
            return _draw(rng, lo, hi, 0.03)

        k = float(10 ** rng.uniform(-2, 2))
        a = {"segs": [(u(-1, 1), u(-1, 1)) for _ in range(int(rng.integers(1, 4)))], "k": k,
             "k_u": k * float(10 ** rng.uniform(-0.2, 2)),
             "bit": [0.0, 0.0, 1e-12, u(-3, 1)][rng.integers(4)], "feed": [0.0, u(-2, 0)][rng.integers(2)],
             "s": float(10 ** rng.uniform(-0.5, 1.5)), "v": u(-3, 3), "lam": _power_of_two(rng, 20),
             "t_max": [None, None, float(rng.uniform(0.5, 10))][rng.integers(3)]}

        def one(a=a):
            def blow(v, feed, bit):
                law = ib.RodRock(segments=[ib.RodSegment(*g) for g in a["segs"]],
                                 rock=ib.BilinearRock(k=a["k"], k_u=a["k_u"]), bit_mass=bit, feed=feed)
                m = ib.BarModel(a["s"], 0.0, 0.0, 0, impact=law)
                return ib.single_blow(m, v) if a["t_max"] is None else ib.single_blow(m, v, t_max=a["t_max"])

            b = blow(a["v"], a["feed"], a["bit"])
            out = _blow_labels(b)
            lam = a["lam"]
            # a long blow with many re-contacts can depend on rounding (a grazing re-contact decided
            # at 1e-16): where a 1e-12 change of the start moves the efficiency, scale is not tested
            nudged = blow(float(a["v"]) * (1 + 1e-12), float(a["feed"]) * (1 + 1e-12), a["bit"])
            sensitive = not _close(b.efficiency, nudged.efficiency, 1e-9, 1e-12)
            try:
                b2 = None if sensitive else blow(a["v"] * lam, a["feed"] * lam, a["bit"])
            except ValueError:  # the scaled one out of range: refused, not answered wrongly
                b2 = None
            if sensitive:
                out.append("ok, rounding-sensitive: scale not tested")
            if b2 is not None:
                if not _close(b.efficiency, b2.efficiency, 1e-8, 1e-12):
                    out.append("BAD efficiency changes with the scale")
                if not _close(b.max_penetration * lam, b2.max_penetration, 1e-7, 1e-12 * lam):
                    out.append("BAD penetration not proportional to the scale")
            if a["bit"] == 1e-12:
                b0 = blow(a["v"], a["feed"], 0.0)
                if not _close(b.efficiency, b0.efficiency, 1e-6, 1e-9):
                    out.append("BAD bit mass 1e-12 far from the massless bit")
            return out or ["ok"]

        case(c, _one_line(one), slow)
    return c


def drive_invariants(rng, n, slow):
    """The position-switched drive on rigid and flexible bars (extreme levels and switches
    included): find_orbit's orbit finite, its period and admissibility unchanged and its velocities
    scaled when every force and switch is scaled by lambda (a power of two); simulate's energy
    account closing; bounded time; refusals one line."""
    c = Counter()
    for _ in range(n):
        def u(lo, hi):
            return _draw(rng, lo, hi, 0.05)

        a = {"stroke": u(-3, 2), "ret": u(-3, 3), "switch_out": u(-3, 3),
             "delay": [0.0, 0.0, u(-3, 0)][rng.integers(3)], "N": int([0, 1, 2, 4][rng.integers(4)]),
             "s": float(10 ** rng.uniform(0, 1)), "d": float(rng.uniform(0, 0.3)),
             "R": float(rng.uniform(0, 0.9)), "lam": _power_of_two(rng, 10),
             "what": int(rng.integers(2))}

        def one(a=a):
            m = ib.BarModel(a["s"], a["d"], a["R"], a["N"])

            def drive(lam):  # (the raw arguments first: the scaled ones only once they are accepted)
                x = {k: a[k] if lam == 1.0 else float(a[k]) * lam for k in ("stroke", "ret", "switch_out")}
                return ib.PositionSwitchedDrive(**x, delay=a["delay"])

            if a["what"] == 0:
                tr = ib.simulate(m, drive(1.0), ib.InitialState.rigid(-0.1 * a["switch_out"], 0.0, a["N"]),
                                 30.0)
                if _nan_in(tr.impact_times, tr.impact_velocities):
                    return ["BAD nan"]
                e = tr.energy
                return ["BAD energy account"] if e.relative_residual > 1e-8 else ["ok"]
            o = ib.find_orbit(m, drive(1.0))
            if _nan_in(o.impact_velocities, o.multipliers) or not math.isfinite(o.period):
                return ["BAD not finite"]
            try:
                o2 = ib.find_orbit(m, drive(a["lam"]))
            except ValueError:
                return ["BAD scaled drive refused where the unscaled one answered"]
            out = []
            if not _close(o.period, o2.period, 1e-7):
                out.append("BAD period changes with the scale")
            if not _close(o.impact_velocities[0] * a["lam"], o2.impact_velocities[0], 1e-7):
                out.append("BAD velocity not proportional to the scale")
            if o.admissible != o2.admissible:
                out.append("BAD admissibility changes with the scale")
            return out or ["ok"]

        case(c, _one_line(one), slow)
    return c


def sustained_invariants(rng, n, slow):
    """The wave law's sustained contact under pressing loads: the run's energy account closing, every
    contact's efficiency in [0, 1], and the run unchanged (times) and scaled (velocities) when the load
    and the start are scaled by lambda."""
    c = Counter()
    for _ in range(n):
        a = {"s": float(10 ** rng.uniform(0, 1.5)), "d": float([0.0, rng.uniform(0, 0.3)][rng.integers(2)]),
             "R": float(rng.uniform(0.05, 0.9)), "N": int([0, 1, 4, 8][rng.integers(4)]),
             "p0": float(rng.uniform(0.5, 4)), "pk": float(rng.uniform(0, 2)), "k": int(rng.integers(1, 3)),
             "lam": _power_of_two(rng, 13)}

        def one(a=a):
            m = ib.BarModel(a["s"], a["d"], a["R"], a["N"], impact="wave")

            def run(lam):
                return ib.simulate(m, ib.CosineLoad(a["p0"] * lam, a["pk"] * lam, a["k"]),
                                   ib.InitialState.rigid(-0.1 * lam, 0.0, a["N"]), 4 * math.pi)

            tr = run(1.0)
            if _nan_in(tr.impact_times, tr.impact_velocities):
                return ["BAD nan"]
            out = []
            if tr.energy.relative_residual > 1e-8:
                out.append("BAD energy account")
            for b in tr.impacts:
                eff = getattr(b, "efficiency", 0.5)
                if not -1e-12 <= eff <= 1.0 + 1e-12:
                    out.append("BAD efficiency outside [0, 1]")
            tr2 = run(a["lam"])
            if tr2.n_impacts != tr.n_impacts:
                out.append("BAD impacts change with the scale")
            elif tr.n_impacts:
                if not np.allclose(tr.impact_times, tr2.impact_times, rtol=1e-8, atol=1e-8):
                    out.append("BAD impact times change with the scale")
                if not np.allclose(tr.impact_velocities * a["lam"], tr2.impact_velocities, rtol=1e-6,
                                   atol=1e-9 * a["lam"]):
                    out.append("BAD velocities not proportional to the scale")
            return out or ["ok"]

        case(c, _one_line(one), slow)
    return c


CATEGORIES = {"constructors": (constructors, 400), "orbits": (orbits_calls, 150),
              "simulate": (simulate_runs, 60), "grazing": (grazing_vs_scipy, 60),
              "sweeps": (sweeps, 3), "physical": (physical, 60),
              "wave": (wave_law, 80), "find_orbit": (find_orbit_calls, 80),
              "continuation": (continuation_calls, 40), "specs": (spec_values, 150),
              "cli": (cli_calls, 60), "rodrock": (rodrock_calls, 60), "drive": (drive_calls, 60),
              "rock42": (rock_invariants, 1000), "drive42": (drive_invariants, 600),
              "sustained42": (sustained_invariants, 400),
              # the oil circuit, the exact blow under a bit and a feed, stepped pistons (fuzz_circuit.py)
              "circuit": (lambda rng, n, slow: fz.circuit_calls(rng, n, slow, case), 1000),
              "exact_blow": (lambda rng, n, slow: fz.exact_blow_calls(rng, n, slow, case), 500),
              "stepped": (lambda rng, n, slow: fz.stepped_calls(rng, n, slow, case), 200),
              # design maps: damaged stores resumed, integer axes, grid sizes (fuzz_maps.py)
              "map_stores": (lambda rng, n, slow: fm.map_store_calls(rng, n, slow, case), 40),
              "map_axes": (lambda rng, n, slow: fm.map_axis_calls(rng, n, slow, case), 100),
              "grid_size": (lambda rng, n, slow: fm.grid_size_calls(rng, n, slow, case), 100),
              # a designer's sets of changes and the optimiser's arguments (fuzz_design.py)
              "change_sets": (lambda rng, n, slow: fd.change_set_calls(rng, n, slow, case), 1200),
              "optimizer_args": (lambda rng, n, slow: fd.optimizer_calls(rng, n, slow, case), 120)}
#: Each category's time limit per case (s) where it is not ``--slow``'s.
LIMITS = {"circuit": 40.0, "exact_blow": 20.0, "stepped": 40.0}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scale", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--slow", type=float, default=60.0, help="seconds after which a case counts as a hang")
    ap.add_argument("--only", nargs="*", default=list(CATEGORIES), choices=list(CATEGORIES))
    ap.add_argument("--bad-log", default=None, help="a file to append each bad case's arguments to, in full")
    ap.add_argument("--note-slow", action="store_true", help="note the cases past a third of their limit")
    args = ap.parse_args(argv)
    global SLOW_NOTE, BAD_LOG
    SLOW_NOTE, BAD_LOG = args.note_slow, args.bad_log
    print(f"impactbar {ib.__version__} from {Path(ib.__file__).parent}")
    # compile the kernels once here, so the forked cases do not each compile them
    ib.simulate(ib.BarModel(5, 0.1, 0.5, 1), ib.CosineLoad(1.2, 1), ib.InitialState.rigid(-0.1, 0, 1), 5)
    ib.simulate(ib.BarModel(5, 0.1, 0.5, 1), ib.SquareWaveLoad(1, 1.5), ib.InitialState.rigid(-0.1, 0, 1), 5)
    if set(args.only) & set(LIMITS):
        fz.warm_up()
    total_bad = 0
    for name in args.only:
        fn, n = CATEGORIES[name]
        rng = np.random.default_rng([args.seed, list(CATEGORIES).index(name)])
        n = max(1, round(n * args.scale))
        t = time.perf_counter()
        c = fn(rng, n, min(args.slow, LIMITS.get(name, args.slow)))
        bad = sum(v for k, v in c.items() if k.startswith("BAD"))
        total_bad += bad
        detail = ", ".join(f"{k}: {v}" for k, v in sorted(c.items()))
        print(f"{name:13s} cases {n:5d}  bad {bad:4d}  ({time.perf_counter() - t:6.1f} s)  {detail}",
              flush=True)
    print(f"total bad: {total_bad}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
