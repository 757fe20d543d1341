# P4: LMV filter / predictor / smoother with zero- vs hold-input compensation.
# Each rule runs one step of eqrec.studies.p4 (steps, figures, values) through the harness (common.smk).
# The sweeps run in p4.sweep_*.chunks scattergather jobs (the resolved
# configuration, or --set-scatter sweep_eta=N); the merging steps (fig5, fig6)
# check that they cover the grid exactly once. The chunks are temp() files
# under intermediate/ (not results/; see common.smk).

P4_EXAMPLES = list(config["p4"]["examples"])


scattergather:
    sweep_eta=config["p4"]["sweep_eta"]["chunks"],
    sweep_q=config["p4"]["sweep_q"]["chunks"],


use rule step as p4_tracking with:
    """P4-F1..F3: one realisation of the tracking example with filter, predictor and smoother."""
    input:
        code=code_inputs("eqrec.studies.p4.steps:step_tracking"),
    output:
        npz="results/p4/tracking.npz",
        f1="results/p4/fig1_filter.pdf",
        f1png=in_report("results/p4/fig1_filter.png", "p4_f1", "P4"),
        f2="results/p4/fig2_predictor.pdf",
        f2png=in_report("results/p4/fig2_predictor.png", "p4_f2", "P4"),
        f3="results/p4/fig3_smoother.pdf",
        f3png=in_report("results/p4/fig3_smoother.png", "p4_f3", "P4"),
    log:
        "logs/p4/tracking.log",
    params:
        step="eqrec.studies.p4.steps:step_tracking",
        cfg=step_config("p4", "T eta_bar examples pred_steps smoother_lag tracking"),


use rule step as p4_mc with:
    """P4-THEORY: theory against Monte Carlo for one example (both mechanisms, same draws)."""
    input:
        code=code_inputs("eqrec.studies.p4.steps:step_mc"),
    output:
        npz="results/p4/mc_{example}.npz",
        se="results/p4/mc_{example}_se.npz",
        json="results/p4/mc_{example}.json",
    log:
        "logs/p4/mc_{example}.log",
    benchmark:
        "results/timings/p4/mc_{example}.tsv"
    wildcard_constraints:
        example="|".join(P4_EXAMPLES),
    priority: 4  # about its seconds of CPU: the long jobs start first (common.smk, "Scheduling")
    params:
        step="eqrec.studies.p4.steps:step_mc",
        cfg=step_config("p4", "T eta_bar examples mc pred_steps smoother_lag"),


use rule step as p4_sweep_eta_chunk with:
    """P4-F5: one chunk of the arrival-rate sweep (steady state)."""
    input:
        code=code_inputs("eqrec.studies.p4.steps:step_sweep_eta_chunk"),
    output:
        npz=temp("intermediate/p4/sweep_eta/chunk_{scatteritem}.npz"),
    log:
        "logs/p4/sweep_eta_{scatteritem}.log",
    params:
        step="eqrec.studies.p4.steps:step_sweep_eta_chunk",
        cfg=step_config("p4", "examples smoother_lag steady sweep_eta"),


use rule step as p4_sweep_q_chunk with:
    """P4-F6: one chunk of the (Q_xi, Q_lambda) sweep (steady state)."""
    input:
        code=code_inputs("eqrec.studies.p4.steps:step_sweep_q_chunk"),
    output:
        npz=temp("intermediate/p4/sweep_q/chunk_{scatteritem}.npz"),
    log:
        "logs/p4/sweep_q_{scatteritem}.log",
    params:
        step="eqrec.studies.p4.steps:step_sweep_q_chunk",
        cfg=step_config("p4", "eta_bar examples smoother_lag steady sweep_q"),


