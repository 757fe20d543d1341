"""``eqrec compare``: every estimator family on the same plant and packet traces, as a table and a figure.

Examples
--------
::

    eqrec compare examples/batch_reactor.yaml --loss 0.1 --max-delay 2 --horizon 5 --runs 50 --out cmp
    eqrec compare examples/acc_system.yaml --loss 0.1 --burst 4 --max-delay 1 --horizon 6 --out cmp_burst
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from eqrec.errors import InputError

#: The time model of one Monte Carlo run of ``N`` steps, every family and its bound plus the information limit:
#: ``SECONDS_PER_STEP · N + SECONDS_PER_STEP2 · N²`` seconds for a plant of ``n = 4`` states, scaled by ``(n/4)²``
#: (measured 2026-11-29 on the batch reactor, T = 5, D = 2: 0.43 s a run of 50 steps, 5.1 s of 200, on the shared
#: 2-core machine); the limit's matrices take about ``8 n N²`` bytes.  An estimate, meant to within a factor 3.
SECONDS_PER_STEP, SECONDS_PER_STEP2 = 3e-3, 1.2e-4

COMPARE_HELP = """\
Families (rows of compare.csv, in words):
  guaranteed, class engine   the delayed-data paper's estimator (mu1 free) for the loss-aware language:
                             delays 0..D and at most m of the T measurements of a block lost; strict=False:
                             the exact bound of its error also when the traces leave the language
  guaranteed, prefix (P1)    the prefix-based paper's estimator for "at most m of T lost" (mu1 free),
                             strict=False; a late packet counts as lost
  set-membership, zonotope   eqrec.ZonotopeEstimator: no language, a guaranteed set on any trace
  Kalman, time-stamped       every packet used at its own time stamp (re-filtering), with its exact bound
  Kalman, delay-unaware      a packet used as a measurement of the time it arrives, with its exact bound
  LMV, zero-input / hold-input   the companion study's LMV predictor (arrival rate = on-time rate);
                             a late packet counts as lost; with its exact bound
