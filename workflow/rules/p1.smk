# P1: prefix-based estimator (Rutledge, Yong, Ozay, ACC 2019).
# Each rule runs one step of eqrec.studies.p1.steps through the harness (common.smk).


use rule step as p1_model with:
    """P1-T1: ACC model from the Table I constants."""
    input:
        code=code_inputs("eqrec.studies.p1.steps:step_model"),
    output:
        json="results/p1/model.json",
    log:
        "logs/p1/model.log",
    params:
        step="eqrec.studies.p1.steps:step_model",
        cfg=step_config("p1", "acc_constants"),


use rule step as p1_designs with:
    """P1-M2, P1-TIME: prefix- and time-based designs on L1, certified, timed, probed."""
    input:
        code=code_inputs("eqrec.studies.p1.steps:step_designs"),
    output:
        json="results/p1/designs.json",
        timings="results/timings/p1/designs.json",
    log:
        "logs/p1/designs.log",
    params:
        step="eqrec.studies.p1.steps:step_designs",
        cfg=step_config(
            "p1",
            "acc_constants language mu1 probe_gap probe_solvers solvers timing_repeats",
        ),


use rule step as p1_simulate with:
    """P1-F1: Monte Carlo runs of both estimators on the same draws."""
    input:
        code=code_inputs("eqrec.studies.p1.steps:step_simulate"),
    output:
        npz="results/p1/simulation.npz",
    log:
        "logs/p1/simulate.log",
    params:
        step="eqrec.studies.p1.steps:step_simulate",
        cfg=step_config("p1", "acc_constants language mu1 simulation"),


use rule step as p1_figure1 with:
    """P1-F1 figure."""
    input:
        npz="results/p1/simulation.npz",
        code=code_inputs("eqrec.studies.p1.figures:step_figure1"),
    output:
        **figure("results/p1/fig1_trajectories", "p1_fig1", "P1"),
    log:
        "logs/p1/figure1.log",
    params:
        step="eqrec.studies.p1.figures:step_figure1",


use rule step as p1_extensions with:
    """P1-EXT: M2*(M1), minimum M1, finite-length language, minimum T."""
    input:
        code=code_inputs("eqrec.studies.p1.steps:step_extensions"),
    output:
        json="results/p1/extensions.json",
    log:
        "logs/p1/extensions.log",
    params:
        step="eqrec.studies.p1.steps:step_extensions",
        cfg=step_config("p1", "acc_constants extensions language mu1"),


use rule step as p1_figure_ext with:
    """P1-EXT figure."""
    input:
        json="results/p1/extensions.json",
        code=code_inputs("eqrec.studies.p1.figures:step_figure_ext"),
    output:
        **figure("results/p1/fig_ext_M2_vs_M1", "p1_ext", "P1"),
    log:
        "logs/p1/figure_ext.log",
    params:
        step="eqrec.studies.p1.figures:step_figure_ext",
        cfg=step_config("p1", "extensions.T_max language"),


use rule step as p1_values with:
    """Our value of every published P1 number, with its evidence."""
    input:
        model="results/p1/model.json",
        designs="results/p1/designs.json",
        designs_timings="results/timings/p1/designs.json",
        simulation="results/p1/simulation.npz",
        extensions="results/p1/extensions.json",
        code=code_inputs("eqrec.studies.p1.steps:step_values"),
    output:
        json="results/p1/values.json",
        timings="results/timings/p1/values.json",
    log:
        "logs/p1/values.log",
    params:
        step="eqrec.studies.p1.steps:step_values",


rule p1:
    """All P1 outputs."""
    input:
        rules.p1_values.output,
        rules.p1_figure1.output,
        rules.p1_figure_ext.output,
