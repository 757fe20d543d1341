# P4: LMV filter / predictor / smoother with zero- vs hold-input compensation.
# Each rule runs one step of eqrec.lmv_study; parameters from config["p4"]
# (config/p4.yaml, validated by the Snakefile).
P4_SRC = module_sources("studies.p4")
VALUES_FILES.append("results/p4/values.json")

P4_CONFIG = resolved("p4")
P4_EXAMPLES = list(config["p4"]["examples"])
P4_ETA_CHUNKS = list(range(int(config["p4"]["sweep_eta"]["chunks"])))
P4_Q_CHUNKS = list(range(int(config["p4"]["sweep_q"]["chunks"])))
P4_TRACK = ["fig1_filter", "fig2_predictor", "fig3_smoother"]


rule p4_tracking:
    """P4-F1..F3: one realisation of Example 1 with filter, predictor and smoother."""
    input:
        config=P4_CONFIG,
        code=P4_SRC,
    output:
        npz="results/p4/tracking.npz",
        f1="results/p4/fig1_filter.pdf",
        f1png=report("results/p4/fig1_filter.png", caption="../report/p4_f1.rst", category="P4"),
        f2="results/p4/fig2_predictor.pdf",
        f2png=report("results/p4/fig2_predictor.png", caption="../report/p4_f2.rst", category="P4"),
        f3="results/p4/fig3_smoother.pdf",
        f3png=report("results/p4/fig3_smoother.png", caption="../report/p4_f3.rst", category="P4"),
    params:
        step=study_cmd("studies.p4", "tracking"),
    log:
        "logs/p4/tracking.log",
    shell:
        "{params.step} --config {input.config} --npz {output.npz} --figs {output.f1} {output.f1png}"
        " {output.f2} {output.f2png} {output.f3} {output.f3png} > {log} 2>&1"


rule p4_mc:
    """P4-THEORY: theory against Monte Carlo for one example (both mechanisms, same draws)."""
    input:
        config=P4_CONFIG,
        code=P4_SRC,
    output:
        npz="results/p4/mc_{example}.npz",
        json="results/p4/mc_{example}.json",
    params:
        step=study_cmd("studies.p4", "mc"),
    log:
        "logs/p4/mc_{example}.log",
    shell:
        "{params.step} --config {input.config} --example {wildcards.example} --npz {output.npz}"
        " --json {output.json} > {log} 2>&1"


rule p4_sweep_eta_chunk:
    """P4-F5: one chunk of the arrival-rate sweep (steady state)."""
    input:
        config=P4_CONFIG,
        code=P4_SRC,
    output:
        "results/p4/sweep_eta/chunk{chunk}.npz",
    params:
        step=study_cmd("studies.p4", "sweep-eta"),
    log:
        "logs/p4/sweep_eta_{chunk}.log",
    wildcard_constraints:
        chunk=r"\d+",
    shell:
        "{params.step} --config {input.config} --chunk {wildcards.chunk} --out {output} > {log} 2>&1"


rule p4_sweep_q_chunk:
    """P4-F6: one chunk of the (Q_xi, Q_lambda) sweep (steady state)."""
    input:
        config=P4_CONFIG,
        code=P4_SRC,
    output:
        "results/p4/sweep_q/chunk{chunk}.npz",
    params:
        step=study_cmd("studies.p4", "sweep-q"),
    log:
        "logs/p4/sweep_q_{chunk}.log",
    wildcard_constraints:
        chunk=r"\d+",
    shell:
        "{params.step} --config {input.config} --chunk {wildcards.chunk} --out {output} > {log} 2>&1"


rule p4_fig4:
    """P4-F4: error variances of predictor, filter, smoother."""
    input:
        config=P4_CONFIG,
        mc=f"results/p4/mc_{config['p4']['tracking']['example']}.npz",
        code=P4_SRC,
    output:
        pdf="results/p4/fig4_variances.pdf",
        png=report("results/p4/fig4_variances.png", caption="../report/p4_f4.rst", category="P4"),
    params:
        step=study_cmd("studies.p4", "fig4"),
    log:
        "logs/p4/fig4.log",
    shell:
        "{params.step} --config {input.config} --mc {input.mc} --pdf {output.pdf} --png {output.png} > {log} 2>&1"


