# P3: delayed/missing-data paper (Hassaan, Shen, Yong; equalized recovery with delayed and missing observations).
# Each rule runs one step of eqrec.studies.p3 (steps, figures, values, strategy, scale tables) through the harness.


use rule step as p3_languages with:
    """P3-LANG: Examples 1-5 and the language counts of {0..max delay}^T."""
    input:
        code=code_inputs("eqrec.studies.p3.steps:step_languages"),
    output:
        json="results/p3/languages.json",
        csv="results/p3/examples.csv",
        md="results/p3/examples.md",
        counts="results/p3/language_counts.csv",
    log:
        "logs/p3/languages.log",
    params:
        step="eqrec.studies.p3.steps:step_languages",
        cfg=step_config("p3", "languages"),


use rule step as p3_reactor_model with:
    """P3-BR: ZOH discretisation of the batch reactor."""
    input:
        code=code_inputs("eqrec.studies.p3.steps:step_reactor_model"),
    output:
        json="results/p3/reactor_model.json",
    log:
        "logs/p3/reactor_model.log",
    params:
        step="eqrec.studies.p3.steps:step_reactor_model",
        cfg=step_config("p3", batch_reactor="Ts eta_v"),


use rule step as p3_reactor_designs with:
    """P3-BR: mu1 free (certified global route and IPOPT on (10)) and at the configured readings of mu1."""
    input:
        code=code_inputs("eqrec.studies.p3.steps:step_reactor_designs"),
    output:
        json="results/p3/reactor_designs.json",
        timings="results/timings/p3/reactor_designs.json",
    log:
        "logs/p3/reactor_designs.log",
    priority: 10  # about its seconds of CPU: the long jobs start first (common.smk, "Scheduling")
    params:
        step="eqrec.studies.p3.steps:step_reactor_designs",
        cfg=step_config("p3", "batch_reactor kalman.x0"),


use rule step as p3_augmented with:
    """The augmented form (4) with fixed L and s0: optimum against pole placements and s0."""
    input:
        code=code_inputs("eqrec.studies.p3.steps:step_augmented"),
    output:
        json="results/p3/augmented.json",
    log:
        "logs/p3/augmented.log",
    priority: 3  # about its seconds of CPU: the long jobs start first (common.smk, "Scheduling")
    params:
        step="eqrec.studies.p3.steps:step_augmented",
        cfg=step_config(
            "p3", "augmented", batch_reactor="Ts cost eta_v horizon max_delay"
        ),


use rule step as p3_kalman with:
    """P3-F1: proposed estimator vs Kalman-type filters on the true pattern (exact worst cases, runs)."""
    input:
        code=code_inputs("eqrec.studies.p3.steps:step_kalman"),
    output:
        json="results/p3/kalman.json",
        npz="results/p3/kalman.npz",
    log:
        "logs/p3/kalman.log",
    params:
        step="eqrec.studies.p3.steps:step_kalman",
        cfg=step_config("p3", "kalman", batch_reactor="Ts cost eta_v horizon max_delay"),


use rule step as p3_figure1 with:
    """P3-F1 figure."""
    input:
        json="results/p3/kalman.json",
        npz="results/p3/kalman.npz",
        code=code_inputs("eqrec.studies.p3.figures:step_figure1"),
    output:
        **figure("results/p3/fig1_kalman", "p3_fig1", "P3"),
    log:
        "logs/p3/figure1.log",
    params:
        step="eqrec.studies.p3.figures:step_figure1",


use rule step as p3_acc with:
    """P3-ACC: the ACC language with mu1 = 1 vs P1's prefix design; mu1 free (footnote 1)."""
    input:
        code=code_inputs("eqrec.studies.p3.steps:step_acc"),
    output:
        json="results/p3/acc.json",
        timings="results/timings/p3/acc.json",
    log:
        "logs/p3/acc.log",
    params:
        step="eqrec.studies.p3.steps:step_acc",
        cfg=step_config("p3", acc="free_costs language mu1"),


