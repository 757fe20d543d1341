"""P2 pipeline steps on a small configuration, and checks of the paper's printed numbers."""
import json

import numpy as np
import pandas as pd
import pytest
import yaml

from eqrec.errors import InputError
from eqrec.studies.pipeline import harness
from eqrec.studies.pipeline import configuration
from eqrec.studies.p2.readings import one_based_word, variant_word
from eqrec.studies.p2.grids import constant_interval

#: The paths of the steps run here, as the rules name them.
P2_FIGURES = "eqrec.studies.p2.figures:step_"
P2_SWEEPS = "eqrec.studies.p2.sweeps:step_"


def test_one_based_word():
    assert one_based_word("100111") == "110011"
    assert one_based_word("111110") == "111111"  # shifted past the horizon


def test_constant_interval():
    lam = np.linspace(-1, 1, 5)
    assert constant_interval(lam, np.array([2, 1, 1, 1, 2.0]), 1e-9) == [-0.5, 0.5]
    assert constant_interval(lam, np.array([1, 1, np.nan, 1, 1.0]), 1e-9) in ([-1.0, -0.5], [0.5, 1.0])


def test_config_errors(tmp_path):
    p = tmp_path / "c.yaml"
    p.write_text("q: 1\n")
    with pytest.raises(configuration.ConfigError, match="section 'p2'"):
        configuration.load_config("p2", p)
    with pytest.raises(configuration.ConfigError, match="p2.heatmap.chunks"):
        configuration.load_config("p2", overrides={"p2": {"heatmap": {"chunks": 0}}})
    with pytest.raises(configuration.ConfigError, match="p2.heatmap.chunks"):  # more chunks than theta values
        configuration.load_config("p2", overrides={"p2": {"heatmap": {"chunks": 40}}})
    with pytest.raises(configuration.ConfigError, match="p2.f2_words"):
        configuration.load_config("p2", overrides={"p2": {"f2_words": ["1011"]}})
    with pytest.raises(InputError):
        variant_word("100111", "nonsense")


def _claim(cid):
    data = yaml.safe_load(open("config/claims.yaml"))
    return next(c for c in data if c["id"] == cid)


def _eigs(acc, L):
    return np.linalg.eigvals(acc.A - np.asarray(L) @ acc.C)


def test_printed_F1_L_has_printed_eigenvalues(acc):
    ev = _eigs(acc, _claim("P2-F1:L")["paper_value"])
    real = ev[np.abs(ev.imag) < 1e-9].real
    pair = ev[ev.imag > 0][0]
    assert abs(real[0] - 1.04) < 0.005 and abs(pair.real - 0.07) < 0.005 and abs(pair.imag - 0.48) < 0.005


def test_printed_F2_L_eigenvalues_only_within_rounding(acc):
    L = np.asarray(_claim("P2-F2:L")["paper_value"], float)
    ev = _eigs(acc, L)
    real = ev[np.abs(ev.imag) < 1e-9].real[0]
    assert abs(real - (-0.09)) > 0.02  # the rounded L does not have the printed real eigenvalue
    rng = np.random.default_rng(1)

    def ok(d):
        e = _eigs(acc, L + d.reshape(3, 2))
        r = e[np.abs(e.imag) < 1e-9]
        c = e[e.imag > 1e-9]
        return (r.size == 1 and c.size == 1 and abs(r[0].real + 0.09) <= 0.005 and abs(c[0].real - 0.18) <= 0.005
                and abs(c[0].imag - 0.07) <= 0.005)
    assert any(ok(rng.uniform(-0.005, 0.005, 6)) for _ in range(20000))


SMALL = {"runs": 20, "heatmap": {"n_r": 4, "n_theta": 4, "chunks": 2, "variants": ["theorem2", "leak", "masked_gain"]},
         "realaxis": {"n": 7}, "s0_samples": [[1.0, 0.0, -1.0]]}


#: The paths of the P2 steps (as the rules name them).
P2 = {name: f"eqrec.studies.p2.{module}:step_{name}" for module, names in (
    ("steps", ("designs", "simulate", "checks", "printed")), ("sweeps", ("heatmap_chunk", "heatmap_merge", "realaxis")),
    ("values", ("values",))) for name in names}


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """The P2 steps on a small grid, run through the harness as the rules run them (defaults from the schema)."""
    d = tmp_path_factory.mktemp("p2")
    cfg = configuration.load_config("p2", "config/p2.yaml", overrides={"p2": SMALL})
    run = lambda step, ins=None, outs=None, **wc: harness.run_step(P2[step], cfg, ins, outs, wc)  # noqa: E731
    t = d / "timings"
    run("designs", outs={"json": d / "designs.json", "npz": d / "designs.npz", "timings": t / "designs.json"})
    run("simulate", {"designs": d / "designs.npz"}, {"npz": d / "simulation.npz"})
    chunks = []
    for c in range(2):
        chunks.append(d / f"hm_{c}.csv")
        run("heatmap_chunk", outs={"csv": chunks[-1]}, scatteritem=f"{c + 1}-of-2")
    run("heatmap_merge", {"chunks": chunks}, {"csv": d / "heatmap.csv", "timings": t / "heatmap.csv"})
    run("realaxis", outs={"csv": d / "realaxis.csv", "timings": t / "realaxis.csv"})
    run("checks", outs={"json": d / "checks.json", "timings": t / "checks.json"})
    run("printed", {"claims": "config/claims.yaml"}, {"json": d / "printed.json"})
    vals = run("values", {"designs": d / "designs.json", "simulation": d / "simulation.npz",
                          "heatmap": d / "heatmap.csv", "realaxis": d / "realaxis.csv", "checks": d / "checks.json",
                          "printed": d / "printed.json"},
               {"json": d / "values.json"})
    return d, cfg, vals


