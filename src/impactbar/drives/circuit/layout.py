r"""Where the oil circuit keeps each of its states and energy terms (theory §11): the layout that the
Python side reads by name (:attr:`HydraulicCircuitDrive.layout
<impactbar.drives.circuit.HydraulicCircuitDrive.layout>`), the compiled kernels (:mod:`._netgen`) by
number.

The integrated state of a flight is ``(q, q', z, E)``: the bar's ``M`` modal coordinates and their
rates, the circuit's states ``z`` (from ``2 M``) and its energy integrands ``E`` (from
``2 M + n_states``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

__all__ = ["CircuitLayout", "PRESET"]

#: the terms of the energy account (:class:`~impactbar.drives.circuit.CircuitEnergy`), and the
#: preset integrands' by name
_TERMS = ("pump", "piston", "orifices", "tank", "compression", "accumulator", "spool")
_PRESET_TERMS = {"pump": "pump", "piston": "piston", "orifices": "orifices", "tank": "tank",
                 "front": "compression", "rear": "compression", "supply": "compression", "gas": "accumulator"}


@dataclass(frozen=True)
class CircuitLayout:
    r"""The order of a circuit's states and energy terms.

    Parameters
    ----------
    states : tuple of str
        The states' names in the kernel's order (``"front"``, ``"rear"``, ``"supply"``: the pressures
        of those oil volumes; ``"spool"``: the valve's opening).
    state_names : tuple of str
        The same states' symbols (``"p_f"``, ...), in the same order: the keys of the histories.
    energies : tuple of str
        The energy integrands' names in the kernel's order (:class:`~impactbar.drives.circuit.CircuitEnergy`).
    terms : tuple of str, optional
        The term of the energy account each integrand adds to (``"pump"``, ``"piston"``,
        ``"orifices"``, ``"tank"``, ``"compression"``, ``"accumulator"``, ``"spool"``: the work on a
        spool valve's spool), in the same order; default: the preset's by name (``front``, ``rear``,
        ``supply``: ``compression``; ``gas``: ``accumulator``; the others their own).
    mechanical : tuple of str, optional
        The states that are not pressures (a spool's velocity): not watched for cavitation.

    Raises
    ------
    ValueError
        Names repeated, ``state_names`` not as many as ``states``, ``terms`` not one of the account's
        for each energy integrand.

    Examples
    --------
    >>> from impactbar.drives.circuit.layout import PRESET
    >>> PRESET["supply"], PRESET["p_s"], PRESET.n_states, PRESET.n_energy, PRESET.energy["gas"]
    (2, 2, 4, 8, 7)
    >>> PRESET.size(3)  # q, q' of 3 modes and the circuit's states
    10
    """

    states: tuple
    state_names: tuple
    energies: tuple
    terms: tuple = ()
    mechanical: tuple = ()

    def __post_init__(self) -> None:
        for name in ("states", "state_names", "energies"):
            value = tuple(getattr(self, name))
            if len(set(value)) != len(value) or not all(isinstance(x, str) for x in value):
                raise ValueError(f"{name} must be distinct names; got {value!r}")
            object.__setattr__(self, name, value)
        if len(self.state_names) != len(self.states):
            raise ValueError(f"state_names must name the {len(self.states)} states {self.states}; got "
                             f"{self.state_names!r}")
        terms = tuple(self.terms) if self.terms else tuple(_PRESET_TERMS.get(e) for e in self.energies)
        if len(terms) != len(self.energies) or not set(terms) <= set(_TERMS):
            raise ValueError(f"terms must give each of the energies {self.energies} one of {_TERMS}; got "
                             f"{self.terms!r}")
        object.__setattr__(self, "terms", terms)

    @property
    def n_states(self) -> int:
        """The number of the circuit's states."""
        return len(self.states)

    @property
    def n_energy(self) -> int:
        """The number of energy integrands."""
        return len(self.energies)

    @functools.cached_property
    def state(self) -> dict:
        """Each state's index in ``z``, by name and by symbol (``{"front": 0, "p_f": 0, ...}``)."""
        out = {name: i for i, name in enumerate(self.states)}
        out.update((name, i) for i, name in enumerate(self.state_names))
        return out

    @functools.cached_property
    def energy(self) -> dict:
        """Each energy integrand's index in ``E`` (``{"pump": 0, ...}``)."""
        return {name: i for i, name in enumerate(self.energies)}

    @property
    def supply(self) -> int:
        """The index of the supply pressure in ``z``."""
        return self["supply"]

    def __getitem__(self, name: str) -> int:
        """A state's index in ``z`` by name or symbol (:attr:`state`).

        Raises
        ------
        KeyError
            An unknown name (the known ones listed).
        """
        try:
            return self.state[name]
        except KeyError:
            raise KeyError(f"the circuit has no state {name!r}: one of {self.states + self.state_names}") \
                from None

    def size(self, M: int) -> int:
        """The integrated state's size without the energies.

        Parameters
        ----------
        M : int
            The bar's modal coordinates (``n_modes + 1``).

        Returns
        -------
        int
            ``2 M + n_states``: ``q``, ``q'`` and the circuit's states; the energies start there.
        """
        return 2 * M + self.n_states


#: The preset circuit's layout (that of its network's generated kernel, :mod:`._netgen`): ``z = (p_f,
#: p_r, p_s, x_v)``, the energy integrands of :class:`~impactbar.drives.circuit.CircuitEnergy` (the
#: compression work split by volume: ``front``, ``rear``, ``supply``).
PRESET = CircuitLayout(states=("front", "rear", "supply", "spool"), state_names=("p_f", "p_r", "p_s", "x_v"),
                       energies=("pump", "piston", "orifices", "tank", "front", "rear", "supply", "gas"))
