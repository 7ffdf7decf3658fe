"""The measurement spec's other ways to a recording: ``recording.files`` (one Tektronix CSV a
channel) and ``recording.file`` with plain columns (read by pandas), each against the example's
``.npz`` of the same samples."""

import json
from pathlib import Path

import pytest

from impactbar.cli import main
from impactbar.measure import Recording

ROOT = Path(__file__).resolve().parents[2]
SPEC = ROOT / "examples" / "shpb_pmma13.toml"
NPZ = ROOT / "examples" / "data" / "shpb_pmma13.npz"
#: the header rows of a Tektronix DPO CSV (columns 1-3), as the PMMA-13 test's files have them
HEADER = (('"Record Length"', "{n}", '"Points"'), ('"Sample Interval"', "{dt:.8e}", "s"),
          ('"Trigger Point"', "3750", '"Samples"'), ('"Trigger Time"', "7.83260388e-009", "s"),
          ('""', "", ""), ('"Horizontal Offset"', "{t0:.8e}", "s"))


def _samples():
    rec = Recording.from_npz(NPZ)
    return rec.time, rec.channels


def _report(spec, capsys):
    assert main(["measure", str(spec), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _spec_with(tmp_path, recording_table):
    text = SPEC.read_text().replace('file = "data/shpb_pmma13.npz"', recording_table)
    path = tmp_path / "spec.toml"
    path.write_text(text)
    return path


def test_plain_columns_read_by_pandas_give_the_npzs_report(tmp_path, capsys):
    import pandas as pd

    time, channels = _samples()
    pd.DataFrame({"t_s": time, **channels}).to_csv(tmp_path / "rec.csv", index=False, float_format="%.17g")
    spec = _spec_with(tmp_path, 'file = "rec.csv"\ntime = "t_s"')
    assert _report(spec, capsys) == _report(SPEC, capsys)  # (the floats written back exactly)


def test_a_missing_time_column_is_named(tmp_path, capsys):
    import pandas as pd

    time, channels = _samples()
    pd.DataFrame({"t_s": time, **channels}).to_csv(tmp_path / "rec.csv", index=False)
    assert main(["measure", str(_spec_with(tmp_path, 'file = "rec.csv"'))]) == 2
    err = capsys.readouterr().err
    assert "time" in err and err.count("\n") == 1, err


def test_tektronix_files_one_a_channel_give_the_npzs_report_to_the_signals_eight_digits(tmp_path, capsys):
    time, channels = _samples()
    n, dt = time.size, time[1] - time[0]
    for name, volts in channels.items():
        rows = []
        for i in range(n):
            head = HEADER[i] if i < len(HEADER) else ("", "", "")
            cells = [c.format(n=n, dt=dt, t0=time[0]) for c in head]
            rows.append(",".join([*cells, f"{time[i]:.17g}", f"{volts[i]:.8e}"]))  # (the signal rounded)
        (tmp_path / f"{name}.csv").write_text("\n".join(rows) + "\n")
    files = ", ".join(f'{c} = "{c}.csv"' for c in channels)
    got = _report(_spec_with(tmp_path, f"files = {{{files}}}"), capsys)
    want = _report(SPEC, capsys)
    for pulse, window in want["windows"].items():
        assert {k: v for k, v in got["windows"][pulse].items() if k != "peak"} == \
            {k: v for k, v in window.items() if k != "peak"}
        assert got["windows"][pulse]["peak"] == pytest.approx(window["peak"], rel=1e-5)
    for key in ("incident", "reflected", "transmitted", "striker_kinetic"):
        assert got["energies_J"][key] == pytest.approx(want["energies_J"][key], rel=1e-6)
    assert got["impact_velocity"]["velocity"] == pytest.approx(want["impact_velocity"]["velocity"], rel=1e-6)


def test_tektronix_files_on_two_time_bases_are_refused_naming_the_channel(tmp_path, capsys):
    time, channels = _samples()
    for k, (name, volts) in enumerate(list(channels.items())[:2]):
        t = time * (1.0 + 0.5 * k)
        rows = (f",,,{a:.8e},{v:.8e}\n" for a, v in zip(t, volts, strict=True))
        (tmp_path / f"{name}.csv").write_text("".join(rows))
    rec = 'files = {ch1 = "ch1.csv", ch2 = "ch2.csv"}'
    assert main(["measure", str(_spec_with(tmp_path, rec))]) == 2
    err = capsys.readouterr().err
    assert "channel 'ch2'" in err and "another time base" in err and err.count("\n") == 1, err
