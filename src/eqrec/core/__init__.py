"""The core: systems, arrival patterns, stacked maps, robust counterparts, LPs and solvers, gains,
certification, the runtime estimator and simulation.  Nothing here designs an estimator (:mod:`eqrec.design`).

:mod:`~eqrec.core.systems`, :mod:`~eqrec.core.acc`, :mod:`~eqrec.core.system_files`
    Affine systems with bounded noise; the ACC model of the prefix-based paper; system files (YAML, mappings).
:mod:`~eqrec.core.patterns`, :mod:`~eqrec.core.words`, :mod:`~eqrec.core.prefix_tree`
    Arrival patterns and their events; the one parser of missing-data and delay words, languages, worst cases;
    prefix trees.
:mod:`~eqrec.core.classes`
    The (time, available data) classes of a language and the class gains.
:mod:`~eqrec.core.stacking`, :mod:`~eqrec.core.robust`
    Stacked error maps over a horizon, and the robust counterparts of ``|G δ| <= μ`` over a box.
:mod:`~eqrec.core.lp`, :mod:`~eqrec.core.solvers`
    LP model (build, solve, read as separate steps) and the solver registry (HiGHS, Clarabel, SciPy, IPOPT;
    one status table for HiGHS, whether driven through highspy or SciPy).
:mod:`~eqrec.core.gains`
    Gain schedules ``(F, u0)`` per word.
:mod:`~eqrec.core.certify`
    Worst cases recomputed from the gains alone.
:mod:`~eqrec.core.arrivals`, :mod:`~eqrec.core.traces`, :mod:`~eqrec.core.packets`
    The one arrival model (every random arrival draw) and its trace type; what reaches an estimator at a step
    (packets, inputs, initial estimates, checked).
:mod:`~eqrec.core.noise`, :mod:`~eqrec.core.checks`
    One system description (the box, Gaussian second moments, multiplicative terms); shared input checks.
:mod:`~eqrec.core.protocol`
    The one estimator protocol (``reset``, then ``step(y, u) -> (x̂, bound or covariance)``) of every estimator.
:mod:`~eqrec.core.intake`, :mod:`~eqrec.core.estimator`, :mod:`~eqrec.core.switching`, :mod:`~eqrec.core.runtime`,
:mod:`~eqrec.core.error_boxes`
    Causal estimators on time-stamped packets, the switching strategy, and the user-facing guaranteed estimator.
:mod:`~eqrec.core.simulate`, :mod:`~eqrec.core.long_runs`
    Runs within one horizon and Monte Carlo; long runs (periodic reuse, the switching scheme).
"""
