import numpy as np

from eqrec.design.prefix import design_prefix
from eqrec.core.simulate import monte_carlo, sample_uncertainty
from eqrec.core.stacking import UncertaintyLayout


def test_samples_stay_in_the_box(rng):
    lay = UncertaintyLayout(6, 1, 2, 3)
    r = lay.radius(0.1, 0.05, 1.0)
    u = sample_uncertainty(lay, r, rng, "uniform", size=200)
    v = sample_uncertainty(lay, r, rng, "vertex", size=200)
    assert np.all(np.abs(u) <= r) and np.allclose(np.abs(v), r)


def test_monte_carlo_inside_certified_bounds(acc, L1_words):
    d = design_prefix(acc, L1_words, 1.0)
    errs, words = monte_carlo(acc, d.schedule, L1_words, 1.0, 50, seed=3, kind="vertex")
    bounds = np.stack([d.certificate.words[w].bounds for w in words])
    assert np.all(np.abs(errs) <= bounds + 1e-9)
    assert set(words) <= set(L1_words)
