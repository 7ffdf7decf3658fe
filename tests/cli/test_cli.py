"""The command line's shared conventions: options a mode ignores are refused, one option name for the
number of modes, strict JSON, a quiet end on a closed pipe, one-line hints for missing optional
dependencies, progress bars only on a terminal, no dashboard port for a local sweep."""

import argparse
import io
import json
import math
import subprocess
import sys

import pytest

from impactbar.cli import _common, build_parser, main


@pytest.mark.parametrize("argv, flags", [
    (["orbits", "--preset", "pneumatic-drill", "--R", "0.9", "--s", "3"], ["--s", "--R"]),
    (["orbits", "--preset", "pneumatic-drill", "--n-modes", "8"], ["--n-modes"]),
    (["orbits", "--pres", "pneumatic-drill", "--R=0.5"], ["--R"]),  # abbreviation; the default value
    (["orbits", "--load", "square", "--p0", "0.7"], ["--p0"]),
    (["orbits", "--p0", "0.3", "--kappa", "1.5"], ["--kappa"]),  # --load cosine is the default
    (["experiment", "hydraulic", "--p0", "1", "--starts", "1"], ["--p0"]),
    (["experiment", "pneumatic", "--q", "1", "--kappa", "1.2", "--starts", "1"], ["--q", "--kappa"]),
    (["experiment", "pneumatic", "--no-plots", "--out", "x", "--starts", "1"], ["--no-plots", "--out"]),
    (["experiment", "pneumatic", "--modes", "2", "--n-modes", "2", "--starts", "1"],
     ["--n-modes", "--modes"]),
])
def test_ignored_or_conflicting_options_are_refused(argv, flags, capsys):
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"impactbar {argv[0]}: error: ")
    for flag in flags:
        assert flag in lines[0]


def test_options_of_the_chosen_mode_are_accepted(capsys):
    assert main(["orbits", "--load", "square", "--q", "1", "--kappa", "1.2", "--n-modes", "0"]) == 0
    assert "SquareWaveLoad(q=1.0, kappa=1.2)" in capsys.readouterr().out
    assert main(["orbits", "--preset", "pneumatic-drill"]) == 0  # no dimensionless option given


def test_explicit_options_counts_defaults_given_and_abbreviations():
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices["orbits"]
    assert _common.explicit_options(sub, ["--R", "0.5", "--pre", "pneumatic-drill"]) >= {"R", "preset"}
    assert "s" not in _common.explicit_options(sub, ["--R", "0.5"])
    # the parser's defaults are restored afterwards
    assert sub.parse_args([]).R == 0.5


def test_n_modes_everywhere_and_the_old_experiment_alias(tmp_path, capsys):
    for name in ("orbits", "experiment"):
        sub = next(a for a in build_parser()._actions
                   if isinstance(a, argparse._SubParsersAction)).choices[name]
        assert "--n-modes" in sub.format_help()
    assert main(["experiment", "pneumatic", "--starts", "2", "--periods", "10", "--modes", "0",
                 "--no-plots", "--quiet"]) == 0
    out, err = capsys.readouterr()
    assert "n_modes=0" in out
    assert "--modes is deprecated; use --n-modes" in err
    assert main(["experiment", "pneumatic", "--starts", "2", "--periods", "10", "--n-modes", "0",
                 "--no-plots", "--quiet"]) == 0
    out, err = capsys.readouterr()
    assert "n_modes=0" in out and err == ""


def test_json_is_strict_with_null_for_non_finite_numbers(capsys):
    # R = 0: the clearance of an orbit that sticks is -inf; JSON has no infinity
    assert main(["orbits", "--R", "0", "--d", "0", "--n-modes", "0", "--s", "50", "--p0", "0.31",
                 "--json"]) == 0
    text = capsys.readouterr().out
    doc = json.loads(text, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))
    assert doc["orbits"]
    assert "Infinity" not in text and "NaN" not in text and '"inf"' not in text
    assert _common.json_ready({"a": math.inf, "b": [math.nan, 1.5], "c": (1, 2j)}) == \
        {"a": None, "b": [None, 1.5], "c": [1, [0.0, 2.0]]}
    import numpy as np

    assert _common.json_ready({"x": np.float64(-np.inf), "y": np.arange(2)}) == {"x": None, "y": [0, 1]}


def test_si_json_uses_the_same_convention(capsys):
    assert main(["orbits", "--preset", "hydraulic-drill", "--json"]) == 0
    text = capsys.readouterr().out
    json.loads(text, parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))


def test_a_closed_pipe_ends_quietly():
    code = ("import sys; from impactbar.cli import main; "
            "sys.exit(main(['orbits', '--n-modes', '0', '--json']))")
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            bufsize=0)
    proc.stdout.read(5)
    proc.stdout.close()  # the reader goes away, as `| head -c 5` does
    err = proc.stderr.read().decode()
    proc.wait(timeout=120)
    assert "Traceback" not in err and "BrokenPipeError" not in err, err
    assert proc.returncode in (0, 141)


