r"""The oil circuit's energy account over a run or an orbit (theory §11): each term the sum of its
energy integrands, in the order the circuit's layout gives them, and the residual that closes it."""

from __future__ import annotations

import numpy as np

from .layout import PRESET

__all__ = ["CircuitEnergy"]


class CircuitEnergy(dict):
    r"""The oil circuit's energy account over a run or an orbit (theory §11), a dict of floats in the
    model's energy unit :math:`m L^2 \Omega^2` (eq. 2): ``pump`` (the pump's work,
    :math:`\int p_s Q_p \, dt`), ``piston`` (the oil's work on the piston, :math:`\int F (-w') \, dt`),
    ``orifices`` (:math:`\int Q \Delta p \, dt` of every opening), ``tank``
    (:math:`\int p_t Q \, dt` to the tank), ``compression`` (:math:`\int (V p / \beta) p' \, dt` of
    the three oil volumes), ``accumulator`` (:math:`\int p_s C_a p_s' \, dt`), and ``residual``
    (the pump's work less all the others: 0 to the integrator's tolerance) and ``relative_residual``
    (over the pump's work)."""

    @classmethod
    def from_terms(cls, E, layout=None) -> CircuitEnergy:
        """The account from the energy integrands' integrals.

        Parameters
        ----------
        E : array_like, shape (n_energy,)
            The integrals in the order of ``layout.energies`` (model energy units).
        layout : CircuitLayout, optional
            Default: the preset's, :data:`~impactbar.drives.circuit.layout.PRESET`
            (:attr:`HydraulicCircuitDrive.layout`); each integrand added to its term
            (``layout.terms``: an extra part's compression and gas work too).

        Returns
        -------
        CircuitEnergy
        """
        E = np.asarray(E, dtype=float)
        layout = layout if layout is not None else PRESET
        at = layout.energy
        pump = float(E[at["pump"]])
        sums: dict = {}
        for k, term in enumerate(layout.terms):  # (each term's integrands in their order, one by one)
            sums[term] = E[k] if term not in sums else sums[term] + E[k]
        out = cls(pump=pump, piston=float(sums["piston"]), orifices=float(sums["orifices"]),
                  tank=float(sums["tank"]), compression=float(sums["compression"]),
                  accumulator=float(sums["accumulator"]))
        if "spool" in sums:  # (a spool valve's: its kinetic energy's change, stops' and damping's losses)
            out["spool"] = float(sums["spool"])
        out["residual"] = float(pump - np.sum(np.delete(E, at["pump"])))
        out["relative_residual"] = out["residual"] / max(abs(pump), 1e-300)
        return out
