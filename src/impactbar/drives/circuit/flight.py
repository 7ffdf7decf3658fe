r"""One flight of the bar under the oil circuit, integrated by SUNDIALS' CVODE (theory §11).

**The integrator, chosen by measurement.** The circuit is stiff (an oil volume behind an orifice relaxes
in ``V / (beta K phi')``, some ``1e-5`` of a period on the example drifter, ``1e-8`` in the ideal limit,
against a period of order 1) and the accuracy asked of it is tight (the energy account to ``1e-8``,
periodic orbits to ``1e-8``), so ``rtol = 1e-10``. scipy's ``Radau``, ``BDF`` and ``LSODA`` take their
steps in Python; CVODE (BDF of orders 1 to 5, SUNDIALS) runs its steps, Newton iterations and root
finding in C. On one stroke flight of the preset ``circuit-drifter`` (``benchmarks/bench_circuit.py``,
this 2-core machine while shared) ``Radau`` with the same compiled right-hand side and Jacobian took
0.14 s (203 steps), CVODE 0.5 ms (380), their impact times 5e-11 apart. The flight's loop runs in
compiled code and hands CVODE the compiled vector field, Jacobian and event functions as C callbacks
(:mod:`._cvode`, on the SUNDIALS libraries that scikit-sundae ships, :mod:`._sundials`): through
scikit-sundae's Python interface, where each of those calls is a call of Python, the same flight took
8.5 ms (``compiled=False`` of :class:`~.settings.CircuitFlightSettings`; the same steps to the bit).
CVODE's counters on it: 380 steps, 498 right-hand sides, 17 error-test failures, 497 Newton iterations,
7 Jacobians: the steps are those BDF's error control asks at this tolerance (the pressures' fast
transients after each switch and impact, the valve's ramp; measured over 20 periods, ``rtol = 1e-8``
took a quarter fewer steps for errors a hundred times larger), not failures. With a flexible piston the
steps follow the modes' oscillations, which the pressures carry, more than the oil's stiffness, and the
plain flights take CVODE's Adams-Moulton method (orders 1 to 12) instead: a stroke of the preset's
piston with 4 modes in 5,025 steps against BDF's 11,344, nearer an independent integration (the
settings' ``multistep``; theory §11, *The integrator*). Where the oil is not stiff against the modes
(:data:`EXPLICIT_STIFFNESS`) those plain flights take the explicit DOP853 instead, compiled with the
network's code (:mod:`._dop853`: scipy's method, CVODE's root finding on its dense output; about half
Adams' CPU time at equal or better accuracy, at :data:`EXPLICIT_TOLERANCE` times its tolerance). The
variational flights' Newton systems (:math:`n + 8 + n^2` unknowns) are solved by the band solver
(``band=True``, the default; ``Phi`` stored by columns), its LU taken once on the state's ``n x n``
block and applied to each column of ``Phi``'s (``blocks=True``, the default; the plain flights' by
CVODE the same LU of the state's block, the energies' rows the identity's, where the dense solver
factored them whole: the same steps, to the bit). Its events (the arrival
``c . q = 0``, the switch positions, the ramp's end ``x_v = 0, 1``, the supply pressure through the
pre-charge and the relief pressure) are located by CVODE's root finding to the integrator's tolerance
(the ramp's end, linear in time, to rounding). Each flight is integrated in its own time, from 0 (the
vector field does not depend on ``t``).

Each flight starts its energy quadratures at 0; with ``variational=True`` it integrates the
fundamental matrix ``Phi`` of the first ``2 N + 6`` components beside them (the variational
equations ``Phi' = A Phi``) and returns ``Phi`` at its end, before the event's map (the solvers
apply the saltation there, Hiskens & Pai 2000).
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import io
import math
import threading

import numpy as np

from ..base import DriveState, FlightSettings
from ..flight import ARRIVAL, END, EVENT, Flight, ModalEnd
from . import _magnus
from ._bar import ARRIVAL_EV
from .extremes import hermite_extremes
from .settings import DEFAULT_SETTINGS, CircuitFlightSettings, circuit_settings

__all__ = ["CircuitPiece", "circuit_flight", "stiffness_ratio", "DEFAULT_SETTINGS", "ADAMS_STIFFNESS",
           "EXPLICIT_STIFFNESS", "EXPLICIT_TOLERANCE", "magnus_state_settings", "uses_magnus", "uses_dop853",
           "spectrum", "keep_spacing", "last_integrator", "compile_callbacks"]


def compile_callbacks() -> int:
    """Compile (or load from numba's cache) the C callbacks of every flight's generated module loaded in
    this process (:mod:`._netgen`), those no flight has used yet too: each compiles at its first use
    (:class:`._cvode.Callback`), so that ``impactbar warmup`` compiles the Jacobian its flights did not
    take here, and a later process compiles nothing.

    Returns
    -------
    int
        How many callbacks (compiled, loaded or already there).
    """
    from . import _netgen

    n = 0
    for module in list(_netgen._MEMO.values()):
        for cb in (getattr(module, "CALLBACKS", None) or ())[:-1]:
            cb.address  # noqa: B018  (the address: compiled on first use)
            n += 1
    return n


class HermiteSteps:
    """An integrator's steps ``t``, its states ``y`` and their rates ``f`` there, with the cubic
    Hermite interpolant between the steps (built on first use; times clipped to ``[t0, t_end]``):
    what the circuit's pieces of a flight and of a blow share."""

    __slots__ = ("t0", "t_end", "t", "y", "_spline")

    def _column(self, k: int | str) -> int:
        """The column of ``y`` of the drive's state component ``k`` (an index of ``z`` or a name of
        ``layout``)."""
        raise NotImplementedError

    @staticmethod
    def extremes_over(pieces, ks) -> tuple[np.ndarray, np.ndarray]:
        """The least and the greatest value of each of the drive's state components ``ks`` over
        ``pieces`` together (:func:`~.extremes.hermite_extremes`: the pieces' :meth:`extremes`, the same
        numbers).

        Parameters
        ----------
        pieces : list of HermiteSteps
            At least one.
        ks : list of int or str
            The components (indices of ``z`` or names of ``layout``).

        Returns
        -------
        lows, highs : numpy.ndarray, shape (len(ks),)
            In model units.
        """
        cols = [[p._column(k) for k in ks] for p in pieces]
        return hermite_extremes(((p.t, p.y[:, c], p.f[:, c]) for p, c in zip(pieces, cols, strict=True)),
                                len(ks))

    def extremes(self, k: int | str) -> tuple[float, float]:
        """The least and the greatest value of the drive's state component ``k`` (an index of ``z``, or
        a name of ``layout``: ``"p_s"``, ``"supply"``) over the piece: its steps and the stationary points
        of its cubic Hermite interpolant (:func:`~.extremes.hermite_extremes`)."""
        (lo,), (hi,) = self.extremes_over([self], [k])
        return float(lo), float(hi)

    def supply_extremes(self) -> tuple[float, float]:
        """The least and the greatest supply pressure over the piece (:meth:`extremes`)."""
        return self.extremes(self.layout.supply)

    def _at(self, t):
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=float)), self.t0, self.t_end)
        if self.t.size < 2:
            return np.repeat(self.y[:1].T, t.size, axis=1)
        if self._spline is None:
            from scipy.interpolate import CubicHermiteSpline

            self._spline = CubicHermiteSpline(self.t, self.y, self.f, axis=0)
        return self._spline(t).T

    def piston_work(self) -> float:
        """The circuit's work on the piston over the piece, its layout's ``"piston"`` energy term
        (:attr:`HydraulicCircuitDrive.piston_work_quadrature`).

        Returns
        -------
        float
            In model energy units.
        """
        return float(self.y[-1, self._energy_start + self.layout.energy["piston"]])


