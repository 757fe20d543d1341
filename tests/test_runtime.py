"""The runnable estimator of a design (Design.estimator) and its python-control form."""
import numpy as np
import pytest

from eqrec.systems.affine import AffineSystem
from eqrec.design.delay.design import delay_language, design_delay, design_delay_global
from eqrec.design.prefix.design import design_prefix
from eqrec.errors import InputError
from eqrec.systems.examples import batch_reactor

LOSS_LANGUAGE = ["000", "300", "030", "003"]  # delay words: at most one of three packets lost (3 = beyond T)


@pytest.fixture(scope="module")
def plant():
    return AffineSystem(A=np.array([[1.0, 0.1], [0.0, 1.0]]), B=np.array([[0.005], [0.1]]),
                        C=np.array([[1.0, 0.0]]), E=0.1 * np.eye(2), eta_w=0.1, eta_v=0.05)


def run_loop(plant, design, rng, steps=300, vertex=False):
    """The README's loop: one lost packet at most per period, inputs, noise in the box; worst error / bound."""
    est = design.estimator().reset(np.zeros(2))
    draw = (lambda r: rng.choice([-r, r], 2)) if vertex else (lambda r: rng.uniform(-r, r, 2))
    x = draw(design.mu1)
    worst, lost = 0.0, 3
    for k in range(steps):
        if k % 3 == 0:
            lost = rng.integers(0, 4)
        u = np.array([np.sin(0.1 * k)])
        y = None if k % 3 == lost else plant.C @ x + rng.uniform(-0.05, 0.05, 1)
        xhat, bound = est.step(y, u)
        x = plant.A @ x + plant.B @ u + plant.E @ draw(0.1)
        worst = max(worst, float(np.abs(x - xhat).max() / bound))
    return worst


def test_readme_loop_stays_within_the_guarantee(plant):
    design = design_delay_global(plant, LOSS_LANGUAGE).design
    rng = np.random.default_rng(1)
    assert run_loop(plant, design, rng) <= 1 + 1e-9
    assert run_loop(plant, design, rng, vertex=True) <= 1 + 1e-9


def test_bounds_are_the_class_levels_and_mu1_at_period_ends(plant):
    design = design_delay(plant, LOSS_LANGUAGE, 1.5, cost="sum")
    est = design.estimator().reset(np.zeros(2))
    cert, classes = design.class_certificate, design.class_gains.classes
    _, b1 = est.step(np.zeros(1))
    assert b1 == pytest.approx(cert.levels[classes.index(1, (0,))])
    _, b2 = est.step(None)
    assert b2 == pytest.approx(cert.levels[classes.index(2, (0,))])
    _, b3 = est.step(np.zeros(1))
    assert b3 == pytest.approx(design.mu1) and b3 >= design.mu1 and est.time == 3  # plus the rounding allowance
    _, b4 = est.step(None)  # next period
    assert b4 == pytest.approx(cert.levels[classes.index(1, ())])


def test_same_estimates_as_the_node_gain_estimator(plant):
    """Class form (class gains) and the recursive form (node gains, tree engine) give the same x̂ on one run."""
    from eqrec.estimators.causal import RecoveryEstimator

    design = design_delay(plant, LOSS_LANGUAGE, 1.5, cost="sum")
    est = design.estimator(periodic=False).reset(np.ones(2))
    ref = RecoveryEstimator(plant, design.schedule).reset(np.ones(2))
    for y in (np.array([0.3]), None, np.array([-0.2])):
        np.testing.assert_allclose(est.step(y, np.array([0.5]))[0], ref.step(y, np.array([0.5]))[0],
                                   atol=1e-12)


def test_late_packets_and_tree_designs(acc):
    """Time-stamped packets (the delayed-data paper) and a node-gain design (P1, tree engine): bounds = levels."""
    d = design_delay(batch_reactor(), delay_language(max_delay=1, horizon=3), 0.8, cost="sum")
    est = d.estimator().reset(np.zeros(4))
    est.step(None)                        # y(0) late
    _, b = est.step([(0, np.zeros(2)), (1, np.zeros(2))])  # y(0) and y(1) arrive at time 1
    assert b == pytest.approx(d.class_certificate.levels[d.class_gains.classes.index(2, (0, 1))])
    p1 = design_prefix(acc, ["101111", "110111", "111011", "111101"], 1.0, engine="tree")
    est = p1.estimator().reset(np.zeros(3))
    for y in (np.zeros(2), None):
        _, b = est.step(y)
        assert b == pytest.approx(p1.mu2)


