"""Command line: design, certify and simulate equalized-recovery estimators for your own system.

Examples
--------
::

    eqrec design system.yaml --words 101111,110111,111011,111101 --method prefix --mu1 1 --out design.json
    eqrec design system.yaml --words 101111,110111 --method time --solver clarabel
    eqrec design system.yaml --words 101111,110111 --method augmented --L free
    eqrec design system.yaml --method delay --delays 21210,00000 --mu1 free --out design.json
    eqrec design system.yaml --method delay --max-delay 2 --horizon 5 --mu1 0.33 --cost max
    eqrec design system.yaml --method delay --max-delay 4 --horizon 30 --mu1 free --out design.json
    eqrec design system.yaml --method delay --max-delay 2 --horizon 5 --engine tree --node-gains
    eqrec compare system.yaml --loss 0.1 --max-delay 2 --horizon 5 --runs 50 --out cmp

Exit status: 0 on success, 1 for malformed input (the message names the file
and field), 2 for a usage error (argparse), 3 for an infeasible or unbounded
design (nothing is written), 4 for a solver or certification failure.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
from collections import Counter
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from eqrec.arrivals.words import MAX_DELAY
from eqrec.lp.solvers import SOLVER_NAMES, retry_log
from eqrec.design.inputs import ESTIMATE_PRINT_SECONDS, MAX_ESTIMATED_SECONDS, MAX_MEMORY_FRACTION, UNSTABLE_GROWTH
from eqrec.errors import CertificationFailure, InfeasibleDesign, InputError, SolverFailure
from eqrec.cli_help import SYSTEM_HELP
from eqrec.io import write_text

if TYPE_CHECKING:
    from eqrec.design.result import Design

EXIT_INPUT, EXIT_USAGE, EXIT_INFEASIBLE, EXIT_SOLVER = 1, 2, 3, 4
#: Seconds the search for the longest horizon that solves may take in all (:func:`_unstable_hint`; the default of
#: :func:`eqrec.longest_horizon`, :data:`eqrec.design.delay.horizon.HORIZON_SEARCH_SECONDS`).
HORIZON_SEARCH_SECONDS = 120.0
#: Largest recovery level the LPs take reliably (HiGHS refuses bounds near 1e15).  The class engine certifies
#: designs up to it (class levels raised by the LP's round-off times mu1: under 0.5 % at 1e12 on the example
#: plants); the tree LP may stop earlier (a solver failure naming the class engine).
MAX_MU1 = 1e12
#: Largest full delay language ``{0..D}^T`` (words) that ``--node-gains`` or ``--engine tree`` enumerate.
MAX_ENUMERATED_WORDS = 20_000
ENGINES = ("classes", "tree")
#: The methods that take ``--mu1 free`` (the class engine's μ1-free theorem covers every prefix tree).
FREE_METHODS = ("prefix", "time", "delay")
#: ``eqrec.design.report.JSON_NODE_GAINS_LIMIT``, for the help text without importing the design modules (a test
#: checks they agree).
JSON_NODE_GAINS_SEQUENCES = 200
EXIT_HELP = ("Exit status: 0 ok; 1 malformed input (file and field named); 2 usage error; "
             "3 infeasible or unbounded design (no file written); 4 solver or certification failure.")



def raise_note(requested: float, raised: float) -> str:
    """``mu1 raised from the requested a to b``, with enough digits that ``a`` and ``b`` differ, and by how much.

    Parameters
    ----------
    requested, raised : float
        The requested and the certified recovery level.

    Returns
    -------
    str
        E.g. ``mu1 raised from the requested 0.203903307 to 0.203903307000003 (by 3e-15, relative 1.5e-14)``.
    """
    digits = next((d for d in range(9, 18) if f"{requested:.{d}g}" != f"{raised:.{d}g}"), 17)
    return (f"mu1 raised from the requested {requested:.{digits}g} to {raised:.{digits}g} (by {raised - requested:.2g}, "
            f"relative {(raised - requested) / requested:.2g})")


def _system_help() -> str:
    return SYSTEM_HELP % {"limit": MAX_ENUMERATED_WORDS, "seq": JSON_NODE_GAINS_SEQUENCES,
                          "print": ESTIMATE_PRINT_SECONDS, "minutes": MAX_ESTIMATED_SECONDS / 60,
                          "mem": 100 * MAX_MEMORY_FRACTION}


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="eqrec",
        description="Equalized-recovery estimators with missing data: design (LP / IPOPT), certify "
                    "the gains independently, and write them as JSON.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog=EXIT_HELP)
    from eqrec import __version__

    ap.add_argument("--version", action="version", version=f"eqrec {__version__}")
    sub = ap.add_subparsers(dest="command", required=True)
    from eqrec.compare.command import add_parser as add_compare_parser

    add_compare_parser(sub, EXIT_HELP)
    d = sub.add_parser("design", help="design and certify an estimator for a system file",
                       description="Minimise the intermediate level mu2 for a given recovery level mu1, "
                                   "recover the gains, certify them from the gains alone, write JSON.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=_system_help() + "\n" + EXIT_HELP)
    d.add_argument("system", help="system YAML file (keys below)")
    d.add_argument("--words", default=None,
                   help="comma-separated words of the missing-data language, e.g. 101111,110111 "
                        "(methods time, prefix, augmented)")
    d.add_argument("--method", choices=tuple(DESIGN_METHODS), default="prefix",
                   help="time: one gain sequence for the worst-case word (bitwise AND); prefix: gains chosen "
                        "by the observed prefix (prefix-based paper); augmented: state-augmented estimator "
                        "(augmented paper); delay: delayed and missing data, gains per event prefix and a "
                        "level per prefix and time (delayed-data paper). Default: prefix")
    d.add_argument("--mu1", default="1",
                   help="recovery level mu1 (default 1); with --method prefix, time or delay also 'free': the "
                        "smallest feasible mu1 (the class engine's mu1-free theorem, one Charnes-Cooper LP, "
                        "certified by a bracket; every level is nondecreasing in mu1, so it is also the global "
                        "optimum of mu2 and of the delay method's J, with a certified lower bound of J)")
    d.add_argument("--delays", default=None,
                   help="delay only: comma-separated delay words, e.g. 21210,00000")
    d.add_argument("--max-delay", type=int, default=None,
                   help=f"delay only: with --horizon, design for all delay words with delays 0..D (D <= {MAX_DELAY}: "
                        "one digit per delay, as in delay words)")
    d.add_argument("--horizon", type=int, default=None, help="delay only: word length T for --max-delay")
    d.add_argument("--max-lost", type=int, default=None,
                   help="delay only, with --max-delay and --horizon: at most m (0..T) measurements lost per block "
                        "besides the delays 0..D (a lost one never arrives; a delay past the block's end is not a "
                        "loss); default: none lost")
    d.add_argument("--engine", choices=ENGINES, default=None,
                   help="prefix and delay only: classes = one small LP per (time, available data) class "
                        "(default; --max-delay languages without enumerating words); tree = one LP over the "
                        "prefix tree (the cross-check; needs the words)")
    d.add_argument("--node-gains", action="store_true",
                   help="delay only: write node gains, levels per event prefix and event sequences (default: "
                        "only for small languages); needs the words enumerated (refused above "
                        f"{MAX_ENUMERATED_WORDS} words)")
    d.add_argument("--cost", choices=("sum", "max"), default=None,
                   help="delay only: sum = the paper's J = mu1 + sum_k sum_alpha mu2_k^alpha (default); "
                        "max = the largest level")
    d.add_argument("--solver", choices=SOLVER_NAMES, default="highs",
                   help="LP solver of the registry (default highs; ipopt is an interior-point NLP solver)")
    d.add_argument("--L", dest="L", default=None,
                   help="augmented only: 'free' (IPOPT over L and s0) or a JSON n x p matrix")
    d.add_argument("--poles", default=None,
                   help="augmented only: comma-separated poles of A - L C, real or complex in Python "
                        "notation, e.g. 0,0.3+0.2j,0.3-0.2j (default: n distinct poles in [-0.5, 0.5])")
    d.add_argument("--s0", default=None, help="augmented only: JSON vector s0 (default zeros)")
    d.add_argument("--state-weights", default=None,
                   help="time, prefix and delay: comma-separated positive weights w_1,...,w_n, one per state: the "
                        "guarantee is then on max_i w_i |x_i - xhat_i| (a state vector of mixed units gets a "
                        "meaningful norm); the JSON's gains stay in the file's coordinates")
    d.add_argument("--jobs", type=int, default=None,
                   help="prefix and delay: worker processes for the class LPs of a large language, solved per "
                        "class (default: every core; 1: in this process); the result does not depend on it")
    d.add_argument("--scheduler", default=None,
                   help="prefix and delay: a Dask scheduler address, e.g. tcp://host:8786, whose workers solve the "
                        "class LPs instead (needs pip install 'eqrec[dask]'); the same result as on this machine")
    d.add_argument("--out", default=None, help="output JSON file (default: print to stdout)")
    d.add_argument("--force", action="store_true",
                   help="delay with --max-delay: run a design past the documented size (estimated time over "
                        f"{MAX_ESTIMATED_SECONDS / 60:.0f} min or memory over {100 * MAX_MEMORY_FRACTION:.0f}%% of the "
                        "available; the estimate is printed either way, and refused otherwise with exit 1)")
    return ap


def _parallel(args: argparse.Namespace) -> dict:
    """``--jobs`` and ``--scheduler`` as the design functions' ``n_jobs`` and ``scheduler`` (checked)."""
    from eqrec.lp.parallel import check_jobs, check_reachable, check_scheduler

    def check_address(scheduler):  # reachable whatever the size of the design (a small one never contacts it)
        check_reachable(check_scheduler(scheduler))

    par = {"n_jobs": args.jobs, "scheduler": args.scheduler}
    for flag, key, check in (("--jobs", "n_jobs", check_jobs), ("--scheduler", "scheduler", check_address)):
        if par[key] is not None and args.method not in ("prefix", "delay"):
            raise InputError(f"{flag} applies to --method prefix and delay only", "command line", flag)
        try:
            check(par[key])
        except InputError as exc:
            raise InputError(str(exc).split(": ", 1)[-1], "command line", flag) from None
    return par