def test_missing_optional_dependency_is_one_line(monkeypatch, capsys):
    from impactbar.cli import orbits

    def fail(args):
        raise ModuleNotFoundError("No module named 'pint'", name="pint")

    monkeypatch.setattr(orbits, "run", fail)  # main builds its parser anew, with the patched run
    assert main(["orbits"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["impactbar orbits: error: this needs pint, which is not installed: "
                   "pip install 'impactbar[units]'"]


def test_unrelated_import_errors_are_not_hidden(monkeypatch):
    from impactbar.cli import orbits

    def fail(args):
        raise ModuleNotFoundError("No module named 'impactbar.nothing'", name="impactbar.nothing")

    monkeypatch.setattr(orbits, "run", fail)
    with pytest.raises(ModuleNotFoundError):
        main(["orbits"])


def test_every_optional_module_names_an_extra_that_all_installs():
    import tomllib
    from pathlib import Path

    doc = tomllib.loads((Path(__file__).parents[2] / "pyproject.toml").read_text())
    extras = doc["project"]["optional-dependencies"]
    in_all = " ".join(extras["all"])
    for module, extra in _common.OPTIONAL_EXTRAS.items():
        assert extra in extras, extra
        assert extra in in_all, extra
        assert any(req.startswith(module) or f"{module}]" in req or req.startswith("dask[")
                   for req in extras[extra]), (module, extra)


def test_progress_bars_only_on_a_terminal(monkeypatch):
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    with _common.progress_bar(3, desc="x", unit="run") as bar:
        assert bar.disable  # not a terminal
    class Tty(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr(sys, "stderr", Tty())
    with _common.progress_bar(3, desc="x", unit="run") as bar:
        assert not bar.disable
        bar.update(3)
        assert bar.n == 3
    assert "x:" in sys.stderr.getvalue() and "/3" in sys.stderr.getvalue()
    with _common.progress_bar(3, desc="x", unit="run", quiet=True) as bar:
        assert bar.disable


def test_paper_and_experiment_report_progress(monkeypatch, tmp_path):
    class Tty(io.StringIO):
        def isatty(self):
            return True

    err = Tty()
    monkeypatch.setattr(sys, "stderr", err)
    assert main(["experiment", "pneumatic", "--starts", "3", "--periods", "10", "--n-modes", "0",
                 "--no-plots"]) == 0
    assert "pneumatic starts:" in err.getvalue() and "/3 [" in err.getvalue()
    err.seek(0)
    err.truncate()
    assert main(["experiment", "pneumatic", "--starts", "3", "--periods", "10", "--n-modes", "0",
                 "--no-plots", "--quiet"]) == 0
    assert err.getvalue() == ""


def test_local_sweep_serves_no_dashboard(monkeypatch, tmp_path):
    """The cluster run_sweep starts serves nothing over HTTP (distributed always opens a scheduler
    HTTP port): no dashboard, no metrics, loopback only, not the dashboard's usual port 8787."""
    import urllib.error
    import urllib.request

    import distributed

    from impactbar.sweeps import open_sweep, parse_spec, run_sweep

    real = distributed.LocalCluster
    probed = []

    def spy(*args, **kwargs):
        cluster = real(*args, **kwargs)
        port = cluster.scheduler.http_server.port
        codes = []
        for path in ("/status", "/health", "/metrics", "/info/main/workers.html"):
            try:
                codes.append(urllib.request.urlopen(f"http://127.0.0.1:{port}{path}", timeout=10).status)
            except urllib.error.HTTPError as err:
                codes.append(err.code)
        probed.append((port, codes))
        return cluster

    monkeypatch.setattr(distributed, "LocalCluster", spy)
    spec = parse_spec({"task": "orbits", "model": {"s": 10.0, "d": 0.0, "R": 0.5, "n_modes": 0},
                       "load": {"kind": "cosine", "p0": 0.3, "pk": 1.0, "k": 1},
                       "axes": {"R": {"start": 0.0, "stop": 0.5, "num": 2}}})
    run_sweep(spec, tmp_path / "s.zarr", n_workers=1, progress=False, executor="dask")
    assert len(probed) == 1
    port, codes = probed[0]
    assert port != 8787 and codes == [404, 404, 404, 404]
    assert bool(open_sweep(tmp_path / "s.zarr")["chunk_done"].all())


def test_help_points_at_the_docs_site_not_at_files():
    parser = build_parser()
    subs = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    for name, sub in subs.items():
        text = sub.format_help()
        assert "docs/" not in text and "MODEL.md" not in text, name


def test_a_namespace_without_the_record_refuses_nothing():
    """run() called with a namespace parsed elsewhere cannot tell defaults from given values."""
    parser = build_parser()
    args = parser.parse_args(["orbits", "--preset", "pneumatic-drill"])
    assert not _common.given(args, "R")
    _common.refuse(args, ["R", "s"], because="never")  # does not raise
