"""A measurement's TOML spec: its files, channels, bars and specimen, read and run.

::

    [recording]
    file = "data/shpb_pmma13.npz"         # relative to the spec; or files = {ch1 = "a.csv", ...}
                                          # (Tektronix CSVs), or file = "x.csv" with time = "t"
                                          # (plain columns, read by pandas)
    baseline_us = [-30.0, -5.0]           # the quiet samples (default: the first tenth)

    [bars.incident]                       # and [bars.transmitted]
    young_modulus = "71.7 GPa"            # or the model's key E
    density = "2810 kg/m^3"
    area = "4.4521 mm^2"                  # or a round bar's diameter = "2.38 mm"
    # wave_speed = "5051.3 m/s"           # default sqrt(E / density)

    [channels.ch1]                        # one table a channel
    bar = "incident"
    station = "102.02 mm"                 # from the specimen's face
    bridge = "half"                       # quarter, half, half-poisson, full, full-poisson
    gauge_factor = 2.1
    excitation = "10 V"
    gain = 100.0

    [specimen]
    length = "1.47 mm"
    area = "1.862 mm^2"

    [striker]                             # optional
    length = "25.4 mm"                    # (material and section: the incident bar's)

Each quantity is a string with its unit, read as the model's configuration reads it; a bare number
is read in SI (m, m^2, Pa, kg/m^3, m/s, V), the older spelling.

    [detection]                           # optional
    threshold = 10.0                      # noise standard deviations
    cutoff_hz = 1.0e6                     # the detection's low-pass

    [dispersion]                          # optional: the waves carried in a round bar's first mode
    poisson = 0.33                        # the bars' Poisson ratio (radius sqrt(area / pi))

A drill rod's spec has ``[rod]``, two channels on it (``bar = "rod"``, stations from the bit) and a
``[bit]`` table instead of ``[specimen]`` (:func:`~impactbar.measure.analyse_drill_rod`). Its
``[[rod.segments]]`` are the model's: the keys, units and checks of a hammer's or a drifter's
``[rod]`` (examples/circuit_drifter_rock.toml), read by the same reader
(:func:`impactbar.physical.rock.rod_from_config`), from the struck end to the bit, each segment
giving its own ``E`` and ``density`` (a measurement has no piston to take them from); the gauges sit
on the last segment, whose section and material the two-point separation takes::

    [[rod.segments]]                      # the shank, from the struck end
    length = "0.5 m"
    area = "1.2e-3 m^2"                   # or diameter = "39 mm"
    E = "200 GPa"
    density = "8000 kg/m^3"
    [[rod.segments]]                      # the rod, down to the bit: the gauges' segment
    length = "3.0 m"
    area = "0.8e-3 m^2"
    E = "200 GPa"
    density = "8000 kg/m^3"

    [bit]
    cutoff_hz = 40.0e3                    # optional: default 0.8 c / (2 (x_far - x_near))
    leak = 1.0                            # optional

    [model]                               # optional: the model's blow, on [rod], fitted to the gauges
    piston_lengths = [0.3]                # m
    piston_areas = [1.0e-3]               # m^2
    start = {impact_velocity = 8.0, "rock.k" = 2.0e8, "rock.k_u" = 2.0e9}
    vary = ["impact_velocity", "rock.k", "rock.k_u"]

The older spelling stays: the gauges' bar as ``[bars.rod]`` (the Kolsky bars' keys) and the model's
rod as ``model.rod_lengths`` and ``model.rod_areas`` (m, m^2, from the struck end, of ``[bars.rod]``'s
material).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .drill import DrillRodTest, analyse_drill_rod
from .kolsky import KolskyTest, analyse_kolsky
from .recording import Bar, Gauge, Recording

__all__ = ["read_spec", "run_spec"]

_SECTIONS = {"recording", "bars", "rod", "channels", "specimen", "striker", "detection", "bit", "model",
             "dispersion"}


def read_spec(path) -> dict:
    """The spec's tables (``tomllib``), the unknown ones refused."""
    import tomllib

    path = Path(path)
    try:
        with path.open("rb") as fh:
            spec = tomllib.load(fh)
    except FileNotFoundError:
        raise ValueError(f"spec: no such file {str(path)!r}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"spec {path}: not valid TOML: {exc}") from None
    unknown = set(spec) - _SECTIONS
    if unknown:
        raise ValueError(f"spec {path}: unknown table(s) {sorted(unknown)}; allowed {sorted(_SECTIONS)}")
    for needed in ("recording", "channels"):
        if needed not in spec:
            raise ValueError(f"spec {path}: the table [{needed}] is missing")
    if ("specimen" in spec) == ("bit" in spec):
        raise ValueError(f"spec {path}: a Kolsky bar's [specimen] or a drill rod's [bit] is needed (one "
                         "of them)")
    if "rod" in spec and "bit" not in spec:
        raise ValueError(f"spec {path}: [rod] (the model's [[rod.segments]]) describes a drill rod, whose "
                         "spec has a [bit]; a Kolsky bar's bars are [bars.incident] and [bars.transmitted]")
    if "bars" not in spec and "rod" not in spec:
        raise ValueError(f"spec {path}: the table [bars] is missing" + (" (or a drill rod's [rod])"
                                                                         if "bit" in spec else ""))
    spec["_folder"] = path.parent
    return spec


def _table(spec: dict, dotted: str, allowed: set, required: set) -> dict:
    table = spec
    for key in dotted.split("."):
        table = table.get(key, {}) if isinstance(table, dict) else {}
    if not isinstance(table, dict):
        raise ValueError(f"{dotted} must be a table")
    unknown = set(table) - allowed
    if unknown:
        raise ValueError(f"{dotted}: unknown key(s) {sorted(unknown)}; allowed {sorted(allowed)}")
    missing = required - set(table)
    if missing:
        raise ValueError(f"{dotted}.{sorted(missing)[0]} is missing")
    return table


def _recording(spec: dict) -> tuple[Recording, slice | None]:
    rec = _table(spec, "recording", {"file", "files", "time", "baseline_us", "full_scale"}, set())
    folder = spec["_folder"]
    full_scale = rec.get("full_scale")
    if "files" in rec:
        files = {k: folder / v for k, v in rec["files"].items()}
        recording = Recording.from_tektronix(files, full_scale=full_scale)
    elif "file" in rec:
        path = folder / rec["file"]
        if not path.exists():
            raise ValueError(f"recording.file: no such file {str(path)!r}")
        if path.suffix == ".npz":
            recording = Recording.from_npz(path, full_scale=full_scale)
        else:
            import pandas as pd

            frame = pd.read_csv(path, float_precision="round_trip")  # (each number as written)
            recording = Recording.from_frame(frame, time=rec.get("time", "time"), full_scale=full_scale)
    else:
        raise ValueError("recording.file (an .npz or a CSV of columns) or recording.files (Tektronix CSVs) "
                         "is missing")
    baseline = None
    if "baseline_us" in rec:
        t0, t1 = (1e-6 * float(x) for x in rec["baseline_us"])
        k0, k1 = np.searchsorted(recording.time, [t0, t1])
        if k1 - k0 < 8:
            raise ValueError(f"recording.baseline_us must span >= 8 samples of the record, got "
                             f"{rec['baseline_us']}")
        baseline = slice(int(k0), int(k1))
    return recording, baseline


_BAR_KEYS = {"young_modulus", "E", "density", "area", "diameter", "wave_speed"}
#: each key with a unit: the unit its number is in, an example (a string with its unit, read by
#: :func:`~impactbar.physical.units.to_si`; a bare number is read in this unit, the older spelling)
_UNITS = {"young_modulus": ("Pa", "'71.7 GPa'"), "E": ("Pa", "'71.7 GPa'"),
          "density": ("kg/m**3", "'2810 kg/m^3'"), "area": ("m**2", "'4.45 mm^2'"),
          "diameter": ("m", "'2.38 mm'"), "wave_speed": ("m/s", "'5051 m/s'"), "length": ("m", "'25.4 mm'"),
          "station": ("m", "'102 mm'"), "excitation": ("V", "'10 V'")}


def _si(table: dict, dotted: str) -> dict:
    """``table`` with each key of :data:`_UNITS` in SI: a quantity with its unit (``"71.7 GPa"``)
    converted, a bare number taken as SI (the older spelling); another value refused, naming it."""
    from ..physical.units import to_si

    out = dict(table)
    for key, value in table.items():
        if key not in _UNITS:
            continue
        unit, example = _UNITS[key]
        if isinstance(value, bool) or not isinstance(value, (int, float, str)):
            raise ValueError(f"{dotted}.{key} must be a quantity in {unit.replace('**', '^')}, e.g. "
                             f"{example}; got {value!r}")
        out[key] = to_si(f"{dotted}.{key}", value, unit, example) if isinstance(value, str) else float(value)
    return out


def _bar(spec: dict, dotted: str, required: bool = True) -> Bar | None:
    """The bar ``[dotted]``: its material (``young_modulus`` or the model's ``E``, ``density``), its
    section (``area``, or a round bar's ``diameter``) and optional ``wave_speed``, each a quantity
    with its unit or a bare SI number; ``None`` for an empty optional table."""
    table = _si(_table(spec, dotted, _BAR_KEYS | ({"length"} if not required else set()), set()), dotted)
    for one, other in (("young_modulus", "E"), ("area", "diameter")):
        if one in table and other in table:
            raise ValueError(f"{dotted}: give {one} or {other}, not both")
    if "E" in table:
        table["young_modulus"] = table.pop("E")
    if "diameter" in table:
        table["area"] = math.pi / 4.0 * table.pop("diameter") ** 2
    table.pop("length", None)
    if not table and not required:
        return None
    for key, alias in (("young_modulus", " (or E)"), ("density", ""), ("area", " (or diameter)")):
        if key not in table:
            raise ValueError(f"{dotted}.{key}{alias} is missing")
    return Bar(**table)


def _gauges(spec: dict) -> dict:
    keys = {"bar", "station", "bridge", "gauge_factor", "excitation", "gain", "poisson", "polarity"}
    return {c: Gauge(**_si(_table(spec, f"channels.{c}", keys, {"bar", "station"}), f"channels.{c}"))
            for c in spec["channels"]}


def _drill_rod(spec: dict) -> tuple[Bar, tuple | None]:
    """The rod where the gauges sit and, from ``[rod]``, its pieces (the model's rod); the older
    ``[bars.rod]`` gives the bar alone."""
    if "rod" in spec:
        from ..physical.rock import rod_from_config

        if "bars" in spec:
            raise ValueError("a drill rod is [rod] (its [[rod.segments]], the model's keys) or the older "
                             "[bars.rod], not both")
        pieces = rod_from_config(spec)
        last = pieces[-1]
        return Bar(last.E_Pa, last.density_kg_m3, last.area_m2), pieces
    unknown = set(spec["bars"]) - {"rod"}
    if unknown:
        raise ValueError(f"bars: a drill rod's spec names one bar, [bars.rod]; got {sorted(unknown)}")
    return _bar(spec, "bars.rod"), None


def _run_drill_rod(spec: dict, recording: Recording, baseline) -> DrillRodTest:
    rod, pieces = _drill_rod(spec)
    gauges = _gauges(spec)
    for channel, gauge in gauges.items():
        if gauge.bar != "rod":
            raise ValueError(f"channel {channel!r} sits on bar {gauge.bar!r}, which the bars do not name "
                             "(a drill rod's is 'rod')")
        if pieces is not None and not 0.0 <= gauge.station < pieces[-1].length_m:
            raise ValueError(f"channels.{channel}.station must lie on the rod's last segment, 0 <= x < "
                             f"{pieces[-1].length_m:g} m from the bit (the waves are carried to the bit "
                             f"through one section); got {gauge.station!r}")
    bit = _table(spec, "bit", {"cutoff_hz", "leak"}, set())
    model = None
    if "model" in spec:
        from ..physical.rock import RodPiece

        keys = {"piston_lengths", "piston_areas", "start", "vary"}
        old = {"rod_lengths", "rod_areas"}
        if pieces is not None:
            given = sorted(old & set(spec["model"]))
            if given:
                raise ValueError(f"model.{given[0]}: the model's rod is [rod]'s segments; give one of them")
            m = _table(spec, "model", keys, keys)
        else:
            m = _table(spec, "model", keys | old, keys | old)
            if len(m["rod_lengths"]) != len(m["rod_areas"]):
                raise ValueError(f"model.rod_lengths and model.rod_areas must be of one length, got "
                                 f"{len(m['rod_lengths'])} and {len(m['rod_areas'])}")
            material = {"E_Pa": rod.young_modulus, "density_kg_m3": rod.density}
            pieces = tuple(RodPiece(length_m=float(le), area_m2=float(a), **material)
                           for le, a in zip(m["rod_lengths"], m["rod_areas"], strict=True))
        model = {"rod": list(pieces), "piston_lengths": m["piston_lengths"],
                 "piston_areas": m["piston_areas"], "values": dict(m["start"]), "vary": list(m["vary"])}
    return analyse_drill_rod(recording, gauges, rod, cutoff=bit.get("cutoff_hz"),
                             leak=float(bit.get("leak", 1.0)), baseline=baseline, model=model)


def run_spec(spec: dict | str | Path) -> KolskyTest | DrillRodTest:
    """Run a spec (a path or :func:`read_spec`'s dict): a Kolsky bar's, or a drill rod's (``[bit]``).

    Raises
    ------
    ValueError
        A missing or unknown key (named by its dotted path), and every refusal of
        :func:`~impactbar.measure.analyse_kolsky` or :func:`~impactbar.measure.analyse_drill_rod`.
    """
    if not isinstance(spec, dict):
        spec = read_spec(spec)
    recording, baseline = _recording(spec)
    if "bit" in spec:
        return _run_drill_rod(spec, recording, baseline)
    bars = {name: _bar(spec, f"bars.{name}") for name in ("incident", "transmitted")}
    gauges = _gauges(spec)
    specimen = _si(_table(spec, "specimen", {"length", "area"}, {"length", "area"}), "specimen")
    striker = _si(_table(spec, "striker", _BAR_KEYS | {"length"}, set()), "striker")
    striker_bar = _bar(spec, "striker", required=False)
    detection = _table(spec, "detection", {"threshold", "cutoff_hz"}, set())
    dispersion = _table(spec, "dispersion", {"poisson"}, {"poisson"}) if "dispersion" in spec else {}
    return analyse_kolsky(recording, gauges, bars["incident"], bars["transmitted"], float(specimen["length"]),
                          float(specimen["area"]), striker_length=striker.get("length"), striker=striker_bar,
                          threshold=float(detection.get("threshold", 10.0)),
                          cutoff=detection.get("cutoff_hz", 1e6), baseline=baseline,
                          poisson=dispersion.get("poisson"))
