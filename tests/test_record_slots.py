"""No kernel reads or writes a slot of a record by its number: the exact blow's records (``PR``,
``BS``, ``CI``, ``CT``, ``CNT``, the blocks ``WB``, ``WN``, the tangent's ``TCUR``, ...) and the
lattice blow's (``bs``, ``bp``, ``ctrl``, ``acc``: ``BIT_*``, ``BITP_*``, ``CTRL_*``, ``ACC_*``) are
indexed by the names of :mod:`impactbar.laws.rodrock._records`, where each slot is said once.

What counts as a slot by number: a name of any length and case, one letter too, or an attribute,
indexed by one integer literal, ``PR[3]``, ``bs[3]``, ``r[1]``, ``self._measured[2]``, and a slot of
an entry reached by subscripts before it, ``windows[-1][2]``, ``pending[0][0]``, ``WB[blk][0]``,
in code (comments and strings are prose). The lists name a name, or for a chained subscript the
name with ``[]`` (``hist[]``: a slot of an entry of ``hist``, not its ends). ``shape`` is never a
record; ``NOT_RECORDS`` lists, module by module, the names that are no records (a mathematical
array's entries: ``Z[-1]`` the last segment's impedance, ``U[-1]`` the continuation's parameter,
``q[0]`` the rigid mode; a sequence's ends; a coefficient array), and ``PYTHON_TUPLES`` the tuples
of named values in Python code that are still read by number. A call's result indexed by a number,
``f(x)[0]``, ``obj.method(a, b)[1]``, ``np.linalg.svd(J)[2][-1]``, a call over lines too, is a slot
as well, listed as ``f()`` (``CALL_NOT_RECORDS``: an array's entry; ``CALL_TUPLES``: a tuple of
named values). The syntax tree is walked too, for what the text scan cannot see: a slot inside an
f-string's expressions (``f"{bad[0]}"``, ``STRING_NOT_RECORDS``), a parenthesised expression's result
(``(a + b)[0]``) and the result of calling an entry (``h[k](x)[0]``), both listed as ``(...)``, a call
nested deeper than eight. Not scanned: a slice, a subscript by a name, a subscript by a tuple (a
two-dimensional array's column, ``NSF[j, 0]``). A record of a kernel is named where it is made: the
rock blow's in ``_records``, the others beside their kernel (``_admissibility_search``'s ``PB_*``,
``SRC_*``, ``WK_*``, ``_rigid_arrays``'s ``O_*``, the switched loop's ``INT_*``, ``CNT_*``, ``CLK_*``,
the wave window's ``W_*``, the blow's end's ``EXT_*``, ``HD_*``)."""

import ast
import io
import re
import tokenize
from pathlib import Path

import impactbar
from impactbar.laws.rodrock import _records

#: a record's slot by an integer literal: of a name (an attribute's too) after any subscripts
SLOT = re.compile(r"\b([A-Za-z_][A-Za-z0-9_]*)((?:\[[^\[\]]*\])*)\[-?[0-9]+\]")
#: parentheses and what they hold, nested up to eight deep, over lines too
_CALL_ARGS = r"\([^()]*\)"
for _ in range(8):
    _CALL_ARGS = r"\((?:[^()]|" + _CALL_ARGS + r")*\)"