def _split_words(text: str, flag: str) -> list[str]:
    """``--words`` / ``--delays``: comma-separated words, none empty (a stray comma) and none given twice."""
    words = [w.strip() for w in text.split(",")]
    empty = [i + 1 for i, w in enumerate(words) if not w]
    if empty:
        raise InputError(f"word {empty[0]} of {len(words)} is empty (a stray comma?) in {text!r}", "command line",
                         flag)
    twice = sorted({w for w in words if words.count(w) > 1})
    if twice:
        raise InputError(f"{', '.join(twice)} given more than once in {text!r}", "command line", flag)
    return words


def _parse_json_array(text: str, field: str) -> np.ndarray:
    try:
        return np.asarray(json.loads(text), dtype=float)
    except (json.JSONDecodeError, TypeError, ValueError) as exc:
        raise InputError(f"not a JSON number array ({exc})", "command line", field) from None


def _parse_weights(text: str | None, n: int) -> np.ndarray | None:
    """``--state-weights``: ``n`` positive finite numbers, comma-separated (``None``: not given)."""
    if text is None:
        return None
    try:
        weights = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise InputError(f"must be comma-separated numbers, got {text!r}", "command line", "--state-weights") from None
    if weights.shape != (n,) or not np.all(np.isfinite(weights)) or np.any(weights <= 0):
        raise InputError(f"need n = {n} positive finite weights, one per state, got {text!r}", "command line",
                         "--state-weights")
    return weights