rule p4_fig5:
    """P4-F5: error variances against the arrival rate."""
    input:
        config=P4_CONFIG,
        chunks=expand("results/p4/sweep_eta/chunk{chunk}.npz", chunk=P4_ETA_CHUNKS),
        code=P4_SRC,
    output:
        merged="results/p4/sweep_eta.npz",
        pdf="results/p4/fig5_eta.pdf",
        png=report("results/p4/fig5_eta.png", caption="../report/p4_f5.rst", category="P4"),
    params:
        step=study_cmd("studies.p4", "fig5"),
    log:
        "logs/p4/fig5.log",
    shell:
        "{params.step} --config {input.config} --chunks {input.chunks} --merged {output.merged}"
        " --pdf {output.pdf} --png {output.png} > {log} 2>&1"


rule p4_fig6:
    """P4-F6: filter variance against Q_xi and Q_lambda, and where each mechanism wins."""
    input:
        config=P4_CONFIG,
        chunks=expand("results/p4/sweep_q/chunk{chunk}.npz", chunk=P4_Q_CHUNKS),
        code=P4_SRC,
    output:
        merged="results/p4/sweep_q.npz",
        pdf="results/p4/fig6_q.pdf",
        png=report("results/p4/fig6_q.png", caption="../report/p4_f6.rst", category="P4"),
        rpdf="results/p4/regions.pdf",
        rpng=report("results/p4/regions.png", caption="../report/p4_regions.rst", category="P4"),
    params:
        step=study_cmd("studies.p4", "fig6"),
    log:
        "logs/p4/fig6.log",
    shell:
        "{params.step} --config {input.config} --chunks {input.chunks} --merged {output.merged}"
        " --pdf {output.pdf} --png {output.png} --regions-pdf {output.rpdf} --regions-png {output.rpng} > {log} 2>&1"


rule p4_compare:
    """P4-F7 (Example 1) / P4-F8 (Example 2): zero-input vs hold-input filter."""
    input:
        config=P4_CONFIG,
        mc="results/p4/mc_{example}.npz",
        code=P4_SRC,
    output:
        pdf="results/p4/fig{number}_compare_{example}.pdf",
        png=report("results/p4/fig{number}_compare_{example}.png", caption="../report/p4_compare.rst",
                   category="P4"),
    params:
        step=study_cmd("studies.p4", "compare"),
    log:
        "logs/p4/fig{number}_{example}.log",
    wildcard_constraints:
        number=r"\d+",
    shell:
        "{params.step} --config {input.config} --example {wildcards.example} --number {wildcards.number}"
        " --mc {input.mc} --pdf {output.pdf} --png {output.png} > {log} 2>&1"


rule p4_values:
    """Our value of every P4 claim, with the evidence."""
    input:
        config=P4_CONFIG,
        tracking="results/p4/tracking.npz",
        mc_json=expand("results/p4/mc_{example}.json", example=P4_EXAMPLES),
        mc_npz=expand("results/p4/mc_{example}.npz", example=P4_EXAMPLES),
        eta="results/p4/sweep_eta.npz",
        q="results/p4/sweep_q.npz",
        code=P4_SRC,
    output:
        values="results/p4/values.json",
        table="results/p4/summary.csv",
    params:
        step=study_cmd("studies.p4", "values"),
        mc_json=" ".join(f"{ex}=results/p4/mc_{ex}.json" for ex in P4_EXAMPLES),
        mc_npz=" ".join(f"{ex}=results/p4/mc_{ex}.npz" for ex in P4_EXAMPLES),
    log:
        "logs/p4/values.log",
    shell:
        "{params.step} --config {input.config} --tracking {input.tracking} --mc-json {params.mc_json}"
        " --mc-npz {params.mc_npz} --eta {input.eta} --q {input.q} --out {output.values}"
        " --table {output.table} > {log} 2>&1"


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
