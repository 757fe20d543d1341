r"""Every estimator family on the same plant and the same packet traces (``eqrec compare``).

No paper of the project puts bounded-error estimators, Kalman-type filters
and LMV filters side by side; this module does, on one plant
(:class:`~eqrec.systems.affine.AffineSystem`: its box for the guaranteed
designs, Gaussian statistics for the others) and, run by run, on one arrival
trace, one noise realisation and one initial error shared by every family:

``guaranteed, class engine``
    The delayed-data paper's estimator (:func:`eqrec.design.delay.design.design_delay_global`, ``μ1`` free)
    for the *loss-aware* language: delays ``0..D`` and at most ``m`` of the ``T`` measurements of a block lost,
    ``m`` the smallest whose block probability under the trace model reaches ``coverage``
    (:func:`eqrec.arrivals.draws.loss_coverage`), lowered while no design exists.  Run with ``strict=False``
    (:mod:`eqrec.estimators.guaranteed`): the exact worst case of its error, also when the traces leave the
    language (then the set-membership fallback).
``guaranteed, prefix (P1)``
    The prefix-based paper's estimator for "at most ``m`` of ``T`` measurements lost" (missing-data words,
    ``μ1`` free), ``strict=False``; a late packet counts as lost (its language has no delays).
``set-membership, zonotope``
    :class:`eqrec.estimators.zonotope.ZonotopeEstimator`: no language, a guaranteed set on every trace.
``set-membership, exact``
    :class:`eqrec.estimators.exact_set.ExactSetEstimator`: the interval hull of the states consistent with the
    data (its window solved as LPs with the measured values), on the first ``exact_runs`` runs only (its cost,
    :class:`CompareSetup`); its estimate is not linear in the data and its bound is its own hull.
``Kalman, time-stamped`` and ``Kalman, delay-unaware``
    :mod:`eqrec.estimators.kalman`, designed from the Gaussian statistics.
``LMV, zero-input`` and ``LMV, hold-input``
    The companion study's LMV one-step predictor (:mod:`eqrec.lmv.estimator`)
    for Bernoulli arrivals of rate ``η̄`` = the probability that a packet
    arrives on time; a late packet counts as lost.

The Kalman and LMV filters carry the exact worst case of their error given the arrivals
(:func:`eqrec.exact_bound`, run on affine columns), and every bound is read against the information limit of
the run (:func:`eqrec.information_limit`): the smallest bound any estimator can guarantee there.  On the first
``exact_runs`` runs every bound is also read against the exact consistent set of the run's own data
(:func:`eqrec.consistent_set`, predicted hull): ``hull_over_exact``, each family's set ``x̂ ± bound`` (sound,
so it contains that set) over the set's half-width, both the largest over the states; one is the smallest set
any guaranteed estimator can report on those data (below the limit when the data are kind).

Every estimator reports the one-step prediction ``x̂(t+1)`` after the data of
time ``t`` (the protocol of :mod:`eqrec.estimators.protocol`), so the errors
compared are those of the same quantity.

**Traces.**  Each measurement is lost with probability ``loss`` (independently,
or in bursts: a Gilbert channel with the same average loss and mean burst
length ``burst``); a packet that is not lost is delayed by ``d`` steps, ``d``
uniform on ``0..D``.  **Noise** and **initial error**: normal with
``σ = bound / 5`` truncated at the bound (the delayed-data paper's Fig. 1), in
the box of the system and within ``μ1`` of both guaranteed designs, so every
guarantee applies.  The Gaussian statistics of the Kalman and LMV filters are
those same normals (``5σ`` = bound) unless the system file gives a
``gaussian`` section (``Qw``, ``Qv``, ``x0_cov``: then the draws use them too,
truncated at the box).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np
import pandas as pd

from eqrec.arrivals.draws import ArrivalTrace, delay_trace, gilbert_elliott_trace, with_uniform_delays
from eqrec.systems.noise import GaussianNoise, NoisySystem
from eqrec.estimators.protocol import OnTimeOnly
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError

#: The families, in the order of the table, in words.
FAMILIES = ("guaranteed, class engine", "guaranteed, prefix (P1)", "set-membership, zonotope",
            "set-membership, exact", "Kalman, time-stamped", "Kalman, delay-unaware", "LMV, zero-input",
            "LMV, hold-input")

#: The family run on the first ``exact_runs`` runs only (:class:`CompareSetup`).
EXACT = FAMILIES[3]

#: The families that carry an exact worst-case bound on every step: all of them (the guaranteed designs their own,
#: the others :func:`eqrec.exact_bound`).
BOUNDED = FAMILIES

#: Reduction order of the zonotopes (set-membership estimator, and the error sets of ``strict=False``).
ORDER = 40

#: The columns of ``compare.csv`` (then ``rms_x1 ... rms_xn``).
COLUMNS = ("estimator", "design", "rms", "max_error", "bound", "median_bound", "violations", "outside_design",
           "limit_median", "bound_over_limit_median", "bound_over_limit_p95", "bound_over_limit_max",
           "hull_over_exact_median", "hull_over_exact_p95")

#: A violation is an error above the bound by more than this relative margin (rounding of the bound's arithmetic).
VIOLATION_RTOL = 1e-9


def count_violations(errors: np.ndarray, bounds: np.ndarray, rtol: float = VIOLATION_RTOL) -> int:
    """The number of steps whose error is above its bound by more than the relative margin ``rtol``.

    ``sum(errors > bounds · (1 + rtol))``: the ``violations`` column of ``compare.csv``.

    Parameters
    ----------
    errors : numpy.ndarray
        The errors ``‖x(t+1) − x̂(t+1)‖∞`` (any shape, e.g. ``(runs, steps)``).
    bounds : numpy.ndarray
        The bound of each step, of the same shape.
    rtol : float, optional
        Relative margin for the rounding of the bound's arithmetic (default :data:`VIOLATION_RTOL`).

    Returns
    -------
    int
        The steps in violation.
    """
    return int(np.sum(np.asarray(errors) > np.asarray(bounds) * (1 + rtol)))


def _number(value: Any, field_name: str, low: float, high: float, integer: bool = False,
            low_open: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(f"must be a number, got {value!r}", field=field_name)
    if integer and float(value) != int(value):
        raise InputError(f"must be an integer, got {value!r}", field=field_name)
    if not np.isfinite(value) or value < low or value > high or (low_open and value == low):
        raise InputError(f"must be in {'(' if low_open else '['}{low}, {high}], got {value!r}", field=field_name)
    return int(value) if integer else float(value)


@dataclass(frozen=True)
class CompareSetup:
    """What ``eqrec compare`` runs: the language of the designs, the traces and the Monte Carlo size.

    Parameters
    ----------
    loss : float
        Probability that a measurement is lost, ``0 <= loss < 1``.
    max_delay : int
        Largest delay ``D`` of a packet that is not lost (and of the class-engine design's language).
    horizon : int
        Recovery time ``T`` of the guaranteed designs.
    runs : int, optional
        Number of Monte Carlo runs (default 50).
    periods : int, optional
        Length of a run in periods of ``T`` steps (default 10).
    burst : float or None, optional
        Mean length of a burst of losses (a Gilbert channel with average loss
        ``loss``; ``None``: independent losses).
    seed : int, optional
        Seed of the draws (default 0).
    sigmas : float, optional
        Bounds in standard deviations of the normals drawn (default 5).
    coverage : float, optional
        The loss budget ``m`` of the guaranteed designs' languages is the smallest whose block probability
        under this trace model reaches ``coverage`` (:func:`eqrec.arrivals.draws.loss_coverage`; default 0.99).
    exact_runs : int, optional
        The first runs (at most ``runs``) on which the exact set-membership estimator runs and every family's
        set is compared with the exact consistent set of the data (default 4: the LPs of every step cost
        about ten times a zonotope step; 0: neither).

    Raises
    ------
    InputError
        A value out of its range, naming the field.
    """

    loss: float
    max_delay: int
    horizon: int
    runs: int = 50
    periods: int = 10
    burst: float | None = None
    seed: int = 0
    sigmas: float = 5.0
    coverage: float = 0.99
    exact_runs: int = 4

    def __post_init__(self) -> None:
        checked = {"loss": _number(self.loss, "loss", 0.0, 0.99),
                   "max_delay": _number(self.max_delay, "max_delay", 0, 10, integer=True),
                   "horizon": _number(self.horizon, "horizon", 1, 30, integer=True),
                   "runs": _number(self.runs, "runs", 1, 100_000, integer=True),
                   "periods": _number(self.periods, "periods", 1, 10_000, integer=True),
                   "seed": _number(self.seed, "seed", 0, 2**63 - 1, integer=True),
                   "sigmas": _number(self.sigmas, "sigmas", 0.0, 100.0, low_open=True),
                   "coverage": _number(self.coverage, "coverage", 0.0, 1.0, low_open=True),
                   "exact_runs": _number(self.exact_runs, "exact_runs", 0, 100_000, integer=True)}
        if self.burst is not None:
            checked["burst"] = _number(self.burst, "burst", 1.0, 1e6)
            if checked["loss"] == 0:
                raise InputError("a burst length needs a positive loss", field="burst")
            if checked["loss"] / (1 - checked["loss"]) / checked["burst"] > 1:
                raise InputError(f"a mean burst of {checked['burst']} steps cannot give an average loss of "
                                 f"{checked['loss']} (the channel would have to enter a burst with probability > 1)",
                                 field="burst")
        for key, value in checked.items():
            object.__setattr__(self, key, value)

    @property
    def exact_subset(self) -> int:
        """The runs of the exact family and of the consistent set: ``min(exact_runs, runs)``."""
        return min(self.exact_runs, self.runs)

    @property
    def steps(self) -> int:
        """Steps of a run: ``periods · T``."""
        return self.periods * self.horizon

    @property
    def max_lost(self) -> int:
        """``m``: losses per block of the guaranteed designs' languages (``coverage`` of the blocks)."""
        from eqrec.arrivals.draws import loss_coverage

        return loss_coverage(self.max_delay, self.horizon, self.loss, self.coverage, burst=self.burst)

    @property
    def on_time_rate(self) -> float:
        """Probability that a packet arrives on time: ``(1 − loss) / (D + 1)`` (the LMV filters' ``η̄``)."""
        return (1.0 - self.loss) / (self.max_delay + 1)


def draw_trace(rng: np.random.Generator, setup: CompareSetup) -> ArrivalTrace:
    """One run's arrivals: losses (independent or in bursts), then a uniform delay ``0..D`` per packet kept.

    Parameters
    ----------
    rng : numpy.random.Generator
        Random source (:mod:`eqrec.arrivals.draws` draws: one uniform per measurement for independent
        losses and delays; the channel, then one delay per measurement, for bursts).
    setup : CompareSetup
        The loss, burst and delay settings.

    Returns
    -------
    ArrivalTrace
        ``setup.steps`` measurements.
    """
    N = setup.steps
    if setup.burst is None:
        return delay_trace(rng, N, [(1.0 - setup.loss) / (setup.max_delay + 1)] * (setup.max_delay + 1))
    # Gilbert channel: bad (every packet lost) for 1/p_bg steps on average, stationary loss = `loss`
    p_bg = 1.0 / setup.burst
    p_gb = setup.loss * p_bg / (1.0 - setup.loss)
    return with_uniform_delays(rng, gilbert_elliott_trace(rng, N, p_gb, p_bg), setup.max_delay)


@dataclass
class CompareResult:
    """What :func:`compare_families` returns.

    Parameters
    ----------
    setup : CompareSetup
        The settings.
    table : pandas.DataFrame
        One row per family (:data:`COLUMNS` and the per-state RMS).
    errors : dict of str to ndarray
        Per family that ran, ``‖x(t+1) − x̂(t+1)‖∞``, shape ``(runs, steps)``.
    bounds : dict of str to ndarray
        Per family with a bound (:data:`BOUNDED`), the bound of each step, shape ``(runs, steps)``.
    mu1 : dict of str to float
        The recovery level of each guaranteed design that exists.
    outside : dict of str to ndarray
        Per guaranteed design, whether each step was outside the design, shape ``(runs, steps)``.
    limit : ndarray
        The information limit ``max_i r_i(t+1)`` of each run and step (:func:`eqrec.information_limit`),
        shape ``(runs, steps)``.
    designs : dict of str to str
        Per family, its design in words (the language, or ``"none needed"``), or why there is none.
    identity : dict
        The class engine's class levels against the one-block information limit
        (:func:`class_limit_identity`; empty without that design).
    us_per_step : dict of str to float
        Per family, the wall time of a step with its bound, in microseconds (a timing: not in the table).
    state_weights : ndarray or None
        The weights of the norm (``None``: the infinity norm).
    exact_hull : ndarray
        The predicted half-width of the exact consistent set (:func:`eqrec.consistent_set`; largest over the
        states, weighted), on the first ``setup.exact_subset`` runs, shape ``(exact_subset, steps)``.
    """

    setup: CompareSetup
    table: pd.DataFrame
    errors: dict[str, np.ndarray]
    bounds: dict[str, np.ndarray]
    mu1: dict[str, float]
    outside: dict[str, np.ndarray] = field(default_factory=dict)
    limit: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    designs: dict[str, str] = field(default_factory=dict)
    identity: dict[str, Any] = field(default_factory=dict)
    us_per_step: dict[str, float] = field(default_factory=dict)
    state_weights: "np.ndarray | None" = None
    exact_hull: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))


