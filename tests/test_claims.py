"""The claims table: comparison kinds, plain templates, reason functions by claim id, explanations tied to
their evidence."""
import json
import re
import string
from pathlib import Path

import pandas as pd
import pytest
import yaml

from eqrec.errors import InputError
from eqrec.studies.claims.reasons import Reason, each, fmtcomplex, fmtlist, join, registry
from eqrec.studies.claims.table import REASONS, build_claims_table, compare_one, default_atol, load_claims, without_timings
from eqrec.studies.claims.published import published_value
from eqrec.studies.pipeline.outputs import write_json

ROOT = Path(__file__).resolve().parents[1]
CLAIMS_FILE = ROOT / "config" / "claims.yaml"


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


def test_list_formats():
    assert join({"highs": "infeasible", "clarabel": "optimal"}) == "highs: infeasible, clarabel: optimal"
    assert join(["101", "110"]) == "101, 110"
    assert each({"highs": {"mu2": 1.5}, "clarabel": {"mu2": 1.25}}, "{key}: {mu2:g}") == "highs: 1.5; clarabel: 1.25"
    assert each([0.5, 0.25], "{key}={item:.2f}", sep=", ") == "0=0.50, 1=0.25"
    assert fmtcomplex([[-0.052, -0.338], [0.496, 0.0]]) == "{-0.052-0.338j, 0.496}"
    assert fmtlist([1.23456, [2, "x"]], ".3g") == "[1.23, [2, x]]"


# --------------------------------------------------------------------------- a fabricated claim and its reason

CLAIMS = """
- id: P9-A:x
  quantity: q
  paper_value: "1.5"
  source: s
  compare: {kind: number}
  value: p9/values.json#x
  note:
    bound: "bound {bound:.2f}"
    proven: proven optimal
    not_proven: not proven
  explanation:
    misprint: "misprint: {paper} is below the proven bound {bound:.2f}"
"""

REASONS_P9, reason_p9 = registry()


@reason_p9("P9-A:x")
def _p9(ev, texts):
    proven = ev["proof"] == "infeasible"
    return Reason(note=["bound", "proven" if proven else "not_proven"],
                  explanation={"misprint": proven and ev["paper"] < ev["bound"]})


def _values(tmp_path, value, **evidence):
    write_json(tmp_path / "p9" / "values.json", {"x": {"value": value, "evidence": evidence}})


def test_table_words_evidence_and_withdraws_an_explanation(tmp_path):
    claims = tmp_path / "claims.yaml"
    claims.write_text(CLAIMS)
    with pytest.raises(FileNotFoundError):
        build_claims_table(claims, tmp_path, REASONS_P9)
    _values(tmp_path, 1.7, bound=1.69, proof="infeasible")
    row = build_claims_table(claims, tmp_path, REASONS_P9).iloc[0]
    assert row["status"] == "differs"
    assert row["reason"] == "bound 1.69 proven optimal misprint: 1.5 is below the proven bound 1.69"
    # the evidence of the explanation disappears: the explanation is withdrawn, and the table says so by name
    _values(tmp_path, 1.7, bound=1.69, proof="optimal")
    row = build_claims_table(claims, [tmp_path / "p9" / "values.json"], REASONS_P9).iloc[0]
    assert row["reason"] == "bound 1.69 not proven [explanation withdrawn: its evidence no longer holds (misprint)]"
    # reproduced: no explanation at all
    _values(tmp_path, 1.5, bound=1.69, proof="infeasible")
    row = build_claims_table(claims, tmp_path, REASONS_P9).iloc[0]
    assert row["status"] == "reproduced"
    assert row["reason"] == "within tolerance 0.05 + 0|paper|; bound 1.69 proven optimal"
    # evidence a text needs is missing: the claim is named
    _values(tmp_path, 1.7, proof="infeasible")
    with pytest.raises(InputError, match="P9-A:x.*'bound'"):
        build_claims_table(claims, tmp_path, REASONS_P9)


def test_a_reason_function_chooses_only_texts_the_claim_has(tmp_path):
    claims = tmp_path / "claims.yaml"
    claims.write_text(CLAIMS)
    _values(tmp_path, 1.7, bound=1.69, proof="infeasible")
    for wrong in (Reason(note=["bound", "proved"], explanation={"misprint": True}),  # no such note
                  Reason(note=["bound"]),  # the explanation not judged
                  Reason(explanation={"misprint": True})):  # named notes, none chosen
        with pytest.raises(InputError, match="P9-A:x"):
            build_claims_table(claims, tmp_path, {"P9-A:x": lambda ev, texts, r=wrong: r})


