import numpy as np
import pytest

from eqrec.bounds.certify import certify_design, certify_schedule
from eqrec.design.prefix.design import design_prefix
from eqrec.errors import CertificationFailure
from eqrec.simulate.loop import sample_uncertainty, simulate_run


def test_bounds_are_attained_and_never_exceeded(acc, L1_words, rng):
    d = design_prefix(acc, L1_words, 1.0)
    cert = d.certificate
    x0 = np.array([20.0, 40.0, 20.0])
    u = np.full((6, 1), 206.0)
    for w in L1_words:
        wc = cert.words[w]
        for t, i in [(2, 0), (3, 1), (6, 2)]:
            tr = simulate_run(acc, d.schedule, w, wc.worst_vertex(t, i), x0, u)
            assert abs(tr.error[t, i]) == pytest.approx(wc.bounds[t, i], abs=1e-9)
        for _ in range(20):
            delta = sample_uncertainty(wc_layout(acc), wc.radius, rng, "vertex")
            tr = simulate_run(acc, d.schedule, w, delta, x0, u)
            assert np.all(np.abs(tr.error) <= wc.bounds + 1e-9)


def wc_layout(acc):
    from eqrec.bounds.stacking import UncertaintyLayout

    return UncertaintyLayout(6, acc.nw, acc.nv, acc.n)


def test_perturbed_gains_fail_certification(acc, L1_words):
    d = design_prefix(acc, L1_words, 1.0)
    d.schedule.row("1").F[:] += 0.5
    with pytest.raises(CertificationFailure):
        certify_design(d)


def test_certificate_json(acc, L1_words):
    d = design_prefix(acc, L1_words, 1.0)
    js = certify_schedule(acc, d.schedule, L1_words, 1.0).to_json()
    assert set(js["bounds"]) == set(L1_words)
    assert js["certified_terminal"] <= 1 + 1e-6


def test_error_maps_equal_the_causal_runs(acc, L1_words, rng):
    """WordCertificate.errors (G δ + c) is what the causal estimator produces for the same δ."""
    d = design_prefix(acc, L1_words, 1.0)
    x0 = np.array([20.0, 40.0, 20.0])
    u = np.full((6, 1), 206.0)
    wc = d.certificate.words[L1_words[0]]
    deltas = np.stack([sample_uncertainty(wc_layout(acc), wc.radius, rng, "uniform") for _ in range(5)])
    runs = np.stack([simulate_run(acc, d.schedule, L1_words[0], dl, x0, u).error for dl in deltas])
    assert np.allclose(wc.errors(deltas), runs, atol=1e-9)


def test_no_data_growth_is_the_infinity_norm_of_the_matrix_power(acc):
    from eqrec.bounds.certify import no_data_growth

    A2 = acc.A @ acc.A
    assert no_data_growth(acc, 2) == pytest.approx(np.abs(A2).sum(axis=1).max(), rel=1e-14)
    assert no_data_growth(acc, 0) == pytest.approx(1.0)


def test_no_data_growth_of_a_time_varying_system_is_the_transition_from_time_0(acc):
    from eqrec.bounds.certify import no_data_growth
    from eqrec.systems.affine import AffineSystem
    from eqrec.errors import InputError

    A = np.stack([acc.A, 2.0 * acc.A, 0.5 * acc.A])
    tv = AffineSystem(A=A, C=acc.C, E=acc.E, eta_w=acc.eta_w, eta_v=acc.eta_v)
    P = A[1] @ A[0]
    assert no_data_growth(tv, 2) == pytest.approx(np.abs(P).sum(axis=1).max(), rel=1e-14)
    # the constant A of the same system would give a different (wrong) factor
    assert no_data_growth(tv, 2) != pytest.approx(no_data_growth(acc, 2))
    with pytest.raises(InputError):
        no_data_growth(tv, 4)