def guaranteed_designs(system: AffineSystem, setup: CompareSetup, solver: str = "highs",
                       state_weights: "np.ndarray | None" = None, memo: "dict | None" = None) -> dict[str, Any]:
    """The two guaranteed designs of the comparison on a loss-aware language, each at its smallest ``μ1``.

    The class engine designs for delays ``0..D`` and at most ``m`` of the ``T`` measurements of a block lost
    (:func:`eqrec.delay_classes` with ``max_lost``); the prefix design for the missing-data words with at most
    ``m`` zeros (:func:`eqrec.missing_words_at_most`; its language has no delays).  ``m`` starts at
    ``setup.max_lost`` (the coverage of the blocks) and goes down while the design does not exist (a language
    with too many losses in a block has no estimator that recovers): the largest feasible ``m`` is used, and a
    design that exists for no ``m`` is a string saying why.

    Parameters
    ----------
    system : AffineSystem
        The plant.
    setup : CompareSetup
        ``D``, ``T`` and the coverage of the loss budget.
    solver : str, optional
        LP solver (default HiGHS).
    state_weights : ndarray or None, optional
        Designs on ``z = W x`` (every level bounds ``max_i w_i |x_i − x̂_i|``); ``None``: unweighted.
    memo : dict or None, optional
        Kept between calls on the same ``system``: each attempt (family, ``m``, ``D``, ``T``, solver, weights)
        made once, its design or why there is none (the same LP on the same data gives the same answer).

    Returns
    -------
    dict
        ``{family: (Design or str, m)}``: the design (or why there is none) and the loss budget it was made for.
    """
    from eqrec.design.delay.design import delay_classes, design_delay_global
    from eqrec.design.inputs import missing_words_at_most
    from eqrec.design.prefix.design import design_prefix
    from eqrec.errors import CertificationFailure, InfeasibleDesign, SolverFailure

    T, D = setup.horizon, setup.max_delay
    w = state_weights
    makers = {FAMILIES[0]: lambda m: design_delay_global(system, delay_classes(max_delay=D, horizon=T, max_lost=m),
                                                         solver=solver, state_weights=w).design,
              FAMILIES[1]: lambda m: design_prefix(system, missing_words_at_most(T, m), "free", solver=solver,
                                                   state_weights=w)}

    def attempt(family: str, m: int) -> Any:
        """The design of ``family`` at ``m``, or why there is none (a string)."""
        try:
            return makers[family](m)
        except (InfeasibleDesign, SolverFailure, CertificationFailure) as exc:
            return f"no design: {type(exc).__name__}: {str(exc).splitlines()[0][:160]}"

    weights = None if w is None else tuple(np.asarray(w, dtype=float).tolist())
    out: dict[str, Any] = {}
    for family in makers:
        first = None
        for m in range(setup.max_lost, -1, -1):
            key = ("design", family, m, D, T, solver, weights)
            found = memo[key] if memo is not None and key in memo else attempt(family, m)
            if memo is not None:
                memo[key] = found
            if not isinstance(found, str):
                out[family] = (found, m)
                break
            first = first or found
        else:
            out[family] = (first, None)
    return out


