"""The report in a real browser: `snakemake --report` opened in headless Chromium.

Checks that the report's single-page app renders (the workflow description is
visible, every category of results is listed), that every result item opens
and every image it shows is decoded by the browser (``naturalWidth > 0``), that
the images inside the executed notebooks load too, and that every
``data:image/png`` the report embeds (also inside the notebooks' HTML) is a
valid PNG (signature, chunk CRCs, zlib stream of the right size; a browser
shows a truncated PNG in part, with its full size, so only this check sees
it).  Screenshots
of the landing page, of one figure and of one notebook are written under the
test's temporary folder and copied to ``/tmp/eqrec-report-screenshots/``
(paths printed; ``pytest -s`` shows them).

Chromium is driven without any Python dependency: a copy of the report gets a
small script that clicks through the app (categories, then each item's
"eye" button) and writes what it saw into the DOM, which ``chromium --headless
--dump-dom`` prints; ``--screenshot`` takes the pictures.  Outside hosts
resolve to nothing, so the test needs no network.  Without Chromium (Debian
package ``chromium``; ``workflow/scripts/install_chromium.sh``) the test is
skipped.
"""
import base64
import html
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHOTS = Path("/tmp/eqrec-report-screenshots")
BROWSERS = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable", "chrome")
DESCRIPTION = "The replication pipeline of the equalized-recovery estimator papers"


def _chromium() -> str:
    exe = os.environ.get("EQREC_CHROMIUM") or next((shutil.which(b) for b in BROWSERS if shutil.which(b)), None)
    if not exe:
        pytest.skip("chromium not installed: apt-get install chromium (or run workflow/scripts/install_chromium.sh)"
                    "; EQREC_CHROMIUM=/path/to/chrome selects another build")
    return exe


def _browser(exe: str, profile: Path, page: Path, *args: str, budget_ms: int = 20000) -> str:
    cmd = [exe, "--headless", "--disable-gpu", "--hide-scrollbars", "--mute-audio", "--no-first-run",
           "--disable-dev-shm-usage", "--disable-extensions", f"--user-data-dir={profile}",
           "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE localhost",  # no network: CDN scripts fail at once
           "--window-size=1400,1000", f"--virtual-time-budget={budget_ms}", *args, page.as_uri()]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        cmd.insert(2, "--no-sandbox")  # Chromium's sandbox refuses to run as root
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=240)
    assert out.returncode == 0, f"{' '.join(cmd)}\n{out.stderr[-3000:]}"
    return out.stdout


# --------------------------------------------------------------------------- PNG check (no imaging library)

