"""No kernel reads or writes a slot of a record by its number: the exact blow's records (``PR``,
``BS``, ``CI``, ``CT``, ``CNT``, the blocks ``WB``, ``WN``, the tangent's ``TCUR``, ...) and the
lattice blow's (``bs``, ``bp``, ``ctrl``, ``acc``: ``BIT_*``, ``BITP_*``, ``CTRL_*``, ``ACC_*``) are
indexed by the names of :mod:`impactbar.laws.rodrock._records`, where each slot is said once.

What counts as a slot by number: a name of two to six characters, of any case, indexed by one
integer literal, ``PR[3]``, ``bs[3]``, ``CNT0[1]``, ``_hist[0]``, in code (comments and strings are
prose). Single-letter names are the package's mathematical arrays, where ``[0]`` and ``[-1]`` are
the first and last entries (``Z[-1]`` the last segment's impedance, ``U[-1]`` the continuation's
parameter, ``q[0]`` the rigid mode); ``shape`` is never a record; ``NOT_RECORDS`` lists, module by
module, the longer names that are no records either, and ``PYTHON_TUPLES`` the tuples of named
values in Python code no kernel runs. A record of a kernel is named where it is made: the rock
blow's in ``_records``, the others beside their kernel (``_admissibility_search``'s ``PB_*``, ``SRC_*``,
``WK_*``, ``_rigid_arrays``'s ``O_*``, the switched loop's ``INT_*``, ``CNT_*``, ``CLK_*``, the wave
window's ``W_*``, the blow's end's ``EXT_*``, ``HD_*``)."""

import io
import re
import tokenize
from pathlib import Path

import impactbar
from impactbar.laws.rodrock import _records