def run_design(args: argparse.Namespace) -> dict:
    """Design, certify and describe one estimator (the ``design`` subcommand): the checks every method shares, then
    the method's entry of :data:`DESIGN_METHODS`."""
    from eqrec.systems.files import load_system

    system, T_file = load_system(args.system)
    mu1 = _parse_mu1(args.mu1, allow_free=args.method in FREE_METHODS)
    if args.method == "augmented" and args.state_weights is not None:
        raise InputError("--state-weights applies to --method time, prefix and delay", "command line",
                         "--state-weights")
    weights = _parse_weights(args.state_weights, system.n)
    par = _parallel(args)
    return DESIGN_METHODS[args.method](args, system, T_file, mu1, weights, par)


def _design_prefix(args: argparse.Namespace, system, words: list, weights: np.ndarray | None,
                   par: dict) -> tuple[Design, dict]:
    """``--method prefix``: the prefix-based design (class engine or tree LP); no entries of its own."""
    from eqrec.design.prefix.design import design_prefix

    design = design_prefix(system, words, args.mu1, solver=args.solver, engine=args.engine or "classes",
                           state_weights=weights, **par)
    return design, {}


def _design_time(args: argparse.Namespace, system, words: list, weights: np.ndarray | None,
                 par: dict) -> tuple[Design, dict]:
    """``--method time``: one gain sequence for the worst-case word."""
    from eqrec.design.prefix.time_based import design_time_based

    design = design_time_based(system, words, args.mu1, solver=args.solver, state_weights=weights)
    return design, {}


