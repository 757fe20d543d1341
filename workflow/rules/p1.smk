# P1: prefix-based estimator (Rutledge, Yong, Ozay, ACC 2019).
VALUES_FILES.append("results/p1/values.json")
P1 = f"{PY} -m eqrec.p1_study"


rule p1_model:
    """P1-T1: ACC model from the Table I constants."""
    input:
        CONFIG_FILE,
        PKG_SRC,
    output:
        "results/p1/model.json",
    log:
        "logs/p1/model.log",
    shell:
        "{P1} model --config {input[0]} --out {output} > {log} 2>&1"


rule p1_designs:
    """P1-M2, P1-TIME: prefix- and time-based designs on L1, certified, timed."""
    input:
        CONFIG_FILE,
        PKG_SRC,
    output:
        "results/p1/designs.json",
    log:
        "logs/p1/designs.log",
    shell:
        "{P1} designs --config {input[0]} --out {output} > {log} 2>&1"


rule p1_simulate:
    """P1-F1: Monte Carlo runs of both estimators on the same draws."""
    input:
        CONFIG_FILE,
        PKG_SRC,
    output:
        "results/p1/simulation.npz",
    log:
        "logs/p1/simulate.log",
    shell:
        "{P1} simulate --config {input[0]} --out {output} > {log} 2>&1"


rule p1_figure1:
    """P1-F1 figure."""
    input:
        "results/p1/simulation.npz",
        PKG_SRC,
    output:
        pdf=report("results/p1/fig1_trajectories.pdf", caption="../report/p1_fig1.rst", category="P1"),
        png="results/p1/fig1_trajectories.png",
    log:
        "logs/p1/figure1.log",
    shell:
        "{P1} figure1 {input[0]} --pdf {output.pdf} --png {output.png} > {log} 2>&1"


rule p1_extensions:
    """P1-EXT: M2*(M1), minimum M1, finite-length language, minimum T."""
    input:
        CONFIG_FILE,
        PKG_SRC,
    output:
        "results/p1/extensions.json",
    log:
        "logs/p1/extensions.log",
    shell:
        "{P1} extensions --config {input[0]} --out {output} > {log} 2>&1"


rule p1_figure_ext:
    """P1-EXT figure."""
    input:
        "results/p1/extensions.json",
        PKG_SRC,
    output:
        pdf=report("results/p1/fig_ext_M2_vs_M1.pdf", caption="../report/p1_ext.rst", category="P1"),
        png="results/p1/fig_ext_M2_vs_M1.png",
    log:
        "logs/p1/figure_ext.log",
    shell:
        "{P1} figure-ext {input[0]} --pdf {output.pdf} --png {output.png} > {log} 2>&1"


rule p1_values:
    """Our value of every published P1 number, with evidence."""
    input:
        model="results/p1/model.json",
        designs="results/p1/designs.json",
        simulation="results/p1/simulation.npz",
        extensions="results/p1/extensions.json",
    output:
        "results/p1/values.json",
    log:
        "logs/p1/values.log",
    shell:
        "{P1} values --model {input.model} --designs {input.designs} --simulation {input.simulation}"
        " --extensions {input.extensions} --out {output} > {log} 2>&1"


rule p1:
    """All P1 outputs."""
    input:
        rules.p1_values.output,
        rules.p1_figure1.output,
        rules.p1_figure_ext.output,
