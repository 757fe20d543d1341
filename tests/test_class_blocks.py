"""The class LPs per class (eqrec.design.classes.blocks): same optimum as the one block LP, the same bytes whatever the
workers, the batching and the backend (local processes or a real Dask cluster), inputs checked, progress as one line per
stage off a terminal."""
import io
import re
import json

import numpy as np
import pytest

from eqrec.cli import main
from eqrec.lp import parallel
from eqrec.bounds.data_classes import classes_of_full_language, classes_of_tree
from eqrec.lp.parallel import Progress, check_jobs, check_scheduler, run_tasks
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.systems.affine import AffineSystem
from eqrec.design.classes import blocks as class_blocks
from eqrec.design.classes.blocks import choose_path, plan_batches
from eqrec.design.classes.engine import solve_classes
from eqrec.design.delay.design import delay_classes, design_delay, design_delay_global
from eqrec.design.classes.mu1_min import min_recovery_level
from eqrec.design.prefix.design import design_prefix
from eqrec.errors import InfeasibleDesign, InputError
from eqrec.systems.examples import batch_reactor

SIZE = (3, 8)  # (max delay, horizon): 54 classes, a few hundred LPs


@pytest.fixture(scope="module")
def reactor():
    return batch_reactor()


@pytest.fixture(scope="module")
def classes():
    return delay_classes(max_delay=SIZE[0], horizon=SIZE[1])


def _bytes(sol) -> bytes:
    """Everything a class solution holds, as bytes: levels, certificate and gains."""
    return b"".join([sol.lp_levels.tobytes(), sol.certificate.bounds.tobytes(), *(k.tobytes() for k in sol.gains.K)])


def _free_bytes(res) -> bytes:
    d = res.design
    return b"".join([np.float64([res.mu1, res.J, res.lower_bound, d.mu2]).tobytes(), _bytes_of_design(d)])


def _bytes_of_design(d) -> bytes:
    return b"".join([d.class_certificate.bounds.tobytes(), *(k.tobytes() for k in d.class_gains.K),
                     np.asarray(d.class_levels).tobytes()])


@pytest.fixture(scope="module")
def local(reactor, classes):
    """The per-class solves in this process, one batch per class (the reference bytes)."""
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(class_blocks, "MIN_BATCH_WORK", 0)
        mp.setattr(class_blocks, "BATCHES_PER_WORKER", 10_000)
        return {"level": solve_classes(reactor, classes, 0.5, path="blocks", n_jobs=1),
                "mu1": min_recovery_level(reactor, classes, path="blocks", n_jobs=1)}


