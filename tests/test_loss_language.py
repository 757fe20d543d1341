"""The loss-aware language (delays 0..D and at most m lost per block, issue 32 §5): its window and counting rules
against brute-force enumeration, designs on it, estimation on traces in it, and the coverage rule for m."""
import itertools
import json
from math import comb

import numpy as np
import pytest

import eqrec
from eqrec.arrivals.draws import NEVER, ArrivalTrace, block_loss_probabilities, loss_coverage
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.bounds.data_classes import (classes_of_full_language, classes_of_tree, full_language_class_count,
                                       full_language_counts)
from eqrec.cli import main
from eqrec.design.delay.design import design_delay, design_delay_global
from eqrec.design.delay.languages import delay_classes, delay_language, delay_loss_words
from eqrec.design.inputs import missing_words_at_most
from eqrec.errors import InputError
from eqrec.systems.affine import AffineSystem
from eqrec.systems.examples import batch_reactor

KEY = lambda c: (c.key, c.terminal, c.inner, c.weight, c.nodes)  # noqa: E731
SMALL = [(T, D, m) for T in range(1, 7) for D in range(0, 4) for m in range(0, T + 1) if (D + 2) ** T <= 5000]


def brute_force(T: int, D: int, m: int) -> tuple[PrefixTree, int]:
    """Every word over {0..D, lost} with at most m lost, straight from the definition; the tree and the word count."""
    patterns, words = {}, 0
    for word in itertools.product([*range(D + 1), "lost"], repeat=T):
        if word.count("lost") > m:
            continue
        words += 1
        arrivals = tuple(None if c == "lost" or i + c >= T else i + c for i, c in enumerate(word))
        patterns.setdefault(arrivals, ArrivalPattern(arrivals))
    return PrefixTree(list(patterns.values())), words


# --- the window rule and the counting rule --------------------------------------------------------------------

@pytest.mark.parametrize("T,D,m", SMALL)
def test_window_rule_with_losses_equals_brute_force(T, D, m):
    tree, words = brute_force(T, D, m)
    rule = classes_of_full_language(T, D, m)
    assert [KEY(c) for c in rule] == [KEY(c) for c in classes_of_tree(tree)]  # classes, weights, nodes
    assert full_language_counts(T, D, m) == {"words": words, "sequences": len(tree.patterns), "nodes": len(tree)}
    assert (rule.words, rule.sequences, rule.nodes) == (words, len(tree.patterns), len(tree))
    assert len(rule) == full_language_class_count(T, D, m)
    assert set(delay_language(max_delay=D, horizon=T, max_lost=m)) == set(tree.patterns)
    assert len(delay_loss_words(T, D, m)) == words


@pytest.mark.parametrize("T,D", [(1, 0), (3, 1), (5, 2), (6, 3), (8, 2)])
def test_no_loss_is_the_full_delay_language(T, D):
    """max_lost=0 gives the classes of the language without losses (the same construction since issue 41)."""
    assert [KEY(c) for c in classes_of_full_language(T, D, 0)] == [KEY(c) for c in classes_of_full_language(T, D)]
    assert full_language_counts(T, D, 0) == full_language_counts(T, D)
    assert full_language_class_count(T, D) == len(classes_of_full_language(T, D))


def test_every_loss_allowed_gives_every_arrival_pattern():
    T, D = 5, 1
    rule = classes_of_full_language(T, D, T)
    assert rule.words == (D + 2) ** T
    # every S ⊆ {0..d-1} at every depth: the data at d-1 can be anything
    assert rule.per_depth() == [2 ** d for d in range(1, T + 1)]


def test_the_lossy_language_scales_to_4_100():
    classes = delay_classes(max_delay=4, horizon=100, max_lost=1)
    assert len(classes) == full_language_class_count(100, 4, 1) == 76062
    assert classes.words == 5 ** 100 + 100 * 5 ** 99
    for c in classes.classes[::97]:  # the rule: at most one old time (<= d-1-D) missing
        old_missing = set(range(max(0, c.depth - 4))) - set(c.available)
        assert len(old_missing) <= 1
    assert len(delay_classes(max_delay=4, horizon=100, max_lost=0)) == len(delay_classes(max_delay=4, horizon=100))


