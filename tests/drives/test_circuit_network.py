"""The oil circuit as a network of part records (``impactbar.drives.circuit._network``): each part
describes itself as records, the drive composes them, and one compiled vector field, Jacobian and set
of event functions serves every topology.

- The preset drifter's records against the preset's kernel written by hand (``circuit_field_reference``:
  ``_base``, ``jac_base``, ``circuit_events``): the same numbers to the bit (the sign of a zero included)
  at random states, in every mode, rigid and with four flexible modes, with a pump and with a held supply,
  with and without an accumulator and a relief valve; and the code generated for the network's topology
  (``_netgen.generate``) the same numbers again.
- A circuit the kernel cannot describe, a return-line accumulator (a node between the valve's
  return port and the tank, with a gas accumulator and an orifice to the tank), defined here alone:
  its vector field against the same equations written out with numpy, its energy account closing
  (the pump's work is the sum of the other terms) and its Jacobian against central differences; the
  code generated for it gives the network's numbers to the bit.
- The generated source depends on the topology only: the same for every mode and value of a network,
  another for another network; written once to its folder, compiled in memory where that cannot be
  written.
"""

import dataclasses
import itertools

import network_interpreter as NI
import numpy as np
import pytest
from circuit_parts_reference import network_jacobian_fd

import circuit_field_reference as K
from impactbar.drives.circuit import Accumulator, Oil, Supply
from impactbar.drives.circuit import _netgen as NG
from impactbar.drives.circuit import _network as NW
from impactbar.physical import circuit_preset

N_STATES = 40  # random states per mode


@pytest.fixture(scope="module")
def drifter():
    return circuit_preset("circuit-drifter")


def _variants(drive):
    """The preset's drive and the same circuit with its supply held, without an accumulator and
    without a relief valve (each with the modes its flags can take)."""
    su = drive.supply
    held = dataclasses.replace(drive, supply=dataclasses.replace(su, pump_flow=None, pressure=1.5))
    return {"preset": drive, "held": held, "no accumulator": dataclasses.replace(drive, accumulator=None),
            "no relief": dataclasses.replace(drive, supply=dataclasses.replace(su, relief_pressure=np.inf))}


def _random_state(rng, M, n_energy):
    xv = rng.choice([0.0, 1.0, rng.uniform()])
    return np.concatenate((rng.normal(0.0, 0.02, 2 * M), rng.uniform(0.05, 2.0, 3), [xv],
                           np.zeros(n_energy)))


def _bits(a):
    return np.asarray(a, dtype=float).view(np.int64)


