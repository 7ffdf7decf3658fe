r"""The shape of a stepped piston that does the most work on the rock per blow (theory §12), in SI.

A piston of ``n`` uniform segments of one material, of given mass ``m`` and length ``L``, strikes the
rod at a given velocity; its segments' lengths and cross-sections set the incident stress wave
(Lundberg & Okrouhlik, "Efficiency of a percussive rock drilling process with consideration of
wave energy radiation into the rock", Int. J. Impact Eng. 32 (2006) 1573-1583; Lundberg & Collet,
"Optimal wave shape with respect to efficiency in percussive drilling with detachable drill bit",
Int. J. Impact Eng. 37 (2010) 901-906; Chiang & Stamm, "Design optimization of valveless DTH
pneumatic hammers by a weighted pseudo-gradient search method", J. Mech. Design 120 (1998) 687-694).
:func:`optimize_piston` maximises the work on the rock of one blow (:func:`~impactbar.single_blow`
with the piston's segments carried by characteristics) over the segments' lengths and areas, the mass
and the length held, the peak of the incident stress wave in the rod kept at or below a limit.

Method (``method="slsqp"``, the default). The segments' boundaries lie on whole cells of a lattice of
``cells`` cells of one travel time along the piston: there its waves are constant on cells and the
lattice's blow is the exact solver's on the lattice's rod (to rounding for a massless bit while
nothing comes back from the rod's end; else within the bit's cell averages). For given boundaries
the segments' masses (a softmax of ``n - 1`` free numbers: the mass held, the uniform piston at the
origin) are found by scipy's SLSQP with the exact gradient of the work
(:func:`~impactbar.laws.rodrock.tangent.rod_rock_blow_tangent`, the blow's tangent-linear run), the
stress limit one inequality per step of the blow on the steps' shank forces and their gradients;
the boundaries by two pattern searches over the cells from the uniform piston (local searches:
with three segments or more the shape has several optima). A parabola through the best
design's work and its neighbours' puts the boundaries between the cells. The best design's blow is
then solved by the exact solver over the same window (every wave of piston and rod a delay line, a
feed or a bit mass included; :func:`~impactbar.single_blow`), at its whole cells and between them,
and so is the uniform piston's. With both a feed and a bit mass (the bit held on the rock rings on
its unloading stiffness, whose switches the exact solver follows one by one: minutes on a stiff
rock), or where the exact blow would pass its default's bounds, both blows are the lattice's on
whole cells. The better of the two feasible designs is returned, so that the result is never worse
than the uniform piston. ``method="nelder-mead"`` is the derivative-free search this replaced (theory
§12: the lattice's work is rippled in boundaries that cross its cells, so that its gradient there
misleads): a cell that a boundary crosses gets the mass of the parts it holds, and scipy's
Nelder-Mead maximises the work less a penalty on the stress above the limit over the softmaxes of
the length and mass fractions, started at the uniform piston and restarted once from its result.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .._shared.renamed import renamed_attribute
from .._shared.validate import check_int, check_real
from .rock import RodPiece

__all__ = ["OptimalPiston", "optimize_piston", "piston_blow"]

#: the free numbers of the softmax are kept in [-BOUND, BOUND]: segments' masses or lengths at most
#: e^(2 BOUND) apart (the stepped piston accepts impedances 1e6 apart)
BOUND = 6.0
#: the penalty per unit of relative excess stress, against the work's scale 1 (the impact energy), of
#: the Nelder-Mead search
PENALTY = 10.0
#: the searches of :func:`optimize_piston`
METHODS = ("slsqp", "nelder-mead")
#: SLSQP's tolerance on the work per impact energy (neighbouring cells' designs differ by ~1e-5)
FTOL = 1e-9


class _Rod(NamedTuple):
    """The rod's pieces in the blow's units: lengths, impedances (over a uniform piston's) and wave
    speeds, each a list over the pieces."""
    lengths: list
    impedances: list
    speeds: list


class _Merit(NamedTuple):
    """A design's merit: the work per impact energy less the stress penalty, and the relative
    excess of the incident wave's peak stress over the limit (0: feasible)."""
    gain: float
    excess: float


class _Rank(NamedTuple):
    """The gradient search's order of designs (compared as a tuple): infeasible (0 or 1, a search
    not started 2 or 3), the excess stress, the work per impact energy negated."""
    infeasible: int
    excess: float
    loss: float


class _Vertex(NamedTuple):
    """One blow of the gradient search: its rank, the objective (work negated) and its gradient,
    the stress constraints and their Jacobian."""
    rank: _Rank
    objective: float
    gradient: np.ndarray
    constraints: np.ndarray
    jacobian: np.ndarray


class _Masses(NamedTuple):
    """The best masses found at given boundaries: their rank and free numbers ``y``."""
    rank: _Rank
    y: np.ndarray


@dataclass(frozen=True)
class OptimalPiston:
    """The best stepped piston found by :func:`optimize_piston` and the uniform piston beside it
    (SI units; theory §12).

    Attributes
    ----------
    lengths_m, areas_m2 : numpy.ndarray, shape (n,)
        The segments' lengths (m) and cross-sections (m^2), from the driven end to the struck end.
    work_on_rock_J, efficiency, peak_rod_stress_Pa : float
        Of its blow: the work on the rock (J), that over the impact energy :math:`m V^2/2` (plus the
        feed's), and the peak of the incident stress wave in the rod's first piece (Pa): the
        largest piston-shank force over the first piece's area before the wave the rock reflects
        first is back at the shank, or over the piston's first contact where that lasts longer (the
        stepped piston's own re-strikes included, what the rock sends back not).
    uniform_work_on_rock_J, uniform_efficiency, uniform_peak_rod_stress_Pa : float
        The same of the uniform piston of the same mass and length (``peak_stress_Pa`` and
        ``uniform_peak_stress_Pa`` the names the peaks had: a ``DeprecationWarning``).
    blow_peak_stress_Pa : float
        The largest piston-shank stress of the whole blow (Pa), the piston's re-contacts on what the
        rock sends back included. Not limited: on a stiff rock's unloading the bit reflects a spike
        of width :math:`Z/K_u` (the exact blow resolves it, the lattice averages it over a cell)
        that a re-contact can carry above the incident wave's peak.
    feasible : bool
        Whether the peak stress is within the limit (if neither this shape nor the uniform piston
        meets it, the one closest to it).
    evaluations : int
        Blows solved by the search (``method="slsqp"``: each with its derivatives in the ``n - 1``
        directions of the masses).
    cell_time_s : float
        The time step of the lattice, or of the exact blow's samples (s).
    times_s : numpy.ndarray, shape (k + 1,)
        The step ends of the blows (s).
    incident_force_N, uniform_incident_force_N : numpy.ndarray, shape (k,)
        The piston-shank force on each step (N) of this shape and of the uniform piston: the
        incident wave while nothing returns from the rod.
    blow, uniform_blow : Blow
        The two blows in the model's units (piston mass, length and wave speed 1).
    max_stress_Pa, mass_kg, length_m, impact_velocity_m_s : float
        The inputs.
    E_Pa, density_kg_m3 : float
        The piston's material (the inputs, or the first rod piece's).
    """

    lengths_m: np.ndarray
    areas_m2: np.ndarray
    work_on_rock_J: float
    efficiency: float
    peak_rod_stress_Pa: float
    uniform_work_on_rock_J: float
    uniform_efficiency: float
    uniform_peak_rod_stress_Pa: float
    blow_peak_stress_Pa: float
    feasible: bool
    evaluations: int
    cell_time_s: float
    times_s: np.ndarray = field(repr=False)
    incident_force_N: np.ndarray = field(repr=False)
    uniform_incident_force_N: np.ndarray = field(repr=False)
    blow: object = field(repr=False)
    uniform_blow: object = field(repr=False)
    max_stress_Pa: float = math.inf
    mass_kg: float = 0.0
    length_m: float = 0.0
    impact_velocity_m_s: float = 0.0
    E_Pa: float = math.nan
    density_kg_m3: float = math.nan

    def __repr__(self) -> str:
        seg = ", ".join(f"{le * 1e3:.4g} mm x {d * 1e3:.4g} mm" for le, d in
                        zip(self.lengths_m, self.diameters_m, strict=True))
        return (f"OptimalPiston({seg}; work on rock {self.work_on_rock_J:.5g} J (uniform "
                f"{self.uniform_work_on_rock_J:.5g} J), efficiency {self.efficiency:.4f}, peak stress "
                f"{self.peak_rod_stress_Pa / 1e6:.4g} MPa)")

    peak_stress_Pa = renamed_attribute("peak_stress_Pa", "peak_rod_stress_Pa")
    uniform_peak_stress_Pa = renamed_attribute("uniform_peak_stress_Pa", "uniform_peak_rod_stress_Pa")

    @property
    def diameters_m(self) -> np.ndarray:
        """The segments' diameters (m) for circular sections, shape ``(n,)``."""
        return np.sqrt(4.0 * self.areas_m2 / math.pi)

    @property
    def bar(self):
        """The piston found, as a :class:`~impactbar.physical.SteppedBar` (a
        :class:`~impactbar.physical.Bar` for one segment), to put into a ``Hammer``, a ``Drifter``
        or a ``CircuitDrifter`` (theory §12)."""
        from .bar import Bar, SteppedBar

        if self.lengths_m.size == 1:
            return Bar(self.E_Pa, self.density_kg_m3, float(self.lengths_m[0]), float(self.areas_m2[0]))
        return SteppedBar(self.E_Pa, self.density_kg_m3, self.lengths_m, self.areas_m2)

    @property
    def gain(self) -> float:
        r"""The work on the rock over the uniform piston's (:math:`\ge 1` when both are feasible)."""
        return self.work_on_rock_J / self.uniform_work_on_rock_J

    def plot(self, axes=None):
        """The best shape and its incident wave against the uniform piston's
        (:func:`impactbar.plotting.piston.plot_piston_design`; matplotlib imported on this call).

        Returns
        -------
        numpy.ndarray of matplotlib.axes.Axes, shape (2,)
        """
        from ..plotting.piston import plot_piston_design

        return plot_piston_design(self, axes=axes)


def optimize_piston(rod, rock, *, mass, length, max_stress, impact_velocity, segments=3,
                    E=None, density=None, bit_mass=0.0, feed=0.0, cells=48, t_max=None,
                    method="slsqp", max_evaluations=None) -> OptimalPiston:
    r"""The stepped piston of given mass and length that does the most work on the rock per blow,
    the incident stress in the rod at most ``max_stress`` (theory §12; SI in and out).

    Parameters
    ----------
    rod : RodPiece or sequence of RodPiece
        The drill string from the shank to the bit (:class:`~impactbar.physical.rock.RodPiece`).
    rock : tuple of float
        :math:`(K, K_u)`: Lundberg's loading and unloading stiffnesses of the bit on the rock (N/m),
        :math:`0 < K \le K_u`.
    mass : float
        The piston's mass (kg), ``> 0``.
    length : float
        The piston's length (m), ``> 0``.
    max_stress : float
        The largest compressive stress (Pa, ``> 0``) allowed in the incident wave: the peak
        piston-shank force over the first rod piece's area before the rock's first reflection is
        back at the shank (:attr:`OptimalPiston.peak_rod_stress_Pa`; ``math.inf``: no limit).
    impact_velocity : float
        The piston's velocity at impact (m/s), ``> 0``; moving rigidly and unstressed.
    segments : int
        ``n``, the piston's segments, 1 to 8 (1: the uniform piston, nothing to optimise).
    E, density : float, optional
        The piston's Young's modulus (Pa) and density (kg/m^3); default the first rod piece's.
    bit_mass, feed : float
        The bit's mass (kg, :math:`\ge 0`) and the static feed force (N, :math:`\ge 0`).
    cells : int
        Cells along the piston in the search and in the final blows (8 to 1024): the rod's pieces
        are rounded to whole cells of ``L / (c cells)`` (:attr:`Blow.length_error`); the gradient
        search's boundaries lie on whole cells of ``L / cells`` (then between them, by the final
        exact blows).
    t_max : float, optional
        The blow's duration (s). Default: the rod-rock law's window, the piston's contact of
        ``4 L/c`` and a wave's round trip through piston and rod after it (so that on a long rod
        the work of the first passage of the wave, Lundberg's).
    method : {"slsqp", "nelder-mead"}
        The search (theory §12): ``"slsqp"``, the boundaries on whole cells by two pattern
        searches over the cells and the masses by scipy's SLSQP with the exact gradients of the
        work and of every step's shank force, the stress limit one constraint per step; or
        ``"nelder-mead"``, scipy's derivative-free search over lengths and masses on the work less
        a penalty on the excess stress (the search before the gradients, kept to compare with).
    max_evaluations : int, optional
        Most blows, :math:`\ge 1`: with ``"slsqp"`` of the whole search (each blow with its
        derivatives), default ``200 (2 n - 2)``; with ``"nelder-mead"`` of each of its two runs
        (from the uniform piston and again from the result), default ``300 (2 n - 2)``.

    Returns
    -------
    OptimalPiston
        The best shape, its blow and the uniform piston's beside it.

    Raises
    ------
    ValueError
        A parameter out of its range (named), ``rod`` not a ``RodPiece`` or a sequence of them,
        ``rock`` not a pair :math:`0 < K \le K_u`.

    Examples
    --------
    >>> from impactbar.physical.piston import optimize_piston
    >>> from impactbar.physical.rock import RodPiece
    >>> rod = [RodPiece(length_m=6.0, area_m2=1.0e-3, E_Pa=2.1e11, density_kg_m3=7850.0)]
    >>> best = optimize_piston(rod, (3.0e8, 3.0e9), mass=2.355, length=0.3, max_stress=2.5e8,
    ...                        impact_velocity=10.0, segments=2)
    >>> bool(best.work_on_rock_J >= best.uniform_work_on_rock_J) and best.feasible
    True
    >>> round(best.uniform_efficiency, 4)  # a matched uniform piston: Lundberg's at alpha = 0.857
    0.6958
    >>> best.blow.method  # the design's blow: every wave exact
    'exact'
    >>> best.lengths_m.round(4), best.diameters_m.round(4)  # heavy at the driven end, slender struck end
    (array([0.1246, 0.1754]), array([0.0391, 0.033 ]))
    >>> round(best.bar.mass_kg, 6), best.bar.n_segments  # the piston for a Hammer or a Drifter
    (2.355, 2)
    """
    pieces = _pieces(rod)
    K, K_u = _rock(rock)
    m = check_real("mass", mass, lo=0.0, lo_open=True)
    L = check_real("length", length, lo=0.0, lo_open=True)
    sigma = math.inf if max_stress == math.inf else check_real("max_stress", max_stress, lo=0.0,
                                                                  lo_open=True)
    V = check_real("impact_velocity", impact_velocity, lo=0.0, lo_open=True)
    n = check_int("segments", segments, lo=1, hi=8)
    E = pieces[0].E_Pa if E is None else check_real("E", E, lo=0.0, lo_open=True)
    rho = pieces[0].density_kg_m3 if density is None else check_real("density", density, lo=0.0, lo_open=True)
    mb = check_real("bit_mass", bit_mass, lo=0.0)
    f = check_real("feed", feed, lo=0.0)
    N = check_int("cells", cells, lo=8, hi=1024)
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(map(repr, METHODS))}; got method={method!r}")
    c, force_N, energy_J, time_s, seg, k, k_u, T, back = _model_units(pieces, K, K_u, m, L, E, rho, t_max)
    scale = force_N / (pieces[0].area_m2 * sigma) if math.isfinite(sigma) else 0.0  # stress / limit per force
    v = V / c

    from ..dynamics.stepped import SteppedPiston
    from ..laws.rodrock.blow import rod_rock_blow

    def blow(piston):
        return rod_rock_blow(1.0, v, *seg, k, k_u, mb / m, f / force_N, cells_per_piston=N, t_max=T,
                             piston=piston)

    def merit(b):
        """Work (in impact energies) less the penalty; the relative excess stress."""
        excess = max(0.0, b.incident_peak_force(back) * scale - 1.0)
        return _Merit(b.work_on_rock / b.energy_at_impact - PENALTY * excess, excess)

    uniform = blow(None)
    refined = None  # the gradient search's design between the cells
    count = [0]
    best_x = np.zeros(2 * n - 2)
    if max_evaluations is not None:
        max_evaluations = check_int("max_evaluations", max_evaluations, lo=1)
    if n > 1 and method == "slsqp":
        from ..laws.rodrock.grid import whole_steps
        from ..laws.rodrock.tangent import rod_rock_blow_tangent

        def blow_tangent(Z, dZ):
            return rod_rock_blow_tangent(1.0, v, *seg, k, k_u, mb / m, f / force_N, Z, dZ, t_max=T)

        maxfev = 200 * (2 * n - 2) if max_evaluations is None else max_evaluations
        edges, mf, refined, count[0] = _gradient_search(blow_tangent, n, N, scale, whole_steps(T, 1.0 / N),
                                                        maxfev, back)
        lf = np.diff(np.concatenate(([0.0], edges, [1.0])))
    elif n > 1:
        from scipy.optimize import minimize

        def objective(x):
            count[0] += 1
            return -merit(blow(_cell_piston(x, n, N, SteppedPiston))).gain

        maxfev = 300 * (2 * n - 2) if max_evaluations is None else max_evaluations
        for _ in range(2):  # started at the uniform piston, restarted once from the result
            simplex = np.vstack([best_x] + [best_x + 0.5 * e for e in np.eye(best_x.size)])
            res = minimize(objective, best_x, method="Nelder-Mead",
                           options={"initial_simplex": simplex, "xatol": 1e-3, "fatol": 1e-9,
                                    "maxfev": maxfev})
            best_x = np.clip(res.x, -BOUND, BOUND)
    if method == "nelder-mead" or n == 1:
        lf, mf = _fractions(best_x, n)
    shaped = None
    if f == 0.0 or mb == 0.0:  # the design where the search put it, every wave exact (a feed too)
        shaped = _exact_blow(v, seg, k, k_u, mb / m, f / force_N, T, N,
                             SteppedPiston(lf, mf / lf) if n > 1 else None)
        plain = _exact_blow(v, seg, k, k_u, mb / m, f / force_N, T, N, None) if shaped is not None else None
        if plain is not None:
            uniform = plain
            other = None
            if refined is not None:
                lf_refined, mf_refined = refined
                other = _exact_blow(v, seg, k, k_u, mb / m, f / force_N, T, N,
                                    SteppedPiston(lf_refined, mf_refined / lf_refined))
            if other is not None and _better(merit(other), merit(shaped)):
                shaped, (lf, mf) = other, refined
        else:
            shaped = None
    if shaped is None:  # the boundaries on whole cells, the lattice's blows
        lf = _whole_cells(lf, N) / N
        shaped = blow(SteppedPiston(lf, mf / lf)) if n > 1 else uniform
    (w_s, x_s), (w_u, x_u) = merit(shaped), merit(uniform)
    if (x_s > 0.0 or w_s < w_u) and (x_u == 0.0 or x_u < x_s):  # the uniform piston is better
        shaped, x_s = uniform, x_u
        lf = mf = np.full(n, 1.0 / n)
    lengths = lf * L
    areas = mf * m / (rho * lengths)
    stress = shaped.incident_peak_force(back) * force_N / pieces[0].area_m2
    u_stress = uniform.incident_peak_force(back) * force_N / pieces[0].area_m2
    steps = min(shaped.shank_forces.size, uniform.shank_forces.size)
    peak, _ = shaped.peak_shank_force()
    return OptimalPiston(
        lengths_m=lengths, areas_m2=areas, work_on_rock_J=shaped.work_on_rock * energy_J,
        efficiency=shaped.efficiency, peak_rod_stress_Pa=stress,
        uniform_work_on_rock_J=uniform.work_on_rock * energy_J, uniform_efficiency=uniform.efficiency,
        uniform_peak_rod_stress_Pa=u_stress, blow_peak_stress_Pa=peak * force_N / pieces[0].area_m2,
        feasible=x_s == 0.0, evaluations=count[0],
        cell_time_s=shaped.cell_time * time_s, times_s=shaped.times[:steps + 1] * time_s,
        incident_force_N=shaped.shank_forces[:steps] * force_N,
        uniform_incident_force_N=uniform.shank_forces[:steps] * force_N, blow=shaped, uniform_blow=uniform,
        max_stress_Pa=sigma, mass_kg=m, length_m=L, impact_velocity_m_s=V, E_Pa=E, density_kg_m3=rho)


