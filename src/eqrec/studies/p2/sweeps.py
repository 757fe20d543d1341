"""P2 eigenvalue sweeps: the Fig. 3a heat map (in θ-chunks) and the Fig. 3b real axis.

Every point has a class (``optimal``, ``infeasible``, ``solver_failed``,
``placement_failed``; :func:`eqrec.design.augmented.sweep.fixed_L_sweep` re-solves an
undecided point with the second solver and gives the all-zero pole set an
exact nilpotent ``L``) and, when optimal, the certified worst case of its gains
as the estimator that runs.

Steps ``heatmap_chunk`` (``wildcards.scatteritem``: a θ-chunk of every variant),
``heatmap_merge`` (checks that the chunks cover the configured grid of every
configured variant exactly once) and ``realaxis``.  In each job the LP of
each variant is built once and only its ``L``-dependent coefficients change
from point to point (:func:`eqrec.design.augmented.sweep.fixed_L_sweep`), and each
observer gain is placed once for all variants.  With ``heatmap.warm_start``
each LP starts from the optimal basis of the previous point of its θ line (of
the real axis): the first point of each line is solved from scratch, so the
answers do not depend on how the lines are split into chunks.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pandas as pd

from eqrec.systems.examples import acc_system
from eqrec.errors import InputError
from eqrec.studies.pipeline.chunks import check_coverage, scatter_indices
from eqrec.studies.pipeline.logs import Progress, get_logger
from eqrec.studies.pipeline.outputs import INTERMEDIATE, write_csv
from eqrec.studies.p2.grids import heatmap_grid, realaxis_grid

log = get_logger("p2")


def _sweep_variants(cfg: dict, system, poles: list[np.ndarray], what: str, run: int) -> Iterator[tuple]:
    """Every configured variant over the same pole sets, one after the other: ``(variant, mode, word, records)``.

    The observer gain of a pole set does not depend on the variant, so each
    ``L`` is placed once (:func:`eqrec.design.augmented.sweep.observer_for`) and
    shared by the variants' LPs.  Each point's gains are certified as the
    estimator that runs (``theorem2`` for the text of Theorem 2, ``hold`` -
    constant ``L`` kept - for the design-only readings).  With
    ``heatmap.warm_start`` each LP starts from the previous point's optimal
    basis within runs of ``run`` consecutive pole sets (a θ line of the heat
    map, the whole real axis), so the answers do not depend on the chunks.
    """
    # here, not at the top: the merge step needs none of the design, LP and Numba layers (about 0.5 s of CPU)
    from eqrec.design.augmented.model import default_runtime
    from eqrec.studies.p2.readings import variant_word
    from eqrec.design.augmented.sweep import fixed_L_sweep, observer_for

    h = cfg["heatmap"]
    observers = [observer_for(system, p) for p in poles]
    for variant in h["variants"]:
        mode, word = variant_word(h["word"], variant)
        yield variant, mode, word, fixed_L_sweep(
            system, word, float(cfg["mu1"]), mode, poles, h["solver"], second_solver=h["second_solver"],
            on_point=Progress(log, len(poles), f"{what} {variant}").advance, certify_runtime=default_runtime(mode),
            observers=observers, warm_start=run if h["warm_start"] else 0)


def step_heatmap_chunk(cfg, inputs, outputs, wildcards) -> pd.DataFrame:
    """P2-F3a, one θ-chunk of every variant."""
    from eqrec.studies.p2.readings import heatmap_poles

    r_grid, th_grid = heatmap_grid(cfg)
    chunk, thetas = scatter_indices(wildcards, len(th_grid), field="heatmap.chunks")
    pts = [(r, th_grid[j]) for j in thetas for r in r_grid]
    swept = _sweep_variants(cfg, acc_system(), [heatmap_poles(r, th) for r, th in pts], f"heat map chunk {chunk}:",
                            run=len(r_grid))  # the chunks are whole θ lines
    df = pd.DataFrame([{"variant": variant, "word": word, "mode": mode, "r": r, "theta": th, **rec}
                       for variant, mode, word, recs in swept for (r, th), rec in zip(pts, recs)])
    write_csv(outputs.csv, df, timings=INTERMEDIATE)  # a temporary chunk: the merge splits the timings off
    return df


def _grid_index(values: np.ndarray, grid: np.ndarray, what: str) -> np.ndarray:
    idx = np.abs(values[:, None] - grid[None, :]).argmin(axis=1)
    off = np.abs(grid[idx] - values)
    if len(off) and off.max() > 1e-9 * max(1.0, float(np.abs(grid).max())):
        raise InputError(f"chunk rows at {what} = {values[off.argmax()]!r}, not a point of the configured grid",
                         field=f"heatmap.{'n_r' if what == 'r' else 'n_theta'}")
    return idx


def check_heatmap_coverage(cfg: dict, df: pd.DataFrame) -> None:
    """Every configured variant has every ``(r, θ)`` point of the configured grid exactly once."""
    r_grid, th_grid = heatmap_grid(cfg)
    variants = list(cfg["heatmap"]["variants"])
    extra = sorted(set(df["variant"]) - set(variants))
    if extra:
        raise InputError(f"chunks of variants {extra} that the configuration does not list", field="heatmap.variants")
    for var in variants:
        g = df[df["variant"] == var]
        i = _grid_index(g["r"].to_numpy(float), r_grid, "r")
        j = _grid_index(g["theta"].to_numpy(float), th_grid, "theta")
        check_coverage(j * len(r_grid) + i, len(th_grid) * len(r_grid), field="heatmap.chunks",
                       what=f"variant {var} (heatmap.chunks = {cfg['heatmap']['chunks']})")


def step_heatmap_merge(cfg, inputs, outputs, wildcards) -> pd.DataFrame:
    """P2-F3a: the whole grid, after checking that the chunks cover it exactly once."""
    files = list(inputs.chunks)
    df = pd.concat([pd.read_csv(p, keep_default_na=False, na_values=["nan", "NaN"]) for p in files],
                   ignore_index=True)
    check_heatmap_coverage(cfg, df)
    df = df.sort_values(["variant", "theta", "r"])
    write_csv(outputs.csv, df, timings=outputs.timings, keys=["variant", "r", "theta"])
    log.info("merged %d chunk files: %d points", len(files), len(df))
    return df


def step_realaxis(cfg, inputs, outputs, wildcards) -> pd.DataFrame:
    """P2-F3b: eigenvalues ``{0, λ, λ}`` for real ``λ`` (the heat map at θ = 0 and π, finer)."""
    lam = realaxis_grid(cfg)
    swept = _sweep_variants(cfg, acc_system(), [np.array([0.0, x, x]) for x in lam], "real axis", run=len(lam))
    df = pd.DataFrame([{"variant": variant, "word": word, "lam": x, **rec}
                       for variant, _, word, recs in swept for x, rec in zip(lam, recs)])
    write_csv(outputs.csv, df, timings=outputs.timings, keys=["variant", "lam"])
    return df
