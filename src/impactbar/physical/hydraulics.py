r"""A circuit part's coefficient from its datasheet (theory §11): the flow a valve, an orifice or a
relief valve passes at a stated pressure drop, turned into the coefficient of the law the circuit
uses for it.

The circuit's orifices and the main valve's openings follow the turbulent orifice law
:math:`Q = K \sqrt{\Delta p}` (smoothed below the transition pressure :math:`p_{tr}` as
:math:`Q = K \Delta p\,(\Delta p^2 + p_{tr}^2)^{-1/4}`, theory §11), with
:math:`K = C_q A \sqrt{2/\rho}` for a sharp-edged opening of area :math:`A` and discharge
coefficient :math:`C_q` in oil of density :math:`\rho`. A datasheet gives a nominal flow
:math:`Q_n` at a pressure drop :math:`\Delta p_n` ("60 L/min at 5 bar per control edge"), so
:math:`K = Q_n / \sqrt{\Delta p_n}`, or, to pass exactly :math:`Q_n` at :math:`\Delta p_n` under the
smoothed law, :math:`K = Q_n (\Delta p_n^2 + p_{tr}^2)^{1/4} / \Delta p_n`. The relief valve's flow
is linear in the pressure over its setting, :math:`Q = K_{rel} (p_s - p_{rel})`, so a datasheet's
flow at an override pressure gives :math:`K_{rel} = Q_n / \Delta p_n`.

References
----------
H. E. Merritt, *Hydraulic Control Systems*, Wiley (1967), chapter 3 (the orifice equation); Hopsan's
``HydraulicTurbulentOrifice`` (:math:`Q = C_q A \sqrt{2 / \rho} \sqrt{\Delta p}`).
"""

from __future__ import annotations

import math

from .units import to_si

__all__ = ["flow_coefficient"]

#: the laws a part's coefficient may be for: the orifice's square root, the relief's linear law
LAWS = ("turbulent", "linear")


def flow_coefficient(flow, pressure_drop, *, law: str = "turbulent", transition_pressure=None) -> float:
    r"""The flow coefficient of a circuit part from a datasheet's nominal flow at a pressure drop.

    Parameters
    ----------
    flow : str or pint.Quantity
        The nominal flow :math:`Q_n`, a volume per time (``"60 L/min"``), ``> 0``.
    pressure_drop : str or pint.Quantity
        The pressure drop :math:`\Delta p_n` at which the part passes it (``"5 bar"``), ``> 0``;
        for the relief valve, the pressure over its setting (the override).
    law : {"turbulent", "linear"}, optional
        ``"turbulent"`` (default): an orifice or a valve's opening, :math:`Q = K \sqrt{\Delta p}`,
        for the config keys ``valve.flow_coefficient`` and ``supply.front_flow_coefficient``;
        ``"linear"``: the relief valve, :math:`Q = K_{rel}\,\Delta p`, for
        ``supply.relief_coefficient``.
    transition_pressure : str or pint.Quantity, optional
        With ``law="turbulent"``, the oil's ``oil.transition_pressure`` :math:`p_{tr} \ge 0`: the
        coefficient then passes exactly :math:`Q_n` at :math:`\Delta p_n` under the circuit's
        smoothed law (theory §11). Default: the plain square-root law.

    Returns
    -------
    float
        :math:`K` in m^3/s/Pa^0.5 (turbulent) or :math:`K_{rel}` in m^3/s/Pa (linear), SI.

    Raises
    ------
    ValueError
        A value without its unit or of the wrong dimension, not positive, or an unknown ``law``
        (each named), or a ``transition_pressure`` with ``law="linear"``.

    Examples
    --------
    A valve edge passing 60 L/min at 5 bar, written as the config's ``valve.flow_coefficient``:

    >>> K = flow_coefficient("60 L/min", "5 bar")
    >>> f"{K:.4e} m^3/s/Pa^0.5"
    '1.4142e-06 m^3/s/Pa^0.5'

    A relief valve passing 100 L/min at 2 MPa over its setting:

    >>> f"{flow_coefficient('100 L/min', '2 MPa', law='linear'):.4e} m^3/s/Pa"
    '8.3333e-10 m^3/s/Pa'
    """
    if law not in LAWS:
        raise ValueError(f"law must be one of {LAWS}; got {law!r}")
    Q = to_si("flow", flow, "m**3/s", "'60 L/min'", what="a flow (volume per time)")
    dp = to_si("pressure_drop", pressure_drop, "Pa", "'5 bar'", what="a pressure")
    if not Q > 0.0:
        raise ValueError(f"flow must be positive; got {flow!r}")
    if not dp > 0.0:
        raise ValueError(f"pressure_drop must be positive; got {pressure_drop!r}")
    if law == "linear":
        if transition_pressure is not None:
            raise ValueError("transition_pressure is for law='turbulent' (the smoothed orifice law); the "
                             "relief valve's law is linear")
        return Q / dp
    if transition_pressure is None:
        return Q / math.sqrt(dp)
    ptr = to_si("transition_pressure", transition_pressure, "Pa", "'0.5 MPa'", what="a pressure")
    if not ptr >= 0.0:
        raise ValueError(f"transition_pressure must be >= 0; got {transition_pressure!r}")
    return Q * (dp * dp + ptr * ptr) ** 0.25 / dp
