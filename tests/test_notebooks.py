"""The notebooks: every one executes against the stored results (so it cannot rot), the workflow's executed
copies (results/notebooks/) are deterministic, current and show no timing, and a failing cell is named."""
import ast
import json
import re
from pathlib import Path
from types import SimpleNamespace

import jupytext
import nbformat
import pytest
from snakemake.iocontainers import Namedlist

from eqrec.studies.pipeline import harness
from eqrec.studies.pipeline import outputs
from eqrec.studies.notebooks import execute as nbstudy

#: The notebooks step, as its rule names it.
EXECUTE = "eqrec.studies.notebooks.execute:step_execute"
ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.py"))
EXECUTED = ROOT / "results" / "notebooks"

# what a timing or memory value would look like in a notebook's outputs (they live in results/timings/)
# a timing or memory field by name (outputs.TIMING_KEYS: results/ holds none of them, results/timings/ all)
TIMING = re.compile(r"\b(" + "|".join(sorted(outputs.TIMING_KEYS)) + r")\b")

SMALL = '''# %% [markdown]
# # A small notebook

# %%
import time

import matplotlib.pyplot as plt
import pandas as pd

for i in range(4):  # printed in several kernel messages
    print("line", i, flush=True)
    time.sleep(0.15)
pd.DataFrame({"a": [1, 2], "b": [0.5, 0.25]})

# %%
fig, ax = plt.subplots(figsize=(3, 2))
ax.plot([0, 1, 2], [1, 0, 2])
ax.set_title("deterministic")
plt.show()
fig.savefig("plot.svg")
'''


def _outputs_text(nb) -> str:
    parts = []
    for cell in nb.cells:
        for out in cell.get("outputs", []):
            parts.append(out.get("text", ""))
            data = out.get("data", {})
            parts += [data.get("text/plain", ""), data.get("text/html", ""), data.get("text/markdown", "")]
    return "\n".join(parts)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_executes(path):
    nb = nbstudy.execute(path, workdir=ROOT)  # raises NotebookError naming the cell if one fails
    assert nbformat.validate(nb) is None
    assert [c.id for c in nb.cells] == [f"cell-{i}" for i in range(len(nb.cells))]
    text = _outputs_text(nb)
    assert not TIMING.search(text), TIMING.search(text).group(0)  # no timing or memory value is shown
    assert str(ROOT) not in text


def _run(tmp_path, source: Path, tag: str):
    out = {"ipynb": tmp_path / tag / f"{source.stem}.ipynb", "html": tmp_path / tag / f"{source.stem}.html"}
    harness.run_step(EXECUTE, {}, inputs={"notebook": str(source), "results": []}, outputs=out)
    return out["ipynb"].read_bytes(), out["html"].read_bytes()


def test_execution_is_byte_identical_and_carries_no_run_metadata(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the step runs the notebook in the working directory (the repository root)
    src = tmp_path / "small.py"
    src.write_text(SMALL)
    ipynb1, html1 = _run(tmp_path, src, "first")
    svg1 = (tmp_path / "plot.svg").read_bytes()
    ipynb2, html2 = _run(tmp_path, src, "second")
    assert ipynb1 == ipynb2 and html1 == html2
    assert (tmp_path / "plot.svg").read_bytes() == svg1  # fixed SVG ids and no date (SOURCE_DATE_EPOCH)
    nb = json.loads(ipynb1)
    assert [c["id"] for c in nb["cells"]] == [f"cell-{i}" for i in range(len(nb["cells"]))]
    assert nb["metadata"] == {"kernelspec": nbstudy.KERNELSPEC, "language_info": nbstudy.LANGUAGE_INFO}
    text = ipynb1.decode()
    for word in ('"execution":', "iopub", "shell.execute", "jupytext", "kernel_id", "ExecuteTime", str(tmp_path)):
        assert word not in text, word
    streams = [o for o in nb["cells"][1]["outputs"] if o["output_type"] == "stream"]
    assert len(streams) == 1 and "".join(streams[0]["text"]).count("line") == 4  # merged into one output
    assert any("image/png" in o.get("data", {}) for o in nb["cells"][2]["outputs"])  # the figure is embedded
    assert b"data:image/png;base64," in html1 and b"<title>small</title>" in html1


def _smk(tmp_path, source: Path):
    out = {"ipynb": str(tmp_path / "out.ipynb"), "html": str(tmp_path / "out.html")}
    return SimpleNamespace(params=Namedlist(fromdict={"step": EXECUTE}),
                           input=Namedlist(fromdict={"notebook": str(source)}), output=Namedlist(fromdict=out),
                           wildcards=Namedlist(fromdict={"name": source.stem}),
                           log=Namedlist([str(tmp_path / "logs" / "nb.log")]))


def test_a_failing_cell_fails_the_step_naming_notebook_and_cell(tmp_path, capfd):
    src = tmp_path / "broken.py"
    src.write_text('# %%\nx = 1\n\n# %% [markdown]\n# text\n\n# %%\ny = x / 0\n')
    with pytest.raises(nbstudy.NotebookError) as exc:
        nbstudy.execute(src, workdir=tmp_path)
    msg = str(exc.value)
    assert str(src) in msg and "cell 2 ('y = x / 0')" in msg and "ZeroDivisionError" in msg
    with pytest.raises(SystemExit) as stop:
        harness.run_from_snakemake(_smk(tmp_path, src))
    assert stop.value.code == 1
    err = capfd.readouterr().err
    assert "[notebooks] step execute failed" in err and "broken.py, cell 2" in err and "ZeroDivisionError" in err
    assert not (tmp_path / "out.ipynb").exists() and not (tmp_path / "out.html").exists()


def _files_named(path: Path) -> set[str]:
    """Result files a notebook names: string literals that end like a result file."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            if re.fullmatch(r"[\w./{}-]+\.(json|csv|png|md|npz)", node.value):
                names.add(node.value)
        elif isinstance(node, ast.JoinedStr):  # f"{name}.png" in a loop over literal names
            text = "".join(v.value if isinstance(v, ast.Constant) else "{}" for v in node.values)
            if re.fullmatch(r"[\w./{}-]+\.(json|csv|png|md|npz)", text):
                names.add(text)
    return names


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_the_rule_declares_every_file_the_notebook_reads(path):
    declared = nbstudy.READS[path.stem]
    assert all((ROOT / f).exists() for f in declared), [f for f in declared if not (ROOT / f).exists()]
    for name in _files_named(path):
        pattern = re.escape(name).replace(r"\{\}", r"\w+")
        assert any(re.search(rf"(^|/){pattern}$", f) for f in declared), f"{path.name} reads {name}, not in READS"


def test_every_notebook_has_its_executed_copy_and_it_is_current():
    assert sorted(nbstudy.READS) == [p.stem for p in NOTEBOOKS]
    for path in NOTEBOOKS:
        ipynb, html = EXECUTED / f"{path.stem}.ipynb", EXECUTED / f"{path.stem}.html"
        assert ipynb.is_file() and html.is_file(), f"run `snakemake --cores 2 notebooks` ({path.name})"
        executed = nbformat.reads(ipynb.read_text(), as_version=4)
        source = jupytext.read(path)
        assert [c.source for c in executed.cells] == [c.source for c in source.cells], \
            f"{ipynb.name} is stale: run `snakemake --cores 2 notebooks`"
        assert not any(o.get("output_type") == "error" for c in executed.cells for o in c.get("outputs", []))
        text = _outputs_text(executed)
        assert not TIMING.search(text) and "/root/" not in text and "/home/" not in text and "/work/" not in text
