import numpy as np
import pytest

from eqrec.core.certify import certify_design, certify_schedule
from eqrec.design.prefix import design_prefix
from eqrec.errors import CertificationFailure
from eqrec.core.simulate import sample_uncertainty, simulate_run


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
    from eqrec.core.stacking import UncertaintyLayout

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
