"""Several parameters of a rod-rock law changed at once (:meth:`~impactbar.RodRock.with_parameters`):
the rock's stiffnesses, the segments' lengths and the law's own fields gathered, then one copy
validated once, whatever the order of the changes."""

from __future__ import annotations

import dataclasses
import re

from ..._shared.parameters import Parameter

__all__ = ["OWN", "changed"]

_SEGMENT = re.compile(r"segment(\d+)\.length")

#: The law's own continuation parameters, declared once, in its units (theory §4d): the rock's
#: loading and unloading stiffnesses (``rock.k_u`` at least the law's ``rock.k``: its records'
#: lower bound), the bit's mass and the feed force; each segment's length (``"segment<i>.length"``)
#: follows them. The law's ``parameters``, its records and the names it takes are views of it.
OWN = (Parameter("rock.k", None, low=0.0, low_open=True, description="rock loading stiffness"),
       Parameter("rock.k_u", None, description="rock unloading stiffness"),
       Parameter("bit_mass", None, low=0.0, description="bit mass (piston masses)"),
       Parameter("feed", None, low=0.0, description="feed force"))
_NAMES = tuple(p.name for p in OWN)


def changed(law, changes: dict):
    """``law`` with ``changes`` (name to value: ``"rock.k"``, ``"segment0.length"``, ``"feed"``, ...)
    applied together, each name checked by the law's ``_check_parameter``.

    Examples
    --------
    >>> from impactbar import BilinearRock, RodRock, RodSegment
    >>> law = RodRock(segments=[RodSegment(length=2.0, impedance=2.0)],
    ...               rock=BilinearRock(k=20.0, k_u=200.0))
    >>> changed(law, {"rock.k": 400.0, "rock.k_u": 800.0}).rock
    BilinearRock(k=400.0, k_u=800.0)
    """
    rock, segs, own = {}, list(law.segments), {}
    for name, value in changes.items():
        law._check_parameter(name)
        match = _SEGMENT.fullmatch(name)
        if name.startswith("rock."):
            rock[name[5:]] = value
        elif match:
            i = int(match.group(1))
            segs[i] = dataclasses.replace(segs[i], length=value)
        else:
            own[name] = value
    if rock:
        own["rock"] = dataclasses.replace(law.rock, **rock)
    if segs != list(law.segments):
        own["segments"] = segs
    return dataclasses.replace(law, **own)
