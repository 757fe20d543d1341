"""P3-IMPL (Section III-B3 of the delayed-data paper) and the P3 scale steps.

The switching estimator's logic, periodic reuse on long runs (inside the
guarantees, late packets across a period boundary read as missing), and the
steps of :mod:`eqrec.studies.p3.strategy` run as the pipeline runs them.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from eqrec.bounds.certify import closed_loop_maps
from eqrec.estimators.causal import Packet, RecoveryEstimator
from eqrec.estimators.switching import SwitchingEstimator
from eqrec.arrivals.words import full_delay_language, parse_delay_word
from eqrec.arrivals.draws import NEVER, ArrivalTrace
from eqrec.simulate.long_runs import long_run_periodic, long_run_switching, periodic_model_gap
from eqrec.design.delay.design import design_delay, design_lp_status
from eqrec.design.report import path_levels
from eqrec.studies.p3.size_run import run_size
from eqrec.errors import InputError
from eqrec.systems.examples import batch_reactor
from eqrec.studies.pipeline import harness
from eqrec.studies.p3 import strategy as p3_strategy
from eqrec.studies.pipeline import outputs

MU1_SWITCH = 0.36  # the smallest period-1 level of the batch reactor (0.3553), rounded up


@pytest.fixture(scope="module")
def reactor():
    return batch_reactor()


@pytest.fixture(scope="module")
def periodic_design(reactor):
    return design_delay(reactor, full_delay_language(5, 2), 0.33)


@pytest.fixture(scope="module")
def switching_designs(reactor):
    perf = design_delay(reactor, ["0"], MU1_SWITCH, kind="delay")
    rec = design_delay(reactor, [w for w in full_delay_language(5, 2) if w[0] != "0"], MU1_SWITCH)
    return perf, rec


def _cfg(steps=300, max_period=3, window=40):
    return {"strategy": {
        "steps": steps, "seed": 3, "noise": ["uniform", "vertex"], "cost": "sum",
        "reactor": {"horizon": 5, "max_delay": 2, "mu1": 0.33, "x0": [1.0, 1.0, 1.0, 1.0]},
        "acc": {"words": ["060000", "006000", "000600", "000060"], "mu1": 1.0, "x0": [20.0, 40.0, 20.0],
                "input_force": 206.4},
        "switching": {"mu1": None, "decimals": 2, "p_on_time": 0.8, "max_period": max_period},
        "figure": {"window": window}},
        "scale": {"tree_sizes": [[3, 1], [4, 2]], "tree_slow_sizes": [[5, 2]], "class_sizes": [[4, 2]], "method": "ipm", "builder": "core", "mu1": 0.5, "time_limit": 60,
                  "mem_limit_gb": 4}}


def _run(step, cfg, inputs=None, outputs=None, wildcards=None):
    """Through the harness, as the rules run the step (``step``: ``module:function`` under eqrec.studies.p3)."""
    return harness.run_step(f"eqrec.studies.p3.{step}", cfg, inputs, outputs, wildcards)


# --------------------------------------------------------------------------- the switching estimator

def test_performance_design_is_infeasible_at_the_papers_mu1(reactor):
    """2 outputs, 4 states: no period-1 design at mu1 = 0.33; the smallest period-1 level is about 0.3553."""
    assert design_lp_status(reactor, ["0"], 0.33, kind="delay") == "infeasible"
    assert design_lp_status(reactor, ["0"], MU1_SWITCH, kind="delay") == "optimal"


def test_switches_at_a_late_packet_and_reverts_after_T(reactor, switching_designs):
    perf, rec = switching_designs
    est = SwitchingEstimator(reactor, perf.schedule, rec.schedule).reset(np.zeros(4))
    y = np.zeros(2)
    modes = []
    # y(3) is late by 2 (arrives at 5), y(7) by 2 (arrives at 9: after the phase 3..7, dropped);
    # y(8) on time: back to performance at 8; y(10) missing: a new phase at 10
    arrivals = {0: [0], 1: [1], 2: [2], 3: [], 4: [4], 5: [3, 5], 6: [6], 7: [], 8: [8], 9: [7, 9], 10: [],
                11: [11]}
    prefixes = {}
    for k in range(12):
        est.step([Packet(tau, y) for tau in arrivals[k]])
        modes.append(est.mode)
        if est.mode == "recovery":
            prefixes[k] = est.recovery_prefix
    assert est.switch_times == [3, 10] and est.revert_times == [8]
    assert modes == ["performance"] * 3 + ["recovery"] * 5 + ["performance"] * 2 + ["recovery"] * 2
    # the late y(3) entered the recovery phase as its measurement 0, arriving at phase time 2
    assert prefixes[7].arrivals == (2, 1, 2, 3, None)
    assert prefixes[7] == parse_delay_word("20002")  # y(7): delay 2, past the phase


def test_a_stale_packet_in_performance_mode_is_dropped(reactor, switching_designs):
    perf, rec = switching_designs
    a = SwitchingEstimator(reactor, perf.schedule, rec.schedule).reset(np.zeros(4))
    b = SwitchingEstimator(reactor, perf.schedule, rec.schedule).reset(np.zeros(4))
    rng = np.random.default_rng(0)
    ys = rng.normal(size=(4, 2))
    for k in range(4):
        a.step([Packet(k, ys[k])])
        b.step([Packet(k, ys[k])] + ([Packet(0, ys[0] + 5.0)] if k == 2 else []))  # a stray old packet
        np.testing.assert_array_equal(a.xhat, b.xhat)
    assert a.switch_times == b.switch_times == [] and (a.dropped_packets, b.dropped_packets) == (0, 1)


def test_recovery_language_must_start_late(reactor, switching_designs):
    perf, _ = switching_designs
    with pytest.raises(InputError, match="first measurement late"):
        SwitchingEstimator(reactor, perf.schedule, design_delay(reactor, ["00000", "10000"], 0.5, kind="delay").schedule)
    with pytest.raises(InputError, match="horizon 1"):
        SwitchingEstimator(reactor, switching_designs[1].schedule, switching_designs[1].schedule)


def test_switching_long_run_inside_the_guarantees(reactor, switching_designs):
    perf, rec = switching_designs
    K = p3_strategy.lqr_gain(reactor)
    for kind in ("uniform", "vertex"):
        r = long_run_switching(reactor, perf.schedule, rec.schedule, 2000, np.random.default_rng(1), mu1=MU1_SWITCH,
                               recovery_level=lambda p: rec.levels[p.label], max_delay=2, p_on_time=0.7, kind=kind,
                               x0=np.ones(4), controller=lambda xh: -K @ xh)
        assert r.max_ratio <= 1 + 1e-9
        assert len(r.switch_times) > 50 and r.recovering.any() and (~r.recovering).any()
        # every phase lasts T = 5 steps; every switch happens at a late measurement
        for s in r.switch_times:
            assert r.delays[s] > 0 and r.recovering[s:s + 5].all()
        assert np.all(r.level[1:][~r.recovering] == MU1_SWITCH)


# --------------------------------------------------------------------------- periodic reuse

def test_periodic_long_run_inside_the_guarantees(reactor, periodic_design):
    d = periodic_design
    words = full_delay_language(5, 2)
    K = p3_strategy.lqr_gain(reactor)
    for kind in ("uniform", "vertex"):
        r = long_run_periodic(reactor, d.schedule, words, 400, np.random.default_rng(2), mu1=0.33,
                              path_levels=lambda w: path_levels(d, w), kind=kind, x0=np.ones(4),
                              controller=lambda xh: -K @ xh)
        assert r.delays.size == 2000 and r.max_ratio <= 1 + 1e-9
        assert np.abs(r.error[::5]).max() <= 0.33 + 1e-9  # back below mu1 at every period boundary
        assert r.dropped and periodic_model_gap(r, reactor, d.schedule) < 1e-9


def test_late_across_a_period_boundary_counts_as_missing(reactor, periodic_design):
    """y(4) with delay 2 arrives in the next period: dropped, exactly as the word's pattern (missing) says."""
    d = periodic_design
    pat = parse_delay_word("00002")
    assert pat.arrivals[4] is None  # the language: delay past the horizon = missing
    assert ArrivalTrace(np.array([0, 0, 0, 0, 2, 0, 0, 0, 0, 0])).schedule()[6] == [4, 6]
    rng = np.random.default_rng(5)
    ys = rng.normal(size=(10, 2))
    with_late = RecoveryEstimator(reactor, d.schedule, periodic=True).reset(np.zeros(4))
    without = RecoveryEstimator(reactor, d.schedule, periodic=True).reset(np.zeros(4))
    for t in range(10):
        late = [Packet(4, ys[4])] if t == 6 else []
        on = [] if t == 4 else [Packet(t, ys[t])]
        np.testing.assert_array_equal(with_late.step(on + late)[0], without.step(on)[0])
    assert (with_late.dropped_packets, without.dropped_packets) == (1, 0)
    r = long_run_periodic(reactor, d.schedule, [], 0, np.random.default_rng(3), mu1=0.33,
                          path_levels=lambda w: path_levels(d, w), kind="vertex", sequence=["00002", "00000", "22222", "00000"])
    assert sorted(r.dropped) == [(4, 6), (13, 15), (14, 16)]  # y(12) arrives at 14, inside its period
    assert periodic_model_gap(r, reactor, d.schedule) < 1e-12
    G, c, lay = closed_loop_maps(reactor, d.schedule, pat)
    assert r.max_ratio <= 1 + 1e-9 and G.shape[0] == 6


