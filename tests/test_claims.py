import json

import pytest

from eqrec.studies.claims import build_claims_table, compare_one, default_atol, write_values


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


def test_table_and_missing_results(tmp_path):
    claims = tmp_path / "claims.yaml"
    claims.write_text("- id: P9-A:x\n  quantity: q\n  paper_value: 1.5\n  source: s\n  compare: {kind: number}\n"
                      "  value: p9/values.json#x\n  explanation: misprint\n")
    with pytest.raises(FileNotFoundError):
        build_claims_table(claims, tmp_path)
    write_values(tmp_path / "p9" / "values.json", {"x": {"value": 1.7, "note": "bound proves it"}})
    t = build_claims_table(claims, tmp_path)
    row = t.iloc[0]
    assert row["status"] == "differs" and "bound proves it" in row["reason"] and "misprint" in row["reason"]
    assert json.loads((tmp_path / "p9" / "values.json").read_text())["x"]["value"] == 1.7