def _design_augmented(args: argparse.Namespace, system, words: list, weights: np.ndarray | None,
                      par: dict) -> tuple[Design, dict]:
    """``--method augmented``: the state-augmented design (``--L``, ``--poles``, ``--s0`` read here); its ``L``,
    ``s0``, ``M``, ``nu`` written after the words."""
    from eqrec.design.augmented.design import design_augmented

    L = None
    if args.L is not None:
        L = "free" if args.L.strip() == "free" else _parse_json_array(args.L, "--L")
    poles = None
    if args.poles is not None:
        try:
            poles = [complex(p) for p in args.poles.split(",")]
        except ValueError:
            raise InputError("poles must be numbers, e.g. 0,0.5,-0.2", "command line", "--poles") from None
    s0 = None if args.s0 is None else _parse_json_array(args.s0, "--s0")
    design = design_augmented(system, words, args.mu1, L=L, poles=poles, s0=s0, solver=args.solver)
    aug = design.augmented
    head = {k: np.asarray(v).tolist() for k, v in (("L", aug.L), ("s0", aug.s0), ("M", aug.M), ("nu", aug.nu))}
    return design, head


def run_word_design(args: argparse.Namespace, system, T_file: int | None, mu1: float | str,
                    weights: np.ndarray | None, par: dict, method) -> dict:
    """A design of a missing-data language given in ``--words`` (``--method prefix``, ``time``, ``augmented``).

    The checks these methods share, then ``method(args, system, words, weights, par)``, which returns the design
    and the JSON entries of its own: ``head`` (after the words) and ``tail`` (after the gains).
    """
    from eqrec.arrivals.words import validate_language

    for flag, value in (("--delays", args.delays), ("--max-delay", args.max_delay), ("--horizon", args.horizon),
                        ("--max-lost", args.max_lost), ("--cost", args.cost),
                        ("--node-gains", args.node_gains or None), ("--force", getattr(args, "force", None) or None)):
        if value is not None:
            raise InputError(f"{flag} applies to --method delay only" +
                             (" (the other methods always write their gains)" if flag == "--node-gains" else ""),
                             "command line", flag)
    if args.engine is not None and args.method not in ("prefix", "delay"):
        raise InputError(f"--engine applies to --method prefix and delay only, not {args.method}", "command line",
                         "--engine")
    if args.words is None:
        raise InputError(f"--method {args.method} needs --words", "command line", "--words")
    args.mu1 = mu1
    words = validate_language(_split_words(args.words, "--words"), source="command line", field_name="--words")
    T = T_file if T_file is not None else len(words[0])
    validate_language(words, length=T, source="command line" if T_file is None else args.system,
                      field_name="--words" if T_file is None else "T")
    if args.method != "augmented" and (args.L or args.poles or args.s0):
        raise InputError("--L, --poles and --s0 apply to --method augmented only", "command line", "--method")
    design, head = method(args, system, words, weights, par)
    from eqrec.design.report import design_json

    # the same record as Design.save: the gains in the file's coordinates, the system as the file gave it
    return design_json(design, words=list(words), head=head, original=system)


def _parse_mu1(text: str, *, allow_free: bool) -> float | str:
    """``--mu1``: a finite number (at most :data:`MAX_MU1` in magnitude) or, for :data:`FREE_METHODS`, ``free``."""
    if text.strip().lower() == "free":
        if not allow_free:
            raise InputError(f"'free' applies to --method {', '.join(FREE_METHODS)} only; give a number",
                             "command line", "--mu1")
        return "free"
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"must be a number{' or free' if allow_free else ''}, got {text!r}",
                         "command line", "--mu1") from None
    if not np.isfinite(value) or abs(value) > MAX_MU1:
        raise InputError(f"must be a finite number of magnitude at most {MAX_MU1:g} (double-precision LP), "
                         f"got {value:g}", "command line", "--mu1")
    if value <= 0:
        raise InputError(f"must be positive, got {value:g}", "command line", "--mu1")
    return value


