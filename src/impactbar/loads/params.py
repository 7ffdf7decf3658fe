"""A load's parameters and records, read from its class's declaration (:class:`LoadTraits`):
:class:`LoadParameters`, the object :attr:`impactbar.Load.params` returns (the parameter protocol
of :mod:`impactbar.parameters`, the records of a sweep spec's ``[load]`` table)."""

from __future__ import annotations

from .._shared.parameters import Parameter

__all__ = ["LoadParameters"]


class LoadParameters:
    """The parameters of one load, as :attr:`impactbar.Load.params` gives them: its records
    (:meth:`parameter_table`), copies with some changed (:meth:`with_parameter`,
    :meth:`with_parameters`, :meth:`with_`) and its record (:meth:`record`), all from what its class
    declares in ``traits`` (:class:`~impactbar.loads.abilities.LoadTraits`).

    Parameters
    ----------
    load : Load

    Examples
    --------
    >>> from impactbar import CosineLoad
    >>> load = CosineLoad(0.3, 1.0)
    >>> [(p.name, p.value, p.continuable) for p in load.params.parameter_table()]
    [('p0', 0.3, True), ('pk', 1.0, True), ('k', 1, False)]
    >>> load.params.with_(pk=2.0)
    CosineLoad(p0=0.3, pk=2.0, k=1)
    >>> load.params.record()
    {'kind': 'cosine', 'p0': 0.3, 'pk': 1.0, 'k': 1}
    """

    __slots__ = ("_load",)

    def __init__(self, load):
        self._load = load

    def parameter_table(self) -> tuple[Parameter, ...]:
        """The load's numbers as parameter records (:func:`impactbar.parameters.parameters`): the
        scalar fields of its ``traits.parameters`` (their long names the descriptions, an integer
        dtype an integer parameter), continuable where named in ``continuation_parameters``, with
        the ranges of ``parameter_ranges``.

        Returns
        -------
        tuple of Parameter
        """
        load = self._load
        traits = load.traits
        out = []
        for f in traits.parameters:
            if f.per is not None:
                continue
            integer = f.dtype.startswith("i")
            value = getattr(load, f.name)
            out.append(Parameter(f.name, int(value) if integer else float(value), description=f.long_name,
                                 continuable=f.name in traits.continuation_parameters, integer=integer,
                                 **traits.parameter_ranges.get(f.name, {})))
        return tuple(out)

    def with_parameter(self, name: str, value):
        """A copy of the load with one of :meth:`parameter_table` changed (validated again by the
        constructor).

        Parameters
        ----------
        name : str
            One of the names of :meth:`parameter_table`.
        value : float or int
            Its new value (an int for an integer field).

        Returns
        -------
        Load

        Raises
        ------
        ValueError
            For a name that is not a parameter of this load, or a value out of its range.
        """
        return self.with_(**{name: value})

    def with_parameters(self, changes: dict):
        """A copy with several of :meth:`parameter_table` changed at once (:meth:`with_`, the result
        validated once)."""
        return self.with_(**changes)

    def with_(self, **changes):
        """A copy of the load with some of its ``traits.parameters`` changed (validated again by the
        constructor).

        Raises
        ------
        ValueError
            For a name that is not a parameter of this load, or a value out of its range.
        """
        load = self._load
        names = load.traits.parameters.names
        if not names or not all(k in names for k in changes):
            unknown = [k for k in changes if k not in names] or list(changes)
            raise ValueError(f"{unknown} not parameter(s) of {type(load).__name__}; it has {list(names)}")
        return type(load)(**{n: changes[n] if n in changes else getattr(load, n) for n in names})

    def record(self) -> dict:
        """The load as JSON-ready data, ``{"kind": ..., <each of its parameters>}`` (a sweep spec's
        ``[load]`` table); :func:`impactbar.loads.load_from_record` reads it back.

        Raises
        ------
        ValueError
            For a load that is not in the table :data:`~impactbar.loads.LOADS` (no ``kind``).
        """
        load = self._load
        traits = load.traits
        if not traits.kind:
            raise ValueError(f"a {type(load).__name__} has no kind: it is not in the table of loads")
        return {"kind": traits.kind, **traits.parameters.record(load)}
