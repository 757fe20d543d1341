# P2: state-augmented estimator (Hassaan, Shen, Yong, ACC 2019).
# Each rule runs one step of eqrec.studies.p2 (steps, sweeps, values, figures) through the harness (common.smk).
# The heat map runs in p2.heatmap.chunks scattergather jobs (the resolved
# configuration, or --set-scatter heatmap=N), each every configured variant;
# the merge checks that they cover the grid exactly once.


scattergather:
    heatmap=config["p2"]["heatmap"]["chunks"],


rule p2_designs:
    """P2-F1, P2-F2: time-based, augmented LP and IPOPT designs and the readings, certified."""
    input:
        code=code_inputs("eqrec.studies.p2.steps:step_designs"),
    output:
        json="results/p2/designs.json",
        timings="results/timings/p2/designs.json",
        npz="results/p2/designs.npz",
    log:
        "logs/p2/designs.log",
    params:
        step="eqrec.studies.p2.steps:step_designs",
        cfg=step_config("p2", "T f1_words f2_words init_poles mu1"),
    script:
        RUN_STEP


rule p2_simulate:
    """P2-F1, P2-F2: Monte Carlo, every estimator on the same draws."""
    input:
        designs="results/p2/designs.npz",
        code=code_inputs("eqrec.studies.p2.steps:step_simulate"),
    output:
        npz="results/p2/simulation.npz",
    log:
        "logs/p2/simulate.log",
    params:
        step="eqrec.studies.p2.steps:step_simulate",
        cfg=step_config("p2", "f1_words f2_words mu1 noise runs seed x0"),
    script:
        RUN_STEP


rule p2_heatmap_chunk:
    """P2-F3a: one theta-chunk of the eigenvalue sweep, every variant (one LP per variant, L values updated)."""
    input:
        code=code_inputs("eqrec.studies.p2.sweeps:step_heatmap_chunk"),
    output:
        csv=temp("results/p2/heatmap/chunk_{scatteritem}.csv"),
    log:
        "logs/p2/heatmap_chunk_{scatteritem}.log",
    params:
        step="eqrec.studies.p2.sweeps:step_heatmap_chunk",
        cfg=step_config("p2", "heatmap mu1"),
    script:
        RUN_STEP


rule p2_heatmap_merge:
    """P2-F3a: the whole grid (every configured variant and chunk, checked to cover it exactly once)."""
    input:
        chunks=gather.heatmap("results/p2/heatmap/chunk_{scatteritem}.csv"),
        code=code_inputs("eqrec.studies.p2.sweeps:step_heatmap_merge"),
    output:
        csv="results/p2/heatmap.csv",
        timings="results/timings/p2/heatmap.csv",
    log:
        "logs/p2/heatmap_merge.log",
    params:
        step="eqrec.studies.p2.sweeps:step_heatmap_merge",
        cfg=step_config("p2", heatmap="chunks n_r n_theta r_max variants"),
    script:
        RUN_STEP


rule p2_realaxis:
    """P2-F3b: real double eigenvalue sweep."""
    input:
        code=code_inputs("eqrec.studies.p2.sweeps:step_realaxis"),
    output:
        csv="results/p2/realaxis.csv",
        timings="results/timings/p2/realaxis.csv",
    log:
        "logs/p2/realaxis.log",
    params:
        step="eqrec.studies.p2.sweeps:step_realaxis",
        cfg=step_config(
            "p2", "mu1 realaxis", heatmap="second_solver solver variants word"
        ),
    script:
        RUN_STEP


rule p2_checks:
    """P2-S0, P2-SOLVER."""
    input:
        code=code_inputs("eqrec.studies.p2.steps:step_checks"),
    output:
        json="results/p2/checks.json",
        timings="results/timings/p2/checks.json",
    log:
        "logs/p2/checks.log",
    params:
        step="eqrec.studies.p2.steps:step_checks",
        cfg=step_config(
            "p2", "f2_words init_poles mu1 noise runs s0_samples seed solvers x0"
        ),
    script:
        RUN_STEP