class CircuitPiece(HermiteSteps, ModalEnd):
    """A flight of the circuit: the steps of the integration (exact to the integrator's tolerance
    at each step) and a cubic Hermite interpolant between them (the vector field at each step).

    Attributes
    ----------
    t0, t_end : float
    t : numpy.ndarray, shape (S,)
        The integrator's steps.
    y : numpy.ndarray, shape (S, 2 N + 2 + n_states + n_energy)
        The state and the energy quadratures (from 0 at ``t0``) at each step.
    layout : CircuitLayout
        Where the circuit keeps its states and energy terms (:attr:`HydraulicCircuitDrive.layout`).
    f : numpy.ndarray, shape (S, 2 N + 2 + n_states + n_energy)
        The vector field at the steps, ``field_at(y, par, f)`` (the compiled ``field_at`` of the
        flight's kernels: the code generated for the circuit's topology, :mod:`._netgen`), evaluated
        on first use (a flight whose end alone is wanted, as
        Newton's residuals, never needs it).
    """

    __slots__ = ("M", "c", "alpha", "layout", "_f", "_par", "_field_at")

    def __init__(self, t, y, par, M, c, alpha, layout, field_at):
        self.t, self.y = t, y
        self.t0, self.t_end = float(t[0]), float(t[-1])
        self.M, self.c, self.alpha, self.layout = M, c, alpha, layout
        self._f, self._par, self._field_at = None, par, field_at
        self._spline = None

    @property
    def f(self) -> np.ndarray:
        """The vector field at the steps (class docstring)."""
        if self._f is None:
            f = np.empty_like(self.y)
            self._field_at(np.ascontiguousarray(self.y), self._par, f)
            self._f, self._par, self._field_at = f, None, None
        return self._f

    def modal(self, t):
        """``(q, v)`` at times ``t``, shape ``(N + 1, T)`` each."""
        Y = self._at(t)
        return Y[:self.M], Y[self.M:2 * self.M]

    def drive_state(self, t):
        """The circuit's states ``z`` (``layout.state_names``) at times ``t``, shape ``(n_states, T)``."""
        return self._at(t)[2 * self.M:self.layout.size(self.M)]

    def force(self, t):
        """The force on the piston, ``p_r - alpha p_f``."""
        z, L = self.drive_state(t), self.layout
        return z[L["rear"]] - self.alpha * z[L["front"]]

    def _column(self, k: int | str) -> int:
        return 2 * self.M + (self.layout[k] if isinstance(k, str) else k)

    def energies(self):
        """The energy quadratures over the piece (theory §11; ``layout.energies``)."""
        start = self._energy_start
        return self.y[-1, start:start + self.layout.n_energy].copy()

    @property
    def _energy_start(self):
        """Where the energy terms start in a row of ``y`` (after ``q, v, z``)."""
        return self.layout.size(self.M)