#: a record's slot by an integer literal
SLOT = re.compile(r"\b[A-Za-z_][A-Za-z0-9_]{1,5}\[-?[0-9]+\]")
#: names never a record: an array's shape
ANYWHERE = {"shape"}
#: module under impactbar/ -> the names there, indexed by a number, of arrays and sequences whose
#: slots are no named fields: first and last entries of a homogeneous sequence (``points[-1]``,
#: ``pieces[0]``, ``axes[0]``), a state or coefficient vector's components (``qa[0]``, the rigid
#: mode; ``y_plus[1]``), a coefficient table's rows, a one-slot box (``count[0]``)
NOT_RECORDS = {
    "_shared/parameters.py": {"bad"},  # the first bad name
    "_shared/schema.py": {"value"},  # a one-entry array's value
    "cli/continue_.py": {"values"},  # a branch's first and last values
    "cli/drifter.py": {"axes"},  # the figure's first axes
    "cli/orbits.py": {"kinds"},  # the first kind offered
    "continuation/branch.py": {"hit"},  # the first index found
    "continuation/one_parameter.py": {"hit", "pieces", "points", "t0",
                                      "tests"},  # sequences' ends, the parameter
    "continuation/engine.py": {"Ua", "Ub", "points", "pred", "rhs", "ta"},  # [-1]: the parameter's component
    "continuation/driven.py": {"_fus", "_lams", "hit", "orbits", "points", "pts", "same", "sides", "t0",
                               "tests"},  # sequences' first and last entries
    "continuation/two_parameter.py": {"e2", "names", "points", "vt"},  # the two parameters, a unit vector
    "drives/circuit/_cvode.py": {"tret"},  # CVODE's one-slot return time
    "drives/circuit/_endfield.py": {"buf", "dut", "yp"},  # the bar state and its derivative's components
    "drives/circuit/_magnus.py": {"_T18", "_T8_A"},  # the Taylor scheme's coefficient rows
    "drives/circuit/_sundials.py": {"hits"},  # the first root found
    "drives/circuit/endflight.py": {"breaks", "ts", "y0", "ext_fn"},  # sequences' ends; a one-slot box
    "drives/circuit/flight.py": {"qe", "ts"},  # the rigid mode; the last time
    "drives/flight.py": {"gs", "out_q", "out_t", "out_v", "qa", "qe", "ts"},  # the rigid mode; first rows
    "drives/orbitproblem.py": {"lu"},  # scipy's LU factor (lu, piv)
    "drives/valve/_compiled_loop.py": {"out_t", "pend_k", "pend_t", "qs", "ts", "vs"},  # queues' heads
    "dynamics/_aberth.py": {"ds", "s89", "ut"},  # sums over the modes as real and imaginary parts
    "dynamics/_crossing.py": {"qa", "qpa", "va", "vpa", "vpb"},  # modal components
    "dynamics/_event_loop.py": {"anchor", "ks", "pim", "pr", "qa", "va", "w2"},  # modal
    # components and a load's first harmonic; anchor[0]: a one-slot box
    "dynamics/certified.py": {"hi", "lo"},  # the first interval's ends
    "dynamics/monodromy.py": {"p11", "p21", "vt"},  # modal components
    "dynamics/stepped.py": {"phi1", "pts"},  # a mode shape's first value; the last point
    "laws/paper/law.py": {"kappa"},  # the rigid mode's
    "laws/paper/periodic.py": {"y_plus"},  # the state's components
    "laws/paper/phase.py": {"orders", "out"},  # the first order; the list's ends
    "laws/rodrock/_bit.py": {"Fn", "Gn", "bounds"},  # cells' first and last; the first boundary
    "laws/rodrock/_exactdata.py": {"starts"},  # the first and last start
    "laws/rodrock/_exactode.py": {"ex"},  # the series' first term
    "laws/rodrock/_exactresume.py": {"before", "off"},  # sequences' ends
    "laws/rodrock/_rockloop.py": {"Fn", "bounds"},  # the far end's cell; the shank's boundary
    "laws/rodrock/_rocktangent.py": {"Fn", "Gf", "Gp", "dFna", "dGa", "seg_z"},  # the first cell or segment's
    "laws/rodrock/blow.py": {"bitf", "off", "times"},  # sequences' first and last entries
    "laws/rodrock/contact.py": {"qa"},  # the rigid mode
    "laws/rodrock/coupled.py": {"column"},  # the far end's cell
    "laws/rodrock/coupled_exact.py": {"travel", "xv"},  # the first segment's; a grid's ends
    "laws/rodrock/exact.py": {"Zp", "Zr"},  # the last segment's impedance
    "laws/rodrock/exactjac.py": {"pieces", "qa", "starts"},  # the first piece and start; the rigid mode
    "laws/rodrock/exactmap.py": {"kappa", "qa"},  # the rigid mode's
    "laws/rodrock/law.py": {"qm"},  # the rigid mode
    "laws/rodrock/longrod.py": {"qm"},  # the rigid mode
    "laws/wave/_characteristics.py": {"first", "hit", "jumps", "nodes", "qa"},  # sequences' ends, rigid mode
    "laws/wave/_separation.py": {"ew", "grid", "p12", "qa", "qm", "ts", "ve"},  # modal components
    "laws/wave/_window.py": {"jumps", "qa"},  # the first jump; the rigid mode
    "laws/wave/impact.py": {"dg", "npi", "th"},  # the rigid mode; a grid's ends
    "laws/wave/law.py": {"jt", "qm"},  # the rigid mode
    "laws/wave/periodic.py": {"DP", "coef", "first", "gq", "orders", "p12", "phases", "qm", "runs",
                              "y_plus"},  # DP[0]: the impact map's Jacobian's first row; modal components
    "laws/wave/sustained.py": {"below", "nxt", "start"},  # sequences' first and last entries
    "loads/fourier.py": {"_k", "_pk", "ks", "pks", "rows", "tau"},  # harmonics' first and last
    "model.py": {"ends", "kappa"},  # the mode shapes at the two ends (rows of one array); the rigid mode's
    "orbits/_admissibility_search.py": {"bufs", "gm",
                                        "upper"},  # the first of four like buffers; the first bound
    "orbits/_closing.py": {"blocks"},  # the first block
    "orbits/_rigid_scalar.py": {"phases"},  # the two phases
    "orbits/_rigid_arrays.py": {"bounds", "phs"},  # the first bound; the two phases
    "orbits/_saltation.py": {"fired"},  # the first event fired
    "orbits/_shooting_data.py": {"blocks"},  # the first block
    "orbits/_valve_flow.py": {"gq", "gv"},  # the rigid mode
    "orbits/admissibility.py": {"cl", "found", "neg", "pos", "q0", "v0"},  # sequences' ends; a one-slot box
    "orbits/charts.py": {"edges", "hs", "kinds", "orders", "pieces", "roots", "xs"},  # sequences' ends
    "orbits/coupled.py": {"qa"},  # the rigid mode
    "orbits/find.py": {"ti"},  # the last impact time
    "orbits/multi_impact.py": {"maps", "pert"},  # sequences' first and last entries
    "orbits/orbit.py": {"phases"},  # the first phase
    "orbits/rigid.py": {"args"},  # the first argument array
    "orbits/shooting.py": {"Xr", "blocks", "hist", "speeds", "used"},  # sequences' ends, components; a box
    "orbits/driven_orbit.py": {"states"},  # the first state
    "orbits/driven_search.py": {"found", "same", "vi"},  # sequences' first and last entries
    "orbits/valve_admissibility.py": {"w2", "za"},  # modal components
    "orbits/valve_search.py": {"gX", "v0", "wq", "wv"},  # modal components and a gradient's
    "orbits/valve_segment.py": {"Eb", "Ed", "dtc", "states", "stroke", "zb"},  # modal components
    "paper.py": {"ax", "bad", "keys", "orbits", "rows"},  # sequences' first and last entries
    "physical/bar.py": {"secs"},  # the first section
    "physical/circuit.py": {"pieces"},  # the first and last piece
    "measure/kolsky.py": {"band", "chans", "later", "time"},  # a band's ends; first channel, pulse, sample
    "physical/optimize_failures.py": {"lines"},  # the error's first line
    "physical/optimize_multistart.py": {"order"},  # the best design's index
    "physical/optimize_result.py": {"axes", "kv"},  # the figure's axes; a (name, constraint) pair's second
    "physical/settle.py": {"last"},  # the first and last impact times
    "physical/tree.py": {"parts"},  # a dotted key's parts (rod.segments.<i>.<name>: the index)
    "physical/circuit_graph.py": {"linked"},  # the first node a part joins
    "measure/figures.py": {"axes"},  # the figure's fourth axes
    "measure/drill.py": {"kv"},  # a (name, gauge) pair's second
    "drives/circuit/part_flows.py": {"flows"},  # a part's only flow
    "measure/model.py": {"count", "ends", "pieces"},  # a counter; the rod's end; its first piece's material
    "measure/recording.py": {"time"},  # the first and last sample times
    "measure/results.py": {"time"},  # the first two sample times (the step)
    "measure/waves.py": {"after", "before", "parts", "time"},  # samples' ends; a window's two pieces
    "physical/forces.py": {"rows"},  # the first row
    "physical/hammer.py": {"breaks", "levels", "pieces"},  # a square wave's two levels and breaks
    "physical/loader.py": {"parts"},  # a dotted name's parts
    "physical/optimize_drifter.py": {"kv"},  # a (name, constraint) pair's constraint
    "physical/piston.py": {"count", "edges", "pieces"},  # a one-slot box; sequences' ends
    "physical/results.py": {"tl"},  # the first and last time
    "physical/rock.py": {"tl"},  # the first and last time
    "physical/sensitivity.py": {"sides"},  # the two sides of a difference
    "plotting/circuit.py": {"axes"},  # the figure's axes
    "plotting/continuation.py": {"yy"},  # the first value
    "plotting/maps.py": {"dims"},  # the first dimension
    "plotting/physical.py": {"segs"},  # the last segment
    "plotting/simulation.py": {"axes", "files"},  # the figure's axes; the last file
    "plotting/sweeps.py": {"dims", "values"},  # the dimensions; the first value
    "simulation/_shortrun.py": {"_ENTRY", "qv", "tv"},  # a one-slot box; rows of times and states
    "simulation/blows.py": {"gaps", "q_arr"},  # the second row; the rigid mode
    "simulation/simulate.py": {"aq", "av", "blocks", "ot", "qm", "vm"},  # first entries, rigid mode
    "simulation/driven.py": {"_ends"},  # the last end
    "simulation/driven_trajectory.py": {"pieces"},  # the last piece
    "simulation/trajectory.py": {"head", "out", "rows", "segs"},  # sequences' first and last entries
    "sweeps/map_spec.py": {"values"},  # the first and last value
    "sweeps/plot.py": {"axes"},  # the figure's first axes
    "sweeps/run.py": {"left"},  # a one-slot box
}
#: module -> tuples of named values in Python code that no kernel runs (a function's results, a
#: cache's key and value, an option's pair): records in the wide sense, to be unpacked or named where
#: next touched, outside what this test guards (the kernels' records)
PYTHON_TUPLES = {
    "cli/continue_.py": {"curve"},  # --curve NAME TO
    "continuation/two_parameter.py": {"key"},  # the cache's key, the two parameters' values
    "drives/circuit/drive.py": {"mode"},  # the mode (valve, ..., checks)
    "drives/valve/drive.py": {"mode"},  # the mode (valve, ...)
    "dynamics/modal.py": {"out"},  # the flow's four coefficient arrays
    "laws/rodrock/coupled_exact.py": {"waves"},  # (F, G)
    "laws/rodrock/exact.py": {"drive", "kept"},  # (starts, pieces); the kept pool
    "laws/rodrock/exactjac.py": {"drive", "res", "waves"},  # (starts, pieces), the run's results
    "laws/rodrock/exactmap.py": {"out"},  # the run's results
    "laws/wave/_jumps.py": {"best", "found"},  # (residual, value)
    "model.py": {"_modal"},  # (w, c, modes, kappa, sticking)
    "orbits/_closing.py": {"out"},  # the flight's results
    "orbits/admissibility.py": {"slope"},  # (slope, smooth)
    "orbits/find.py": {"guess"},  # (times, states)
    "orbits/one_impact.py": {"form"},  # the load's closed form's parameters
    "orbits/shooting.py": {"last", "out"},  # the cache; the flight's results
    "orbits/valve_search.py": {"window"},  # (lo, hi)
    "orbits/valve_segment.py": {"_last", "window"},  # the cache; (lo, hi)
    "physical/forces.py": {"header"},  # the header's (time, force)
    "physical/geometry.py": {"ends"},  # (lengths, diameters)
    "physical/optimize_problem.py": {"ends"},  # the two sides' outputs
    "physical/piston.py": {"best", "rank", "seg", "side"},  # (residual, y), (lengths, ..., speeds)
    "simulation/initial.py": {"out"},  # (q, v)
    "simulation/simulate.py": {"last"},  # the cache (model, load, value)
}
_PROSE = {tokenize.COMMENT, tokenize.STRING} | {getattr(tokenize, "FSTRING_MIDDLE", tokenize.STRING)}


