"""The words next to the results are made from them: every caption and every notebook's prose, rendered with
the stored results, is checked against them.

* every caption renders from the stored results (no name it quotes is missing) into reStructuredText that
  docutils reads without a warning;
* the typed text (caption templates outside their Jinja, notebook markdown cells) quotes no number: the
  numbers come from the results or the configuration, through the template or the notebook's code; only
  references (Fig. 3, eq. (10), Section III-B3, ref. [9], ids such as P3-F1) are typed;
* every decimal number of the rendered prose (captions, the notebooks' markdown) is a stored result or a
  configured value printed at its precision;
* no raw TeX and no ASCII maths (``mu_{2,k}``, ``||x||_inf``, ``10^4``, ``mu1``) reaches a rendered caption, a
  notebook page's text or an image's alt text;
* the compare figures' families and lines are all named in their captions;
* no cell of a notebook page's tables is cut (``...``), and a figure shown ``width=800`` is 800 px wide;
* every file a notebook names exists.
"""

from __future__ import annotations

import csv
import html as html_lib
import json
import math
import re
from pathlib import Path

import jupytext
import nbformat
import pytest

from eqrec.studies.notebooks.captions import FACTS_KEY, default_config, plain, render_caption, report_facts
from eqrec.studies.notebooks.execute import CAPTIONS_DIR, READS, RULES_DIR
from eqrec.studies.notebooks.text import ASCII_MATHS, RAW_TEX

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.py"))
HTML = sorted((RESULTS / "notebooks").glob("*.html"))
IPYNB = sorted((RESULTS / "notebooks").glob("*.ipynb"))

# an output in the report: in_report("<path>", "<caption>", ...) or figure("<stem>", "<caption>", ...)
_REPORTED = re.compile(r'\b(?:in_report|figure)\(\s*"(?P<path>[^"]+)"\s*,\s*"(?P<caption>\w+)"')


def _reported() -> list[tuple[str, dict]]:
    """``(caption name, wildcards)`` of every stored output the report shows, and the report's own caption."""
    out = [("workflow", {})]
    for rules in sorted((ROOT / RULES_DIR).glob("*.smk")):
        for m in _REPORTED.finditer(rules.read_text()):
            path = m["path"] if "." in Path(m["path"]).name else m["path"] + ".png"
            names = re.findall(r"\{(\w+)\}", path)
            regex = re.sub(r"\\\{(\w+)\\\}", r"(?P<\1>[^/]+?)", re.escape(path))
            for f in sorted(ROOT.glob(re.sub(r"\{\w+\}", "*", path))):
                wc = re.fullmatch(regex, str(f.relative_to(ROOT)))
                if wc and all(n in wc.groupdict() for n in names):
                    out.append((m["caption"], wc.groupdict()))
    return sorted({(c, json.dumps(w, sort_keys=True)) for c, w in out})


CAPTIONS = [(c, json.loads(w)) for c, w in _reported()]
CAPTION_IDS = [f"{c}-{'-'.join(w.values())}" if w else c for c, w in CAPTIONS]


@pytest.fixture(scope="module")
def config():
    return {**default_config(ROOT), FACTS_KEY: report_facts(ROOT)}


def _rendered(name: str, wildcards: dict, config) -> str:
    return render_caption((ROOT / CAPTIONS_DIR / f"{name}.rst").read_text(), wildcards, config)


def _prose_of_caption(rst: str) -> str:
    """A rendered caption's text, its literals (````code````) aside."""
    return plain(re.sub(r"``[^`]*``", "", rst))


# --------------------------------------------------------------------------- typed text quotes no number