#: The most steps of one flight (CVODE's ``max_num_steps``). A settling flight of a piston of 16 modes
#: takes over 200,000 steps at ``SETTLE_RTOL`` and its variational periods some 320,000; the stored
#: steps grow as they are taken, so the bound costs nothing until a flight needs it.
_MAX_STEPS = 2_000_000

#: What a flight that empties a chamber is told (:meth:`~impactbar.drives.circuit.Chambers.check_volumes`).
_OVERTRAVEL = ("near t = {t:.6g}: the piston overtravels it; give a larger {which}_volume (now {now:g}) or a "
            "switch position nearer the stop")


#: The tolerances of a variational flight's state under Magnus, relative to the flight's own: without
#: ``Phi``'s ``n^2`` components in CVODE's error test the plain flight takes some three times fewer
#: steps and its state is the less accurate (on the preset's orbit with 4 modes the impact velocity
#: 1.3e-6 off at the drive's tolerance); a thousand times finer, the orbit is the variational flights'
#: to 1e-10 (theory §11, "Sensitivities").
MAGNUS_STATE_TOLERANCE = 1e-3

#: DOP853's tolerances (``rtol`` and ``atol``) over the CVODE settings a flight is given: on the
#: preset ``circuit-drifter``'s orbit (one period of the plain flights under Magnus' ``Phi``) DOP853
#: at three times CVODE's ``rtol = 1e-13`` ends each flight nearer a reference (scipy's DOP853 at
#: ``rtol = 2.3e-14``) than Adams-Moulton does: with 4, 8 and 16 modes 1.7e-9, 3.1e-9 and 2.0e-8
#: against 1.4e-8, 1.6e-8 and 2.6e-8, in 0.59, 0.53 and 0.39 of its CPU time (at ten times, 5.7e-9,
#: 1.1e-8 and 6.2e-8: worse with 16 modes); at ``rtol = 1e-10`` (the drive's own) 1.7e-6, 3.1e-6 and
#: 1.3e-5 against 1.5e-5, 2.0e-5 and 3.1e-5, in 0.54, 0.33 and 0.32 of its CPU time
#: (``benchmarks/probes/explicit_flight.py``).
EXPLICIT_TOLERANCE = 3.0

#: The stiffness ratio (:func:`stiffness_ratio`) up to which ``multistep="auto"`` takes Adams-Moulton
#: for a flexible piston's plain flights. Measured on the preset ``circuit-drifter`` with its oil's bulk
#: modulus scaled (CPU time of 3 periods of ``simulate``, BDF's over Adams'): with 8 modes 2.6 at a
#: ratio of 1.3, 1.7 at 3.9, 1.4 at 13, 0.47 at 39, 0.25 at 130; with 4 modes 1.0 at 7.8 and 0.39 at
#: 78; with 16 modes 1.9 at 1.9 and 0.70 at 19. Periodic orbits, whose flights take the finer state
#: tolerance of the variational flights, favour Adams more (8 modes: 1.2 at 13, 0.8 at 130).
ADAMS_STIFFNESS = 15.0

#: The stiffness ratio (:func:`stiffness_ratio`) up to which ``multistep="auto"`` takes the explicit
#: DOP853 (:mod:`._dop853`) for a flexible piston's plain flights, instead of Adams-Moulton: its steps
#: follow the modes while the oil's decay is not much faster than they are, and shrink to the decay's
#: (explicit: ``h |lambda|`` bounded) as it grows. Measured on the preset ``circuit-drifter`` with its
#: oil's bulk modulus scaled (CPU time of 3 periods of ``simulate``, Adams' over DOP853's, BDF's
#: beside): with 8 modes 2.7 at a ratio of 1.3, 1.2 at 10.4 and at 15.6 (BDF there as fast as
#: DOP853), 0.99 at 20.7, 0.68 at 31; with 4 modes 1.8 at 10.4, 1.5 at 15.6, 0.90 at 20.7; with 16
#: modes 3.2 at 0.65, 1.2 at 10.4 (DOP853 the fastest of the three), 1.15 at 15.6 (BDF the fastest)
#: (``benchmarks/probes/explicit_flight.py --stiffer``). Periodic orbits, whose flights take the finer
#: state tolerance, favour DOP853 more.
EXPLICIT_STIFFNESS = 12.0