def _png_problem(data: bytes) -> str | None:
    """None if ``data`` is a complete, valid PNG (signature, CRCs, IHDR, zlib stream of the right size)."""
    if not data.startswith(b"\x89PNG\r\n\x1a\n"):
        return "no PNG signature"
    pos, idat, ihdr, end = 8, [], None, False
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length:pos + 12 + length] or b"\0\0\0\0")
        if len(body) != length or zlib.crc32(kind + body) != crc:
            return f"chunk {kind!r} truncated or with a bad CRC"
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat.append(body)
        elif kind == b"IEND":
            end = True
            break
        pos += 12 + length
    if ihdr is None or not idat or not end:
        return "IHDR, IDAT or IEND missing"
    width, height, depth, colour, _, _, interlace = ihdr
    if width == 0 or height == 0:
        return "empty image"
    try:
        raw = zlib.decompress(b"".join(idat))
    except zlib.error as exc:
        return f"image data does not inflate: {exc}"
    channels = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}[colour]
    if interlace == 0 and len(raw) != height * (1 + (width * channels * depth + 7) // 8):
        return f"image data of {len(raw)} bytes for {width}x{height}"
    return None


PNG_URI = re.compile(r"data:image/png;(?:[\w=.-]+;)*base64,([A-Za-z0-9+/=]+)")
HTML_URI = re.compile(r"data:text/html;(?:[\w=.-]+;)*base64,([A-Za-z0-9+/=]+)")


def _embedded_pngs(text: str, where: str):
    for i, m in enumerate(PNG_URI.finditer(text)):
        yield f"{where} image {i}", base64.b64decode(m.group(1))
    for i, m in enumerate(HTML_URI.finditer(text)):  # the notebooks: HTML items carrying their own images
        yield from _embedded_pngs(base64.b64decode(m.group(1)).decode("utf-8", "replace"), f"{where} html {i}")


def _js_var(text: str, name: str):
    """The JSON value of the report's ``var <name> = {...};`` (the app's data)."""
    m = re.search(rf"\bvar {name} = (?=\{{\")", text)
    assert m, f"no 'var {name}' in the report"
    return json.JSONDecoder().raw_decode(text, m.end())[0]


# --------------------------------------------------------------------------- the driver injected into the report

DRIVER = r"""
<script>
window.addEventListener('load', async () => {
  const PLAN = __PLAN__;
  const sleep = ms => new Promise(r => setTimeout(r, ms));
  const app = document.getElementById('app');
  const links = () => Array.from(app.querySelectorAll('a'));
  const link = t => links().find(a => a.textContent.trim() === t);
  const row = item => Array.from(app.querySelectorAll('tr')).find(r => {
    const td = r.querySelector('td'); return td && td.textContent.trim() === item; });
  const out = {landing: null, items: [], errors: [], done: false};
  const pre = document.createElement('pre');  // progress, read back from chromium --dump-dom
  pre.id = 'eqrec-check'; pre.style.display = 'none';
  document.body.appendChild(pre);
  const save = () => { pre.textContent = JSON.stringify(out); };
  // every iframe the app inserts gets a load listener before it can load (the notebooks are data: documents,
  // opaque to this page, so their load event is the only sign that they rendered)
  new MutationObserver(ms => ms.forEach(m => m.addedNodes.forEach(n => {
    const frames = n.tagName === 'IFRAME' ? [n] : (n.querySelectorAll ? Array.from(n.querySelectorAll('iframe')) : []);
    frames.forEach(f => f.addEventListener('load', () => { f.dataset.eqrecLoaded = '1'; }));
  }))).observe(app, {childList: true, subtree: true});
  async function waitFor(f, tries = 40) { for (let i = 0; i < tries; i++) { const v = f(); if (v) return v; await sleep(100); } return null; }
  async function home() {
    const h = app.querySelector('nav ol li a');
    if (h) h.click();
    await sleep(100);
    if (!link('Workflow')) { const r = link('Results'); if (r) r.click(); await sleep(100); }
  }
  async function open(entry) {
    await home();
    const cat = await waitFor(() => link(entry.category));
    if (!cat) { out.errors.push('no category link ' + entry.category); return false; }
    cat.click();
    let r = await waitFor(() => row(entry.item), 10);
    if (!r && link(entry.subcategory)) { link(entry.subcategory).click(); r = await waitFor(() => row(entry.item)); }
    if (!r) { out.errors.push('no row for ' + entry.item); return false; }
    const eye = r.querySelector('a[iconname=eye]') || r.querySelector('a');
    eye.click();
    return true;
  }
  async function shown(entry) {
    const want = 'filename=' + entry.item.split('/').pop();
    const img = await waitFor(() => Array.from(app.querySelectorAll('img')).find(i => i.src.includes(want)));
    const frame = img ? null : await waitFor(() => Array.from(app.querySelectorAll('iframe')).find(f => f.src.includes(want)), 20);
    const rec = {item: entry.item, img: null, iframe: !!frame, text: 0};
    if (img) {
      // an image that fails to decode fires 'error' and keeps naturalWidth 0
      const ok = !!(await waitFor(() => img.complete && img.naturalWidth > 0));
      rec.img = {decoded: ok, complete: img.complete, w: img.naturalWidth, h: img.naturalHeight};
    }
    if (frame) {
      const loaded = !!(await waitFor(() => frame.dataset.eqrecLoaded, 100));
      const b = frame.getBoundingClientRect();
      rec.frame = {loaded: loaded, w: b.width, h: b.height};
    }
    rec.text = app.innerText.length;
    return rec;
  }
  try {
    await waitFor(() => link('Workflow'));
    out.landing = {text: app.innerText, links: links().map(a => a.textContent.trim()).filter(t => t)};
    if (PLAN.mode === 'check') {
      for (const entry of PLAN.items) { if (await open(entry)) out.items.push(await shown(entry)); save(); }
      await home();
    } else if (PLAN.mode === 'show') {
      if (await open(PLAN.item)) out.items.push(await shown(PLAN.item));
      await sleep(1000);
    }
  } catch (e) { out.errors.push(String(e && e.stack || e)); }
  out.done = true;
  save();
});
</script>
"""

NOTEBOOK_CHECK = r"""
<script>
window.addEventListener('load', async () => {
  const imgs = Array.from(document.images);
  const res = [];
  for (const i of imgs) {  // after 'load' every image has loaded or failed (a failed one has naturalWidth 0)
    res.push({decoded: i.complete && i.naturalWidth > 0, w: i.naturalWidth, h: i.naturalHeight,
              png: i.src.startsWith('data:image/png')});
  }
  const pre = document.createElement('pre'); pre.id = 'eqrec-check'; pre.style.display = 'none';
  pre.textContent = JSON.stringify({images: res, text: document.body.innerText.length, title: document.title});
  document.body.appendChild(pre);
});
</script>
"""


def _with_script(page: str, script: str) -> str:
    i = page.rfind("</body>")
    return page[:i] + script + page[i:] if i >= 0 else page + script


def _result(dom: str) -> dict:
    m = re.search(r'<pre id="eqrec-check"[^>]*>(.*?)</pre>', dom, flags=re.S)
    assert m, "the page's check script did not finish (no #eqrec-check in the DOM): " + dom[-500:]
    return json.loads(html.unescape(m.group(1)))


def _keep(path: Path) -> Path:
    SHOTS.mkdir(parents=True, exist_ok=True)
    kept = SHOTS / path.name
    shutil.copyfile(path, kept)
    print(f"screenshot: {kept} (also {path})")
    return kept


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    exe = _chromium()  # skip before building anything
    tmp = tmp_path_factory.mktemp("report")
    out_file = tmp / "report.html"
    out = subprocess.run([sys.executable, "-m", "snakemake", "--report", str(out_file)], cwd=ROOT,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, (out.stdout + out.stderr)[-3000:]
    text = out_file.read_text(encoding="utf-8")
    return {"exe": exe, "tmp": tmp, "file": out_file, "text": text,
            "results": _js_var(text, "results"), "categories": _js_var(text, "categories")}


def _items(report) -> list[dict]:
    return [{"category": cat, "subcategory": sub, "item": item}
            for cat, subs in report["categories"].items() for sub, items in subs.items() for item in items]


def test_the_png_check_catches_broken_images():
    """A truncated PNG still shows (partly) in a browser with its full naturalWidth: hence the byte-level check."""
    good = (ROOT / "results" / "p1" / "fig1_trajectories.png").read_bytes()
    assert _png_problem(good) is None
    flipped = bytearray(good)
    flipped[len(good) // 2] ^= 0xFF
    for bad in (good[:5000], bytes(flipped), b"GIF89a" + good[6:], good[:-12]):
        assert _png_problem(bad) is not None


def test_every_png_the_report_embeds_is_valid(report):
    found = list(_embedded_pngs(report["text"], "report"))
    expected = [k for k, v in report["results"].items() if v["mime_type"] == "image/png"]
    assert len(expected) >= 10 and len(found) >= len(expected)
    assert any(" html " in where for where, _ in found), "no image inside the notebooks' HTML"
    bad = {where: p for where, data in found if (p := _png_problem(data))}
    assert not bad, bad


def test_the_app_renders_and_every_item_opens_with_its_images_loaded(report):
    items = _items(report)
    assert {"Notebooks", "P1", "P2", "P3", "P4", "Claims"} <= set(report["categories"])
    page = report["tmp"] / "check.html"
    page.write_text(_with_script(report["text"], DRIVER.replace("__PLAN__", json.dumps(
        {"mode": "check", "items": items}))), encoding="utf-8")
    res = _result(_browser(report["exe"], report["tmp"] / "profile-check", page, "--dump-dom", budget_ms=120000))
    assert res["done"] and not res["errors"], (res["errors"], [r["item"] for r in res["items"]])
    landing = " ".join(res["landing"]["text"].split())
    assert DESCRIPTION in landing  # the workflow description is visible
    assert {"Workflow", "Statistics", *report["categories"]} <= set(res["landing"]["links"])
    seen = {r["item"]: r for r in res["items"]}
    assert set(seen) == {e["item"] for e in items}, "items the app did not open"
    for entry in items:
        rec, mime = seen[entry["item"]], report["results"][entry["item"]]["mime_type"]
        if mime.startswith("image/"):
            assert rec["img"] and rec["img"]["decoded"] and rec["img"]["w"] > 0 and rec["img"]["h"] > 0, rec
        elif mime == "text/html":  # the notebooks, in an iframe
            assert rec["iframe"] and rec["frame"]["loaded"] and rec["frame"]["w"] > 100 and rec["frame"]["h"] > 100, rec
        assert rec["text"] > 0


@pytest.mark.parametrize("name", ["p1_prefix_based", "p2_augmented", "p3_delayed", "p4_lmv"])
def test_notebook_html_in_the_report_loads_its_images(report, name):
    item = f"results/notebooks/{name}.html"
    uri = report["results"][item]["data_uri"]
    page_html = base64.b64decode(uri.split("base64,", 1)[1]).decode("utf-8")
    page = report["tmp"] / f"{name}.html"
    page.write_text(_with_script(page_html, NOTEBOOK_CHECK), encoding="utf-8")
    res = _result(_browser(report["exe"], report["tmp"] / f"profile-{name}", page, "--dump-dom"))
    assert res["title"] == name and res["text"] > 500
    pngs = [i for i in res["images"] if i["png"]]
    assert pngs or name == "p2_augmented", "no figure in the notebook"  # P2's notebook has tables only
    bad = [i for i in res["images"] if not (i["decoded"] and i["w"] > 0 and i["h"] > 0)]
    assert not bad, bad


def _screenshot(report, name: str, plan: dict) -> Path:
    page = report["tmp"] / f"shot-{name}.html"
    page.write_text(_with_script(report["text"], DRIVER.replace("__PLAN__", json.dumps(plan))), encoding="utf-8")
    shot = report["tmp"] / f"report-{name}.png"
    res = _result(_browser(report["exe"], report["tmp"] / f"profile-shot-{name}", page, "--dump-dom",
                           f"--screenshot={shot}"))
    assert res["done"] and not res["errors"], res  # the view the screenshot shows was reached, and loaded:
    for rec in res["items"]:
        assert (rec["img"] or {}).get("decoded") or (rec.get("frame") or {}).get("loaded"), rec
    data = shot.read_bytes()
    assert _png_problem(data) is None
    raw = zlib.decompress(b"".join(
        data[m.end():m.end() + struct.unpack(">I", data[m.start() - 4:m.start()])[0]]
        for m in re.finditer(b"IDAT", data)))
    assert len(set(raw[::97])) > 8, f"{shot} looks blank"
    return _keep(shot)


def test_screenshots_of_the_landing_page_a_figure_and_a_notebook(report):
    shots = [
        _screenshot(report, "landing", {"mode": "landing"}),
        _screenshot(report, "figure", {"mode": "show", "item": {
            "category": "P1", "subcategory": "Other", "item": "results/p1/fig1_trajectories.png"}}),
        _screenshot(report, "notebook", {"mode": "show", "item": {
            "category": "Notebooks", "subcategory": "Other", "item": "results/notebooks/p1_prefix_based.html"}}),
    ]
    assert all(p.stat().st_size > 10_000 for p in shots)
