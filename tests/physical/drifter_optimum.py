"""The whole-drifter optimiser's documented optimum of the example rock drifter with its piston
given by its shape (docs/optimising_a_drifter.md, the drilling rate held), and, from the same search
with the blows ended at the law's fixed window (the rod-rock law's default under the circuit before
they ended where the piston is free for good), its design and designs beside it with a wider collar:
for the tests of its designs without an operating point, of its border (which name that end,
:func:`window_end`) and for ``benchmarks/bench_failed_evaluation.py`` (which runs it on other trees
too: no import of the package here but in :func:`window_end`)."""

from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "circuit_drifter_rock_piston.toml"
#: the optimum with the drilling rate held (docs/optimising_a_drifter.md)
OPTIMUM = {"piston.collar_diameter": "0.04729667723050768 m",
           "piston.front_rod_diameter": "0.04560725499462594 m",
           "piston.rear_rod_diameter": "0.040608256863568164 m",
           "chambers.rear_volume": "8.253871828916914e-05 m**3", "valve.switch_out": "0.021428704551485933 m",
           "accumulator.precharge": "10003024.1343202 Pa"}

#: the same search's optimum with the blows ended at the law's window (docs/optimising_a_drifter.md,
#: "Why it is not one")
WINDOW_OPTIMUM = {"piston.collar_diameter": "0.04721879723846864 m",
           "piston.front_rod_diameter": "0.04560714397207219 m",
           "piston.rear_rod_diameter": "0.04058336647137088 m",
           "chambers.rear_volume": "8.177116598602943e-05 m**3", "valve.switch_out": "0.02140236229697432 m",
           "accumulator.precharge": "10041438.916236278 Pa"}

#: a design COBYLA evaluated on its way to the window's optimum (``benchmarks/bench_optimize_drifter.py``'s
#: 30 designs) without a one-impact orbit: followed from rest to Newton's start (``orbit()``'s default
#: chain) its impact velocities alternate 0.16 % apart, where those of :func:`collar`'s designs settle
SEARCHED = {"piston.collar_diameter": "47.18611888624688 mm",
            "piston.front_rod_diameter": "45.59684291177947 mm",
            "piston.rear_rod_diameter": "40.512836367322485 mm",
            "chambers.rear_volume": "0.08342482983520652 L", "valve.switch_out": "21.399470250974566 mm",
            "accumulator.precharge": "9.971329060826521 MPa"}

#: a design the twentieth restarted COBYLA search of ``benchmarks/bench_optimize_restarts.py`` met (its
#: tenth), the collar at its low bound and the front rod 0.005 mm narrower (a front annulus of
#: 0.39 mm^2, the optimum's 101 mm^2): no one-impact orbit from rest on the stop (``orbit()``'s default
#: chain: the front chamber empties); from rest two blows, then the piston buzzes on the shank, some 700
#: impacts a second at 8 mm/s. It has a one-impact orbit all the same, stable (|mu| 0.575), the relief
#: valve open twice a period, that rest does not reach: from rest at the switch point
#: (``orbit(switch_start=True)``), or continued along its collar from 47.3 mm
BUZZING = {"piston.collar_diameter": "47 mm", "piston.front_rod_diameter": "46.99465241488195 mm",
           "piston.rear_rod_diameter": "41.30492914694012 mm",
           "chambers.rear_volume": "0.13030154711250988 L",
           "valve.switch_out": "22.003353215148817 mm", "accumulator.precharge": "12.62220827319058 MPa"}


def collar(factor: float) -> dict:
    """The window's optimum with its collar's diameter times ``factor``: from about 1.0095 to 1.0125 (47.69 mm
    at 1.01) no one-impact orbit, at 1.003, 1.009, 1.013 and 1.03 one."""
    return dict(WINDOW_OPTIMUM, **{"piston.collar_diameter": f"{0.04721879723846864 * factor!r} m"})


