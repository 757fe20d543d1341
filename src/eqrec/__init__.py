"""eqrec: equalized-recovery estimators with missing and delayed data.

Reference replication of

* K. J. Rutledge, S. Z. Yong, N. Ozay, "Prefix-based bounded-error estimation
  with intermittent observations", ACC 2019 (the *prefix-based paper*);
* S. M. Hassaan, Q. Shen, S. Z. Yong, "Bounded-error estimator design with
  missing data patterns via state augmentation", ACC 2019 (the *augmented
  paper*);
* the companion LMV study of packet dropouts with zero-input compensation.

One module per concept: :mod:`eqrec.systems`, :mod:`eqrec.languages`,
:mod:`eqrec.stacking`, :mod:`eqrec.robust`, :mod:`eqrec.lp`,
:mod:`eqrec.design_prefix`, :mod:`eqrec.gains`, :mod:`eqrec.certify`,
:mod:`eqrec.estimator`, :mod:`eqrec.simulate`, :mod:`eqrec.plotting`,
:mod:`eqrec.claims`.
"""

__version__ = "0.1.0"