@pytest.mark.parametrize("n_modes", [0, 4])
@pytest.mark.parametrize("variant", ["preset", "held", "no accumulator", "no relief"])
def test_the_drifters_records_give_the_kernels_numbers_to_the_bit(drifter, n_modes, variant):
    """Every mode ``(target, moving, acc, relief)``: 16 (a held supply's relief valve never opens,
    its mode keeps ``relief`` 0: 8), each at ``N_STATES`` random states (pressures in (0.05, 2), the
    spool at 0, 1 or between, small modal displacements and velocities)."""
    drive = _variants(drifter.drive())[variant]
    model = drifter.model().with_(n_modes=n_modes)
    M = n_modes + 1
    n = 2 * M + 4
    rng = np.random.default_rng(7 + n_modes)
    checked = 0
    for mode in itertools.product((0, 1), (0, 1), (0, 1), (0, 1)):
        if drive.supply.held and mode[3]:
            continue  # the kernel's held supply's work leaves out a relief flow that cannot be there
        par = K.preset_par(drive, model, mode)
        net = drive._network_par(model, mode)
        assert NI.sizes(net, M) == (4, 3, K.N_ENERGY, 3)
        gen = NG.generate(net[K.HEAD + 3 * M:])
        for _ in range(N_STATES):
            y = _random_state(rng, M, K.N_ENERGY)
            want, got = np.empty(n + K.N_ENERGY), np.full(n + K.N_ENERGY, np.nan)
            K._base(y, par, M, want)
            NI.base(y, net, M, got)
            A, B = np.empty((n, n)), np.full((n, n), np.nan)
            K.jac_base(y, par, M, A)
            NI.jac_base(y, net, M, B)
            g, h = np.empty(3), np.full(3, np.nan)
            K.circuit_events(y[2 * M + 3], y[2 * M + 2], par, K.HEAD + 3 * M, g, 0)
            NI.events(y[2 * M:], net, M, h, 0, -y[0])
            assert np.array_equal(_bits(got), _bits(want)), (mode, got - want)
            assert np.array_equal(_bits(B), _bits(A)), (mode, np.argwhere(_bits(B) != _bits(A)))
            assert np.array_equal(_bits(h), _bits(g)), (mode, h, g)
            got2, B2, h2 = np.full_like(got, np.nan), np.full_like(B, np.nan), np.full_like(h, np.nan)
            gen.base(y, net, M, got2)
            gen.jac_base(y, net, M, B2)
            gen.events(y[2 * M:], net, M, h2, 0, -y[0])
            assert np.array_equal(_bits(got2), _bits(want)), (mode, got2 - want)
            assert np.array_equal(_bits(B2), _bits(A)), (mode, np.argwhere(_bits(B2) != _bits(A)))
            assert np.array_equal(_bits(h2), _bits(g)), (mode, h2, g)
            got3, B3 = np.full_like(got, np.nan), np.full_like(B, np.nan)
            gen.rates(y, net, M, got3, B3)  # (both at once: the variational right-hand side's)
            assert np.array_equal(_bits(got3), _bits(want)) and np.array_equal(_bits(B3), _bits(A)), mode
            checked += 1
    assert checked == N_STATES * (8 if drive.supply.held else 16)


def test_the_composition_refuses_a_network_it_cannot_integrate():
    oil = Oil(100.0, 0.01)
    sup = Supply(pump_flow=0.1, hose_volume=1.0, front_coefficient=1.0, tank_pressure=0.03)
    recs = sup.records(0, 1, 0, oil)
    with pytest.raises(ValueError, match="exactly one valve"):
        NW.compose(recs, 1, 4, 1, 0)
    valve = NW.record(NW.VALVE, pressure_port=0, work_port=0, return_port=5, coefficient=1.0, ptr2=1e-4)
    with pytest.raises(ValueError, match="names node 5"):
        NW.compose(recs + [valve], 1, 4, 1, 0)
    with pytest.raises(ValueError, match="a chamber needs a node"):
        NW.compose(recs + Accumulator(0.5, 1.0).records(0) + [NW.record(NW.CHAMBER, node=0, area=-1.0)],
                   1, 4, 1, 0)
    with pytest.raises(ValueError, match="fields are"):
        NW.record(NW.PUMP, nod=0)


# -- a part the kernel does not have: a return-line accumulator ------------------------------------

#: the return network's nodes (states first, the tank held) and energy slots
FRONT, REAR, SUPPLY, RETURN, TANK = range(5)
E_PUMP, E_PISTON, E_ORIF, E_TANK, E_FRONT, E_REAR, E_SUPPLY, E_GAS, E_RET, E_RETGAS = range(10)
N_EN, N_EV = 10, 4
RAMP, ACC, REL, RETACC = range(4)


@dataclasses.dataclass(frozen=True)
class ReturnAccumulator:
    """A return line between the valve's return port and the tank: a volume of oil with a gas
    accumulator on it, drained to the tank through an orifice (records only: no kernel edited)."""

    volume: float
    gas: Accumulator
    coefficient: float

    def records(self, node, tank, oil, holding):
        return [NW.record(NW.NODE, id=node, volume=self.volume, beta=oil.bulk_modulus,
                          compression_energy=E_RET),
                *self.gas.records(node, holding=holding, energy=E_RETGAS, event=RETACC),
                NW.record(NW.ORIFICE, source=node, target=tank, coefficient=self.coefficient,
                          ptr2=oil.transition_pressure ** 2, energy=E_ORIF)]


