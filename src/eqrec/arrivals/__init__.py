"""Arrival patterns: which measurements reach the estimator, and when.

:mod:`~eqrec.arrivals.patterns`
    One arrival pattern (events per time) and its data.
:mod:`~eqrec.arrivals.words`
    The one parser of missing-data and delay words, languages, worst cases.
:mod:`~eqrec.arrivals.prefix_tree`
    The prefix tree of a language (one node per distinct prefix).
:mod:`~eqrec.arrivals.traces`
    The arrival trace of a run (a delay per measurement, or never).
:mod:`~eqrec.arrivals.draws`
    The one arrival model: every random arrival draw (uniform words, Bernoulli, delays, Gilbert–Elliott bursts).
:mod:`~eqrec.arrivals.packets`
    What reaches an estimator at one step (packets, inputs, initial estimates), checked.
"""
