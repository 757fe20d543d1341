"""An answer for every size (issue 33 §2): the estimate before solving, the refusal past the documented size
unless --force, and the message naming a horizon that works for an unstable plant."""

import json
import re
from pathlib import Path

import eqrec
from eqrec.errors import InputError

import numpy as np
import pytest

from eqrec import cli
from eqrec.design import inputs
from eqrec.design.delay.design import delay_classes
from eqrec.design.inputs import _class_sizes, estimate_delay_design
from eqrec.errors import SolverFailure
from eqrec.systems.files import load_system

ROOT = Path(__file__).resolve().parents[1]
ACC = ROOT / "examples" / "acc_system.yaml"


@pytest.mark.parametrize("D,T", [(0, 5), (1, 3), (1, 30), (2, 33), (4, 9), (4, 41)])
def test_class_sizes_without_building_them(D, T):
    """The window rule extended from a short horizon gives exactly the classes' (time, |S|) of the full build."""
    depth, size, terminal = _class_sizes(D, T)
    built = delay_classes(max_delay=D, horizon=T).classes
    assert sorted(zip(depth.tolist(), size.tolist())) == sorted((c.depth, len(c.available)) for c in built)
    assert terminal.sum() == sum(c.depth == T for c in built)


def test_estimate_grows_and_flags_the_huge():
    system, _ = load_system(ROOT / "examples" / "two_mass.yaml")
    small = estimate_delay_design(system, 1, 100, mu1_free=True, workers=2)
    big = estimate_delay_design(system, 1, 1000, mu1_free=True, workers=2)
    assert small.classes == 200 and big.classes == 2000
    assert small.lp_rows == 4 * sum(range(1, 101)) + 4 * sum(range(0, 100))  # n rows per measurement per class
    assert small.seconds < big.seconds and small.memory < big.memory
    assert small.too_large(available_memory=16 * 2**30) is None
    huge = estimate_delay_design(system, 1, 100_000, mu1_free=True, workers=2)
    assert "GiB" in huge.too_large(available_memory=16 * 2**30)
    assert "min" in huge.too_large(available_memory=1e30)  # time, when memory is no limit
    assert "200000 classes" in huge.summary()


def test_cli_refuses_a_huge_horizon_at_once(capsys):
    rc = cli.main(["design", str(ROOT / "examples" / "two_mass.yaml"), "--method", "delay", "--max-delay", "1",
                   "--horizon", "100000", "--mu1", "free"])
    err = capsys.readouterr().err
    assert rc == cli.EXIT_INPUT
    assert "eqrec: estimate: 200000 classes" in err
    assert "'--horizon': refused: it needs about" in err and "pass --force" in err


