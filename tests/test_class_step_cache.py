"""The per-class cache of the class form (issue 40 §3) changes no number: the estimates, the bounds, the per-state
bounds and the rounding allowances of ``design.estimator()`` and ``design.estimator(strict=False)`` are bit for
bit those of the computation without it (every quantity recomputed at every step: the class looked up for each
use, ``|K|`` and the rounding map rebuilt, the level asked of the rule, ``|B| |u|`` formed even for ``u = 0``, the
error map built by :meth:`ClassEstimator.error_map` and the set-membership estimator given its own intake), in and
out of the design, with and without inputs."""
import numpy as np
import pytest

from eqrec.arrivals.draws import bernoulli_trace, with_uniform_delays
from eqrec.arrivals.traces import NEVER, ArrivalTrace
from eqrec.bounds.rounding_kernels import injection_bound
from eqrec.bounds.zonotope import outer_row_sums
from eqrec.design.delay.design import design_delay_global
from eqrec.design.delay.languages import delay_classes
from eqrec.errors import InputError
from eqrec.estimators.causal import ClassEstimator, has_class
from eqrec.estimators.error_maps import ClassErrorMaps, ClassSteps, RoundingMaps
from eqrec.estimators.guaranteed import GuaranteedEstimator
from eqrec.simulate.loop import closed_loop, draw_box
from eqrec.systems.examples import two_mass


class UncachedClassEstimator(ClassEstimator):
    """The class step as it was before the cache: every quantity recomputed (module docstring), with the generic
    intake of :class:`eqrec.estimators.intake.StampedEstimator` (the residuals formed in Python as packets arrive,
    the period's state in lists and dicts) instead of the class form's arrays and compiled residuals."""

    def step(self, y=None, u=None):
        return self._advance(self._open(y, u))

    def _advance(self, step, entry=None):
        sysm = self.system
        t = step.t
        S = tuple(sorted(step.yxi))
        xbar0 = self.xhat if step.restarted else self._xbar
        xbar = sysm.A_at(t) @ xbar0 + sysm.B_at(t) @ step.u + sysm.f
        xhat = self.gains.estimate(t + 1, S, xbar, [step.yxi[tau] for tau in S])
        record = self._period_record(step)
        for tau in self._new_packets(step):
            self._output_injection(record, tau, step.yxi[tau], step.history[tau])
        absA, absB, _, e, _, f = self._absolute_model(step.t)
        add = e + 2.0 * (absB @ np.abs(step.u) + f) if absB.shape[1] else self._drift(step.t)
        record.w[step.t] = injection_bound(absA, step.history[step.t], 1.0, record.true[step.t], self._zeros, add,
                                           sysm.n + sysm.nw + sysm.m + 3)
        maps = RoundingMaps(sysm, self.gains).absolute(t + 1, S)  # rebuilt, not the kept one
        extra = 0.0
        if S:
            r = np.concatenate([step.yxi[tau] for tau in S]) if len(S) > 1 else step.yxi[S[0]]
            extra = injection_bound(np.abs(self.gains.gain(t + 1, S)), r, 1.0, np.zeros(r.size), xbar,
                                    self._zeros, len(S) * sysm.p + 2)
        self._commit(step, (record, self._allowance(record, maps, extra)))
        self._xbar, self.xhat = xbar, xhat
        level = self.mu1 if self._t == self.T else float(self.bound_of(self.observed_prefix))
        self.bound = float(np.nextafter(level + self.rounding, np.inf))
        return self.xhat.copy(), self.bound

    def error_map(self):
        return ClassErrorMaps(self.system, self.gains).error_map(self._start, self._t, tuple(sorted(self._yxi)))


class UncachedGuaranteed(GuaranteedEstimator):
    """``strict=False`` as it was before the cache and the shared intake (module docstring)."""

    def reset(self, xhat0, t0=0):
        super().reset(xhat0, t0)
        self._est = UncachedClassEstimator(self.system, self.gains, np.asarray(xhat0, float), periodic=True, t0=t0,
                                           bound_of=self.bound_of, mu1=self.mu1)
        return self

    def _relaxed_step(self, est, packets, u):
        T = self.gains.horizon
        if self._outside:
            now = self._sm.time
            if (now - self._t0) % T == 0 and np.all(outer_row_sums(self._sm.carried_set[1]) <= self.mu1):
                self._spare = UncachedClassEstimator(self.system, self.gains, periodic=True, bound_of=self.bound_of,
                                                     mu1=self.mu1)
                est, _ = self._return_to_design(now, packets, u, self._sm.carried_set)
            else:
                self._sm.step(packets, u)
                return self._outside_bounds()
        opened = est._open(packets, u)  # opened again, on purpose: the twin does what the step did before
        t, S = opened.t, tuple(sorted(opened.yxi))
        if not has_class(self.gains, t + 1, S):
            self._sm.step(packets, u)
            self._outside = True
            return self._outside_bounds()
        self._sm.step(packets, u)
        xhat, level = est._advance(opened)
        beta = np.nextafter(self._set.advance(est.error_map()) + est.rounding_vector, np.inf)
        designed = np.minimum(beta, level)
        if self.tight:
            sm_bounds = self._sm._beta
            use_sm = sm_bounds < designed
            xhat = np.where(use_sm, self._sm._xhat, xhat)
            self._bounds = np.where(use_sm, sm_bounds, designed)
            self._use_sm = use_sm
        else:
            self._bounds = designed
        self._xhat = xhat
        self.bound = float(self._bounds.max())
        return xhat.copy(), self.bound