def test_missing_words_at_most_are_the_lossy_language_without_delay():
    words = missing_words_at_most(6, 2)
    assert len(words) == 1 + 6 + 15 and [p.label for p in words[:3]] == ["111111", "011111", "101111"]
    assert all(p.label.count("0") <= 2 for p in words) and len({p.label for p in words}) == len(words)
    tree = classes_of_tree(PrefixTree(list(words)))
    assert [KEY(c) for c in tree] == [KEY(c) for c in classes_of_full_language(6, 0, 2)]
    assert len(missing_words_at_most(4, 4)) == 16 and [p.label for p in missing_words_at_most(3, 0)] == ["111"]
    assert eqrec.missing_words_at_most is missing_words_at_most


@pytest.mark.parametrize("call,field", [
    (lambda: delay_classes(max_delay=2, horizon=5, max_lost=-1), "max_lost"),
    (lambda: delay_classes(max_delay=2, horizon=5, max_lost=6), "max_lost"),
    (lambda: delay_classes(max_delay=2, horizon=5, max_lost=1.0), "max_lost"),
    (lambda: delay_classes(max_delay=2, horizon=5, max_lost=True), "max_lost"),
    (lambda: classes_of_full_language(5, 2, 9), "max_lost"),
    (lambda: delay_language(["012"], max_lost=1), "max_lost"),
    (lambda: delay_language(max_delay=1, max_lost=1), "max_lost"),
    (lambda: missing_words_at_most(4, 5), "m"),
    (lambda: missing_words_at_most(0, 0), "T"),
])
def test_bad_loss_budgets_name_the_field(call, field):
    with pytest.raises(InputError) as err:
        call()
    assert err.value.field == field


# --- designs and estimation on the lossy language -------------------------------------------------------------

def test_class_engine_on_the_rule_equals_the_tree_lp_on_the_words():
    system, T, D, m = batch_reactor(), 4, 1, 1
    rule = delay_classes(max_delay=D, horizon=T, max_lost=m)
    words = delay_language(max_delay=D, horizon=T, max_lost=m)
    free = design_delay_global(system, rule)
    ref = design_delay_global(system, words, engine="tree")
    # μ1,min comes from the class LPs, here of classes built two ways (equal, see above); the LPs may see them
    # with other bookkeeping (a tree attached), hence the rounding-level tolerance
    assert free.mu1 == pytest.approx(ref.mu1, rel=1e-12)
    assert free.J == pytest.approx(ref.J, rel=1e-7)  # the weights of the sum cost (tree LP: one solver tolerance)
    mu1 = 1.2 * free.mu1
    assert design_delay(system, rule, mu1).J == pytest.approx(
        design_delay(system, words, mu1, engine="tree", certify=False).J, rel=1e-7)


@pytest.fixture(scope="module")
def plant():
    return AffineSystem(A=np.array([[1.0, 0.1], [0.0, 1.0]]), B=np.array([[0.005], [0.1]]),
                        C=np.array([[1.0, 0.0]]), E=0.1 * np.eye(2), eta_w=0.1, eta_v=0.05)


def one_loss_per_block(rng, T: int, D: int, blocks: int) -> ArrivalTrace:
    """Delays uniform on 0..D and exactly one measurement of each block lost."""
    delays = rng.integers(0, D + 1, T * blocks)
    delays[np.arange(blocks) * T + rng.integers(0, T, blocks)] = NEVER
    return ArrivalTrace(delays)


