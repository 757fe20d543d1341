"""Linear programs: the sparse LP model (build, solve and read as separate steps), the solver registry, the
robust counterparts of box-uncertain rows, and independent solves on every core or a Dask cluster.

:mod:`~eqrec.lp.model`
    The LP model and its builder; solving and reading are separate steps.
:mod:`~eqrec.lp.solvers`
    The solver registry (HiGHS, Clarabel, SciPy, IPOPT): one list of names, one entry point, one status table.
:mod:`~eqrec.lp.box_simplex`
    Small dense box LPs with many objectives (interval hulls): a compiled dual simplex, or one HiGHS model.
:mod:`~eqrec.lp.robust`
    Robust counterparts of ``|G δ + c| <= μ`` over a box, as LP rows.
:mod:`~eqrec.lp.parallel`
    Independent tasks on every core, or on a Dask cluster, through joblib.
"""
