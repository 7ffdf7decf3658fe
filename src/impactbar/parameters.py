"""One parameter protocol for every part of a problem (the bar, its impact law, a load, a drive): each
part declares its parameters once, as :class:`Parameter` records with a dotted name, value, unit,
bounds, description and whether the problem is smooth in it; the functions here read and change them
on a ``(model, forcing)`` pair, with no case for any particular part. Continuation, sweeps and the
command line reach parameters through them alone.

Examples
--------
>>> from impactbar import BarModel, CosineLoad
>>> from impactbar.parameters import parameters, with_parameter
>>> model, load = BarModel(s=10.0, d=0.3, R=0.5, n_modes=4), CosineLoad(0.3, 1.0)
>>> [name for name, p in parameters(model, load).items() if p.continuable]
['s', 'd', 'R', 'p0', 'pk']
>>> with_parameter(model, load, "pk", 1.5)[1]
CosineLoad(p0=0.3, pk=1.5, k=1)
"""

from ._shared.parameters import Parameter as Parameter
from ._shared.parameters import check_continuable as check_continuable
from ._shared.parameters import parameter_value as parameter_value
from ._shared.parameters import parameters as parameters
from ._shared.parameters import with_parameter as with_parameter
from ._shared.parameters import with_parameters as with_parameters

__all__ = ["Parameter", "parameters", "parameter_value", "with_parameter", "with_parameters",
           "check_continuable"]
