"""Executed notebooks: ``notebooks/<name>.py`` (jupytext, percent format) run against ``results/``.

One step, ``execute``: read the notebook with jupytext, run it in a fresh
``python3`` kernel with the repository root (the working directory) as its
working directory, and write

* ``results/notebooks/<name>.ipynb``: the notebook with its outputs and
  figures embedded (GitHub renders it without running anything), and
* ``results/notebooks/<name>.html``: its nbconvert HTML rendering (an item of
  ``snakemake --report``), readable offline: its maths is MathML made at build
  time and it loads no script from the network (:mod:`eqrec.studies.notebooks.html`).

Every figure of the report a notebook shows carries the report's caption
(``workflow/report/``) as its alt text (:func:`add_alt_text`).

Both files depend only on the notebook and the results it reads: cell ids are
``cell-0``, ``cell-1``, ...; no execution timestamps, kernel ids or jupytext
versions; consecutive stream outputs are merged (how a kernel splits printed
text into messages depends on timing); the kernel runs with
``SOURCE_DATE_EPOCH=0`` and a fixed SVG hash salt, and matplotlib's inline PNGs
carry no date, so a figure drawn in a notebook is byte-identical too.  The
notebooks show no timing or memory value (those live in ``results/timings/``).

A cell that raises fails the step with one line naming the notebook, the cell
(number and first source line) and the error.
"""

from __future__ import annotations

import base64
import os
import re
import tempfile
import time
from pathlib import Path
from unittest import mock

from eqrec.errors import StepError
from eqrec.studies.pipeline.logs import get_logger
from eqrec.studies.pipeline.outputs import write_text

log = get_logger("notebooks")

#: Seconds a single cell may run before the step fails.
CELL_TIMEOUT = 300

KERNELSPEC = {"display_name": "Python 3", "language": "python", "name": "python3"}
LANGUAGE_INFO = {"name": "python", "pygments_lexer": "ipython3"}

#: Environment of the kernel: no dates in files matplotlib writes, fixed string hashes (set order).
KERNEL_ENV = {"SOURCE_DATE_EPOCH": "0", "PYTHONHASHSEED": "0"}
#: The kernel's matplotlib rc file (``MATPLOTLIBRC``): fixed SVG ids, no PDF/SVG dates.
MATPLOTLIBRC = "svg.hashsalt: eqrec-notebooks\n"


#: The result files each notebook reads (its rule's inputs): a notebook runs after them and re-runs when
#: one changes.  ``tests/test_notebooks.py`` checks that every file a notebook names is listed here.
READS: dict[str, list[str]] = {
    "p1_prefix_based": [*(f"results/p1/{f}" for f in (
        "model.json", "designs.json", "extensions.json", "fig1_trajectories.png", "fig_ext_M2_vs_M1.png"))],
    "p2_augmented": [*(f"results/p2/{f}" for f in (
        "values.json", "designs.json", "checks.json", "heatmap.csv", "realaxis.csv", "f1_trajectories.png",
        "f2_trajectories.png", "f3a_heatmap.png", "f3b_realaxis.png"))],
    "p3_delayed": [*(f"results/p3/{f}" for f in (
        "languages.json", "reactor_model.json", "reactor_designs.json", "augmented.json", "kalman.json", "acc.json",
        "values.json", "examples.md", "language_counts.csv", "fig1_kalman.png", "fig2_acc.png", "scale_table.csv",
        "fig_strategy.png", "strategy_values.json"))],
    "p4_lmv": [*(f"results/p4/{f}" for f in (
        "values.json", "mc_ex1.json", "mc_ex2.json", "fig1_filter.png", "fig2_predictor.png", "fig3_smoother.png",
        "fig4_variances.png", "fig5_eta.png", "fig6_q.png", "regions.png", "fig7_compare_ex1.png",
        "fig8_compare_ex2.png"))],
    "compare": ["results/compare/compare.csv", "results/compare/summary.json",
                *(f"results/compare/{system}_{setting}.png" for system in ("acc", "reactor")
                  for setting in ("loss01", "loss03", "burst", "loss04"))],
}
for _files in READS.values():  # every notebook reads the claims table
    _files.append("results/claims.csv")


