"""The exact rows of the running ``"hold"`` error (``augmented_guarantee._running_rows``).

Their coefficients come from the running estimator's model (P2 eqs. (2)-(3), (6)-(8),
:func:`eqrec.design.augmented.runtime.running_error_maps`); here they are checked against
(a) a finite-difference reference (unit steps through the certified maps, kept in this test only),
(b) :func:`eqrec.bounds.certify.closed_loop_maps` of the converted gains at random points, and
(c) the best guarantee among the optima, certified independently, on the P2 study's inputs
(``config/p2.yaml``: the ``printed`` step's word, ``μ1``, printed ``L``, LP solvers).
"""
from pathlib import Path

import numpy as np
import pytest

from eqrec.errors import InputError
from eqrec.bounds.certify import certify_schedule, closed_loop_maps
from eqrec.arrivals.words import validate_language, worst_case_word
from eqrec.design.augmented import guarantee as ag
from eqrec.design.augmented.word_lp import AugmentedLP
from eqrec.design.augmented.model import arrival_indicator
from eqrec.design.augmented.runtime import running_error_maps, schedule_from_augmented
from eqrec.design.observers import deadbeat_observer
from eqrec.studies.pipeline import configuration

ROOT = Path(__file__).resolve().parents[1]
CFG = configuration.load_config("p2", root=ROOT)
WORDS = validate_language(CFG["f2_words"], length=int(CFG["T"]))
WORD = worst_case_word(WORDS)  # the printed step's designed word (100111)
MU1 = float(CFG["mu1"])
SOLVERS = [CFG["heatmap"]["solver"]] + [s for s in CFG["solvers"] if s in ("highs", "clarabel", "scipy")
                                        and s != CFG["heatmap"]["solver"]]  # as step_printed
RTOL = 1e-12


@pytest.fixture(scope="module")
def printed_L(published):
    return published(CFG["printed"]["L_claim"])


def _maps(system, design, x, runtime):
    G, c, _ = closed_loop_maps(system, schedule_from_augmented(system, design.gains_from_x(x), runtime), design.word)
    return G.reshape(-1, G.shape[-1]), c.reshape(-1)


def _fd_reference(system, design, x_base, cols, runtime, keep):
    """The former coefficients: unit steps in each column through the certified maps (dense)."""
    G0, c0 = _maps(system, design, x_base, runtime)
    dG, dc = np.zeros(G0.shape + (x_base.size,)), np.zeros(c0.shape + (x_base.size,))
    for j in cols:
        x = x_base.copy()
        x[j] += 1.0
        Gj, cj = _maps(system, design, x, runtime)
        dG[..., j], dc[:, j] = Gj - G0, cj - c0
    xb = np.zeros(x_base.size)
    xb[cols] = x_base[cols]
    return G0[keep] - dG[keep] @ xb, dG[keep], c0[keep] - dc[keep] @ xb, dc[keep]


def _dense(rows, D):
    """``(G0, Gx, c0, cx)`` of :class:`UncertainAffineRows` as dense arrays ``(R, D)``, ``(R, D, nx)``, ..."""
    R, nx = rows.num_rows, rows.cx.shape[1]
    G0, Gx = np.zeros((R, D)), np.zeros((R, D, nx))
    G0[rows.entry_row, rows.entry_coord] = rows.G0
    Gx[rows.entry_row, rows.entry_coord] = rows.Gx.toarray()
    return G0, Gx, rows.c0, rows.cx.toarray()


def _free_columns(design):
    """The columns best_guarantee_among_optima leaves free: gains of steps >= the last missing step."""
    q = arrival_indicator(design.word)
    k_last = int(np.flatnonzero(q == 0).max())
    early = np.concatenate([mc for (s, _), mc in design.m_cols.items() if s < k_last]
                           + [design.nu_cols[: k_last * design.system.n]])
    return np.setdiff1d(np.arange(1, design.num_columns), early)


def _rel(a, b):
    return float(np.abs(a - b).max() / max(1.0, np.abs(b).max()))


