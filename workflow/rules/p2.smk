# P2: state-augmented estimator (Hassaan, Shen, Yong, ACC 2019).
# Each rule runs one step of eqrec.studies.p2 (steps, sweeps, values, figures) through the harness (common.smk).
# The heat map runs in p2.heatmap.chunks scattergather jobs (the resolved
# configuration, or --set-scatter heatmap=N), each every configured variant;
# the merge checks that they cover the grid exactly once. The chunks are temp()
# files under intermediate/ (not results/; see common.smk).


scattergather:
    heatmap=config["p2"]["heatmap"]["chunks"],


use rule step as p2_designs with:
    """P2-F1, P2-F2: time-based, augmented LP and IPOPT designs and the readings, certified."""
    input:
        code=code_inputs("eqrec.studies.p2.steps:step_designs"),
    output:
        json="results/p2/designs.json",
        timings="results/timings/p2/designs.json",
        npz="results/p2/designs.npz",
    log:
        "logs/p2/designs.log",
    priority: 3  # the head of a chain of four jobs before the P2 values (common.smk, "Scheduling")
    params:
        step="eqrec.studies.p2.steps:step_designs",
        cfg=step_config("p2", "T f1_words f2_words init_poles mu1"),


use rule step as p2_simulate with:
    """P2-F1, P2-F2: Monte Carlo, every estimator on the same draws."""
    input:
        designs="results/p2/designs.npz",
        code=code_inputs("eqrec.studies.p2.steps:step_simulate"),
    output:
        npz="results/p2/simulation.npz",
    log:
        "logs/p2/simulate.log",
    priority: 3  # the head of a chain of four jobs before the P2 values (common.smk, "Scheduling")
    params:
        step="eqrec.studies.p2.steps:step_simulate",
        cfg=step_config("p2", "f1_words f2_words mu1 noise runs seed x0"),


use rule step as p2_heatmap_chunk with:
    """P2-F3a: one theta-chunk of the eigenvalue sweep, every variant (one LP per variant, L values updated)."""
    input:
        code=code_inputs("eqrec.studies.p2.sweeps:step_heatmap_chunk"),
    output:
        csv=temp("intermediate/p2/heatmap/chunk_{scatteritem}.csv"),
    log:
        "logs/p2/heatmap_chunk_{scatteritem}.log",
    priority: 7  # about its seconds of CPU: the long jobs start first (common.smk, "Scheduling")
    params:
        step="eqrec.studies.p2.sweeps:step_heatmap_chunk",
        cfg=step_config("p2", "heatmap mu1"),


use rule step as p2_heatmap_merge with:
    """P2-F3a: the whole grid (every configured variant and chunk, checked to cover it exactly once)."""
    input:
        chunks=gather.heatmap("intermediate/p2/heatmap/chunk_{scatteritem}.csv"),
        code=code_inputs("eqrec.studies.p2.sweeps:step_heatmap_merge"),
    output:
        csv="results/p2/heatmap.csv",
        timings="results/timings/p2/heatmap.csv",
    log:
        "logs/p2/heatmap_merge.log",
    params:
        step="eqrec.studies.p2.sweeps:step_heatmap_merge",
        cfg=step_config("p2", heatmap="chunks n_r n_theta r_max variants"),


use rule step as p2_realaxis with:
    """P2-F3b: real double eigenvalue sweep."""
    input:
        code=code_inputs("eqrec.studies.p2.sweeps:step_realaxis"),
    output:
        csv="results/p2/realaxis.csv",
        timings="results/timings/p2/realaxis.csv",
    log:
        "logs/p2/realaxis.log",
    priority: 5  # about its seconds of CPU: the long jobs start first (common.smk, "Scheduling")
    params:
        step="eqrec.studies.p2.sweeps:step_realaxis",
        cfg=step_config(
            "p2",
            "mu1 realaxis",
            heatmap="second_solver solver variants warm_start word",
        ),


use rule step as p2_checks with:
    """P2-S0, P2-SOLVER."""
    input:
        code=code_inputs("eqrec.studies.p2.steps:step_checks"),
    output:
        json="results/p2/checks.json",
        timings="results/timings/p2/checks.json",
    log:
        "logs/p2/checks.log",
    priority: 4  # about its seconds of CPU: the long jobs start first (common.smk, "Scheduling")
    params:
        step="eqrec.studies.p2.steps:step_checks",
        cfg=step_config(
            "p2", "f2_words init_poles mu1 noise runs s0_samples seed solvers x0"
        ),


use rule step as p2_printed with:
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


use rule step as p2_values with:
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


use rule step as p2_figure_trajectories with:
    """P2-F1 / P2-F2 figures."""
    input:
        designs="results/p2/designs.json",
        simulation="results/p2/simulation.npz",
        code=code_inputs("eqrec.studies.p2.figures:step_figure_trajectories"),
    output:
        **figure("results/p2/{fig}_trajectories", "p2_trajectories", "P2"),
    log:
        "logs/p2/figure_{fig}.log",
    wildcard_constraints:
        fig="f1|f2",
    params:
        step="eqrec.studies.p2.figures:step_figure_trajectories",
        # the paper's mu2 of each figure (config/claims.yaml), drawn for comparison
        cfg=step_config("p2", "mu1")
        | published(f1="P2-F1:mu2-augmented", f2="P2-F2:mu2-augmented"),


use rule step as p2_figure_heatmap with:
    """P2-F3a figure."""
    input:
        csv="results/p2/heatmap.csv",
        printed="results/p2/printed.json",
        code=code_inputs("eqrec.studies.p2.figures:step_figure_heatmap"),
    output:
        **figure("results/p2/f3a_heatmap", "p2_f3a", "P2"),
    log:
        "logs/p2/figure_f3a.log",
    params:
        step="eqrec.studies.p2.figures:step_figure_heatmap",
        cfg=step_config("p2", "mu2_tol", heatmap="n_r n_theta r_max variants")
        # the paper's smallest mu2 (config/claims.yaml): a labelled tick of the colour bar
        | published(mu2="P2-F3a:mu2-region"),


use rule step as p2_figure_realaxis with:
    """P2-F3b figure."""
    input:
        csv="results/p2/realaxis.csv",
        printed="results/p2/printed.json",
        code=code_inputs("eqrec.studies.p2.figures:step_figure_realaxis"),
    output:
        **figure("results/p2/f3b_realaxis", "p2_f3b", "P2"),
    log:
        "logs/p2/figure_f3b.log",
    params:
        step="eqrec.studies.p2.figures:step_figure_realaxis",


rule p2:
    """All P2 outputs."""
    input:
        rules.p2_values.output,
        expand("results/p2/{fig}_trajectories.pdf", fig=["f1", "f2"]),
        rules.p2_figure_heatmap.output,
        rules.p2_figure_realaxis.output,
        rules.p2_checks.output,