def test_never_delivered_packets(reactor):
    sched = ArrivalTrace(np.array([0, NEVER, 1, 0])).schedule()
    assert sched == [[0], [], [], [2, 3]]


# --------------------------------------------------------------------------- steps

def test_strategy_steps(tmp_path, published):
    cfg = _cfg()
    out = {"npz": str(tmp_path / "strategy.npz"), "values": str(tmp_path / "strategy_values.json"),
           "timings": str(tmp_path / "timings" / "strategy_values.json")}
    _run("strategy:step_strategy", cfg, outputs=out)
    vals = json.loads(Path(out["values"]).read_text())
    for key in ("periodic_reactor_within", "periodic_acc_within", "switching_within"):
        assert vals[key]["value"] == "inside", vals[key]
        assert vals[key]["evidence"]["max_ratio"] <= 1 + 1e-9
    assert vals["performance_period1_status"]["value"] == "infeasible"
    ev = vals["performance_period1_status"]["evidence"]
    assert 0.355 < ev["mu1_min"] < 0.356 and ev["smallest_period"] == 3
    assert vals["switching_mu1"]["value"] == MU1_SWITCH and vals["switching_mu1"]["evidence"]["lp_status"] == "optimal"
    assert vals["periodic_reactor_within"]["evidence"]["model_gap"] < 1e-9
    assert abs(vals["periodic_reactor_within"]["evidence"]["max_mu2"] - published("P3-BR:max-mu2")) < 5e-5
    for entry in vals.values():  # claims format: numbers, statuses, lists; no prose
        assert set(entry) == {"value", "evidence"}
    figs = {"pdf": str(tmp_path / "fig.pdf"), "png": str(tmp_path / "fig.png")}
    _run("figures:step_strategy_figure", cfg, inputs={"npz": out["npz"]}, outputs=figs)
    assert Path(figs["png"]).stat().st_size > 10_000


