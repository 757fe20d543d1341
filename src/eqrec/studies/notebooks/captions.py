"""The report's captions rendered from the results they describe: no number, family or setting typed by hand.

A caption (``workflow/report/<name>.rst``) is a Jinja template, rendered by
``snakemake --report`` with ``snakemake.wildcards`` and ``snakemake.config``.
The Snakefile adds to the configuration, under :data:`FACTS_KEY`, what
:func:`report_facts` reads from ``results/`` when the report is made (the
result JSONs of every study, the claims table, the compare study's families),
so a caption quotes ``{{ snakemake.config.facts.p1.designs.designs.prefix.mu2 }}``
instead of typing 1.15, and the words follow the results when they change.
The notebooks' alt texts are the same captions rendered the same way
(:func:`render_caption`, used by :func:`eqrec.studies.notebooks.execute.figure_caption`).
"""

from __future__ import annotations

import csv
import json
from pathlib import Path
from types import SimpleNamespace
from typing import Any, Mapping

#: The configuration key under which the Snakefile puts :func:`report_facts` for the captions.
FACTS_KEY = "facts"
#: The studies whose ``results/<study>/*.json`` the captions may quote.
STUDIES = ("p1", "p2", "p3", "p4", "compare")


def report_facts(root: str | Path = ".") -> dict[str, Any]:
    """What the captions quote, read from ``results/`` (empty parts where a file is not made yet).

    Parameters
    ----------
    root : str or Path, optional
        The repository root.

    Returns
    -------
    dict
        ``{study: {stem: JSON}}`` for every ``results/<study>/*.json``; ``figures``: constants the figures are
        drawn with (``compare_band``, ``p4_z_band``, ``p4_band_level``); ``claims``: ``{id: row}`` of
        ``results/claims.csv``; ``compare_pairs``: ``{"<system>_<setting>": pair}`` of
        ``results/compare/summary.json``, each pair with ``families`` (the compare study's families, in
        the order its figure draws them) and ``rows`` (its rows of ``compare.csv``, by family).
    """
    import math

    from eqrec.compare.families import FAMILIES
    from eqrec.compare.figure import BAND_WORDS
    from eqrec.studies.p4.figures import Z_BAND

    res = Path(root) / "results"
    # the constants the figures are drawn with: the compare band's quantiles, the LMV figures' Monte Carlo band
    # (half-width in standard errors and its normal level)
    figures = {"compare_band": BAND_WORDS, "p4_z_band": Z_BAND, "p4_band_level": 100 * math.erf(Z_BAND / math.sqrt(2))}
    facts: dict[str, Any] = {"families": list(FAMILIES), "figures": figures}
    for study in STUDIES:
        facts[study] = {p.stem: json.loads(p.read_text()) for p in sorted((res / study).glob("*.json"))}
    claims = res / "claims.csv"
    facts["claims"] = {r["id"]: r for r in csv.DictReader(claims.open())} if claims.exists() else {}
    rows: dict[str, dict[str, dict]] = {}
    table = res / "compare" / "compare.csv"
    if table.exists():
        for r in csv.DictReader(table.open()):
            rows.setdefault(f"{r['system']}_{r['setting']}", {})[r["estimator"]] = r
    facts["compare_pairs"] = {
        f"{p['system']}_{p['setting']}": {**p, "families": list(FAMILIES),
                                          "rows": rows.get(f"{p['system']}_{p['setting']}", {})}
        for p in facts["compare"].get("summary", {}).get("pairs", [])}
    return facts


def default_config(root: str | Path = ".") -> dict[str, Any]:
    """The workflow's default configuration (``config/*.yaml`` as the Snakefile loads them, no overrides)."""
    import yaml

    config: dict[str, Any] = {}
    for name in ("config", "p2", "p3", "p4", "compare"):
        path = Path(root) / "config" / f"{name}.yaml"
        if path.exists():
            config.update(yaml.safe_load(path.read_text()) or {})
    return config


def render_caption(template: str, wildcards: Mapping[str, str], config: Mapping[str, Any]) -> str:
    """A caption's text: its Jinja rendered as ``snakemake --report`` does, with ``snakemake.wildcards`` and
    ``snakemake.config`` (which holds :func:`report_facts` under :data:`FACTS_KEY`); a name the template
    uses that is not there raises (Snakemake would render it empty).

    Parameters
    ----------
    template : str
        The caption file's text.
    wildcards : mapping
        The figure's wildcards.
    config : mapping
        The configuration, with the facts.

    Returns
    -------
    str
        The reStructuredText of the caption.
    """
    import jinja2

    env = jinja2.Environment(trim_blocks=True, lstrip_blocks=True, undefined=jinja2.StrictUndefined)
    snakemake = SimpleNamespace(wildcards=SimpleNamespace(**wildcards), config=config)
    return env.from_string(template).render(snakemake=snakemake)


def plain(rst: str) -> str:
    """A rendered caption as plain text (alt text): reStructuredText literals unquoted, on one line."""
    return " ".join(rst.replace("``", "").split())
