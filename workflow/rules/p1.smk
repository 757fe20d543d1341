# P1: prefix-based estimator (Rutledge, Yong, Ozay, ACC 2019).
# Each rule runs one step of eqrec.p1_study; see `python -m eqrec.p1_study --help`.
P1_SRC = module_sources("studies.p1")
VALUES_FILES.append("results/p1/values.json")


rule p1_model:
    """P1-T1: ACC model from the Table I constants."""
    input:
        config=CONFIG_FILE,
        code=P1_SRC,
    output:
        "results/p1/model.json",
    params:
        step=study_cmd("studies.p1", "model"),
    log:
        "logs/p1/model.log",
    shell:
        "{params.step} --config {input.config} --out {output} > {log} 2>&1"


rule p1_designs:
    """P1-M2, P1-TIME: prefix- and time-based designs on L1, certified, timed."""
    input:
        config=CONFIG_FILE,
        code=P1_SRC,
    output:
        "results/p1/designs.json",
    params:
        step=study_cmd("studies.p1", "designs"),
    log:
        "logs/p1/designs.log",
    shell:
        "{params.step} --config {input.config} --out {output} > {log} 2>&1"


rule p1_simulate:
    """P1-F1: Monte Carlo runs of both estimators on the same draws."""
    input:
        config=CONFIG_FILE,
        code=P1_SRC,
    output:
        "results/p1/simulation.npz",
    params:
        step=study_cmd("studies.p1", "simulate"),
    log:
        "logs/p1/simulate.log",
    shell:
        "{params.step} --config {input.config} --out {output} > {log} 2>&1"


rule p1_figure1:
    """P1-F1 figure."""
    input:
        sim="results/p1/simulation.npz",
        code=P1_SRC,
    output:
        pdf="results/p1/fig1_trajectories.pdf",
        png=report("results/p1/fig1_trajectories.png", caption="../report/p1_fig1.rst", category="P1"),
    params:
        step=study_cmd("studies.p1", "figure1"),
    log:
        "logs/p1/figure1.log",
    shell:
        "{params.step} {input.sim} --pdf {output.pdf} --png {output.png} > {log} 2>&1"


rule p1_extensions:
    """P1-EXT: M2*(M1), minimum M1, finite-length language, minimum T."""
    input:
        config=CONFIG_FILE,
        code=P1_SRC,
    output:
        "results/p1/extensions.json",
    params:
        step=study_cmd("studies.p1", "extensions"),
    log:
        "logs/p1/extensions.log",
    shell:
        "{params.step} --config {input.config} --out {output} > {log} 2>&1"


rule p1_figure_ext:
    """P1-EXT figure."""
    input:
        ext="results/p1/extensions.json",
        code=P1_SRC,
    output:
        pdf="results/p1/fig_ext_M2_vs_M1.pdf",
        png=report("results/p1/fig_ext_M2_vs_M1.png", caption="../report/p1_ext.rst", category="P1"),
    params:
        step=study_cmd("studies.p1", "figure-ext"),
    log:
        "logs/p1/figure_ext.log",
    shell:
        "{params.step} {input.ext} --pdf {output.pdf} --png {output.png} > {log} 2>&1"


rule p1_values:
    """Our value of every published P1 number, with evidence."""
    input:
        model="results/p1/model.json",
        designs="results/p1/designs.json",
        simulation="results/p1/simulation.npz",
        extensions="results/p1/extensions.json",
        code=P1_SRC,
    output:
        "results/p1/values.json",
    params:
        step=study_cmd("studies.p1", "values"),
    log:
        "logs/p1/values.log",
    shell:
        "{params.step} --model {input.model} --designs {input.designs} --simulation {input.simulation}"
        " --extensions {input.extensions} --out {output} > {log} 2>&1"


rule p1:
    """All P1 outputs."""
    input:
        rules.p1_values.output,
        rules.p1_figure1.output,
        rules.p1_figure_ext.output,