def test_scale_steps(tmp_path):
    cfg = _cfg()
    files, timings = [], []
    for T, tau in cfg["scale"]["tree_sizes"]:
        f, t = str(tmp_path / f"T{T}_tau{tau}.json"), str(tmp_path / "timings" / f"T{T}_tau{tau}.json")
        _run("scale_table:step_scale_size", cfg, outputs={"json": f, "timings": t}, wildcards={"T": T, "tau": tau})
        files.append(f)
        timings.append(t)
    rows = [outputs.read_json(f, timings=t) for f, t in zip(files, timings)]
    assert [(r["T"], r["tau"], r["words"], r["sequences"], r["status"]) for r in rows] == [
        (3, 1, 8, 8, "optimal"), (4, 2, 81, 54, "optimal")]
    assert all(r["cols"] > 0 and r["nnz"] > 0 and r["peak_mb"] > 0 for r in rows)
    out = {"csv": str(tmp_path / "scale.csv"), "md": str(tmp_path / "scale.md"),
           "timings_csv": str(tmp_path / "timings" / "scale.csv"), "timings_md": str(tmp_path / "timings" / "scale.md")}
    _run("scale_table:step_scale_table", cfg, inputs={"sizes": files[::-1], "timings": timings[::-1]}, outputs=out)
    import pandas as pd

    frame = pd.read_csv(out["csv"])
    assert frame["T"].tolist() == [3, 4] and frame["status"].tolist() == ["optimal", "optimal"]
    md = Path(out["md"]).read_text()
    assert "| 4 | 2 | 81 | 54 |" in md and "(5, 2)" in md  # the slow size without a row is named


def test_scale_limits_are_reported_not_crashes(reactor):
    assert run_size(reactor, 4, 2, "ipm", time_limit=1e-4, mem_limit_gb=4)["status"] == "time limit"
    r = run_size(reactor, 6, 2, "ipm", time_limit=60, mem_limit_gb=0.25, wall_margin=60)
    assert r["status"] == "memory limit" and r["words"] == 729 and r["nodes"] == 728  # sizes kept