def run_delay_design(args: argparse.Namespace, system, T_file: int | None, mu1: float | str,
                     weights: np.ndarray | None = None, par: dict | None = None) -> dict:
    """The delayed-data design (``--method delay``): Theorem 1 / Proposition 1 of the delayed-data paper."""
    from decimal import Decimal

    from eqrec.bounds.data_classes import ClassSet, full_language_counts
    from eqrec.arrivals.words import as_language
    from eqrec.design.delay.design import delay_classes, delay_language
    from eqrec.design.inputs import size_check_done
    from eqrec.design.report import JSON_NODE_GAINS_LIMIT, design_json

    if args.words is not None:
        raise InputError("--method delay takes delay words in --delays (digits), not --words", "command line",
                         "--words")
    if args.L or args.poles or args.s0:
        raise InputError("--L, --poles and --s0 apply to --method augmented only", "command line", "--method")
    engine = args.engine or "classes"
    full = args.max_delay is not None or args.horizon is not None
    if args.max_lost is not None and not full:
        raise InputError("--max-lost goes with --max-delay and --horizon (delay words given in --delays write a "
                         "loss as a delay past the horizon)", "command line", "--max-lost")
    if (args.delays is None) == (not full):
        raise InputError("give either --delays W1,W2,... or both --max-delay and --horizon", "command line",
                         "--delays")
    if full:
        if args.max_delay is None or args.horizon is None:
            raise InputError("--max-delay and --horizon go together", "command line",
                             "--horizon" if args.horizon is None else "--max-delay")
        if not 0 <= args.max_delay <= MAX_DELAY:
            raise InputError(f"must be 0..{MAX_DELAY} (one digit per delay), got {args.max_delay}", "command line",
                             "--max-delay")
        if args.horizon < 1:
            raise InputError(f"must be at least 1, got {args.horizon}", "command line", "--horizon")
        if T_file is not None and T_file != args.horizon:
            raise InputError(f"T = {T_file} in the system file but --horizon {args.horizon}", args.system, "T")
        lost = args.max_lost
        if lost is not None and not 0 <= lost <= args.horizon:
            raise InputError(f"must be 0..{args.horizon} (the horizon), got {lost}", "command line", "--max-lost")
        if engine == "classes":  # with --max-lost too: the same size model (eqrec.design.inputs.class_shape)
            _check_size(args, system, mu1 == "free", par or {})
        n_words = full_language_counts(args.horizon, args.max_delay, lost)["words"]
        size = (f"{{0..{args.max_delay}}}^{args.horizon}" + (f" with at most {lost} lost" if lost is not None else "")
                + f" has {Decimal(n_words):.3g} words, more than the {MAX_ENUMERATED_WORDS} that can be enumerated")
        if args.node_gains and n_words > MAX_ENUMERATED_WORDS:
            raise InputError(f"node gains need the prefix tree of every word: {size}; drop --node-gains (the "
                             "JSON holds the class gains K)", "command line", "--node-gains")
        if engine == "tree" and n_words > MAX_ENUMERATED_WORDS:
            raise InputError(f"the tree engine needs every word: {size}; use --engine classes", "command line",
                             "--engine")
        # the words are enumerated for the tree engine, node gains, or a language small enough that its node
        # gains are written by default (to_json); otherwise the classes come from the window rule
        enumerate_words = (args.node_gains or engine == "tree" or (
            n_words <= MAX_ENUMERATED_WORDS
            and full_language_counts(args.horizon, args.max_delay, lost)["sequences"] <= JSON_NODE_GAINS_LIMIT))
        with size_check_done() if engine == "classes" else contextlib.nullcontext():  # checked above
            if enumerate_words:  # at most MAX_ENUMERATED_WORDS words
                patterns = delay_language(max_delay=args.max_delay, horizon=args.horizon, max_lost=lost,
                                          source="command line")
            else:
                patterns = delay_classes(max_delay=args.max_delay, horizon=args.horizon, max_lost=lost)
    else:
        if getattr(args, "force", False):
            raise InputError("--force applies to --max-delay and --horizon (delay words given in --delays are "
                             "solved whatever their number)", "command line", "--force")
        if not args.delays.strip():
            raise InputError("no delay words given", "command line", "--delays")
        words = _split_words(args.delays, "--delays")
        patterns = as_language(words, kind="delay", field_name="--delays", source="command line")
        if T_file is not None and patterns[0].T != T_file:
            raise InputError(f"T = {T_file} in the system file but the delay words have length {patterns[0].T}",
                             args.system, "T")
    cost = args.cost or "sum"
    node_gains = True if args.node_gains else None
    with size_check_done() if full and engine == "classes" else contextlib.nullcontext():  # checked above
        design, free = _run_delay(args, system, patterns, mu1, cost, engine, node_gains, weights, par)
    words = [p.label for p in patterns] if not isinstance(patterns, ClassSet) else None
    # the same record as Design.save (eqrec.design.report.design_json), with the command's own entries
    out = design_json(design, free=free, node_gains=node_gains, words=words, original=system)
    system_entry = out.pop("system")
    if full:
        out.update(max_delay=args.max_delay, horizon=args.horizon)
        if args.max_lost is not None:
            out["max_lost"] = args.max_lost
    if isinstance(patterns, ClassSet):  # classes from the window rule: no word enumerated
        out["words"] = int(patterns.words)
    out["system"] = system_entry
    return out


