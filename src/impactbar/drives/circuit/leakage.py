r"""Laminar leakage between two nodes of the circuit (theory §11, *Parts of a drill's circuit*): a
part of its own (:class:`~impactbar.drives.circuit.CircuitPart`), its equation in
:mod:`.kinds.leak`.

References
----------
Hopsan's component library, ``componentLibraries/defaultLibrary/Hydraulic``:
``Restrictors/HydraulicLaminarOrifice.hpp`` (``q = K_c (p_1 - p_2)``).
"""

from __future__ import annotations

from dataclasses import dataclass

from ._network import LEAK, record
from .composition import NamedPart, PartField

__all__ = ["LaminarLeak"]


def _check_names(part, *fields) -> None:
    for f in fields:
        if not isinstance(getattr(part, f), str) or not getattr(part, f):
            raise ValueError(f"{f} must be a non-empty string; got {getattr(part, f)!r}")


def _check_ends(part) -> None:
    """A part between two nodes: its ``source``, ``target`` and ``name`` strings, two nodes."""
    _check_names(part, "source", "target", "name")
    if part.source == part.target:
        raise ValueError(f"source and target must be two nodes; got {part.source!r} twice")


@dataclass(frozen=True)
class BetweenNodes(NamedPart):
    """A part between two nodes, ``source`` and ``target`` (its connections), its loss one energy
    integrand, ``name``, in the account's ``orifices`` term (the base of :class:`LaminarLeak` and
    :class:`~impactbar.drives.circuit.CheckValve`)."""

    connections = {"source": ("node", None), "target": ("node", None)}

    def __post_init__(self) -> None:
        _check_ends(self)
        super().__post_init__()

    @property
    def energies(self) -> tuple:
        """Its loss, in the term ``orifices``."""
        return ((self.name, "orifices"),)


@dataclass(frozen=True)
class LaminarLeak(BetweenNodes):
    r"""Laminar leakage from node ``source`` to node ``target``: ``q = G (p_source - p_target)``, a
    clearance's flow (the piston's, rear chamber to front; the spool's). Its loss
    :math:`\int G \Delta p^2 \, dt` is an energy integrand of its own, ``name``, in the account's
    ``orifices`` term. ``G = 0`` leaves the circuit as it is (to the bit where the loss is pooled into
    the ``orifices`` integrand: a subclass with ``energies = ()``). The kind ``"laminar_leak"`` of a
    configuration's ``[parts.<name>]`` table (``conductance`` in m^3/s/Pa, the relief coefficient's
    scale).

    Parameters
    ----------
    source, target : str
        The nodes it joins (the preset's ``front``, ``rear``, ``supply``, ``tank`` or another part's).
    conductance : float
        :math:`G \ge 0` (model units: the flow scale over the pressure scale, :mod:`.parts`); an annular
        gap of diameter ``D``, radial clearance ``c`` and length ``l`` in oil of viscosity ``mu`` has
        :math:`G = \pi D c^3 / (12 \mu l)` (SI: m^3 s^-1 Pa^-1).
    name : str, optional
        Its energy integrand's name and its parameter's prefix (``<name>.conductance``), an
        identifier.

    Raises
    ------
    ValueError
        A conductance out of range, a node name that is not a string or the same node twice, a name
        that is not an identifier.

    Examples
    --------
    >>> from dataclasses import replace
    >>> from impactbar.physical import circuit_preset
    >>> leak = LaminarLeak("rear", "front", conductance=0.01)
    >>> drive = replace(circuit_preset("circuit-drifter").drive(), extra_parts=(leak,))
    >>> drive.layout.energies[-1], drive.with_(**{"leak.conductance": 0.02}).value("leak.conductance")
    ('leak', 0.02)
    """

    source: str
    target: str
    conductance: float
    name: str = "leak"

    si_fields = (PartField("conductance", "m**3/s/Pa", "'1e-12 m^3/s/Pa'", "relief", low_open=False,
                           description="the laminar leakage's conductance"),)
    def records(self, slots, oil) -> list:
        """The leak's record (:mod:`.kinds.leak`)."""
        return [record(LEAK, source=slots.node(self.source, self), target=slots.node(self.target, self),
                       conductance=self.conductance, energy=slots.loss(self.name))]