def _return_network(drive, model, mode, line):
    """``par`` of the drifter with its valve's return port on the return line."""
    target, moving, acc, rel, racc = mode
    ch, va, su, oil = drive.chambers, drive.valve, drive.supply, drive.oil
    recs = ch.records(FRONT, REAR, oil.bulk_modulus, front_energy=E_FRONT, rear_energy=E_REAR)
    recs += su.records(SUPPLY, TANK, FRONT, oil, relief_open=bool(rel),
                       energies={"pump": E_PUMP, "orifices": E_ORIF, "tank": E_TANK, "compression": E_SUPPLY},
                       relief_event=REL)
    tau = va.switching_time
    recs += va.records(SUPPLY, REAR, RETURN, oil.transition_pressure,
                       rate=(1.0 if target else -1.0) / tau if moving else 0.0,
                       opening=(1 if target else -1) if moving else 0, energy=E_ORIF, event=RAMP)
    recs += drive.accumulator.records(SUPPLY, holding=bool(acc), energy=E_GAS, event=ACC)
    recs += line.records(RETURN, TANK, oil, bool(racc))
    net = NW.compose(recs, 4, N_EN, N_EV, E_PISTON)
    return np.concatenate((drive._par(model, mode[:4]), net))


def _numpy_field(drive, model, mode, line, y):
    """The return network's equations written out: ``(y', events)``."""
    target, moving, acc, rel, racc = mode
    ch, va, su, oil, ac = drive.chambers, drive.valve, drive.supply, drive.oil, drive.accumulator
    M = model.n_modes + 1
    q, qd = y[:M], y[M:2 * M]
    pf, pr, ps, pt_, xv = y[2 * M:2 * M + 5]
    beta, ptr2, pt = oil.bulk_modulus, oil.transition_pressure ** 2, su.tank_pressure
    w, wd = -model.drive_weights @ q, -model.drive_weights @ qd

    def phi(x):
        return x * (x * x + ptr2) ** -0.25

    def compliance(gas, p, on):
        n = gas.polytropic_exponent
        return gas.volume / n * gas.precharge ** (1 / n) * p ** (-1 / n - 1) if on else 0.0

    qf = su.front_coefficient * phi(ps - pf)
    qin = va.coefficient * xv * phi(ps - pr)
    qout = va.coefficient * (1 - xv) * phi(pr - pt_)
    qrel = su.relief_coefficient * (ps - su.relief_pressure) if rel else 0.0
    qt = line.coefficient * phi(pt_ - pt)
    a = ch.area_ratio
    vf, vr = ch.front_volume + a * w, ch.rear_volume - w
    cs = su.hose_volume / beta + compliance(ac, ps, acc)
    cr = line.volume / beta + compliance(line.gas, pt_, racc)
    dpf = beta / vf * (qf - a * wd)
    dpr = beta / vr * (qin - qout + wd)
    dps = (su.pump_flow - qf - qin - qrel) / cs
    dpt = (qout - qt) / cr
    force = pr - a * pf
    qdd = force - model.d * qd - model.frequencies ** 2 * q
    rate = ((1.0 if target else -1.0) / va.switching_time) if moving else 0.0
    E = [ps * su.pump_flow, -force * wd,
         qf * (ps - pf) + qin * (ps - pr) + qout * (pr - pt_) + qrel * (ps - pt) + qt * (pt_ - pt),
         pt * (qrel + qt), vf * pf * dpf / beta, vr * pr * dpr / beta, su.hose_volume * ps * dps / beta,
         ps * compliance(ac, ps, acc) * dps, line.volume * pt_ * dpt / beta,
         pt_ * compliance(line.gas, pt_, racc) * dpt]
    ev = [xv - 1.0 if (moving and target) else (xv if moving else 1.0), ps - ac.precharge,
          ps - su.relief_pressure, pt_ - line.gas.precharge]
    return np.concatenate((qd, qdd, [dpf, dpr, dps, dpt, rate], E)), np.array(ev)