def _run_delay(args: argparse.Namespace, system, patterns, mu1, cost: str, engine: str, node_gains, weights,
               par: dict | None):
    """The delay design itself (μ1 fixed or free): the design and the μ1-free result (or ``None``)."""
    from eqrec.design.delay.design import design_delay, design_delay_global

    if mu1 == "free":
        free = design_delay_global(system, patterns, kind="delay", cost=cost, solver=args.solver,
                                   node_gains=node_gains, engine=engine, state_weights=weights, **(par or {}))
        return free.design, free
    design = design_delay(system, patterns, mu1, kind="delay", cost=cost, solver=args.solver, engine=engine,
                          node_gains=node_gains, state_weights=weights, **(par or {}))
    return design, None


#: ``--method``: the function that designs with it, from the loaded system, its ``T`` (or ``None``), the parsed
#: ``--mu1``, ``--state-weights`` and the parallel options; it returns the JSON of the design.
DESIGN_METHODS = {
    "time": partial(run_word_design, method=_design_time),
    "prefix": partial(run_word_design, method=_design_prefix),
    "augmented": partial(run_word_design, method=_design_augmented),
    "delay": run_delay_design,
}


def _check_size(args: argparse.Namespace, system, mu1_free: bool, par: dict) -> None:
    """Print the estimate of a long ``--max-delay`` design; refuse one past the documented size unless ``--force``."""
    from eqrec.design.inputs import estimate_delay_design, report_size
    from eqrec.lp.parallel import check_jobs

    workers = 1 if par.get("scheduler") is not None else check_jobs(par.get("n_jobs"))
    est = estimate_delay_design(system, args.max_delay, args.horizon, max_lost=args.max_lost, mu1_free=mu1_free,
                                workers=workers)
    report_size(est, force=args.force, field="--horizon", source="command line",
                advice="shorten --horizon or --max-delay" + (" or lower --max-lost" if args.max_lost else ""))


def _probe_design(args: argparse.Namespace, seconds: float) -> tuple[str, str]:
    """One design of the horizon search in a child process, stopped after ``seconds``: ``("solves" | "fails" |
    "no answer", failure message)`` (:func:`eqrec.design.delay.horizon.probe_in_child`: a solver that does not
    return in time is stopped, so the search stays bounded)."""
    from eqrec.design.delay.horizon import probe_in_child

    def run() -> None:
        with retry_log():
            run_design(args)

    return probe_in_child(run, seconds)


