"""The state-augmented engine: one model for the augmented paper (P2, Theorem 2) and the delayed-data
paper's form (4).

:mod:`~eqrec.design.augmented.model`
    The model of the state-augmented estimator (modes, gains, arrival indicators).
:mod:`~eqrec.design.augmented.runtime`
    The conversions to and from gain schedules and the error maps of the running estimator (which is
    :class:`eqrec.estimators.augmented.AugmentedEstimator`).
:mod:`~eqrec.design.augmented.word_lp`
    The LP of one missing-data word at fixed ``L`` and ``s0`` (P2 Remark 1).
:mod:`~eqrec.design.augmented.sweep`
    That LP over a list of pole-placement gains, warm-started along runs of neighbouring points (P2 Fig. 3).
:mod:`~eqrec.design.augmented.tree_lp`
    The LP with gains per event prefix of a delay language (P3 form (4)).
:mod:`~eqrec.design.augmented.nlp`
    ``L`` and ``s0`` free (P2 Proposition 1), by IPOPT through CasADi.
:mod:`~eqrec.design.augmented.guarantee`
    The guarantee of the running estimator among the optima of P2's LP (the masked-gain reading), an LP.
:mod:`~eqrec.design.augmented.design`
    The entry point :func:`~eqrec.design.augmented.design.design_augmented`.
"""
