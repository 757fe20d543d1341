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


def _prose(html: str) -> str:
    """The page's text outside code, maths, style sheets and embedded images."""
    html = re.sub(r"<(pre|code|math|style)\b.*?</\1>", "", html, flags=re.S)
    return re.sub(r"data:image/[a-z]+;base64,[A-Za-z0-9+/=]*", "", html)


@pytest.mark.parametrize("path", HTML, ids=[p.name for p in HTML])
def test_the_stored_html_has_its_maths_as_mathml_and_no_dollar_left(path):
    html = path.read_text()
    body = _prose(html.split("<body", 1)[1])
    assert "$" not in body, body[max(0, body.index("$") - 80):body.index("$") + 80]
    source = (ROOT / "notebooks" / f"{path.stem}.py").read_text()
    if re.search(r"^#.*\$[^$\n]+\$", source, flags=re.M):  # maths in a markdown cell: drawn as MathML
        assert html.count("<math") >= 5


@pytest.mark.parametrize("path", HTML, ids=[p.name for p in HTML])
def test_every_image_of_the_stored_html_has_a_caption_as_alt_text(path):
    imgs = re.findall(r"<img\b[^>]*>", path.read_text())
    assert imgs
    for img in imgs:
        alt = re.search(r"""\balt=(["'])(.*?)\1""", img)  # the page's HTML quotes with ' a value holding a "
        assert alt and len(alt.group(2)) > 80 and "No description" not in alt.group(2), img[:120]


def test_an_image_output_with_alt_metadata_gets_it_as_its_alt():
    png = ("iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg==")
    out = nbformat.v4.new_output("display_data", data={"image/png": png, "text/plain": "<Figure>"},
                                 metadata={"image/png": {"alt": 'Fig. 1 & "its" caption'}})
    nb = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell("1", outputs=[out])])
    html = offline_html(nb, "alt")
    assert """alt='Fig. 1 &amp; "its" caption'""" in html and "No description" not in html  # escaped, quoted
    del out.metadata["image/png"]
    assert "No description has been provided" in offline_html(nb, "alt")  # nbconvert's default, without one
