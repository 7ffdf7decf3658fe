"""One meaning and one default per option name across the subcommands, the old spellings kept with
a warning, and the table of the CLI page that documents them."""

import argparse
import re
from pathlib import Path

import pytest

from impactbar.cli import build_parser, main

DOCS = Path(__file__).resolve().parents[2] / "docs" / "getting_started.md"


def _subparsers():
    parser = build_parser()
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices


def _defaults(sub):
    return {a.option_strings[0]: a.default for a in sub._actions
            if a.option_strings and a.help != argparse.SUPPRESS}


def test_bar_and_load_defaults_agree_between_orbits_and_continue():
    subs = _subparsers()
    o, c = _defaults(subs["orbits"]), _defaults(subs["continue"])
    shared = ["--s", "--d", "--R", "--n-modes", "--load", "--p0", "--pk", "--k", "--q", "--kappa",
              "--impact"]
    assert {k: o[k] for k in shared} == {k: c[k] for k in shared}
    assert (o["--d"], o["--n-modes"], o["--p0"]) == (0.05, 4, 0.3)


def test_options_of_the_same_name_mean_the_same_thing():
    """``--periods`` is a run's length in load periods wherever it appears (``continue``'s motion
    period is ``--load-periods``); ``--quiet`` is the only switch for the progress bar; every
    folder ``--out`` has a default."""
    subs = _subparsers()
    for name, sub in subs.items():
        helps = {a.option_strings[0]: a.help or "" for a in sub._actions if a.option_strings}
        if "--periods" in helps and helps["--periods"] != argparse.SUPPRESS:
            assert name in ("simulate", "experiment")
            assert "length of" in helps["--periods"] and "load periods" in helps["--periods"]
        assert "--no-progress" not in sub.format_help()
        out = next((a for a in sub._actions if "--out" in a.option_strings), None)
        if out is not None and name not in ("sweep", "plot"):  # those name one file or store
            assert not out.required and str(out.default).startswith("out/") or out.default is None
    assert "--load-periods" in subs["continue"].format_help()


