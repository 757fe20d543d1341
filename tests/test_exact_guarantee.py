"""No tolerance on the guarantee side (issue 32 §4, issue 33 §1): every certified worst case <= its stored level.

At ``μ1`` just above ``μ1,min`` (and just below it, within the LP's tolerance, where the class engine raises ``μ1``
to the fixed point the gains certify) on four plants, for prefix designs (both engines) and delay designs (both
engines, and ``μ1`` free): the certificates recomputed from the gains are at most the stored levels exactly, and
the worst-case noise played back through the design's own estimator gives error/bound <= 1 + 1e-12 at every step
(the estimator's arithmetic differs from the certificate's by round-off, ~1e-15 relative: that is the only
tolerance, and it is on the played-back ratio, not on any stored level).
"""

import json
from pathlib import Path

import numpy as np
import pytest

import eqrec
from eqrec.arrivals.draws import ArrivalTrace
from eqrec.arrivals.words import as_language, worst_case_pattern
from eqrec.bounds.certify import certify_schedule, recovery_fixed_point
from eqrec.bounds.stacking import UncertaintyLayout
from eqrec.cli import main
from eqrec.design.classes.gains import certify_classes
from eqrec.design.result import node_level
from eqrec.errors import CertificationFailure
from eqrec.simulate.loop import closed_loop

ROOT = Path(__file__).resolve().parents[1]
TWO_MASS = ROOT / "examples" / "two_mass.yaml"
ONE_LOST = ["111111", "011111", "101111", "110111", "111011", "111101", "111110"]


def two_mass() -> eqrec.AffineSystem:
    """The user's plant of issue 33: two carts and a spring, only x1 measured (the example file if present)."""
    if TWO_MASS.exists():
        return eqrec.load_system(TWO_MASS)[0]
    import scipy.linalg as sl

    Ac = np.array([[0, 1, 0, 0], [-1, -0.02, 1, 0.02], [0, 0, 0, 1], [1, 0.02, -1, -0.02]], float)
    return eqrec.AffineSystem(A=sl.expm(0.1 * Ac), C=[[1.0, 0, 0, 0]], E=[[0, 0], [1, 0], [0, 0], [0, 1]],
                              eta_w=[0.01, 0.02], eta_v=0.05, name="two carts")


def random_plant() -> eqrec.AffineSystem:
    """A random stable plant with negative entries (n = 3, one output)."""
    rng = np.random.default_rng(7)
    A = rng.uniform(-1, 1, (3, 3))
    A *= 0.9 / np.abs(np.linalg.eigvals(A)).max()
    assert (A < 0).any()
    return eqrec.AffineSystem(A=A, C=rng.uniform(-1, 1, (1, 3)), E=np.eye(3), eta_w=0.05, eta_v=0.1, name="random")


PLANTS = {"acc": eqrec.acc_system, "reactor": eqrec.batch_reactor, "two_mass": two_mass, "random": random_plant}
#: Missing-data words (at most one lost in a block) and delay languages per plant (the reactor is unstable: T = 5).
PREFIX_WORDS = {"acc": ONE_LOST, "reactor": [w[:5] for w in ONE_LOST[:6]], "two_mass": ONE_LOST,
                "random": ONE_LOST}
DELAYS = {"acc": (6, 1), "reactor": (5, 1), "two_mass": (6, 1), "random": (5, 1)}


def assert_exact(design) -> None:
    """Every worst case recomputed from the gains at the design's ``mu1`` is <= its stored level: no tolerance."""
    mu1 = design.mu1
    if design.schedule is not None:
        cert = certify_schedule(design.system, design.schedule, list(design.patterns), mu1)
        for wc in cert.words.values():
            T = wc.pattern.T
            assert wc.bounds[T].max() <= mu1, (wc.word, wc.bounds[T].max() - mu1)
            for t in range(1, T):
                level = node_level(design, wc.pattern.prefix(t))
                assert wc.bounds[t].max() <= level, (wc.word, t, wc.bounds[t].max() - level)
        assert cert.mu2 <= design.mu2 and design.certificate.mu2 <= design.mu2
        assert design.certificate.terminal <= mu1
    if design.class_gains is not None:
        cc = certify_classes(design.system, design.class_gains, mu1)
        stored = design.class_certificate
        assert stored.mu1 == mu1 and np.array_equal(cc.bounds, stored.bounds)
        levels = np.asarray(design.class_levels)
        for i, cls in enumerate(cc.classes.classes):
            assert cc.levels[i] <= levels[i]
            if cls.terminal:
                assert cc.levels[i] <= mu1, (cls.label, cc.levels[i] - mu1)
            if cls.inner:
                assert cc.levels[i] <= design.mu2