@pytest.mark.parametrize("n_modes", [0, 4])
def test_a_return_line_accumulator_is_a_new_part_of_records_only(drifter, n_modes):
    drive = drifter.drive()
    model = drifter.model().with_(n_modes=n_modes)
    line = ReturnAccumulator(volume=0.3, gas=Accumulator(precharge=0.08, volume=0.5, polytropic_exponent=1.3),
                             coefficient=1.2)
    M = n_modes + 1
    n = 2 * M + 5
    rng = np.random.default_rng(11)
    for mode in itertools.product((0, 1), (0, 1), (0, 1), (0, 1), (0, 1)):
        par = _return_network(drive, model, mode, line)
        assert NI.sizes(par, M) == (5, 4, N_EN, N_EV)
        gen = NG.generate(par[K.HEAD + 3 * M:])
        for _ in range(10):
            y = np.concatenate((rng.normal(0.0, 0.02, 2 * M), rng.uniform(0.05, 2.0, 4),
                                [rng.choice([0.0, 1.0, rng.uniform()])], np.zeros(N_EN)))
            out = np.empty(n + N_EN)
            NI.base(y, par, M, out)
            want, ev = _numpy_field(drive, model, mode, line, y)
            assert np.allclose(out, want, rtol=1e-13, atol=1e-13 * np.max(np.abs(want))), mode
            # the account closes: the pump's work goes to the piston, the openings, the tank, the
            # oil's compression and the gas
            assert abs(out[n + E_PUMP] - np.sum(out[n + 1:])) <= 1e-12 * np.sum(np.abs(out[n:]))
            g = np.empty(N_EV)
            NI.events(y[2 * M:n], par, M, g, 0, -y[0])
            assert np.allclose(g, ev, rtol=0.0, atol=1e-15)
            out2, g2, A2 = np.full_like(out, np.nan), np.full_like(g, np.nan), np.full((n, n), np.nan)
            gen.base(y, par, M, out2)
            gen.events(y[2 * M:n], par, M, g2, 0, -y[0])
            assert np.array_equal(_bits(out2), _bits(out)), (mode, out2 - out)
            assert np.array_equal(_bits(g2), _bits(g)), (mode, g2, g)
            A = np.empty((n, n))
            NI.jac_base(y, par, M, A)
            gen.jac_base(y, par, M, A2)
            assert np.array_equal(_bits(A2), _bits(A)), (mode, np.argwhere(_bits(A2) != _bits(A)))
            out3, A3 = np.full_like(out, np.nan), np.full((n, n), np.nan)
            gen.rates(y, par, M, out3, A3)
            assert np.array_equal(_bits(out3), _bits(out)) and np.array_equal(_bits(A3), _bits(A)), mode
            fd = network_jacobian_fd(y, par, M, n, N_EN)
            scale = np.max(np.abs(A), axis=1, keepdims=True)
            assert np.allclose(A, fd, rtol=1e-6, atol=1e-7 * scale), (mode, np.max(np.abs(A - fd)))


# -- the generated code's source and its cache --------------------------------------------------------


def test_the_generated_source_is_one_per_topology(drifter):
    """Every mode and every parameter value of the drifter give one source (the values are read from
    ``par``); the return line, another topology, another source; the source names no value."""
    drive = drifter.drive()
    model = drifter.model()
    M = model.n_modes + 1
    sources = {NG.emit(drive._network_par(model, mode)[K.HEAD + 3 * M:])
               for mode in itertools.product((0, 1), repeat=4)}
    oil = dataclasses.replace(drive.oil, bulk_modulus=2 * drive.oil.bulk_modulus)
    other = dataclasses.replace(drive, oil=oil)
    sources.add(NG.emit(other._network_par(model, (1, 1, 1, 0))[K.HEAD + 3 * M:]))
    assert len(sources) == 1
    line = ReturnAccumulator(volume=0.3, gas=Accumulator(precharge=0.08, volume=0.5), coefficient=1.2)
    ret = NG.emit(_return_network(drive, model, (1, 1, 1, 0, 1), line)[K.HEAD + 3 * M:])
    assert ret not in sources
    assert repr(drive.oil.bulk_modulus) not in sources.pop()
    with pytest.raises(ValueError, match="composed network"):
        NG.emit(np.zeros(NW.NW_SIZE + 3))


