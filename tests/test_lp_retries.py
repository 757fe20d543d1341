"""solve_lp's retries: a solve without a usable status is retried with other settings, then another solver;
the answer says which attempt gave it, and the CLI says so too (issue 33 §1)."""

import json
from pathlib import Path

import numpy as np
import pytest

from eqrec.errors import SolverFailure
from eqrec.lp import solvers
from eqrec.lp.model import LPSolution
from eqrec.lp.solvers import (RETRIES, SOLVERS, SolverInfo, record_retries, retry_log, scaled_lp, solve_lp,
                              solve_lp_grid)
from tests.test_lp import small_lp

ROOT = Path(__file__).resolve().parents[1]


def _fake(name, fails):
    """A registry entry that answers 'Unknown' (no usable status) when ``fails(options)``, else the real solver."""
    real = SOLVERS[name]

    def solve(lp, options):
        if fails(options):
            return LPSolution("Unknown", None, np.nan, name, 0, 0.0, lp.blocks)
        return real.solve(lp, options)

    return SolverInfo(name, real.description, solve, real.accuracy)


def test_failed_solve_is_retried_with_other_settings(monkeypatch):
    monkeypatch.setitem(SOLVERS, "highs", _fake("highs", lambda o: o.get("presolve") == "off"))
    with retry_log() as log:
        sol = solve_lp(small_lp(), "highs", {"presolve": "off"})
    assert sol.optimal and sol.objective == -8.0 and sol.solver == "highs"
    assert sol.attempts == ("highs, presolve=off: Unknown",)
    assert sol.solved_by == "highs, defaults, cold start"
    assert log == ["highs, defaults, cold start"]
    # without retries: the first answer
    assert solve_lp(small_lp(), "highs", {"presolve": "off"}, retry=False).status == "Unknown"


def test_next_solver_when_every_highs_setting_fails(monkeypatch):
    monkeypatch.setitem(SOLVERS, "highs", _fake("highs", lambda o: True))
    sol = solve_lp(small_lp(), "highs")
    assert sol.optimal and sol.solver == "clarabel" and sol.solved_by == "clarabel"
    assert sol.objective == pytest.approx(-8.0, abs=1e-6)  # Clarabel: interior point, to its tolerance
    # the caller's own solve ({} = the first retry's settings) is not repeated
    assert sol.attempts == ("highs: Unknown", "highs, presolve off: Unknown", "highs, primal simplex: Unknown",
                            "highs, interior point: Unknown", "highs, scaled model: Unknown")


def test_all_attempts_fail_names_them(monkeypatch):
    for name in ("highs", "clarabel"):
        monkeypatch.setitem(SOLVERS, name, _fake(name, lambda o: True))
    with retry_log() as log:
        sol = solve_lp(small_lp(), "highs")
    assert sol.status == "Unknown" and sol.solver == "highs" and len(sol.attempts) == len(RETRIES)
    assert log == ["failed"]
    with pytest.raises(SolverFailure, match=r"status 'Unknown' \(tried: highs: Unknown; highs, presolve off: "
                                            r"Unknown; .*; clarabel: Unknown\)"):
        sol.require_optimal("the test LP")


def test_definitive_status_is_not_retried(monkeypatch):
    calls = []
    real = SOLVERS["highs"]
    monkeypatch.setitem(SOLVERS, "highs", SolverInfo("highs", "", lambda lp, o: calls.append(o) or
                                                     real.solve(lp, o)))
    assert solve_lp(small_lp(infeasible=True), "highs").status == "infeasible" and len(calls) == 1
    # a limit the caller set is the answer (another setting would meet it again)
    sol = solve_lp(small_lp(), "highs", {"simplex_iteration_limit": 0, "presolve": "off"})
    assert sol.status == "Iteration limit reached" and sol.attempts == () and len(calls) == 2


def test_warm_started_grid_solve_that_breaks_down_is_solved_cold(monkeypatch):
    """A HiGHS run of solve_lp_grid without a usable status: that variant from scratch, the others untouched."""
    lp = small_lp()
    costs = [np.array([-1.0, -2.0]), np.array([-2.0, -1.0]), np.array([-1.0, -1.0])]
    plain = solve_lp_grid(lp, costs)[0]
    real_run, runs = solvers._highs_run, []

    def run(h, lp_, cost):
        runs.append(1)
        if len(runs) == 2:  # the second warm-started run breaks down
            h.run()
            return LPSolution("Unknown", None, np.nan, "highs", 0, 0.0, lp_.blocks)
        return real_run(h, lp_, cost)

    monkeypatch.setattr(solvers, "_highs_run", run)
    with retry_log() as log:
        sols = solve_lp_grid(lp, costs)[0]
    assert [s.objective for s in sols] == [s.objective for s in plain]
    assert sols[1].attempts == ("highs, warm start: Unknown",) and sols[1].solved_by == "highs, cold start"
    assert sols[0].attempts == sols[2].attempts == () and log == ["highs, cold start"]


