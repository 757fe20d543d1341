"""Reasons of the P1 claims (prefix-based paper): which wording of ``config/claims.yaml`` a row shows.

Each function reads the evidence of its row's ``values.json`` entry (written by
:mod:`eqrec.studies.p1.steps`) and returns a :class:`~eqrec.studies.claims.reasons.Reason`;
see :mod:`eqrec.studies.claims.reasons` for the contract.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Mapping

from eqrec.studies.claims.reasons import Reason, all_are, join, reason


@reason("P1-M2:time-L1")
def time_l1(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The LP optimum, and whether the LP probe below it, infeasible for every solver, proves it the lowest M2
    of the class."""
    proven = all_are(ev["probe_status"], "infeasible")
    return Reason(fields={"probe_statuses": join(ev["probe_status"])},
                  note=["optimum", "proven" if proven else "not_proven"])


@reason("P1-M2:prefix-L1")
def prefix_l1(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """As P1-M2:time-L1, with the alternative readings; the misprint explanation holds while the published
    value is below the proven optimum and our optimum rounds to the delayed-data paper's value (P3-ACC:mu2)."""
    optimum = time_l1(ev, texts)
    misprint = (all_are(ev["probe_status"], "infeasible") and ev["paper"] < ev["mu2"] - ev["probe_gap"]
                and abs(ev["mu2"] - ev["published"]["P3-ACC:mu2"]) <= 5.0e-5)
    return replace(optimum, note=[*optimum.note, "readings"], explanation={"misprint": misprint})


@reason("P1-EXT:finite-length")
def finite_length(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The words of the finite-length language, listed."""
    return Reason(fields={"word_list": join(ev["words"])})


@reason("P1-EXT:min-recovery-time")
def min_recovery_time(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The minimum recovery time T per level M1 (none found up to T_max for some)."""
    levels = "; ".join(texts["level" if lv["T"] is not None else "level_unrecovered"].format_map(lv)
                       for lv in ev["levels"])
    return Reason(fields={"level_list": levels}, note=["levels"])


@reason("P1-TIME:prefix-seconds", "P1-TIME:time-seconds")
def solve_time(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """Build and solve times in milliseconds."""
    return Reason(fields={"build_ms": ev["build_s"] * 1e3, "solve_ms": ev["solve_s"] * 1e3})


@reason("P1-TIME:prefix-iterations", "P1-TIME:time-iterations")
def iterations(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """Names HiGHS's dual simplex when HiGHS solved the design."""
    return Reason(note=["highs"] if ev["solver"] == "highs" else [])