def _unstable_hint(args: argparse.Namespace, max_tries: int = 8, budget: float | None = None, *,
                   suspect: bool = False) -> str:
    """For a failed ``--horizon`` design of an unstable plant: the longest horizon that solves, found by bisection.

    Every error map of the horizon grows like ``ρ^T`` (``ρ`` the spectral radius of ``A``): past about
    ``log(1e8) / log ρ`` steps its entries span more than a double-precision LP resolves
    (:func:`eqrec.design.inputs.growth_hint`).  The search (:func:`eqrec.design.delay.horizon.search_horizon`, the
    one of :func:`eqrec.longest_horizon`) starts there and halves the interval between a horizon that solved and
    one that did not: at most ``max_tries`` designs and ``budget`` seconds in all, announced first (default
    :data:`HORIZON_SEARCH_SECONDS`).  Each design is estimated first
    (:func:`eqrec.design.inputs.estimate_delay_design`) and skipped when its estimate exceeds the time left; one
    that runs past the time left is stopped and counts as failed; each is printed.  Empty when ``ρ^T`` is below
    :data:`UNSTABLE_GROWTH` (``suspect``, after a design found infeasible: below
    :data:`~eqrec.design.inputs.RESOLVED_GROWTH`), without ``--horizon``, or with ``T`` in the system file.
    """
    import copy

    from eqrec.design.delay.horizon import search_horizon, spectral_radius
    from eqrec.design.inputs import estimate_delay_design, growth_hint
    from eqrec.systems.files import load_system

    if getattr(args, "command", None) != "design" or getattr(args, "horizon", None) is None:
        return ""
    try:
        system, T_file = load_system(args.system)
    except (InputError, ValueError):
        return ""
    rho = spectral_radius(system)
    budget = HORIZON_SEARCH_SECONDS if budget is None else budget
    reason = growth_hint(system, args.horizon, suspect=suspect)
    head = reason.split("; horizons up to")[0]
    if T_file is not None or not head or not rho > 1:
        return ""

    def probe_args(T: int) -> argparse.Namespace:
        probe = copy.copy(args)
        probe.horizon, probe.out, probe.jobs, probe.scheduler = T, None, 1, None
        return probe

    def estimate(T: int) -> float:
        if args.max_delay is None:
            return 0.0
        return estimate_delay_design(system, args.max_delay, T, max_lost=args.max_lost,
                                     mu1_free=str(args.mu1).strip().lower() == "free").seconds

    found = search_horizon(lambda T, seconds: _probe_design(probe_args(T), seconds), int(args.horizon), rho,
                           estimate=estimate, budget=budget, max_tries=max_tries, flag="--horizon ", reason=reason)
    return head + "; " + found.summary("--horizon ")


def _print_hint(exc: Exception, hint: str) -> None:
    """Print the horizon search's answer, without the reason when the design's message gave it already
    (:func:`eqrec.design.inputs.growth_hint`)."""
    head = hint.split("; ")[0]
    if hint and head in str(exc):
        hint = hint[len(head) + 2:]
    if hint:
        print(f"eqrec: {hint}", file=sys.stderr)


def _check_out(out: str | None) -> Path | None:
    """Check the output path before any design work: its folder exists and it is not a folder."""
    if out is None:
        return None
    path = Path(out)
    if path.is_dir():
        raise InputError("is a directory; give a file name for the JSON", str(path), "--out")
    if not path.parent.is_dir():
        raise InputError(f"folder {path.parent} does not exist", str(path), "--out")
    return path


def _write_atomic(path: Path, text: str) -> None:
    try:
        write_text(path, text)  # a temporary file beside it, then os.replace; removed on failure
    except OSError as exc:
        raise InputError(f"cannot write ({exc.strerror})", str(path), "--out") from None


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.command == "compare":
            from eqrec.compare.command import run as run_compare

            print(run_compare(args))
            return 0
        out_path = _check_out(args.out)
        with retry_log() as retried:
            result = run_design(args)
        if retried:  # which solve answered the LPs the first one did not (solve_lp's retries)
            result["solver_retries"] = dict(Counter(retried))
        text = json.dumps(result, indent=2)
        if out_path is not None:
            _write_atomic(out_path, text + "\n")
    except InputError as exc:
        print(f"eqrec: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except InfeasibleDesign as exc:
        print(f"eqrec: infeasible: {exc}", file=sys.stderr)
        _print_hint(exc, _unstable_hint(args, suspect=True))  # past what an LP resolves: maybe the solver's verdict
        return EXIT_INFEASIBLE
    except (SolverFailure, CertificationFailure) as exc:
        print(f"eqrec: failed: {exc}", file=sys.stderr)
        _print_hint(exc, _unstable_hint(args))
        return EXIT_SOLVER
    if "mu1_requested" in result:
        print(f"eqrec: note: {raise_note(result['mu1_requested'], result['mu1'])}, the smallest level these gains "
              "certify (the LP meets its bound only to its tolerance)", file=sys.stderr)
    if retried:
        print(f"eqrec: note: {len(retried)} LP(s) had no usable status at the first solve and were answered by "
              + ", ".join(f"{k} ({v})" for k, v in result["solver_retries"].items()), file=sys.stderr)
    if out_path is not None:
        print(f"mu1 = {result['mu1']:.6g}, mu2 = {result['mu2']:.6g} (certified {result['certified_mu2']:.6g}); "
              f"wrote {out_path}", file=sys.stderr)
    else:
        try:
            print(text)
            sys.stdout.flush()
        except BrokenPipeError:  # the reader left (eqrec design ... | head): the design itself succeeded
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    return 0


if __name__ == "__main__":
    sys.exit(main())