#: What typed text may hold with digits: references to the papers' figures, equations, sections and
#: references, ids of targets and claims, the venues' years, script digits of maths, ordinals of a list.
_REFERENCE = re.compile(
    r"\b(?:Figs?\.|Examples?|Eqs?\.|eqs?\.|Sections?|Theorems?|Def\.|Definitions?|Tables?|ref\.|Appendix)"
    r"\s*\(?[0-9IVX]+[a-zA-Z0-9-]*\)?(?:\s*(?:,|and|–|-|\.\.)\s*(?:Fig\.\s*)?\(?[0-9]+[a-z]?\)?)*"
    r"|\bP[1-4](?:-[A-Z0-9]+)*(?::[\w-]+)?|\((?:ACC|CDC) \d{4}\)|\(\d{1,2}\)|\[\d{1,2}\]|\bIII-B\d\b"
    r"|[_^]\{[^}]*\}|[_^]\d|\bx̃\d|\bone-step\b|\b[0-9]-based\b|\bsum_k\b|\bp[1-4]_\w+|\bF\d\b|F\d[ab]?\b")
#: Typed numbers that are names, not values: a column's name (``bound_over_limit_p95``), the venue's year, the
#: configurations of the scale study's legend.
_NAMES = ("95th percentile", "ACC 2019", "1 and 2 workers")


def _typed_numbers(text: str) -> list[str]:
    """The numbers typed in ``text`` (markdown or a caption template outside its Jinja), references aside.

    Zero and one are structure (``t = 0``, ``x(t+1)``, ``period 1``, a ratio of one) and not counted; any other
    integer and every decimal is, unless it is a reference or a name of :data:`_NAMES`.
    """
    text = re.sub(r"\{\{.*?\}\}|\{%.*?%\}", " ", text, flags=re.S)  # the template's expressions
    text = re.sub(r"``[^`]*``|`[^`]*`", " ", text)  # code and literals
    for name in _NAMES:
        text = text.replace(name, " ")
    text = _REFERENCE.sub(" ", text)
    return [text[max(0, m.start() - 30):m.end() + 20] for m in re.finditer(r"(?<![\w₀-₉.])\d+(?:\.\d+)?", text)
            if "." in m[0] or int(m[0]) > 1]


def _markdown_cells(path: Path) -> str:
    return "\n\n".join(c.source for c in jupytext.read(path).cells if c.cell_type == "markdown")


@pytest.mark.parametrize("path", sorted((ROOT / CAPTIONS_DIR).glob("*.rst")), ids=lambda p: p.stem)
def test_a_caption_template_types_no_number(path):
    assert not _typed_numbers(path.read_text()), _typed_numbers(path.read_text())


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_a_notebook_markdown_cell_types_no_number(path):
    assert not _typed_numbers(_markdown_cells(path)), _typed_numbers(_markdown_cells(path))


def test_the_typed_number_check_finds_a_typed_value():
    assert _typed_numbers("hold-input wins for $Q_\\lambda$ below about 0.8")
    assert _typed_numbers("the designs cover 3 of 6 measurements")
    assert not _typed_numbers("Fig. 3a and eq. (10) of ref. [9], rows P3-F1, $\\mu_{2,k}$, {{ x.y }} steps")


# --------------------------------------------------------------------------- every caption renders

@pytest.mark.parametrize(("name", "wildcards"), CAPTIONS, ids=CAPTION_IDS)
def test_every_caption_renders_from_the_stored_results_into_clean_rst(name, wildcards, config):
    from docutils.core import publish_parts

    rst = _rendered(name, wildcards, config)
    assert "{{" not in rst and "{%" not in rst
    # a docutils warning (an unclosed literal, a stray emphasis mark) raises
    publish_parts(rst, writer_name="html", settings_overrides={"halt_level": 2, "report_level": 2})
    prose = _prose_of_caption(rst)
    bad = [prose[max(0, m.start() - 30):m.end() + 30] for r in (ASCII_MATHS, RAW_TEX) for m in r.finditer(prose)]
    assert not bad, f"ASCII maths or raw TeX in the caption {name} {wildcards}: {bad}"