#: The report captions (``<name>.rst``) and the rules that attach them to figures.
CAPTIONS_DIR, RULES_DIR = Path("workflow") / "report", Path("workflow") / "rules"
# a figure in the report: ``figure("<stem>", "<caption>", ...)`` or ``in_report("<path>.png", "<caption>", ...)``
_REPORTED = re.compile(r'(?:\bfigure\(\s*"(?P<stem>[^"]+)"|\bin_report\(\s*"(?P<path>[^"]+\.png)")\s*,\s*"(?P<caption>\w+)"')


def reported_figures(root: str | Path = ".") -> dict[str, str]:
    """The PNG figures the report shows, as ``{path pattern: caption name}``, read from the workflow's rules.

    Parameters
    ----------
    root : str or Path, optional
        The repository root.

    Returns
    -------
    dict
        Keys are paths under ``results/`` with the rule's wildcards (``results/p2/{fig}_trajectories.png``),
        values the names of their captions in :data:`CAPTIONS_DIR`.
    """
    found = {}
    for rules in sorted((Path(root) / RULES_DIR).glob("*.smk")):
        for m in _REPORTED.finditer(rules.read_text()):
            found[m["path"] or f"{m['stem']}.png"] = m["caption"]
    return found


def figure_caption(png: str, root: str | Path = ".", config: dict | None = None) -> str | None:
    """The report's caption of figure ``png`` (a path under ``results/``) as plain text, or ``None``.

    The caption's Jinja is rendered as ``snakemake --report`` renders it
    (:func:`eqrec.studies.notebooks.captions.render_caption`): with the wildcards the path matches and the
    configuration holding the facts it quotes from ``results/``; its reStructuredText literals (````x````)
    become plain text.

    Parameters
    ----------
    png : str
        The figure's path relative to the repository root.
    root : str or Path, optional
        The repository root.
    config : dict or None, optional
        The configuration with the facts (default: the default configuration and the stored results' facts).

    Returns
    -------
    str or None
        The caption, or ``None`` when the report does not show the figure.
    """
    from eqrec.studies.notebooks.captions import FACTS_KEY, default_config, plain, render_caption, report_facts

    for pattern, caption in reported_figures(root).items():
        regex = re.sub(r"\\\{(\w+)\\\}", r"(?P<\1>[^/]+?)", re.escape(pattern))
        m = re.fullmatch(regex, png)
        if m:
            if config is None:
                config = {**default_config(root), FACTS_KEY: report_facts(root)}
            text = (Path(root) / CAPTIONS_DIR / f"{caption}.rst").read_text()
            return plain(render_caption(text, m.groupdict(), config))
    return None


def add_alt_text(nb, figures: list[str], root: str | Path = ".") -> int:
    """Give every PNG output that shows one of ``figures`` its report caption as alt text (in place).

    An output shows a figure when its bytes are the file's (``IPython.display.Image(filename=...)``).

    Parameters
    ----------
    nb : nbformat.NotebookNode
        The executed notebook.
    figures : list of str
        Paths (relative to ``root``) of the figures the notebook may show.
    root : str or Path, optional
        The repository root.

    Returns
    -------
    int
        The number of images given a caption.
    """
    from eqrec.studies.notebooks.captions import FACTS_KEY, default_config, report_facts

    by_bytes = {(Path(root) / f).read_bytes(): f for f in figures if f.endswith(".png")}
    config = {**default_config(root), FACTS_KEY: report_facts(root)}
    done = 0
    for cell in nb.cells:
        for out in cell.get("outputs", []):
            data = out.get("data", {})
            path = by_bytes.get(base64.b64decode(data["image/png"])) if "image/png" in data else None
            caption = figure_caption(path, root, config) if path else None
            if caption:
                out.setdefault("metadata", {}).setdefault("image/png", {})["alt"] = caption
                done += 1
    return done


def rule_inputs(wildcards) -> dict[str, str | list[str]]:
    """The inputs of the rule running notebook ``wildcards.name``: its source, the result files it reads, and the
    report's captions and rules (the alt text of its figures)."""
    return {"notebook": f"notebooks/{wildcards.name}.py", "results": list(READS[wildcards.name]),
            "captions": sorted(str(p) for p in (*CAPTIONS_DIR.glob("*.rst"), *RULES_DIR.glob("*.smk")))}