#: a call's result's slot by an integer literal (``f(x)[0]``, ``obj.method(a, b)[1]``), after any
#: subscripts; listed as ``f()`` (``f()[]`` with subscripts before)
CALL = re.compile(r"\b([A-Za-z_][A-Za-z0-9_]*)" + _CALL_ARGS + r"((?:\[[^\[\]]*\])*)\[-?[0-9]+\]")
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
    "continuation/driven.py": {"hit", "orbits", "points", "pts", "same", "sides", "t0",
                               "tests"},  # sequences' first and last entries
    "continuation/two_parameter.py": {"e2", "names", "points", "vt"},  # the two parameters, a unit vector
    "drives/circuit/_cvode.py": {"tret"},  # CVODE's one-slot return time
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
    # the shank's boundary; the records' first entries (bitf, pen); the driven end's cell (Z); the first
    # slot at the start (FF, GG, W)
    "laws/rodrock/_rockslots.py": {"bounds", "bitf", "pen", "Z", "FF", "GG", "W"},
    # the slots' grids' first edges (edges, cum, eold, ubuf, srt) and a source's first slot (cur); the
    # heap's root (hk, hi, hv)
    "laws/rodrock/_slotgrid.py": {"edges", "cum", "cur", "eold", "ubuf", "srt", "hk", "hi", "hv"},
    "laws/rodrock/_rocktangent.py": {"Fn", "Gf", "Gp", "dFna", "dGa", "seg_z"},  # the first cell or segment's
    "laws/rodrock/blow.py": {"bitf", "times"},  # sequences' first and last entries
    "laws/rodrock/grid.py": {"off", "times"},  # sequences' first and last entries
    "laws/rodrock/contact.py": {"qa"},  # the rigid mode
    # the far end's cell; a step's (widths, values) pair (a); the blow's last step (times, dts, force,
    # shank_forces, vel, pos); the drive's last interval (drop, narrow, lo)
    "laws/rodrock/coupled.py": {"column", "a", "times", "force", "shank_forces", "vel", "pos", "drop",
                                "narrow", "lo"},
    "laws/rodrock/coupled_exact.py": {"travel", "xv"},  # the first segment's; a grid's ends
    "laws/rodrock/coupled_tangent.py": {"travel", "c", "y_end"},  # the first segment's; the rigid
    # mode's weight; the last piece's end
    "laws/rodrock/exact.py": {"Zp", "Zr"},  # the last segment's impedance
    # c: a piece's coefficient array (a piecewise load's constant); the first piece, start and initial
    # wave; the rigid mode
    "laws/rodrock/exactjac.py": {"c", "pieces", "starts", "waves"},
    "laws/rodrock/exactmap.py": {"kappa", "qa"},  # the rigid mode's
    "laws/rodrock/law.py": {"qm"},  # the rigid mode
    "laws/rodrock/longrod.py": {"peaks", "qm"},  # the first boundary's (the shank's); the rigid mode
    "laws/wave/_characteristics.py": {"first", "hit", "jumps", "nodes", "qa"},  # sequences' ends, rigid mode
    "laws/wave/_separation.py": {"ew", "grid", "p12", "qa", "qm", "ts", "ve"},  # modal components
    "laws/wave/_window.py": {"jumps", "qa"},  # the first jump; the rigid mode
    "laws/wave/impact.py": {"dg", "npi", "th"},  # the rigid mode; a grid's ends
    "laws/wave/law.py": {"jt", "qm"},  # the rigid mode
    "laws/wave/periodic.py": {"DP", "coef", "gq", "orders", "p12", "phases", "qm",
                              "y_plus"},  # DP[0]: the impact map's Jacobian's first row; modal components
    "laws/wave/sustained.py": {"below", "nxt", "start"},  # sequences' first and last entries
    "loads/fourier.py": {"_k", "_pk", "ks", "pks", "tau"},  # harmonics' first and last
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
    "orbits/charts.py": {"hs", "kinds", "orders", "pieces", "roots", "xs"},  # sequences' ends
    "orbits/coupled.py": {"qa"},  # the rigid mode
    "orbits/find.py": {"ti"},  # the last impact time
    "orbits/multi_impact.py": {"maps", "pert"},  # sequences' first and last entries
    "orbits/orbit.py": {"phases"},  # the first phase
    "orbits/rigid.py": {"args"},  # the first argument array
    "orbits/shooting.py": {"Xr", "blocks", "hist", "seq", "speeds", "used"},  # ends, components; a box
    "orbits/driven_orbit.py": {"states"},  # the first state
    "orbits/driven_search.py": {"found", "same", "vi"},  # sequences' first and last entries
    "orbits/valve_admissibility.py": {"w2", "za"},  # modal components
    "orbits/valve_search.py": {"gX", "v0", "wq", "wv"},  # modal components and a gradient's
    "orbits/valve_segment.py": {"Ed", "dtc", "states", "stroke", "zb"},  # modal components
    "paper.py": {"ax", "bad", "keys", "orbits", "rows"},  # sequences' first and last entries
    "physical/bar.py": {"secs"},  # the first section
    "physical/circuit.py": {"pieces"},  # the first and last piece
    "measure/kolsky.py": {"band", "later", "time"},  # a band's ends; first pulse, sample
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
    "physical/hammer.py": {"breaks", "levels", "pieces"},  # a square wave's two levels and breaks
    "physical/loader.py": {"parts"},  # a dotted name's parts
    "physical/optimize_problem.py": {"kv"},  # a (name, constraint) pair's constraint
    "physical/piston.py": {"count", "edges", "pieces"},  # a one-slot box; sequences' ends
    "physical/results.py": {"tl"},  # the first and last time
    "physical/rock.py": {"tl"},  # the first and last time
    "plotting/circuit.py": {"axes"},  # the figure's axes
    "plotting/continuation.py": {"yy"},  # the first value
    "plotting/maps.py": {"dims"},  # the first dimension
    "plotting/physical.py": {"segs"},  # the last segment
    "plotting/simulation.py": {"axes", "files"},  # the figure's axes; the last file
    "plotting/sweeps.py": {"dims", "values"},  # the dimensions; the first value
    "simulation/_shortrun.py": {"_ENTRY", "qv"},  # a one-slot box; rows of states (displacements, velocities)
    "simulation/blows.py": {"q_arr"},  # the rigid mode
    # first entries, the rigid mode; contacts: the last contact
    "simulation/simulate.py": {"aq", "av", "blocks", "contacts", "ot", "qm", "vm"},
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
}
#: module -> the names the scan met once it read names of any length, attributes and chained
#: subscripts, that are no records (as ``NOT_RECORDS``)
WIDER_NOT_RECORDS = {
    "_shared/parameters.py": {"refused"},  # refused: the first refusal
    "cli/_common.py": {"option_strings"},  # option_strings: the first option string
    "cli/continue_.py": {"impact_times"},  # impact_times: the first impact time
    # records: the last record of a list; v: the modal velocities ([0] the rigid mode) or a series' last
    "cli/drifter.py": {"records", "v"},
    # e: a basis vector's or series' entry; v: the modal velocities ([0] the rigid mode) or a series'
    # last
    "cli/simulate.py": {"e", "v"},
    "continuation/cascade.py": {"branches"},  # branches: the last branch
    # U: a continuation point: [-1] (and [-2]) its parameter; Vh: the right singular vectors, [-1] the
    # null vector; d: a chord: [-1] the parameter's component; pairs: the last pair of a list; records:
    # the last record of a list; tangents: the last tangents
    "continuation/driven.py": {"U", "Vh", "d", "pairs", "records", "tangents"},
    "continuation/engine.py": {"tangents"},  # tangents: the last tangents
    # U: a continuation point: [-1] (and [-2]) its parameter; V: a continuation point: [-1] its
    # parameter; Vh: the right singular vectors, [-1] the null vector; e: a basis vector's or series'
    # entry; tangents: the last tangents; tangents[]: a tangent's last component (the parameter)
    "continuation/one_parameter.py": {"U", "V", "Vh", "e", "tangents", "tangents[]"},
    "continuation/two_parameter.py": {"U"},  # U: a continuation point: [-1] (and [-2]) its parameter
    # q: the modal coordinates: [0] the rigid mode; v: the modal velocities ([0] the rigid mode) or a
    # series' last
    "drives/base.py": {"q", "v"},
    "drives/circuit/_bar.py": {"y"},  # y: a state vector's components ([0] the rigid mode)
    "drives/circuit/_cvode.py": {"callbacks"},  # callbacks: the first callback
    # W: a stack of like matrices, each named where taken; c: a coefficient array's entries; q: the
    # modal coordinates: [0] the rigid mode
    "drives/circuit/_magnus.py": {"W", "c", "q"},
    "drives/circuit/composition.py": {"replaced"},  # replaced: the first replaced part
    "drives/circuit/cushion.py": {"openings"},  # openings: the first and last opening
    "drives/circuit/drive.py": {"q"},  # q: the modal coordinates: [0] the rigid mode
    # T: a time grid's first and last; t: a time grid's first and last; y: a state vector's components
    "drives/circuit/endflight.py": {"T", "t", "y"},
    # Y: rows of states: the first and last; t: a time grid's first and last
    "drives/circuit/flight.py": {"Y", "t"},
    # q: the modal coordinates: [0] the rigid mode; t: a time grid's first and last; v: the modal
    # velocities ([0] the rigid mode) or a series' last
    "drives/flight.py": {"q", "t", "v"},
    # c: a coefficient array's entries; out_vel: a one-slot box; q: the modal coordinates: [0] the rigid
    # mode; v: the modal velocities ([0] the rigid mode) or a series' last
    "drives/valve/_compiled_loop.py": {"c", "out_vel", "q", "v"},
    "drives/valve/_state.py": {"pending"},  # pending: the queue's head
    # pending: the queue's head; q: the modal coordinates: [0] the rigid mode
    "drives/valve/drive.py": {"pending", "q"},
    "dynamics/_aberth.py": {"s"},  # s: a root's index or a sum's real and imaginary parts
    "dynamics/_crossing.py": {"anchor_t", "c"},  # anchor_t: a one-slot box; c: a coefficient array's entries
    # c: a coefficient array's entries; q: the modal coordinates: [0] the rigid mode; v: the modal
    # velocities ([0] the rigid mode) or a series' last
    "dynamics/_event_loop.py": {"c", "q", "v"},
    # a: a coefficient array's entries; b: a coefficient array's entries
    "dynamics/invariants.py": {"a", "b"},
    # f: a series' first and last values; g: a grid function's first value; lengths: the first or last
    # segment's; mass_per_length: the last segment's; overlap: the first row; u: the transfer matrix's
    # displacement row: its last; wavenumbers: a mode's wavenumber; x: a grid's or state's entries; z: a
    # state vector's or grid's entries
    "dynamics/stepped.py": {"f", "g", "lengths", "mass_per_length", "overlap", "u", "wavenumbers", "x", "z"},
    "laws/paper/law.py": {"v_before"},  # v_before: the rigid mode's
    # q: the modal coordinates: [0] the rigid mode; v: the modal velocities ([0] the rigid mode) or a
    # series' last; y_minus: the state's component
    "laws/paper/periodic.py": {"q", "v", "y_minus"},
    "laws/paper/phase.py": {"amplitudes"},  # amplitudes: the first harmonic's
    # F: the first cell or the first of a list; G: the cells' first wave; Z: the segments' first and
    # last impedance
    "laws/rodrock/_bit.py": {"F", "G", "Z"},
    "laws/rodrock/_choice.py": {"segments"},  # segments: the first or last segment
    # G: the cells' first wave; Z: the segments' first and last impedance
    "laws/rodrock/_rockloop.py": {"G", "Z"},
    # Z: the segments' first and last impedance; bit_forces: the series' ends
    "laws/rodrock/blow.py": {"Z", "bit_forces"},
    "laws/rodrock/checks.py": {"segments"},  # segments: the first or last segment
    "laws/rodrock/contact.py": {"q"},  # q: the modal coordinates: [0] the rigid mode
    # G: the cells' first wave; Z: the segments' first and last impedance; q: the modal coordinates: [0]
    # the rigid mode; v: the modal velocities ([0] the rigid mode) or a series' last
    "laws/rodrock/coupled.py": {"G", "Z", "q", "v"},
    # impedance: the first segment's; q: the modal coordinates: [0] the rigid mode; v: the modal
    # velocities ([0] the rigid mode) or a series' last
    "laws/rodrock/coupled_exact.py": {"impedance", "q", "v"},
    "laws/rodrock/exactjac.py": {"q"},  # q: the modal coordinates: [0] the rigid mode
    # a: a coefficient array's entries; b: a coefficient array's entries; end_weights: the rigid mode's;
    # lengths: the first or last segment's; q: the modal coordinates: [0] the rigid mode
    "laws/rodrock/exactmap.py": {"a", "b", "end_weights", "lengths", "q"},
    "laws/rodrock/longrod.py": {"mass_per_length"},  # mass_per_length: the last segment's
    "laws/rodrock/tangent.py": {"Z"},  # Z: the segments' first and last impedance
    # _pieces: the first and last piece; b: a coefficient array's entries; e: a basis vector's or
    # series' entry; m: the pieces' panel counts; q: the modal coordinates: [0] the rigid mode; v: the
    # modal velocities ([0] the rigid mode) or a series' last; z: a state vector's or grid's entries
    "laws/wave/_characteristics.py": {"_pieces", "b", "e", "m", "q", "v", "z"},
    # a: a coefficient array's entries; b: a coefficient array's entries
    "laws/wave/_separation.py": {"a", "b"},
    "laws/wave/_window.py": {"b"},  # b: a coefficient array's entries
    # q: the modal coordinates: [0] the rigid mode; v: the modal velocities ([0] the rigid mode) or a
    # series' last
    "laws/wave/coupled.py": {"q", "v"},
    "laws/wave/impact.py": {"v"},  # v: the modal velocities ([0] the rigid mode) or a series' last
    # q: the modal coordinates: [0] the rigid mode; v: the modal velocities ([0] the rigid mode) or a
    # series' last
    "laws/wave/law.py": {"q", "v"},
    # _pieces: the first and last piece; f: a series' first and last values; t: a time grid's first and
    # last
    "laws/wave/sustained.py": {"_pieces", "f", "t"},
    "loads/piecewise.py": {"b"},  # b: a coefficient array's entries
    # s: a root's index or a sum's real and imaginary parts; t: a time grid's first and last
    "measure/dispersion.py": {"s", "t"},
    # energy_f2: the series' last; energy_fv: the series' last
    "measure/drill.py": {"energy_f2", "energy_fv"},
    # energy_fv: the series' last; inc_pulses: the first pulse; strain_k: the series' last
    "measure/kolsky.py": {"energy_fv", "inc_pulses", "strain_k"},
    "measure/recording.py": {"t"},  # t: a time grid's first and last
    # p: a fit's parameter vector; sd: the fit's standard deviations; t: a time grid's first and last
    "measure/reflection.py": {"p", "sd", "t"},
    "measure/spec.py": {"pieces"},  # pieces: the last piece
    "measure/waves.py": {"windows"},  # windows: the last window
    "model.py": {"c"},  # c: a coefficient array's entries
    # V: the Fourier flow's coefficient table (row 1 its frequencies, as _load_flow reads it); W: a
    # stack of like matrices, each named where taken; x: a grid's or state's entries
    "orbits/_admissibility_search.py": {"V", "W", "x"},
    "orbits/_assemble.py": {"t"},  # t: a time grid's first and last
    "orbits/_newton.py": {"t", "z"},  # t: a time grid's first and last; z: a state vector's or grid's entries
    "orbits/_settling.py": {"x"},  # x: a grid's or state's entries
    "orbits/_shooting_data.py": {"q"},  # q: the modal coordinates: [0] the rigid mode
    # a: a coefficient array's entries; b: a coefficient array's entries; c: a coefficient array's
    # entries; e: a basis vector's or series' entry; g: a grid function's first value
    "orbits/_valve_flow.py": {"a", "b", "c", "e", "g"},
    "orbits/charts.py": {"amplitudes"},  # amplitudes: the first harmonic's
    "orbits/coupled.py": {"end_weights"},  # end_weights: the rigid mode's
    # impact_velocities: the first impact's; q: the modal coordinates: [0] the rigid mode; v: the modal
    # velocities ([0] the rigid mode) or a series' last
    "orbits/driven_orbit.py": {"impact_velocities", "q", "v"},
    # fallback: a kernel's one-slot flag; n_orbits: a kernel's one-slot count
    "orbits/one_impact.py": {"fallback", "n_orbits"},
    # contacts: the first contact; impact_times: the first impact time; impact_velocities: the first
    # impact's; states_after_impact: the first impact's; states_before_impact: the first impact's
    "orbits/orbit.py": {"contacts", "impact_times", "impact_velocities", "states_after_impact",
                        "states_before_impact"},
    # sources: the first source; y: a state vector's components
    "orbits/shooting.py": {"sources", "y"},
    # c: a coefficient array's entries; z: a state vector's or grid's entries
    "orbits/valve_admissibility.py": {"c", "z"},
    # G: the cells' first wave; T: a time grid's first and last; h: a one-entry step; z: a state
    # vector's or grid's entries
    "orbits/valve_search.py": {"G", "T", "h", "z"},
    # Eb[]: a matrix's entry; durations: the legs' durations in order; dzb_dh1: the rigid mode's; g: a
    # grid function's first value
    "orbits/valve_segment.py": {"Eb[]", "durations", "dzb_dh1", "g"},
    # areas_m2: the first or last segment's; lengths: the first or last segment's; wavenumbers: a mode's
    # wavenumber
    "physical/bar.py": {"areas_m2", "lengths", "wavenumbers"},
    # drive_states: the first impact's; q: the modal coordinates: [0] the rigid mode; v: the modal
    # velocities ([0] the rigid mode) or a series' last
    "physical/circuit.py": {"drive_states", "q", "v"},
    # drive_states, impact_times, states_after_impact: the first impact's; due: the last impact due
    "physical/circuit_switch.py": {"drive_states", "due", "impact_times", "states_after_impact"},
    "physical/drifter.py": {"t[]"},  # t[]: the selected times' ends
    # f: a series' first and last values; r: a CSV row's first cell; rows[]: the first row's first cell;
    # t: a time grid's first and last; times_s: the first time
    "physical/forces.py": {"f", "r", "rows[]", "t", "times_s"},
    # contacts: the first contact; segments: the first or last segment
    "physical/optimize_outputs.py": {"contacts", "segments"},
    # multipliers: the first multiplier; states_after_impact: the first impact's; t: a time grid's first
    # and last
    "physical/outputs.py": {"multipliers", "states_after_impact", "t"},
    # areas_m2: the first or last segment's; lengths_m: the first segment's
    "physical/piston.py": {"areas_m2", "lengths_m"},
    # chatter: the first blow's count; mass_per_length: the last segment's; v: the modal velocities ([0]
    # the rigid mode) or a series' last
    "physical/results.py": {"chatter", "mass_per_length", "v"},
    # contacts: the first contact; segments: the first or last segment
    "physical/rock.py": {"contacts", "segments"},
    "physical/sensitivity.py": {"F"},  # F: the first cell or the first of a list
    "plotting/circuit.py": {"h[]"},  # h[]: a history's first sample
    # R_CURVES: a grid's first values; data[]: a curve's first value; y: a state vector's components
    "plotting/paper.py": {"R_CURVES", "data[]", "y"},
    # diameters_m: the last segment's; pressing: the last sample; x: a grid's or state's entries
    "plotting/piston.py": {"diameters_m", "pressing", "x"},
    # Q: the first state's coordinates; V: a continuation point: [-1] its parameter
    "simulation/_shortrun.py": {"Q", "V"},
    "simulation/blows.py": {"q"},  # q: the modal coordinates: [0] the rigid mode
    # level_cores: the first level's; q: the modal coordinates: [0] the rigid mode; t: a time grid's
    # first and last; v: the modal velocities ([0] the rigid mode) or a series' last
    "simulation/driven.py": {"level_cores", "q", "t", "v"},
    # q: the modal coordinates: [0] the rigid mode; v: the modal velocities ([0] the rigid mode) or a
    # series' last
    "simulation/experiments.py": {"q", "v"},
    # q: the modal coordinates: [0] the rigid mode; v: the modal velocities ([0] the rigid mode) or a
    # series' last
    "simulation/initial.py": {"q", "v"},
    # q: the modal coordinates: [0] the rigid mode; v: the modal velocities ([0] the rigid mode) or a
    # series' last; x: a grid's or state's entries
    "simulation/_core.py": {"q", "v", "x"},
    # q: the modal coordinates: [0] the rigid mode; v: the modal velocities ([0] the rigid mode) or a
    # series' last
    "simulation/simulate.py": {"q", "v"},
    # _segments: the last segment; q: the modal coordinates: [0] the rigid mode; v: the modal velocities
    # ([0] the rigid mode) or a series' last
    "simulation/trajectory.py": {"_segments", "q", "v"},
    "sweeps/bar_spec.py": {"c"},  # c: a coefficient array's entries
    "sweeps/tasks.py": {"contacts"},  # contacts: the first contact
}
#: module -> the tuples of named values, read by number, that the wider scan met (as
#: ``PYTHON_TUPLES``)
WIDER_TUPLES = {
}
#: module -> the calls whose result, read by number, is an array's or a sequence's entry, not a
#: named value: a one-point evaluation's value (``f(np.array([t]))[0]``), a mode shape's row at the
#: struck end, a unit vector (``eye(n)[-1]``), ``nonzero()``'s indices, a string's parts
#: (``split(".")[0]``), a sorted list's first
CALL_NOT_RECORDS = {
    "cli/_common.py": {"split()", "splitlines()"},  # a dotted name's first part; a message's first line
    "cli/continue_.py": {"sorted()"},  # the best orbit: the sorted list's first
    "cli/drifter.py": {"split()"},  # a dotted name's first part; the words after the first
    "continuation/engine.py": {"eye()"},  # the parameter's unit vector
    "continuation/one_parameter.py": {"eye()"},  # the parameter's unit vector
    "drives/circuit/drive.py": {"asarray()"},  # the rigid mode
    "drives/circuit/endflight.py": {"_at()", "atleast_2d()"},  # the state's first row; the last event's
    "drives/circuit/flight.py": {"atleast_2d()"},  # the last event's flags
    "dynamics/certified.py": {"f()"},  # a one-point evaluation's value
    "dynamics/stepped.py": {"f()", "shapes()"},  # a one-point value; the mode shapes at the struck end
    "laws/rodrock/contact.py": {"asarray()"},  # a one-point value; the first row
    "laws/rodrock/coupled_exact.py": {"self()"},  # a one-point value
    "laws/rodrock/exactmap.py": {"asarray()", "shapes()"},  # a one-point value; the shapes at the end
    "laws/wave/_characteristics.py": {"A()", "Acum()", "integral()"},  # one-point values
    "laws/wave/coupled.py": {"impulse_at()", "integral()"},  # one-point values
    "laws/wave/periodic.py": {"resid()"},  # a one-point value
    "laws/wave/sustained.py": {"fv_at()", "nonzero()"},  # a one-point value; the indices
    "loads/fourier.py": {"nonzero()"},  # the indices
    "measure/dispersion.py": {"_frequency_equation()", "nonzero()"},  # a one-point value; the indices
    "measure/kolsky.py": {"_pulses()"},  # the first pulse found
    "model.py": {"shapes()"},  # the mode shapes at the struck end
    "orbits/rigid.py": {"nonzero()"},  # the indices
    "orbits/valve_admissibility.py": {"_apply()"},  # an affine map's state: [0] the rigid mode
    "orbits/valve_segment.py": {"_legs()"},  # the legs' end states in order
    "physical/forces.py": {"rsplit()"},  # a column name's last part
    "physical/optimize_failures.py": {"splitlines()"},  # the error's first line
    "physical/plausibility.py": {"split()"},  # a message's first word
    "physical/tree.py": {"rsplit()"},  # a dotted key's parts
    "simulation/driven_trajectory.py": {"force()"},  # a one-point value
    "simulation/initial.py": {"ravel()"},  # a one-point value
    "sweeps/store.py": {"split()"},  # a description's first part
    "sweeps/tasks.py": {"generate_state()", "nonzero()"},  # a one-word state; the indices
}
#: module -> the calls whose result is a tuple of named values still read by number (as
#: ``PYTHON_TUPLES``), to be unpacked where next touched
CALL_TUPLES = {
}
#: module -> the names that only the syntax tree meets (inside an f-string's expressions), that are no
#: records: a message's first offending name of a sorted list, a sequence's ends, a column's first value
STRING_NOT_RECORDS = {
    "cli/continue_.py": {"parameters"},  # the curve's two parameters
    "continuation/branch.py": {"values"},  # the first and last value
    "continuation/two_parameter.py": {"values"},  # the first and last value
    "drives/base.py": {"bad"},  # the first bad name
    "drives/valve/drive.py": {"bad"},  # the first bad name
    "laws/rodrock/law.py": {"segments"},  # the last segment
    "measure/model.py": {"missing", "unknown"},  # the first name
    "measure/recording.py": {"args"},  # an exception's message
    "measure/spec.py": {"given", "sorted()"},  # the first name
    "model.py": {"bad"},  # the first bad name
    "paper.py": {"d5[]", "d8[]"},  # a column's first value
    "physical/circuit_switch.py": {"rest"},  # the first rest
    "physical/circuit_branch.py": {"v"},  # the first and last value
    "physical/circuit_parts.py": {"bad", "unknown"},  # the first name
    "physical/config.py": {"extra", "unknown"},  # the first name
    "physical/design_keys.py": {"split()"},  # a message's last part
    "physical/drifter.py": {"extra"},  # the first name
    "physical/geometry.py": {"given"},  # the first name
    "physical/hammer.py": {"missing", "unknown"},  # the first name
    "physical/optimize_drifter.py": {"ranked"},  # the best-ranked design
    "physical/optimize_integers.py": {"history", "runs"},  # the config's own integer design's (the first)
    "physical/optimize_problem.py": {"circuit", "unknown"},  # the first name
    "physical/rock.py": {"unknown"},  # the first name
    "physical/sensitivity.py": {"splitlines()"},  # a message's first line
    "plotting/circuit.py": {"missing"},  # the first name
    "plotting/continuation.py": {"branches", "orbits"},  # the first branch, orbit
    "simulation/blows.py": {"times"},  # the first time
}
#: every list of names passed, module by module
LISTS = (NOT_RECORDS, PYTHON_TUPLES, WIDER_NOT_RECORDS, WIDER_TUPLES, CALL_NOT_RECORDS, CALL_TUPLES,
         STRING_NOT_RECORDS)
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