rule p2_printed:
    """P2-F2 at the paper's printed L (read from config/claims.yaml): theorem2 and masked_gain LPs, the
    masked_gain gains certified as the estimator that runs; nilpotent L at r = 0."""
    input:
        claims=ancient("config/claims.yaml"),
        code=code_inputs("eqrec.studies.p2.steps:step_printed"),
    output:
        json="results/p2/printed.json",
    log:
        "logs/p2/printed.log",
    params:
        step="eqrec.studies.p2.steps:step_printed",
        cfg=step_config("p2", "T f2_words heatmap.solver mu1 printed solvers"),
        published=[
            published_value(CLAIMS_FILE, config["p2"]["printed"][k])
            for k in ("L_claim", "interval_claim")
        ],
    script:
        RUN_STEP


rule p2_values:
    """Our value of every published P2 number, with its evidence."""
    input:
        designs="results/p2/designs.json",
        simulation="results/p2/simulation.npz",
        heatmap="results/p2/heatmap.csv",
        realaxis="results/p2/realaxis.csv",
        checks="results/p2/checks.json",
        printed="results/p2/printed.json",
        code=code_inputs("eqrec.studies.p2.values:step_values"),
    output:
        json="results/p2/values.json",
    log:
        "logs/p2/values.log",
    params:
        step="eqrec.studies.p2.values:step_values",
        cfg=step_config(
            "p2", "init_poles mu1 mu2_tol realaxis", heatmap="n_r n_theta r_max"
        ),
    script:
        RUN_STEP


rule p2_figure_trajectories:
    """P2-F1 / P2-F2 figures."""
    input:
        designs="results/p2/designs.json",
        simulation="results/p2/simulation.npz",
        code=code_inputs("eqrec.studies.p2.figures:step_figure_trajectories"),
    output:
        pdf="results/p2/{fig}_trajectories.pdf",
        png=report(
            "results/p2/{fig}_trajectories.png",
            caption="../report/p2_trajectories.rst",
            category="P2",
        ),
    log:
        "logs/p2/figure_{fig}.log",
    wildcard_constraints:
        fig="f1|f2",
    params:
        step="eqrec.studies.p2.figures:step_figure_trajectories",
        # the paper's mu2 of each figure (config/claims.yaml), drawn for comparison
        cfg=step_config("p2", "mu1")
        | published(f1="P2-F1:mu2-augmented", f2="P2-F2:mu2-augmented"),
    script:
        RUN_STEP


rule p2_figure_heatmap:
    """P2-F3a figure."""
    input:
        csv="results/p2/heatmap.csv",
        printed="results/p2/printed.json",
        code=code_inputs("eqrec.studies.p2.figures:step_figure_heatmap"),
    output:
        pdf="results/p2/f3a_heatmap.pdf",
        png=report(
            "results/p2/f3a_heatmap.png", caption="../report/p2_f3a.rst", category="P2"
        ),
    log:
        "logs/p2/figure_f3a.log",
    params:
        step="eqrec.studies.p2.figures:step_figure_heatmap",
        cfg=step_config("p2", "mu2_tol", heatmap="n_r n_theta r_max variants")
        # the paper's smallest mu2 (config/claims.yaml): a labelled tick of the colour bar
        | published(mu2="P2-F3a:mu2-region"),
    script:
        RUN_STEP


rule p2_figure_realaxis:
    """P2-F3b figure."""
    input:
        csv="results/p2/realaxis.csv",
        printed="results/p2/printed.json",
        code=code_inputs("eqrec.studies.p2.figures:step_figure_realaxis"),
    output:
        pdf="results/p2/f3b_realaxis.pdf",
        png=report(
            "results/p2/f3b_realaxis.png",
            caption="../report/p2_f3b.rst",
            category="P2",
        ),
    log:
        "logs/p2/figure_f3b.log",
    params:
        step="eqrec.studies.p2.figures:step_figure_realaxis",
    script:
        RUN_STEP


rule p2:
    """All P2 outputs."""
    input:
        rules.p2_values.output,
        expand("results/p2/{fig}_trajectories.pdf", fig=["f1", "f2"]),
        rules.p2_figure_heatmap.output,
        rules.p2_figure_realaxis.output,
        rules.p2_checks.output,
