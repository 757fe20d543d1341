"""Reasons of the P4 claims (LMV companion study): which wording of ``config/claims.yaml`` a row shows.

Each function reads the evidence of its row's ``values.json`` entry (written by
:mod:`eqrec.studies.p4.steps`) and returns a :class:`~eqrec.studies.claims.reasons.Reason`;
see :mod:`eqrec.studies.claims.reasons` for the contract.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Mapping

from eqrec.studies.claims.reasons import Reason, each, fmtlist, fmtlists, reason


@reason("P4-F1:tracking")
def tracking(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """Our value shown as one line per estimator (relative rms error and correlation per component)."""
    estimators = "; ".join(texts["estimator"].format(key=k, **fmtlists(v, "rel_rms", "corr"))
                           for k, v in ev["value"].items())
    return Reason(fields={"estimator_list": estimators}, note=["realisation"])


@reason("P4-F4:ordering")
def ordering(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The theory and Monte Carlo variances of each estimator."""
    return Reason(fields={f"{source}_{est}": fmtlist(ev[source][est])
                          for source in ("theory", "mc") for est in ("predictor", "filter", "smoother")})


@reason("P4-F5:eta-trend")
def eta_trend(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """Monotonicity per estimator and the filter variances at three arrival rates."""
    return Reason(fields={**{f"decreasing_{est}": ev["decreasing"][est] for est in ("pred", "filt", "smooth")},
                          **fmtlists(ev, "filt_lo", "filt_mid", "filt_hi")})


@reason("P4-F6:q-trend")
def q_trend(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The filter variances at the corners of the (Q_xi, Q_lambda) grid."""
    return Reason(fields=fmtlists(ev, "filt_lo", "filt_hi"))


def _eta_range(texts: Mapping[str, str], cells: Mapping[str, Any], single: bool = False) -> str:
    """The arrival rates of one verdict: none, one value (``single``), or a range of grid values."""
    if not cells["count"]:
        return texts["no_eta"]
    return texts["eta_value" if single and cells["count"] == 1 else "eta_values"].format_map(cells)


@reason("P4-F8:better-ex2")
def better_ex2(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The compensation comparison (zero-input vs hold-input): variances, the Q_lambda threshold, the regions."""
    threshold = ev["qlam_threshold"]
    fields = {**fmtlists(ev, "steady_zero", "steady_hold", "theory_zero_T", "theory_hold_T", "mc_zero_T", "mc_hold_T"),
              "zero_from_t": ev["from_t"]["zero-input"], "hold_from_t": ev["from_t"]["hold-input"],
              **{f"threshold_{k}": threshold[k] for k in ("Qxi", "root", "below", "above", "lo", "hi")},
              "hold_better": _eta_range(texts, ev["hold_better_eta"]),
              "zero_better": _eta_range(texts, ev["zero_better_eta"]),
              "tie": _eta_range(texts, ev["tie_eta"], single=True),
              "percent_hold": 100.0 * ev["frac_hold"], "percent_zero": 100.0 * ev["frac_zero"]}
    return Reason(fields=fields, note=["variances", "threshold" if threshold["root"] is not None else "no_threshold",
                                       "regions"])


@reason("P4-F7:better-ex1")
def better_ex1(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The comparison (as P4-F8:better-ex2); the threshold explanation while both filters pass the Monte Carlo test
    and the published verdict is ours below a Q_lambda threshold only."""
    threshold = ev["qlam_threshold"]
    holds = (ev["theory_checks_passed"] and threshold["root"] is not None and threshold["below"] == ev["paper"]
             and ev["value"] != ev["paper"])
    return replace(better_ex2(ev, texts), explanation={"threshold": holds})


@reason("P4-THEORY:recursion")
def theory_recursion(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """One line per example."""
    return Reason(fields={"example_list": each(ev["examples"], texts["example"])}, note=["recursion"])


@reason("P4-THEORY:eq9")
def eq9(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """One line per example; the correction explains the difference while it passes and the printed form fails."""
    lists = ("P_printed_T", "P_corrected_T", "P_true_T", "mc_T", "se_T")
    examples = "; ".join(texts["example"].format_map({**v, "key": k, **fmtlists(v, *lists)})
                         for k, v in ev["examples"].items())
    return Reason(fields={"example_list": examples}, note=["printed"],
                  explanation={"corrected": ev["corrected_passed"] and not ev["printed_passed"]})