def test_a_trace_with_one_loss_per_block_runs_strictly_within_the_bounds(plant):
    T, D, blocks = 6, 2, 40
    design = design_delay_global(plant, delay_classes(max_delay=D, horizon=T, max_lost=1)).design
    rng = np.random.default_rng(11)
    ratios, steps = [], 0
    for _ in range(5):
        trace = one_loss_per_block(rng, T, D, blocks)
        assert trace.lost.reshape(blocks, T).sum(axis=1).tolist() == [1] * blocks
        est = design.estimator(strict=True)
        x = rng.uniform(-2, 2, 2)
        est.reset(x - rng.choice([-1.0, 1.0], 2) * design.mu1)  # initial error at a corner of the μ1 box
        ys = {}
        for t in range(T * blocks):
            ys[t] = plant.C @ x + rng.choice([-1.0, 1.0], 1) * plant.eta_v  # noise at the box corners
            u = np.array([np.sin(0.3 * t)])
            xhat, bound = est.step([(tau, ys[tau]) for tau in trace.arriving_at(t)], u)
            x = plant.A @ x + plant.B @ u + plant.E @ (rng.choice([-1.0, 1.0], 2) * plant.eta_w)
            err = float(np.abs(x - xhat).max())
            # corner noise attains some class levels exactly (e.g. 0.625 at a class without data), where the
            # simulated x and x̂ carry rounding of a few ulps: the criterion for played-back worst cases
            assert err <= bound * (1 + 1e-12)
            ratios.append(err / bound)
            steps += 1
    assert steps == 5 * T * blocks and max(ratios) > 0.99  # the runs did reach the bounds
    # the same kind of trace with two losses in a block leaves the language: strict refuses it
    est = design.estimator(strict=True).reset(np.zeros(2))
    est.step([])
    with pytest.raises(InputError):
        for t in range(1, T):
            est.step([])


# --- the coverage rule ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("T,loss", [(1, 0.3), (5, 0.1), (20, 0.25), (30, 0.05)])
def test_independent_losses_are_binomial(T, loss):
    law = block_loss_probabilities(T, loss)
    exact = [comb(T, j) * loss ** j * (1 - loss) ** (T - j) for j in range(T + 1)]
    np.testing.assert_allclose(law, exact, rtol=1e-12, atol=1e-300)  # two float evaluations of one formula
    for coverage in (0.5, 0.9, 0.99, 0.999):
        m = loss_coverage(2, T, loss, coverage)
        cdf = [sum(exact[:j + 1]) for j in range(T + 1)]
        assert cdf[m] >= coverage - 1e-12 and (m == 0 or cdf[m - 1] < coverage + 1e-12)


@pytest.mark.parametrize("loss,burst", [(0.2, None), (0.2, 3.0), (0.1, 5.0), (0.4, 1.5)])
def test_block_law_matches_monte_carlo_of_the_trace_model(loss, burst):
    """The law against the blocks of a long trace of the comparison's draw_trace (a fixed seed). Tolerance 0.02 on
    each P(at most j lost): about 4 standard deviations of a mean over 10,000 blocks (<= 0.005), with margin for the
    bursts' correlation between neighbouring blocks."""
    from eqrec.compare.families import CompareSetup, draw_trace

    T, periods = 8, 10_000
    setup = CompareSetup(loss=loss, max_delay=2, horizon=T, periods=periods, burst=burst, seed=0)
    trace = draw_trace(np.random.default_rng(5), setup)
    counts = trace.lost.reshape(periods, T).sum(axis=1)
    empirical = np.array([(counts <= j).mean() for j in range(T + 1)])
    law = block_loss_probabilities(T, loss, burst)
    assert law.sum() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(np.cumsum(law), empirical, atol=0.02)
    m = loss_coverage(2, T, loss, 0.95, burst)
    assert empirical[m] >= 0.95 - 0.02


def test_bursts_need_a_larger_budget_and_the_budget_grows_with_the_coverage():
    T = 20
    for burst in (None, 2.0, 6.0):
        budgets = [loss_coverage(3, T, 0.1, c, burst) for c in (0.1, 0.5, 0.9, 0.99, 0.999, 1.0)]
        assert budgets == sorted(budgets) and budgets[-1] == T
    assert loss_coverage(3, T, 0.1, 0.99, burst=6.0) > loss_coverage(3, T, 0.1, 0.99)
    assert loss_coverage(0, 12, 0.0) == 0 and loss_coverage(0, 12, 0.0, 1.0) == 0
    assert loss_coverage(2, 12, 1.0) == 12
    assert eqrec.loss_coverage is loss_coverage