def play_back(design) -> float:
    """Largest error/bound over every step when the worst vertex of each (word, time)'s worst row is played back.

    The design's own estimator (``design.estimator()``) runs in the loop; its bound at each step is compared with
    the true error (weighted norm for a weighted design).
    """
    system = design.system
    weights = np.ones(system.n) if design.state_weights is None else design.state_weights
    words = list(design.patterns)
    cert = certify_schedule(system, design.schedule, words, design.mu1)  # the node gains realise the class maps
    worst = 0.0
    for pat in words:
        T = pat.T
        lay = UncertaintyLayout(T, system.nw, system.nv, system.n)
        wc = cert.words[pat.label]
        for delta in [wc.worst_vertex(t, int(np.argmax(wc.bounds[t]))) for t in range(1, T + 1)]:
            w, v, xi0 = lay.split(delta)
            x0 = np.linspace(-1.0, 1.0, system.n)
            # the design is made on z = W x; the loop runs in x (the estimator takes and returns x)
            run = closed_loop(_plant(design), design.estimator(), ArrivalTrace.from_pattern(pat), x0 / weights,
                              xi0 / weights, w, v)
            err = np.abs(run.x - run.xhat) * weights
            bounds = np.asarray(run.spread, float)
            assert bounds.shape == (T,) and np.all(bounds > 0)
            worst = max(worst, float(np.max(err[1:].max(axis=1) / bounds)))
    return worst


def _plant(design) -> eqrec.AffineSystem:
    """The plant in the file's coordinates (a weighted design holds the system of ``z = W x``)."""
    if design.state_weights is None:
        return design.system
    return design.system.scaled(1.0 / design.state_weights)


@pytest.fixture(scope="module", params=sorted(PLANTS))
def plant(request):
    name = request.param
    system = PLANTS[name]()
    words = PREFIX_WORDS[name]
    mm = eqrec.min_recovery_level(system, words, kind="missing")
    return name, system, words, mm.upper


@pytest.mark.parametrize("engine", ["classes", "tree"])
def test_prefix_just_above_mu1_min_is_exact_and_played_back(plant, engine):
    name, system, words, mu1_min = plant
    design = eqrec.design_prefix(system, words, mu1_min * (1 + 1e-9), engine=engine)
    assert design.mu1 >= mu1_min * (1 + 1e-9)
    assert_exact(design)
    assert play_back(design) <= 1 + 1e-12


def test_prefix_just_below_mu1_min_raises_mu1_to_what_the_gains_certify(plant):
    """Within the LP's tolerance below μ1,min the class engine accepts, with μ1 raised to its certified fixed point."""
    name, system, words, mu1_min = plant
    asked = mu1_min * (1 - 3e-7)
    design = eqrec.design_prefix(system, words, asked)
    assert design.mu1 > asked and design.mu1_requested == asked
    assert design.mu1 <= mu1_min * (1 + 1e-6)
    assert_exact(design)
    assert play_back(design) <= 1 + 1e-12


def test_time_and_weighted_designs_are_exact(plant):
    name, system, words, mu1_min = plant
    language = words[2:4]  # two words: their worst case (bitwise AND) still recovers
    time_min = eqrec.min_recovery_level(system, [worst_case_pattern(as_language(language, kind="missing"))]).upper
    for engine in ("classes", "tree"):
        assert_exact(eqrec.design_time_based(system, language, time_min * (1 + 1e-9), engine=engine))
    weights = np.linspace(1.0, 2.0, system.n)
    weighted = eqrec.design_prefix(system, words, "free", state_weights=weights)
    assert_exact(weighted)
    assert play_back(weighted) <= 1 + 1e-12