use rule step as p3_acc_simulate with:
    """P3-F2: proposed vs P1 prefix-based estimator on the true pattern, same draws."""
    input:
        code=code_inputs("eqrec.studies.p3.steps:step_acc_simulate"),
    output:
        npz="results/p3/acc_simulation.npz",
    log:
        "logs/p3/acc_simulate.log",
    params:
        step="eqrec.studies.p3.steps:step_acc_simulate",
        cfg=step_config("p3", acc="cost language mu1 simulation true_pattern"),


use rule step as p3_figure2 with:
    """P3-F2 figure."""
    input:
        npz="results/p3/acc_simulation.npz",
        code=code_inputs("eqrec.studies.p3.figures:step_figure2"),
    output:
        **figure("results/p3/fig2_acc", "p3_fig2", "P3"),
    log:
        "logs/p3/figure2.log",
    params:
        step="eqrec.studies.p3.figures:step_figure2",
        cfg=step_config("p3", "acc.true_pattern"),


use rule step as p3_values with:
    """Our value of every published P3 number and claim, with its evidence."""
    input:
        languages="results/p3/languages.json",
        model="results/p3/reactor_model.json",
        designs="results/p3/reactor_designs.json",
        augmented="results/p3/augmented.json",
        kalman="results/p3/kalman.json",
        acc="results/p3/acc.json",
        acc_npz="results/p3/acc_simulation.npz",
        code=code_inputs("eqrec.studies.p3.values:step_values"),
    output:
        json="results/p3/values.json",
    log:
        "logs/p3/values.log",
    params:
        step="eqrec.studies.p3.values:step_values",
        cfg=step_config("p3", batch_reactor="horizon max_delay"),


# --- P3-IMPL (Section III-B3) and the scale table: eqrec.studies.p3 (strategy, figures, scale_table) ---
# Scale table: the tree LP at the fast sizes and the class engine run in the default run (seconds each);
# the slow tree sizes only in the target p3_scale (minutes and up to 16 GB each).
P3_SCALE_TREE = scale_files("tree_sizes")
P3_SCALE_CLASSES = scale_files("class_sizes", engine="classes_")
P3_SCALE = list(dict.fromkeys(P3_SCALE_TREE + P3_SCALE_CLASSES))
P3_SCALE_FULL = list(
    dict.fromkeys(P3_SCALE_TREE + scale_files("tree_slow_sizes") + P3_SCALE_CLASSES)
)


use rule step as p3_strategy with:
    """P3-IMPL: gains reused every T (batch reactor, ACC) and the switching scheme; 10^4-step runs vs the guarantees."""
    input:
        code=code_inputs("eqrec.studies.p3.strategy:step_strategy"),
    output:
        npz="results/p3/strategy.npz",
        values="results/p3/strategy_values.json",
        timings="results/timings/p3/strategy_values.json",
    log:
        "logs/p3/strategy.log",
    priority: 5  # about its seconds of CPU: the long jobs start first (common.smk, "Scheduling")
    params:
        step="eqrec.studies.p3.strategy:step_strategy",
        cfg=step_config("p3", strategy="acc cost noise reactor seed steps switching"),


use rule step as p3_strategy_figure with:
    """P3-IMPL figure: errors per state with the per-time guarantees, period boundaries and switching instants."""
    input:
        npz="results/p3/strategy.npz",
        code=code_inputs("eqrec.studies.p3.figures:step_strategy_figure"),
    output:
        **figure("results/p3/fig_strategy", "p3_strategy", "P3"),
    log:
        "logs/p3/strategy_figure.log",
    params:
        step="eqrec.studies.p3.figures:step_strategy_figure",
        cfg=step_config("p3", "strategy.figure"),


use rule step as p3_scale_size with:
    """Scale table, one size of the tree LP: {0..tau}^T enumerated, node-per-prefix LP, fresh process with limits."""
    input:
        code=code_inputs("eqrec.studies.p3.scale_table:step_scale_size"),
    output:
        json="results/p3/scale/T{T}_tau{tau}.json",
        timings="results/timings/p3/scale/T{T}_tau{tau}.json",
    log:
        "logs/p3/scale_T{T}_tau{tau}.log",
    wildcard_constraints:
        T=r"\d+",
        tau=r"\d+",
    params:
        step="eqrec.studies.p3.scale_table:step_scale_size",
        cfg=step_config("p3", scale="builder mem_limit_gb method mu1 time_limit"),