def test_blocks_give_the_block_lp_optimum(reactor, classes, local):
    mono = solve_classes(reactor, classes, 0.5, path="monolithic")
    blocks = local["level"]
    np.testing.assert_allclose(blocks.lp_levels, mono.lp_levels, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(blocks.certificate.bounds, blocks.lp_levels, rtol=1e-9, atol=1e-12)
    assert blocks.model_shape == mono.model_shape and blocks.nonzeros == mono.nonzeros
    assert blocks.solution.status == "optimal" and blocks.solution.x is None
    mm = min_recovery_level(reactor, classes, path="monolithic")
    assert local["mu1"].upper == pytest.approx(mm.upper, rel=1e-9)
    assert local["mu1"].lower < local["mu1"].upper and local["mu1"].binding["time"] == SIZE[1]
    np.testing.assert_allclose(np.sort(local["mu1"].ratios), np.sort(mm.ratios), rtol=1e-9)


@pytest.mark.parametrize("n_jobs, min_batch", [(1, 10**9), (2, 0), (2, 10**9), (3, 50_000)])
def test_same_bytes_whatever_the_workers_and_batches(reactor, classes, local, monkeypatch, n_jobs, min_batch):
    monkeypatch.setattr(class_blocks, "MIN_BATCH_WORK", min_batch)
    monkeypatch.setattr(class_blocks, "POOL_MIN_WORK", 0)
    sol = solve_classes(reactor, classes, 0.5, path="blocks", n_jobs=n_jobs)
    assert _bytes(sol) == _bytes(local["level"])
    mm = min_recovery_level(reactor, classes, path="blocks", n_jobs=n_jobs)
    assert (mm.upper, mm.lower, mm.binding) == (local["mu1"].upper, local["mu1"].lower, local["mu1"].binding)
    assert mm.ratios.tobytes() == local["mu1"].ratios.tobytes()
    assert all(np.array_equal(a, b) for a, b in zip(mm.gains.K, local["mu1"].gains.K))


def test_dask_local_cluster_gives_the_local_bytes(reactor, classes, local, monkeypatch):
    """A real LocalCluster with two worker processes, through a Client and through its tcp:// address."""
    distributed = pytest.importorskip("distributed")
    monkeypatch.setattr(class_blocks, "MIN_BATCH_WORK", 50_000)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as lc, \
            distributed.Client(lc) as client:
        by_client = solve_classes(reactor, classes, 0.5, path="blocks", scheduler=client)
        by_address = solve_classes(reactor, classes, 0.5, path="blocks", scheduler=lc.scheduler_address)
        mm = min_recovery_level(reactor, classes, path="blocks", scheduler=client)
        monkeypatch.setattr(class_blocks, "MONOLITHIC_MAX_WORK", 0)  # the whole design per class
        on_dask = design_delay_global(reactor, classes, scheduler=lc.scheduler_address)
        assert len(client.scheduler_info()["workers"]) == 2
    assert _bytes(by_client) == _bytes(local["level"]) == _bytes(by_address)
    assert mm.ratios.tobytes() == local["mu1"].ratios.tobytes() and mm.upper == local["mu1"].upper
    here = design_delay_global(reactor, classes, n_jobs=2)
    assert _free_bytes(on_dask) == _free_bytes(here)


def test_auto_path_by_size(reactor):
    small = classes_of_full_language(5, 2)
    assert choose_path("auto", small, None, reactor) == "monolithic"
    assert choose_path("auto", classes_of_full_language(20, 4), None, reactor) == "blocks"
    assert choose_path("monolithic", classes_of_full_language(20, 4), None, reactor) == "monolithic"
    assert choose_path("blocks", small, None, reactor) == "blocks"
    with pytest.raises(InputError) as exc:
        choose_path("fast", small, None, reactor)
    assert exc.value.field == "path"


def test_large_design_per_class_matches_the_block_lp(reactor, monkeypatch):
    """design_delay_global through every entry point: per class (forced) and as one block LP agree within 1e-9."""
    classes = classes_of_full_language(8, 3)
    mono = design_delay_global(reactor, classes)
    monkeypatch.setattr(class_blocks, "MONOLITHIC_MAX_WORK", 0)
    blocks = design_delay_global(reactor, classes, n_jobs=1)
    for a, b in ((mono.mu1, blocks.mu1), (mono.J, blocks.J), (mono.mu2, blocks.mu2),
                 (mono.lower_bound, blocks.lower_bound)):
        assert b == pytest.approx(a, rel=1e-9)
    np.testing.assert_allclose(blocks.design.class_levels, mono.design.class_levels, rtol=1e-9)
    fixed = design_delay(reactor, classes, 0.5, n_jobs=1)
    assert fixed.J == pytest.approx(design_delay(reactor, classes, 0.5, n_jobs=2).J, rel=0)
    words = ["101111", "110111", "111011", "111101"]
    from eqrec.systems.examples import acc_system

    assert design_prefix(acc_system(), words, 1.0, n_jobs=1).mu2 == pytest.approx(
        design_prefix(acc_system(), words, 1.0, engine="tree").mu2, rel=1e-9)


def test_no_recovery_level_per_class_names_the_class():
    unstable = AffineSystem(A=np.array([[2.0]]), C=np.array([[1.0]]), E=np.zeros((1, 0)), eta_w=0.0, eta_v=0.1)
    with pytest.raises(InfeasibleDesign, match="terminal class 3:"):
        min_recovery_level(unstable, classes_of_tree(PrefixTree(["000"], kind="missing")), path="blocks", n_jobs=1)


@pytest.mark.parametrize("bad", [0, -2, 1.5, "2", True])
def test_n_jobs_checked(reactor, classes, bad):
    for call in (lambda: solve_classes(reactor, classes, 0.5, n_jobs=bad),
                 lambda: min_recovery_level(reactor, classes, n_jobs=bad),
                 lambda: design_delay_global(reactor, classes, n_jobs=bad)):
        with pytest.raises(InputError) as exc:
            call()
        assert exc.value.field == "n_jobs"
    assert check_jobs(None) == check_jobs(-1) >= 1 and check_jobs(3) == 3


@pytest.mark.parametrize("bad", ["localhost:8786", "tcp://", 8786, object()])
def test_scheduler_checked(reactor, classes, bad):
    for call in (lambda: solve_classes(reactor, classes, 0.5, scheduler=bad),
                 lambda: design_delay(reactor, classes, 0.5, scheduler=bad),
                 lambda: design_delay_global(reactor, classes, scheduler=bad)):
        with pytest.raises(InputError) as exc:
            call()
        assert exc.value.field == "scheduler"
    assert check_scheduler(None) is None and check_scheduler(" tcp://10.0.0.1:8786 ") == "tcp://10.0.0.1:8786"


def test_unreachable_scheduler_is_an_input_error(reactor, classes, monkeypatch):
    monkeypatch.setattr(parallel, "CONNECT_TIMEOUT", 2.0)
    with pytest.raises(InputError, match="cannot reach the Dask scheduler") as exc:
        solve_classes(reactor, classes, 0.5, path="blocks", scheduler="tcp://127.0.0.1:9")
    assert exc.value.field == "scheduler"


def test_batches_cover_every_class_in_runs(reactor):
    weights = [4 * class_blocks.class_work(c, reactor) for c in classes_of_full_language(30, 4)]
    for workers in (1, 2, 7):
        runs = plan_batches(weights, workers)
        assert sorted(i for run in runs for i in run) == list(range(len(weights)))
        assert all(run == list(range(run[0], run[-1] + 1)) for run in runs)
        loads = [sum(weights[i] for i in run) for run in runs]
        assert loads == sorted(loads, reverse=True)
    assert len(plan_batches(weights, 2)) > 1


def _square(x):
    return x * x


def test_run_tasks_keeps_task_order_and_counts_progress():
    buf = io.StringIO()
    progress = Progress(10, "items", enabled=True)
    progress_stream = parallel.sys.stderr
    parallel.sys.stderr = buf
    try:
        out = run_tasks(_square, [(i,) for i in range(5)], n_jobs=2, progress=progress, units=[2] * 5)
    finally:
        parallel.sys.stderr = progress_stream
    assert out == [0, 1, 4, 9, 16]
    assert re.search(r"\ritems: 10 / 10 \[#{24}\] 100% \(\d+ s\)\n$", buf.getvalue())


def test_progress_one_line_per_stage_off_a_terminal(capsys):
    progress = Progress(3, "classes")  # pytest's stderr is not a terminal: a line at the start and one at the end
    progress.advance(2)
    assert capsys.readouterr().err == "classes: 0 / 3 ...\n"
    progress.advance(1)
    assert re.fullmatch(r"classes: 3 / 3 in \d+\.\d s\n", capsys.readouterr().err)
    Progress(3, "classes", enabled=False).advance(3)
    assert capsys.readouterr().err == ""


def test_cli_jobs_and_scheduler(tmp_path, capsys):
    system = "examples/batch_reactor.yaml"
    base = ["design", system, "--method", "delay", "--max-delay", "2", "--horizon", "5", "--mu1", "free"]
    outs = []
    for extra in (["--jobs", "1"], ["--jobs", "2"]):
        out = tmp_path / f"d{len(outs)}.json"
        assert main(base + extra + ["--out", str(out)]) == 0
        outs.append(json.loads(out.read_text()))
    for d in outs:
        d.get("mu1_free", {}).pop("time", None)
        d.pop("time", None)
    assert outs[0]["mu1"] == outs[1]["mu1"] and outs[0]["mu2"] == outs[1]["mu2"]
    capsys.readouterr()
    assert main(base + ["--jobs", "0"]) == 1
    assert "field '--jobs'" in capsys.readouterr().err
    assert main(base + ["--scheduler", "localhost"]) == 1
    assert "field '--scheduler'" in capsys.readouterr().err
    assert main(["design", system, "--words", "11111", "--method", "time", "--jobs", "2"]) == 1
    assert "--jobs applies to --method prefix and delay" in capsys.readouterr().err


def test_scale_free_step_writes_values_timings_and_figure(tmp_path, monkeypatch):
    """The p3_scale target's mu1-free scaling: values in results, times and memory in the timings, and the figure
    drawn from those two by its own step."""
    from types import SimpleNamespace

    import eqrec.studies.p3.free_table as free

    monkeypatch.setattr(free, "FREE_SIZES", [(2, 5)])
    out = SimpleNamespace(**{k: str(tmp_path / f"{k}.{ext}") for k, ext in (
        ("csv", "csv"), ("timings_csv", "csv"), ("timings_md", "md"), ("pdf", "pdf"), ("png", "png"))})
    free.step_scale_free({"scale": {"time_limit": 600}}, None, out, None)
    values = (tmp_path / "csv.csv").read_text().splitlines()
    assert values[0] == "tau,T,classes,config,status,mu1,J,mu2,lower_bound" and len(values) == 4
    assert len({line.split(",", 4)[-1] for line in values[1:]}) == 1  # the same values for every configuration
    assert (tmp_path / "timings_csv.csv").read_text().startswith("tau,T,config,wall_time,peak_mb")
    assert "| 2 | 5 | 18 | blocks-2 |" in (tmp_path / "timings_md.md").read_text()
    from eqrec.studies.p3.figures import step_scale_free_figure

    step_scale_free_figure({}, SimpleNamespace(csv=out.csv, timings=out.timings_csv), out, None)
    assert (tmp_path / "png.png").stat().st_size > 0 and (tmp_path / "pdf.pdf").stat().st_size > 0


def test_workers_started_ahead_give_the_same_bytes_and_are_settled(reactor, classes, monkeypatch):
    import warnings

    monkeypatch.setattr(class_blocks, "MONOLITHIC_MAX_WORK", 0)
    monkeypatch.setattr(class_blocks, "POOL_MIN_WORK", 0)
    one = design_delay_global(reactor, classes, n_jobs=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # joblib warns about warm-up tasks nobody waited for
        assert class_blocks.prestart_workers(reactor, classes, n_jobs=2)
        parallel.settle()
        two = design_delay_global(reactor, classes, n_jobs=2)
    assert not parallel._WARMING
    assert _free_bytes(one) == _free_bytes(two)
