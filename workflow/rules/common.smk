# Shared by the rules files. Every rule that runs a step inherits (Snakemake's
# "use rule step as p1_model with") from the template rule `step` of the
# Snakefile, which holds the one thing they share, the generic script
# workflow/scripts/run_step.py, which calls
# eqrec.studies.pipeline.harness.run_from_snakemake. Each rule gives its files,
# its log and its params: the step by the path of its function
# (step="eqrec.studies.p1.steps:step_model", resolved with
# pkgutil.resolve_name) and cfg, the configuration keys that step reads (no
# more; none when absent), as Snakemake resolved them (config files,
# --configfile, --config; validated by the Snakefile), nested as in the study's
# section. A changed value therefore re-plans the jobs whose step reads it
# (params rerun trigger), and only those: a figure's parameter re-plans that
# figure. A step reading a key its rule does not give fails naming the key
# (harness.StepConfig).
#
# Each rule lists as `code` inputs the package modules its step imports,
# transitively (the module of the step function and what it imports, from the
# import graph grimp builds of the package: eqrec.studies.pipeline.code), so
# editing code a step does not import (the LP modules for a figure, eqrec/lmv
# for P1) does not re-run its job. No mathematics here.
#
# Intermediate files (the sweeps' chunks, temp() outputs that a merging step
# reads) live under intermediate/ (git-ignored), never under results/: a hard
# kill after a merging job has ended but before Snakemake has removed its
# chunks leaves them behind, and the merge, complete, does not run again on
# resume to remove them; results/ holds only what an uninterrupted run writes.
# (`snakemake --delete-temp-output` removes such leftovers.) A killed write
# inside results/ leaves the temporary file of eqrec.io.atomic_path: the job
# runs again on resume and workflow/scripts/run_step.py removes it first
# (eqrec.io.remove_stale_temporaries).
#
# Scheduling: the rules of the nine longest jobs of the default run carry a
# `priority` of about their seconds of CPU (measured on 2 cores, 2026-11-30),
# so that Snakemake starts the long jobs first and the short ones fill the
# gaps (longest-processing-time-first). Without it a 10-second job could start
# last and hold the values, the claims and the notebooks behind it while the
# other core waited (about 7 s of one core idle in a forced run). The head of
# the longest chain of short jobs (P2: designs, simulate, the trajectory
# figures, the values) gets a priority too, so that the chain does not end
# alone. Only the order of the jobs changes, never a result.
#
# The step is named twice, in `code=code_inputs(...)` and `step=...`, because
# no directive sees the other: input functions get only the wildcards, and
# `input: **d` / `params: **d` (valid Snakemake) fill one directive each.
# step_config takes the keys as one space-separated string (as
# collections.namedtuple takes its field names), which snakefmt keeps on one
# line where a list of strings is broken into one key a line. (This file has
# functions, so `snakemake --lint` wants no rule in it, and the template lives
# in the Snakefile.)
from eqrec.studies.claims.published import published_value
from eqrec.studies.pipeline.code import code_inputs
from eqrec.studies.pipeline.configuration import step_params

# The timings file (under results/timings/) a step writes beside each results file.
from eqrec.studies.pipeline.outputs import timings_of

# The only place published numbers live.
CLAIMS_FILE = "config/claims.yaml"


def step_config(section, keys="", **subtrees):
    """A rule's ``cfg`` param: the configuration keys its step reads.

    Parameters
    ----------
    section : str
        The study's section of the configuration (``"p3"``).
    keys : str
        Space-separated dotted paths in that section (``"mu1 heatmap.solver"``,
        or a whole subtree such as ``"strategy.figure"``).
    **subtrees : str
        Keys of one subtree, space-separated (``heatmap="n_r n_theta"`` is
        ``"heatmap.n_r heatmap.n_theta"``).

    Returns
    -------
    dict
        The keys nested as in the section (``configuration.step_params``).
    """
    paths = keys.split()
    for subtree, subkeys in subtrees.items():
        paths += [f"{subtree}.{key}" for key in subkeys.split()]
    return step_params(config, section, *paths)


def published(**claims):
    """The paper's values of claims (config/claims.yaml), as ``{"published": {name: value}}``.

    For the ``cfg`` of steps that draw a published value for comparison
    (``step_config("p2", "mu1") | published(f1="P2-F1:mu2-augmented")``). As a
    param, the rule reruns when that value changes, not on other edits of
    claims.yaml.
    """
    return {
        "published": {
            name: published_value(CLAIMS_FILE, claim) for name, claim in claims.items()
        }
    }


# The captions (workflow/report/*.rst) quote the results they describe, rendered
# by Jinja from snakemake.config: the facts read from results/ when the
# Snakefile is read (snakemake --report reads it after the results are made;
# eqrec.studies.notebooks.captions). No step reads this key.
from eqrec.studies.notebooks.captions import FACTS_KEY, report_facts

config[FACTS_KEY] = report_facts(workflow.basedir)


def in_report(path, caption, category, each=None, **kwargs):
    """An output shown in ``snakemake --report``: ``path`` with the caption
    ``workflow/report/<caption>.rst``, under ``category`` (``kwargs``:
    ``subcategory`` and the other options of Snakemake's ``report``). ``each``:
    wildcards given their values here (``{"setting": [...]}``), for a job that
    writes one such file per value: the list of them."""
    paths = expand(path, **each, allow_missing=True) if each else path
    return report(
        paths, caption=f"../report/{caption}.rst", category=category, **kwargs
    )


def figure(stem, caption, category):
    """A figure's two outputs: ``pdf`` (``<stem>.pdf``) and ``png``, shown in the
    report (``in_report``); for ``output: **figure(...)``."""
    return {"pdf": f"{stem}.pdf", "png": in_report(f"{stem}.png", caption, category)}


def scale_files(sizes, engine=""):
    """The per-size JSONs of one size list of p3.scale (engine="classes_": the class engine's)."""
    scale = config["p3"]["scale"]
    return [f"results/p3/scale/{engine}T{T}_tau{tau}.json" for T, tau in scale[sizes]]