def _model_units(pieces, K, K_u, m, L, E, rho, t_max):
    """The blow's units (length ``L``, time ``L/c``, mass ``m``: force ``m c^2/L``, energy ``m c^2``)
    and the rod and rock in them: ``(c, force_N, energy_J, time_s, seg, k, k_u, T)``, ``seg`` the
    rod's lengths, impedances (over a uniform piston's, ``m c / L``) and wave speeds, ``T`` the
    window (default the contact of ``4 L/c`` and a wave's round trip through the rod after it),
    ``back`` that round trip (when the rock's first reflection is back at the shank)."""
    c = math.sqrt(E / rho)
    force_N, energy_J, time_s = m * c * c / L, m * c * c, L / c
    Zu = m * c / L  # a uniform piston's impedance
    seg = _Rod([g.length_m / L for g in pieces], [g.impedance_kg_s / Zu for g in pieces],
               [g.wave_speed_m_s / c for g in pieces])
    k, k_u = K * L * L / (m * c * c), K_u * L * L / (m * c * c)
    travel = sum(le / sp for le, sp in zip(seg.lengths, seg.speeds, strict=True))
    T = 4.0 + 2.0 * travel if t_max is None else check_real("t_max", t_max, lo=0.0, lo_open=True) / time_s
    return c, force_N, energy_J, time_s, seg, k, k_u, T, 2.0 * travel