@pytest.mark.parametrize("engine", ["classes", "tree"])
def test_delay_designs_just_above_mu1_min(plant, engine):
    name, system, _, _ = plant
    T, D = DELAYS[name]
    language = eqrec.delay_words(eqrec.full_delay_language(T, D))
    mu1_min = eqrec.min_recovery_level(system, language).upper
    for cost in ("sum", "max"):
        design = eqrec.design_delay(system, language, mu1_min * (1 + 1e-9), cost=cost, engine=engine,
                                    node_gains=True)
        assert_exact(design)
        assert play_back(design) <= 1 + 1e-12
    free = eqrec.design_delay_global(system, language, engine=engine, node_gains=True)
    assert free.mu1 == free.design.mu1 >= free.mu1_min.upper
    assert_exact(free.design)
    assert play_back(free.design) <= 1 + 1e-12


def test_augmented_design_is_exact(acc):
    design = eqrec.design_augmented(acc, ["101111", "110111"], mu1=1.0)
    assert design.certificate.mu2 <= design.mu2 and design.certificate.terminal <= design.mu1


@pytest.mark.parametrize("mu1", [1e9, 1e12])
def test_large_mu1_prefix_designs_certify(mu1):
    """Issue 33: --mu1 1e9 (and the documented limit 1e12) gave 'the gains give worst case ... > the LP's level'.

    The gap is the LP's round-off times μ1 on the ξ0 columns: the class levels are raised to the certified values,
    which stay close to the levels at a moderate μ1 (not nonsense: within 1 % on this plant).
    """
    system = two_mass()
    design = eqrec.design_prefix(system, ONE_LOST, mu1)
    assert design.mu1 == mu1
    assert_exact(design)
    moderate = eqrec.design_prefix(system, ONE_LOST, 1e3)
    term = [i for i, c in enumerate(design.class_gains.classes.classes) if c.terminal]
    ratio = design.class_certificate.levels[term] / moderate.class_certificate.levels[term]
    assert np.all(ratio >= 1 - 1e-6) and np.all(ratio <= 1.01)


def test_tree_engine_unbounded_at_huge_mu1_is_a_solver_failure():
    """The tree LP is bounded: HiGHS's 'unbounded' at μ1 = 1e12 is numerical trouble, reported as such (exit 4)."""
    try:
        design = eqrec.design_prefix(two_mass(), ONE_LOST, 1e12, engine="tree")
    except CertificationFailure:
        raise
    except eqrec.SolverFailure as exc:
        assert "class engine" in str(exc)
    else:  # another solver build may solve it: then it is exact
        assert_exact(design)


def test_recovery_fixed_point_is_exact_and_refuses_gains_that_do_not_contract():
    a, b = np.array([0.5, 0.9]), np.array([1.0, 0.1])

    def term(mu):
        return float(np.max(a * mu + b))

    mu = recovery_fixed_point(term, lambda: (a, b), 1.0)
    assert term(mu) <= mu and mu == pytest.approx(2.0, rel=1e-15)  # max(1/0.5, 0.1/0.1)
    assert recovery_fixed_point(term, lambda: (a, b), 3.0) == 3.0  # already certified: unchanged
    with pytest.raises(CertificationFailure, match="do not contract"):
        recovery_fixed_point(lambda mu: 1.1 * mu + 1.0, lambda: (np.array([1.1]), np.array([1.0])), 1.0)


def _cli(tmp_path, mu1, *extra):
    out = tmp_path / "design.json"
    rc = main(["design", str(TWO_MASS), "--method", "prefix", "--words", ",".join(ONE_LOST), "--mu1", mu1,
               "--out", str(out), *extra])
    return rc, (json.loads(out.read_text()) if out.exists() else None)


@pytest.mark.skipif(not TWO_MASS.exists(), reason="examples/two_mass.yaml not present")
@pytest.mark.parametrize("which", ["below", "1e9", "1e12"])
def test_cli_design_certified_at_most_stored(tmp_path, capsys, which):
    """The issue's command: `eqrec design two_mass.yaml --method prefix --words 111111,... --mu1 X` exits 0 with
    certified <= stored (X just below μ1,min, as 6.92731 was on the user's plant; and 1e9, 1e12)."""
    if which == "below":
        mu1_min = eqrec.min_recovery_level(two_mass(), ONE_LOST, kind="missing").upper
        mu1 = f"{mu1_min * (1 - 3e-7):.9g}"
    else:
        mu1 = which
    rc, js = _cli(tmp_path, mu1)
    assert rc == 0
    assert js["certified_terminal"] <= js["mu1"] and js["certified_mu2"] <= js["mu2"]
    if which == "below":
        assert js["mu1_requested"] == float(mu1) < js["mu1"]
        assert "mu1 raised from the requested" in capsys.readouterr().err
