"""The batch reactor of the delayed-data paper (Section IV-A), discretised from the continuous model."""
import numpy as np
import pytest

from eqrec.errors import InputError
from eqrec.systems.examples import BATCH_REACTOR_C, batch_reactor, batch_reactor_matrices, discretisation_gaps, zoh

def test_zoh_discretisation_reproduces_the_printed_matrices_to_rounding(published):
    # printed in Section IV-A of the delayed-data paper (four decimals): claims P3-BR:A, P3-BR:B
    gaps = discretisation_gaps(published("P3-BR:A"), published("P3-BR:B"))
    assert gaps["A"] <= 5e-5 + 1e-12 and gaps["B"] <= 5e-5 + 1e-12  # printed = ZOH rounded to 4 decimals
    assert gaps["A_rel_digit"] <= 1.0 and gaps["B_rel_digit"] <= 1.0


def test_zoh_is_the_matrix_exponential():
    import scipy.linalg as sla

    from eqrec.systems.examples import BATCH_REACTOR_AC, BATCH_REACTOR_BC

    n, m = 4, 2
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = BATCH_REACTOR_AC, BATCH_REACTOR_BC
    E = sla.expm(M * 0.05)
    A, B = batch_reactor_matrices()
    np.testing.assert_allclose(A, E[:n, :n], atol=1e-12)
    np.testing.assert_allclose(B, E[:n, n:], atol=1e-12)


@pytest.mark.parametrize(("n", "m", "Ts"), [(4, 2, 0.05), (1, 1, 0.3), (3, 2, 1.0), (7, 3, 0.01)])
def test_zoh_gives_the_bits_of_scipy_cont2discrete(n, m, Ts):
    # zoh does cont2discrete's arithmetic without importing scipy.signal: the results (and every study built on the
    # batch reactor) keep their bytes
    from scipy.signal import cont2discrete

    from eqrec.systems.examples import BATCH_REACTOR_AC, BATCH_REACTOR_BC

    rng = np.random.default_rng(n)
    Ac, Bc = (BATCH_REACTOR_AC, BATCH_REACTOR_BC) if n == 4 else (rng.standard_normal((n, n)), rng.standard_normal((n, m)))
    A, B = zoh(Ac, Bc, Ts)
    Ad, Bd, *_ = cont2discrete((Ac, Bc, np.eye(n), np.zeros((n, m))), Ts, method="zoh")
    assert A.tobytes() == np.asarray(Ad).tobytes() and B.tobytes() == np.asarray(Bd).tobytes()


def test_batch_reactor_system():
    s = batch_reactor()
    assert (s.n, s.p, s.m, s.nw) == (4, 2, 2, 0)
    assert s.eta_v == 0.05 and s.eta_w == 0.0
    np.testing.assert_array_equal(s.V, np.eye(2))
    np.testing.assert_array_equal(s.C, BATCH_REACTOR_C)
    assert max(abs(np.linalg.eigvals(s.A))) > 1  # open-loop unstable, as Rosenbrock's reactor


def test_bad_inputs():
    with pytest.raises(InputError, match="sampling time"):
        zoh(np.eye(2), np.ones((2, 1)), -1.0)
    with pytest.raises(InputError, match="shapes"):
        discretisation_gaps(np.eye(3), np.ones((4, 2)))
