"""eqrec: equalized-recovery bounded-error estimators with missing and delayed data.

Reference replication of

* K. J. Rutledge, S. Z. Yong, N. Ozay, "Prefix-based bounded-error estimation
  with intermittent observations", ACC 2019 (the *prefix-based paper*);
* S. M. Hassaan, Q. Shen, S. Z. Yong, "Bounded-error estimator design with
  missing data patterns via state augmentation", ACC 2019 (the *augmented
  paper*);
* S. M. Hassaan, Q. Shen, S. Z. Yong, "Equalized recovery state estimators
  for linear systems with delayed and missing observations" (the
  *delayed-data paper*);
* the companion LMV study of packet dropouts with zero-input compensation.

The user-facing functions are in this namespace, as in python-control's
``control``::

    import eqrec
    system = eqrec.acc_system()
    design = eqrec.design_prefix(system, ["101111", "110111"], mu1=1.0)
    estimator = design.estimator()

Systems
    :class:`AffineSystem`, :func:`acc_system`, :func:`batch_reactor`, :func:`two_mass`, :func:`load_system`
Arrival patterns (languages)
    :func:`missing_words`, :func:`delay_words` (a 0/1 string reads both ways: say which),
    :func:`as_language`, :func:`validate_language`, :func:`parse_delay_word`,
    :func:`full_delay_language`, :func:`delay_classes` (a full delay language's classes, no word listed;
    ``max_lost=`` at most that many lost per block), :func:`missing_words_at_most`, :func:`loss_coverage`
    (the smallest loss budget whose block probability reaches a coverage),
    :class:`PrefixTree`, :class:`ArrivalTrace` (a run's arrivals: each measurement's delay, or lost)
Designs (each returns a certified :class:`Design`)
    :func:`design_time_based`, :func:`design_prefix`, :func:`design_delay`,
    :func:`design_delay_global`, :func:`design_augmented`, :func:`min_recovery_level`,
    :func:`longest_horizon` (after a failed design of an unstable plant: the longest horizon that solves, by a
    bisection bounded in time)
Certificates
    :func:`certify_schedule`, :func:`information_limit` (the smallest bound any estimator can guarantee on a trace),
    :func:`consistent_set` (the exact hull of the states consistent with the measured data, filtered and
    predicted: a :class:`ConsistentSet`)
Estimators and simulation
    :class:`GuaranteedEstimator` (``Design.estimator()``), :class:`Packet` (a time-stamped
    measurement for ``step``), :class:`ClassEstimator`,
    :class:`ZonotopeEstimator` (set-membership, no language), :class:`ExactSetEstimator` (the hull of the
    set consistent with the data), :func:`simulate_run`, :func:`monte_carlo`
Errors
    :class:`EqrecError`, :class:`InputError`, :class:`InfeasibleDesign`,
    :class:`SolverFailure`, :class:`CertificationFailure`

The rooms, from the bottom layer up (each imports only from the rooms below it; the
import-linter contracts of ``pyproject.toml`` hold the order):
:mod:`eqrec.errors`, :mod:`eqrec.checks` (input checks), :mod:`eqrec.io` (atomic file writing),
:mod:`eqrec.systems`, :mod:`eqrec.arrivals`, :mod:`eqrec.lp`, :mod:`eqrec.bounds` (the
bounded-error mathematics), :mod:`eqrec.lmv` (the LMV study's mathematics), :mod:`eqrec.estimators`,
:mod:`eqrec.simulate`,
:mod:`eqrec.design` (one subpackage per engine), :mod:`eqrec.interop`, :mod:`eqrec.compare`,
:mod:`eqrec.studies` (one folder per paper), and on top the command line :mod:`eqrec.cli`
(its long help in :mod:`eqrec.cli_help`; ``python -m eqrec``: :mod:`eqrec.__main__`).
They are importable as usual.  The names
above load on first use (PEP 562), so ``import eqrec`` itself imports no
solver.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

#: Public name -> the module that defines it.
_PUBLIC: dict[str, str] = {
    # systems
    "AffineSystem": "eqrec.systems.affine",
    "acc_system": "eqrec.systems.examples",
    "load_system": "eqrec.systems.files",
    "batch_reactor": "eqrec.systems.examples",
    "two_mass": "eqrec.systems.examples",
    # arrival patterns
    "missing_words": "eqrec.design.inputs",
    "missing_words_at_most": "eqrec.design.inputs",
    "delay_words": "eqrec.design.inputs",
    "as_language": "eqrec.arrivals.words",
    "validate_language": "eqrec.arrivals.words",
    "parse_delay_word": "eqrec.arrivals.words",
    "full_delay_language": "eqrec.arrivals.words",
    "delay_classes": "eqrec.design.delay.design",
    "PrefixTree": "eqrec.arrivals.prefix_tree",
    "ArrivalTrace": "eqrec.arrivals.traces",
    "loss_coverage": "eqrec.arrivals.draws",
    # designs
    "Design": "eqrec.design.result",
    "design_time_based": "eqrec.design.prefix.time_based",
    "design_prefix": "eqrec.design.prefix.design",
    "load_design": "eqrec.design.saved",
    "design_delay": "eqrec.design.delay.design",
    "design_delay_global": "eqrec.design.delay.design",
    "longest_horizon": "eqrec.design.delay.horizon",
    "design_augmented": "eqrec.design.augmented.design",
    "min_recovery_level": "eqrec.design.classes.mu1_min",
    # certificates
    "certify_schedule": "eqrec.bounds.certify",
    "information_limit": "eqrec.bounds.information",
    "consistent_set": "eqrec.bounds.consistent",
    "ConsistentSet": "eqrec.bounds.consistent",
    # estimators and simulation
    "GuaranteedEstimator": "eqrec.estimators.guaranteed",
    "Packet": "eqrec.arrivals.packets",
    "ClassEstimator": "eqrec.estimators.causal",
    "ZonotopeEstimator": "eqrec.estimators.zonotope",
    "ExactSetEstimator": "eqrec.estimators.exact_set",
    "exact_bound": "eqrec.estimators.exact",
    "simulate_run": "eqrec.simulate.loop",
    "monte_carlo": "eqrec.simulate.loop",
    # errors
    "EqrecError": "eqrec.errors",
    "InputError": "eqrec.errors",
    "InfeasibleDesign": "eqrec.errors",
    "SolverFailure": "eqrec.errors",
    "CertificationFailure": "eqrec.errors",
}

__all__ = ["__version__", *_PUBLIC]


def __getattr__(name: str) -> Any:
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'eqrec' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later lookups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_PUBLIC))
