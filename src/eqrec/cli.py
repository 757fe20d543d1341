"""Command line: design, certify and simulate equalized-recovery estimators for your own system.

Examples
--------
::

    eqrec design system.yaml --words 101111,110111,111011,111101 --method prefix --mu1 1 --out design.json
    eqrec design system.yaml --words 101111,110111 --method time --solver clarabel
    eqrec design system.yaml --words 101111,110111 --method augmented --L free

Exit status: 0 on success, 1 for malformed input (the message names the file
and field), 2 for a usage error (argparse), 3 for an infeasible or unbounded
design (nothing is written), 4 for a solver or certification failure.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from eqrec.core.solvers import SOLVER_NAMES
from eqrec.errors import CertificationFailure, InfeasibleDesign, InputError, SolverFailure

EXIT_INPUT, EXIT_USAGE, EXIT_INFEASIBLE, EXIT_SOLVER = 1, 2, 3, 4
#: Largest recovery level the LPs take reliably (HiGHS refuses bounds near 1e15).
MAX_MU1 = 1e12
EXIT_HELP = ("Exit status: 0 ok; 1 malformed input (file and field named); 2 usage error; "
             "3 infeasible or unbounded design (no file written); 4 solver or certification failure.")

SYSTEM_HELP = """\
SYSTEM.yaml keys (matrices as nested lists):
  A      n x n state matrix                       (required)
  C      p x n output matrix                      (required)
  E      n x nw process-noise gain                (required)
  eta_w  bound on |w(t)|_inf                      (required)
  eta_v  bound on |v(t)|_inf                      (required)
  T      recovery time (default: the word length)
  B, f   input matrix and affine term (do not affect the design)
  V      p x nv measurement-noise gain (default identity)

Words are strings over {0,1}: character t is 1 if the measurement of time t
(0-based) arrives, 0 if it is missing; all words must have length T.

Output JSON: method, mu1, mu2 (optimum), certified_mu2 (worst case recomputed
from the gains alone), solver, status, words, gains: for each designed word
{"F": (T*n x T*p), "u0": (T*n)} in the convention
  ue(t) = u0(t) + sum_{tau<=t} F(t,tau) y_xi(tau),
  xhat(t+1) = A xhat + B u - ue + f,
  y_xi(tau) = y(tau) - C xhat(tau) if available, else 0.
"""


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
    d = sub.add_parser("design", help="design and certify an estimator for a system file",
                       description="Minimise the intermediate level mu2 for a given recovery level mu1, "
                                   "recover the gains, certify them from the gains alone, write JSON.",
                       formatter_class=argparse.RawDescriptionHelpFormatter, epilog=SYSTEM_HELP + "\n" + EXIT_HELP)
    d.add_argument("system", help="system YAML file (keys below)")
    d.add_argument("--words", required=True,
                   help="comma-separated words of the missing-data language, e.g. 101111,110111")
    d.add_argument("--method", choices=("time", "prefix", "augmented"), default="prefix",
                   help="time: one gain sequence for the worst-case word (bitwise AND); prefix: gains chosen "
                        "by the observed prefix (prefix-based paper); augmented: state-augmented estimator "
                        "(augmented paper). Default: prefix")
    d.add_argument("--mu1", type=float, default=1.0, help="recovery level M1 (default 1)")
    d.add_argument("--solver", choices=SOLVER_NAMES, default="highs",
                   help="LP solver of the registry (default highs; ipopt is an interior-point NLP solver)")
    d.add_argument("--L", dest="L", default=None,
                   help="augmented only: 'free' (IPOPT over L and s0) or a JSON n x p matrix")
    d.add_argument("--poles", default=None,
                   help="augmented only: comma-separated poles of A - L C, real or complex in Python "
                        "notation, e.g. 0,0.3+0.2j,0.3-0.2j (default: n distinct poles in [-0.5, 0.5])")
    d.add_argument("--s0", default=None, help="augmented only: JSON vector s0 (default zeros)")
    d.add_argument("--out", default=None, help="output JSON file (default: print to stdout)")
    return ap


def _parse_json_array(text: str, field: str) -> np.ndarray:
    try:
        return np.asarray(json.loads(text), dtype=float)
    except (json.JSONDecodeError, TypeError, ValueError) as exc:
        raise InputError(f"not a JSON number array ({exc})", "command line", field) from None


def run_design(args: argparse.Namespace) -> dict:
    """Design, certify and describe one estimator (the ``design`` subcommand)."""
    from eqrec.design.prefix import design_prefix
    from eqrec.design.time_based import design_time_based
    from eqrec.core.patterns import validate_language
    from eqrec.core.systems import load_system

    system, T_file = load_system(args.system)
    if not np.isfinite(args.mu1) or abs(args.mu1) > MAX_MU1:
        raise InputError(f"must be a finite number of magnitude at most {MAX_MU1:g} (double-precision LP), "
                         f"got {args.mu1:g}", "command line", "--mu1")
    words = validate_language([w for w in args.words.split(",") if w.strip()], source="command line",
                              field_name="--words")
    T = T_file if T_file is not None else len(words[0])
    validate_language(words, length=T, source="command line" if T_file is None else args.system,
                      field_name="--words" if T_file is None else "T")
    if args.method != "augmented" and (args.L or args.poles or args.s0):
        raise InputError("--L, --poles and --s0 apply to --method augmented only", "command line", "--method")
    extra = {}
    if args.method == "prefix":
        design = design_prefix(system, words, args.mu1, solver=args.solver)
    elif args.method == "time":
        design = design_time_based(system, words, args.mu1, solver=args.solver)
    else:
        try:
            from eqrec.design.augmented import design_augmented
        except ImportError:  # pragma: no cover - depends on the P2 module being present
            raise InputError("the augmented design is not available in this installation",
                             "command line", "--method") from None
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
        extra = {k: (np.asarray(v).tolist() if v is not None else None) for k, v in design.extra.items()
                 if k in ("L", "s0", "M", "nu")}
    cert = design.certificate
    out = {"method": args.method, "mu1": design.M1, "mu2": design.mu2, "certified_mu2": cert.mu2,
           "certified_terminal": cert.terminal, "solver": design.solution.solver, "status": design.solution.status,
           "words": list(words), "designed_words": list(design.schedule.designed_words),
           "gains": design.schedule.to_json(), **extra}
    if args.method == "time":
        out["worst_case_word"] = design.extra["worst_case_word"]
    return out


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
    tmp = path.with_name(path.name + ".tmp")
    try:
        tmp.write_text(text)
        tmp.replace(path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise InputError(f"cannot write ({exc.strerror})", str(path), "--out") from None


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        out_path = _check_out(args.out)
        result = run_design(args)
        text = json.dumps(result, indent=2)
        if out_path is not None:
            _write_atomic(out_path, text + "\n")
    except InputError as exc:
        print(f"eqrec: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except InfeasibleDesign as exc:
        print(f"eqrec: infeasible: {exc}", file=sys.stderr)
        return EXIT_INFEASIBLE
    except (SolverFailure, CertificationFailure) as exc:
        print(f"eqrec: failed: {exc}", file=sys.stderr)
        return EXIT_SOLVER
    if out_path is not None:
        print(f"mu2 = {result['mu2']:.6g} (certified {result['certified_mu2']:.6g}); wrote {out_path}",
              file=sys.stderr)
    else:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
