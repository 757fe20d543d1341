# P3: delayed/missing-data paper (Hassaan, Shen, Yong; equalized recovery with delayed and missing observations).
# Each rule runs one step of eqrec.studies.p3 through the harness (common.smk).
P3_CODE = code_inputs("p3")
P3_CFG = section_params(config, "p3")
VALUES_FILES.append("results/p3/values.json")


rule p3_languages:
    """P3-LANG: Examples 1-5 and the language counts of {0..max delay}^T."""
    input:
        code=P3_CODE,
    output:
        json="results/p3/languages.json",
        csv="results/p3/examples.csv",
        md="results/p3/examples.md",
        counts="results/p3/language_counts.csv",
    params:
        study="p3",
        step="languages",
        cfg=P3_CFG,
    log:
        "logs/p3/languages.log",
    script:
        RUN_STEP


rule p3_reactor_model:
    """P3-BR: ZOH discretisation of the batch reactor."""
    input:
        code=P3_CODE,
    output:
        json="results/p3/reactor_model.json",
    params:
        study="p3",
        step="reactor_model",
        cfg=P3_CFG,
    log:
        "logs/p3/reactor_model.log",
    script:
        RUN_STEP


rule p3_reactor_designs:
    """P3-BR: mu1 free (certified global route and IPOPT on (10)) and at the configured readings of mu1."""
    input:
        code=P3_CODE,
    output:
        json="results/p3/reactor_designs.json",
    params:
        study="p3",
        step="reactor_designs",
        cfg=P3_CFG,
    log:
        "logs/p3/reactor_designs.log",
    script:
        RUN_STEP


rule p3_augmented:
    """The augmented form (4) with fixed L and s0: optimum against pole placements and s0."""
    input:
        code=P3_CODE,
    output:
        json="results/p3/augmented.json",
    params:
        study="p3",
        step="augmented",
        cfg=P3_CFG,
    log:
        "logs/p3/augmented.log",
    script:
        RUN_STEP


rule p3_kalman:
    """P3-F1: proposed estimator vs Kalman-type filters on the true pattern (exact worst cases, runs)."""
    input:
        code=P3_CODE,
    output:
        json="results/p3/kalman.json",
        npz="results/p3/kalman.npz",
    params:
        study="p3",
        step="kalman",
        cfg=P3_CFG,
    log:
        "logs/p3/kalman.log",
    script:
        RUN_STEP


rule p3_figure1:
    """P3-F1 figure."""
    input:
        json="results/p3/kalman.json",
        npz="results/p3/kalman.npz",
        code=P3_CODE,
    output:
        pdf="results/p3/fig1_kalman.pdf",
        png=report("results/p3/fig1_kalman.png", caption="../report/p3_fig1.rst", category="P3"),
    params:
        study="p3",
        step="figure1",
        cfg=P3_CFG,
    log:
        "logs/p3/figure1.log",
    script:
        RUN_STEP


rule p3_acc:
    """P3-ACC: the ACC language with mu1 = 1 vs P1's prefix design; mu1 free (footnote 1)."""
    input:
        code=P3_CODE,
    output:
        json="results/p3/acc.json",
    params:
        study="p3",
        step="acc",
        cfg=P3_CFG,
    log:
        "logs/p3/acc.log",
    script:
        RUN_STEP


rule p3_acc_simulate:
    """P3-F2: proposed vs P1 prefix-based estimator on the true pattern, same draws."""
    input:
        code=P3_CODE,
    output:
        npz="results/p3/acc_simulation.npz",
    params:
        study="p3",
        step="acc_simulate",
        cfg=P3_CFG,
    log:
        "logs/p3/acc_simulate.log",
    script:
        RUN_STEP


rule p3_figure2:
    """P3-F2 figure."""
    input:
        npz="results/p3/acc_simulation.npz",
        code=P3_CODE,
    output:
        pdf="results/p3/fig2_acc.pdf",
        png=report("results/p3/fig2_acc.png", caption="../report/p3_fig2.rst", category="P3"),
    params:
        study="p3",
        step="figure2",
        cfg=P3_CFG,
    log:
        "logs/p3/figure2.log",
    script:
        RUN_STEP


rule p3_values:
    """Our value of every published P3 number and claim, with its evidence."""
    input:
        languages="results/p3/languages.json",
        model="results/p3/reactor_model.json",
        designs="results/p3/reactor_designs.json",
        augmented="results/p3/augmented.json",
        kalman="results/p3/kalman.json",
        acc="results/p3/acc.json",
        acc_npz="results/p3/acc_simulation.npz",
        code=P3_CODE,
    output:
        json="results/p3/values.json",
    params:
        study="p3",
        step="values",
        cfg=P3_CFG,
    log:
        "logs/p3/values.log",
    script:
        RUN_STEP


rule p3:
    """All P3 outputs (the P3-IMPL and scale-table targets are added by their own rules)."""
    input:
        rules.p3_values.output,
        rules.p3_languages.output,
        rules.p3_figure1.output,
        rules.p3_figure2.output,