def test_bad_use_is_refused(plant):
    design = design_delay(plant, LOSS_LANGUAGE, 1.5)
    est = design.estimator()
    with pytest.raises(InputError, match="reset"):
        est.step(None)
    with pytest.raises(InputError, match="n = 2"):
        est.reset(np.zeros(3))
    est.reset(np.zeros(2))
    est.step(None)
    with pytest.raises(InputError, match="outside the design"):  # two losses in one period: not in the language
        est.step(None)


# --- python-control -----------------------------------------------------------------------------------------

control = pytest.importorskip("control")


def test_statespace_in_estimator_out_input_output_response(plant):
    from eqrec.interop.python_control import estimator_iosys, system_from_statespace

    ss = control.ss(plant.A, plant.B, plant.C, np.zeros((1, 1)), True)
    system = system_from_statespace(ss, eta_w=0.1, eta_v=0.05, E=0.1 * np.eye(2))
    np.testing.assert_array_equal(system.A, plant.A)
    design = design_delay_global(system, LOSS_LANGUAGE).design
    est_io = estimator_iosys(design)
    rng = np.random.default_rng(4)
    N = 30
    u = np.sin(0.1 * np.arange(N)).reshape(1, N)
    arrived = np.ones(N)
    arrived[[1, 5, 9, 14]] = 0  # one loss at most per period of 3
    x = np.zeros((2, N + 1))
    x[:, 0] = rng.uniform(-design.mu1, design.mu1, 2)
    y = np.zeros((1, N))
    for k in range(N):
        y[:, k] = plant.C @ x[:, k] + rng.uniform(-0.05, 0.05)
        x[:, k + 1] = plant.A @ x[:, k] + plant.B @ u[:, k] + plant.E @ rng.uniform(-0.1, 0.1, 2)
    resp = control.input_output_response(est_io, np.arange(N), np.vstack([u, y, arrived]),
                                         est_io.initial_state(np.zeros(2)))
    out = resp.outputs
    # the same run through design.estimator(): same estimates and bounds
    est = design.estimator().reset(np.zeros(2))
    for k in range(N - 1):
        xhat, bound = est.step(y[:, k] if arrived[k] else None, u[:, k])
        np.testing.assert_allclose(out[:2, k + 1], xhat, atol=1e-12)
        assert out[2, k + 1] == pytest.approx(bound)
        assert np.abs(x[:, k + 1] - xhat).max() <= bound * (1 + 1e-9)


def test_statespace_checks():
    from eqrec.interop.python_control import estimator_iosys, system_from_statespace

    with pytest.raises(InputError, match="continuous-time"):
        system_from_statespace(control.ss([[0.0]], [[1.0]], [[1.0]], [[0.0]]), eta_w=0.1, eta_v=0.1)
    with pytest.raises(InputError, match="D must be zero"):
        system_from_statespace(control.ss([[0.5]], [[1.0]], [[1.0]], [[1.0]], True), eta_w=0.1, eta_v=0.1)
    from eqrec.design.prefix.time_based import design_time_based
    from eqrec.systems.examples import acc_system

    with pytest.raises(InputError, match="class-engine design"):
        estimator_iosys(design_time_based(acc_system(), ["101111"], 1.0, engine="tree"))


def test_readme_loop_runs_as_written():
    """The README's ten-line loop, executed with a sensor that loses one packet in three."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "README.md").read_text()
    section = text.split("## Run it on your own system", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, flags=re.S).group(1)
    scope = {"read_sensor": lambda k: None if k % 3 == 1 else np.array([0.01 * k])}
    exec(compile(code, "README.md", "exec"), scope)
    assert np.isfinite(scope["xhat"]).all() and scope["bound"] > 0


def test_readme_from_python_block_runs_as_written():
    """The design guide's "From Python" lines (a P1 design and the (30, 4) full delay language), executed as written."""
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "guide" / "design.md").read_text()
    section = text.split("## From Python", 1)[1]
    code = re.search(r"```python\n(.*?)```", section, flags=re.S).group(1)
    scope: dict = {}
    exec(compile(code, "README.md", "exec"), scope)
    d, g = scope["d"], scope["g"]
    assert d.certificate.mu2 <= d.mu2 * (1 + 1e-6) and d.mu1 == 1.0
    assert g.mu1 >= g.mu1_min.lower and g.design.class_gains.K[0].ndim == 2