def test_old_spellings_warn_and_still_work(tmp_path, capsys, monkeypatch):
    import impactbar.cli.continue_ as cont

    seen = {}

    def fake_start(model, load, args):
        seen["m, n"] = (args.impacts, args.load_periods)
        raise ValueError("stop here")

    monkeypatch.setattr(cont, "_start", fake_start)
    argv = ["continue", "--parameter", "p0", "--to", "0.8", "--out", str(tmp_path), "--impacts", "2"]
    assert main([*argv, "--periods", "2"]) == 2
    err = capsys.readouterr().err
    assert "warning: --periods is deprecated; use --load-periods" in err and seen["m, n"] == (2, 2)
    assert main([*argv, "--load-periods", "3"]) == 2
    err = capsys.readouterr().err
    assert "deprecated" not in err and seen["m, n"] == (2, 3)
    assert main([*argv, "--load-periods", "3", "--periods", "2"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--load-periods and --periods cannot be used together" in err[0]
    # --orbit is refused when the start comes from a simulation, the old spelling included
    assert main(["continue", "--parameter", "p0", "--to", "0.8", "--out", str(tmp_path),
                 "--periods", "2", "--orbit", "0"]) == 2
    assert "--orbit is ignored" in capsys.readouterr().err


def test_sweep_no_progress_is_quiet(monkeypatch, tmp_path, capsys):
    from impactbar.cli import sweep as cli_sweep

    seen = {}

    def fake_run(args):
        seen["quiet"] = args.quiet
        return 0

    monkeypatch.setattr(cli_sweep, "run", fake_run)
    assert main(["sweep", "spec.toml", "--out", str(tmp_path / "s.zarr"), "--no-progress"]) == 0
    assert seen["quiet"] is True
    assert "--no-progress is deprecated; use --quiet" in capsys.readouterr().err
    assert main(["sweep", "spec.toml", "--out", str(tmp_path / "s.zarr")]) == 0
    assert seen["quiet"] is False and capsys.readouterr().err == ""


def test_simulate_out_has_a_default(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sub = _subparsers()["simulate"]
    assert sub.parse_args(["--preset", "pneumatic-drill"]).out == "out/simulate"


def test_the_cli_page_table_lists_every_shared_option_with_its_default():
    text = DOCS.read_text(encoding="utf-8")
    table = text[text.index("### One meaning per option"):]
    rows = [r for r in table.splitlines() if r.startswith("| `--")]
    documented = {o for r in rows for o in re.findall(r"`(--[A-Za-z0-9-]+)`", r.split("|")[1])}
    subs = _subparsers()
    used = {}
    for name, sub in subs.items():
        for a in sub._actions:
            if a.option_strings and a.help != argparse.SUPPRESS and a.option_strings[0] != "-h":
                used.setdefault(a.option_strings[0], set()).add(name)
    shared = {o for o, names in used.items() if len(names) > 1}
    assert shared <= documented, sorted(shared - documented)
    defaults = _defaults(subs["orbits"])
    row = next(r for r in rows if r.startswith("| `--s`"))
    assert row.split("|")[3].strip() == ", ".join(
        f"{defaults[o]:g}" for o in ("--s", "--d", "--R", "--n-modes"))


def test_the_cli_page_table_lists_every_command_that_takes_each_option():
    """Each option's rows name every command that takes it (``drifter --json`` and ``optimize
    --quiet`` were left out); the page's command table names every command."""
    text = DOCS.read_text(encoding="utf-8")
    table = text[text.index("### One meaning per option"):]
    subs = _subparsers()
    listed = {}
    for row in (r for r in table.splitlines() if r.startswith("| `--")):
        cells = row.split("|")
        for option in re.findall(r"`(--[A-Za-z0-9-]+)`", cells[1]):
            listed.setdefault(option, set()).update(set(re.findall(r"`([a-z]+)`", cells[4])) & set(subs))
    for name, sub in subs.items():
        for a in sub._actions:
            option = a.option_strings[0] if a.option_strings else None
            if option in listed and a.help != argparse.SUPPRESS:  # (an old spelling: hidden)
                assert name in listed[option], (option, name)
    commands = text[text.index("## The command line"):text.index("### One meaning per option")]
    assert set(subs) <= set(re.findall(r"`impactbar ([a-z]+)`", commands)), set(subs)


@pytest.mark.parametrize("command", ["orbits", "continue"])
def test_help_states_the_shared_defaults(command):
    text = _subparsers()[command].format_help()
    assert "(default 0.05)" in text and "(default 4)" in text and "(default 0.3)" in text


class _Tty:
    """A stderr that says it is a terminal."""

    def __init__(self):
        import io

        self.buf = io.StringIO()

    def isatty(self):
        return True

    def write(self, text):
        return self.buf.write(text)

    def flush(self):
        pass


def test_continue_shows_stages_and_simulate_a_bar_on_a_terminal_only(monkeypatch, tmp_path, capsys):
    """``continue`` and ``simulate`` name the stage running and the time elapsed
    on a terminal's stderr; nothing with ``--quiet`` or off a terminal."""
    import sys

    from impactbar.cli import _common

    tty = _Tty()
    monkeypatch.setattr(sys, "stderr", tty)
    argv = ["continue", "--n-modes", "0", "--parameter", "p0", "--to", "0.8", "--brute", "0",
            "--json", "--out", str(tmp_path / "c")]
    assert main(argv) == 0
    text = tty.buf.getvalue()
    assert "continue: 0/2 stages done, start" in text and "branches in p0" in text
    assert "2/2 stages done, done" in text
    tty.buf = type(tty.buf)()
    assert main([*argv, "--quiet"]) == 0
    assert tty.buf.getvalue() == ""
    # simulate's bar counts load periods with an estimate (the library's progress callback),
    # with the run shortened
    import impactbar.physical as ph

    real = ph.simulate
    monkeypatch.setattr(ph, "simulate", lambda h, **kw: real(h, periods=2, gap_m=kw["gap_m"],
                                                             progress=kw.get("progress")))
    tty.buf = type(tty.buf)()
    assert main(["simulate", "--preset", "pneumatic-drill", "--out", str(tmp_path / "s")]) == 0
    text = tty.buf.getvalue()
    assert "simulate:" in text and "/40" in text and "period/s" in text
    tty.buf = type(tty.buf)()
    assert main(["simulate", "--preset", "pneumatic-drill", "--out", str(tmp_path / "s2"), "--quiet"]) == 0
    assert "period/s" not in tty.buf.getvalue()
    capsys.readouterr()
    monkeypatch.setattr(sys, "stderr", __import__("io").StringIO())  # not a terminal
    with _common.stage_bar(2, desc="x", first="a") as bar:
        assert bar.bar.disable


def test_json_load_is_structured(capsys):
    import json

    assert main(["orbits", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["load"] == {"kind": "cosine", "p0": 0.3, "pk": 1.0,
                                                           "k": 1}
    assert main(["orbits", "--load", "square", "--kappa", "1.4", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["load"] == {"kind": "square", "q": 1.0, "kappa": 1.4}


def test_documented_commands_write_only_into_ignored_folders():
    """Every ``impactbar`` command of the README and the docs that writes a folder writes it under
    a path .gitignore ignores (a new user's clone stays clean), its default included."""
    root = DOCS.parents[1]
    ignored = [line.strip("/") for line in (root / ".gitignore").read_text().splitlines()
               if line.startswith("/")]
    texts = [root / "README.md", *sorted((root / "docs").glob("*.md"))]
    subs = _subparsers()
    seen = 0
    for path in texts:
        for cmd in re.findall(r"impactbar (paper|continue|simulate|experiment)\b([^`\n]*)",
                              path.read_text(encoding="utf-8")):
            name, rest = cmd
            m = re.search(r"--out[ =](\S+)", rest)
            out = m.group(1) if m else subs[name].get_default("out") or "out/experiment"
            assert out.split("/")[0] in ignored, (path.name, name, rest)
            seen += 1
    assert seen >= 5
