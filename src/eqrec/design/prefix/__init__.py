"""The prefix-based engine (P1): the tree LP of Theorem 3 and the time-based comparison design.

:mod:`~eqrec.design.prefix.design`
    The entry point :func:`~eqrec.design.prefix.design.design_prefix` (solve, read, certify).
:mod:`~eqrec.design.prefix.tree_lp`
    The tree LP of Theorem 3 of the prefix-based paper: build and read.
:mod:`~eqrec.design.prefix.time_based`
    One gain per time step (the authors' earlier work, ref. [10] of the prefix-based paper).
"""