def _code(text):
    """``text``'s lines with its comments and strings blanked."""
    lines = [list(line) for line in text.splitlines()]
    for tok in tokenize.generate_tokens(io.StringIO(text).readline):
        if tok.type not in _PROSE:
            continue
        (r0, c0), (r1, c1) = tok.start, tok.end
        for r in range(r0, r1 + 1):
            row = lines[r - 1]
            lo = c0 if r == r0 else 0
            hi = c1 if r == r1 else len(row)
            row[lo:hi] = " " * (hi - lo)
    return ["".join(row) for row in lines]


def slots_by_number(text, module=""):
    """``(line, match)`` of every record slot indexed by a number in the source ``text`` of
    ``module``, those its lists let pass left out."""
    passed = ANYWHERE.union(*(names.get(module, ()) for names in (NOT_RECORDS, PYTHON_TUPLES)))
    out = []
    for i, line in enumerate(_code(text), start=1):
        for m in SLOT.finditer(line):
            if m.group().split("[")[0] not in passed:
                out.append((i, m.group()))
    return out


def test_the_scan_finds_a_slot_by_number_in_code_only():
    text = ('PR[3] = 1.0\n'
            'x = WB[0] + CNT0[-1] * CH_T[12]\n'
            '# PR[3] in a comment\n'
            's = "CT[9]" + BS[2]\n'
            '"""a docstring quoting CI[0]"""\n'
            'shape, z, n, y = (16, 4), Z[-1], a.shape[0], PR[PR_MASS] + WB[blk][0] + NSF[j, 0]\n')
    assert slots_by_number(text) == [(1, "PR[3]"), (2, "WB[0]"), (2, "CNT0[-1]"), (2, "CH_T[12]"),
                                     (4, "BS[2]")]
    assert slots_by_number("u = DP[0] @ v\n", "laws/wave/periodic.py") == []
    assert slots_by_number("u = DP[0] @ v\n") == [(1, "DP[0]")]