def _key(match):
    """The name the lists give a slot ``match``: its name, with ``[]`` where subscripts come before."""
    name, chain = match.groups()
    return name + "[]" if chain else name


def _int_literal(node):
    """Whether the syntax-tree ``node`` is an integer literal (``3``, ``-1``)."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
        node = node.operand
    return isinstance(node, ast.Constant) and type(node.value) is int


def _tree_key(node):
    """The name the lists give a subscripted ``node`` of the syntax tree: a name's, an attribute's,
    a call's (``f()``), ``(...)`` for anything else (a parenthesised expression's result)."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    if isinstance(node, ast.Call):
        inner = _tree_key(node.func)
        return "(...)" if inner == "(...)" else inner + "()"
    return "(...)"


def _tree_slots(text):
    """``(line, column, key, source)`` of every slot by an integer literal that the syntax tree of
    ``text`` holds, f-strings' expressions and parenthesised expressions' results too; a chain of
    such subscripts once, by its last (the key with ``[]``, as :data:`SLOT`'s)."""
    tree = ast.parse(text)
    chained = {id(node.value) for node in ast.walk(tree)
               if isinstance(node, ast.Subscript) and _int_literal(node.slice)
               and isinstance(node.value, ast.Subscript)}
    out = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.Subscript) or not _int_literal(node.slice) or id(node) in chained:
            continue
        base, chain = node.value, False
        while isinstance(base, ast.Subscript):
            base, chain = base.value, True
        out.append((node.lineno, node.col_offset, _tree_key(base) + ("[]" if chain else ""),
                    ast.unparse(node)))
    return out


