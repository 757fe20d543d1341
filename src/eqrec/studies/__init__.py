"""The studies: one per paper, orchestration, values and figures only (the mathematics is in
:mod:`eqrec.core`, :mod:`eqrec.design`, :mod:`eqrec.lmv` and :mod:`eqrec.filters`).

Each Snakemake rule runs one *step* ``step(cfg, inputs, outputs, wildcards)``; a module that defines steps
lists them in its ``STEPS`` table.

:mod:`~eqrec.studies.p1`, :mod:`~eqrec.studies.p2`, :mod:`~eqrec.studies.p3`, :mod:`~eqrec.studies.p4`
    The computing steps of each paper (with :mod:`~eqrec.studies.p2_sweeps`, :mod:`~eqrec.studies.p3_strategy`,
    :mod:`~eqrec.studies.p3_scale`); ``pN_figures`` draws, ``pN_values`` states our value of every published
    number with its evidence, ``pN_claims`` picks the wording of each claim row (a function per claim id).
:mod:`~eqrec.studies.claims`, :mod:`~eqrec.studies.claims_file`, :mod:`~eqrec.studies.claim_reasons`
    The claims table (``results/claims.csv``, ``results/REPRODUCTION.md``) from ``config/claims.yaml``.
:mod:`~eqrec.studies.notebooks`
    The executed notebooks.
:mod:`~eqrec.studies.harness`, :mod:`~eqrec.studies.steps`, :mod:`~eqrec.studies.imports`
    Running one step; the registry of steps; each rule's code inputs (read with :mod:`ast`).
:mod:`~eqrec.studies.configuration`, :mod:`~eqrec.studies.config_checks`
    Configuration sections, schemas, overrides, the keys each step reads; cross-field checks.
:mod:`~eqrec.studies.outputs`, :mod:`~eqrec.studies.logs`, :mod:`~eqrec.studies.chunks`, :mod:`~eqrec.studies.plotting`
    Writers and timings; logs and progress lines; sweeps in chunk jobs; the papers' figure style.
"""
