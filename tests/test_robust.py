import itertools

import numpy as np
import pytest
import scipy.sparse as sp

from eqrec.lp.model import LPBuilder
from eqrec.lp.solvers import solve_lp
from eqrec.lp.robust import UncertainAffineRows, add_robust_rows, worst_case_abs, worst_case_vertex


def test_worst_case_matches_vertex_enumeration(rng):
    G = rng.normal(size=(4, 5))
    c = rng.normal(size=4)
    b = rng.uniform(0.1, 2, 5)
    brute = np.max([np.abs(c + G @ (np.array(s) * b)) for s in itertools.product([-1, 1], repeat=5)], axis=0)
    np.testing.assert_allclose(worst_case_abs(G, c, b), brute)
    for k in range(4):
        v = worst_case_vertex(G[k], c[k], b)
        assert abs(c[k] + G[k] @ v) == pytest.approx(worst_case_abs(G, c, b)[k])


def _random_problem(rng, form):
    # min level  s.t. |c(x) + G(x) δ| <= level for all |δ| <= b, with G, c affine in x.
    R, D, nx = 3, 4, 3
    b = LPBuilder()
    level = int(b.add_variables(1, lower=0.0, name="level")[0])
    x = b.add_variables(nx, lower=-5, upper=5, name="x")
    b.set_cost(level, 1.0)
    er, ec = np.divmod(np.arange(R * D), D)
    G0 = rng.normal(size=R * D)
    Gx = rng.normal(size=(R * D, b.num_variables)) * (rng.uniform(size=(R * D, b.num_variables)) < 0.3)
    Gx[:, level] = 0
    cx = rng.normal(size=(R, b.num_variables)) * (rng.uniform(size=(R, b.num_variables)) < 0.5)
    cx[:, level] = 0
    rows = UncertainAffineRows(er, ec, G0, sp.csr_matrix(Gx), rng.normal(size=R), sp.csr_matrix(cx))
    radius = np.array([0.5, 1.0, 0.2, 2.0])
    add_robust_rows(b, rows, radius, level_const=0.0, level_col=level, form=form)
    return b.build(), rows, radius, level, x


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("form", ["split", "abs"])
def test_forms_equal_paper_dual_form(seed, form):
    lp_abs, rows, radius, level, x = _random_problem(np.random.default_rng(seed), form)
    lp_dual, *_ = _random_problem(np.random.default_rng(seed), "dual")
    s1, s2 = solve_lp(lp_abs), solve_lp(lp_dual)
    assert s1.optimal and s2.optimal
    assert s1.objective == pytest.approx(s2.objective, abs=1e-8)
    # and the optimum is the true worst case of the optimal x
    xs = s1.x[: rows.Gx.shape[1]]
    G = np.zeros((3, 4))
    G[rows.entry_row, rows.entry_coord] = rows.G0 + rows.Gx @ xs
    c = rows.c0 + rows.cx @ xs
    assert worst_case_abs(G, c, radius).max() == pytest.approx(s1.objective, abs=1e-7)


def test_unknown_form():
    with pytest.raises(ValueError):
        _random_problem(np.random.default_rng(0), "primal")