m: the smallest loss budget whose block probability under the trace model reaches --coverage (default
0.99; eqrec.loss_coverage). A design that does not exist (e.g. T too short for m losses) is a row saying why.
Horizon: --horizon is 1..30 (the languages grow quickly with T, D and m).
Traces: each measurement lost with probability --loss (independently, or in bursts of mean length --burst
with the same average loss); a packet kept is delayed uniformly by 0..D steps. Noise and initial error:
normal with 5 sigma = the bound, truncated at it (the delayed-data paper's Fig. 1); the Kalman and LMV
filters are designed with those statistics, or with the system file's optional section
  gaussian: {Qw: [[...]], Qv: [[...]], x0_cov: [[...]]}   (any of them; the others from the box).
Every family runs on the same traces, noise and initial errors; each reports x^(t+1) after the data of t.
The information limit of each run (eqrec.information_limit, initial radius mu1) is the smallest bound any
estimator can guarantee on its arrivals.

compare.csv columns: estimator, design (the language in words), rms (over runs, steps and states),
max_error (largest ||x - x^||_inf), bound and median_bound (largest and median bound), violations (steps
with an error above the bound), outside_design (fraction of steps outside the design's language),
limit_median, bound_over_limit_median / _p95 / _max (bound / information limit, per step),
hull_over_exact_median / _p95 (each family's set x^ +- bound over the half-width of the exact consistent set
of the run's own data, eqrec.consistent_set, per step, on the first --exact-runs runs), rms_x1 .. rms_xn.
The family "set-membership, exact" (eqrec.ExactSetEstimator, LPs at every step) runs on those runs only.
The printed table adds us_per_step (microseconds per step with the bound; a timing, not in the CSV).
compare.png / compare.pdf: the errors, the bounds, the limit and mu1 over time.
"""


def add_parser(sub: Any, exit_help: str) -> None:
    """Add the ``compare`` subcommand to the CLI's subparsers.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of ``eqrec``.
    exit_help : str
        The exit-status paragraph shared by the subcommands.
    """
    c = sub.add_parser("compare", help="every estimator family on the same plant and packet traces",
                       description="Run the guaranteed estimators (class engine, prefix), the Kalman-type\n"
                                   "filters and the LMV zero-/hold-input filters on the same packet traces, noise\n"
                                   "and initial errors; write DIR/compare.csv and DIR/compare.png (and .pdf).",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=COMPARE_HELP + "\n" + exit_help)
    c.add_argument("system", help="system YAML file (the keys of `eqrec design --help`, and optionally gaussian:)")
    c.add_argument("--loss", type=float, required=True, help="probability that a measurement is lost (0 <= P < 1)")
    c.add_argument("--max-delay", type=int, required=True, dest="max_delay",
                   help="largest delay D of a packet that is not lost (also the class-engine design's language)")
    c.add_argument("--horizon", type=int, required=True, help="recovery time T of the guaranteed designs")
    c.add_argument("--runs", type=int, default=50, help="Monte Carlo runs (default 50)")
    c.add_argument("--periods", type=int, default=10, help="length of a run in periods of T steps (default 10)")
    c.add_argument("--burst", type=float, default=None,
                   help="mean length of a burst of losses (Gilbert channel with the same average loss)")
    c.add_argument("--seed", type=int, default=0, help="seed of every draw (default 0)")
    c.add_argument("--exact-runs", type=int, default=4, dest="exact_runs",
                   help="the first runs on which the exact set-membership estimator runs and every family's set is "
                        "compared with the exact consistent set of the data (hull_over_exact; default 4, 0: none)")
    c.add_argument("--state-weights", default=None, dest="state_weights",
                   help="w1,...,wn: measure errors, bounds and the limit as max_i w_i |e_i| (states of mixed units); "
                        "the designs are made on z = W x")
    c.add_argument("--coverage", type=float, default=0.99,
                   help="block probability the designs' loss budget m must reach (default 0.99)")
    c.add_argument("--solver", default="highs", help="LP solver of the guaranteed designs (default highs)")
    c.add_argument("--out", required=True, help="output folder (created if missing; its parent must exist)")
    c.add_argument("--force", action="store_true",
                   help="run a comparison past the documented size (the guaranteed designs and the runs estimated "
                        "over 10 min or over 80%% of the available memory; the estimate is printed either way, and "
                        "refused otherwise with exit 1)")


def _out_dir(out: str) -> Path:
    path = Path(out)
    if path.exists() and not path.is_dir():
        raise InputError("is a file; give a folder for compare.csv and compare.png", str(path), "--out")
    if not path.parent.is_dir():
        raise InputError(f"folder {path.parent} does not exist", str(path), "--out")
    return path


def check_size(system: Any, setup: Any, *, force: bool) -> None:
    """Print the estimate of a long comparison; refuse one past the documented size unless ``force`` (``--force``).

    The guaranteed class-engine design of the loss-aware language (the size model of ``eqrec design``,
    :func:`eqrec.design.inputs.estimate_delay_design`, μ1 free) plus ``--runs`` Monte Carlo runs of
    ``--periods · --horizon`` steps (:data:`SECONDS_PER_STEP`, :data:`SECONDS_PER_STEP2`), answered by
    :func:`eqrec.design.inputs.report_size`.

    Parameters
    ----------
    system : AffineSystem
        The plant.
    setup : CompareSetup
        The comparison's language and Monte Carlo size.
    force : bool
        Run past the documented size anyway.

    Raises
    ------
    InputError
        Past the documented size without ``force`` (field ``--runs``, ``--periods`` or ``--horizon``, whichever
        costs most; nothing is written).
    """
    from eqrec.design.inputs import SetEstimate, estimate_delay_design, report_size

    design = estimate_delay_design(system, setup.max_delay, setup.horizon, max_lost=setup.max_lost, mu1_free=True,
                                   workers=1)
    N, scale = setup.steps, (system.n / 4) ** 2
    per_run = scale * (SECONDS_PER_STEP * N + SECONDS_PER_STEP2 * N ** 2)
    runs_seconds = setup.runs * per_run
    memory = max(design.memory, 2e8 + 8.0 * system.n * N ** 2 + 8.0 * 16 * setup.runs * N * system.n)
    what = (f"the designs ({design.classes} classes) and {setup.runs} runs of {N} steps "
            f"(about {per_run:.2g} s a run)")
    if design.seconds > runs_seconds:
        field = "--horizon"
    else:
        field = "--periods" if SECONDS_PER_STEP2 * N > SECONDS_PER_STEP * 10 and setup.periods > 10 else "--runs"
    report_size(SetEstimate(what, design.seconds + runs_seconds, memory), force=force, field=field,
                source="command line", advice="fewer --runs or --periods, or a shorter --horizon or --max-delay")


def run(args: argparse.Namespace) -> str:
    """Run ``eqrec compare`` (nothing is written unless everything succeeds).

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments.

    Returns
    -------
    str
        The table, formatted for reading.

    Raises
    ------
    InputError, InfeasibleDesign, SolverFailure, CertificationFailure
        As the designs and the inputs (the CLI maps them to its exit codes).
    """
    import yaml

    from eqrec.compare.families import CompareSetup, compare_families, write_table
    from eqrec.compare.figure import compare_figure
    from eqrec.systems.files import load_system

    out = _out_dir(args.out)
    setup = CompareSetup(loss=args.loss, max_delay=args.max_delay, horizon=args.horizon, runs=args.runs,
                         periods=args.periods, burst=args.burst, seed=args.seed, coverage=args.coverage,
                         exact_runs=getattr(args, "exact_runs", 4))
    system, T_file = load_system(args.system)
    if T_file is not None and T_file != args.horizon:  # as eqrec design: the file's T is the designs' horizon
        raise InputError(f"T = {T_file} in the system file but --horizon {args.horizon}", args.system, "T")
    check_size(system, setup, force=getattr(args, "force", False))
    with open(args.system, encoding="utf-8") as fh:
        gaussian = (yaml.safe_load(fh) or {}).get("gaussian")
    if gaussian is not None and not isinstance(gaussian, dict):
        raise InputError("must be a mapping with some of Qw, Qv, x0_cov", args.system, "gaussian")
    talk = sys.stderr.isatty()
    weights = None
    if args.state_weights is not None:
        try:
            weights = [float(x) for x in args.state_weights.split(",")]
        except ValueError:
            raise InputError(f"comma-separated numbers, got {args.state_weights!r}", field="--state-weights") \
                from None
        if len(weights) != system.n:
            raise InputError(f"{system.n} weights (one per state), got {len(weights)}", field="--state-weights")
    from eqrec.design.inputs import size_check_done

    with size_check_done():  # the designs were estimated with the runs (check_size)
        result = compare_families(system, setup, gaussian=gaussian, solver=args.solver, state_weights=weights,
                                  progress=(lambda line: print(f"  {line}", file=sys.stderr)) if talk else None)
    out.mkdir(exist_ok=True)
    write_table(result, str(out / "compare.csv"))
    compare_figure(result, str(out / "compare.png"), str(out / "compare.pdf"))
    shown = result.table[["estimator", "rms", "max_error", "bound", "violations", "outside_design",
                          "bound_over_limit_median", "bound_over_limit_p95", "hull_over_exact_median"]].astype(object)
    shown = shown.assign(us_per_step=[round(result.us_per_step.get(f, float("nan")), 1)
                                      for f in result.table["estimator"]])
    shown = shown.rename(columns={"bound_over_limit_median": "b/lim_med", "bound_over_limit_p95": "b/lim_p95",
                                  "hull_over_exact_median": "hull/exact_med"})
    return shown.where(shown.notna(), "-").to_string(index=False, float_format=lambda v: f"{v:.4g}")