def stiffness_ratio(drive, model) -> float:
    r"""How much stiffer the oil is than the piston's modes: the fastest decay of the circuit's vector
    field over its fastest oscillation, :math:`\max(-\operatorname{Re}\lambda) /
    \max|\operatorname{Im}\lambda|` over the eigenvalues of its Jacobian at the drive's start (the
    piston at rest on the stop, :meth:`HydraulicCircuitDrive.start`); ``inf`` without an oscillation.

    The decay is an oil volume's relaxation behind its openings (on the preset ``circuit-drifter``
    the front chamber's, :math:`\beta K_f / (V_f \sqrt{p_{tr}})`); the oscillation the piston's
    highest mode (:math:`N \pi s` for a uniform piston of ``N`` modes). Adams-Moulton's steps follow the
    oscillation while the ratio is small, and shrink to the decay's as it grows, where BDF's do
    not (:data:`ADAMS_STIFFNESS`; theory §11, *The integrator*).

    Parameters
    ----------
    drive : HydraulicCircuitDrive
        The circuit, its pressures in units of its pressure scale.
    model : BarModel
        The piston; its ``n_modes`` sets the highest mode's frequency.

    Returns
    -------
    float
        Dimensionless, :math:`\ge 0`.

    Examples
    --------
    >>> from impactbar.physical import circuit_preset
    >>> d = circuit_preset("circuit-drifter")
    >>> round(stiffness_ratio(d.drive(), d.model().with_(n_modes=8)), 2)
    1.3
    """
    decay, oscillation, _ = spectrum(drive, model)
    return decay / oscillation if oscillation > 0.0 else math.inf


@functools.lru_cache(maxsize=64)
def spectrum(drive, model) -> tuple[float, float, float]:
    r"""The circuit's fastest rates at the drive's start (the piston at rest on the stop,
    :meth:`HydraulicCircuitDrive.start`), from the eigenvalues :math:`\lambda` of its vector field's
    Jacobian there: the fastest decay :math:`\max(-\operatorname{Re}\lambda, 0)`, the fastest
    oscillation :math:`\max|\operatorname{Im}\lambda|` and the largest :math:`|\lambda|`
    (:func:`stiffness_ratio`; the spacing of an explicit flight's kept points, :func:`keep_spacing`).

    Parameters
    ----------
    drive : HydraulicCircuitDrive
    model : BarModel

    Returns
    -------
    tuple of float
        ``(decay, oscillation, modulus)``, in the model's inverse time units.
    """
    M = model.n_modes + 1
    zeros = np.zeros(M)
    start = drive.start(model, zeros, zeros)
    net, code = drive._compiled_network(start.mode)
    par = np.concatenate((drive._par(model, start.mode, False), net))
    n = drive.layout.size(M)
    y = np.zeros(n + drive.layout.n_energy)
    y[2 * M:n] = start.z
    A = np.empty((n, n))
    code.jac_base(y, par, M, A)
    lam = np.linalg.eigvals(A)
    return (max(float(np.max(-lam.real)), 0.0), float(np.max(np.abs(lam.imag))),
            float(np.max(np.abs(lam))))


#: The kept points of an explicit flight at the tolerance :data:`KEEP_RTOL` (:func:`keep_spacing`) at
#: most this over the circuit's largest rate apart: CVODE's Adams steps on the preset
#: ``circuit-drifter`` with 8 modes at that tolerance, which the flights kept before, are 0.2 over its
#: largest rate (the oil's decay 7964, the highest mode 6138 rad/s, the step 2.55e-5) apart.
KEEP_PHASE = 0.2

#: The CVODE tolerance at which an explicit flight's kept points are :data:`KEEP_PHASE` apart (the
#: plain flights under Magnus' ``Phi``); at a looser ``rtol`` their spacing grows as
#: ``(rtol / KEEP_RTOL) ** (1/5)``, the cubic Hermite interpolant's error (of order 4 in the spacing)
#: staying below the points' own as the tolerance loosens: on the preset's orbit with 8 modes at
#: ``rtol = 1e-10`` 2e-5 from a reference, CVODE's over its steps 2.9e-5
#: (``benchmarks/probes/explicit_flight.py``).
KEEP_RTOL = 1e-13


def keep_spacing(drive, model, rtol: float = KEEP_RTOL) -> float:
    r"""The largest spacing of an explicit flight's kept points: :data:`KEEP_PHASE` over the largest
    :math:`|\lambda|` of :func:`spectrum`, times ``(rtol / KEEP_RTOL) ** (1/5)`` at a looser
    tolerance (``inf`` where the rate is 0), the cubic Hermite interpolant between them as fine as
    over CVODE's steps at ``rtol``.

    Parameters
    ----------
    drive : HydraulicCircuitDrive
    model : BarModel
    rtol : float, optional
        The flight's CVODE tolerance (before :data:`EXPLICIT_TOLERANCE`).

    Returns
    -------
    float
    """
    _, _, rate = spectrum(drive, model)
    return KEEP_PHASE * max(rtol / KEEP_RTOL, 1.0) ** 0.2 / rate if rate > 0.0 else math.inf