def test_the_scan_finds_a_lower_case_slot_and_passes_the_listed_names():
    text = ('bs[3] = bp[1] * bs[0]\n'
            'u, loss = acc[0], _hist[-1]\n'
            'p = q[0] + a.shape[0] + bs[BIT_P] + scratch[2]\n'
            '# bs[3] in a comment\n')
    assert slots_by_number(text) == [(1, "bs[3]"), (1, "bp[1]"), (1, "bs[0]"), (2, "acc[0]"),
                                     (2, "_hist[-1]")]
    assert slots_by_number("x = qa[0] + pr[0]\n", "dynamics/_event_loop.py") == []
    assert slots_by_number("x = qa[0] + pr[0]\n", "dynamics/modal.py") == [(1, "qa[0]"), (1, "pr[0]")]
    assert slots_by_number("bs[3] = 0.0\n", "laws/rodrock/_rockloop.py") == [(1, "bs[3]")]


def test_the_lists_are_disjoint_and_name_modules_that_exist():
    """A name is listed once per module, in one list, and each listed module exists and still
    indexes that name by a number (a list that outlives its reason would hide a new record)."""
    top = Path(impactbar.__file__).parent
    lists = (NOT_RECORDS, PYTHON_TUPLES)
    for module in NOT_RECORDS.keys() & PYTHON_TUPLES.keys():
        assert not NOT_RECORDS[module] & PYTHON_TUPLES[module], module
    for names in lists:
        for module, listed in names.items():
            text = (top / module).read_text()
            seen = {m.group().split("[")[0] for line in _code(text) for m in SLOT.finditer(line)}
            assert listed <= seen, (module, listed - seen)