def _assert_rows_match(system, design, x_base, cols, runtime, keep):
    rows = ag._running_rows(system, design, x_base.copy(), cols, runtime, keep)
    D = design.st.layout.size
    exact, ref = _dense(rows, D), _fd_reference(system, design, x_base, cols, runtime, keep)
    for name, a, b in zip(("G0", "Gx", "c0", "cx"), exact, ref):
        assert _rel(a, b) <= RTOL, name
    # the sparsity structure: every nonzero of the reference is an entry of the rows (no entry dropped)
    G0r, Gxr = ref[0], ref[1]
    scale = max(1.0, np.abs(G0r).max(), np.abs(Gxr).max())
    struct = np.zeros((keep.size, D), bool)
    struct[rows.entry_row, rows.entry_coord] = True
    assert not np.any(((np.abs(G0r) > 1e-13 * scale) | np.any(np.abs(Gxr) > 1e-13 * scale, axis=-1)) & ~struct)
    return rows, exact


# --------------------------------------------------------------------------- (a) exact = finite differences

def test_exact_rows_match_finite_differences_in_the_study(acc, printed_L, monkeypatch):
    """Every _running_rows call of the printed step's hold runs (each LP solver; also bound="terminal")
    against unit steps through closed_loop_maps, at the x_base the lower LP really returned."""
    calls = []
    real = ag._running_rows

    def recording(system, design, x_base, cols, runtime, keep):
        calls.append((system, design, x_base.copy(), np.asarray(cols).copy(), runtime, np.asarray(keep).copy()))
        return real(system, design, x_base, cols, runtime, keep)

    monkeypatch.setattr(ag, "_running_rows", recording)
    for solver in SOLVERS:
        ag.best_guarantee_among_optima(acc, WORD, MU1, printed_L, runtime="hold", solver=solver)
    ag.best_guarantee_among_optima(acc, WORD, MU1, printed_L, runtime="hold", bound="terminal")
    monkeypatch.setattr(ag, "_running_rows", real)
    assert len(calls) == len(SOLVERS) + 1 and all(c[4] == "hold" for c in calls)
    for system, design, x_base, cols, runtime, keep in calls:
        rows, _ = _assert_rows_match(system, design, x_base, cols, runtime, keep)
        assert rows.Gx.nnz and rows.cx.nnz  # the free gains do act on the error


@pytest.mark.parametrize("mode", ["masked_gain", "theorem2", "leak"])
@pytest.mark.parametrize("which_L", ["printed", "deadbeat"])
def test_exact_rows_match_finite_differences_random_gains(acc, printed_L, mode, which_L):
    L = printed_L if which_L == "printed" else deadbeat_observer(acc.A, acc.C, seed=0).L
    d = AugmentedLP(acc, WORD, MU1, L, mode=mode)
    x = np.random.default_rng(7).normal(size=d.num_columns)
    _assert_rows_match(acc, d, x, _free_columns(d), "hold", np.arange((d.T + 1) * acc.n))
    _assert_rows_match(acc, d, x, _free_columns(d), "hold", np.arange(d.T * acc.n, (d.T + 1) * acc.n))


def test_comparison_detects_a_wrong_coefficient(acc, printed_L):
    """The tolerance is tight enough to see a coefficient wrong in its 10th digit."""
    d = AugmentedLP(acc, WORD, MU1, printed_L, mode="masked_gain")
    x = np.random.default_rng(3).normal(size=d.num_columns)
    cols, keep = _free_columns(d), np.arange((d.T + 1) * acc.n)
    rows = ag._running_rows(acc, d, x.copy(), cols, "hold", keep)
    Gx = _dense(rows, d.st.layout.size)[1]
    ref = _fd_reference(acc, d, x, cols, "hold", keep)[1]
    assert _rel(Gx, ref) <= RTOL
    k = np.unravel_index(np.argmax(np.abs(Gx)), Gx.shape)
    Gx[k] *= 1 + 1e-10
    assert _rel(Gx, ref) > RTOL


# --------------------------------------------------------------------------- (b) G0 + Gx x = the certified maps

