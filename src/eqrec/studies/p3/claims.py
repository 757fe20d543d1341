"""Reasons of the P3 claims (delayed/missing-data paper): which wording of ``config/claims.yaml`` a row shows.

Each function reads the evidence of its row's ``values.json`` entry (written by
:mod:`eqrec.studies.p3.values` and the strategy step) and returns a
:class:`~eqrec.studies.claims.reasons.Reason`; see :mod:`eqrec.studies.claims.reasons`
for the contract.
"""

from __future__ import annotations

from typing import Any, Mapping

from eqrec.studies.claims.reasons import Reason, each, fmtlist, fmtlists, join, reason


#: A causal run at a worst-case vertex attains a bound when it is within this gap.
VERTEX_GAP = 1e-9


def _vertex(ev: Mapping[str, Any], key: str = "vertex_gap") -> str:
    return "vertex_attained" if ev[key] <= VERTEX_GAP else "vertex_missed"


@reason("P3-LANG:example1-words")
def example1_words(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The delay words, listed."""
    return Reason(fields={"word_list": join(ev["words"])})


@reason("P3-LANG:example3-reduced")
def example3_reduced(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The event sequences, listed."""
    return Reason(fields={"sequence_list": join(ev["sequences"])})


@reason("P3-BR:words")
def reactor_words(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """How many language sizes the counts table holds."""
    return Reason(fields={"sizes": len(ev["counts"])})


@reason("P3-BR:mu1")
def reactor_mu1(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The global optimum, and whether the causal runs at the worst-case vertices attain the bounds."""
    return Reason(note=["global", _vertex(ev)])


@reason("P3-BR:max-mu2")
def reactor_max_mu2(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """As P3-BR:mu1, with the largest level; the explanation holds while the prefix with no data at times 0, 1
    forces max mu2 = ||A^2|| mu1 and the published value is that bound at the printed mu1 (P3-BR:mu1)."""
    a2, paper = ev["A2_inf_norm"], ev["paper"]
    printed_mu1 = (ev["no_data_prefix"] and abs(ev["mu2_over_mu1"] - a2) <= 1e-6 * a2
                   and ev["reading_mu1"] == ev["published"]["P3-BR:mu1"]
                   and abs(ev["reading_mu2"] - paper) <= ev["tol"] and paper > ev["value"] + ev["tol"])
    return Reason(note=["global", _vertex(ev), "largest_level"], explanation={"printed_mu1": printed_mu1})


@reason("P3-BR:max-mu2-at-printed-mu1")
def reactor_printed_mu1(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The LP at the printed mu1, and whether the vertex runs attain the bounds."""
    return Reason(note=["reading", _vertex(ev)])


@reason("P3-BR:augmented-L-s0")
def augmented_l_s0(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The objective for each (L, s0) pair; equal to the prefix design within ``rtol`` (p3_values decides) or not."""
    equal = ev["value"] == "independent"
    agreement = texts["equal" if equal else "different"].format_map(ev)
    return Reason(fields={"objective_list": fmtlist(ev["objectives"], ".6f"), "agreement": agreement},
                  note=["objectives"])


@reason("P3-F1:proposed-inside")
def f1_proposed(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The levels and the exact worst case along the pattern."""
    return Reason(fields=fmtlists(ev, "levels", "certified_norm"))


@reason("P3-F1:kalman-timestamped", "P3-F1:kalman-unaware", "P3-F1:kalman-random-delay-lmv")
def f1_kalman(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The exact worst case against the levels (whether a box vertex attains it), and how many sampled runs
    leave the bars."""
    vertex = texts[_vertex(ev, "attain_gap")].format_map(ev)
    fields = {**fmtlists(ev, "worst_norm", "levels"), "time_list": join(ev["times"]),
              "filtered_time_list": join(ev["filtered_times"]), "vertex": vertex}
    return Reason(fields=fields, note=["worst_case", "none_sampled" if ev["sampled_exceed"] == 0 else "some_sampled"])


@reason("P3-ACC:mu2")
def acc_mu2(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The missing-data language, listed."""
    return Reason(fields={"language": join(ev["missing_data_language"])})


@reason("P3-ACC:same-as-prefix")
def acc_same_as_prefix(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """Both costs within ``SAME_RTOL`` of P1's optimum (p3_values decides), or their differences."""
    return Reason(note=[ev["value"]])


@reason("P3-ACC:footnote-mu1-free")
def acc_mu1_free(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The optimum, and the other costs' values."""
    return Reason(fields={"cost_list": each(ev["other_costs"], texts["cost"])}, note=["optimum"])


@reason("P3-F2:better-levels")
def f2_levels(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """Both estimators' levels along the pattern."""
    return Reason(fields=fmtlists(ev, "proposed_levels", "prefix_levels"))


@reason("P3-F2:better-mean-error")
def f2_mean_error(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """Whether both estimators' runs stay inside their bars."""
    return Reason(fields={"both_inside": ev["inside_proposed"] and ev["inside_prefix"]})


@reason("P3-F2:better-worst-case")
def f2_worst_case(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """Both exact worst cases; 'better' holds for the levels and the mean error (the explanation) while ours
    differs on the worst case only."""
    holds = (ev["value"] != ev["paper"] and ev["levels_verdict"] == ev["paper"]
             and ev["mean_error_proposed"] < ev["mean_error_prefix"])
    return Reason(fields=fmtlists(ev, "proposed_bound", "prefix_bound"), explanation={"levels_and_mean": holds})


@reason("P3-F1:kalman-sampled")
def f1_kalman_sampled(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """Per variant the runs leaving the bars and the ratios; the claim holds as a worst-case statement only
    while every exact worst case leaves the bars and no sampled run reaches them."""
    holds = (ev["value"] != ev["paper"] and ev["exact_outside"]
             and max(ev["sampled_max_ratio"].values()) < 1)
    fields = {"exceed_list": each(ev["sampled_exceed"], texts["count"]),
              "sampled_ratio_list": each(ev["sampled_max_ratio"], texts["ratio"]),
              "exact_ratio_list": each(ev["exact_max_ratio"], texts["ratio"])}
    return Reason(fields=fields, note=["sampled"], explanation={"worst_case_only": holds})


@reason("P3-IMPL:switching")
def switching(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The fraction of steps in recovery, in percent."""
    return Reason(fields={"recovery_percent": 100.0 * ev["recovery_fraction"]})


@reason("P3-IMPL:period1-feasible")
def period1(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The LP status; the shortest recovering period when there is one; why no one-step gain exists when the
    LP is infeasible."""
    note = ["status"]
    if ev["smallest_period"] is not None:
        note.append("shortest_period")
    if ev["lp_status"] == "infeasible":
        note.append("infeasible")
    return Reason(fields=fmtlists(ev, "period_mu1_min"), note=note)
