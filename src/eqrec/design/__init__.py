"""Design methods, built on the rooms below (systems, arrivals, lp, bounds, estimators): each builds an LP (or
NLP), solves it with a solver of the registry, reads the gains and certifies them from the gains alone.

One subpackage per engine:

:mod:`~eqrec.design.prefix`
    The prefix-tree LP of Theorem 3 of the prefix-based paper, and the time-based comparison design.
:mod:`~eqrec.design.classes`
    The class engine: independent LPs per (time, available data) class, on every core or a Dask cluster, and
    μ1 free (:mod:`~eqrec.design.classes.mu1_min`: the smallest feasible μ1 in closed form).
:mod:`~eqrec.design.delay`
    The delayed-data paper's designs (Theorem 1 / Proposition 1), μ1 fixed or free, and its IPOPT route.
:mod:`~eqrec.design.augmented`
    The state-augmented estimator: model, what runs, the fixed-``L`` LPs of a word (P2) and of a prefix tree
    (P3), IPOPT, design.

What every engine shares:

:mod:`~eqrec.design.inputs`
    What the design entries take, checked: typed word lists (:func:`~eqrec.design.inputs.missing_words`,
    :func:`~eqrec.design.inputs.delay_words`), languages, the system, ``μ1``, the solver.
:mod:`~eqrec.design.cost`
    The delayed-data paper's cost ``J``, from node levels, class levels or a certificate.
:mod:`~eqrec.design.observers`
    Observer gains by pole placement.
:mod:`~eqrec.design.weighted`
    Per-state weights of the bound: the design on ``z = W x`` and its estimator in the original state.
:mod:`~eqrec.design.result`, :mod:`~eqrec.design.report`
    :class:`~eqrec.design.result.Design`, what every design returns, and how to read it (tables, JSON).
:mod:`~eqrec.design.saved`
    A design JSON of ``eqrec design --out`` read back into a :class:`~eqrec.design.result.Design`
    (:func:`~eqrec.design.saved.load_design`).
"""
