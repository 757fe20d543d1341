"""Every stored figure is readable at report width: text at least 11 px tall (em) when shown 800 px wide.

The sizes are read from the stored PDFs (``results/**/*.pdf``) with pdfminer.six: each text drawn in
a ``BT ... ET`` block gets its font size times the scale of the text and current transformation
matrices, in PDF points; shown ``REPORT_WIDTH_PX`` wide, a page ``W`` points wide draws it
``size * REPORT_WIDTH_PX / W`` px tall.  Matplotlib draws a mathtext string (``"level $M_2^*$"``) in one
block, its sub- and superscripts smaller: a block's text is as tall as its largest glyph, and its
smaller glyphs (the scripts) are set aside, as the rule says.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from pdfminer.pdfdevice import PDFDevice
from pdfminer.pdfdocument import PDFDocument
from pdfminer.pdfinterp import PDFPageInterpreter, PDFResourceManager
from pdfminer.pdfpage import PDFPage
from pdfminer.pdfparser import PDFParser
from pdfminer.utils import mult_matrix

from eqrec.studies.plotting import MIN_EM_PX, REPORT_WIDTH_PX

RESULTS = Path(__file__).resolve().parents[1] / "results"
FIGURES = sorted(p for p in RESULTS.rglob("*.pdf") if "timings" not in p.parts)


class _TextSizes(PDFDevice):
    """Records, per text block, the size (PDF points) and text of every string drawn."""

    def __init__(self, rsrcmgr):
        super().__init__(rsrcmgr)
        self.blocks: list[list[tuple[float, str]]] = []

    def render_string(self, textstate, seq, ncs, graphicstate):
        a, b, c, d, _, _ = mult_matrix(textstate.matrix, self.ctm)
        size = textstate.fontsize * math.sqrt(abs(a * d - b * c))
        text = "".join(textstate.font.to_unichr(cid) if _has_unicode(textstate.font, cid) else "?"
                       for obj in seq if isinstance(obj, bytes) for cid in textstate.font.decode(obj))
        if not self.blocks:
            self.blocks.append([])
        self.blocks[-1].append((size, text))


def _has_unicode(font, cid) -> bool:
    try:
        font.to_unichr(cid)
    except Exception:  # a glyph without a Unicode mapping: counted, shown as '?'
        return False
    return True


class _BlockInterpreter(PDFPageInterpreter):
    """Starts a new block of the device at every ``BT`` (one matplotlib text, mathtext included)."""

    def do_BT(self):
        self.device.blocks.append([])
        super().do_BT()


def text_heights(pdf: Path) -> tuple[float, list[tuple[float, str]]]:
    """``(page width in points, [(em in px at REPORT_WIDTH_PX, text), ...])``, one entry per text block.

    Parameters
    ----------
    pdf : Path
        A one-page PDF figure.

    Returns
    -------
    tuple
        The page width and, per text block, the em of its largest glyph (scripts aside) at report width.
    """
    with open(pdf, "rb") as fh:
        doc = PDFDocument(PDFParser(fh))
        rsrc = PDFResourceManager()
        device = _TextSizes(rsrc)
        pages = list(PDFPage.create_pages(doc))
        assert len(pages) == 1, f"{pdf}: {len(pages)} pages"
        x0, _, x1, _ = pages[0].mediabox
        _BlockInterpreter(rsrc, device).process_page(pages[0])
    width = float(x1 - x0)
    out = []
    for block in device.blocks:
        if block:
            out.append((max(s for s, _ in block) * REPORT_WIDTH_PX / width, "".join(t for _, t in block)))
    return width, out


def _figure(tmp_path, fontsize: float, text: str) -> Path:
    from eqrec.studies.pipeline.outputs import save_figure
    from eqrec.studies.plotting import paper_style, pyplot

    paper_style()
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 3.0))
    ax.set_xlabel(text, fontsize=fontsize)
    ax.tick_params(labelsize=9)
    path = tmp_path / "f.pdf"
    save_figure(fig, path)
    return path


def test_the_measure_reads_font_sizes_and_sets_scripts_aside(tmp_path):
    width, texts = text_heights(_figure(tmp_path, 9.0, "level $M_2^*$"))
    label = [em for em, t in texts if t.startswith("level")]
    assert label and abs(label[0] - 9.0 * REPORT_WIDTH_PX / width) < 1e-6  # the 6.3-pt scripts set aside
    width, texts = text_heights(_figure(tmp_path, 5.0, "tiny label"))
    small = [t for em, t in texts if em < MIN_EM_PX]
    assert small == ["tiny label"]


def test_every_stored_png_figure_has_its_pdf():
    pngs = {p.with_suffix("") for p in RESULTS.rglob("*.png") if "notebooks" not in p.parts}
    assert pngs and pngs <= {p.with_suffix("") for p in FIGURES}


@pytest.mark.parametrize("pdf", FIGURES, ids=[str(p.relative_to(RESULTS)) for p in FIGURES])
def test_text_is_at_least_11_px_at_report_width(pdf):
    width, texts = text_heights(pdf)
    assert texts, f"{pdf} has no text"
    small = sorted((round(em, 2), t) for em, t in texts if em < MIN_EM_PX)
    assert not small, (f"{pdf.relative_to(RESULTS)} ({width / 72:.2f} in wide): text under {MIN_EM_PX:g} px at "
                       f"{REPORT_WIDTH_PX} px width: {small[:5]}")