use rule step as p4_fig4 with:
    """P4-F4: error variances of predictor, filter, smoother."""
    input:
        mc=f"results/p4/mc_{config['p4']['tracking']['example']}.npz",
        se=f"results/p4/mc_{config['p4']['tracking']['example']}_se.npz",
        code=code_inputs("eqrec.studies.p4.figures:step_fig4"),
    output:
        **figure("results/p4/fig4_variances", "p4_f4", "P4"),
    log:
        "logs/p4/fig4.log",
    params:
        step="eqrec.studies.p4.figures:step_fig4",
        cfg=step_config("p4", "eta_bar smoother_lag"),


use rule step as p4_fig5 with:
    """P4-F5: merge the arrival-rate chunks; error variances against the arrival rate."""
    input:
        chunks=gather.sweep_eta("intermediate/p4/sweep_eta/chunk_{scatteritem}.npz"),
        code=code_inputs("eqrec.studies.p4.figures:step_fig5"),
    output:
        **figure("results/p4/fig5_eta", "p4_f5", "P4"),
        merged="results/p4/sweep_eta.npz",
    log:
        "logs/p4/fig5.log",
    params:
        step="eqrec.studies.p4.figures:step_fig5",
        cfg=step_config("p4", "examples smoother_lag sweep_eta.num tracking.example"),


use rule step as p4_fig6 with:
    """P4-F6: merge the Q chunks; filter variance against Q_xi and Q_lambda, and where each mechanism wins."""
    input:
        chunks=gather.sweep_q("intermediate/p4/sweep_q/chunk_{scatteritem}.npz"),
        code=code_inputs("eqrec.studies.p4.figures:step_fig6"),
    output:
        **figure("results/p4/fig6_q", "p4_f6", "P4"),
        merged="results/p4/sweep_q.npz",
        rpdf="results/p4/regions.pdf",
        rpng=in_report("results/p4/regions.png", "p4_regions", "P4"),
    log:
        "logs/p4/fig6.log",
    params:
        step="eqrec.studies.p4.figures:step_fig6",
        cfg=step_config("p4", "eta_bar examples sweep_q.num tracking.example"),


use rule step as p4_compare with:
    """P4-F7 (Example 1) / P4-F8 (Example 2): zero-input vs hold-input filter."""
    input:
        mc="results/p4/mc_{example}.npz",
        se="results/p4/mc_{example}_se.npz",
        code=code_inputs("eqrec.studies.p4.figures:step_compare"),
    output:
        pdf="results/p4/fig{number}_compare_{example}.pdf",
        png=in_report(
            "results/p4/fig{number}_compare_{example}.png", "p4_compare", "P4"
        ),
    log:
        "logs/p4/fig{number}_{example}.log",
    wildcard_constraints:
        number=r"\d+",
    params:
        step="eqrec.studies.p4.figures:step_compare",
        # the paper's verdict of each figure (config/claims.yaml), printed beside ours
        cfg=step_config("p4", "eta_bar examples")
        | published(ex1="P4-F7:better-ex1", ex2="P4-F8:better-ex2"),


use rule step as p4_values with:
    """Our value of every P4 claim, with its evidence."""
    input:
        tracking="results/p4/tracking.npz",
        mc_json=expand("results/p4/mc_{example}.json", example=P4_EXAMPLES),
        mc_npz=expand("results/p4/mc_{example}.npz", example=P4_EXAMPLES),
        eta="results/p4/sweep_eta.npz",
        q="results/p4/sweep_q.npz",
        code=code_inputs("eqrec.studies.p4.values:step_values"),
    output:
        values="results/p4/values.json",
        table="results/p4/summary.csv",
    log:
        "logs/p4/values.log",
    params:
        step="eqrec.studies.p4.values:step_values",
        cfg=step_config(
            "p4", "T eta_bar examples mc.alpha smoother_lag steady tracking"
        ),


rule p4:
    """All P4 outputs."""
    input:
        rules.p4_values.output,
        rules.p4_tracking.output,
        rules.p4_fig4.output,
        rules.p4_fig5.output,
        rules.p4_fig6.output,
        "results/p4/fig7_compare_ex1.pdf",
        "results/p4/fig8_compare_ex2.pdf",