def test_no_kernel_reads_a_record_slot_by_its_number():
    top = Path(impactbar.__file__).parent
    found = []
    for path in sorted(top.rglob("*.py")):
        module = path.relative_to(top).as_posix()
        found += [f"{module}:{line}: {m}" for line, m in slots_by_number(path.read_text(), module)]
    assert found == [], "record slots by number (name them in laws/rodrock/_records.py):\n" + \
        "\n".join(found)


def test_each_record_names_its_slots_once_within_its_size():
    """The layout itself: within a record no two names share a slot, and every slot lies in the
    record's length (the sizes the workspace is made with)."""
    names = {k: v for k, v in vars(_records).items() if k.isupper() and isinstance(v, int)}
    sizes = {k[:-5]: v for k, v in names.items() if k.endswith("_SIZE")}
    sizes["B"] = names["BLOCKS"]
    assert set(sizes) == {"PR", "BS", "BI", "CI", "CT", "CNT", "TCUR", "B",
                          "HMAX", "BIT", "BITP", "CTRL", "ACC", "TSCR", "CELL"}
    for rec, size in sizes.items():
        slots = {k: v for k, v in names.items()
                 if re.fullmatch(rec + r"_[A-Z0-9]+", k) and k != rec + "_SIZE"}
        assert slots, rec
        assert len(set(slots.values())) == len(slots), (rec, slots)
        assert all(0 <= v < size for v in slots.values()), (rec, slots)
    for tup in ("WS_", "TG_"):  # the tuples' places
        positions = [v for k, v in names.items() if k.startswith(tup)]
        assert len(set(positions)) == len(positions), tup
