"""The notebooks' HTML reads offline: its maths is MathML made at build time and no script comes from the network."""
import re
from pathlib import Path

import nbformat
import pytest

from eqrec.studies.notebooks.html import markdown_maths, offline_html, tex_to_mathml

ROOT = Path(__file__).resolve().parents[1]
HTML = sorted((ROOT / "results" / "notebooks").glob("*.html"))
# an element that loads something (script, style sheet, image, frame) from an address on the network
NETWORK_LOAD = re.compile(r"<(script|link|img|iframe)\b[^>]*\b(src|href)\s*=\s*[\"']?(https?:)?//", re.I)


def test_inline_and_display_maths_become_mathml_and_code_stays():
    md = markdown_maths(r"gain $L_1$, cost $$J = \sum_k \mu_k$$ and `a $x$ b`, price \$5")
    assert md.count("<math") == 2 and 'display="block"' in md and 'display="inline"' in md
    assert "`a $x$ b`" in md and r"\$5" in md
    assert 'alttext="L_1"' in md  # the TeX source kept for copy and screen readers


def test_script_letters_are_unicode_characters():
    # MathML Core draws mathvariant="normal" only: a script L must be the character itself
    assert "\u2112" in tex_to_mathml(r"\mathcal L^{E'}") and "mathvariant" not in tex_to_mathml(r"\mathcal L")


def test_a_page_loads_no_script_and_keeps_its_maths(tmp_path):
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_markdown_cell(r"# Title with $\mu_2$" "\n\n" r"$A - LC$")])
    nb.cells.append(nbformat.v4.new_code_cell("1", outputs=[nbformat.v4.new_output(
        "display_data", data={"text/markdown": r"output maths $\bar\tau = 2$", "text/plain": "x"})]))
    html = offline_html(nb, "small")
    assert "<script" not in html and "mathjax" not in html.lower()
    assert html.count("<math") == 3 and "$" not in html.split("<body", 1)[1]
    assert ":math" not in html  # a heading's maths stays MathML (no namespace prefix an HTML parser ignores)
    assert nb.cells[0].source.startswith("# Title with $\\mu_2$")  # the notebook itself keeps its TeX


@pytest.mark.parametrize("path", HTML, ids=[p.name for p in HTML])
def test_the_stored_html_loads_nothing_from_the_network(path):
    html = path.read_text()
    assert not NETWORK_LOAD.search(html), NETWORK_LOAD.search(html).group(0)
    assert "<script" not in html and "mathjax" not in html.lower()
    assert not re.search(r"url\(\s*[\"']?(https?:)?//", html)  # no style sheet or font from the network either


@pytest.mark.parametrize("path", HTML, ids=[p.name for p in HTML])
def test_the_stored_html_has_no_raw_tex_in_its_text(path):
    html = path.read_text()
    prose = re.sub(r"<(pre|code|math)\b.*?</\1>", "", html, flags=re.S)  # code and maths aside
    assert not re.search(r"(?<![\\$])\$[^$<>\n]*\\[A-Za-z]+[^$<>\n]*\$", prose), "TeX left for a script to render"
