import numpy as np
import pytest

from eqrec.design.prefix.design import design_prefix
from eqrec.errors import InputError
from eqrec.estimators.causal import RecoveryEstimator
from eqrec.simulate.loop import simulate_run


def test_runtime_estimator_follows_the_closed_loop_map(acc, L1_words, rng):
    d = design_prefix(acc, L1_words, 1.0)
    wc = d.certificate.words["110111"]
    delta = rng.uniform(-1, 1, wc.radius.size) * wc.radius
    tr = simulate_run(acc, d.schedule, "110111", delta, np.array([20.0, 40, 20]), np.full((6, 1), 206.0))
    pred = np.einsum("tnd,d->tn", wc.G, delta) + wc.c
    np.testing.assert_allclose(tr.error, pred, atol=1e-10)


def test_prefix_outside_language_is_an_error(acc, L1_words):
    d = design_prefix(acc, L1_words, 1.0)
    # q(0) = 0: no word of L1 starts with 0
    with pytest.raises(InputError, match="not a prefix"):
        RecoveryEstimator(acc, d.schedule).reset(np.zeros(3)).step(None)


def test_wrong_measurement_size(acc, L1_words):
    d = design_prefix(acc, L1_words, 1.0)
    with pytest.raises(InputError, match="p = 2"):
        RecoveryEstimator(acc, d.schedule).reset(np.zeros(3)).step(np.zeros(3))


def test_periodic_reuse_stays_within_guarantees(acc, L1_words, rng):
    """Section V: repeating words of L1 with period T, the error stays below M2 and returns below M1."""
    d = design_prefix(acc, L1_words, 1.0)
    est = RecoveryEstimator(acc, d.schedule, periodic=True).reset(np.zeros(3))
    x = rng.uniform(-1, 1, 3)  # ξ(0) = x - 0 within M1 = 1
    worst, worst_end = 0.0, 0.0
    for period in range(40):
        w = L1_words[rng.integers(4)]
        for t in range(6):
            y = acc.C @ x + rng.uniform(-acc.eta_v, acc.eta_v, 2) if w[t] == "1" else None
            xhat, _ = est.step(y, np.zeros(1))
            x = acc.A @ x + acc.f + acc.E[:, 0] * rng.uniform(-acc.eta_w, acc.eta_w)
            worst = max(worst, np.abs(x - xhat).max())
        worst_end = max(worst_end, np.abs(x - xhat).max())
    assert worst <= d.mu2 + 1e-9
    assert worst_end <= 1.0 + 1e-9


def test_horizon_over_without_periodic(acc, L1_words):
    d = design_prefix(acc, L1_words, 1.0)
    est = RecoveryEstimator(acc, d.schedule).reset(np.zeros(3))
    for t in range(6):
        est.step(np.zeros(2) if L1_words[0][t] == "1" else None)
    with pytest.raises(InputError, match="horizon"):
        est.step(np.zeros(2))


def test_late_packet_uses_the_estimate_of_its_own_time(acc):
    """A late y(τ) enters as y(τ) - C x̂(τ); the certificate's maps assume exactly that."""
    from eqrec.bounds.certify import closed_loop_maps
    from eqrec.estimators.causal import Packet, RecoveryEstimator
    from eqrec.arrivals.words import parse_delay_word
    from eqrec.simulate.loop import simulate_run

    pats = [parse_delay_word(w) for w in ("0100", "0000", "2000")]
    d = design_prefix(acc, pats, 1.0)
    rng = np.random.default_rng(3)
    for pat in pats:
        G, c, lay = closed_loop_maps(acc, d.schedule, pat)
        delta = rng.uniform(-1, 1, lay.size) * lay.radius(acc.eta_w, acc.eta_v, 1.0)
        tr = simulate_run(acc, d.schedule, pat, delta, np.ones(acc.n))
        np.testing.assert_allclose(tr.error, np.einsum("tnd,d->tn", G, delta) + c, atol=1e-10)
    est = RecoveryEstimator(acc, d.schedule).reset(np.zeros(acc.n))
    with pytest.raises(InputError, match="future"):
        est.step([Packet(1, np.zeros(acc.p))])
    est = RecoveryEstimator(acc, d.schedule).reset(np.zeros(acc.n))
    est.step([Packet(0, np.zeros(acc.p))])
    with pytest.raises(InputError, match="second packet"):
        est.step([Packet(0, np.zeros(acc.p))])