def piston_blow(rod, rock, *, lengths, areas, impact_velocity, E=None, density=None, bit_mass=0.0, feed=0.0,
                cells=48, t_max=None) -> dict:
    r"""The blow of a given stepped piston on the rod and rock, as :func:`optimize_piston` scores its
    designs (theory §12; SI in and out): the work on the rock of one blow in the same window, every
    wave exact (where the exact solver's bounds allow, and not both a feed and a bit mass; else the
    lattice's blow, its boundaries rounded to whole cells of ``L / cells``).

    Parameters
    ----------
    rod, rock, impact_velocity, E, density, bit_mass, feed, cells, t_max
        As :func:`optimize_piston`'s.
    lengths, areas : sequence of float, shape (n,)
        The segments' lengths (m) and cross-sections (m^2), driven end first, each ``> 0``
        (:attr:`OptimalPiston.lengths_m` and ``areas_m2``; one segment: the uniform piston).

    Returns
    -------
    dict
        ``work_on_rock_J``, ``efficiency`` (the work over the impact energy, plus the feed's),
        ``impact_energy_J`` (:math:`m V^2/2`), ``peak_rod_stress_Pa`` (the exact peak of the
        incident wave, the piston-shank force over the rod's first area as
        :attr:`OptimalPiston.peak_rod_stress_Pa` reads it), ``blow_peak_stress_Pa`` (of the whole
        blow, re-contacts included), ``mass_kg``, ``length_m``, ``method``
        (``"exact"`` or ``"lattice"``) and ``blow`` (the :class:`~impactbar.laws.rodrock.Blow`, in
        the units of piston mass, length and wave speed 1).

    Raises
    ------
    ValueError
        A parameter out of its range (named); ``lengths`` and ``areas`` not of one length ``1`` to
        ``8``.

    Examples
    --------
    >>> from impactbar.physical.piston import piston_blow
    >>> from impactbar.physical.rock import RodPiece
    >>> rod = [RodPiece(length_m=6.0, area_m2=1.0e-3, E_Pa=2.1e11, density_kg_m3=7850.0)]
    >>> b = piston_blow(rod, (3.0e8, 3.0e9), lengths=[0.3], areas=[1.0e-3], impact_velocity=10.0)
    >>> round(b["efficiency"], 4), b["method"]  # the uniform piston of optimize_piston's example
    (0.6958, 'exact')
    """
    pieces = _pieces(rod)
    K, K_u = _rock(rock)
    try:
        lengths, areas = (np.asarray([check_real(f"{name}[{j}]", x, lo=0.0, lo_open=True)
                                      for j, x in enumerate(xs)])
                          for name, xs in (("lengths", lengths), ("areas", areas)))
    except TypeError:
        raise ValueError("lengths and areas must be sequences of numbers") from None
    if not 1 <= lengths.size <= 8 or areas.size != lengths.size:
        raise ValueError(f"lengths and areas must be of one length, 1 to 8; got {lengths.size} and "
                         f"{areas.size}")
    V = check_real("impact_velocity", impact_velocity, lo=0.0, lo_open=True)
    E = pieces[0].E_Pa if E is None else check_real("E", E, lo=0.0, lo_open=True)
    rho = pieces[0].density_kg_m3 if density is None else check_real("density", density, lo=0.0, lo_open=True)
    mb = check_real("bit_mass", bit_mass, lo=0.0)
    f = check_real("feed", feed, lo=0.0)
    N = check_int("cells", cells, lo=8, hi=1024)
    L = float(lengths.sum())
    m = rho * float(np.sum(lengths * areas))
    c, force_N, energy_J, _, seg, k, k_u, T, back = _model_units(pieces, K, K_u, m, L, E, rho, t_max)
    from ..dynamics.stepped import SteppedPiston
    from ..laws.rodrock.blow import rod_rock_blow

    lf, mf = lengths / L, rho * lengths * areas / m
    b = None
    if f == 0.0 or mb == 0.0:
        b = _exact_blow(V / c, seg, k, k_u, mb / m, f / force_N, T, N,
                        SteppedPiston(lf, mf / lf) if lf.size > 1 else None)
    if b is None:
        lf = _whole_cells(lf, N) / N
        b = rod_rock_blow(1.0, V / c, *seg, k, k_u, mb / m, f / force_N, cells_per_piston=N, t_max=T,
                          piston=SteppedPiston(lf, mf / lf) if lf.size > 1 else None)
    to_Pa = force_N / pieces[0].area_m2
    peak, _ = b.peak_shank_force()
    return {"work_on_rock_J": b.work_on_rock * energy_J, "efficiency": b.efficiency,
            "impact_energy_J": 0.5 * m * V * V,
            "peak_rod_stress_Pa": b.incident_peak_force(back) * to_Pa,
            "blow_peak_stress_Pa": peak * to_Pa,
            "mass_kg": m, "length_m": L, "method": b.method, "blow": b}