def test_the_generated_module_is_written_once_and_compiled_in_memory_where_it_cannot_be(tmp_path):
    recs = [NW.record(NW.NODE, id=0, volume=1.0, beta=100.0, compression_energy=0),
            NW.record(NW.NODE, id=1, pressure=0.0),
            NW.record(NW.VALVE, pressure_port=0, work_port=1, return_port=1, coefficient=1.0, ptr2=1e-4,
                      rate=0.5, open=1, event=0)]
    net = NW.compose(recs, 1, 2, 1, 1)
    gen = NG.generate(net, folder=tmp_path)
    assert gen.path.parent == tmp_path and gen.path.read_text() == gen.source
    stamp = gen.path.stat().st_mtime_ns
    NG._MEMO.clear()
    assert NG.generate(net, folder=tmp_path).path.stat().st_mtime_ns == stamp
    blocked = tmp_path / "a file"
    blocked.write_text("")
    mem = NG.generate(net, folder=blocked)
    assert mem.path is None
    par = np.concatenate((np.zeros(K.HEAD + 3), net))
    y = np.array([0.0, 0.0, 0.7, 0.4, 0.0, 0.0])
    for g in (gen, mem):
        out, want = np.empty(6), np.empty(6)
        NI.base(y, par, 1, want)
        g.base(y, par, 1, out)
        assert np.array_equal(_bits(out), _bits(want))


# -- the flights through the generated code --------------------------------------------------------------


@pytest.mark.parametrize("variational", [False, True], ids=["plain", "variational"])
@pytest.mark.parametrize("modes", [0, 2])
@pytest.mark.parametrize("variant", ["preset", "held"])
def test_a_flight_through_the_generated_code_is_the_kernels_to_the_bit(drifter, variant, variational, modes):
    """``circuit_flight`` (the flight's kernels and CVODE's C callbacks generated for the network's
    topology, the network read from ``par``) against ``kernels=circuit_field_reference.KERNELS`` (the
    preset's hand-written kernels and callbacks): the same steps, states, rates and fundamental matrix, to the
    bit, by the compiled driver and (plain) through scikit-sundae's interface (CVODE's methods:
    Adams-Moulton for the flexible piston's plain flights, which ``"auto"`` gives the generated
    code's DOP853)."""
    from impactbar.drives import DriveState
    from impactbar.drives.circuit import CircuitFlightSettings, _sundials
    from impactbar.drives.circuit import flight as F

    if not _sundials.available():
        pytest.skip(_sundials.reason())
    drive = _variants(drifter.drive())[variant]
    model = drifter.model().with_(n_modes=modes)
    M = modes + 1
    q, v = np.zeros(M), np.zeros(M)
    q[0] = -0.08
    state = DriveState((1, 1, 1, 0), np.array([0.9, 0.9, 0.9, 0.3]))
    for compiled in (True, False) if not variational else (True,):
        settings = CircuitFlightSettings(compiled=compiled, sensitivity="cvode",
                                         multistep="adams" if modes and not variational else "auto")
        a, b = (F.circuit_flight(drive, model, state, 0.3, q, v, 50.0, settings, variational, kernels=k)
                for k in (None, K.KERNELS))
        assert a.end == b.end and a.t == b.t and a.piece.t.size > 50
        for x, y in ((a.piece.t, b.piece.t), (a.piece.y, b.piece.y), (a.piece.f, b.piece.f), (a.q, b.q),
                     (a.v, b.v), (a.z, b.z)):
            assert np.array_equal(x, y)
        if variational:
            assert np.array_equal(a.sensitivity, b.sensitivity)
    net, code = drive._compiled_network((1, 1, 1, 0))
    assert code.CALLBACKS is not None and code.CALLBACKS[-1] == K.N_EVENTS
    assert np.array_equal(net, drive._network((1, 1, 1, 0)))