@pytest.fixture(scope="module")
def design():
    system = two_mass()
    return system, design_delay_global(system, delay_classes(max_delay=2, horizon=6, max_lost=1)).design


def _twin(design, strict: bool, tight: bool = True):
    system, d = design
    if strict:
        return d.estimator(), UncachedGuaranteed(system, d.class_gains, d.estimator().bound_of, d.mu1)
    return (d.estimator(strict=False, tight=tight),
            UncachedGuaranteed(system, d.class_gains, d.estimator().bound_of, d.mu1, strict=False, tight=tight))


def _same(a, b):
    return np.array_equal(a, b) and np.array_equal(np.signbit(a), np.signbit(b))


@pytest.mark.parametrize("loss", [0.0, 0.4])
@pytest.mark.parametrize("inputs", [False, True])
@pytest.mark.parametrize("strict,tight", [(True, True), (False, True), (False, False)])
def test_cached_step_is_bit_identical_to_the_uncached_one(design, loss, inputs, strict, tight):
    system, d = design
    rng = np.random.default_rng(3)
    N = 90
    trace = with_uniform_delays(rng, bernoulli_trace(rng, N, loss), 2)
    if strict:  # the language: at most one of each block of 6 lost
        delays = np.array(trace.delays)
        for b in range(0, N, 6):
            lost = [k for k in range(b, min(b + 6, N)) if delays[k] == NEVER]
            for k in lost[1:]:
                delays[k] = 0
        trace = ArrivalTrace(delays)
    w = draw_box(rng, system.eta_w, (N, system.nw), "vertex")
    v = draw_box(rng, system.eta_v, (N, system.nv), "vertex")
    xi0 = draw_box(rng, d.mu1, (system.n,), "vertex")
    x0 = rng.normal(size=system.n) * 5.0
    u_at = (lambda k, xhat: np.array([np.sin(0.3 * k) * 2.0])) if inputs else None
    fast, slow = _twin(design, strict, tight)
    fast_rows, slow_rows = [], []
    for est, rows in ((fast, fast_rows), (slow, slow_rows)):
        def after(k, est=est, rows=rows):
            rows.append((est.x, est.bound, est.state_bounds, est.rounding_vector if not strict else
                         est._est.rounding_vector, est.in_design))
        closed_loop(system, est, trace, x0, xi0, w, v, u_at=u_at, after_step=after)
    outside = 0
    for k, (a, b) in enumerate(zip(fast_rows, slow_rows)):
        assert _same(a[0], b[0]), k
        assert a[1] == b[1] and np.signbit(a[1]) == np.signbit(b[1]), k
        assert _same(a[2], b[2]), k
        assert _same(a[3], b[3]), k
        assert a[4] == b[4], k
        outside += not a[4]
    if not strict and loss > 0:
        assert outside > 0  # the run leaves the design (and the twins agree there and after the returns)


def test_class_steps_are_kept_per_class_and_absent_classes_are_none(design):
    system, d = design
    steps = ClassSteps.of(system, d.class_gains)
    assert ClassSteps.of(system, d.class_gains) is steps
    cls = d.class_gains.classes.classes[5]
    entry = steps.get(*cls.key)
    assert entry is steps.get(*cls.key) and entry.index == 5
    assert np.array_equal(entry.gain, d.class_gains.K[5]) and np.array_equal(entry.abs_gain, np.abs(d.class_gains.K[5]))
    assert steps.get(1, (0, 0)) is None and steps.get(99, ()) is None


def test_a_refused_strict_step_changes_nothing_with_the_cache(design):
    system, d = design
    est = d.estimator().reset(np.zeros(system.n))
    twin = d.estimator().reset(np.zeros(system.n))
    for k in range(6):  # nothing arrives: outside the language (at most one of six lost) within a block
        try:
            est.step(None)
        except InputError:
            break
        twin.step(None)
    else:
        pytest.fail("the language was not left")
    assert est.time == twin.time and est.bound == twin.bound and np.array_equal(est.x, twin.x)
    assert np.array_equal(est._est.rounding_vector, twin._est.rounding_vector)


def test_row_sums_of_the_blocks_are_numpys_row_sums_of_the_concatenation():
    """:func:`outer_row_sums_of_parts` adds as NumPy's ``sum`` does: bit for bit, every length, wide magnitudes."""
    from eqrec.bounds.zonotope import outer_row_sums_of_parts

    rng = np.random.default_rng(0)
    for q1 in list(range(0, 140)) + [255, 256, 257, 300, 517, 1000, 4000, 5000]:
        for n in (1, 4, 10):
            q2 = int(rng.integers(0, 60))
            P = rng.normal(size=(n, q1)) * 10.0 ** rng.integers(-9, 9, size=(n, q1))
            N = rng.normal(size=(n, q2)) * 10.0 ** rng.integers(-9, 9, size=(n, q2))
            ref = outer_row_sums(np.concatenate([P, N], axis=1))
            assert np.array_equal(outer_row_sums_of_parts(P, N), ref), (q1, q2, n)
            assert np.array_equal(outer_row_sums_of_parts(np.asfortranarray(P), N[:, ::-1]),
                                  outer_row_sums(np.concatenate([P, N[:, ::-1]], axis=1))), (q1, q2, n)