def _slots(text):
    """``(line, column, key, match)`` of every slot by number in the source ``text``, a name's
    (:data:`SLOT`) and a call's result's (:data:`CALL`, ``key`` the function's name with ``()``), and
    those only the syntax tree sees (:func:`_tree_slots`: in f-strings, of parenthesised
    expressions), in the order they stand."""
    code = _code(text)
    out = [(i, m.start(), _key(m), m.group()) for i, line in enumerate(code, start=1)
           for m in SLOT.finditer(line)]
    whole = "\n".join(code)
    for m in CALL.finditer(whole):
        name, chain = m.groups()
        line = whole.count("\n", 0, m.start()) + 1
        column = m.start() - (whole.rfind("\n", 0, m.start()) + 1)
        out.append((line, column, name + ("()[]" if chain else "()"), " ".join(m.group().split())))
    seen = {(line, key) for line, _, key, _ in out}  # what the text scan cannot see: the tree's
    out += [(line, column, key, source) for line, column, key, source in _tree_slots(text)
            if (line, key) not in seen]
    return sorted(out)


def slots_by_number(text, module=""):
    """``(line, match)`` of every record slot indexed by a number in the source ``text`` of
    ``module``, those its lists let pass left out."""
    passed = ANYWHERE.union(*(names.get(module, ()) for names in LISTS))
    return [(line, match) for line, _, key, match in _slots(text) if key not in passed]