@pytest.mark.parametrize("kwargs,field", [
    ({"coverage": 0.0}, "coverage"), ({"coverage": 1.5}, "coverage"), ({"coverage": "high"}, "coverage"),
    ({"loss": -0.1}, "loss"), ({"loss": 1.0, "burst": 3.0}, "loss"), ({"burst": 0.5}, "burst"),
    ({"loss": 0.9, "burst": 1.0}, "burst"), ({"max_delay": -1}, "max_delay"), ({"horizon": 0}, "horizon"),
])
def test_bad_coverage_inputs_name_the_field(kwargs, field):
    args = {"max_delay": 2, "horizon": 10, "loss": 0.1, **kwargs}
    with pytest.raises(InputError) as err:
        loss_coverage(**args)
    assert err.value.field == field


# --- command line ---------------------------------------------------------------------------------------------

REACTOR = "examples/batch_reactor.yaml"


def test_cli_max_lost_designs_the_lossy_language(tmp_path):
    from pathlib import Path
    system = str(Path(__file__).resolve().parents[1] / REACTOR)
    for D, listed in ((1, True), (2, False)):  # 96 sequences: node gains and words listed; 324: classes only
        out = tmp_path / f"d{D}.json"
        assert main(["design", system, "--method", "delay", "--max-delay", str(D), "--horizon", "5",
                     "--max-lost", "1", "--mu1", "free", "--out", str(out)]) == 0
        d = json.loads(out.read_text())
        assert d["max_lost"] == 1 and d["max_delay"] == D and d["horizon"] == 5
        counts = full_language_counts(5, D, 1)
        if listed:
            assert len(d["words"]) == counts["sequences"] and any("x" in w for w in d["words"])  # a loss as x
        else:
            assert d["words"] == counts["words"] == 648
        assert d["certified_terminal"] <= d["mu1"]
        ref = design_delay_global(batch_reactor(), delay_classes(max_delay=D, horizon=5, max_lost=1))
        # the same class LPs (words listed or not); the command may raise μ1 to the level its gains certify
        assert ref.mu1_min.lower <= d["mu1"] <= ref.mu1 * (1 + 1e-5)


@pytest.mark.parametrize("extra,code,text", [
    (["--max-delay", "2", "--horizon", "5", "--max-lost", "-1"], 1, "--max-lost"),
    (["--max-delay", "2", "--horizon", "5", "--max-lost", "6"], 1, "--max-lost"),
    (["--max-lost", "1", "--delays", "21210"], 1, "--max-lost"),
    (["--max-lost", "1"], 1, "--max-lost"),
    (["--max-delay", "2", "--horizon", "5", "--max-lost", "1.5"], 2, "--max-lost"),
])
def test_cli_bad_max_lost(extra, code, text, capsys):
    from pathlib import Path
    system = str(Path(__file__).resolve().parents[1] / REACTOR)
    if code == 2:
        with pytest.raises(SystemExit) as exc:
            main(["design", system, "--method", "delay", *extra])
        assert exc.value.code == 2
    else:
        assert main(["design", system, "--method", "delay", *extra]) == 1
    assert text in capsys.readouterr().err


def test_cli_max_lost_is_for_the_delay_method(capsys):
    from pathlib import Path
    system = str(Path(__file__).resolve().parents[1] / "examples" / "acc_system.yaml")
    assert main(["design", system, "--words", "101111,110111", "--max-lost", "1"]) == 1
    assert "--max-lost applies to --method delay only" in capsys.readouterr().err


def test_help_describes_max_lost(capsys):
    with pytest.raises(SystemExit):
        main(["design", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "--max-lost" in text and "at most m lost per block" in text and "is not a loss" in text
