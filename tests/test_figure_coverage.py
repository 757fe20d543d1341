"""Every figure under results/ is shown twice: in the report, with a caption, and in a notebook, whose image
carries that caption as its alt text (issue 33 §5)."""
import base64
import re
from pathlib import Path

import nbformat
import pytest

from eqrec.studies.notebooks import execute as nbstudy

ROOT = Path(__file__).resolve().parents[1]
FIGURES = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "results").rglob("*.png") if "timings" not in p.parts)
EXECUTED = sorted((ROOT / "results" / "notebooks").glob("*.ipynb"))


def _images() -> dict[bytes, str]:
    """The PNGs the executed notebooks show, each with its alt text ('' when none)."""
    shown = {}
    for path in EXECUTED:
        for cell in nbformat.reads(path.read_text(), as_version=4).cells:
            for out in cell.get("outputs", []):
                if "image/png" in out.get("data", {}):
                    alt = out.get("metadata", {}).get("image/png", {}).get("alt", "")
                    shown[base64.b64decode(out["data"]["image/png"])] = alt
    return shown


def test_the_figures_are_found():
    assert len(FIGURES) >= 25 and "results/p3/fig_strategy.png" in FIGURES


@pytest.mark.parametrize("png", FIGURES)
def test_the_figure_has_a_report_caption(png):
    caption = nbstudy.figure_caption(png, ROOT)
    assert caption, f"{png} is in no rule's figure(...) or in_report(...): not in the report"
    assert "{%" not in caption and "``" not in caption and len(caption) > 80


@pytest.mark.parametrize("png", FIGURES)
def test_the_figure_is_shown_in_a_notebook_with_its_caption_as_alt_text(png):
    assert any(png in files for files in nbstudy.READS.values()), f"no notebook reads {png}"
    shown = _images()
    data = (ROOT / png).read_bytes()
    assert data in shown, f"no executed notebook shows the current {png} (run `snakemake --cores 2 notebooks`)"
    assert shown[data] == nbstudy.figure_caption(png, ROOT)


def test_a_caption_is_rendered_for_the_figure_its_wildcards_name(tmp_path):
    (tmp_path / "workflow" / "rules").mkdir(parents=True)
    (tmp_path / "workflow" / "report").mkdir(parents=True)
    (tmp_path / "workflow" / "rules" / "x.smk").write_text(
        'output:\n    png=in_report(\n        "results/x/{kind}_{n}.png",\n        "cap",\n        "X"),\n'
        '    **figure("results/x/plain", "plain_cap", "X"),\n')
    (tmp_path / "workflow" / "report" / "cap.rst").write_text(
        'Panel {% if snakemake.wildcards.kind == "a" %}A{% else %}other{% endif %} ``n`` = {{ snakemake.wildcards.n }}.')
    (tmp_path / "workflow" / "report" / "plain_cap.rst").write_text("Plain\ncaption.\n")
    assert nbstudy.figure_caption("results/x/a_3.png", tmp_path) == "Panel A n = 3."
    assert nbstudy.figure_caption("results/x/b_4.png", tmp_path) == "Panel other n = 4."
    assert nbstudy.figure_caption("results/x/plain.png", tmp_path) == "Plain caption."
    assert nbstudy.figure_caption("results/x/missing.png", tmp_path) is None
    assert re.fullmatch(r"results/x/\{kind\}_\{n\}\.png", next(iter(nbstudy.reported_figures(tmp_path))))