def _better(a, b):
    """Whether the merit ``a = (work less penalty, excess)`` beats ``b``: feasible before not, then
    the more work, or the less excess."""
    if (a.excess > 0.0) != (b.excess > 0.0):
        return b.excess > 0.0
    return a.gain > b.gain if a.excess == 0.0 else a.excess < b.excess


def _exact_blow(v, seg, k, k_u, bit_mass, feed, T, samples, piston):
    """The blow of ``piston`` (None: uniform) in the window ``T`` by the exact solver, sampled
    ``samples`` times a piston crossing; None where its pieces would pass the default's bounds or
    its energy account is not closed (:func:`~impactbar.single_blow`'s ``method="auto"``)."""
    from ..laws.rodrock.exact import PoolOverflow
    from ..laws.rodrock.exactrecord import exact_rod_rock_blow
    from ..laws.rodrock.law import AUTO_MAX_PIECES, AUTO_MAX_POOL_BYTES, EXACT_ACCOUNT_TOLERANCE

    try:
        b = exact_rod_rock_blow(1.0, v, *seg, k, k_u, bit_mass, feed, t_max=T, samples_per_piston=samples,
                                max_pieces=AUTO_MAX_PIECES, piston=piston, max_pool_bytes=AUTO_MAX_POOL_BYTES)
    except PoolOverflow:
        return None
    return b if b.ended_by != "budget" and b.energy_error <= EXACT_ACCOUNT_TOLERANCE else None