def test_the_scan_finds_a_slot_by_number_in_code_only():
    text = ('PR[3] = 1.0\n'
            'x = WB[0] + CNT0[-1] * CH_T[12]\n'
            '# PR[3] in a comment\n'
            's = "CT[9]" + BS[2]\n'
            '"""a docstring quoting CI[0]"""\n'
            'shape, z, n, y = (16, 4), Z[-1], a.shape[0], PR[PR_MASS] + WB[blk][0] + NSF[j, 0]\n')
    assert slots_by_number(text) == [(1, "PR[3]"), (2, "WB[0]"), (2, "CNT0[-1]"), (2, "CH_T[12]"),
                                     (4, "BS[2]"), (6, "Z[-1]"), (6, "WB[blk][0]")]
    assert slots_by_number("u = DP[0] @ v\n", "laws/wave/periodic.py") == []
    assert slots_by_number("u = DP[0] @ v\n") == [(1, "DP[0]")]


def test_the_scan_finds_a_lower_case_slot_and_passes_the_listed_names():
    text = ('bs[3] = bp[1] * bs[0]\n'
            'u, loss = acc[0], _hist[-1]\n'
            'p = q[0] + a.shape[0] + bs[BIT_P] + scratch[2]\n'
            '# bs[3] in a comment\n')
    assert slots_by_number(text) == [(1, "bs[3]"), (1, "bp[1]"), (1, "bs[0]"), (2, "acc[0]"),
                                     (2, "_hist[-1]"), (3, "q[0]"), (3, "scratch[2]")]
    assert slots_by_number("x = qa[0] + pr[0]\n", "dynamics/_event_loop.py") == []
    assert slots_by_number("x = qa[0] + pr[0]\n", "dynamics/modal.py") == [(1, "qa[0]"), (1, "pr[0]")]
    assert slots_by_number("bs[3] = 0.0\n", "laws/rodrock/_rockloop.py") == [(1, "bs[3]")]


