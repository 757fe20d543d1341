"""The claims table: comparison kinds, the evidence language, and explanations tied to their evidence."""
import json
import re
from pathlib import Path

import pandas as pd
import pytest

from eqrec.errors import InputError
from eqrec.studies.claims import (ExpressionError, build_claims_table, compare_one, default_atol, evaluate, holds,
                                  load_claims, render, without_timings)
from eqrec.studies.outputs import write_json

ROOT = Path(__file__).resolve().parents[1]


def entry(paper, kind="number", **cmp):
    return {"id": "X-1:a", "quantity": "q", "paper_value": paper, "source": "s", "compare": {"kind": kind, **cmp},
            "value": "v.json#a"}


def test_default_tolerance_is_half_last_digit():
    assert default_atol("1.1490") == pytest.approx(5e-5)  # trailing zeros only survive as text
    assert default_atol(2.9864) == pytest.approx(5e-5)
    assert default_atol(1.05) == pytest.approx(5e-3)


@pytest.mark.parametrize("paper,ours,status", [(2.9864, 2.98637, "reproduced"), (1.1490, 1.14982, "differs"),
                                               (1.05, 1.0549, "reproduced"), (1.05, 1.056, "differs")])
def test_number(paper, ours, status):
    assert compare_one(entry(paper), ours)[0] == status


def test_other_kinds():
    assert compare_one(entry("Hold-input", "text"), "hold-input")[0] == "reproduced"
    assert compare_one(entry([[1, 2]], "array", atol=0.01), [[1, 2.005]])[0] == "reproduced"
    assert compare_one(entry([[1, 2]], "array", atol=0.01), [[1, 2.5]])[0] == "differs"
    assert compare_one(entry([-0.7, 0.9], "interval"), [-0.7, 0.96])[0] == "differs"
    assert compare_one(entry(0.11, "none", why="hardware"), 0.05)[0] == "not comparable"


EVIDENCE = {"mu2": 1.149819, "probe_status": {"highs": "infeasible", "clarabel": "infeasible"},
            "solvers": {"highs": {"mu2": 1.5}, "clarabel": {"mu2": 1.25}}, "words": ["101", "110"],
            "eig": [[-0.052, -0.338], [0.496, 0.0]]}


def test_expression_language():
    assert evaluate("mu2 * 2 > 2 and probe_status.highs == 'infeasible'", EVIDENCE) is True
    assert evaluate("all_are(probe_status, 'infeasible')", EVIDENCE) is True
    assert evaluate("probe_status['clarabel']", EVIDENCE) == "infeasible"
    assert evaluate("words[1]", EVIDENCE) == "110"
    assert evaluate("'a' if len(words) == 2 else 'b'", EVIDENCE) == "a"
    assert evaluate("abs(-1) + max(1, 2)", EVIDENCE) == 3
    assert not holds("missing_key > 1", EVIDENCE)  # missing evidence: the condition does not hold
    for bad in ("__import__('os')", "mu2.__class__", "[x for x in words]", "open('f')", "lambda: 1", "mu2 ** 2"):
        with pytest.raises(ExpressionError):
            evaluate(bad, EVIDENCE)


def test_templates():
    assert render("LP optimum {mu2:.4f}; {join(probe_status)}", EVIDENCE) == \
        "LP optimum 1.1498; highs: infeasible, clarabel: infeasible"
    assert render("{each(solvers, '{key}: {mu2:g}')}", EVIDENCE) == "highs: 1.5; clarabel: 1.25"
    assert render("{{0, {fmtcomplex(eig, '.3f')}}}", EVIDENCE) == "{0, {-0.052-0.338j, 0.496}}"
    assert render("{fmtlist([1.23456, 2], '.3g')}", {}) == "[1.23, 2]"
    with pytest.raises(ExpressionError):
        render("{mu2", EVIDENCE)


CLAIMS = """
- id: P9-A:x
  quantity: q
  paper_value: "1.5"
  source: s
  compare: {kind: number}
  value: p9/values.json#x
  note:
    - "bound {bound:.2f}"
    - {when: "proof == 'infeasible'", text: "proven optimal", else: "not proven"}
  explanation:
    when: "proof == 'infeasible' and paper < bound"
    text: "misprint: {paper} is below the proven bound {bound:.2f}"
"""


def _values(tmp_path, value, **evidence):
    write_json(tmp_path / "p9" / "values.json", {"x": {"value": value, "evidence": evidence}})


