"""The compiled building blocks of the dynamics that the other packages build on: the interface
between the dynamics' private kernels (``_flight``: the closed-form flight; ``_crossing``: the
certified event search; ``_event_loop``; ``_load_flow``: the loads' flows and the admissibility
bounds; ``_tiers``: the first calls run while a child compiles) and the compiled code of the laws,
the drives, the loads and the orbit solvers, and the simulator's drivers. What another package uses
of those kernels it imports from here, by these names; the private modules behind them may change.

Every function here is a numba dispatcher (plain float arrays, the load and the modal basis as the
views of :mod:`impactbar.dynamics.compiled_views`), callable from Python and from compiled code alike.

- :data:`CACHE`: numba's ``cache=`` for every kernel of the package (``False`` where no cache folder
  is writable: compiled in memory).
- the flight: :data:`TWO_PI`, :func:`load_value` (the load ``p(t)``), :func:`piece_of` (the piece of
  a piecewise-constant load at ``t``), :func:`sort_head` (the ``n`` smallest entries first);
- the event loop: :func:`run_free` (flights and impacts of the free bar until ``t_end`` or
  ``max_imp`` impacts), :func:`run_free_rigid` (its twin for the rigid bar's fast search),
  :func:`find_crossing` (the certified search of ``h = 0``), :func:`propagate_many` (the modes at
  many times, called from Python) and :func:`propagate_views` (the same, called from compiled code),
  with their statuses (:data:`NONE`, :data:`CROSS`, :data:`FAIL`; the event loop's :data:`END`,
  :data:`MAXIMP`, :data:`CHATTER`, :data:`CONTACT`, :data:`FULL`, :data:`FAILED`);
- the loads' flows and the admissibility bounds: :func:`fourier_flow`, :func:`piecewise_flow`,
  :func:`fourier_column`, :func:`piecewise_column`, :func:`bound_column`,
  :func:`end_velocity_bound`;
- :func:`disable_tiers`: every kernel compiled in this process before its first call runs
  (``impactbar warmup``);
- :func:`interpreted_first`: a kernel's interpreted twin for its first calls in a process where
  numba holds no machine code of it, until they have cost a budget of CPU time.
"""

from ._crossing import CROSS as CROSS
from ._crossing import FAIL as FAIL
from ._crossing import NONE as NONE
from ._crossing import find_crossing as find_crossing
from ._event_loop import CHATTER as CHATTER
from ._event_loop import CONTACT as CONTACT
from ._event_loop import END as END
from ._event_loop import FAILED as FAILED
from ._event_loop import FULL as FULL
from ._event_loop import MAXIMP as MAXIMP
from ._event_loop import _propagate_many as propagate_views
from ._event_loop import propagate_many as propagate_many
from ._event_loop import run_free as run_free
from ._event_loop import run_free_rigid as run_free_rigid
from ._flight import CACHE as CACHE
from ._flight import TWO_PI as TWO_PI
from ._flight import load_value as load_value
from ._flight import piece_of as piece_of
from ._flight import sort_head as sort_head
from ._load_flow import bound_column as bound_column
from ._load_flow import end_velocity_bound as end_velocity_bound
from ._load_flow import fourier_column as fourier_column
from ._load_flow import fourier_flow as fourier_flow
from ._load_flow import piecewise_column as piecewise_column
from ._load_flow import piecewise_flow as piecewise_flow
from ._tiers import disable as disable_tiers
from ._tiers import interpreted_first as interpreted_first

__all__ = ["CACHE", "TWO_PI", "load_value", "piece_of", "sort_head", "bound_column", "end_velocity_bound",
           "fourier_column", "fourier_flow", "piecewise_column", "piecewise_flow", "CHATTER", "CONTACT",
           "CROSS", "END", "FAIL", "FAILED", "FULL", "MAXIMP", "NONE", "propagate_views", "find_crossing",
           "propagate_many", "run_free", "run_free_rigid", "disable_tiers", "interpreted_first"]
