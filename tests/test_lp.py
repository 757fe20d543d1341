import numpy as np
import pytest

from eqrec.errors import InfeasibleDesign
from eqrec.lp.model import LPBuilder
from eqrec.lp.solvers import solve_lp


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


# -- one HiGHS status table for both HiGHS drivers (highspy and SciPy's linprog) ----------------------------------

@pytest.mark.parametrize("presolve", [True, False])
@pytest.mark.parametrize("kind,status,objective", [("optimal", "optimal", -8.0), ("infeasible", "infeasible", np.inf),
                                                   ("unbounded", "unbounded", -np.inf)])
def test_highs_drivers_agree(kind, status, objective, presolve):
    """highspy and SciPy's linprog (HiGHS inside) give the same status and objective on the same small LPs."""
    lp = lambda: small_lp(infeasible=kind == "infeasible", unbounded=kind == "unbounded")  # noqa: E731
    direct = solve_lp(lp(), "highs", {} if presolve else {"presolve": "off"})
    scipy = solve_lp(lp(), "scipy", {} if presolve else {"presolve": False})
    assert (direct.status, scipy.status) == (status, status)
    assert direct.objective == pytest.approx(objective) and scipy.objective == pytest.approx(objective)
    assert (direct.x is None, scipy.x is None) == (kind != "optimal",) * 2


@pytest.mark.parametrize("highs_options,scipy_options,status", [
    ({"simplex_iteration_limit": 0}, {"maxiter": 0}, "Iteration limit reached"),
    ({"time_limit": 0.0}, {"time_limit": 0.0}, "Time limit reached")])
def test_highs_drivers_agree_on_limits(highs_options, scipy_options, status):
    """A limit reads the same through both drivers (SciPy's own message used to be the status)."""
    direct = solve_lp(small_lp(), "highs", {"presolve": "off", **highs_options})
    scipy = solve_lp(small_lp(), "scipy", {"presolve": False, **scipy_options})
    assert (direct.status, scipy.status) == (status, status)
    assert np.isnan(direct.objective) and np.isnan(scipy.objective) and direct.x is None and scipy.x is None


def test_highs_status_table():
    """Every HiGHS model status is in the table; the non-definitive ones in HiGHS's own words."""
    highspy = pytest.importorskip("highspy")
    from eqrec.lp.solvers import HIGHS_STATUS, highs_status

    h = highspy.Highs()
    members = {int(getattr(highspy.HighsModelStatus, name)): getattr(highspy.HighsModelStatus, name)
               for name in dir(highspy.HighsModelStatus) if name.startswith("k")}
    assert set(members) == set(HIGHS_STATUS)
    definitive = {"kOptimal": "optimal", "kInfeasible": "infeasible", "kUnboundedOrInfeasible": "infeasible",
                  "kUnbounded": "unbounded"}
    for code, member in members.items():
        assert HIGHS_STATUS[code] == definitive.get(member.name, h.modelStatusToString(member)), member.name
    assert highs_status(9) == ("infeasible", np.inf) and highs_status(10) == ("unbounded", -np.inf)
    status, objective = highs_status(15)
    assert status == "Unknown" and np.isnan(objective)
    assert highs_status(99, "odd")[0] == "odd" and highs_status(99)[0] == "HiGHS model status 99"


def _highs_lp_model(lp, options):
    """The LP loaded field by field in a ``highspy.HighsLp`` (how :func:`highs_model` loaded it before)."""
    import highspy

    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    for key, val in options.items():
        h.setOptionValue(key, val)
    model = highspy.HighsLp()
    nr, nc = lp.A.shape
    model.num_col_, model.num_row_ = nc, nr
    model.col_cost_, model.col_lower_, model.col_upper_ = lp.c, lp.col_lower, lp.col_upper
    model.row_lower_, model.row_upper_ = lp.row_lower, lp.row_upper
    model.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    model.a_matrix_.start_, model.a_matrix_.index_, model.a_matrix_.value_ = lp.A.indptr, lp.A.indices, lp.A.data
    model.a_matrix_.num_col_, model.a_matrix_.num_row_ = nc, nr
    h.passModel(model)
    return h


@pytest.mark.parametrize("options", [{}, {"presolve": "off", "simplex_strategy": 4}])
def test_highs_model_loads_the_lp_entry_for_entry(options):
    """highs_model passes NumPy buffers to HiGHS: the model it holds is the LP's, entry for entry, and its runs
    give the bytes of the same LP loaded through highspy.HighsLp (values, multipliers and iterations)."""
    import scipy.sparse as sp

    from eqrec.lp.model import LinearProgram
    from eqrec.lp.solvers import highs_model

    rng = np.random.default_rng(7)
    A = sp.random(30, 80, density=0.4, format="csc", random_state=3)
    lp = LinearProgram(c=rng.standard_normal(80), A=A, row_lower=np.zeros(30), row_upper=np.r_[np.zeros(20),
                       np.full(10, np.inf)], col_lower=-rng.random(80), col_upper=np.r_[rng.random(79), np.inf])
    h = highs_model(lp, options)
    held = h.getLp()
    for mine, theirs in [(lp.c, held.col_cost_), (lp.col_lower, held.col_lower_), (lp.col_upper, held.col_upper_),
                         (lp.row_lower, held.row_lower_), (lp.row_upper, held.row_upper_),
                         (A.indptr, held.a_matrix_.start_), (A.indices, held.a_matrix_.index_),
                         (A.data, held.a_matrix_.value_)]:
        np.testing.assert_array_equal(np.asarray(theirs), mine)
    reference = _highs_lp_model(lp, options)
    for k in range(3):  # a cold run, then warm runs after a change of objective, as solve_lp_grid does
        cost = lp.c if k == 0 else rng.standard_normal(80)
        for model in (h, reference):
            model.changeColsCost(80, np.arange(80, dtype=np.int32), cost)
            model.run()
        a, b = h.getSolution(), reference.getSolution()
        assert h.getModelStatus() == reference.getModelStatus()
        assert h.getInfo().simplex_iteration_count == reference.getInfo().simplex_iteration_count
        for x, y in [(a.col_value, b.col_value), (a.row_dual, b.row_dual), (a.col_dual, b.col_dual)]:
            assert np.asarray(x).tobytes() == np.asarray(y).tobytes()