def class_limit_identity(design: Any) -> dict[str, Any]:
    """The class levels of a class-engine design against the one-block information limit (issue 32 §1).

    For every class ``(d, S)``: its stored level and the largest per-state radius of information of
    ``x(d)`` given the data ``S`` and a box of radius ``μ1`` at the block's start
    (:func:`eqrec.bounds.information.block_limit`); the two are equal (LP duality, Smolyak's theorem: the
    docstring of :func:`eqrec.information_limit`).

    Parameters
    ----------
    design : Design
        A class-engine design (``design.class_gains`` and ``design.class_levels``).

    Returns
    -------
    dict
        ``classes`` (how many), ``largest_relative_difference``, ``all_within_1e-9_relative`` and ``rows``: per
        class ``label``, ``level``, ``limit``.
    """
    from eqrec.bounds.information import block_limit

    rows = []
    for cls, level in zip(design.class_gains.classes.classes, design.class_levels):
        limit = float(block_limit(design.system, cls.depth, cls.available, design.mu1).max())
        rows.append({"label": cls.label, "level": float(level), "limit": limit})
    worst = max((abs(r["level"] - r["limit"]) / r["level"] for r in rows if r["level"] > 0), default=0.0)
    # the differences are LP round-off (1e-16 .. 1e-14, machine-dependent): whether they are within 1e-9 is the
    # stable result the study stores
    return {"classes": len(rows), "largest_relative_difference": worst, "all_within_1e-9_relative": worst <= 1e-9,
            "rows": rows}


