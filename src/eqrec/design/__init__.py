"""Design methods, built on :mod:`eqrec.core`: each builds an LP (or NLP), solves it with a solver of the
registry, reads the gains and certifies them from the gains alone.

:mod:`~eqrec.design.time_based`
    One gain per time step (the prefix-based paper's comparison estimator).
:mod:`~eqrec.design.prefix`
    The prefix-tree LP of Theorem 3 of the prefix-based paper (engine ``"tree"``).
:mod:`~eqrec.design.classes`, :mod:`~eqrec.design.class_lp`, :mod:`~eqrec.design.class_gains`
    The class engine: the separation theorem and the design (solve, certify); the block LP of every
    (time, available data) class and state row (build, read); what its gains ``K`` give (certificate, node gains).
:mod:`~eqrec.design.mu1_min`
    μ1 free: the μ1-free theorem, the smallest feasible μ1 in closed form (Charnes–Cooper), certified.
:mod:`~eqrec.design.cost`
    The delayed-data paper's cost ``J``, from node levels, class levels or a certificate.
:mod:`~eqrec.design.delay`
    The delayed-data paper's designs (Theorem 1 / Proposition 1), μ1 fixed or free.
:mod:`~eqrec.design.delay_ipopt`
    The delayed-data paper's own μ1-free route: IPOPT on the bilinear problem (10).
:mod:`~eqrec.design.augmented_model`, :mod:`~eqrec.design.augmented_runtime`, :mod:`~eqrec.design.augmented_lp`,
:mod:`~eqrec.design.augmented_tree_lp`, :mod:`~eqrec.design.augmented_nlp`, :mod:`~eqrec.design.augmented`
    The state-augmented estimator, one model for the augmented paper (Theorem 2) and the delayed-data
    paper's form (4): model, what runs (conversions, runtime), the fixed-``L`` LP of one word (P2) and of a
    prefix tree (P3), IPOPT, design.
:mod:`~eqrec.design.augmented_guarantee`
    A P2 reading analysis: the best guarantee as run among a design reading's optima.
:mod:`~eqrec.design.observers`
    Observer gains by pole placement.
:mod:`~eqrec.design.sweeps`, :mod:`~eqrec.design.scale_sweep`
    Sweeps over levels, poles and language sizes.
:mod:`~eqrec.design.inputs`
    What the design entries take, checked: typed word lists (:func:`~eqrec.design.inputs.missing_words`,
    :func:`~eqrec.design.inputs.delay_words`), languages, the system, ``μ1``, the solver.
:mod:`~eqrec.design.weighted`
    Per-state weights of the bound: the design on ``z = W x`` and its estimator in the original state.
:mod:`~eqrec.design.result`, :mod:`~eqrec.design.report`
    :class:`~eqrec.design.result.Design`, what every design returns, and how to read it (tables, JSON).
"""
