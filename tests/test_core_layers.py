"""Core layers added for arrival patterns: solver registry, tracked LP entries, per-row levels, per-node levels."""
import numpy as np
import pytest
import yaml
from pathlib import Path

from eqrec.lp.model import LPBuilder
from eqrec.arrivals.words import full_delay_language, parse_delay_word
from eqrec.lp.solvers import SOLVER_NAMES, solve_lp, solver_info
from eqrec.design.prefix.design import design_prefix
from eqrec.design.prefix.tree_lp import build_prefix_lp
from eqrec.errors import InputError

ROOT = Path(__file__).resolve().parents[1]


def _tiny_lp():
    b = LPBuilder()
    x = b.add_variables(2, lower=0.0)
    b.set_cost(x, [1.0, 2.0])
    rows = b.add_rows([0, 0], x, [1.0, 1.0], lower=1.0, upper=np.inf, count=1)
    return b, x, rows


@pytest.mark.parametrize("solver", SOLVER_NAMES)
def test_every_registered_solver_solves_a_tiny_lp(solver):
    b, x, _ = _tiny_lp()
    sol = solve_lp(b.build(), solver).require_optimal()
    assert sol.objective == pytest.approx(1.0, abs=1e-6)


def test_unknown_solver_names_the_choices():
    with pytest.raises(ValueError, match="choose one of"):
        solver_info("gurobi")


def test_solver_names_agree_with_the_cli_and_the_schemas():
    from eqrec.cli import _parser

    choices = None
    for action in _parser()._subparsers._group_actions[0].choices["design"]._actions:
        if "--solver" in action.option_strings:
            choices = tuple(action.choices)
    assert choices is not None and tuple(choices) == SOLVER_NAMES
    for schema in (ROOT / "config" / "schemas").glob("*.yaml"):
        text = yaml.safe_load(schema.read_text())

        def enums(node):
            if isinstance(node, dict):
                if "enum" in node and "highs" in node["enum"]:
                    yield tuple(node["enum"])
                for v in node.values():
                    yield from enums(v)
            elif isinstance(node, list):
                for v in node:
                    yield from enums(v)
        for e in enums(text):
            assert set(e) <= set(SOLVER_NAMES), f"{schema.name}: solver enum {e} not in the registry"


def test_tracked_entries_can_be_rewritten_in_place():
    b, x, rows = _tiny_lp()
    h = b.add_entries(np.array([rows[0]]), np.array([x[0]]), np.array([0.0]), track=True)  # kept although zero
    lp = b.build()
    pos = lp.positions(h)
    assert lp.A.data[pos][0] == 1.0  # summed with the existing coefficient
    lp.A.data[pos] = 3.0
    assert solve_lp(lp).objective == pytest.approx(1.0 / 3.0)


def test_robust_index_locates_the_rows_and_entries(acc, L1_words):
    for form in ("split", "abs", "dual"):
        m = build_prefix_lp(acc, L1_words, 1.0, form=form)
        idx = m.robust_index
        assert idx.form == form
        assert all(r.size == m.robust_index.level_rows[0].size for r in idx.level_rows)
        assert idx.gx_entries.size == idx.gx_cols.size > 0


def test_per_node_levels_max_equals_common_and_sum_is_certified_per_node(acc, L1_words):
    common = design_prefix(acc, L1_words, 1.0)
    mx = design_prefix(acc, L1_words, 1.0, levels="max")
    sm = design_prefix(acc, L1_words, 1.0, levels="sum")
    assert mx.mu2 == pytest.approx(common.mu2, abs=1e-8)
    assert sm.mu2 >= common.mu2 - 1e-8
    assert min(sm.levels.values()) < common.mu2  # some prefixes get a lower level than the common one
    assert sm.certificate.mu2 <= sm.mu2 + 1e-8
    with pytest.raises(InputError, match="level structure"):
        build_prefix_lp(acc, L1_words, 1.0, levels="each")


def test_missing_data_language_as_delay_words_gives_the_p1_optimum_exactly(acc, L1_words):
    ref = design_prefix(acc, L1_words, 1.0)
    as_delays = [parse_delay_word(w) for w in ("090000", "009000", "000900", "000090")]
    assert design_prefix(acc, as_delays, 1.0).mu2 == ref.mu2


def test_delay_design_is_certified_and_causal_runs_attain_the_bounds(acc):
    from eqrec.simulate.loop import simulate_run

    pats = [parse_delay_word(w) for w in full_delay_language(4, 1)]
    d = design_prefix(acc, pats, 1.0)
    assert d.certificate.mu2 <= d.mu2 + 1e-8
    gap = 0.0
    for cert in d.certificate.words.values():
        for t in range(1, 5):
            for i in range(acc.n):
                tr = simulate_run(acc, d.schedule, cert.pattern, cert.worst_vertex(t, i), np.zeros(acc.n))
                gap = max(gap, abs(abs(tr.error[t, i]) - cert.bounds[t, i]))
    assert gap < 1e-9


def test_mu1_as_a_variable_pinned_to_m1_gives_the_fixed_m1_optimum(acc, L1_words):
    ref = design_prefix(acc, L1_words, 1.0).mu2
    m = build_prefix_lp(acc, L1_words, 1.0, mu1_range=(1.0, 1.0), mu1_cost=0.0)
    assert solve_lp(m.lp).objective == pytest.approx(ref, abs=1e-9)
    # relaxing the box radius to the interval's lower end gives a lower bound of the cost on the interval
    lo = build_prefix_lp(acc, L1_words, 0.9, mu1_range=(0.9, 1.0), mu1_cost=0.0)
    assert solve_lp(lo.lp).objective <= ref + 1e-9
    with pytest.raises(InputError, match="range of mu1"):
        build_prefix_lp(acc, L1_words, 1.0, mu1_range=(1.0, 0.5))