def design_in_words(family: str, setup: CompareSetup, m: "int | None" = None) -> str:
    """The language a family is designed for, in words (the ``design`` column).

    Parameters
    ----------
    family : str
        One of :data:`FAMILIES`.
    setup : CompareSetup
        The settings.
    m : int or None, optional
        The loss budget of the design (default: ``setup.max_lost``).

    Returns
    -------
    str
        E.g. ``"delays 0..1, at most 2 of 6 lost"`` (with ``", m = 3 has no design"`` when the coverage's
        budget had to be lowered).
    """
    target, T, D = setup.max_lost, setup.horizon, setup.max_delay
    m = target if m is None else m
    lowered = f" ({setup.coverage:g} of the blocks needs m = {target}: no design)" if m < target else ""
    if family == FAMILIES[0]:
        return f"delays 0..{D}, at most {m} of {T} lost{lowered}"
    if family == FAMILIES[1]:
        return f"on time, at most {m} of {T} lost (late = lost){lowered}"
    return "none needed"


def _lmv(system: AffineSystem, gaussian: GaussianNoise, mechanism: str, eta_bar: float, steps: int) -> Any:
    from eqrec.lmv.estimator import LMVEstimator
    from eqrec.lmv.model import system_of
    from eqrec.lmv.plant import Plant
    from eqrec.lmv.recursion import lmv_recursion

    if system.nw == 0:  # the LMV plant has a process noise: give it a zero one (same system)
        system = AffineSystem(A=system.A, C=system.C, E=np.zeros((system.n, 1)), eta_w=1.0, eta_v=system.eta_v,
                              B=system.B, f=system.f, V=system.V, name=system.name, source=system.source)
        gaussian = GaussianNoise(Qw=np.zeros((1, 1)), Qv=gaussian.Qv, x0_cov=gaussian.x0_cov,
                                 x0_mean=gaussian.x0_mean)
    plant = Plant.from_description(NoisySystem(system, gaussian))
    sys = system_of(plant, mechanism, eta_bar)
    gains = lmv_recursion(sys, steps + 1, check_stability=False)  # the same gains for every run
    # one estimator for every run (each starts with reset): the matrices of a step that depend on its index alone
    # are made once (LMVEstimator._step_matrices), not once per run
    estimator = LMVEstimator(sys, gains, system=system)
    return lambda: estimator