def test_retry_log_is_innermost_only():
    with retry_log() as outer:
        with retry_log() as inner:
            record_retries(["a"])
        record_retries(inner + ["b"])
    assert outer == ["a", "b"]
    record_retries(["c"])  # no active log: dropped
    assert outer == ["a", "b"]


def test_scaled_model_gives_the_same_optimum():
    """The equilibrated model (factors powers of 2) has the same optimum, mapped back to the original's x and y."""
    lp = small_lp()
    lp.A = lp.A * 1e-6
    lp.row_upper = lp.row_upper * 1e-6
    model, R, S = scaled_lp(lp)
    assert np.all(np.log2(R) == np.round(np.log2(R))) and np.all(np.log2(S) == np.round(np.log2(S)))
    assert np.abs(model.A.data).max() / np.abs(model.A.data).min() <= 2.0
    sol = solvers._solve_scaled("highs", lp, {})
    ref = solve_lp(lp, "highs")
    # both are exact vertex solutions of the same LP; the scaled one rounds differently, to the last digits
    np.testing.assert_allclose(sol.x, ref.x, rtol=1e-12)
    np.testing.assert_allclose(sol.row_dual, ref.row_dual, rtol=1e-12)
    assert lp.residual(sol.x) <= 1e-15


def test_scaled_model_with_empty_rows():
    """Rows without entries (last ones included) keep the factor 1; the optimum is the same."""
    import scipy.sparse as sp

    from eqrec.lp.model import LinearProgram

    A = sp.csc_matrix(np.array([[1e-6, 2e3, 0], [0, 0, 0], [3.0, 0, 5e-4], [0, 0, 0]]))
    lp = LinearProgram(c=np.ones(3), A=A, row_lower=np.array([1.0, -np.inf, 1, -np.inf]),
                       row_upper=np.array([np.inf, 0, np.inf, 0]), col_lower=np.zeros(3), col_upper=np.full(3, np.inf))
    _, R, _ = scaled_lp(lp)
    assert R[1] == R[3] == 1.0
    # the same vertex, reached through a differently rounded model: equal to the last digits
    assert solvers._solve_scaled("highs", lp, {}).objective == pytest.approx(solve_lp(lp).objective, rel=1e-14)


def _two_mass():
    """The two carts and a spring of issue 33 (E from the ZOH of velocity disturbances)."""
    from eqrec.systems.affine import AffineSystem
    from eqrec.systems.examples import zoh

    Ac = np.array([[0, 1, 0, 0], [-1, -0.02, 1, 0.02], [0, 0, 0, 1], [1, 0.02, -1, -0.02]], float)
    A, E = zoh(Ac, np.array([[0, 0], [1, 0], [0, 0], [0, 1]], float), 0.1)
    return AffineSystem(A=A, C=np.array([[1.0, 0, 0, 0]]), E=E, eta_w=np.array([0.01, 0.02]), eta_v=0.05)


def test_two_mass_charnes_cooper_lp_is_answered():
    """The LP that stopped the (4, 100) two-mass design with 'Not Set' (HiGHS's dual phase 1 meets a spurious
    unbounded ray on a matrix with entries over 3.5e7 in range): answered, by a retry if the first solve fails."""
    from eqrec.bounds.stacking import Stacking
    from eqrec.design.classes.block_lp import build_ratio_lp, block_lp_options
    from eqrec.design.delay.design import delay_classes

    system = _two_mass()
    classes = delay_classes(max_delay=4, horizon=100)
    ci = next(i for i, c in enumerate(classes.classes) if c.label == "100:" + "1" * 95 + "10111")
    model = build_ratio_lp(system, classes, [ci], Stacking(system, 100), rows=[1])
    sol = solve_lp(model.lp, "highs", block_lp_options("highs"))
    assert sol.optimal
    first = solve_lp(model.lp, "highs", block_lp_options("highs"), retry=False)
    # HiGHS 1.15: the first solve stops with 'Not Set'; the retry with HiGHS's defaults answers
    assert sol.attempts == (() if first.optimal else (f"highs, presolve=off: {first.status}",))
    assert model.lp.residual(sol.x) <= 1e-7  # HiGHS's primal feasibility tolerance (the gains are certified apart)


def test_cli_reports_the_retries(tmp_path, monkeypatch, capsys):
    """The JSON and the summary say which solve answered the LPs the first solve did not."""
    from eqrec.cli import main

    calls = []
    monkeypatch.setitem(SOLVERS, "highs", _fake("highs", lambda o: calls.append(o) or len(calls) == 1))
    out = tmp_path / "d.json"
    rc = main(["design", str(ROOT / "examples" / "acc_system.yaml"), "--method", "delay", "--max-delay", "1",
               "--horizon", "6", "--mu1", "free", "--jobs", "1", "--out", str(out)])
    assert rc == 0
    d = json.loads(out.read_text())
    (solved_by, count), = d["solver_retries"].items()
    assert count == 1 and solved_by.startswith("highs, ")
    assert f"were answered by {solved_by} (1)" in capsys.readouterr().err
