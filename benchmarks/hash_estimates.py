"""Hash every estimate and bound of the causal estimators on fixed runs (issue 40 §3: a speed-up changes no number).

    python benchmarks/hash_estimates.py [--out FILE] [--plants carts,cart-pole,chain,acc,reactor] [--steps 60]

Per plant (the three of ``benchmarks/bench_tight.py`` and the two of the compare study, ``config/compare.yaml``),
loss rate (0, 20, 40 %, Bernoulli, delays ``0..D`` uniform) and input (none, or a deterministic ``u(t)`` where the
plant has one), the estimators are stepped on the same arrivals: ``design.estimator()`` (``strict=True``; a refused
step is recorded with its message and the estimator reset from its estimate), ``strict=False`` (tight and
``tight=False``; the estimate, the bound, the per-state bounds, ``in_design``), the zonotope estimator alone, and on the
compare plants the prefix design's node-gain estimator (``strict=True`` and ``False``, on-time packets only).  The
digest of every number (their bytes) is printed per case and written as JSON; run it before and after a change and
compare the files (``diff``): one differing byte changes the digest.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_tight import HORIZON, MAX_DELAY, MAX_LOST, cart_chain, cart_pole  # noqa: E402
from eqrec.arrivals.draws import bernoulli_trace, with_uniform_delays  # noqa: E402
from eqrec.design.delay.design import design_delay_global  # noqa: E402
from eqrec.design.delay.languages import delay_classes  # noqa: E402
from eqrec.design.inputs import missing_words_at_most  # noqa: E402
from eqrec.design.prefix.design import design_prefix  # noqa: E402
from eqrec.errors import InputError  # noqa: E402
from eqrec.estimators.protocol import OnTimeOnly  # noqa: E402
from eqrec.estimators.zonotope import ZonotopeEstimator  # noqa: E402
from eqrec.simulate.loop import closed_loop, draw_box, what_arrived  # noqa: E402
from eqrec.systems.examples import acc_system, batch_reactor, two_mass  # noqa: E402

PLANTS = {"carts": (two_mass, HORIZON, MAX_DELAY, MAX_LOST), "cart-pole": (cart_pole, HORIZON, MAX_DELAY, MAX_LOST),
          "chain": (lambda: cart_chain(5), HORIZON, MAX_DELAY, MAX_LOST), "acc": (acc_system, 6, 1, None),
          "reactor": (batch_reactor, 5, 2, None)}


def _inputs(system, steps, with_input):
    if not with_input or system.m == 0:
        return None
    t = np.arange(steps)[:, None]
    return 0.3 * np.sin(0.37 * t + np.arange(system.m)[None, :])


def _arrivals(system, design, trace, u, seed):
    """What reaches an estimator at each step (from one simulated run, noise at random box corners)."""
    rng = np.random.default_rng(seed)
    N = trace.steps
    w = draw_box(rng, system.eta_w, (N, system.nw), "vertex")
    v = draw_box(rng, system.eta_v, (N, system.nv), "vertex")
    xi0 = draw_box(rng, design.mu1, (system.n,), "vertex")
    x0 = np.linspace(-1.0, 1.0, system.n)
    u_at = None if u is None else (lambda k, xhat: u[k])
    run = closed_loop(system, ZonotopeEstimator(system, x0_radius=design.mu1, max_delay=HORIZON), trace, x0, xi0,
                      w, v, u_at=u_at)
    schedule = trace.schedule()
    return [what_arrived(schedule[k], k, run.y) for k in range(N)], x0 - xi0


def _digest(est, arrived, u, xhat0, strict, extra) -> str:
    h = hashlib.sha256()
    est.reset(xhat0)
    for k, y in enumerate(arrived):
        uk = None if u is None else u[k]
        try:
            xhat, bound = est.step(y, uk)
        except InputError as err:
            if not strict:
                raise
            h.update(str(err).encode())
            est.reset(est.x, t0=est.time)
            xhat, bound = est.step(y, uk)
        h.update(np.ascontiguousarray(xhat, float).tobytes())
        h.update(np.float64(bound).tobytes())
        for name in extra:
            h.update(np.ascontiguousarray(np.asarray(getattr(est, name), float)).tobytes())
    return h.hexdigest()[:16]


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=None, help="JSON file of the digests")
    ap.add_argument("--plants", default=",".join(PLANTS))
    ap.add_argument("--steps", type=int, default=60)
    args = ap.parse_args(argv)
    digests = {}
    for key in args.plants.split(","):
        make, T, D, lost = PLANTS[key]
        system = make()
        t0 = time.perf_counter()
        lang = delay_classes(max_delay=D, horizon=T, max_lost=lost) if lost is not None else \
            delay_classes(max_delay=D, horizon=T)
        design = design_delay_global(system, lang).design
        makers = {"strict=True": (lambda: design.estimator(), True, ()),
                  "strict=False": (lambda: design.estimator(strict=False), False,
                                   ("state_bounds", "in_design", "rounding_vector")),
                  "strict=False,tight=False": (lambda: design.estimator(strict=False, tight=False), False,
                                               ("state_bounds", "in_design")),
                  "zonotope": (lambda: ZonotopeEstimator(system, x0_radius=design.mu1, max_delay=T), False,
                               ("state_bounds",))}
        if key in ("acc", "reactor"):
            prefix = design_prefix(system, missing_words_at_most(T, 1), "free")
            makers["prefix strict=True"] = (lambda: OnTimeOnly(prefix.estimator(), system.p), True, ())
            makers["prefix strict=False"] = (lambda: OnTimeOnly(prefix.estimator(strict=False), system.p), False,
                                             ())
        print(f"{key}: designs {time.perf_counter() - t0:.1f} s", flush=True)
        for loss in (0.0, 0.2, 0.4):
            rng = np.random.default_rng(int(loss * 10) + 1)
            trace = with_uniform_delays(rng, bernoulli_trace(rng, args.steps, loss), D)
            for with_input in (False, True):
                u = _inputs(system, args.steps, with_input)
                if with_input and u is None:
                    continue
                arrived, xhat0 = _arrivals(system, design, trace, u, 3)
                for name, (mk, strict, extra) in makers.items():
                    case = f"{key} loss={loss:.1f} input={with_input} {name}"
                    digests[case] = _digest(mk(), arrived, u, xhat0, strict, extra)
                    print(f"  {case}: {digests[case]}", flush=True)
    if args.out:
        Path(args.out).write_text(json.dumps(digests, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    main()
