"""P2 sweeps: every point classified (second solver for undecided solves, nilpotent L at r = 0), counts add up."""
import numpy as np
import pandas as pd
import pytest

from eqrec.lp.model import LPSolution
from eqrec.design.augmented.word_lp import AugmentedLP
from eqrec.design.augmented.sweep import fixed_L_sweep, observer_for
from eqrec.studies.p2.readings import heatmap_poles
from eqrec.studies.p2.values import CLASSES, class_counts


def test_r0_gets_an_exact_nilpotent_L(acc):
    pp, how = observer_for(acc, heatmap_poles(0.0, 0.7))
    assert how == "deadbeat" and pp.ok
    assert np.linalg.norm(np.linalg.matrix_power(acc.A - pp.L @ acc.C, 3)) < 1e-10
    assert observer_for(acc, heatmap_poles(0.5, 0.7))[1] == "place_poles"
    rec, = fixed_L_sweep(acc, "100111", 1.0, "theorem2", [heatmap_poles(0.0, 0.0)], certify_runtime="theorem2")
    assert rec["status"] == "optimal" and rec["observer"] == "deadbeat"
    assert rec["certified_mu2"] == pytest.approx(rec["mu2"], rel=1e-6)  # Theorem 2: the design is what runs


@pytest.fixture
def undecided_highs(monkeypatch):
    """HiGHS stops with status 'Unknown' (as on some machines); other solvers run for real."""
    real = AugmentedLP.solve

    def solve(self, solver="highs", options=None):
        if solver == "highs":
            return LPSolution("Unknown", None, float("nan"), "highs", 0, 0.0)
        return real(self, solver, options)
    monkeypatch.setattr(AugmentedLP, "solve", solve)


@pytest.mark.parametrize("mode,expected", [("theorem2", "optimal"), ("leak", "infeasible")])
def test_undecided_point_is_classified_by_the_second_solver(acc, undecided_highs, mode, expected):
    poles = [heatmap_poles(0.5, 2.5)]  # leak is infeasible on the left half of the map
    rec, = fixed_L_sweep(acc, "100111", 1.0, mode, poles, "highs", second_solver="clarabel")
    assert rec["status_first"] == "Unknown" and rec["status_second"] == expected
    assert rec["status"] == expected and rec["solver"] == "clarabel"
    if expected == "optimal":
        assert rec["mu2"] == pytest.approx(1.7370933, rel=1e-6)  # the time-based optimum on 100111
    rec, = fixed_L_sweep(acc, "100111", 1.0, mode, poles, "highs", second_solver=None)
    assert rec["status"] == "solver_failed" and rec["status_second"] == "" and np.isnan(rec["mu2"])


def test_second_solver_only_for_undecided_points(acc, monkeypatch):
    calls = []
    real = AugmentedLP.solve
    monkeypatch.setattr(AugmentedLP, "solve", lambda self, solver="highs", options=None:
                        calls.append(solver) or real(self, solver, options))
    fixed_L_sweep(acc, "100111", 1.0, "theorem2", [heatmap_poles(0.5, 1.0)], second_solver="clarabel")
    assert calls == ["highs"]


def test_class_counts_add_up_and_reject_unknown_statuses():
    g = pd.DataFrame({"status": ["optimal", "infeasible", "infeasible", "solver_failed", "placement_failed"],
                      "status_second": ["", "infeasible", "", "Unknown", ""],
                      "observer": ["deadbeat", "place_poles", "place_poles", "place_poles", "place_poles"]})
    c = class_counts(g)
    assert sum(c[k] for k in CLASSES) == c["points"] == 5
    assert c["second_solver_tried"] == 2 and c["second_solver_decided"] == 1 and c["deadbeat"] == 1
    with pytest.raises(ValueError, match="outside"):
        class_counts(g.assign(status=["optimal", "Unknown", "optimal", "optimal", "optimal"]))


def test_chunks_partition_the_grid_and_the_merge_checks_coverage():
    from eqrec.errors import InputError
    from eqrec.studies.pipeline.chunks import check_coverage, chunk_indices

    for num, chunks in ((31, 1), (31, 4), (5, 5)):
        parts = [chunk_indices(num, chunks, k) for k in range(chunks)]
        assert all(len(p) for p in parts) and np.array_equal(np.concatenate(parts), np.arange(num))
    with pytest.raises(InputError, match="chunks 0..3"):
        chunk_indices(31, 4, 4)
    check_coverage(np.arange(6)[::-1], 6)  # every point once, in any order
    with pytest.raises(InputError, match="miss 1 and repeat 1 of the 4"):
        check_coverage(np.array([0, 1, 1, 3]), 4)
    with pytest.raises(InputError, match="1 rows outside"):
        check_coverage(np.arange(5), 4)


def _line(theta: float, n_r: int = 9) -> list[np.ndarray]:
    return [heatmap_poles(r, theta) for r in np.linspace(0.0, 1.5, n_r)]


@pytest.mark.parametrize("mode", ["theorem2", "masked_gain", "leak"])
def test_warm_started_sweep_agrees_with_cold_and_ignores_chunking(acc, mode):
    """Warm starts (each LP from the previous point's basis within a θ line) give each LP's own optimum: the
    same classes as cold solves and the same μ2 to rounding, certified; and the answers of two lines swept
    together equal those of each line swept alone (so the heat map does not depend on its chunks)."""
    one, two = _line(0.6), _line(2.2)
    kw = dict(certify_runtime="theorem2" if mode == "theorem2" else "hold")
    cold = fixed_L_sweep(acc, "100111", 1.0, mode, one + two, **kw)
    both = fixed_L_sweep(acc, "100111", 1.0, mode, one + two, warm_start=len(one), **kw)
    alone = (fixed_L_sweep(acc, "100111", 1.0, mode, one, warm_start=len(one), **kw)
             + fixed_L_sweep(acc, "100111", 1.0, mode, two, warm_start=len(two), **kw))
    assert [r["status"] for r in both] == [r["status"] for r in cold]
    for w, c in zip(both, cold):
        if c["status"] == "optimal":
            assert w["mu2"] == pytest.approx(c["mu2"], rel=1e-9)
            assert w["certified_mu2"] >= w["mu2"] * (1 - 1e-9)  # the gains it returns are certified as they run
    keys = ("status", "mu2", "certified_mu2", "certified_terminal", "solver")
    assert [[r[k] for k in keys] for r in both] == [[r[k] for k in keys] for r in alone]


def test_warm_start_saves_simplex_iterations_and_cold_start_is_solve_lp(acc):
    from eqrec.lp.solvers import solve_lp, solve_lp_warm

    line = _line(0.6)
    model = AugmentedLP(acc, "100111", 1.0, observer_for(acc, line[3])[0].L)
    first, basis = solve_lp_warm(model.lp)
    ref = solve_lp(model.lp, "highs")
    assert first.objective == ref.objective and np.array_equal(first.x, ref.x)  # no basis: the cold solve
    model.set_L(observer_for(acc, line[4])[0].L)
    warm, _ = solve_lp_warm(model.lp, basis)
    cold = solve_lp(model.lp, "highs")
    assert warm.status == cold.status == "optimal"
    assert warm.objective == pytest.approx(cold.objective, rel=1e-12)
    assert warm.iterations < cold.iterations / 2
    with pytest.raises(Exception, match="warm_start"):
        fixed_L_sweep(acc, "100111", 1.0, "theorem2", line, warm_start=-1)
