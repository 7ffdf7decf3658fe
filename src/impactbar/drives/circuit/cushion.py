r"""A cushion: a position-controlled orifice on the rear chamber's way out (theory §11, *Parts of a
drill's circuit*), a part of its own (:class:`~impactbar.drives.circuit.CircuitPart`), its equations
in :mod:`.kinds.cushion` (the flow) and :mod:`.kinds.level` (its kinks).

References
----------
Hopsan's component library, ``componentLibraries/defaultLibrary/Hydraulic``:
``Volumes&Lines/HydraulicVolume.hpp`` (the cushion's node), ``Restrictors/HydraulicTurbulentOrifice.hpp``
(the port, here of an opening that the piston's gap sets).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ._network import CUSHION, LEVEL, NODE, record
from .composition import NO_PORT, NamedPart, OwnNode, PartField
from .leakage import _check_names

__all__ = ["Cushion", "opening_segment"]


def opening_segment(gaps, openings, above) -> tuple[float, float]:
    """The piece ``g = intercept + slope y`` of the piecewise linear ``g`` through ``(gaps[i],
    openings[i])`` (constant beyond the ends) on which the gap lies, ``above[i]`` saying whether it
    is at or above ``gaps[i]`` (the mode's flags).

    Examples
    --------
    >>> opening_segment((0.1, 0.2), (1.0, 0.0), (True, False))
    (2.0, -10.0)
    >>> opening_segment((0.1, 0.2), (1.0, 0.0), (True, True))
    (0.0, 0.0)
    """
    k = int(sum(bool(a) for a in above))
    if k == 0:
        return float(openings[0]), 0.0
    if k == len(gaps):
        return float(openings[-1]), 0.0
    slope = (openings[k] - openings[k - 1]) / (gaps[k] - gaps[k - 1])
    return float(openings[k - 1] - slope * gaps[k - 1]), float(slope)


@dataclass(frozen=True)
class Cushion(OwnNode, NamedPart):
    r"""A cushion on the rear chamber's way out: the valve's return port drains into a node of oil
    ``volume`` (named ``name``), and from it to ``target`` through a port that the piston's gap
    ``y`` opens, ``q = K_max g(y) phi(p_cushion - p_target)``, ``g`` piecewise linear through the
    points ``(gaps[i], openings[i])``, constant beyond the end points (a port the piston shuts as it
    returns: ``g`` falling to a small opening at the top of the stroke brakes it). Each point is a
    kink of ``g``, an event of the flights (``<name>_kink<i>``: the gap through ``gaps[i]``). Its
    node's compression work and the port's loss are energy integrands of their own (``name`` in the
    ``compression`` term, ``<name>_port`` in ``orifices``). ``g = 1``, ``K_max`` to infinity and the
    volume to 0 remove it. The kind ``"cushion"`` of a configuration's ``[parts.<name>]`` table (its
    ``gaps`` a list of lengths, its ``openings`` a list of numbers; its parameters
    ``<name>.volume``, ``<name>.coefficient``).

    Parameters
    ----------
    volume : float
        The cushion node's oil volume, ``> 0`` (``A_r L`` units).
    coefficient : float
        :math:`K_\max \ge 0`, the port's fully open flow coefficient (model units, as an orifice's).
    gaps : tuple of float
        The points' gaps, increasing (bar lengths).
    openings : tuple of float
        ``g`` at them, each in ``[0, 1]``.
    target : str, optional
        The node it drains to (default the tank; a return line's node).
    name : str, optional
        Its node's name and its events', integrands' and parameters' prefix, an identifier.
    port : str, optional
        The preset's port it takes (``"valve_return"``), or ``"none"``: none (its node fed by
        another part that names it, as a cushion's ``target``).

    Raises
    ------
    ValueError
        A value out of its range, gaps not increasing, openings of another count.

    Examples
    --------
    >>> from dataclasses import replace
    >>> from impactbar.physical import circuit_preset
    >>> c = Cushion(volume=0.05, coefficient=5.0, gaps=(0.03, 0.05), openings=(1.0, 0.2))
    >>> drive = replace(circuit_preset("circuit-drifter").drive(), extra_parts=(c,))
    >>> drive.layout.states
    ('front', 'rear', 'supply', 'cushion', 'spool')
    >>> [e.name for e in drive.events((1, 0, 1, 0, 1, 0))][-2:]
    ['cushion_kink0', 'cushion_kink1']
    """

    volume: float
    coefficient: float
    gaps: tuple
    openings: tuple
    target: str = "tank"
    name: str = "cushion"
    port: str = "valve_return"

    si_fields = (
        PartField("volume", "m**3", "'0.05 L'", "volume", description="the cushion node's oil volume"),
        PartField("coefficient", "m**3/s/Pa**0.5", "'1e-5 m^3/s/Pa^0.5'", "orifice", low_open=False,
                  description="the cushion port's full opening coefficient"))
    si_lists = (
        PartField("gaps", "m", "['3 mm', '5 mm']", "length", low=-math.inf, low_open=False,
                  description="the gaps of the points of the port's opening"),
        PartField("openings", "", "[1.0, 0.2]", "one", low=0.0, high=1.0, low_open=False, high_open=False,
                  description="the port's opening at those gaps"))
    connections = {"port": ("port", "valve_return"), "target": ("node", "tank")}

    def __post_init__(self) -> None:
        _check_names(self, "target", "name")
        given_gaps, given_openings = self.gaps, self.openings
        super().__post_init__()
        gaps, openings = self.gaps, self.openings
        rising = all(b > a for a, b in zip(gaps, gaps[1:], strict=False))
        if not gaps or len(openings) != len(gaps) or not rising:
            raise ValueError(f"{self.name}.gaps must be one or more increasing gaps, with as many openings "
                             f"(each in [0, 1]); got gaps {given_gaps!r}, openings {given_openings!r}")

    @property
    def energies(self) -> tuple:
        return ((self.name, "compression"), (f"{self.name}_port", "orifices"))

    @property
    def events(self) -> tuple:
        return tuple(f"{self.name}_kink{i}" for i in range(len(self.gaps)))

    @property
    def ports(self) -> dict:
        return {} if self.port == NO_PORT else {self.port: self.name}

    def records(self, slots, oil) -> list:
        """The cushion's node, its port (:mod:`.kinds.cushion`) on the segment of ``g`` the mode's
        flags give, and a watched level (:mod:`.kinds.level`) at each point."""
        n = slots.node(self.name, self)
        intercept, slope = opening_segment(self.gaps, self.openings, [slots.flags[e] for e in self.events])
        out = [record(NODE, id=n, volume=self.volume, beta=oil.bulk_modulus,
                      compression_energy=slots.energy[self.name]),
               record(CUSHION, source=n, target=slots.node(self.target, self), coefficient=self.coefficient,
                      ptr2=oil.transition_pressure ** 2, intercept=intercept, slope=slope,
                      energy=slots.loss(f"{self.name}_port"))]
        for e, y in zip(self.events, self.gaps, strict=True):
            out.append(record(LEVEL, gap=1, level=y, on=slots.flags[e], event=slots.events[e]))
        return out