def test_pipeline_values(small_run, acc):
    d, cfg, _ = small_run
    vals = json.loads((d / "values.json").read_text())
    tb = vals["f2_mu2_time"]["value"]
    assert vals["f2_mu2_augmented"]["value"] == pytest.approx(tb, rel=1e-6)  # augmented ⊂ time-based
    assert vals["f1_mu2_augmented"]["value"] == pytest.approx(vals["f1_mu2_time"]["value"], rel=1e-6)
    assert vals["f2_mu2_one_based_augmented"]["value"] < tb - 0.1
    assert vals["s0_mu2_unchanged"]["value"] == "unchanged"
    assert vals["runtime_equivalence"]["value"] < 1e-9
    assert vals["f2_mu2_augmented"]["evidence"]["one_based"]["word"] == "110011"
    hm = pd.read_csv(d / "heatmap.csv")
    assert len(hm) == 3 * 16
    r0 = hm[hm["r"] == 0]
    assert set(r0["observer"]) == {"deadbeat"}  # an exact nilpotent L, not a placement failure
    assert set(r0[r0["variant"] == "theorem2"]["status"]) == {"optimal"}
    variants = vals["f3a_mu2_region"]["evidence"]["variants"]
    for c in variants.values():  # every grid point has exactly one class
        assert c["optimal"] + c["infeasible"] + c["solver_failed"] + c["placement_failed"] == c["points"] == 16
        assert c["deadbeat"] == 4
    for c in vals["f3b_interval"]["evidence"]["variants"].values():
        assert sum(c["counts"][k] for k in ("optimal", "infeasible", "solver_failed", "placement_failed")) \
            == c["counts"]["points"] == 43  # 7 points, all on the k/14 grid
    # the printed Fig. 2 L: the masked_gain design LP and its gains as the estimator that runs
    mg = vals["f2_mu2_masked_gain"]
    assert mg["evidence"]["theorem2_mu2"] == pytest.approx(tb, rel=1e-6)
    assert mg["value"] < tb - 0.1 and vals["f2_time_vs_masked_gain"]["value"] == "larger"
    cert = vals["f2_masked_gain_certified"]
    assert cert["value"] > tb and cert["evidence"]["hold_terminal"] > 1.0  # worse than a runnable design
    ao = cert["evidence"]["among_optima"]  # the best any optimum gives as run: at most each solver's pick
    assert ao["agree"] and all(cert["value"] <= b["hold"] * (1 + 1e-6) for b in cert["evidence"]["by_solver"].values())
    sim = np.load(d / "simulation.npz")
    assert sim["f1/time"].shape == (20, 7, 3)


def test_heatmap_merge_rejects_a_partial_or_repeated_grid(small_run, tmp_path):
    d, cfg, _ = small_run
    chunks = sorted(d.glob("hm_*.csv"))
    with pytest.raises(InputError, match="miss 8"):
        harness.run_step(P2_SWEEPS + "heatmap_merge", cfg, {"chunks": chunks[:-1]},
                         {"csv": tmp_path / "h.csv", "timings": tmp_path / "t.csv"})
    with pytest.raises(InputError, match="repeat"):
        harness.run_step(P2_SWEEPS + "heatmap_merge", cfg, {"chunks": chunks + chunks[:1]},
                         {"csv": tmp_path / "h.csv", "timings": tmp_path / "t.csv"})
    assert not (tmp_path / "h.csv").exists()


def test_figures(small_run, tmp_path):
    from pathlib import Path

    from eqrec.studies.claims.published import published_value

    d, cfg, _ = small_run
    claims = Path(__file__).resolve().parents[1] / "config" / "claims.yaml"
    # the rules add the paper's values (config/claims.yaml) to the figures' cfg
    paper = {"f1": published_value(claims, "P2-F1:mu2-augmented"), "f2": published_value(claims, "P2-F2:mu2-augmented"),
             "mu2": published_value(claims, "P2-F3a:mu2-region")}
    cfg = {**cfg, "published": paper}
    for fig in ("f1", "f2"):
        harness.run_step(P2_FIGURES + "figure_trajectories", cfg,
                         {"designs": d / "designs.json", "simulation": d / "simulation.npz"},
                         {"pdf": tmp_path / f"{fig}.pdf", "png": tmp_path / f"{fig}.png"}, {"fig": fig})
    harness.run_step(P2_FIGURES + "figure_heatmap", cfg, {"csv": d / "heatmap.csv", "printed": d / "printed.json"},
                     {"pdf": tmp_path / "h.pdf", "png": tmp_path / "h.png"})
    harness.run_step(P2_FIGURES + "figure_realaxis", cfg, {"csv": d / "realaxis.csv", "printed": d / "printed.json"},
                     {"pdf": tmp_path / "r.pdf", "png": tmp_path / "r.png"})
    assert all((tmp_path / f).stat().st_size > 1000 for f in ("f1.png", "f2.png", "h.png", "r.png"))