def uses_magnus(sensitivity: str, model, generated: bool = True) -> bool:
    """Whether a variational flight of the piston of ``model`` takes its fundamental matrix by
    Magnus' method over the steps of a plain flight (:attr:`CircuitFlightSettings.sensitivity
    <.settings.CircuitFlightSettings.sensitivity>`), with the code generated for the network
    (``generated``: a flight's own ``kernels`` are flown by CVODE alone, :func:`circuit_flight`)."""
    return generated and (sensitivity == "magnus" or (sensitivity == "auto" and model.n_modes > 0))


def magnus_state_settings(settings: FlightSettings | None) -> CircuitFlightSettings:
    """The integrator of the plain flight under a variational flight by Magnus' method with
    ``settings`` (:func:`.settings.circuit_settings`; default, or not CVODE: :data:`DEFAULT_SETTINGS`),
    its options kept: its tolerances :data:`MAGNUS_STATE_TOLERANCE` times finer (CVODE's floor
    ``1e-13`` on ``rtol``), ``atol`` scaled as much. A plain flight with these settings is the
    variational flight's state, bit for bit.

    Parameters
    ----------
    settings : FlightSettings or None

    Returns
    -------
    CircuitFlightSettings
    """
    settings = circuit_settings(settings)
    rtol = max(settings.rtol * MAGNUS_STATE_TOLERANCE, 1e-13)  # (CVODE's floor: some 100 roundings)
    return dataclasses.replace(settings, rtol=rtol, atol=settings.atol * rtol / settings.rtol)


_LAST = threading.local()


@functools.lru_cache(maxsize=2)
def _compiled_driver(compiled: bool = True):
    """:mod:`._cvode` where ``compiled`` and the libraries bind, else None (asked once: the libraries
    bind once in a process, :func:`._sundials.bind`)."""
    if not compiled:
        return None
    from . import _sundials

    if not _sundials.available():
        return None
    from . import _cvode

    return _cvode


def _message(flag) -> str:
    from sksundae._cy_cvode import CVMESSAGES

    return CVMESSAGES.get(int(flag), f"CVODE's flag {int(flag)}")


def _integrate_compiled(cv, band, blocks, adams, n_energy, code, par, settings, directions, y0, t, end,
                        keep):
    """``(flag, message, t, y[:, :keep], y_end, events hit)`` by :func:`._cvode.fly` (the message
    None, :func:`_message` of the flag when it is wanted; ``band``: the
    variational flights' Newton systems by the band solver, else the dense one; ``blocks``: the band
    solver's setup and solve on the blocks, :class:`._cvode.Workspace`, and with ``band`` the plain
    flights' too (the state's block, the energies' identity: the dense solver's steps to the bit), else
    the plain flights' by the dense solver; ``adams``: Adams-Moulton's
    method, else BDF; ``n_energy`` the energy integrands after the ``n`` states; ``code``: the
    flight's kernels, whose C callbacks CVODE calls: the generated module, :mod:`._netgen`); a
    variational flight's fundamental matrix (after the ``keep`` leading components) at
    ``settings.phi_atol`` where it is given (:func:`._cvode.fly_split`)."""
    n = keep - n_energy
    var = band and y0.size > keep  # variational: the band solver
    by_blocks = var or (band and blocks and n_energy > 0)  # (a plain flight's blocks: the energies' rows)
    rhs, jac, jac_band, events, n_events = code.CALLBACKS
    callbacks = (rhs, jac_band if by_blocks else jac, events, n_events)
    ws = cv.workspace(y0.size, n - 1 if by_blocks else 0, callbacks, blocks and by_blocks, adams,
                      not var)
    directions = np.asarray(directions, dtype=np.int32)
    if var and settings.phi_atol is not None:  # (the fundamental matrix's own absolute tolerance)
        flag, ts, Y, yend, roots = cv.fly_split(ws.mem, ws.y, float(t), y0, float(end), float(settings.rtol),
                                                float(settings.atol), keep, float(settings.phi_atol),
                                                ws.atol, directions, par, keep, _MAX_STEPS)
    else:
        flag, ts, Y, yend, roots = cv.fly(ws.mem, ws.y, float(t), y0, float(end), float(settings.rtol),
                                          float(settings.atol), directions, par, keep, _MAX_STEPS)
    return int(flag), None, ts, Y, yend, [i for i, r in enumerate(roots.tolist()) if r]


def _displacements(x, weights):
    """The driven end's displacements ``w = -(x @ weights)`` over a flight's steps (``x`` the modal
    positions there, shape ``(S, M)``; ``weights`` the driven end's, shape ``(M,)``) as
    :meth:`~.parts.Chambers.check_volumes` reads them (theory §11): for a rigid piston of weight
    ``> 0`` only their greatest and least, ``-(weight min x)`` and ``-(weight max x)`` (the product's
    to the bit: rounding is monotone), without the product's array; else the product."""
    if weights.size == 1:
        (weight,) = weights.tolist()
        if weight > 0.0:
            return np.array((-(weight * float(x.min())), -(weight * float(x.max()))))
    return -(x @ weights)