def compare_families(system: AffineSystem, setup: CompareSetup, *, gaussian: "GaussianNoise | dict | None" = None,
                     solver: str = "highs", progress: Callable[[str], None] | None = None,
                     state_weights: Any = None, memo: "dict | None" = None) -> CompareResult:
    """Run every family (module docstring) on the same traces, noise and initial errors, with the information limit.

    Every family with a bound (:data:`BOUNDED`) reports the exact worst case of its own error on the run's
    arrivals: the guaranteed designs with ``strict=False`` (:mod:`eqrec.estimators.guaranteed`), the
    set-membership estimator its set, the Kalman and LMV filters :func:`eqrec.exact_bound` (affine columns).
    The information limit of each run (:func:`eqrec.information_limit`, initial radius ``μ1``) is the smallest bound any estimator can
    guarantee there; every bound is compared with it.

    Parameters
    ----------
    system : AffineSystem
        The plant (time-invariant).
    setup : CompareSetup
        Traces, coverage of the loss budget and Monte Carlo size.
    gaussian : GaussianNoise, dict or None, optional
        Second moments of the noise and of the initial error (``None``: from
        the box, ``5σ`` = bound, with ``μ1`` the smallest of the designs';
        a dict with some of ``Qw``, ``Qv``, ``x0_cov``, as a system file's
        ``gaussian`` section, takes the others from the box).
    solver : str, optional
        LP solver of the guaranteed designs and of the information limit.
    progress : callable or None, optional
        Called with a line of text per family done.
    state_weights : array_like or None, optional
        ``w`` (``n`` positive numbers): every error, bound and limit is measured as ``max_i w_i |·_i|`` (a state
        vector of mixed units), the guaranteed designs are made on ``z = W x`` and the initial error is drawn in
        the box ``|ξ_i(0)| <= μ1 / w_i``; ``None``: the infinity norm.
    memo : dict or None, optional
        A dict kept between calls on the same ``system`` object (the settings of one plant): the guaranteed
        designs of a loss budget, delays and horizon already made, and their class levels against the
        information limit (:func:`class_limit_identity`), are taken from it instead of being made again (the
        same LPs on the same data; settings that differ only in their traces share the design).  ``None``: made
        here.

    Returns
    -------
    CompareResult
        The table, the errors, the bounds, the limit, the designs in words and the time per step.

    Raises
    ------
    InputError
        A time-varying system, or a Gaussian description that does not fit it.
    """
    import time

    # imported here, as the estimators below: the compare study's table step merges CSVs and needs no simulation
    # (saves ~0.4 s CPU of numba and scipy.linalg imports in that job)
    from eqrec.bounds.stacking import UncertaintyLayout
    from eqrec.simulate.loop import closed_loop, plant_run
    from eqrec.bounds.information import information_limit
    from eqrec.bounds.consistent import consistent_set
    from eqrec.estimators.exact import exact_bound
    from eqrec.estimators.exact_set import ExactSetEstimator
    from eqrec.estimators.kalman import DelayUnawareKalman, TimestampedKalman
    from eqrec.estimators.zonotope import ZonotopeEstimator

    if system.is_time_varying:
        raise InputError("the comparison runs on a time-invariant system", system.source, "A")
    w = None
    if state_weights is not None:
        try:
            w = np.array(np.broadcast_to(np.asarray(state_weights, dtype=float), (system.n,)))
        except (TypeError, ValueError):
            raise InputError(f"{system.n} positive numbers, got {state_weights!r:.60}", field="state_weights") \
                from None
        if not np.all(np.isfinite(w)) or np.any(w <= 0):
            raise InputError(f"weights must be finite and > 0, got {w.tolist()}", field="state_weights")
    if memo is not None and memo.get("system") is not system:
        memo.clear()
        memo["system"] = system  # kept alive with its entries: they are this object's
    found = guaranteed_designs(system, setup, solver, state_weights=w, memo=memo)
    designs = {f: d for f, (d, _) in found.items() if not isinstance(d, str)}
    words = {f: (d if isinstance(d, str) else design_in_words(f, setup, m)) for f, (d, m) in found.items()}
    words.update({f: design_in_words(f, setup) for f in FAMILIES if f not in found})
    if designs:
        mu1 = min(d.mu1 for d in designs.values())
    else:  # no guaranteed design: the initial error of the runs from the open-loop box of one period
        mu1 = float(max(np.abs(system.C).sum(), 1.0))
    r0 = mu1 if w is None else mu1 / w  # the initial error's box: |w_i ξ_i(0)| <= μ1
    if w is not None and (gaussian is None or (isinstance(gaussian, dict) and "x0_cov" not in gaussian)):
        gaussian = {**(gaussian or {}), "x0_cov": np.diag((r0 / setup.sigmas) ** 2)}
    gaussian = _gaussian(system, gaussian, mu1, setup.sigmas)
    kalman = gaussian.design(system)  # P0, Q = E Qw Eᵀ, R = V Qv Vᵀ
    N, n, p = setup.steps, system.n, system.p
    truths: dict = {}  # the true columns of each run, simulated once for the four families run on columns
    makers: dict[str, Callable[[], Any]] = {
        FAMILIES[2]: lambda: ZonotopeEstimator(system, x0_radius=r0, max_delay=setup.max_delay, order=ORDER),
        EXACT: lambda: ExactSetEstimator(system, x0_radius=r0, max_delay=setup.max_delay),
        FAMILIES[4]: lambda: exact_bound(TimestampedKalman(system, kalman), system, r0, steps=N, truths=truths),
        FAMILIES[5]: lambda: exact_bound(DelayUnawareKalman(system, kalman), system, r0, steps=N, truths=truths),
    }
    if FAMILIES[0] in designs:
        makers[FAMILIES[0]] = lambda: designs[FAMILIES[0]].estimator(strict=False)
    if FAMILIES[1] in designs:
        makers[FAMILIES[1]] = lambda: OnTimeOnly(designs[FAMILIES[1]].estimator(strict=False), p)
    for family, mechanism in ((FAMILIES[6], "zero-input"), (FAMILIES[7], "hold-input")):
        make = _lmv(system, gaussian, mechanism, setup.on_time_rate, N)  # a late packet counts as lost
        makers[family] = (lambda make=make: exact_bound(make(), system, r0, steps=N, truths=truths))
    # the draws, in order, per run: the trace, then the noise and the initial error
    rng = np.random.default_rng(setup.seed)
    lay = UncertaintyLayout(N, system.nw, system.nv, n)
    radius = lay.radius(system.eta_w, system.eta_v, mu1)
    radius[lay.xi0] = r0
    scale = np.concatenate([np.tile(np.sqrt(np.diag(gaussian.Qw)), N), np.tile(np.sqrt(np.diag(gaussian.Qv)), N),
                            np.sqrt(np.diag(gaussian.x0_cov))])
    runs = []
    for _ in range(setup.runs):
        trace = draw_trace(rng, setup)
        z = _truncated_normal(rng, lay.size, setup.sigmas)
        delta = np.clip(z * scale, -radius, radius)  # within the box, so every guarantee applies
        runs.append((trace, *lay.split(delta)))
    scale_of = np.ones(n) if w is None else w  # the norm of every error, bound and limit: max_i w_i |·_i|
    limit = np.stack([(information_limit(system, trace, r0, solver=solver) * scale_of).max(axis=1)
                      for trace, *_ in runs])
    if progress is not None:
        progress(f"information limit: median {np.median(limit):.4g} ({setup.runs} runs x {N} steps)")
    errors, bounds, outside, rows, us = {}, {}, {}, [], {}
    x0 = np.zeros(n)
    # the true states and measurements of each run, the same for every family (zero input): simulated once
    plants = [plant_run(system, N, x0, w_noise, v) for _, w_noise, v, _ in runs]
    K = setup.exact_subset
    data: dict[int, np.ndarray] = {}  # the measurements of the first K runs (the same for every family)
    for family in FAMILIES:
        row: dict[str, Any] = {"estimator": family, "design": words[family]}
        if family not in makers:  # a guaranteed design that does not exist: a row that says so
            row.update(rms=np.nan, max_error=np.nan, bound=np.nan, median_bound=np.nan,
                       violations=pd.NA, outside_design=np.nan, limit_median=np.nan,
                       **{c: np.nan for c in COLUMNS[9:]}, **{f"rms_x{i + 1}": np.nan for i in range(n)})
            rows.append(row)
            continue
        mine = runs[:K] if family == EXACT else runs  # the exact family: the first K runs only
        if not mine:
            row.update(rms=np.nan, max_error=np.nan, bound=np.nan, median_bound=np.nan, violations=pd.NA,
                       outside_design=np.nan, limit_median=np.nan, **{c: np.nan for c in COLUMNS[9:]},
                       **{f"rms_x{i + 1}": np.nan for i in range(n)})
            rows.append(row)
            continue
        err = np.zeros((len(mine), N))
        sq = np.zeros(n)
        bnd = np.full((len(mine), N), np.nan)
        out = np.zeros((len(mine), N), bool)
        elapsed = 0.0
        for r, (trace, w_noise, v, xi0) in enumerate(mine):
            est = makers[family]()
            flags: list[bool] = []
            per_state: list[float] = []  # weighted: max_i w_i β_i per step (a design's own bound is weighted already)

            def after(_k, est=est, flags=flags, per_state=per_state, design=family in designs):
                if design:
                    flags.append(not est.in_design)
                elif w is not None:
                    per_state.append(float((w * est.state_bounds).max()))
            t_start = time.perf_counter()
            run = closed_loop(system, est, trace, x0, xi0, w_noise, v, after_step=after, plant=plants[r])
            elapsed += time.perf_counter() - t_start
            if r < K and r not in data:
                data[r] = run.y
            e = run.error[1:]
            err[r] = (np.abs(e) * scale_of).max(axis=1)
            sq += (e ** 2).sum(axis=0)
            if family in BOUNDED:
                bnd[r] = per_state if per_state else run.spread
            if family in designs:
                out[r] = flags
        errors[family] = err
        us[family] = 1e6 * elapsed / (len(mine) * N)
        row.update(rms=float(np.sqrt(sq.sum() / (len(mine) * N * n))), max_error=float(err.max()))
        if family in BOUNDED:
            bounds[family] = bnd
            ratio = bnd / limit[:len(mine)]
            row.update(bound=float(bnd.max()), median_bound=float(np.median(bnd)),
                       violations=count_violations(err, bnd),
                       outside_design=float(out.mean()) if family in designs else np.nan,
                       limit_median=float(np.median(limit[:len(mine)])),
                       bound_over_limit_median=float(np.median(ratio)),
                       bound_over_limit_p95=float(np.quantile(ratio, 0.95)), bound_over_limit_max=float(ratio.max()))
        else:
            row.update(bound=np.nan, median_bound=np.nan, violations=pd.NA, outside_design=np.nan,
                       limit_median=float(np.median(limit)), **{c: np.nan for c in COLUMNS[9:]})
        if family in designs:
            outside[family] = out
        row.update({f"rms_x{i + 1}": float(np.sqrt(sq[i] / (len(mine) * N))) for i in range(n)})
        rows.append(row)
        if progress is not None:
            progress(f"{family}: rms {row['rms']:.4g}, max error {row['max_error']:.4g}")
    # the exact consistent set of each of the first K runs' data (the same initial box as the estimators': centre
    # x̂(0) = x(0) − ξ(0) = −ξ(0), radius r0), predicted only (what the families report), and each family's hull
    # over it
    hull = np.stack([(consistent_set(system, runs[r][0], data[r], r0, x0 - runs[r][3], solver=solver,
                                     kinds=("predicted",))
                      .predicted_radius * scale_of).max(axis=1) for r in range(K)]) if K else np.zeros((0, N))
    for row in rows:
        if row["estimator"] in bounds and K:
            over = bounds[row["estimator"]][:K] / hull
            row.update(hull_over_exact_median=float(np.median(over)),
                       hull_over_exact_p95=float(np.quantile(over, 0.95)))
        else:
            row.update(hull_over_exact_median=np.nan, hull_over_exact_p95=np.nan)
    if progress is not None and K:
        progress(f"exact consistent set: median half-width {np.median(hull):.4g} ({K} runs x {N} steps)")
    table = pd.DataFrame(rows, columns=[*COLUMNS, *[f"rms_x{i + 1}" for i in range(n)]])
    table["violations"] = table["violations"].astype("Int64")
    return CompareResult(setup=setup, table=table, errors=errors, bounds=bounds,
                         mu1={f: float(d.mu1) for f, d in designs.items()}, outside=outside, limit=limit,
                         designs=words, us_per_step=us, state_weights=w, exact_hull=hull,
                         identity=_identity(designs, memo))