def test_cli_force_runs_past_the_limit(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(inputs, "MAX_ESTIMATED_SECONDS", 0.0)  # every design is "too long"
    args = ["design", str(ACC), "--method", "delay", "--max-delay", "1", "--horizon", "6", "--mu1", "1",
            "--jobs", "1", "--out", str(tmp_path / "d.json")]
    assert cli.main(args) == cli.EXIT_INPUT and not (tmp_path / "d.json").exists()
    assert "refused: it would take about" in capsys.readouterr().err
    assert cli.main(args + ["--force"]) == 0
    assert json.loads((tmp_path / "d.json").read_text())["horizon"] == 6


def _unstable_system(tmp_path, rho=1.3):
    path = tmp_path / "unstable.yaml"
    path.write_text(f"A: [[{rho}, 0.1], [0, 0.5]]\nC: [[1, 0]]\nE: [[1], [0]]\neta_w: 0.1\neta_v: 0.1\n")
    return path


def test_unstable_plant_names_a_horizon_that_works(tmp_path, monkeypatch, capsys):
    """A failed long design of an unstable plant: the message says why and which horizon solves (bisection)."""
    tried = []

    def fake_design(args):
        tried.append(args.horizon)
        if args.horizon > 37:
            raise SolverFailure("the class LPs: solver highs stopped with status 'Unknown'")
        return {}

    monkeypatch.setattr(cli, "run_design", fake_design)
    rc = cli.main(["design", str(_unstable_system(tmp_path)), "--method", "delay", "--max-delay", "1",
                   "--horizon", "100", "--mu1", "free"])
    err = capsys.readouterr().err
    assert rc == cli.EXIT_SOLVER
    assert "the horizon 100 is too long for so unstable a plant: A has spectral radius 1.3" in err
    assert "--horizon 37 solves and 38 does not" in err
    assert tried[0] == 100  # the design itself; the search's designs run in child processes, printed:
    first = int(np.log(1e8) / np.log(1.3))  # the first guess: where ρ^T = 1e8
    assert err.index(f"eqrec: trying --horizon {first}: ") < err.index("eqrec: trying --horizon 37: solves")
    assert "searching for the longest horizon that solves: at most 8 designs and 120 s" in err


def test_the_horizon_search_is_bounded_in_time(tmp_path, monkeypatch, capsys):
    """A design of the search that never returns (a solver stuck on a numerically hopeless LP) is stopped when the
    search's time is up: the search ends with what it found."""
    import time

    def stuck_design(args):
        if args.horizon > 37:
            time.sleep(3600)  # in the search's child process: stopped
            raise SolverFailure("stopped")
        return {}

    def failing(args):
        raise SolverFailure("the class LPs: solver highs stopped with status 'Unknown'")

    monkeypatch.setattr(cli, "HORIZON_SEARCH_SECONDS", 4.0)
    monkeypatch.setattr(cli, "run_design", failing)
    monkeypatch.setattr(cli, "_probe_design", _probe_with(stuck_design))
    t0 = time.perf_counter()
    rc = cli.main(["design", str(_unstable_system(tmp_path)), "--method", "delay", "--max-delay", "1",
                   "--horizon", "100", "--mu1", "free"])
    spent = time.perf_counter() - t0
    err = capsys.readouterr().err
    assert rc == cli.EXIT_SOLVER and spent < 30
    assert "no answer within" in err and "at most 8 designs and 4 s" in err


def _probe_with(design):
    """cli._probe_design running ``design`` instead of run_design (in the child process, as the CLI does)."""
    original = cli._probe_design

    def probe(args, seconds):
        saved = cli.run_design
        cli.run_design = design
        try:
            return original(args, seconds)
        finally:
            cli.run_design = saved
    return probe


def test_stable_plant_gets_no_horizon_hint(tmp_path, monkeypatch, capsys):
    def fake_design(args):
        raise SolverFailure("stopped")

    monkeypatch.setattr(cli, "run_design", fake_design)
    rc = cli.main(["design", str(_unstable_system(tmp_path, rho=0.9)), "--method", "delay", "--max-delay", "1",
                   "--horizon", "100", "--mu1", "free"])
    assert rc == cli.EXIT_SOLVER and "too long" not in capsys.readouterr().err


@pytest.mark.parametrize("extra,field", [(["--method", "prefix", "--words", "101111,110111"], "--force"),
                                         (["--method", "delay", "--delays", "000000,100000"], "--force")])
def test_force_without_a_max_delay_language_is_refused(extra, field, capsys):
    assert cli.main(["design", str(ACC), *extra, "--force"]) == cli.EXIT_INPUT
    err = capsys.readouterr().err
    assert f"field '{field}'" in err and "--force applies to" in err


# --- issue 41, section 2: one size model for Python and the CLI ------------------------------------------------

def _refused_fast(call, field):
    import time

    t0 = time.perf_counter()
    with pytest.raises(InputError) as exc:
        call()
    assert exc.value.field == field and "refused" in str(exc.value), str(exc.value)
    assert time.perf_counter() - t0 < 5.0
    return str(exc.value)


def test_class_shape_counts_the_classes_of_every_language():
    from eqrec.bounds.data_classes import classes_of_full_language, full_language_class_count
    from eqrec.design.inputs import class_shape

    for T, D, m in ((1, 0, None), (7, 2, None), (12, 3, 1), (9, 1, 3), (30, 4, None), (40, 2, 2), (6, 2, 6)):
        shape = class_shape(D, T, m)
        assert shape.classes == pytest.approx(full_language_class_count(T, D, m), rel=1e-12)
        built = classes_of_full_language(T, D, m)
        assert shape.entries == pytest.approx(sum(len(c.available) for c in built.classes), rel=1e-12)
        from collections import Counter

        counted = Counter()
        for d, size, count in zip(shape.depth.tolist(), shape.size.tolist(), shape.count.tolist()):
            counted[(d, size)] += count
        exact = Counter((c.depth, len(c.available)) for c in built.classes)
        assert counted.keys() == exact.keys()  # the counts are floats (lgamma): equal to rounding
        assert all(counted[k] == pytest.approx(exact[k], rel=1e-12) for k in exact)


def test_huge_class_sets_and_languages_are_estimated_and_refused_at_once(capsys):
    from eqrec.design.delay.design import delay_classes, delay_language

    _refused_fast(lambda: delay_classes(max_delay=1, horizon=10**8), "horizon")  # 10^5: built in seconds (linear)
    _refused_fast(lambda: delay_classes(max_delay=2, horizon=10**6, max_lost=1), "horizon")
    message = _refused_fast(lambda: delay_language(max_delay=2, horizon=30, max_lost=1), "horizon")
    assert "force=True" in message and "delay_classes" in message
    _refused_fast(lambda: delay_language(max_delay=3, horizon=30), "horizon")
    assert capsys.readouterr().err.count("eqrec: estimate: ") == 4


def test_python_and_the_cli_give_the_same_estimate(tmp_path, capsys):
    from eqrec.design.delay.design import delay_classes, design_delay, design_delay_global

    system = eqrec.load_system(ROOT / "examples" / "two_mass.yaml")[0]
    classes = delay_classes(max_delay=4, horizon=800)
    capsys.readouterr()
    _refused_fast(lambda: design_delay_global(system, classes, n_jobs=2), "patterns")
    python = capsys.readouterr().err
    _refused_fast(lambda: design_delay(system, classes, 1.0, n_jobs=2), "patterns")
    capsys.readouterr()
    rc = cli.main(["design", str(ROOT / "examples" / "two_mass.yaml"), "--method", "delay", "--max-delay", "4",
                   "--horizon", "800", "--mu1", "free", "--jobs", "2"])
    command = capsys.readouterr().err
    assert rc == cli.EXIT_INPUT
    # the same classes, LP rows and time (the CLI adds the class set's construction to the memory)
    same = python.split("; about")[0].split("estimate: ")[1]
    assert same in command and "12766 classes" in same


def test_max_lost_goes_through_the_size_check(capsys):
    import time

    t0 = time.perf_counter()
    rc = cli.main(["design", str(ROOT / "examples" / "two_mass.yaml"), "--method", "delay", "--max-delay", "2",
                   "--horizon", "1000000", "--max-lost", "1"])
    err = capsys.readouterr().err
    assert rc == cli.EXIT_INPUT and time.perf_counter() - t0 < 5.0
    assert "eqrec: estimate: " in err and "--max-lost" in err and "--force" in err


@pytest.mark.parametrize("size, field", [(["--runs", "100000"], "--runs"), (["--periods", "10000"], "--periods")])
def test_compare_estimates_and_refuses_a_long_run(tmp_path, capsys, size, field):
    rc = cli.main(["compare", str(ROOT / "examples" / "batch_reactor.yaml"), "--loss", "0.1", "--max-delay", "2",
                   "--horizon", "5", *size, "--out", str(tmp_path / "cmp")])
    err = capsys.readouterr().err
    assert rc == cli.EXIT_INPUT and f"field '{field}': refused" in err and "--force" in err
    assert not (tmp_path / "cmp").exists()


# --- issue 41 §2: the horizon search on a real unstable plant (no fake design) ------------------------------------

def _cart_pole(Ts: float = 0.1):
    """The gallery's cart-pole (examples/gallery/plot_cart_pole.py) sampled at 100 ms: one unstable mode,
    spectral radius 1.59, so a design fails past about 50 steps (its error maps grow like 1.59^T)."""
    from scipy.linalg import expm

    M, m, length, g = 1.0, 0.1, 0.5, 9.81
    Ac = np.array([[0, 1, 0, 0], [0, 0, -m * g / M, 0], [0, 0, 0, 1], [0, 0, (M + m) * g / (M * length), 0]])
    Bc = np.array([[0], [1 / M], [0], [-1 / (M * length)]])
    big = expm(np.block([[Ac, Bc], [np.zeros((1, 5))]]) * Ts)
    return eqrec.AffineSystem(A=big[:4, :4], B=big[:4, 4:], C=[[1, 0, 0, 0], [0, 0, 1, 0]],
                              E=np.diag([0, Ts, 0, Ts]) + np.diag([Ts ** 2 / 2, 0, Ts ** 2 / 2], 1), eta_w=0.05,
                              eta_v=0.002, name="cart-pole")


def test_python_finds_the_longest_horizon_of_the_real_cart_pole(capsys):
    """The design at T = 80 fails (the solver cannot resolve 1.59^80) and says what to call; longest_horizon then
    answers with a horizon that solves (the first guess, log(1e8)/log(1.59) = 39) and one that does not."""
    import time

    plant = _cart_pole()
    with pytest.raises(SolverFailure) as exc:
        eqrec.design_delay_global(plant, delay_classes(max_delay=0, horizon=80), n_jobs=1)
    assert "too long for so unstable a plant" in str(exc.value) and "eqrec.longest_horizon(" in str(exc.value)
    t0 = time.perf_counter()
    found = eqrec.longest_horizon(plant, 0, 80, max_tries=2, budget=60)
    assert time.perf_counter() - t0 < 60
    assert [t[:2] for t in found.tries] == [(39, "solves"), (59, "fails")]
    assert found.longest == 39 and found.shortest_failing == 59 and not found.exact
    assert found.summary().startswith("horizon 39 solves (the longest found in 2 designs")
    assert found.summary().endswith("59 does not)") and found.tries[1][3]  # the failure's message is kept
    assert "too long for so unstable a plant" in found.reason
    err = capsys.readouterr().err
    assert "at most 2 designs and 60 s" in err and "trying horizon 39: solves" in err
    eqrec.design_delay_global(plant, delay_classes(max_delay=0, horizon=found.longest), n_jobs=1)  # it does solve


def test_the_cli_search_on_the_real_cart_pole_ends_within_its_budget(tmp_path, monkeypatch, capsys):
    """eqrec design at T = 80 fails; the search, given 5 s, ends with what it found in them (no fake design)."""
    import time

    plant = _cart_pole()
    path = tmp_path / "cart_pole.yaml"
    path.write_text("\n".join(f"{k}: {np.asarray(v).tolist()}" for k, v in
                              (("A", plant.A), ("B", plant.B), ("C", plant.C), ("E", plant.E))) +
                    "\neta_w: 0.05\neta_v: 0.002\n")
    monkeypatch.setattr(cli, "HORIZON_SEARCH_SECONDS", 5.0)
    t0 = time.perf_counter()
    rc = cli.main(["design", str(path), "--method", "delay", "--max-delay", "0", "--horizon", "80", "--mu1", "free",
                   "--jobs", "1"])
    spent = time.perf_counter() - t0
    err = capsys.readouterr().err
    assert rc == cli.EXIT_SOLVER, err
    assert "the horizon 80 is too long for so unstable a plant" in err
    assert "at most 8 designs and 5 s" in err and "eqrec: trying --horizon 39: " in err
    assert spent < 5.0 + 30.0  # the design itself, then at most the search's 5 s (and a child stopped)
    last = err.strip().splitlines()[-1]
    # the first guess 39 solves; an idle machine may bisect further up within the 5 s, a loaded one may time out
    found = re.search(r"--horizon (\d+) solves", last)
    assert (found and 39 <= int(found.group(1)) < 80) or "no horizon below" in last, last


def test_an_infeasible_verdict_past_what_an_lp_resolves_starts_the_search(tmp_path, monkeypatch, capsys):
    """The gallery cart-pole at (1, 1000) is "infeasible" (no gain makes the initial error contract along a class
    that has every measurement but one): a verdict on error maps grown by 1.097^1000 = 2e40, which a longer
    horizon cannot deserve.  Past RESOLVED_GROWTH an infeasible design gets the reason and the search; below it
    (a genuine infeasibility, e.g. mu1 too small) neither."""
    from eqrec.errors import InfeasibleDesign

    def infeasible_past_37(args):
        if args.horizon > 37:
            raise InfeasibleDesign("no recovery level is feasible: along the terminal class ...")
        return {}

    monkeypatch.setattr(cli, "run_design", infeasible_past_37)
    rc = cli.main(["design", str(_unstable_system(tmp_path)), "--method", "delay", "--max-delay", "1",
                   "--horizon", "100", "--mu1", "free"])
    err = capsys.readouterr().err
    assert rc == cli.EXIT_INFEASIBLE
    assert "this verdict may be the solver's, not the plant's: the horizon 100 is too long" in err
    assert "--horizon 37 solves and 38 does not" in err
    rc = cli.main(["design", str(_unstable_system(tmp_path)), "--method", "delay", "--max-delay", "1",
                   "--horizon", "60", "--mu1", "free"])  # 1.3^60 = 7e6: the LP resolves it, the verdict stands
    err = capsys.readouterr().err
    assert rc == cli.EXIT_INFEASIBLE and "searching" not in err and "too long" not in err


def test_python_says_why_on_the_real_cart_pole_past_the_resolved_growth():
    """At T = 54 (1.59^54 = 8e10) the cart-pole's design fails, as "infeasible" or as a solver failure depending on
    the LP's round-off; either way the message gives the reason and the call that finds a horizon that solves."""
    from eqrec.errors import InfeasibleDesign

    with pytest.raises((InfeasibleDesign, SolverFailure)) as exc:
        eqrec.design_delay_global(_cart_pole(), delay_classes(max_delay=0, horizon=54), n_jobs=1)
    assert "the horizon 54 is too long for so unstable a plant" in str(exc.value)
    assert "eqrec.longest_horizon(system, max_delay, 54)" in str(exc.value)

# --- issue 41 census: every size is estimated or refused at once, from Python as from the CLI --------------------

@pytest.mark.parametrize("call,field", [
    (lambda: eqrec.full_delay_language(30, 2), "T"),
    (lambda: eqrec.full_delay_language(60, 1), "T"),
    (lambda: eqrec.missing_words_at_most(60, 30), "T"),
    (lambda: eqrec.loss_coverage(2, 10**9, 0.1), "horizon"),
    (lambda: eqrec.delay_classes(max_delay=1, horizon=4, force="yes"), "force"),
], ids=["full-language-30-2", "full-language-60-1", "at-most-30-of-60", "coverage-1e9", "force-a-string"])
def test_huge_listings_and_string_flags_are_refused_at_once(call, field):
    import time

    start = time.perf_counter()
    with pytest.raises(InputError) as exc:
        call()
    assert exc.value.field == field and time.perf_counter() - start < 5.0


def test_listings_below_the_limit_still_run():
    assert len(eqrec.full_delay_language(5, 2)) == 243
    assert len(eqrec.missing_words_at_most(10, 3)) == 1 + 10 + 45 + 120
    assert eqrec.loss_coverage(2, 20, 0.1) == 6


def test_min_recovery_level_is_estimated_and_refused_past_the_limit(capsys):
    reactor = load_system(ROOT / "examples" / "batch_reactor.yaml")[0]
    classes = delay_classes(max_delay=4, horizon=800)
    with pytest.raises(InputError) as exc:
        eqrec.min_recovery_level(reactor, classes)
    assert exc.value.field == "classes" and "force=True" in str(exc.value)
    assert "estimate:" in capsys.readouterr().err
    with pytest.raises(InputError) as exc:
        eqrec.min_recovery_level(reactor, delay_classes(max_delay=1, horizon=3), force="no")
    assert exc.value.field == "force"


def test_memory_and_time_of_runs_are_checked_before_they_start():
    plant = eqrec.AffineSystem(A=[[1.0, 0.1], [0.0, 1.0]], C=[[1.0, 0.0]], E=0.1 * np.eye(2), eta_w=0.1, eta_v=0.05)
    design = eqrec.design_prefix(plant, ["1111", "1011"], 1.0)
    for runs, what in ((10**9, "memory"), (10**7, "s (one takes")):
        with pytest.raises(InputError) as exc:
            eqrec.monte_carlo(plant, design.schedule, ["1111", "1011"], 1.0, runs, 0)
        assert exc.value.field == "runs" and what in str(exc.value)
    assert eqrec.monte_carlo(plant, design.schedule, ["1111", "1011"], 1.0, 3, 0)[0].shape == (3, 5, 2)
    from eqrec.estimators.kalman import TimestampedKalman
    from eqrec.systems.noise import GaussianDesign
    with pytest.raises(InputError) as exc:
        eqrec.exact_bound(TimestampedKalman(plant, GaussianDesign.from_box(plant, 1.0)), plant, 0.5, steps=10**12)
    assert exc.value.field == "steps"


def test_the_cli_estimates_a_huge_horizon_without_listing_its_classes(capsys):
    """--max-delay 9 --horizon 1e9 listed every class before its estimate (minutes, gigabytes)."""
    import time

    start = time.perf_counter()
    assert cli.main(["design", str(ROOT / "examples" / "batch_reactor.yaml"), "--method", "delay", "--max-delay",
                     "9", "--horizon", str(10**9)]) == 1
    assert time.perf_counter() - start < 5.0
    err = capsys.readouterr().err
    assert "estimate:" in err and "--force" in err and "field '--horizon'" in err
    assert inputs.MAX_LISTED_HORIZON < 10**9