def _integrate_explicit(code, par, settings, directions, y0, end, keep, spacing):
    """``(flag, message, t, y[:, :keep], y_end, events hit)`` by the generated module's DOP853
    (``code.dop853_fly``, :mod:`._dop853`) from 0 to ``end``, at :data:`EXPLICIT_TOLERANCE` times
    ``settings``' tolerances, its kept points at most ``spacing`` apart."""
    from ._dop853 import MESSAGES

    rtol, atol = float(settings.rtol * EXPLICIT_TOLERANCE), float(settings.atol * EXPLICIT_TOLERANCE)
    flag, ts, Y, yend, roots, _ = code.dop853_fly(0.0, y0, float(end), rtol, atol,
                                                  np.asarray(directions, dtype=np.int32), par, keep,
                                                  _MAX_STEPS, float(spacing))
    _LAST.method = "dop853"
    return int(flag), MESSAGES.get(int(flag), ""), ts, Y, yend, np.flatnonzero(roots)


def last_integrator() -> str | None:
    """The integrator of this thread's last flight: ``"dop853"``, ``"adams"`` or ``"bdf"`` (None
    before the first).

    Returns
    -------
    str or None
    """
    return getattr(_LAST, "method", None)


def uses_dop853(multistep: str, drive, model, generated: bool = True) -> bool:
    """Whether a plain flight of the piston of ``model`` takes the explicit DOP853 (:mod:`._dop853`;
    :attr:`CircuitFlightSettings.multistep <.settings.CircuitFlightSettings.multistep>`): asked
    (``"dop853"``), or by ``"auto"`` for a piston with modes where the oil is not stiff against
    DOP853's steps (:func:`stiffness_ratio` at most :data:`EXPLICIT_STIFFNESS`); only with the
    generated code.

    Parameters
    ----------
    multistep : {"auto", "cvode", "adams", "bdf", "dop853"}
    drive : HydraulicCircuitDrive
    model : BarModel
    generated : bool, optional
        Whether the flight runs the code generated for the network (:func:`circuit_flight` without
        ``kernels``).

    Returns
    -------
    bool

    Raises
    ------
    ValueError
        ``"dop853"`` without the generated code.
    """
    if multistep == "dop853":
        if not generated:
            raise ValueError("multistep='dop853' runs on the code generated for the network (kernels=None)")
        return True
    return multistep == "auto" and generated and model.n_modes > 0 and \
        stiffness_ratio(drive, model) <= EXPLICIT_STIFFNESS


def _integrate_binding(adams, code, par, settings, directions, y0, t, end, keep):
    """The same through scikit-sundae's ``CVODE`` (its Python interface)."""
    from sksundae.cvode import CVODE

    rhs, jac, events = code.flight_rhs, code.flight_jac, code.flight_events
    n_events = len(directions)

    def f(t, y, yp):
        rhs(t, y, yp, par)

    def jf(t, y, yp, JJ):
        jac(t, y, yp, JJ, par)

    def ev(t, y, g):
        events(t, y, g, par)

    ev.terminal = [True] * n_events
    ev.direction = [int(d) for d in directions]
    solver = CVODE(f, method="Adams" if adams else "BDF", rtol=settings.rtol, atol=settings.atol, jacfn=jf,
                   eventsfn=ev, num_events=n_events, max_num_steps=_MAX_STEPS)
    with contextlib.redirect_stdout(io.StringIO()):  # scikit-sundae prints CVODE's errors: in sol.message
        sol = solver.solve(np.array([t, end]), y0)
    Y = np.asarray(sol.y, dtype=float)
    hit = np.array([], dtype=int)
    if sol.status == 2 and sol.i_events is not None:
        hit = np.flatnonzero(np.atleast_2d(sol.i_events)[-1])
    return int(sol.status), sol.message, np.asarray(sol.t, dtype=float), Y[:, :keep], Y[-1], hit


