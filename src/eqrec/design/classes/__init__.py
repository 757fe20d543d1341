"""The class engine: every prefix-tree design as independent LPs per (time, available data) class.

:mod:`~eqrec.design.classes.engine`
    The separation theorem and the design (solve, certify).
:mod:`~eqrec.design.classes.block_lp`
    One block LP holding the LP of every class and state row (build, read).
:mod:`~eqrec.design.classes.blocks`
    The class LPs one class at a time, in batches, on every core or a Dask cluster.
:mod:`~eqrec.design.classes.chains`
    The large class LPs of a chain of classes (every maximum delay 1 design) in state-space form, warm-started
    from one class to the next.
:mod:`~eqrec.design.classes.gains`
    What the class gains ``K`` give: their exact worst case and the node gains of the recursive estimator.
:mod:`~eqrec.design.classes.mu1_min`
    μ1 free: the μ1-free theorem, the smallest feasible μ1 in closed form (Charnes–Cooper), certified; the
    engine asks it where ``μ1`` is infeasible.
"""