class NotebookError(StepError):
    """A notebook cell raised; the message names the notebook and the cell."""


def normalise(nb) -> None:
    """Make an executed notebook depend only on its source and outputs (in place).

    Consecutive outputs of one stream become one (how a kernel splits printed text into messages depends on
    timing: nbconvert's ``CoalesceStreamsPreprocessor``).
    """
    from nbconvert.preprocessors import CoalesceStreamsPreprocessor

    CoalesceStreamsPreprocessor().preprocess(nb, {})
    nb.metadata = {"kernelspec": dict(KERNELSPEC), "language_info": dict(LANGUAGE_INFO)}
    for i, cell in enumerate(nb.cells):
        cell["id"] = f"cell-{i}"
        for key in ("execution", "jupytext", "ExecuteTime", "collapsed", "scrolled"):
            cell.metadata.pop(key, None)
        for out in cell.get("outputs", []):
            out.get("metadata", {}).pop("execution", None)
    nb.nbformat, nb.nbformat_minor = 4, 5


def _cell_line(nb, i: int) -> str:
    """``cell 3 ('summary = heat.groupby(...')``: the cell's number and first non-empty source line."""
    first = next((ln.strip() for ln in nb.cells[i].source.splitlines() if ln.strip()), "")
    return f"cell {i} ({first!r})"


def execute(source: str | Path, workdir: str | Path | None = None, timeout: int = CELL_TIMEOUT):
    """The executed, normalised notebook of a jupytext file (raises :class:`NotebookError` if a cell fails)."""
    import jupytext
    from nbclient import NotebookClient

    source = Path(source)
    workdir = Path(workdir or Path.cwd()).resolve()
    nb = jupytext.read(source)
    client = NotebookClient(nb, timeout=timeout, kernel_name="python3", record_timing=False,
                            resources={"metadata": {"path": str(workdir)}})
    # the kernel inherits this environment
    with tempfile.TemporaryDirectory(prefix="eqrec-nb-") as tmp:
        rc = Path(tmp) / "matplotlibrc"
        rc.write_text(MATPLOTLIBRC)
        with mock.patch.dict(os.environ, {**KERNEL_ENV, "MATPLOTLIBRC": str(rc)}):
            _run(client, nb, source)
    normalise(nb)
    return nb


def _run(client, nb, source: Path) -> None:
    """Execute; a failing cell becomes one :class:`NotebookError` line naming the notebook and the cell."""
    from nbclient.exceptions import CellExecutionError, CellTimeoutError, DeadKernelError

    current: list[int] = []
    client.on_cell_execute = lambda cell, cell_index: current.append(cell_index)
    try:
        client.execute()
    except (CellExecutionError, CellTimeoutError, DeadKernelError) as exc:
        where = _cell_line(nb, current[-1]) if current else "before the first cell"
        if isinstance(exc, CellExecutionError):
            what = f"{exc.ename}: {exc.evalue}"
        else:  # a timeout or a dead kernel: the last line of its message
            what = f"{type(exc).__name__}: {(str(exc).strip().splitlines() or [''])[-1]}"
        raise NotebookError(f"notebook {source}, {where}: {what}") from None


def step_execute(cfg, inputs, outputs, wildcards):
    """``notebooks/<name>.py`` executed against ``results/``: ``<name>.ipynb`` and ``<name>.html`` (readable
    offline: maths as MathML, no script from the network, :func:`eqrec.studies.notebooks.html.offline_html`)."""
    import nbformat

    from eqrec.studies.notebooks.html import offline_html

    t0 = time.perf_counter()
    nb = execute(inputs.notebook, workdir=Path.cwd())
    log.info("%s executed in %.1f s", inputs.notebook, time.perf_counter() - t0)
    captioned = add_alt_text(nb, list(getattr(inputs, "results", None) or []))
    log.info("%s: %d figures carry their caption as alt text", inputs.notebook, captioned)
    nbformat.validate(nb)
    write_text(outputs.ipynb, nbformat.writes(nb, version=4) + "\n")
    write_text(outputs.html, offline_html(nb, Path(inputs.notebook).stem))