def _fractions(x, n):
    """Length and mass fractions, shape ``(n,)`` each, of the free numbers ``x`` (shape
    ``(2 n - 2,)``): softmaxes with the first segment's number 0."""
    x = np.clip(np.asarray(x, float), -BOUND, BOUND)
    a = np.exp(np.concatenate(([0.0], x[:n - 1])))
    b = np.exp(np.concatenate(([0.0], x[n - 1:])))
    return a / a.sum(), b / b.sum()


def _cell_piston(x, n, N, SteppedPiston):
    """The piston of the free numbers ``x`` on ``N`` cells: each cell's mass per length the mass it
    holds over its length (continuous in the segments' boundaries)."""
    lf, mf = _fractions(x, n)
    edges = np.concatenate(([0.0], np.cumsum(lf)))
    edges[-1] = 1.0
    held = np.interp(np.arange(N + 1) / N, edges, np.concatenate(([0.0], np.cumsum(mf))))
    return SteppedPiston(np.ones(N), np.maximum(np.diff(held), 1e-300))


class _Budget(Exception):
    """The search's blows are spent."""


def _gradient_search(blow_tangent, n, N, scale, n_steps, maxfev, back=math.inf):
    """The gradient search (theory §12): the segments' boundaries on whole cells ``B`` (shape
    ``(n - 1,)``), where a stepped piston's lattice blow has its waves constant on cells; for each
    ``B`` the segments' masses (a softmax of ``n - 1`` free numbers ``y``, bounded) by
    SLSQP on the work per impact energy with its exact gradient (``blow_tangent(Z, dZ)``,
    :func:`~impactbar.laws.rodrock.tangent.rod_rock_blow_tangent`) and, with ``scale > 0``, one
    constraint ``scale N_i <= 1`` per step ``i`` of the incident wave (the peak stress's limit, every
    step's force its own constraint: no maximum differentiated; ``back`` the rock's first
    reflection back at the shank, :func:`_whole_cell_blow`); over ``B`` two pattern searches
    from the uniform piston (each boundary, and each inner segment whole, moved by half and by a
    quarter of a uniform segment's cells, on in a direction while the design gains, the moves
    halved down to one cell), the better kept. At most ``maxfev`` blows (each with its
    derivatives). Returns the best design's boundaries and mass fractions, a design between the
    cells near it (or None) and the blows solved."""
    from scipy.optimize import minimize

    from ..dynamics.stepped import MAX_IMPEDANCE_RATIO

    count = [0]
    # the masses' free numbers bounded so that no two segments' impedances are further apart than
    # a SteppedPiston takes (a mass ratio e^(2 bound), a length ratio below N)
    bound = min(BOUND, 0.5 * math.log(MAX_IMPEDANCE_RATIO / N))

    def vertex(B, y):
        """``(rank, -work, -d work/dy, c, dc/dy)`` of the boundaries ``B`` and masses ``y``."""
        if count[0] >= maxfev:
            raise _Budget
        count[0] += 1
        work, dwork, c, dc = _whole_cell_blow(blow_tangent, B, y, N, scale, n_steps, back)
        excess = max(0.0, -float(c.min()))
        return _Vertex(_Rank(int(excess > 0.0), excess, -work), -work, -dwork, c, dc)

    def masses(B, y0):
        """The best ``(rank, y)`` of the boundaries ``B`` by SLSQP from ``y0``."""
        last = {}
        best = _Masses(_Rank(2, 0.0, 0.0), y0)

        def evaluate(y):
            nonlocal best
            y = np.clip(np.asarray(y, dtype=float), -bound, bound)
            key = y.tobytes()
            if key not in last:
                last.clear()
                last[key] = vertex(B, y)
                if last[key].rank < best.rank:
                    best = _Masses(last[key].rank, y.copy())
            return last[key]

        try:
            # the steps whose force is above half the limit at the start are constrained (every
            # step's force counts in the rank)
            steps = np.flatnonzero(evaluate(y0).constraints < 0.5) if scale > 0.0 else ()
            constraints = ([{"type": "ineq", "fun": lambda y: evaluate(y).constraints[steps],
                             "jac": lambda y: evaluate(y).jacobian[steps]}] if len(steps) else [])
            minimize(lambda y: evaluate(y).objective, y0, jac=lambda y: evaluate(y).gradient, method="SLSQP",
                     bounds=[(-bound, bound)] * (n - 1), constraints=constraints,
                     options={"maxiter": 100, "ftol": FTOL})
        except _Budget:
            if best.rank.infeasible == 2:
                raise
        return best

    B = np.round(N * np.arange(1, n) / n).astype(np.int64)  # the uniform piston
    y = np.zeros(n - 1)
    eye = np.eye(n - 1, dtype=np.int64)
    moves = [d * eye[j] for j in range(n - 1) for d in (1, -1)]
    moves += [d * (eye[j] + eye[j + 1]) for j in range(n - 2) for d in (1, -1)]  # an inner segment whole

    def design(C, y, visited):
        """``(rank, y)`` of the boundaries ``C``, its masses from ``y`` (or as this run found them)."""
        key = C.tobytes()
        if key not in visited:
            visited[key] = masses(C, y)
        return visited[key]

    # the best design: its rank, boundaries, masses, and the designs its search visited
    best_rank, best_B, best_y, best_seen = _Rank(3, 0.0, 0.0), B, y, {}
    try:
        # two pattern searches from the uniform piston, their first moves half and a quarter of a
        # uniform segment's cells, halved down to one cell (each its own: the masses' optimum at
        # given boundaries depends on where SLSQP starts)
        for first in sorted({max(1, N // (2 * n)), max(1, N // (4 * n))}, reverse=True):
            visited = {}
            C, yc = B, np.zeros(n - 1)
            r, yc = design(C, yc, visited)
            if r < best_rank:
                best_rank, best_B, best_y, best_seen = r, C, yc, visited
            step = first
            while step >= 1:
                improved = True
                while improved:
                    improved = False
                    for move in moves:
                        while True:  # on in this direction while it gains
                            D = C + step * move
                            if np.diff(np.concatenate(([0], D, [N]))).min() < 1:
                                break
                            rd, yd = design(D, yc, visited)
                            if rd >= r:
                                break
                            C, yc, r, improved = D, yd, rd, True
                            if r < best_rank:
                                best_rank, best_B, best_y, best_seen = r, C, yc, visited
                step //= 2
    except _Budget:
        pass
    rank, B, y, seen = best_rank, best_B, best_y, best_seen
    # between the cells: per boundary the parabola through the best design's and its two
    # neighbours' work (masses alike), where all three are feasible
    b, yr = B.astype(float), y.copy()
    for j in range(n - 1):
        side = [seen.get((B + d * eye[j]).tobytes()) for d in (-1, 1)]
        below, above = side
        if rank.infeasible or any(t is None or t.rank.infeasible for t in side):
            continue
        lo, mid, hi = -below.rank.loss, -rank.loss, -above.rank.loss
        curv = lo - 2.0 * mid + hi
        if curv < 0.0:
            d = float(np.clip(0.5 * (lo - hi) / curv, -0.5, 0.5))
            b[j] += d
            yr += 0.5 * d * (above.y - below.y) + 0.5 * d * d * (above.y - 2.0 * y + below.y)
    refined = None
    if np.any(b != B):
        mf_refined, _ = _softmax_jacobian(yr)
        refined = np.diff(np.concatenate(([0.0], b, [N]))) / N, mf_refined
    mf, _ = _softmax_jacobian(y)
    return B / N, mf, refined, count[0]


def _whole_cell_blow(blow_tangent, B, y, N, scale, n_steps, back=math.inf):
    """The gradient search's blow: the segments' boundaries on the whole cells ``B`` (int, shape
    ``(n - 1,)``, increasing in ``(0, N)``), their masses ``softmax([0, y])``. Returns the work per
    impact energy and its gradient in ``y`` (shape ``(n - 1,)``), and the constraints
    ``c = 1 - scale N_i`` on the ``n_steps`` steps and their Jacobian ``(n_steps, n - 1)``: on the
    incident wave's steps (those that start before ``back``, the rock's first reflection back at the
    shank, or within the piston's first contact: :meth:`~impactbar.laws.rodrock.Blow.incident_peak_force`),
    ``c = 1`` and no gradient on the others (0 force after the blow's end); ``blow_tangent(Z, dZ)`` runs
    :func:`~impactbar.laws.rodrock.tangent.rod_rock_blow_tangent` on the cells' impedances ``Z``
    (``N`` times the mass per length) along the directions ``dZ``."""
    from ..laws.rodrock.grid import incident_steps

    mf, J_m = _softmax_jacobian(y)
    n = mf.size
    cells = np.diff(np.concatenate(([0], B, [N])))
    seg = np.repeat(np.arange(n), cells)
    tb = blow_tangent(N * mf[seg] / cells[seg], N * J_m[seg] / cells[seg][:, None])
    E0, W = tb.energy_at_impact, tb.work_on_rock
    c = np.ones(n_steps)
    dc = np.zeros((n_steps, n - 1))
    f = tb.shank_forces
    m = incident_steps(f, tb.cell_time * np.arange(f.size), back)
    c[:m] -= scale * f[:m]
    dc[:m] = -scale * tb.shank_tangents[:m]
    return W / E0, tb.work_tangent / E0 - W * tb.energy_tangent / (E0 * E0), c, dc


def _softmax_jacobian(y):
    """The mass fractions ``softmax([0, y])``, shape ``(n,)``, and their Jacobian ``(n, n - 1)``."""
    e = np.exp(np.concatenate(([0.0], y)))
    mf = e / e.sum()
    n = mf.size
    J = mf[:, None] * ((np.arange(n)[:, None] == np.arange(1, n)[None, :]) - mf[None, 1:])
    return mf, J


def _whole_cells(lf, N):
    """The segments' cells, shape ``(n,)`` (float), each at least 1, summing to ``N``: the boundaries
    rounded to whole cells."""
    n = lf.size
    b = np.round(np.cumsum(lf)[:-1] * N)
    prev = 0.0
    for i in range(n - 1):
        b[i] = prev = min(max(b[i], prev + 1.0), float(N - (n - 1 - i)))
    return np.diff(np.concatenate(([0.0], b, [float(N)])))


def _pieces(rod):
    pieces = (rod,) if isinstance(rod, RodPiece) else tuple(rod) if isinstance(rod, (list, tuple)) else ()
    if not pieces or not all(isinstance(g, RodPiece) for g in pieces):
        raise ValueError(f"rod must be a RodPiece or a non-empty sequence of RodPiece; got rod={rod!r}")
    return pieces


def _rock(rock):
    try:
        K, K_u = rock
    except (TypeError, ValueError):
        raise ValueError(f"rock must be a pair (K, K_u) of stiffnesses in N/m; got rock={rock!r}") from None
    K = check_real("rock K", K, lo=0.0, lo_open=True)
    return K, check_real("rock K_u", K_u, lo=K)