def test_the_scan_finds_any_name_an_attribute_and_a_chained_slot():
    """The forms a scan of short names alone missed: a one-letter name, a long name, an attribute,
    a slot of an entry reached by subscripts; a listed name passes only in its own form (``hist``
    listed passes ``hist[-1]``, not ``hist[-1][2]``, and ``h[]`` the reverse)."""
    text = ('r = records[-1][1] + r[1]\n'
            'source = (arrival[3].mode, arrival[2])\n'
            'return self._force_extremes[0] + f.typical[1]\n'
            'if windows and windows[-1][2] == sign and pending[0][0] <= t:\n'
            '    lo = OBJECTIVES[key][0] + hist[-1 - m][2] + hist[-1]\n'
            'x = a[:2] + b[i] + f(a)[:2] + g(b)[i]\n')
    assert slots_by_number(text) == [(1, "records[-1][1]"), (1, "r[1]"), (2, "arrival[3]"), (2, "arrival[2]"),
                                     (3, "_force_extremes[0]"), (3, "typical[1]"), (4, "windows[-1][2]"),
                                     (4, "pending[0][0]"), (5, "OBJECTIVES[key][0]"), (5, "hist[-1 - m][2]"),
                                     (5, "hist[-1]")]
    assert slots_by_number("y = h[0][0] + h[-1]\n", "plotting/circuit.py") == [(1, "h[-1]")]
    assert slots_by_number("y = h[0][0] + h[-1]\n", "orbits/orbit.py") == [(1, "h[0][0]"), (1, "h[-1]")]
    assert slots_by_number("y = Xr[0] + Xr[0][1]\n", "orbits/shooting.py") == [(1, "Xr[0][1]")]


def test_the_scan_finds_a_call_s_result_read_by_number():
    """A call's result read by a number: a function's, a method's, through nested calls, over lines,
    after subscripts, and a parenthesised expression's; a listed call (``nonzero()``) passes in its
    own module only; a slice, a subscript by a name, comments and strings are no slots."""
    text = ('F = evaluate(u, jacobian=False)[0] + self.problem.residual(X)[1]\n'
            'w = np.linalg.svd(J[:, :-1])[2][-1] + g(h(x), [1, 2])[-1]\n'
            'r = fit(yk,\n'
            '        n)[1]\n'
            'x = f(a)[:2] + f(a)[i] + (a + b)[0]\n'
            '# f(x)[0] in a comment\n'
            's = "f(x)[0]" + msg.splitlines()[0]\n')
    assert slots_by_number(text) == [(1, "evaluate(u, jacobian=False)[0]"), (1, "residual(X)[1]"),
                                     (2, "svd(J[:, :-1])[2][-1]"), (2, "g(h(x), [1, 2])[-1]"),
                                     (3, "fit(yk, n)[1]"), (5, "(a + b)[0]"), (7, "splitlines()[0]")]
    assert slots_by_number("i = np.nonzero(m)[0]\n", "sweeps/tasks.py") == []
    assert slots_by_number("i = np.nonzero(m)[0]\n", "orbits/orbit.py") == [(1, "nonzero(m)[0]")]


def test_the_syntax_tree_finds_a_slot_inside_an_f_string():
    """What the text scan cannot see, the tree's walk finds: a slot in an f-string's expression (a
    nested one too), of a parenthesised expression, of an entry's call; a plain string's text is no
    code, and a slot both scans see is reported once."""
    text = ('raise ValueError(f"got {pair[1]!r} and {s[\'channels\'][0]}: {f\'{deep[2]}\'}")\n'
            'x = (a + b)[0] + h[k](x)[1] + r[2]\n'
            's = "not code: q[0]" + f"{len(w)}"\n')
    assert slots_by_number(text) == [(1, "pair[1]"), (1, "s['channels'][0]"), (1, "deep[2]"),
                                     (2, "(a + b)[0]"), (2, "h[k](x)[1]"), (2, "r[2]")]
    assert slots_by_number('m = f"{bad[0]}"\n', "model.py") == []
    assert slots_by_number('m = f"{bad[0]}"\n', "drives/flight.py") == [(1, "bad[0]")]


def test_no_tuple_of_named_values_is_read_by_number():
    """The count the lists keep: no module reads a tuple of named values (a record in Python code)
    by its number, in any form the scans see."""
    assert PYTHON_TUPLES == WIDER_TUPLES == CALL_TUPLES == {}


def test_the_lists_are_disjoint_and_name_modules_that_exist():
    """A name is listed once per module, in one list, and each listed module exists and still
    indexes that name by a number (a list that outlives its reason would hide a new record)."""
    top = Path(impactbar.__file__).parent
    for i, first in enumerate(LISTS):
        for second in LISTS[i + 1:]:
            for module in first.keys() & second.keys():
                assert not first[module] & second[module], module
    for names in LISTS:
        for module, listed in names.items():
            seen = {key for _, _, key, _ in _slots((top / module).read_text())}
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


