"""The drive's work on the piston is the quadrature the drive names (``piston_work`` of its ability
:class:`~impactbar.drives.Quadratures`), wherever it keeps it among its own quadratures: the pieces of
a run give it as ``piston_work()``, and no solver reads a drive's quadratures by a literal index (the
oil circuit keeps it second, a drive of its own may keep it anywhere).

- ``Metered``: a first-order lag of the force toward the level of its mode (``Lag`` of
  ``test_new_drive.py``) that keeps quadratures in the order it declares, one of them its work on the
  piston ``int p u_t(0, t) dt`` (zero while the piston rests on the stop), the others not (the time,
  ``int z^2 dt``). On a rigid piston with ``R = 0`` every impact leaves it resting on the stop while
  the force presses it: the run's energy account closes, and its work is the same drive's without
  quadratures, only if the rests add the piston's quadrature and not another.
- A blow's piece (:class:`~impactbar.simulation.blows.BlowPiece`) sums its drive pieces' work on the
  piston, the last one cut where the piece ends, whatever slot the pieces keep it in.
"""

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from test_new_drive import Lag  # (the test's directory is on the path, as pytest runs it)

import impactbar
from impactbar import BarModel, InitialState, simulate
from impactbar.drives import DriveAbilities, Quadratures
from impactbar.drives.flight import QuadratureRestPiece
from impactbar.simulation.blows import BlowPiece

TOP = Path(impactbar.__file__).parent


@dataclass(frozen=True)
class Metered(Lag):
    """The lag drive with the quadratures ``names`` (``"piston"``, ``"clock"``, ``"square"``) in that
    order."""

    names: tuple = ()

    @property
    def abilities(self):
        work = self.names.index("piston") if "piston" in self.names else None
        return DriveAbilities(quadratures=Quadratures(len(self.names), self._integrands, work))

    def _integrands(self, mode, z, q, v, model=None):
        terms = {"piston": float(z[0]) * float(v[0]), "clock": 1.0, "square": float(z[0]) ** 2}
        return np.array([terms[n] for n in self.names])


@pytest.mark.parametrize("names", [("piston", "clock"), ("clock", "square", "piston"), ("square", "clock")])
def test_the_rests_add_the_drives_work_on_the_piston_not_another_quadrature(names):
    """The rigid piston with ``R = 0`` rests on the stop after each impact: the account's work is the
    same run's under the drive without quadratures (the rests' work is the force against the driven
    end's velocity, zero), and the account closes."""
    model = BarModel(s=10.0, d=0.05, R=0.0, n_modes=0)
    start = InitialState.rigid(-0.5, 0.3)
    plain = simulate(model, Metered(1.0, 1.0, 1.0, lag=0.5), start, 50.0)
    run = simulate(model, Metered(1.0, 1.0, 1.0, lag=0.5, names=names), start, 50.0)
    rests = [p for p in run.pieces if isinstance(p, QuadratureRestPiece)]
    assert run.n_impacts >= 5 and len(rests) >= 5
    assert sum(p.t_end - p.t0 for p in rests) > 1.0  # (what the clock would add)
    np.testing.assert_allclose(run.impact_times, plain.impact_times, rtol=0, atol=1e-7)
    assert run.energy.work == pytest.approx(plain.energy.work, rel=1e-7)
    assert run.energy.relative_residual < 1e-9
    assert all(p.piston_work() == 0.0 for p in rests)


def test_a_piston_work_quadrature_outside_the_drives_quadratures_is_refused():
    with pytest.raises(ValueError, match=r"piston_work must be None or an integer in \[0, 2\)"):
        QuadratureRestPiece(0.0, 1.0, None, np.zeros(1), 1, np.ones(1), [1.0, 2.0], 2)


class _Piece:
    """A drive piece over ``[t0, t_end]`` keeping its work on the piston in the quadrature ``slot``
    of three, each growing linearly (``energies_at`` interpolates)."""

    def __init__(self, t0, t_end, totals, slot):
        self.t0, self.t_end, self.t = t0, t_end, np.array([t0, t_end])
        self.totals, self.slot = np.asarray(totals, dtype=float), slot

    def energies(self):
        return self.totals.copy()

    def energies_at(self, t):
        return self.totals * (t - self.t0) / (self.t_end - self.t0)

    def piston_work(self):
        return float(self.totals[self.slot])

    def piston_work_at(self, t):
        return float(self.energies_at(t)[self.slot])


class _Record:
    duration = 1.0

    def account(self, tau):
        return 0.0, 0.0, 0.0


@pytest.mark.parametrize("slot", [0, 2])
def test_a_blows_account_sums_its_pieces_work_on_the_piston(slot):
    """Three drive pieces, the blow's piece ending in the middle of the last one: the account's drive
    work is the first two pieces' work and half the third's, from the slot they keep it in."""
    pieces = [_Piece(0.0, 0.5, [1.0, 10.0, 100.0], slot), _Piece(0.5, 1.0, [2.0, 20.0, 200.0], slot),
              _Piece(1.0, 2.0, [4.0, 40.0, 400.0], slot)]
    arrival = (np.zeros(1), np.zeros(1))
    blow = BlowPiece(0.0, 1.5, _Record(), arrival, pieces, np.ones(1), end_state=arrival)
    want = [1.0 + 2.0 + 2.0, None, 100.0 + 200.0 + 200.0][slot]
    assert blow.account()[0] == pytest.approx(want, rel=1e-15)
    assert blow.piston_work() == pytest.approx(want, rel=1e-15)


_LITERAL = re.compile(r"\benergies(?:_at)?\([^()]*\)\s*\[\s*[-+]?\d")


def literal_reads(text):
    """The lines of ``text`` that index a drive's quadratures (``energies()``, ``energies_at(t)``) by a
    literal, ``(number, line)``."""
    return [(j, ln.strip()) for j, ln in enumerate(text.splitlines(), 1) if _LITERAL.search(ln)]


def test_the_scan_sees_a_literal_read():
    planted = ("w = float(piece.energies()[1])\nE = p.energies_at(t) [ 0]\n"
               "ok = p.energies()[layout.energy['pump']]")
    assert [j for j, _ in literal_reads(planted)] == [1, 2]


def test_no_module_reads_a_drives_quadratures_by_a_literal_index():
    """The drive's work on the piston is ``piece.piston_work()``; another term by its name in the
    drive's layout (``layout.energy["pump"]``)."""
    reads = [f"{p.relative_to(TOP)}:{j}: {ln}" for p in sorted(TOP.rglob("*.py"))
             for j, ln in literal_reads(p.read_text(encoding="utf-8"))]
    assert reads == []