def window_end(monkeypatch) -> None:
    """Builds the designs of the calling test with their blows ended at the law's fixed window
    (``RodRock(driven_end="window")``) and their contacts' events at the lattice's step ends
    (``contact_events="step"``, the example's setting before it took ``"inside"``), where
    :data:`WINDOW_OPTIMUM`, :data:`SEARCHED` and :func:`collar`'s designs were found and measured
    (theory §11, "The coupled blow")."""
    import impactbar.physical.rock as rock

    law = rock.RodRock

    def measured_there(*args, **kwargs):
        return law(*args, **{**kwargs, "driven_end": "window", "contact_events": "step"})

    monkeypatch.setattr(rock, "RodRock", measured_there)


def documented_problem():
    """The page's six-variable problem (docs/optimising_a_drifter.md, the drilling rate held;
    ``benchmarks/bench_optimize_drifter.py``'s) on the example as the calling test builds it: the
    config, its folder, the bounds' spec, the keys, the spans (SI), the limits and ``fresh(u)``, the
    record and orbit of a fresh ``orbit()`` of the scaled design ``u``, and ``scaled(changes)``, a
    design's scaled variables."""
    import numpy as np

    from impactbar.physical import build, read_config, with_values
    from impactbar.physical.design_keys import design_bounds
    from impactbar.physical.optimize_problem import DEFAULT_CONSTRAINTS, _limits, evaluate_design

    vary = {"piston.collar_diameter": ("47 mm", "52 mm"), "piston.front_rod_diameter": ("43 mm", "47 mm"),
            "piston.rear_rod_diameter": ("38 mm", "43 mm"), "chambers.rear_volume": ("0.06 L", "0.2 L"),
            "valve.switch_out": ("18 mm", "25 mm"), "accumulator.precharge": ("8 MPa", "14 MPa")}
    cfg, folder = read_config(EXAMPLE)
    spec = design_bounds(cfg, vary, folder)
    keys = list(spec)
    lo = np.array([spec[k]["low"] for k in keys])
    span = np.array([spec[k]["high"] - lo[j] for j, k in enumerate(keys)])
    limits = _limits({"peak_rod_stress": "250 MPa", "min_drilling_rate": "2.5 m/min"},
                     build(cfg, folder), ideal=False)
    kept = dict.fromkeys(DEFAULT_CONSTRAINTS) | limits
    units = {k: spec[k]["unit"] for k in keys}

    def fresh(u):
        changes = {k: f"{float(x)!r} {units[k]}" for k, x in zip(keys, lo + span * u, strict=True)}
        rec, orbit = evaluate_design(build(with_values(cfg, changes), folder), kept)
        rec.update(changes=changes, values={k: float(x) for k, x in zip(keys, lo + span * u, strict=True)})
        return rec, orbit

    def scaled(changes):
        at = design_bounds(with_values(cfg, changes), vary, folder)
        return (np.array([at[k]["start"] for k in keys]) - lo) / span

    return cfg, folder, spec, keys, span, limits, fresh, scaled


#: the documented multistart's designs without a one-impact orbit (its history's 61st, 89th and 145th, all
#: in the sample; its four other failures cavitate), on the example's own settings (not
#: :func:`window_end`): none from the switch point either (``orbit(switch_start=True)``)
DOCUMENTED_NO_ORBIT = (
    {"piston.collar_diameter": "50.6147900018841 mm", "piston.front_rod_diameter": "43.4569100625813 mm",
     "piston.rear_rod_diameter": "42.90997654385865 mm", "chambers.rear_volume": "0.13154953349381687 L",
     "valve.switch_out": "22.705367892049253 mm", "accumulator.precharge": "11.189523413777351 MPa"},
    {"piston.collar_diameter": "51.49733991641551 mm", "piston.front_rod_diameter": "43.02336393296719 mm",
     "piston.rear_rod_diameter": "41.76984755042941 mm", "chambers.rear_volume": "0.07446330640465022 L",
     "valve.switch_out": "23.92294740397483 mm", "accumulator.precharge": "9.296958465129137 MPa"},
    {"piston.collar_diameter": "50.98309485055506 mm", "piston.front_rod_diameter": "43.25002878904343 mm",
     "piston.rear_rod_diameter": "42.159363550134 mm", "chambers.rear_volume": "0.08264897244051099 L",
     "valve.switch_out": "21.29995989240706 mm", "accumulator.precharge": "10.162000801414251 MPa"},
)