def test_table_words_evidence_and_withdraws_an_explanation(tmp_path):
    claims = tmp_path / "claims.yaml"
    claims.write_text(CLAIMS)
    with pytest.raises(FileNotFoundError):
        build_claims_table(claims, tmp_path)
    _values(tmp_path, 1.7, bound=1.69, proof="infeasible")
    row = build_claims_table(claims, tmp_path).iloc[0]
    assert row["status"] == "differs"
    assert row["reason"] == "bound 1.69 proven optimal misprint: 1.5 is below the proven bound 1.69"
    # the evidence of the explanation disappears: the explanation is withdrawn, and the table says so
    _values(tmp_path, 1.7, bound=1.69, proof="optimal")
    row = build_claims_table(claims, [tmp_path / "p9" / "values.json"]).iloc[0]
    assert row["status"] == "differs" and "misprint" not in row["reason"] and "not proven" in row["reason"]
    assert "explanation withdrawn" in row["reason"] and "proof == 'infeasible'" in row["reason"]
    # reproduced: no explanation at all
    _values(tmp_path, 1.5, bound=1.69, proof="infeasible")
    row = build_claims_table(claims, tmp_path).iloc[0]
    assert row["status"] == "reproduced" and row["reason"].startswith("within tolerance") and "misprint" not in row["reason"]


def test_claims_file_is_checked(tmp_path):
    bad = tmp_path / "claims.yaml"
    bad.write_text(CLAIMS.replace("when: \"proof == 'infeasible' and paper < bound\"\n", ""))
    with pytest.raises(InputError, match="explanation needs the evidence"):
        load_claims(bad)
    bad.write_text(CLAIMS.replace("bound {bound:.2f}", "bound {bound.__class__}"))
    with pytest.raises(InputError, match="not part of the claims expression language"):
        load_claims(bad)


def test_every_claim_names_a_target_of_TARGETS_md():
    """Each claim id starts with a target ID of ../shared/TARGETS.md (P1-M2, P2-F3a, ...), and each target of
    TARGETS.md has at least one claim (the claims file is checked against the list, not only loaded)."""
    targets_md = ROOT.parent / "shared" / "TARGETS.md"
    if not targets_md.is_file():
        pytest.skip(f"{targets_md} not beside the repository")
    targets = set(re.findall(r"\bP[1-4]-[A-Za-z0-9]+\b", targets_md.read_text()))
    claims = load_claims(ROOT / "config" / "claims.yaml")
    ids = {e["id"].split(":")[0] for e in claims}
    assert ids <= targets, sorted(ids - targets)
    assert targets <= ids, f"targets without a claim: {sorted(targets - ids)}"


def test_stored_table_matches_the_stored_values():
    """results/claims.csv is what the claims step makes of the stored values.json files; the timing rows in full
    are in results/timings/claims.csv, and claims.csv names that file in their place."""
    values = sorted(str(p) for p in (ROOT / "results").glob("p*/*values.json"))
    values += sorted(str(p) for p in (ROOT / "results" / "timings").glob("p*/*values.json"))
    fresh = build_claims_table(ROOT / "config" / "claims.yaml", values)
    stored = pd.read_csv(ROOT / "results" / "claims.csv", dtype=str, keep_default_na=False)
    fixed = without_timings(fresh)
    for col in ("id", "quantity", "paper_value", "our_value", "status", "reason"):
        assert list(fixed[col].astype(str)) == list(stored[col]), col
    assert not any("explanation withdrawn" in r for r in stored["reason"])
    timing = fresh[fresh["timing"]]
    assert set(timing["id"]) == {"P1-TIME:prefix-seconds", "P1-TIME:time-seconds"}
    assert (stored.set_index("id").loc[list(timing["id"]), "our_value"]
            == "measured each run: results/timings/claims.csv").all()
    stored_timings = pd.read_csv(ROOT / "results" / "timings" / "claims.csv", dtype=str, keep_default_na=False)
    assert list(stored_timings["id"]) == list(timing["id"]) and all(float(v) > 0 for v in stored_timings["our_value"])


def test_values_files_hold_numbers_and_evidence_only():
    for path in (ROOT / "results").glob("p*/*values.json"):
        for key, item in json.loads(path.read_text()).items():
            assert set(item) == {"value", "evidence"}, f"{path.parent.name}/{key}: {sorted(item)}"