def _identity(designs: dict, memo: "dict | None") -> dict[str, Any]:
    """:func:`class_limit_identity` of the class-engine design (``{}`` without one), from ``memo`` when it holds it."""
    if FAMILIES[0] not in designs:
        return {}
    design = designs[FAMILIES[0]]
    if memo is None:
        return class_limit_identity(design)
    key = ("identity", id(design))  # the design is kept alive by the memo's designs
    if key not in memo:
        memo[key] = class_limit_identity(design)
    return memo[key]


def _gaussian(system: AffineSystem, given: "GaussianNoise | dict | None", mu1: float, sigmas: float) -> GaussianNoise:
    """The Gaussian description: given, or from a system file's ``gaussian`` section, or from the box."""
    box = GaussianNoise.from_box(system, mu1, sigmas)
    if given is None:
        return box
    if isinstance(given, dict):
        unknown = set(given) - {"Qw", "Qv", "x0_cov"}
        if unknown:
            raise InputError(f"unknown key(s) {sorted(unknown)}; allowed: Qw, Qv, x0_cov", system.source, "gaussian")
        given = GaussianNoise(Qw=given.get("Qw", box.Qw), Qv=given.get("Qv", box.Qv),
                              x0_cov=given.get("x0_cov", box.x0_cov))
    given.check(system)
    return given


def _truncated_normal(rng: np.random.Generator, size: int, sigmas: float) -> np.ndarray:
    """Standard normals redrawn until within ``±sigmas`` (in draw order: deterministic for a seed)."""
    z = rng.standard_normal(size)
    bad = np.abs(z) > sigmas
    while bad.any():
        z[bad] = rng.standard_normal(int(bad.sum()))
        bad = np.abs(z) > sigmas
    return z


def write_table(result: CompareResult, path: str) -> None:
    """Write ``compare.csv``: one row per family, numbers with 6 significant digits, empty where not applicable.

    Parameters
    ----------
    result : CompareResult
        The comparison.
    path : str
        The CSV file to write.
    """
    result.table.to_csv(path, index=False, float_format="%.6g", na_rep="", lineterminator="\n")

