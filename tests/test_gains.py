import numpy as np
import pytest

from eqrec.bounds.certify import closed_loop_maps
from eqrec.bounds.gains import GainSchedule, f_to_q, q_to_f, schedule_from_word_gains
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.bounds.stacking import Stacking


def _random_lower(rng, T, n, p, word):
    F = np.zeros((T * n, T * p))
    for t in range(T):
        for tau in range(t + 1):
            if word[tau] == "1":
                F[t * n:(t + 1) * n, tau * p:(tau + 1) * p] = rng.normal(scale=0.3, size=(n, p))
    return F


@pytest.mark.parametrize("word", ["111111", "100111", "101101"])
def test_eq1_eq2_roundtrip_and_eq13(acc, rng, word):
    st = Stacking(acc, 6)
    F = _random_lower(rng, 6, 3, 2, word)
    u0 = rng.normal(size=18)
    CS = st.C_bar(word) @ st.S
    Q, r = f_to_q(F, u0, CS)
    F2, u02 = q_to_f(Q, r, CS)
    np.testing.assert_allclose(F2, F, atol=1e-10)
    np.testing.assert_allclose(u02, u0, atol=1e-10)
    # eq. (13) in (Q, r) equals the closed loop of the causal estimator with gains (F, u0)
    tree = PrefixTree([word])
    sched = schedule_from_word_gains(tree, {word: (F, u0)}, 3, 2)
    G, c, _ = closed_loop_maps(acc, sched, word)
    Gq, cq = st.error_map_from_Q(word, Q, r)
    np.testing.assert_allclose(G.reshape(-1, G.shape[-1]), Gq, atol=1e-9)
    np.testing.assert_allclose(c.reshape(-1), cq, atol=1e-9)


def test_inconsistent_prefix_gains_are_rejected(rng):
    tree = PrefixTree(["11", "10"])
    F1 = rng.normal(size=(2, 2))
    F2 = F1.copy()
    F2[0, 0] += 1.0  # the two words disagree at the shared prefix "1"
    with pytest.raises(AssertionError, match="prefix '1'"):
        schedule_from_word_gains(tree, {"11": (np.tril(F1), np.zeros(2)), "10": (np.tril(F2), np.zeros(2))}, 1, 1)


def test_time_based_schedule_ignores_observed_prefix():
    from eqrec.bounds.gains import GainRow

    rows = {"1": GainRow(np.ones((1, 1)), np.zeros(1)), "10": GainRow(np.ones((1, 2)), np.ones(1))}
    s = GainSchedule(rows=rows, n=1, p=1, time_based=True, designed=("10",))
    assert s.row("11") is s.rows[s.designed[0]]
    s2 = GainSchedule(rows=rows, n=1, p=1, time_based=False, designed=("10",))
    from eqrec.errors import InputError

    with pytest.raises(InputError, match="not a prefix"):
        s2.row("11")