def test_the_maths_check_finds_ascii_maths_and_tex():
    for text in ("mu_{2,k}", "x(t|I_{t-1})", "r e^{+-j theta}", "||x - x^||_inf", "10^4", "mu1", "E_alpha"):
        assert ASCII_MATHS.search(text) or RAW_TEX.search(text), text
    assert RAW_TEX.search(r"$L_1 = \{101111\}$")
    assert not ASCII_MATHS.search("μ₂,ₖ of x̂(t | t − 1), ‖x − x̂‖∞, 10⁴ runs, μ₁ = 0.33")


# --------------------------------------------------------------------------- numbers come from the results

def _numbers_of(value, out: set[float]) -> None:
    if isinstance(value, bool):
        return
    if isinstance(value, (int, float)):
        if math.isfinite(value):
            out.add(float(value))
    elif isinstance(value, dict):
        for v in value.values():
            _numbers_of(v, out)
    elif isinstance(value, list):
        for v in value:
            _numbers_of(v, out)
    elif isinstance(value, str):
        out.update(float(x) for x in re.findall(r"-?\d+(?:\.\d+)?(?:e-?\d+)?", value))


@pytest.fixture(scope="module")
def stored_numbers(config) -> set[float]:
    """Every number of the stored results (JSON leaves, CSV and Markdown cells and their texts) and of the
    configuration."""
    out: set[float] = set()
    _numbers_of(config, out)
    for path in RESULTS.rglob("*"):
        if "timings" in path.parts or "notebooks" in path.parts:
            continue
        if path.suffix == ".json":
            _numbers_of(json.loads(path.read_text()), out)
        elif path.suffix in (".csv", ".md"):
            _numbers_of(path.read_text(), out)
    return out


def _is_stored(printed: str, numbers: set[float], percent: bool) -> bool:
    """``printed`` (``1.737``) is some stored number rounded to its decimals (or that number in percent)."""
    decimals = len(printed.split(".")[1])
    value = float(printed)
    return any(abs(round(v * (100 if percent else 1), decimals) - value) < 10 ** -(decimals + 3)
               or abs(round(abs(v) * (100 if percent else 1), decimals) - value) < 10 ** -(decimals + 3)
               for v in numbers)


def _decimals(text: str) -> list[tuple[str, bool]]:
    """The decimal numbers of ``text`` (``1.737``, ``20.5 %``), each with whether it is a percentage."""
    return [(m[1], bool(m[2])) for m in re.finditer(r"(?<![\w.])(\d+\.\d+)(?![\d.]*\w)(\s*%)?", text)]


@pytest.mark.parametrize(("name", "wildcards"), CAPTIONS, ids=CAPTION_IDS)
def test_every_decimal_of_a_rendered_caption_is_a_stored_result(name, wildcards, config, stored_numbers):
    prose = _prose_of_caption(_rendered(name, wildcards, config))
    bad = [p for p, pct in _decimals(prose) if not _is_stored(p, stored_numbers, pct)]
    assert not bad, f"{name} {wildcards}: numbers no result holds: {bad}"


def _markdown_outputs(path: Path) -> str:
    nb = nbformat.read(path, as_version=4)
    return "\n".join(out["data"]["text/markdown"] for cell in nb.cells for out in cell.get("outputs", [])
                     if "text/markdown" in out.get("data", {}))


@pytest.mark.parametrize("path", IPYNB, ids=lambda p: p.stem)
def test_every_decimal_of_a_notebook_text_is_a_stored_result(path, stored_numbers):
    text = re.sub(r"`[^`]*`", "", _markdown_outputs(path))
    assert text.strip(), f"{path.name} shows no text made from its results"
    bad = [p for p, pct in _decimals(text) if not _is_stored(p, stored_numbers, pct)]
    assert not bad, f"{path.name}: numbers no result holds: {bad}"


def test_the_number_check_finds_a_number_no_result_holds():
    assert _is_stored("1.737", {1.7370933}, False) and _is_stored("39.0", {0.39}, True)
    assert not _is_stored("0.8", {0.7183, 2.0}, False)
    assert _decimals("about 0.8; 20 % and 12.5 %") == [("0.8", False), ("12.5", True)]


