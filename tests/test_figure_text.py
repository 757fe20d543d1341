"""Every stored figure is readable at report width: text at least 11 px tall (em) when shown 800 px wide, and
every digit at least 9 px tall (a script's digit, such as a log axis's exponent, at least 7 px), measured on
the glyph.

The sizes are read from the stored PDFs (``results/**/*.pdf``) with pdfminer.six: each text drawn in
a ``BT ... ET`` block gets its font size times the scale of the text and current transformation
matrices, in PDF points; shown ``REPORT_WIDTH_PX`` wide, a page ``W`` points wide draws it
``size * REPORT_WIDTH_PX / W`` px tall.  Matplotlib draws a mathtext string (``"level $M_2^*$"``) in one
block, its sub- and superscripts smaller: a block's text is as tall as its largest glyph, and its
smaller glyphs (the scripts) are set aside, as the rule says.

The digits are measured as glyphs, not as font sizes: a digit drawn at size ``s`` in font ``F`` is
``s * h_F(d)`` tall, ``h_F(d)`` the height of the outline of digit ``d`` in ``F`` per unit of size, read from
the font file matplotlib embedded (FreeType, no hinting).  The scripts are not set aside here: a
superscript's digits (``10^{-2}`` on a logarithmic axis) must reach :data:`MIN_SCRIPT_DIGIT_PX`, the other
digits :data:`MIN_DIGIT_PX`.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import pytest
from pdfminer.pdfdevice import PDFDevice
from pdfminer.pdfdocument import PDFDocument
from pdfminer.pdfinterp import PDFPageInterpreter, PDFResourceManager
from pdfminer.pdfpage import PDFPage
from pdfminer.pdfparser import PDFParser
from pdfminer.utils import mult_matrix

from eqrec.studies.plotting import MIN_DIGIT_PX, MIN_EM_PX, MIN_SCRIPT_DIGIT_PX, REPORT_WIDTH_PX

RESULTS = Path(__file__).resolve().parents[1] / "results"
FIGURES = sorted(p for p in RESULTS.rglob("*.pdf") if "timings" not in p.parts)


class _TextSizes(PDFDevice):
    """Records, per text block, the size (PDF points) and text of every string drawn."""

    def __init__(self, rsrcmgr):
        super().__init__(rsrcmgr)
        self.blocks: list[list[tuple[float, str]]] = []
        self.fonts: list[list[str]] = []  # the font of each string, parallel to blocks

    def render_string(self, textstate, seq, ncs, graphicstate):
        a, b, c, d, _, _ = mult_matrix(textstate.matrix, self.ctm)
        size = textstate.fontsize * math.sqrt(abs(a * d - b * c))
        text = "".join(textstate.font.to_unichr(cid) if _has_unicode(textstate.font, cid) else "?"
                       for obj in seq if isinstance(obj, bytes) for cid in textstate.font.decode(obj))
        if not self.blocks:
            self.blocks.append([])
            self.fonts.append([])
        self.blocks[-1].append((size, text))
        self.fonts[-1].append(textstate.font.fontname)


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
        self.device.fonts.append([])
        super().do_BT()


def _read(pdf: Path) -> tuple[float, _TextSizes]:
    with open(pdf, "rb") as fh:
        doc = PDFDocument(PDFParser(fh))
        rsrc = PDFResourceManager()
        device = _TextSizes(rsrc)
        pages = list(PDFPage.create_pages(doc))
        assert len(pages) == 1, f"{pdf}: {len(pages)} pages"
        x0, _, x1, _ = pages[0].mediabox
        _BlockInterpreter(rsrc, device).process_page(pages[0])
    return float(x1 - x0), device


@functools.lru_cache(maxsize=None)
def digit_height(fontname: str, digit: str) -> float:
    """Height of the outline of ``digit`` in the font ``fontname`` (a PDF font name, ``ABCDEF+DejaVuSerif``) per
    unit of font size, from the font file matplotlib knows by that PostScript name."""
    from matplotlib import font_manager
    from matplotlib.ft2font import FT2Font, LoadFlags

    name = fontname.split("+", 1)[-1]
    for entry in font_manager.fontManager.ttflist:
        font = FT2Font(entry.fname)
        if font.postscript_name == name:
            font.set_size(1000, 72)  # 1000 px per em
            return font.load_char(ord(digit), LoadFlags.NO_HINTING).height / 64 / 1000
    raise LookupError(f"font {fontname} of a stored figure is not one matplotlib knows")


def digit_heights(pdf: Path) -> list[tuple[float, str, bool]]:
    """``[(height in px at REPORT_WIDTH_PX, text, is_script), ...]``: the smallest digit of every string with one.

    A string is a script when it is drawn smaller than the largest string of its text block (a mathtext
    super- or subscript).
    """
    width, device = _read(pdf)
    out = []
    for block, fonts in zip(device.blocks, device.fonts):
        if not block:
            continue
        top = max(s for s, _ in block)
        for (size, text), font in zip(block, fonts):
            digits = [c for c in text if c.isdigit() and c.isascii()]
            if digits:
                h = min(size * digit_height(font, c) for c in digits) * REPORT_WIDTH_PX / width
                out.append((h, text, size < top - 1e-9))
    return out


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
    width, device = _read(pdf)
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


def test_the_digit_measure_reads_glyphs_and_counts_exponents(tmp_path):
    from eqrec.studies.pipeline.outputs import save_figure
    from eqrec.studies.plotting import paper_style, pyplot

    paper_style()
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 3.0))
    ax.set_yscale("log")
    ax.set_ylim(1e-3, 10)
    ax.set_xlabel("step 12", fontsize=9)
    path = tmp_path / "f.pdf"
    save_figure(fig, path)
    found = digit_heights(path)
    width, _ = text_heights(path)
    label = [h for h, t, script in found if t.startswith("step")]
    em = 9.0 * REPORT_WIDTH_PX / width  # 9 pt on a page `width` points wide shown 800 px wide
    assert label and 0.70 * em < label[0] < 0.78 * em  # a lining digit is about three quarters of an em
    exponents = [h for h, t, script in found if script]
    assert exponents and max(exponents) < min(h for h, t, script in found if not script)


@pytest.mark.parametrize("pdf", FIGURES, ids=[str(p.relative_to(RESULTS)) for p in FIGURES])
def test_digits_are_at_least_9_px_and_exponents_7_px_at_report_width(pdf):
    small = sorted((round(h, 2), t, script) for h, t, script in digit_heights(pdf)
                   if h < (MIN_SCRIPT_DIGIT_PX if script else MIN_DIGIT_PX))
    assert not small, (f"{pdf.relative_to(RESULTS)}: digits under {MIN_DIGIT_PX:g} px (scripts {MIN_SCRIPT_DIGIT_PX:g} px)"
                       f" at {REPORT_WIDTH_PX} px width: {small[:6]}")
