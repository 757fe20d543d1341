# Compare (issue 24, beyond the papers): every estimator family (guaranteed class
# engine and prefix designs with strict=False, time-stamped and delay-unaware
# Kalman, LMV zero-/hold-input) on the same plant, packet traces, noise and
# initial errors. One job per system of config/compare.yaml runs eqrec.compare on
# each of its (system, setting) pairs through eqrec.studies.compare.steps
# (harness, common.smk): the settings of a system share one process (imports,
# compiled kernels and plotting loaded once: a job per pair spent about 3 s of its
# 6-9 s of CPU on them on 2 cores); each pair keeps its own files. The table step
# merges the pairs' tables, checking that they cover the configured pairs.
# every (system, setting) pair, for expand()
COMPARE_PAIRS = dict(
    system=list(config["compare"]["systems"]),
    setting=list(config["compare"]["settings"]),
)
# one system's files (but its figures), one per setting: its job writes them all
COMPARE_FILES = {
    key: expand(path, setting=COMPARE_PAIRS["setting"], allow_missing=True)
    for key, path in {
        "csv": "results/compare/{system}_{setting}.csv",
        "json": "results/compare/{system}_{setting}.json",
        "pdf": "results/compare/{system}_{setting}.pdf",
        "timings": "results/timings/compare/{system}_{setting}.json",
    }.items()
}


use rule step as compare_run with:
    """One system, every setting: per pair the table, the figure and the summary of every family on the same traces."""
    input:
        code=code_inputs("eqrec.studies.compare.steps:step_run"),
    output:
        **COMPARE_FILES,
        png=in_report(
            "results/compare/{system}_{setting}.png",
            "compare",
            "Compare",
            each={"setting": COMPARE_PAIRS["setting"]},
            subcategory="{system}",
        ),
    log:
        "logs/compare/{system}.log",
    benchmark:
        "results/timings/compare/{system}.tsv"
    wildcard_constraints:
        system="|".join(COMPARE_PAIRS["system"]),
    priority: 9  # about its seconds of CPU: the long jobs start first (common.smk, "Scheduling")
    params:
        step="eqrec.studies.compare.steps:step_run",
        cfg=step_config("compare", "periods runs seed settings systems exact_runs"),


use rule step as compare_table with:
    """Every (system, setting) in one table, compare.csv, and the summaries in summary.json."""
    input:
        csv=expand("results/compare/{system}_{setting}.csv", **COMPARE_PAIRS),
        json=expand("results/compare/{system}_{setting}.json", **COMPARE_PAIRS),
        code=code_inputs("eqrec.studies.compare.steps:step_table"),
    output:
        csv=in_report("results/compare/compare.csv", "compare_table", "Compare"),
        json="results/compare/summary.json",
    log:
        "logs/compare/table.log",
    params:
        step="eqrec.studies.compare.steps:step_table",
        cfg=step_config("compare", "settings systems"),


rule compare:
    """All compare outputs."""
    input:
        rules.compare_table.output,
        expand(
            "results/compare/{system}_{setting}.{ext}",
            **COMPARE_PAIRS,
            ext=("png", "pdf"),
        ),
