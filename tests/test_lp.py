import numpy as np
import pytest

from eqrec.errors import InfeasibleDesign
from eqrec.core.lp import LPBuilder
from eqrec.core.solvers import solve_lp


def small_lp(infeasible=False, unbounded=False):
    b = LPBuilder()
    x = b.add_variables(2, lower=0.0, name="x")
    b.set_cost(x, [-1.0, -2.0] if not unbounded else [-1.0, 0.0])
    if not unbounded:
        b.add_rows([0, 0, 1, 1], [x[0], x[1], x[0], x[1]], [1, 1, 1, -1], lower=-np.inf, upper=[4, 1])
    if infeasible:
        b.add_rows([0], [x[0]], [1.0], lower=10, upper=np.inf)
    return b.build()


@pytest.mark.parametrize("solver", ["highs", "clarabel", "scipy"])
def test_solvers_agree(solver):
    sol = solve_lp(small_lp(), solver)
    assert sol.optimal
    assert sol.objective == pytest.approx(-8.0, abs=1e-6)
    np.testing.assert_allclose(sol.block("x"), [0, 4], atol=1e-6)


@pytest.mark.parametrize("solver", ["highs", "clarabel", "scipy"])
def test_infeasible_and_unbounded(solver):
    sol = solve_lp(small_lp(infeasible=True), solver)
    assert sol.status == "infeasible"
    with pytest.raises(InfeasibleDesign):
        sol.require_optimal()
    assert solve_lp(small_lp(unbounded=True), solver).status in ("unbounded", "infeasible")


def test_unknown_solver():
    with pytest.raises(ValueError, match="unknown solver"):
        solve_lp(small_lp(), "gurobi")