# -- the library runs the generated kernel only ----------------------------------------------------------

#: the parameters of the preset's parts that only its equations written by hand read (the reference's own,
#: after the bar's entries of ``par``: ``circuit_field_reference.preset_par``): the generated code reads
#: each part's values from its records
_PRESET_SCALARS = {"NUR", "NUF", "KV", "KF", "QP", "NUS", "PT", "PREL", "KREL", "P0", "NU0", "NPOL", "BETA",
                   "PTR2", "HELD", "ACC", "REL", "XRATE", "OPEN", "HASREL", "HASACC"}


def _hand_written_reads(path):
    """``(function, index)`` of each read ``par[X]`` or ``par[o + X]`` (from the reference's offset) of a
    preset scalar (:data:`_PRESET_SCALARS`, bare or as a module's attribute) inside a compiled function
    (``njit`` or ``cfunc``) of ``path``."""
    import ast

    found = []
    for fn in ast.walk(ast.parse(path.read_text())):
        if not isinstance(fn, ast.FunctionDef) or not any(
                "njit" in ast.unparse(d) or "cfunc" in ast.unparse(d) for d in fn.decorator_list):
            continue
        for node in ast.walk(fn):
            if isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Load):
                key = node.slice
                if isinstance(key, ast.BinOp) and ast.unparse(key.left) == "o":  # (from the offset o)
                    key = key.right
                name = key.id if isinstance(key, ast.Name) else key.attr if isinstance(key, ast.Attribute) \
                    else None
                if name in _PRESET_SCALARS:
                    found.append((fn.name, name))
    return found


def test_no_library_module_holds_the_preset_circuits_equations_by_hand():
    """The flights, the variational flights and the blows run the code generated for the circuit's
    network from its parts' records: no compiled function of the library reads a preset scalar of
    ``par`` (the equations of the preset written by hand, kept as the tests' reference in
    ``circuit_field_reference``, ``circuit_blow_reference``, which the scan does find)."""
    from pathlib import Path

    import impactbar.drives.circuit as pkg

    root = Path(pkg.__file__).parent
    found = {str(p.relative_to(root)): r for p in sorted(root.rglob("*.py")) if (r := _hand_written_reads(p))}
    assert found == {}
    reference = Path(__file__).resolve().parents[1] / "circuit_field_reference.py"
    assert {f for f, _ in _hand_written_reads(reference)} >= {"_flows", "_base", "jac_base", "circuit_events"}


def test_par_holds_only_what_the_librarys_kernels_read():
    """Each scalar slot of ``par`` (``_bar``'s indices below ``HEAD``) is read as ``par[NAME]`` by a
    kernel of the library (a compiled function, or the code :mod:`_netgen` and :mod:`_endgen` write):
    the preset's parts' values are not there (the tests' reference writes its own,
    ``circuit_field_reference.preset_par``)."""
    import re
    from pathlib import Path

    import impactbar.drives.circuit as pkg
    from impactbar.drives.circuit import _bar

    slots = {n for n, v in vars(_bar).items() if type(v) is int and n.isupper() and 0 <= v < _bar.HEAD
             and not n.endswith("_EV") and not n.startswith("N_")}
    assert "DAMP" in slots and sorted(vars(_bar)[n] for n in slots) == list(range(_bar.HEAD))
    text = "".join(p.read_text() for p in Path(pkg.__file__).parent.rglob("*.py"))
    read = {n for n in slots if re.search(rf"\bpar\[{n}\]", text)}
    assert read == slots, sorted(slots - read)
    assert not slots & _PRESET_SCALARS
