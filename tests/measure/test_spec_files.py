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


def _write_plain_tektronix(path, t, volts):
    path.write_text("".join(f",,,{a:.17g},{v:.17g}\n" for a, v in zip(t, volts, strict=True)))


def test_tektronix_files_on_two_rates_are_resampled_to_the_one_rate_report(tmp_path, capsys):
    """One channel at half the rate (every other sample of the example's, 62.5 MHz): resampled back
    onto the other channels' times (a 2:1 polyphase filter), the report's energies and the striker's
    velocity within 1e-3 of the example's (measured: 4.2e-4 at most). Not closer: the half-rate
    channel has lost what the record holds above its Nyquist frequency (31 MHz: the recorder's noise,
    1 % of the peak, folded back by the naive decimation), which no resampling gives back; the
    record's first and last 20 samples, in its baseline, are left out."""
    time, channels = _samples()
    names = list(channels)
    for k, name in enumerate(names):
        step = 2 if k == 1 else 1
        _write_plain_tektronix(tmp_path / f"{name}.csv", time[::step], channels[name][::step])
    files = ", ".join(f'{c} = "{c}.csv"' for c in names)
    got = _report(_spec_with(tmp_path, f"files = {{{files}}}"), capsys)
    want = _report(SPEC, capsys)
    for key in ("incident", "reflected", "transmitted", "striker_kinetic"):
        assert got["energies_J"][key] == pytest.approx(want["energies_J"][key], rel=1e-3)
    assert got["impact_velocity"]["velocity"] == pytest.approx(want["impact_velocity"]["velocity"], rel=1e-3)


def test_tektronix_files_that_do_not_overlap_are_refused_naming_the_channel(tmp_path, capsys):
    time, channels = _samples()
    for k, (name, volts) in enumerate(list(channels.items())[:2]):
        _write_plain_tektronix(tmp_path / f"{name}.csv", time + k * (time[-1] - time[0] + 1e-3), volts)
    rec = 'files = {ch1 = "ch1.csv", ch2 = "ch2.csv"}'
    assert main(["measure", str(_spec_with(tmp_path, rec))]) == 2
    err = capsys.readouterr().err
    assert "channel 'ch2'" in err and "overlaps the other channels' times by fewer than 8" in err, err
    assert err.count("\n") == 1, err