def test_compiled_products_are_numpys_for_every_layout():
    """:func:`matrix_vector` on :func:`blas_ready` arrays gives NumPy's ``M @ x`` bit for bit: C, Fortran and strided
    matrices (the column block Φ of a class map, a plant's ``B`` column), one row, no column."""
    from eqrec.estimators.error_maps import blas_ready, matrix_vector

    rng = np.random.default_rng(1)
    for trial in range(300):
        n, k = int(rng.integers(1, 12)), int(rng.integers(0, 80))
        big = rng.normal(size=(n, 2 * k + 3)) * 10.0 ** rng.integers(-6, 6, size=(n, 2 * k + 3))
        x = rng.normal(size=k)
        for M in (big[:, :k].copy(), np.asfortranarray(big[:, :k]), big[:, k + 3:], big.T[:k].T, big[:, 1:k + 1]):
            ready = blas_ready(M)
            assert ready.flags.c_contiguous or ready.flags.f_contiguous
            assert _same(matrix_vector(ready, x), M @ x), (trial, n, k, M.strides)


def test_the_long_row_path_gives_the_same_numbers(design, monkeypatch):
    """Rows past the compiled sums' limit take the NumPy sums (``ErrorSet.advance``): the same numbers."""
    import eqrec.estimators.guaranteed as guaranteed

    system, d = design
    rng = np.random.default_rng(5)
    N = 40
    trace = with_uniform_delays(rng, bernoulli_trace(rng, N, 0.3), 2)
    w = draw_box(rng, system.eta_w, (N, system.nw), "vertex")
    v = draw_box(rng, system.eta_v, (N, system.nv), "vertex")
    xi0 = draw_box(rng, d.mu1, (system.n,), "vertex")
    rows = []
    for limit in (guaranteed.PARTS_LIMIT, 0):
        monkeypatch.setattr(guaranteed, "PARTS_LIMIT", limit)
        est = d.estimator(strict=False)
        got = []
        closed_loop(system, est, trace, np.ones(system.n), xi0, w, v,
                    after_step=lambda k: got.append((est.x, est.bound, est.state_bounds, est.rounding_vector)))
        rows.append(got)
    for a, b in zip(*rows):
        assert _same(a[0], b[0]) and a[1] == b[1] and _same(a[2], b[2]) and _same(a[3], b[3])


def test_the_estimators_of_a_design_share_the_levels_they_look_up(design):
    """Two rules of one design are equal (the certificate gives its levels as a new array each time), so a new
    estimator of the design finds the levels its predecessors looked up, even after they are gone."""
    system, d = design
    a = d.estimator(strict=False).reset(np.zeros(system.n))
    assert a.bound_of == d.estimator().bound_of and hash(a.bound_of) == hash(d.estimator().bound_of)
    a.step(np.zeros(system.p))
    kept = dict(a._est._levels)
    assert kept
    del a
    b = d.estimator(strict=False).reset(np.zeros(system.n))
    assert all(b._est._levels.get(key) == level for key, level in kept.items())


def test_the_compiled_step_on_a_time_varying_plant_is_the_uncached_one():
    """A, B, C read per period time, a drift f and inputs: the compiled class step gives the numbers of the step
    computed afresh, bit for bit."""
    import eqrec
    from eqrec.systems.affine import AffineSystem

    acc = eqrec.acc_system()
    A = np.stack([acc.A * (1 + 0.02 * k) for k in range(5)])
    C = np.stack([acc.C * (1 + 0.05 * k) for k in range(5)])
    plant = AffineSystem(A=A, B=np.stack([acc.B] * 5), C=C, E=acc.E, eta_w=acc.eta_w, eta_v=acc.eta_v,
                         f=acc.f + 0.1)
    words = ["10111", "11011", "11101"]
    d = eqrec.design_prefix(plant, words, 1.0)
    rule = d.estimator().bound_of
    rng = np.random.default_rng(0)
    x0 = rng.normal(size=plant.n)
    fast = ClassEstimator(plant, d.class_gains, x0, periodic=True, bound_of=rule, mu1=d.mu1)
    slow = UncachedClassEstimator(plant, d.class_gains, x0, periodic=True, bound_of=rule, mu1=d.mu1)
    k = 0
    for word in words * 4:
        for ch in word:
            y = rng.normal(size=plant.p) if ch == "1" else None
            u = rng.normal(size=plant.m) if k % 2 else None
            a, b = fast.step(y, u), slow.step(y, u)
            assert _same(a[0], b[0]) and a[1] == b[1] and _same(fast.rounding_vector, slow.rounding_vector), k
            k += 1