def circuit_flight(drive, model, state: DriveState, t: float, q, v, t_stop: float,
                   settings: FlightSettings | None = None, variational: bool = False, *,
                   kernels=None, start=None) -> Flight:
    """One flight from ``(q, v)`` and the circuit's ``state`` at ``t`` to the next arrival at the
    stop, the circuit's next event or ``t_stop`` (module docstring).

    Parameters
    ----------
    settings : CircuitFlightSettings or FlightSettings, optional
        The integrator (:func:`.settings.circuit_settings`: a plain
        :class:`~impactbar.drives.base.FlightSettings` of CVODE gives its tolerances, every option its
        default; default, or another method: :data:`DEFAULT_SETTINGS`) and how the flight is
        integrated:

        - ``compiled``: CVODE driven from compiled code (:mod:`._cvode`: no Python between the
          flight's start and its end) where the SUNDIALS libraries that scikit-sundae ships bind
          (:func:`._sundials.available`); ``False``: through scikit-sundae's Python interface, each
          call of the vector field, the Jacobian and the events a call of Python (the way before, the
          fallback, and the baseline of ``benchmarks/bench_circuit.py``). The same steps either way,
          to the bit.
        - ``band``: the variational flights' Newton systems by SUNDIALS' band solver
          (half-bandwidths ``n - 1``: ``Phi`` is stored by columns, each column's equations coupling
          only its own components); ``False``: the dense solver (the way before;
          ``benchmarks/bench_circuit.py``'s baseline for the flexible piston). Only with ``compiled``.
        - ``blocks``: with ``band``, the band solver's factorisation and solve taken on the Newton
          matrix's blocks (it is block-diagonal: the state's ``n x n`` block, repeated for each column
          of ``Phi``): one LU of the block (``n`` times fewer operations than the band LU) applied to
          each, the same operations on each block as the band solver's, in its order (the same steps,
          to the bit; :class:`._cvode.Workspace`); ``False``: the band solver's own (the way before).
        - ``sensitivity``: how a variational flight's fundamental matrix is taken: ``"magnus"``, the
          plain flight integrated and ``Phi`` over its steps by Magnus' method of order 6
          (:mod:`._magnus`, without ``kernels`` only); ``"cvode"``, the variational equations
          integrated beside the state by CVODE (:math:`n^2` more unknowns); ``"auto"`` (default),
          Magnus where the piston has modes and CVODE for the rigid piston (whose six unknowns CVODE
          takes cheaply, to the drive's tolerance). The flight's states are the plain flight's either
          way with ``"magnus"``; its ``Phi`` agrees with a variational flight at a 100 times finer
          tolerance to some ``1e-7`` with 8 modes (the state's error;
          ``benchmarks/probes/monodromy_magnus.py``), where CVODE's at the drive's tolerance is some
          ``1e-5`` off (theory §11).
        - ``multistep``: the plain flights' integrator: CVODE's linear multistep method, ``"bdf"``,
          the backward differentiation formulas of orders 1 to 5, or ``"adams"``, Adams-Moulton of
          orders 1 to 12 (Newton's iterations with the same Jacobian either way), for every flight;
          ``"dop853"``, the explicit Dormand-Prince 8(5,3) compiled with the generated code for every
          plain flight (:mod:`._dop853`: scipy's method and step control, at
          :data:`EXPLICIT_TOLERANCE` times the tolerances of ``settings``, the events found on its
          dense output, its kept points at most :func:`keep_spacing` apart; ``ValueError`` with
          ``kernels``); ``"auto"`` (default), for the plain flights of a piston with modes (those of
          a variational flight by Magnus among them) DOP853 where the oil is not stiff against its
          steps (:func:`stiffness_ratio` at most :data:`EXPLICIT_STIFFNESS`), else Adams-Moulton
          where the oil is not much stiffer than the modes (at most :data:`ADAMS_STIFFNESS`), BDF for
          the rest, the rigid piston and CVODE's variational flights (which ``"dop853"`` leaves to
          these CVODE methods too; module docstring); ``"cvode"``, ``"auto"``'s choice among CVODE's
          methods only, no DOP853 (the way before it, the baseline).
    kernels : types.SimpleNamespace or None, optional
        The compiled kernels the flight runs. ``None`` (default): the vector field, its Jacobian, the
        events and CVODE's C callbacks of the code generated for the circuit's network of part
        records (:meth:`HydraulicCircuitDrive._compiled_network`, :mod:`._netgen`: one module per
        topology, the values read from ``par`` with the network after the bar's entries). Else a
        namespace with a generated module's names ``flight_rhs``, ``flight_jac``, ``flight_events``,
        ``field_at`` and ``CALLBACKS`` (``None`` where SUNDIALS is not driven from compiled code),
        and ``par(drive, model, mode, variational)``, the parameter vector they read (the drive's,
        :mod:`._bar`, then in place of the network their own parameters of the drive's parts): a
        reference to check the generated code against (the tests' hand-written preset circuit takes
        the same steps, to the bit), flown by CVODE only (neither Magnus' method nor DOP853).
    start : numpy.ndarray or None, optional
        With ``variational``, the fundamental matrix at the flight's start (shape ``(n, n)``; default
        the identity): the flight's ``sensitivity`` is then the matrix carried to its end
        (:attr:`.settings.CircuitFlightSettings.carry`).

    Returns
    -------
    Flight
        With ``piece`` a :class:`CircuitPiece`; at an arrival, ``events`` those whose levels CVODE's
        (or DOP853's) root finding found on the arrival's root (crossed with it: their flags turn
        before the impact, so that the state handed on agrees with its mode); with ``variational``,
        ``sensitivity`` the fundamental matrix of ``(q, q', p_f, p_r, p_s, x_v)`` over the flight
        (before the map of the event that ends it), times ``start``.

    Raises
    ------
    ValueError
        Where CVODE or DOP853 fails (the message says why: a chamber emptied, a pressure out of
        range); ``multistep="dop853"`` with ``kernels``.
    """
    settings = circuit_settings(settings)
    compiled, band, blocks = settings.compiled, settings.band, settings.blocks
    sensitivity, multistep = settings.sensitivity, settings.multistep
    mode, z = state
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    M = q.size
    generated = kernels is None
    magnus = variational and uses_magnus(sensitivity, model, generated)
    if magnus:  # the plain flight, its state as accurate as the variational flight's, then Phi over its steps
        variational = False
        settings = magnus_state_settings(settings)
    L = drive.layout
    n, n_energy = L.size(M), L.n_energy
    if generated:  # (made once per drive, bar and mode: never written; the piece's c its own)
        par, code, directions, c, weights = drive._flight_data(model, mode, variational)
        c = c.copy()
    else:
        par, code, directions = kernels.par(drive, model, mode, variational), kernels, drive._directions(mode)
        c, weights = model.end_weights, model.drive_weights
    field_at = code.field_at
    keep = n + n_energy
    y0 = np.zeros(keep + n * n if variational else keep)  # (q, v, z, the energies from 0, Phi by columns)
    y0[:M], y0[M:2 * M], y0[2 * M:n] = q, v, z
    if variational:
        if start is None:
            y0[keep::n + 1] = 1.0  # (the identity)
        else:
            y0[keep:] = start.T.ravel()
    end = t_stop if math.isfinite(t_stop) else t + 1e4
    if end <= t:
        piece = CircuitPiece(np.array([t]), y0[None, :keep], par, M, c,
                             drive.chambers.area_ratio, L, field_at)
        return Flight(t, q, v, np.asarray(z, dtype=float), END, (), piece,
                      (np.eye(n) if start is None else start) if variational or magnus else None)
    # in the flight's own time from 0 (the vector field and the events do not depend on t): late in a
    # run the first steps (1e-15 where the variational equations start) would be lost in t's rounding
    explicit = not variational and uses_dop853(multistep, drive, model, generated)
    if explicit:
        status, message, ts, Y, yend, hit = _integrate_explicit(code, par, settings, directions,
                                                                y0, end - t, keep,
                                                                keep_spacing(drive, model, settings.rtol))
    else:
        adams = multistep == "adams" or (multistep != "bdf" and M > 1 and not variational
                                         and stiffness_ratio(drive, model) <= ADAMS_STIFFNESS)
        cv = _compiled_driver(compiled)
        integrate = functools.partial(_integrate_binding, adams, code) if cv is None \
            else functools.partial(_integrate_compiled, cv, band, blocks, adams, n_energy, code)
        status, message, ts, Y, yend, hit = integrate(par, settings, directions, y0, 0.0, end - t, keep)
        _LAST.method = "adams" if adams else "bdf"
    if status < 0 or not np.isfinite(yend).all():
        raise ValueError(drive._failure(model, _message(status) if message is None else message, t))
    own = ts  # (the flight's own time, from 0)
    ts = ts + t
    later = ts[1:] > ts[:-1]  # (not at a repeated point at an event)
    if not later.all():  # (else no copy: the kept points of a period are megabytes)
        keep_t = np.concatenate(([True], later))
        ts, Y, own = ts[keep_t], Y[keep_t], own[keep_t]
    piece = CircuitPiece(ts, np.ascontiguousarray(Y), par, M, c, drive.chambers.area_ratio, L, field_at)
    drive.chambers.check_volumes(_displacements(piece.y[:, :weights.size], weights), t, _OVERTRAVEL)
    te = float(ts[-1])
    qe, ve, ze = yend[:M].copy(), yend[M:2 * M].copy(), yend[2 * M:n].copy()
    Phi = yend[n + n_energy:].reshape(n, n).T.copy() if variational else None  # (stored by columns)
    if magnus:
        d = _magnus.balance(code.jac_base, piece.y[piece.t.size // 2], par, M, n)
        theta = _magnus.DEFAULT_THETA if settings.magnus_theta is None else settings.magnus_theta
        Phi, _ = code.magnus_phi(np.ascontiguousarray(own), piece.y, piece.f, par, M, theta, d)
        if start is not None:
            Phi = Phi @ start
    if status == 2:
        if ARRIVAL_EV in hit:  # (with the drive's events on the same root: the caller turns their flags)
            qe[0] -= float(c @ qe)  # exactly on the stop
            together = drive._fired(mode, hit) if len(hit) > 1 else ()
            return Flight(te, qe, ve, ze, ARRIVAL, together, piece, Phi)
        fired = drive._fired(mode, hit)
        if fired:
            return Flight(te, qe, ve, ze, EVENT, fired, piece, Phi)
    return Flight(te, qe, ve, ze, END, (), piece, Phi)