# -- columns: a table whose columns are different quantities (a record a row) is read by its columns'
# names; the scan sees every subscript with two or more indices whose last is a number (``x[i, 0]``,
# ``x[:, 2:]``, ``x[..., -1]``, ``f(y)[:, 0]``, ``a.b[k][i, 1]``), and these are its other arrays --

#: why an array's columns are not a record's (the categories of NOT_COLUMN_RECORDS)
ONE_TIME = "an evaluation at one time, its only column (or a column vector's)"
LAST_TIME = "the integration's last time point"
RIGID = "modal coordinates by mode: mode 0 the rigid one, the flexible ones from 1"
MATRIX = "a matrix's rows and columns (a Jacobian, a monodromy, transfer or factor matrix)"
COEFFS = "a formula's coefficients by degree, harmonic, mode or segment, a sum's terms in order"
ROOTS = "the roots or the multipliers of one equation, in their order"
PARAMETER = "the augmented unknowns' last entries, the continuation parameters (x, lambda)"
EQUATIONS = "the two equations' residuals (F1, F2) and their rounding floors"
GRID = "a grid's or a bracket list's points in order (the first, the ends)"
CELLS = "the lattice's cells by index (cell 0 the driven end)"
ENTRIES = "a log's entries after its start (its rows are named)"
AXES = "matplotlib's grid of axes"

NOT_COLUMN_RECORDS = {
    "continuation/driven.py": {"J": MATRIX, "P": PARAMETER},
    "continuation/one_parameter.py": {"J": MATRIX, "P": PARAMETER},
    "continuation/two_parameter.py": {"P": PARAMETER, "uu": MATRIX},
    "drives/circuit/endflight.py": {"self._at([t])": ONE_TIME},
    "drives/flight.py": {"sol.y": LAST_TIME},
    "drives/orbitproblem.py": {"P": MATRIX, "Q": MATRIX},
    "drives/valve/_compiled_loop.py": {"eq": ONE_TIME, "ev": ONE_TIME},
    "dynamics/_event_loop.py": {"hpi": COEFFS, "hpr": COEFFS},
    "dynamics/invariants.py": {"C": RIGID, "S": RIGID},
    "dynamics/modal.py": {"q": ONE_TIME, "v": ONE_TIME},
    "dynamics/monodromy.py": {"A": MATRIX, "V": MATRIX},
    "dynamics/stepped.py": {"amp": COEFFS, "fixed.amplitudes": COEFFS, "self.amplitudes": COEFFS},
    "laws/paper/periodic.py": {n: ONE_TIME for n in ("fq", "fv", "qm", "qp", "vm", "vp")},
    "laws/paper/stability.py": {"U": MATRIX, "V": MATRIX, "mu": ROOTS},
    "laws/rodrock/_exactdata.py": {"rows": COEFFS},
    "laws/rodrock/_exacthistory.py": {"BIN": COEFFS},
    "laws/rodrock/_exactode.py": {"Y": COEFFS},
    "laws/rodrock/_exactpieces.py": {"B": COEFFS},
    "laws/rodrock/_rocktangent.py": {"J": MATRIX, "dGf": CELLS, "out": MATRIX},
    "laws/rodrock/contact.py": {"Nq": RIGID, "amp": COEFFS, "modes.shapes(np.zeros(1))": RIGID, "xe": GRID},
    "laws/rodrock/coupled.py": {"field": CELLS},
    "laws/rodrock/_rockslots.py": {"Fn": CELLS, "GG": CELLS},
    "laws/rodrock/coupled_exact.py": {"c": COEFFS},
    "laws/rodrock/coupled_tangent.py": {"cubic": COEFFS, "dq0": RIGID},
    "laws/rodrock/exactjac.py": {"dq": RIGID, "jac": MATRIX},
    "laws/rodrock/exactmap.py": {"Im": RIGID, "Ip": RIGID, "a": RIGID, "b": RIGID, "modes.amplitudes": COEFFS,
                                 "q": RIGID, "v": RIGID, "self.a": COEFFS, "self.b": COEFFS},
    "laws/wave/_jumps.py": {"z": COEFFS},
    "laws/wave/_separation.py": {"fq": ONE_TIME, "fv": ONE_TIME},
    "laws/wave/_window.py": {"ic_": COEFFS},
    "laws/wave/impact.py": {"g": RIGID, "sa": RIGID, "sb": RIGID},
    "laws/wave/law.py": {"jac": MATRIX},
    "laws/wave/periodic.py": {"U": MATRIX, "V": MATRIX, "fq": RIGID, "q": ONE_TIME, "v": ONE_TIME,
                              "y_end": RIGID, "y_minus": RIGID},
    "laws/wave/sustained.py": {"np.diag(w2)": RIGID, "piece.states(np.array([tb]))": ONE_TIME, "q": ONE_TIME,
                               "sys.particular(np.array([ta]), self.level)": ONE_TIME, "v": ONE_TIME},
    "loads/abilities.py": {"q1": ONE_TIME, "v1": ONE_TIME},
    "loads/fourier.py": {n: ONE_TIME for n in ("dq", "dv", "lam", "src", "static", "w2f")},
    "loads/piecewise.py": {"qn": GRID, "vn": GRID},
    "model.py": {"phi": RIGID},
    "orbits/_admissibility_search.py": {"q": ONE_TIME, "v": ONE_TIME, "x": ONE_TIME},
    "orbits/_rigid_arrays.py": {"out[O_MULTS]": ROOTS, "out[O_SCHUR]": ROOTS},
    "orbits/_rigid_scalar.py": {"q": ONE_TIME, "v": ONE_TIME},
    "orbits/_shooting_data.py": {"Q": MATRIX},
    "orbits/find.py": {"q": ONE_TIME, "v": ONE_TIME},
    "orbits/multi_impact.py": {"A": MATRIX, "maps": MATRIX, "q": ONE_TIME, "v": ONE_TIME, "y_plus": RIGID},
    "orbits/rigid.py": {"alpha": COEFFS, "bT": COEFFS, "bounds": GRID, "cT": COEFFS, "mult": ROOTS,
                        "ph": ROOTS, "self.multipliers": ROOTS, "sgn": GRID, "vb": GRID},
    "orbits/stability.py": {"blocks": COEFFS, "vper": ONE_TIME},
    "orbits/valve_search.py": {"F": EQUATIONS, "J": MATRIX, "Y": MATRIX, "floor": EQUATIONS},
    "orbits/valve_segment.py": {"G": MATRIX, "q": RIGID, "v": ONE_TIME},
    "physical/piston.py": {"mf": RIGID},
    "plotting/paper.py": {"axes": AXES},
    "plotting/simulation.py": {"grid": AXES},
    "simulation/_shortrun.py": {"TV": ENTRIES, "self.TV": ENTRIES, "tv": ENTRIES},
    "simulation/blows.py": {"piece.drive_state([t_end])": ONE_TIME},
    "simulation/driven.py": {"sol.y": LAST_TIME},
    "simulation/driven_trajectory.py": {n: ONE_TIME for n in ("q", "q0", "q1", "v", "v0", "v1")},
    "simulation/_core.py": {n: ONE_TIME for n in ("r2", "rv2")},
    "simulation/simulate.py": {n: ONE_TIME for n in ("a", "qe", "r", "rv", "ve")},
    "simulation/trajectory.py": {n: ONE_TIME for n in ("qe", "qm", "ve", "vm")},
}


