r"""How the whole-drifter optimiser's search (:func:`~impactbar.physical.optimize_drifter`) scores a
design without a one-impact orbit: as the far side of a border, located from the sensitivities of the
nearest design that has one, not as a penalty (theory §11, "Optimising a drifter").

A design :math:`u_f` (the variables scaled to :math:`[0, 1]`) where the orbit is not found is scored
from the nearest design :math:`u_s` evaluated with an orbit (one continued along
:class:`~impactbar.physical.optimize_cache.OrbitChain`, or a multistart sample's, whose gradient then
starts from a fresh orbit) by that design's first-order model, the
implicit function theorem's gradients of its figures
(:func:`~impactbar.physical.sensitivity.tangent_derivatives`, one gradient per design, kept):

.. math::

   f(u_f) = f_s + \nabla f_s \cdot d, \qquad c_i(u_f) = c_{i,s} + \nabla c_{i,s} \cdot d,
   \qquad d = u_f - u_s,

and by one constraint more, "the one-impact orbit exists", :math:`e(u) \ge 0`. At a design with an
orbit :math:`e` is its existence margin, the largest Floquet multiplier's modulus to the unit circle,
:math:`1 - |\mu|_{max}` (scaled as the ``max_multiplier`` constraint's margin, whose scale is 1): the
orbit is lost where a multiplier leaves the unit circle (a fold, a period
doubling: the period-2 motions the failed designs settle into), as a design map's border is located,
where its margin extrapolates to zero
(:meth:`~impactbar.physical.sensitivity.OperatingPointSensitivities.distance_to_border`). At the
failed design the border lies on the segment
from :math:`u_s` at :math:`t^* = -e_s / (\nabla e_s \cdot d)` where that is in :math:`(0, 1)`, and
:math:`e(u_f) = e_s + \nabla e_s \cdot d = e_s (1 - 1/t^*) < 0`, the margin's own extrapolation;
where it is not (the margin does not reach zero before :math:`u_f`: the orbit ends otherwise, at a
grazing re-contact, cavitation, ...), the border is taken at a distance :math:`\rho` from the
success, half that of the nearest failed design scored from it (:math:`\rho \le |d|/2`, one radius
per success: the least of its failures' so far), :math:`t^* = \rho / |d|`, and
:math:`e(u_f) = e_s (1 - |d| / \rho) \le -e_s`: the linear function of the distance that is
:math:`e_s` at the success and zero at the border, falling on past it, so that a search's linear
model of the constraint points back across the border. The model costs a failed design no orbit
and at most one gradient, its nearest success's, computed once for all the failures that lie
nearest it (and kept with SLSQP's in the cache file).

The multistart's polish (SLSQP, :mod:`~impactbar.physical.optimize_polish`) scores a failed design
by the same model, built from the gradients it computes itself (the step refined where it meets a
border; the record says which), and is given the model's gradients with it: the nearest success's
for the objective and the margins, and for the existence constraint :func:`existence_gradient`, the
model's own (exact; the model is first order in the step). The existence margin is the multiplier's
alone: at the documented problem's designs without an orbit, none of the other margins the orbit
reports for its borders (the impact velocity, the gap's rate at the valve's switch, the circuit's
pressure borders) goes to zero where the orbit ends (the docs' page, "Optimising a drifter").
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

__all__ = ["EXISTENCE", "BorderScore", "border_score", "existence_gradient", "existence_margin"]

#: The name of the constraint the border model adds: the one-impact orbit exists.
EXISTENCE = "one_impact_orbit"


class BorderScore(NamedTuple):
    """A failed design's scores by the border model: the objective and the constraints' scaled margins
    extrapolated, the existence constraint, the border's location on the segment from the nearest
    success (``t``, in ``[0, 1)``), how it was located (``"margin"``: where the existence margin
    extrapolates to zero; ``"radius"``: at the success's border radius) and that radius (``nan`` where
    the margin located it)."""

    objective: float
    margins: np.ndarray
    exists: float
    t: float
    located: str
    radius: float

    def as_record(self) -> dict:
        """The scores as a failed design's record keeps them (``border``, beside ``nearest``).

        Returns
        -------
        dict
            ``objective``, ``margins`` (a list), the existence constraint under :data:`EXISTENCE`,
            ``t``, ``located`` and, only where located at the radius, ``radius``: plain JSON data.

        Examples
        --------
        >>> s = BorderScore(3.0, np.array([0.4]), -0.6, 0.25, "margin", math.nan)
        >>> sorted(s.as_record())
        ['located', 'margins', 'objective', 'one_impact_orbit', 't']
        >>> r = BorderScore.from_record(s.as_record())
        >>> r.objective, r.margins.tolist(), r.exists, r.t, r.located, math.isnan(r.radius)
        (3.0, [0.4], -0.6, 0.25, 'margin', True)
        """
        return {"objective": self.objective, "margins": self.margins.tolist(), EXISTENCE: self.exists,
                "t": self.t, "located": self.located,
                **({"radius": self.radius} if self.located == "radius" else {})}

    @classmethod
    def from_record(cls, record: dict) -> BorderScore:
        """The scores a failed design's record keeps (:meth:`as_record`'s).

        Parameters
        ----------
        record : dict
            The record's ``border``.

        Returns
        -------
        BorderScore
            ``radius`` ``nan`` where the record has none (located by the margin).

        Raises
        ------
        KeyError
            A score missing from ``record``.
        """
        return cls(record["objective"], np.asarray(record["margins"], dtype=float), record[EXISTENCE],
                   record["t"], record["located"], record.get("radius", math.nan))


def existence_margin(record: dict, scale: float) -> float:
    """A design's existence margin: its largest Floquet multiplier's modulus to the unit circle over
    ``scale`` (the ``max_multiplier`` constraint's scale; theory §11, "Optimising a drifter").

    Parameters
    ----------
    record : dict
        A design's record with an orbit (its ``figures`` give ``max_multiplier``).
    scale : float
        The scale of the multiplier's margin (positive).

    Returns
    -------
    float
        Positive where the orbit is stable, 0 on the unit circle.

    Raises
    ------
    ValueError
        ``scale`` not positive.

    Examples
    --------
    >>> round(existence_margin({"figures": {"max_multiplier": 0.81}}, 0.95), 12)
    0.2
    """
    if not (isinstance(scale, int | float) and scale > 0.0):
        raise ValueError(f"scale must be a positive number; got {scale!r}")
    return (1.0 - record["figures"]["max_multiplier"]) / scale


def border_score(u, near_u, objective: float, margins, exists: float, d_objective, d_margins,
                 d_exists=None, radius: float = math.inf) -> BorderScore:
    r"""A failed design's scores from its nearest success's first-order model (module docstring).

    Parameters
    ----------
    u, near_u : array_like, shape (n,)
        The failed design and its nearest success, scaled variables.
    objective : float
        The success's objective (as the search scores it).
    margins : array_like, shape (m,)
        The success's constraints' scaled margins.
    exists : float
        The success's existence margin (:func:`existence_margin`).
    d_objective : array_like, shape (n,)
        The objective's gradient at the success in the scaled variables.
    d_margins : array_like, shape (m, n)
        The margins' gradients.
    d_exists : array_like, shape (n,), optional
        The existence margin's gradient; ``None`` where not known: the border at the radius.
    radius : float
        The success's border radius so far (scaled; ``inf``: none): where the margin does not locate
        the border, it is taken at ``min(radius, |d| / 2)`` from the success (positive).

    Returns
    -------
    BorderScore

    Raises
    ------
    ValueError
        ``u`` and ``near_u`` the same design, shapes that do not agree, or ``radius`` not positive.

    Examples
    --------
    A margin 0.2 falling by 0.8 per unit of the first variable: the border a quarter along a step of
    1, the margin there extrapolated to -0.6; the objective and a constraint extrapolated:

    >>> s = border_score([1.0, 0.0], [0.0, 0.0], 2.0, [0.5], 0.2, [1.0, 0.0], [[-0.1, 0.0]], [-0.8, 0.0])
    >>> s.objective, s.margins.tolist(), round(s.exists, 12), s.t, s.located
    (3.0, [0.4], -0.6, 0.25, 'margin')

    Without the margin's gradient, a first failure at 1 puts the border at 0.5; one at 2 after it
    lies four radii out:

    >>> border_score([0.0, 2.0], [0.0, 0.0], 2.0, [0.5], 0.2, [0.0, 0.0], [[0.0, 0.0]], radius=0.5)[2:]
    (-0.6000000000000001, 0.25, 'radius', 0.5)
    """
    u, near_u = np.asarray(u, dtype=float), np.asarray(near_u, dtype=float)
    d = u - near_u
    if u.shape != near_u.shape or not np.any(d):
        raise ValueError("u and near_u must be two different designs of the same shape")
    if not radius > 0.0:
        raise ValueError(f"radius must be positive (inf: none yet); got {radius!r}")
    d_margins = np.asarray(d_margins, dtype=float).reshape(len(np.atleast_1d(margins)), d.size)
    obj = float(objective + np.dot(d_objective, d))
    mar = np.asarray(margins, dtype=float) + d_margins @ d
    slope = 0.0 if d_exists is None else float(np.dot(d_exists, d))
    if exists > 0.0 and slope < 0.0 and -exists / slope < 1.0:  # (the margin's zero on the segment)
        return BorderScore(obj, mar, exists + slope, -exists / slope, "margin", math.nan)
    if exists <= 0.0:  # (the success itself past the unit circle: its margin, less where it falls on)
        return BorderScore(obj, mar, exists + min(slope, 0.0) - math.ulp(1.0), 0.0, "margin", math.nan)
    length = float(np.linalg.norm(d))
    rho = min(radius, 0.5 * length)
    return BorderScore(obj, mar, exists * (1.0 - length / rho), rho / length, "radius", rho)


def existence_gradient(u, near_u, score: BorderScore, exists: float, d_exists=None) -> np.ndarray:
    r"""The gradient of a failed design's existence constraint as :func:`border_score` scores it, in the
    scaled variables, the nearest success :math:`u_s`, its margin :math:`e_s` and the border radius
    :math:`\rho` held (the model's own gradient, exact; the model is first order in the step): where
    the margin locates the border, :math:`\nabla e_s`; at the radius,
    :math:`-e_s\, d / (|d|\, \rho)` (:math:`e_s (1 - |d|/\rho)` differentiated); for a success past
    the unit circle, :math:`\nabla e_s` where the margin falls along the step, else 0 (theory §11,
    "Optimising a drifter").

    Parameters
    ----------
    u, near_u : array_like, shape (n,)
        The failed design and its nearest success, scaled variables.
    score : BorderScore
        :func:`border_score`'s at ``u`` from ``near_u``.
    exists : float
        The success's existence margin.
    d_exists : array_like, shape (n,), optional
        Its gradient (``None``: not known, as :func:`border_score` was given).

    Returns
    -------
    numpy.ndarray, shape (n,)
        The constraint's gradient in the scaled variables.

    Raises
    ------
    ValueError
        ``u`` and ``near_u`` the same design, or ``score`` located neither way.

    Examples
    --------
    At the radius 0.5 of a step of 1 along the first variable, the margin 0.2 falls by 0.4 per unit:

    >>> s = border_score([1.0, 0.0], [0.0, 0.0], 2.0, [0.5], 0.2, [1.0, 0.0], [[-0.1, 0.0]])
    >>> existence_gradient([1.0, 0.0], [0.0, 0.0], s, 0.2).tolist()
    [-0.4, -0.0]
    """
    u, near_u = np.asarray(u, dtype=float), np.asarray(near_u, dtype=float)
    d = u - near_u
    if u.shape != near_u.shape or not np.any(d):
        raise ValueError("u and near_u must be two different designs of the same shape")
    grad = np.zeros(d.size) if d_exists is None else np.asarray(d_exists, dtype=float).reshape(d.size)
    if score.located == "radius":
        return -exists * d / (float(np.linalg.norm(d)) * score.radius)
    if score.located != "margin":
        raise ValueError(f"score.located must be 'margin' or 'radius'; got {score.located!r}")
    if exists <= 0.0 and not float(np.dot(grad, d)) < 0.0:
        return np.zeros(d.size)
    return grad
