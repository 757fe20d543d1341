# P2: state-augmented estimator (Hassaan, Shen, Yong, ACC 2019).
# Thin rules: each runs one step of eqrec.p2_study; parameters from config["p2"]
# (config/p2.yaml, schema config/schemas/p2.schema.yaml).
P2_SRC = module_sources("studies.p2")
VALUES_FILES.append("results/p2/values.json")
# config["p2"] is loaded and validated (config/schemas/p2.schema.yaml) by the Snakefile.

P2_CONFIG = resolved("p2")
P2_VARIANTS = config["p2"]["heatmap"]["variants"]
P2_CHUNKS = list(range(config["p2"]["heatmap"]["chunks"]))


rule p2_designs:
    """P2-F1, P2-F2: time-based, augmented LP and IPOPT designs and the readings, certified."""
    input:
        config=P2_CONFIG,
        code=P2_SRC,
    output:
        json="results/p2/designs.json",
        npz="results/p2/designs.npz",
    params:
        step=study_cmd("studies.p2", "designs"),
    log:
        "logs/p2/designs.log",
    shell:
        "{params.step} --config {input.config} --out {output.json} --npz {output.npz} > {log} 2>&1"


rule p2_simulate:
    """P2-F1, P2-F2: Monte Carlo, every estimator on the same draws."""
    input:
        code=P2_SRC,
        config=P2_CONFIG,
        designs="results/p2/designs.npz",
    output:
        "results/p2/simulation.npz",
    params:
        step=study_cmd("studies.p2", "simulate"),
    log:
        "logs/p2/simulate.log",
    shell:
        "{params.step} --config {input.config} --designs {input.designs} --out {output} > {log} 2>&1"


rule p2_heatmap_chunk:
    """P2-F3a: one theta-chunk of the eigenvalue sweep (one LP built, L values updated)."""
    input:
        config=P2_CONFIG,
        code=P2_SRC,
    output:
        "results/p2/heatmap/{variant}_{chunk}.csv",
    params:
        step=study_cmd("studies.p2", "heatmap-chunk"),
    log:
        "logs/p2/heatmap_{variant}_{chunk}.log",
    wildcard_constraints:
        chunk=r"\d+",
    shell:
        "{params.step} --config {input.config} --variant {wildcards.variant} --chunk {wildcards.chunk}"
        " --out {output} > {log} 2>&1"


rule p2_heatmap_merge:
    """P2-F3a: the whole grid."""
    input:
        chunks=expand("results/p2/heatmap/{variant}_{chunk}.csv", variant=P2_VARIANTS, chunk=P2_CHUNKS),
        code=P2_SRC,
    output:
        "results/p2/heatmap.csv",
    params:
        step=study_cmd("studies.p2", "heatmap-merge"),
    log:
        "logs/p2/heatmap_merge.log",
    shell:
        "{params.step} {input.chunks} --out {output} > {log} 2>&1"


rule p2_realaxis:
    """P2-F3b: real double eigenvalue sweep."""
    input:
        config=P2_CONFIG,
        code=P2_SRC,
    output:
        "results/p2/realaxis.csv",
    params:
        step=study_cmd("studies.p2", "realaxis"),
    log:
        "logs/p2/realaxis.log",
    shell:
        "{params.step} --config {input.config} --out {output} > {log} 2>&1"


rule p2_checks:
    """P2-S0, P2-SOLVER."""
    input:
        config=P2_CONFIG,
        code=P2_SRC,
    output:
        "results/p2/checks.json",
    params:
        step=study_cmd("studies.p2", "checks"),
    log:
        "logs/p2/checks.log",
    shell:
        "{params.step} --config {input.config} --out {output} > {log} 2>&1"


rule p2_values:
    """Our value of every published P2 number, with evidence."""
    input:
        code=P2_SRC,
        config=P2_CONFIG,
        designs="results/p2/designs.json",
        simulation="results/p2/simulation.npz",
        heatmap="results/p2/heatmap.csv",
        realaxis="results/p2/realaxis.csv",
        checks="results/p2/checks.json",
    output:
        "results/p2/values.json",
    params:
        step=study_cmd("studies.p2", "values"),
    log:
        "logs/p2/values.log",
    shell:
        "{params.step} --config {input.config} --designs {input.designs} --simulation {input.simulation}"
        " --heatmap {input.heatmap} --realaxis {input.realaxis} --checks {input.checks} --out {output} > {log} 2>&1"


rule p2_figure_trajectories:
    """P2-F1 / P2-F2 figures."""
    input:
        code=P2_SRC,
        config=P2_CONFIG,
        designs="results/p2/designs.json",
        simulation="results/p2/simulation.npz",
    output:
        pdf="results/p2/{fig}_trajectories.pdf",
        png=report("results/p2/{fig}_trajectories.png", caption="../report/p2_trajectories.rst", category="P2"),
    params:
        step=study_cmd("studies.p2", "figure-trajectories"),
    log:
        "logs/p2/figure_{fig}.log",
    wildcard_constraints:
        fig="f1|f2",
    shell:
        "{params.step} --config {input.config} --designs {input.designs} --simulation {input.simulation}"
        " --fig {wildcards.fig} --pdf {output.pdf} --png {output.png} > {log} 2>&1"


rule p2_figure_heatmap:
    """P2-F3a figure."""
    input:
        code=P2_SRC,
        config=P2_CONFIG,
        heatmap="results/p2/heatmap.csv",
    output:
        pdf="results/p2/f3a_heatmap.pdf",
        png=report("results/p2/f3a_heatmap.png", caption="../report/p2_f3a.rst", category="P2"),
    params:
        step=study_cmd("studies.p2", "figure-heatmap"),
    log:
        "logs/p2/figure_f3a.log",
    shell:
        "{params.step} --config {input.config} --heatmap {input.heatmap} --pdf {output.pdf} --png {output.png}"
        " > {log} 2>&1"


rule p2_figure_realaxis:
    """P2-F3b figure."""
    input:
        code=P2_SRC,
        config=P2_CONFIG,
        realaxis="results/p2/realaxis.csv",
    output:
        pdf="results/p2/f3b_realaxis.pdf",
        png=report("results/p2/f3b_realaxis.png", caption="../report/p2_f3b.rst", category="P2"),
    params:
        step=study_cmd("studies.p2", "figure-realaxis"),
    log:
        "logs/p2/figure_f3b.log",
    shell:
        "{params.step} --config {input.config} --realaxis {input.realaxis} --pdf {output.pdf}"
        " --png {output.png} > {log} 2>&1"


rule p2:
    """All P2 outputs."""
    input:
        rules.p2_values.output,
        expand("results/p2/{fig}_trajectories.pdf", fig=["f1", "f2"]),
        rules.p2_figure_heatmap.output,
        rules.p2_figure_realaxis.output,
        rules.p2_checks.output,
