"""The documentation site (docs/), built and checked like code.

* The site builds with ``sphinx-build -W --keep-going -n`` (every warning and every broken cross-reference fails),
  which also runs every gallery example (``examples/gallery/plot_*.py``: an example that raises stops the build).
* Every internal link and anchor of every page resolves; no page loads anything from the network.
* The API reference has a page for every name of ``eqrec.__all__``; the CLI reference has every command's help.
* In headless Chromium (the approach of ``test_report_browser.py``, whose helpers this reuses): the landing page,
  the ``ZonotopeEstimator`` API page and the cart-pole example render their maths (MathML laid out with a size)
  and their figures (decoded images).  Screenshots go to ``/tmp/eqrec-docs-screenshots/``.
* The README stays a README: at most 150 lines, the two commands, the command that builds the site.

The build takes about a minute on 2 cores (the gallery's examples run in it); it runs once per test session.
"""
from __future__ import annotations

import html
import os
import re
import shutil
import subprocess
import sys
import time
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

import eqrec

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
SHOTS = Path("/tmp/eqrec-docs-screenshots")
EXAMPLES = sorted(p.stem for p in (ROOT / "examples" / "gallery").glob("plot_*.py"))

pytestmark = pytest.mark.docs


class _Page(HTMLParser):
    """The links, ids and network resources of one HTML page."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.links: list[tuple[str, str]] = []  # (tag, url)
        self.ids: set[str] = set()
        self.remote: list[str] = []  # resources a browser would fetch from the network

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if a.get("id"):
            self.ids.add(a["id"])
        if tag == "a" and a.get("name"):
            self.ids.add(a["name"])
        for key in ("href", "src"):
            url = a.get(key)
            if not url:
                continue
            self.links.append((tag, url))
            fetched = tag in ("script", "img", "iframe") or (tag == "link" and "stylesheet" in (a.get("rel") or ""))
            if fetched and re.match(r"(https?:)?//", url):
                self.remote.append(f"<{tag} {key}={url}>")


def _parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8", errors="replace"))
    return page


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    out = tmp_path_factory.mktemp("docs")
    html_dir, doctrees = out / "html", out / "doctrees"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]),
           "MPLBACKEND": "Agg"}
    t0 = time.perf_counter()
    # the README's command for the site, into a temporary folder (-E: a fresh environment, every page read)
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-n", "-E", "-q", "-b", "html",
           "-d", str(doctrees), str(DOCS), str(html_dir)]
    run = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=env, timeout=1200)
    seconds = time.perf_counter() - t0
    assert run.returncode == 0, f"{' '.join(cmd)}\n{run.stdout[-3000:]}\n{run.stderr[-6000:]}"
    # the site's pages (not the theme's template fragments under _static/, not the copied notebooks)
    pages = sorted(p for p in html_dir.rglob("*.html")
                   if not {"notebooks", "_static"} & set(p.relative_to(html_dir).parts))
    print(f"docs: {len(pages)} pages built in {seconds:.0f} s")
    return {"dir": html_dir, "pages": pages, "seconds": seconds}


def test_the_site_builds_without_warnings_and_has_every_part(site):
    names = {p.relative_to(site["dir"]).as_posix() for p in site["pages"]}
    for page in ("index.html", "getting-started.html", "guide/index.html", "api.html", "cli.html",
                 "replication.html", "changelog.html", "auto_examples/index.html"):
        assert page in names, page
    for name in EXAMPLES:
        assert f"auto_examples/{name}.html" in names, name
    assert len(EXAMPLES) >= 5


def test_every_gallery_example_ran_and_drew_its_figure(site):
    for name in EXAMPLES:
        text = (site["dir"] / "auto_examples" / f"{name}.html").read_text(encoding="utf-8")
        assert "sphx-glr-script-out" in text, f"{name}: no printed output in its page"
        assert f"sphx_glr_{name}_001.png" in text, f"{name}: no figure in its page"
        assert (site["dir"] / "_images" / f"sphx_glr_{name}_001.png").stat().st_size > 5000


def test_every_internal_link_and_anchor_resolves(site):
    root = site["dir"]
    parsed = {p: _parse(p) for p in site["pages"]}
    broken = []
    checked = 0
    for page, info in parsed.items():
        for tag, url in info.links:
            parts = urlsplit(url)
            if parts.scheme or url.startswith("//") or url.startswith(("mailto:", "javascript:", "data:")):
                continue
            target = page if not parts.path else (page.parent / unquote(parts.path)).resolve()
            if target.is_dir():
                target = target / "index.html"
            if not target.exists():
                broken.append(f"{page.relative_to(root)}: <{tag}> {url} (no such file)")
                continue
            if root.resolve() not in target.resolve().parents and target.resolve() != root.resolve():
                broken.append(f"{page.relative_to(root)}: {url} leaves the site")
                continue
            checked += 1
            if parts.fragment and target.suffix == ".html":
                ids = parsed[target].ids if target in parsed else _parse(target).ids
                if unquote(parts.fragment) not in ids:
                    broken.append(f"{page.relative_to(root)}: {url} (no anchor #{parts.fragment})")
    assert checked > 500
    assert not broken, "\n".join(broken[:40])


def test_no_page_loads_anything_from_the_network(site):
    remote = {p.relative_to(site["dir"]).as_posix(): _parse(p).remote for p in site["pages"]}
    remote = {k: v for k, v in remote.items() if v}
    assert not remote, remote
    for page in site["pages"]:  # the maths is MathML, made at build time: no MathJax, no KaTeX
        scripts = re.findall(r"<script[^>]*>", page.read_text(encoding="utf-8"), flags=re.I)
        assert not [s for s in scripts if re.search(r"mathjax|katex", s, flags=re.I)], page


def test_the_api_reference_is_eqrec_all(site):
    api = (site["dir"] / "api.html").read_text(encoding="utf-8")
    for name in eqrec.__all__:
        if name == "__version__":
            continue
        page = site["dir"] / "generated" / f"eqrec.{name}.html"
        assert page.is_file(), name
        assert f"generated/eqrec.{name}.html" in api, name
    zono = (site["dir"] / "generated" / "eqrec.ZonotopeEstimator.html").read_text(encoding="utf-8")
    for method in ("reset", "step"):
        assert f'id="eqrec.ZonotopeEstimator.{method}"' in zono, method
    assert "<math" in zono


def test_the_cli_reference_is_the_commands_help(site):
    text = html.unescape(re.sub(r"<[^>]+>", "", (site["dir"] / "cli.html").read_text(encoding="utf-8")))
    for command in ("design", "compare"):
        out = subprocess.run([sys.executable, "-m", "eqrec", command, "--help"], capture_output=True, text=True,
                             env={**os.environ, "COLUMNS": "100"}, cwd=ROOT, timeout=120)
        assert out.returncode == 0
        first = next(line for line in out.stdout.splitlines() if line.strip())
        assert first.strip() in text, (command, first)


def test_the_replication_page_is_the_claims_file(site):
    text = (site["dir"] / "replication.html").read_text(encoding="utf-8")
    claims = (ROOT / "results" / "claims.csv").read_text(encoding="utf-8").splitlines()[1:]
    ids = [line.split(",")[0] for line in claims if line]
    assert len(ids) > 50
    missing = [i for i in ids if html.escape(i) not in text and i not in text]
    assert not missing, missing[:10]
    for name in ("p1_prefix_based", "p2_augmented", "p3_delayed", "p4_lmv", "compare"):
        assert (site["dir"] / "notebooks" / f"{name}.html").is_file()


# --------------------------------------------------------------------------- in a real browser

CHECK = r"""
<script>
window.addEventListener('load', () => {
  const maths = Array.from(document.querySelectorAll('math'));
  const res = {
    title: document.title,
    maths: maths.length,
    // MathML Core laid out: the element has a size, and the browser knows it as MathML (its own display type)
    maths_drawn: maths.filter(m => { const b = m.getBoundingClientRect(); return b.width > 0 && b.height > 0; }).length,
    math_display: maths.length ? getComputedStyle(maths[0]).display : null,
    // TeX left as text outside the code (a formula that did not become MathML)
    raw_tex: (() => { const c = document.body.cloneNode(true);
                      c.querySelectorAll('pre, code, .highlight, script, style').forEach(e => e.remove());
                      return /\\(frac|hat|mu|infty|left|right)\b|\$\$/.test(c.textContent); })(),
    images: Array.from(document.images).map(i => ({src: i.getAttribute('src'), ok: i.complete && i.naturalWidth > 0,
                                                   w: i.naturalWidth, h: i.naturalHeight})),
    styled: getComputedStyle(document.body).fontFamily,
    navbar: (h => !!h && h.getBoundingClientRect().height > 0)(document.querySelector('.bd-header')),
    text: document.body.innerText.length,
  };
  const pre = document.createElement('pre'); pre.id = 'eqrec-check'; pre.style.display = 'none';
  pre.textContent = JSON.stringify(res);
  document.body.appendChild(pre);
});
</script>
"""


def _browser_helpers():
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import test_report_browser as report  # noqa: PLC0415 (the report's browser helpers, one implementation)

    return report


@pytest.mark.parametrize("page, has_figure", [
    ("index.html", False),
    ("generated/eqrec.ZonotopeEstimator.html", False),
    ("auto_examples/plot_cart_pole.html", True),
])
def test_pages_render_maths_and_figures_in_chromium(site, page, has_figure):
    report = _browser_helpers()
    exe = report._chromium()  # skips without Chromium
    source = site["dir"] / page
    checked = source.with_name(f"check-{source.name}")  # beside the page: its relative links still load
    checked.write_text(report._with_script(source.read_text(encoding="utf-8"), CHECK), encoding="utf-8")
    profile = site["dir"].parent / f"profile-{source.stem}"
    res = report._result(report._browser(exe, profile, checked, "--dump-dom"))
    assert res["maths"] > 0 and res["maths_drawn"] == res["maths"], res
    assert res["math_display"] in ("inline math", "block math", "math"), res  # MathML, laid out by the browser
    assert not res["raw_tex"], "TeX source shown as text"
    assert res["navbar"] and res["text"] > 300, res  # the theme's layout loaded
    bad = [i for i in res["images"] if not i["ok"]]
    assert not bad, bad
    if has_figure:
        assert any("sphx_glr_plot_cart_pole" in (i["src"] or "") and i["w"] > 300 for i in res["images"]), res
    shot = site["dir"].parent / f"docs-{source.stem}.png"
    report._browser(exe, profile, source, f"--screenshot={shot}")
    assert report._png_problem(shot.read_bytes()) is None
    SHOTS.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(shot, SHOTS / shot.name)
    print(f"screenshot: {SHOTS / shot.name}")


# --------------------------------------------------------------------------- the README

def test_the_readme_is_short_and_names_the_commands():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    lines = readme.splitlines()
    assert len(lines) <= 150, len(lines)
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    test_command = next(line for line in lines[:12] if "pytest" in line).split("#")[0].strip()
    assert test_command in ci, "the README's test command is what .ci/run runs"
    assert "sphinx-build -W --keep-going -n docs docs/_build/html" in readme  # the one command for the site
    assert "requirements/pipeline.lock" in readme
    for page in ("getting-started", "guide/own-system", "replication", "api"):
        assert page in readme, page