@pytest.mark.parametrize("bad,match", [
    ('bound {bound:.2f}"', None),  # the good file, for contrast
    ('bound {bound.real:.2f}"', r"P9-A:x, note\.bound: field \{bound\.real:\.2f\} is not a plain name"),
    ('bound {bound[0]}"', r"P9-A:x, note\.bound: field \{bound\[0\]\}"),
    ('bound {abs(bound)}"', r"P9-A:x, note\.bound: field \{abs\(bound\)"),
    ('bound {bound!r}"', r"P9-A:x, note\.bound: field \{bound!r\}"),
    ('bound {bound:{spec}}"', r"P9-A:x, note\.bound: field \{bound:\{spec\}\}"),
    ('bound {}"', r"P9-A:x, note\.bound: field \{\}"),
    ('bound {bound"', r"P9-A:x, note\.bound: .*unmatched|P9-A:x, note\.bound: expected"),
])
def test_loader_refuses_fields_that_are_not_plain_names(tmp_path, bad, match):
    path = tmp_path / "claims.yaml"
    path.write_text(CLAIMS.replace('bound {bound:.2f}"', bad))
    if match is None:
        assert [e["id"] for e in load_claims(path, REASONS_P9)] == ["P9-A:x"]
    else:
        with pytest.raises(InputError, match=match):
            load_claims(path, REASONS_P9)


def test_loader_refuses_conditions_and_logic_without_a_reason_function(tmp_path):
    path = tmp_path / "claims.yaml"
    path.write_text(CLAIMS.replace("  explanation:\n", "  when: \"proof == 'infeasible'\"\n  explanation:\n"))
    with pytest.raises(InputError, match=r"claim P9-A:x: unknown keys \['when'\]"):
        load_claims(path, REASONS_P9)
    path.write_text(CLAIMS.replace("    misprint: ", "    when: proof == 'infeasible'\n    misprint: "))
    load_claims(path, REASONS_P9)  # a text named 'when' is only a name: the function decides
    path.write_text(CLAIMS)
    with pytest.raises(InputError, match="P9-A:x: named texts and explanations are chosen by a reason function"):
        load_claims(path, {})
    path.write_text(CLAIMS.replace('"misprint: {paper} is below the proven bound {bound:.2f}"', "3"))
    with pytest.raises(InputError, match="P9-A:x, explanation.misprint: a text must be a string"):
        load_claims(path, REASONS_P9)


# --------------------------------------------------------------------------- the claims file and its reason functions

def _claims():
    return load_claims(CLAIMS_FILE)


def test_reason_functions_and_claims_match_by_id():
    """Every registered reason function belongs to a claim of the file (no orphan), and every claim whose
    wording needs a choice (named notes, an explanation) has one; a claim without one has a single note."""
    claims = _claims()
    ids = {e["id"] for e in claims}
    assert set(REASONS) <= ids, sorted(set(REASONS) - ids)
    for e in claims:
        if e["id"] not in REASONS:
            assert isinstance(e.get("note", ""), str) and "explanation" not in e, e["id"]


def test_reason_functions_are_found_by_their_claim_id():
    """grep the id: the module of the study holds the line registering the function that words the row."""
    src = ROOT / "src" / "eqrec" / "studies"
    for cid in REASONS:
        study = cid[:2].lower()
        text = (src / study / "claims.py").read_text()
        assert re.search(r'@reason\([^)]*"' + re.escape(cid) + '"', text), cid


