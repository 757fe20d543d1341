"""P4 counts are tie-robust: equal variances (eta_bar = 1, both compensations the same filter) count as ties."""
import numpy as np

from eqrec.studies.p4.values import TIE_RTOL, _ranking


def _better(zero, hold) -> str:
    """The ranking of one point (what step_values reads for the steady states)."""
    return str(_ranking(zero, hold)[()])


def test_last_digit_differences_are_ties():
    z = np.array([[1.0, 2.0], [1.7242172, 2.29519868]])
    for eps in (0.0, 4.4e-16, -8.9e-16):  # the two machines' last-digit noise at eta_bar = 1
        h = z.copy()
        h[1] += eps
        assert list(_ranking(z, h)) == ["tie", "tie"]
    assert _better(z[1], z[1] * (1 + 0.1 * TIE_RTOL)) == "tie"


def test_clear_differences_and_mixed():
    z = np.array([[1.0, 2.0], [1.0, 2.0], [1.0, 2.0]])
    h = np.array([[1.1, 2.1], [0.9, 1.9], [0.9, 2.1]])
    assert list(_ranking(z, h)) == ["zero-input", "hold-input", "mixed"]
    # a point lower in one component and tied in the other is not "better"
    assert _better(np.array([1.0, 2.0]), np.array([1.1, 2.0])) == "mixed"


def test_grid_counts_add_up():
    rng = np.random.default_rng(0)
    z = rng.uniform(1, 2, size=(50, 2))
    h = z + rng.choice([-0.1, 0.0, 0.1], size=(50, 1))
    r = _ranking(z, h)
    assert sum((r == k).sum() for k in ("zero-input", "hold-input", "tie", "mixed")) == 50
    assert (r == "tie").sum() == int((h == z).all(axis=1).sum())