@pytest.mark.parametrize("mode", ["masked_gain", "leak"])
def test_rows_equal_closed_loop_maps_at_random_points(acc, printed_L, mode):
    d = AugmentedLP(acc, WORD, MU1, printed_L, mode=mode)
    rng = np.random.default_rng(11)
    x_base = rng.normal(size=d.num_columns)
    cols, keep = _free_columns(d), np.arange((d.T + 1) * acc.n)
    G0, Gx, c0, cx = _dense(ag._running_rows(acc, d, x_base.copy(), cols, "hold", keep), d.st.layout.size)
    for _ in range(5):
        x = x_base.copy()
        x[cols] = rng.normal(size=cols.size) * rng.choice([0.1, 1.0, 10.0])
        G, c = _maps(acc, d, x, "hold")
        assert _rel(G0 + Gx @ x, G) <= RTOL and _rel(c0 + cx @ x, c) <= RTOL
        # the model itself, every gain at x (not only the free ones), is the certified estimator
        Gm, cm, _, _ = running_error_maps(acc, d.gains_from_x(x), "hold")
        assert _rel(Gm.reshape(G.shape), G) <= RTOL and _rel(cm.reshape(-1), c) <= RTOL
    # a nonzero s0 enters the constant part (the model's e(0) = ξ0 - s0)
    d0 = AugmentedLP(acc, WORD, MU1, printed_L, s0=np.array([0.5, -0.3, 0.2]), mode=mode)
    G0, Gx, c0, cx = _dense(ag._running_rows(acc, d0, x_base.copy(), cols, "hold", keep), d0.st.layout.size)
    G, c = _maps(acc, d0, x_base, "hold")
    assert _rel(G0 + Gx @ x_base, G) <= RTOL and _rel(c0 + cx @ x_base, c) <= RTOL


def test_affinity_is_checked(acc, printed_L):
    """Free gains before the last missing step (whose injection reaches s at a missing step, then e) are refused
    in "hold"; in "theorem2" (L_k = 0 at missing steps) every gain column may be free."""
    d = AugmentedLP(acc, WORD, MU1, printed_L, mode="masked_gain")
    x = np.random.default_rng(5).normal(size=d.num_columns)
    keep = np.arange((d.T + 1) * acc.n)
    all_gains = np.arange(1, d.num_columns)
    with pytest.raises(InputError, match="not affine"):
        ag._running_rows(acc, d, x.copy(), all_gains, "hold", keep)
    with pytest.raises(InputError, match="gain columns"):
        ag._running_rows(acc, d, x.copy(), np.array([0]), "hold", keep)  # the μ2 column
    G0, Gx, c0, cx = _dense(ag._running_rows(acc, d, x.copy(), all_gains, "theorem2", keep), d.st.layout.size)
    y = np.random.default_rng(6).normal(size=d.num_columns)
    G, c = _maps(acc, d, y, "theorem2")
    assert _rel(G0 + Gx @ y, G) <= RTOL and _rel(c0 + cx @ y, c) <= RTOL
    # and the hold error is indeed not affine in those gains: the refusal is needed
    Gh = [_maps(acc, d, t * y, "hold")[0] for t in (0.0, 1.0, 2.0)]
    assert _rel(Gh[2] - 2 * Gh[1] + Gh[0], Gh[1]) > 1e-6


# --------------------------------------------------------------------------- (c) the best guarantee, certified

@pytest.mark.parametrize("solver", SOLVERS)
def test_best_guarantee_hold_certifies(acc, printed_L, solver):
    r = ag.best_guarantee_among_optima(acc, WORD, MU1, printed_L, runtime="hold", solver=solver)
    assert r.runtime == "hold" and r.lower <= r.upper * (1 + 1e-9) + 1e-9 and r.exact
    words = sorted(set(WORDS) | {WORD})
    cert = certify_schedule(acc, schedule_from_augmented(acc, r.gains, "hold"), words, MU1)
    assert cert.mu2 == pytest.approx(r.upper, rel=1e-6) and cert.mu2 <= r.upper * (1 + 1e-6)
    assert r.design_mu2 <= r.optimum_bound
