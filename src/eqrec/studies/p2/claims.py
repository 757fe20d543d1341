"""Reasons of the P2 claims (augmented paper): which wording of ``config/claims.yaml`` a row shows.

Each function reads the evidence of its row's ``values.json`` entry (written by
:mod:`eqrec.studies.p2.values`) and returns a :class:`~eqrec.studies.claims.reasons.Reason`;
see :mod:`eqrec.studies.claims.reasons` for the contract.  ``mu2_tol`` of the
evidence is the configured tolerance under which two optima are the same.
"""

from __future__ import annotations

from typing import Any, Mapping

from eqrec.studies.claims.reasons import Reason, each, fmtcomplex, fmtlist, join, reason


def _solver_name(solver: str) -> str:
    return "HiGHS" if solver == "highs" else solver


def _reaches(value: float, target: float, mu2_tol: float) -> bool:
    """Whether ``value`` is ``target`` within the relative tolerance ``mu2_tol``."""
    return abs(value - target) <= mu2_tol * max(1, target)


@reason("P2-F1:mu2-time")
def time_lp(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The solver of the time-based LP, by name."""
    return Reason(fields={"solver_name": _solver_name(ev["solver"])})


@reason("P2-SOLVER:gains")
def gain_difference(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The reference solver of the gain comparison, by name."""
    return Reason(fields={"reference_name": _solver_name(ev["reference"])})


@reason("P2-F1:L", "P2-F2:L")
def gain_L(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The eigenvalues of our A - LC; the flat heat map (every L the same optimum) when it is flat."""
    flat = ev["heatmap_spread"] <= ev["mu2_tol"]
    return Reason(fields={"eig_list": fmtcomplex(ev["eig"], ".3f")}, note=["eig", "flat"] if flat else ["eig"])


@reason("P2-F1:s0")
def initial_s0(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """Why IPOPT's s0 means nothing, while the optimum is the same for every sampled s0."""
    return Reason(note=["flat"] if ev["s0_mu2_spread"] <= ev["mu2_tol"] else [])


@reason("P2-F2:mu2-augmented")
def f2_augmented(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The time-based lower bound, whether IPOPT reaches it, the 'leak' reading; two explanations of the
    published 1.05: the 'masked_gain' reading at the printed L, and the 1-based reading of the caption's word."""
    tol, mu2_tol, paper = ev["tol"], ev["mu2_tol"], ev["paper"]
    masked, one_based = ev["masked_gain"], ev["one_based"]
    reached = _reaches(ev["value"], ev["time_mu2"], mu2_tol)
    leak = "; ".join(texts["leak_designed" if "design_mu2" in item else "leak_failed"].format_map({**item, "key": k})
                     for k, item in ev["leak"].items())
    explanation = {
        "masked_gain": (paper < ev["time_mu2"] - mu2_tol and reached and abs(masked["mu2"] - paper) <= tol
                        and masked["best_agree"]),
        # the Fig. 2 caption's missing steps k = 2, 3, read 1-based
        "one_based": (abs(one_based["augmented_mu2"] - paper) <= tol and abs(one_based["time_mu2"] - paper) <= tol
                      and one_based["missing"] == [2, 3]
                      and one_based["on_true_word"] > one_based["augmented_mu2"]),
    }
    return Reason(fields={"leak_list": leak, **_readings(ev)},
                  note=["lower_bound", "reached" if reached else "not_reached", "leak"], explanation=explanation)


def _readings(ev: Mapping[str, Any]) -> dict[str, Any]:
    """The 'masked_gain' and 1-based readings' numbers the Fig. 2 explanations cite."""
    masked, one_based = ev["masked_gain"], ev["one_based"]
    return {"masked_gain_mu2": masked["mu2"], "masked_gain_best": masked["best"],
            "one_based_missing": join(one_based["missing"]), "one_based_word": one_based["word"],
            "one_based_augmented_mu2": one_based["augmented_mu2"], "one_based_on_true_word": one_based["on_true_word"]}


@reason("P2-F2:time-vs-augmented")
def f2_time_vs_augmented(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """'Larger' explained by the 'masked_gain' reading, and by comparing designs for different words."""
    equal = ev["value"] == "equal"
    explanation = {"masked_gain": equal and ev["masked_gain"]["mu2"] < ev["time_mu2"] - ev["mu2_tol"],
                   "one_based": equal and ev["one_based"]["augmented_mu2"] < ev["time_mu2"] - ev["mu2_tol"]}
    return Reason(fields=_readings(ev), explanation=explanation)


@reason("P2-F2:mu2-masked-gain")
def f2_masked_gain(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The design LP at the printed L; 'one reading for three figures' while it gives the published value."""
    note = ["design", "one_reading"] if abs(ev["value"] - ev["paper"]) <= ev["tol"] else ["design"]
    return Reason(fields={"eig_list": fmtcomplex(ev["eig"], ".3f")}, note=note)


@reason("P2-F2:certified-masked-gain")
def f2_certified_masked_gain(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The best guarantee among the optima of the 'masked_gain' design LP, with both runtimes; the
    explanation (the published value is a design level, not a guarantee) while the solvers agree."""
    optima, heatmap = ev["among_optima"], ev["heatmap"]
    hold, theorem2 = optima["runtimes"]["hold"], optima["runtimes"]["theorem2"]
    fields = {"rel_tol": optima["rel_tol"], "abs_tol": optima["abs_tol"], "word_list": join(ev["words"]),
              **{f"optima_{rt}{suffix}": r[key] for rt, r in (("hold", hold), ("theorem2", theorem2)) for suffix, key
                 in (("", "value"), ("_spread", "solver_spread"), ("_certify_difference", "certify_difference"))},
              "worst_time": hold["worst_time"], "agree_until": optima["agree_until"],
              "solver_optima": each(ev["by_solver"], texts["solver_optimum"]),
              "terminal_theorem2": optima["terminal_theorem2"]["value"],
              "recover_theorem2": optima["recover_theorem2"]["value"],
              "recover_theorem2_terminal": optima["recover_theorem2"]["terminal"]}
    same_worst_time = (abs(hold["value"] - theorem2["value"]) <= ev["mu2_tol"]
                       and hold["worst_time"] <= optima["agree_until"] and hold["exact"])
    if heatmap["certified_min"] is not None:
        low, high = heatmap["certified_at_min"]
        fields.update(heatmap_certified_min=heatmap["certified_min"], heatmap_certified_low=low,
                      heatmap_certified_high=high, heatmap_certified_terminal_min=heatmap["certified_terminal_min"])
    note = [name for name, shown in (("among_optima", True), ("same_worst_time", same_worst_time),
                                     ("unsettled", not optima["agree"]), ("solver_optima", True),
                                     ("recover", optima["terminal_theorem2"]["value"] <= ev["M1"]),
                                     ("heatmap", heatmap["certified_min"] is not None)) if shown]
    as_run = (abs(ev["masked_gain_mu2"] - ev["paper"]) <= ev["tol"] and optima["agree"]
              and ev["value"] > ev["time_mu2"] + ev["mu2_tol"])
    return Reason(fields=fields, note=note, explanation={"as_run": as_run})


@reason("P2-F3a:mu2-region")
def f3a_region(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """Whether the heat map is flat, the points per reading; explained by the bijection (Theorem 2 as
    stated is flat) and by the 'masked_gain' reading (its region)."""
    mu2_tol, variants = ev["mu2_tol"], ev["variants"]
    flat = ev["spread"] <= mu2_tol
    leak, one_based, masked = variants["leak"], variants["one_based"], variants["masked_gain"]
    bijection = (flat and _reaches(ev["value"], ev["time_mu2"], mu2_tol)
                 and one_based["max"] - one_based["min"] <= mu2_tol
                 and leak["min"] >= ev["time_mu2"] - mu2_tol and leak["infeasible"] > leak["optimal"])
    masked_gain = abs(masked["min"] - ev["paper"]) <= ev["tol"] and masked["at_min"] < masked["optimal"]
    return Reason(fields={"variant_list": each(variants, texts["variant"])},
                  note=["grid", "flat" if flat else "not_flat", "classes"],
                  explanation={"bijection": bijection, "masked_gain": masked_gain})


@reason("P2-F3a:mu2-region-masked-gain")
def f3a_region_masked_gain(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The region where the minimum is attained (when it is one), and the spread over nilpotent L at r = 0."""
    region = ev["at_min"] < ev["optimal"] and ev["at_min_r_max"] < ev["r_max"]
    deadbeat = ev["r0_deadbeat"]
    return Reason(fields={"deadbeat_count": len(deadbeat["seeds"]), "deadbeat_min": deadbeat["min"],
                          "deadbeat_max": deadbeat["max"]},
                  note=["minimum", "region" if region else "no_region", "deadbeat"])


@reason("P2-F3b:interval")
def f3b_interval(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The interval of each reading; explained by the bijection (no interval) and the 'masked_gain' reading."""
    variants = "; ".join(texts["variant"].format(key=k, interval_list=fmtlist(v["interval"], ".4g"))
                         for k, v in ev["variants"].items())
    paper, tol, masked = ev["paper"], ev["tol"], ev["masked_gain_interval"]
    explanation = {"bijection": ev["spread"] <= ev["mu2_tol"] and ev["all_solved"],
                   "masked_gain": abs(masked[0] - paper[0]) <= tol and abs(masked[1] - paper[1]) <= tol}
    return Reason(fields={"variant_list": variants}, note=["eigenvalues"], explanation=explanation)


@reason("P2-F3b:interval-masked-gain")
def f3b_interval_masked_gain(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The interval on the k/14 grid, and the value at lambda = 0 (not unique)."""
    return Reason(fields={"value_list": fmtlist(ev["value"], ".6f"), "at_zero_list": fmtlist(ev["at_zero"], ".4g"),
                          "deadbeat_max": ev["r0_deadbeat"]["max"]})


@reason("P2-F3b:interval-masked-gain-fine")
def f3b_interval_fine(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The interval on the fine grid; the published endpoints are grid points next to its edges while it
    contains the k/14 grid's interval."""
    value, grid = ev["value"], ev["grid_interval"]
    between = value[0] <= grid[0] and value[1] >= grid[1] and value != grid
    return Reason(fields={"value_list": fmtlist(value, ".4g")}, explanation={"between_grid_points": between})


@reason("P2-S0:mu2")
def s0_mu2(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """The optimum for every sampled s0."""
    return Reason(fields={"mu2_list": fmtlist(ev["mu2"], ".9f")})


@reason("P2-SOLVER:mu2")
def solver_mu2(ev: Mapping[str, Any], texts: Mapping[str, str]) -> Reason:
    """One line per solver."""
    return Reason(fields={"solver_list": each(ev["solvers"], texts["solver"])}, note=["solvers"])