def _column_by_number(index):
    """Whether a subscript's column (the tuple's last entry) is an integer literal or a slice with
    one (``3``, ``-1``, ``3:``, ``:5``)."""
    if _int_literal(index):
        return True
    return isinstance(index, ast.Slice) and any(b is not None and _int_literal(b) for b in (index.lower,
                                                                                            index.upper))


def columns_by_number(text):
    """``(line, table, source)`` of every subscript in the source ``text`` (its syntax tree: code only,
    f-strings' expressions too) with two or more indices whose last is a number; ``table`` is the
    subscripted expression as written (a name, an attribute, a call, a subscript)."""
    return [(node.lineno, ast.unparse(node.value), ast.unparse(node)) for node in ast.walk(ast.parse(text))
            if isinstance(node, ast.Subscript) and isinstance(node.slice, ast.Tuple)
            and len(node.slice.elts) >= 2 and _column_by_number(node.slice.elts[-1])]


def test_the_column_scan_finds_every_form_of_a_column_by_number():
    text = ('t0, nx = PF[p, 0], PI[p, PI_NEXT]\n'
            'PF[rows, 3:] = math.nan; PI[rows, PI_TERMS:] = 0\n'
            'x = PF[PI[p, 0], PF_START] + NSF[j, k] + PF[p] + out[O][i, j, -1] + self.c[k, :2]\n'
            's = "PF[p, 0]" + f"{PI[q, 1]}" + str(f(y)[..., 0])  # a[:, 0]\n')
    assert sorted((line, source) for line, _, source in columns_by_number(text)) == [
        (1, "PF[p, 0]"), (2, "PF[rows, 3:]"), (3, "PI[p, 0]"), (3, "out[O][i, j, -1]"), (3, "self.c[k, :2]"),
        (4, "PI[q, 1]"), (4, "f(y)[..., 0]")]
    assert {table for _, table, _ in columns_by_number(text)} == {"PF", "PI", "out[O]", "self.c", "f(y)"}


def test_no_module_reads_a_record_column_by_its_number():
    """Every table whose columns are different quantities is read and written by its columns' names
    (the exact blow's pool, channels, nodes, switch log, roots, episodes, stacks and tangent batch in
    ``laws/rodrock/_records.py``; intervals in ``_shared/columns.py``; a module's own tables in it);
    what the scan finds besides is listed in NOT_COLUMN_RECORDS, module by module, with why."""
    top = Path(impactbar.__file__).parent
    found, seen = [], set()
    for path in sorted(top.rglob("*.py")):
        module = path.relative_to(top).as_posix()
        for line, table, source in columns_by_number(path.read_text()):
            seen.add((module, table))
            if table not in NOT_COLUMN_RECORDS.get(module, {}):
                found.append(f"{module}:{line}: {source}")
    assert found == [], "columns by number (name them, or list the array with why):\n" + "\n".join(found)
    listed = {(module, table) for module, tables in NOT_COLUMN_RECORDS.items() for table in tables}
    assert sorted(listed - seen) == [], "listed arrays no module reads by a column's number any more"


def test_each_table_names_its_columns_once_within_its_width():
    """The column names of the tables with a width (``*_COLS``): no two share a column (a switch log's
    values apart: their meaning depends on the switch), every one inside the width."""
    names = {k: v for k, v in vars(_records).items() if k.isupper() and isinstance(v, int)}
    widths = {k[:-5]: v for k, v in names.items() if k.endswith("_COLS")}
    assert set(widths) == {"PF", "PI", "NSF", "NSI", "RD", "EP", "STK", "IMP", "END", "BITREC", "OUT"}
    for table, width in widths.items():
        cols = {k: v for k, v in names.items() if re.fullmatch(table + r"_[A-Z0-9]+", k)
                and k not in (table + "_COLS", "RD_HEAD", "RD_ROWS", "RD_FULL")}
        assert cols, table
        assert len(set(cols.values())) == len(cols), (table, cols)
        assert all(0 <= v < width for v in cols.values()), (table, cols)


def strides(text):
    """``(line, source)`` of every subscript in the source ``text`` with a slice whose step is a
    number other than 1 and -1: a flat record's fields taken every so many places (``x[1::4]``, a
    tuple's ``[::2]``)."""
    def strided(index):
        return isinstance(index, ast.Slice) and index.step is not None and _int_literal(index.step) \
            and abs(ast.literal_eval(index.step)) != 1
    return [(node.lineno, ast.unparse(node)) for node in ast.walk(ast.parse(text))
            if isinstance(node, ast.Subscript)
            and any(strided(i) for i in (node.slice.elts if isinstance(node.slice, ast.Tuple)
                                         else [node.slice]))]


def test_the_stride_scan_finds_a_field_taken_every_so_many_places():
    text = ('h1, h3 = d[1::4], d[3::4]\nkey = design(u)[::2]\nrev = x[::-1] + x[0:5:1] + q[:, ::3]\n'
            's = f"{e[::2]}"  # e[1::2]\n')
    assert sorted(strides(text)) == [(1, "d[1::4]"), (1, "d[3::4]"), (2, "design(u)[::2]"), (3, "q[:, ::3]"),
                                     (4, "e[::2]")]


def test_no_module_reads_a_record_by_a_stride():
    """A flat array of records (an orbit's four durations per impact, a design's id and changes, runs'
    starts and ends) is reshaped to a row per record and read by its columns' names, not every so
    many places."""
    top = Path(impactbar.__file__).parent
    found = [f"{path.relative_to(top).as_posix()}:{line}: {source}" for path in sorted(top.rglob("*.py"))
             for line, source in strides(path.read_text())]
    assert found == [], "records read by a stride:\n" + "\n".join(found)
