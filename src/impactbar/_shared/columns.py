"""The columns of the small tables the package's modules hand each other, by name (private).

A table whose columns are different quantities is read by its columns' names, never by their
numbers (compiled kernels read these module-level integers as compile-time constants). The tables
of one module alone name their columns in that module (the exact blow's in
:mod:`impactbar.laws.rodrock._records`).
"""

#: an interval's lower end, a row ``[lo, hi]`` of a table of intervals (a contact's or a sticking
#: interval's start, a bracket's lower end)
IV_LO = 0
#: its upper end (a contact's or a sticking interval's end)
IV_HI = 1