def test_the_table_finds_the_reasons_through_the_registry():
    """The claims table imports no study (no arrow back up inside ``studies/``): it imports each configured study's
    ``claims`` module by name, whose ``@reason`` functions fill the one registry; the claims rule's code inputs still
    list those modules (a changed reason function re-runs the table)."""
    import ast

    from eqrec.studies.claims import reasons
    from eqrec.studies.claims.table import load_reasons
    from eqrec.studies.pipeline import code

    tree = ast.parse((ROOT / "src" / "eqrec" / "studies" / "claims" / "table.py").read_text())
    imported = {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    imported |= {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    assert not [m for m in imported if m and re.match(r"eqrec\.studies\.(p\d|compare)", m)], sorted(imported)
    assert REASONS is reasons.REASONS and {cid.split("-")[0] for cid in REASONS} == {"P1", "P2", "P3", "P4"}
    assert load_reasons(["compare"]) is REASONS  # a study without a claims module adds nothing
    with pytest.raises(ValueError, match="two reason functions"):
        reasons.reason(next(iter(REASONS)))(lambda ev, texts: Reason())
    inputs = code.code_inputs("eqrec.studies.claims.table:step_table")
    assert all(f"src/eqrec/studies/p{n}/claims.py" in inputs for n in range(1, 5)), inputs


def test_claims_file_has_plain_templates_only():
    """No text of the claims file has an expression field; no entry has a condition key."""
    raw = yaml.safe_load(CLAIMS_FILE.read_text())
    for e in raw:
        assert not {"when", "else", "text"} & set(e), e["id"]
        texts = []
        for key in ("note", "explanation", "shown_as"):
            spec = e.get(key)
            texts += [spec] if isinstance(spec, str) else list((spec or {}).values())
        for t in texts:
            for _, name, spec, conv in string.Formatter().parse(t):
                if name is not None:
                    assert re.fullmatch(r"[A-Za-z_]\w*", name) and not conv and "{" not in (spec or ""), (e["id"], name)


def _number(x):
    try:
        return float(x) if isinstance(x, str) else x
    except ValueError:
        return x


def _stored_evidence(claim_id):
    e = next(c for c in _claims() if c["id"] == claim_id)
    file, _, key = e["value"].partition("#")
    item = json.loads((ROOT / "results" / file).read_text())[key]
    paper = published_value(CLAIMS_FILE, claim_id)
    published = {c["id"]: _number(c["paper_value"]) for c in _claims()}
    return e, {**item["evidence"], "value": item["value"], "paper": _number(paper), "tol": 5e-5, "published": published}


def test_prefix_l1_misprint_explanation_shown_and_withdrawn():
    """P1-M2:prefix-L1: the misprint explanation holds on the stored evidence; it is withdrawn when the probe
    no longer proves the optimum, when the published value is not below it, or when our optimum no longer
    rounds to the delayed-data paper's value (read from the claims file, P3-ACC:mu2)."""
    e, ev = _stored_evidence("P1-M2:prefix-L1")
    fn = REASONS["P1-M2:prefix-L1"]
    shown = fn(ev, e["note"])
    assert shown.explanation == {"misprint": True} and shown.note == ["optimum", "proven", "readings"]
    assert abs(ev["mu2"] - float(published_value(CLAIMS_FILE, "P3-ACC:mu2"))) <= 5e-5
    unproven = {**ev, "probe_status": {**ev["probe_status"], "clarabel": "optimal"}}
    assert fn(unproven, e["note"]) == Reason(fields={"probe_statuses": "highs: infeasible, clarabel: optimal"},
                                             note=["optimum", "not_proven", "readings"],
                                             explanation={"misprint": False})
    assert fn({**ev, "paper": ev["mu2"]}, e["note"]).explanation == {"misprint": False}
    assert fn({**ev, "mu2": ev["mu2"] + 1e-3}, e["note"]).explanation == {"misprint": False}


def test_prefix_l1_row_under_fabricated_evidence(tmp_path):
    """The row as the table writes it, from the real entries, on fabricated values files."""
    raw = [c for c in yaml.safe_load(CLAIMS_FILE.read_text()) if c["id"] in ("P1-M2:prefix-L1", "P3-ACC:mu2")]
    raw[1].pop("note")  # P3-ACC:mu2 is here for its published value only
    path = tmp_path / "claims.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    reasons = {"P1-M2:prefix-L1": REASONS["P1-M2:prefix-L1"], "P3-ACC:mu2": lambda ev, texts: Reason()}
    _, ev = _stored_evidence("P1-M2:prefix-L1")
    evidence = {k: v for k, v in ev.items() if k not in ("value", "paper", "tol", "published")}
    write_json(tmp_path / "p3" / "values.json", {"acc_mu2": {"value": 1.0, "evidence": {}}})
    write_json(tmp_path / "p1" / "values.json", {"prefix_L1_mu2": {"value": ev["mu2"], "evidence": evidence}})
    reason = build_claims_table(path, tmp_path, reasons).set_index("id").loc["P1-M2:prefix-L1", "reason"]
    assert "transposition misprint" in reason and "withdrawn" not in reason
    evidence["probe_status"] = {"highs": "infeasible", "clarabel": "unknown"}
    write_json(tmp_path / "p1" / "values.json", {"prefix_L1_mu2": {"value": ev["mu2"], "evidence": evidence}})
    reason = build_claims_table(path, tmp_path, reasons).set_index("id").loc["P1-M2:prefix-L1", "reason"]
    assert "misprint" not in reason.replace("withdrawn: its evidence no longer holds (misprint)", "")
    assert reason.endswith("[explanation withdrawn: its evidence no longer holds (misprint)]")
    assert "not proven to be the lowest M2" in reason


def test_reason_functions_take_their_other_branches():
    """A few shared shapes under fabricated evidence: the alternative texts and the per-item wording."""
    e, ev = _stored_evidence("P3-IMPL:period1-feasible")
    fn = REASONS["P3-IMPL:period1-feasible"]
    assert fn({**ev, "smallest_period": None, "lp_status": "optimal"}, e["note"]).note == ["status"]
    assert fn({**ev, "smallest_period": 3, "lp_status": "infeasible"}, e["note"]).note == \
        ["status", "shortest_period", "infeasible"]
    e, ev = _stored_evidence("P1-EXT:min-recovery-time")
    levels = [{"M1": 1.0, "T": 6}, {"M1": 0.2, "T": None}]
    assert REASONS["P1-EXT:min-recovery-time"]({**ev, "levels": levels}, e["note"]).fields["level_list"] == \
        "M1 = 1: T = 6; M1 = 0.2: T = none up to T_max"
    e, ev = _stored_evidence("P4-F7:better-ex1")
    no_root = {**ev, "qlam_threshold": {**ev["qlam_threshold"], "root": None}}
    r = REASONS["P4-F7:better-ex1"](no_root, e["note"])
    assert r.note == ["variances", "no_threshold", "regions"] and r.explanation == {"threshold": False}
    ties = {**ev, "tie_eta": {"count": 3, "min": 0.5, "max": 0.7}, "hold_better_eta": {"count": 0}}
    r = REASONS["P4-F8:better-ex2"](ties, e["note"])
    assert r.fields["tie"] == "3 grid values in [0.5, 0.7]" and r.fields["hold_better"] == "no eta_bar"
    assert not r.explanation


def test_published_value_reads_the_claims_file():
    assert published_value(CLAIMS_FILE, "P1-M2:prefix-L1") == "1.1490"  # as printed: the trailing zero kept
    printed = published_value(CLAIMS_FILE, "P2-F2:L")
    printed[0][0] = 99.0  # a copy: the cached file is not changed
    assert published_value(CLAIMS_FILE, "P2-F2:L") != printed
    with pytest.raises(InputError, match="no claim 'P9-X:y'"):
        published_value(CLAIMS_FILE, "P9-X:y")


def test_every_claim_names_a_target_of_TARGETS_md():
    """Each claim id starts with a target ID of ../shared/TARGETS.md (P1-M2, P2-F3a, ...), and each target of
    TARGETS.md has at least one claim (the claims file is checked against the list, not only loaded)."""
    targets_md = ROOT.parent / "shared" / "TARGETS.md"
    if not targets_md.is_file():
        pytest.skip(f"{targets_md} not beside the repository")
    targets = set(re.findall(r"\bP[1-4]-[A-Za-z0-9]+\b", targets_md.read_text()))
    ids = {e["id"].split(":")[0] for e in _claims()}
    assert ids <= targets, sorted(ids - targets)
    assert targets <= ids, f"targets without a claim: {sorted(targets - ids)}"


def test_stored_table_matches_the_stored_values():
    """results/claims.csv is what the claims step makes of the stored values.json files; the timing rows in full
    are in results/timings/claims.csv, and claims.csv names that file in their place."""
    values = sorted(str(p) for p in (ROOT / "results").glob("p*/*values.json"))
    values += sorted(str(p) for p in (ROOT / "results" / "timings").glob("p*/*values.json"))
    fresh = build_claims_table(CLAIMS_FILE, values)
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


def test_published_values_need_the_claims_file_only():
    """The Snakefile and P2's printed step read published values through eqrec.studies.claims.published, which
    imports no wording code: editing a reason function re-plans the claims table, not P2's designs."""
    from eqrec.studies.pipeline.code import code_inputs

    def rel(paths):
        return {Path(p).as_posix().split("src/eqrec/", 1)[1] for p in paths}

    names = rel(code_inputs("eqrec.studies.p2.steps:step_printed"))
    assert "studies/claims/published.py" in names
    assert not names & {"studies/claims/table.py", "studies/claims/reasons.py", "studies/p1/claims.py",
                        "studies/p2/claims.py", "studies/p3/claims.py", "studies/p4/claims.py"}, sorted(names)
    claims_inputs = rel(code_inputs("eqrec.studies.claims.table:step_table"))
    assert {"studies/claims/published.py", "studies/claims/reasons.py", "studies/p1/claims.py",
            "studies/p4/claims.py"} <= claims_inputs