# --------------------------------------------------------------------------- what the compare figures draw

COMPARE = sorted({(w["system"], w["setting"]) for c, w in CAPTIONS if c == "compare"})


@pytest.mark.parametrize(("system", "setting"), COMPARE, ids=[f"{a}_{b}" for a, b in COMPARE])
def test_every_family_and_line_of_a_compare_figure_is_named_in_its_caption(system, setting, config):
    prose = _prose_of_caption(_rendered("compare", {"system": system, "setting": setting}, config))
    with open(RESULTS / "compare" / f"{system}_{setting}.csv") as fh:
        families = [r["estimator"] for r in csv.DictReader(fh)]
    assert families
    from eqrec.compare.figure import LINES

    missing = [f for f in (*families, *LINES) if f not in prose]
    assert not missing, f"the caption of {system}_{setting} does not name {missing}"


# --------------------------------------------------------------------------- the notebook pages

def _page_text(page: str) -> str:
    """A page's text outside code, maths, style sheets and embedded images, entities decoded."""
    page = page.split("<body", 1)[1]
    page = re.sub(r"<(pre|code|math|style)\b.*?</\1>", " ", page, flags=re.S)
    page = re.sub(r"<[^>]+>", " ", page)
    return html_lib.unescape(page)


@pytest.mark.parametrize("path", HTML, ids=lambda p: p.stem)
def test_a_notebook_page_has_no_ascii_maths_or_tex_in_its_text_or_alt_texts(path):
    page = path.read_text()
    alts = [html_lib.unescape(a[1]) for a in re.findall(r"""\balt=(["'])(.*?)\1""", page)]
    for text in (_page_text(page), *alts):
        bad = [text[max(0, m.start() - 40):m.end() + 40] for r in (ASCII_MATHS, RAW_TEX) for m in r.finditer(text)]
        assert not bad, f"{path.name}: {bad[:5]}"


@pytest.mark.parametrize("path", HTML, ids=lambda p: p.stem)
def test_no_table_cell_of_a_notebook_page_is_cut(path):
    cells = re.findall(r"<t[dh]\b[^>]*>(.*?)</t[dh]>", path.read_text(), flags=re.S)
    assert cells
    cut = [c for c in cells if re.search(r"(\.\.\.|…)\s*$", re.sub(r"<[^>]+>", "", c))]
    assert not cut, f"{path.name}: cut cells {cut[:3]}"


@pytest.mark.parametrize("path", HTML, ids=lambda p: p.stem)
def test_a_notebook_figure_shown_800_wide_is_800_wide_in_its_page(path):
    source = (ROOT / "notebooks" / f"{path.stem}.py").read_text()
    asked = len(re.findall(r"\bImage\([^\n]*width=800", source))
    imgs = re.findall(r"<img\b[^>]*>", path.read_text())
    wide = [i for i in imgs if 'width="800"' in i]
    assert asked and len(wide) >= asked, f"{path.name}: {len(wide)} images 800 px wide, {asked} asked"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_every_file_a_notebook_names_exists(path):
    source = path.read_text()
    named = set(re.findall(r"\bresults/[\w./-]+\.(?:png|pdf|csv|json|md|npz|html|ipynb)\b", source))
    res = re.search(r'^RES = ROOT / "results" / "(\w+)"', source, flags=re.M)
    if res:
        named |= {f"results/{res[1]}/{f}" for f in re.findall(r'RES / f?"([\w.{}\[\]\'_]+\.\w+)"', source)
                  if "{" not in f}
    assert named
    missing = sorted(f for f in named if not (ROOT / f).exists())
    assert not missing, f"{path.name} names files that are not there: {missing}"
    reads = set(READS[path.stem])
    assert {f for f in named if not f.startswith("results/timings/")} <= reads | {
        f for f in named if f.endswith(".ipynb")}, "a file the notebook names is not an input of its rule"