# Scale table, the class engine at every size of scale.class_sizes in one job: seconds
# each, so a job per size spent more CPU starting than solving; each size still runs
# in a fresh worker process (its own peak memory), with the same files as one job each.
use rule step as p3_scale_class_sizes with:
    """Scale table, the class engine at every configured size: the classes of {0..tau}^T by the window rule, fresh process each."""
    input:
        code=code_inputs("eqrec.studies.p3.scale_table:step_scale_sizes"),
    output:
        json=P3_SCALE_CLASSES,
        timings=timings_of(P3_SCALE_CLASSES),
    log:
        "logs/p3/scale_classes.log",
    priority: 10  # about its seconds of CPU: the long jobs start first (common.smk, "Scheduling")
    params:
        step="eqrec.studies.p3.scale_table:step_scale_sizes",
        cfg=step_config(
            "p3", scale="builder class_sizes mem_limit_gb method mu1 time_limit"
        ),


use rule step as p3_scale_table with:
    """Scale table of the default run: the tree LP at the fast sizes next to the class engine (CSV and Markdown)."""
    input:
        sizes=P3_SCALE,
        timings=timings_of(P3_SCALE),
        code=code_inputs("eqrec.studies.p3.scale_table:step_scale_table"),
    output:
        csv="results/p3/scale_table.csv",
        timings_csv="results/timings/p3/scale_table.csv",
        timings_md="results/timings/p3/scale_table.md",
        md=in_report("results/p3/scale_table.md", "p3_scale", "P3"),
    log:
        "logs/p3/scale_table.log",
    params:
        step="eqrec.studies.p3.scale_table:step_scale_table",
        cfg=step_config("p3", "scale.tree_slow_sizes"),


# The same step on the slow tree sizes too (target p3_scale).
use rule p3_scale_table as p3_scale_table_full with:
    """Full scale table: the default run's rows and the slow tree sizes (CSV and Markdown)."""
    input:
        sizes=P3_SCALE_FULL,
        timings=timings_of(P3_SCALE_FULL),
        code=code_inputs("eqrec.studies.p3.scale_table:step_scale_table"),
    output:
        csv="results/p3/scale_table_full.csv",
        md="results/p3/scale_table_full.md",
        timings_csv="results/timings/p3/scale_table_full.csv",
        timings_md="results/timings/p3/scale_table_full.md",
    log:
        "logs/p3/scale_table_full.log",


use rule step as p3_scale_free with:
    """The class engine with mu1 free against the number of classes: per class on 1 and 2 workers, one block LP."""
    input:
        code=code_inputs("eqrec.studies.p3.free_table:step_scale_free"),
    output:
        csv="results/p3/scale_free.csv",
        timings_csv="results/timings/p3/scale_free.csv",
        timings_md="results/timings/p3/scale_free.md",
    log:
        "logs/p3/scale_free.log",
    threads: 2
    params:
        step="eqrec.studies.p3.free_table:step_scale_free",
        cfg=step_config("p3", "scale.time_limit"),


use rule step as p3_scale_free_figure with:
    """The mu1-free scaling figure: design time against the number of classes, from its values and timings."""
    input:
        csv=rules.p3_scale_free.output.csv,
        timings=rules.p3_scale_free.output.timings_csv,
        code=code_inputs("eqrec.studies.p3.figures:step_scale_free_figure"),
    output:
        **figure("results/timings/p3/fig_scale_free", "p3_scale_free", "P3"),
    log:
        "logs/p3/scale_free_figure.log",
    params:
        step="eqrec.studies.p3.figures:step_scale_free_figure",


rule p3_scale:
    """Full P3 scale table with the slow tree sizes and the mu1-free scaling (outside `all`; up to 16 GB)."""
    input:
        rules.p3_scale_table_full.output,
        rules.p3_scale_free.output,
        rules.p3_scale_free_figure.output,


rule p3:
    """All P3 outputs of the default run, the scale table of the fast sizes included (slow tree sizes: p3_scale)."""
    input:
        rules.p3_values.output,
        rules.p3_languages.output,
        rules.p3_figure1.output,
        rules.p3_figure2.output,
        rules.p3_strategy.output,
        rules.p3_strategy_figure.output,
        rules.p3_scale_table.output,
