"""Compare study: every estimator family on the same plant and the same packet traces (issue 24, beyond the papers).

Pipeline steps (``step_<name>``; one per rule of ``workflow/rules/compare.smk``, run by
:mod:`eqrec.studies.pipeline.harness`), each ``step(cfg, inputs, outputs, wildcards)``
with ``cfg`` the validated ``compare`` section (``config/compare.yaml``):

``run``     one system (``wildcards.system``), every setting of the section (the rule's order): per (system,
            setting) pair, :func:`eqrec.compare.compare_families` on that plant and those traces; its table
            (``<system>_<setting>.csv``, :func:`eqrec.compare.write_table`), its figure
            (``.png``/``.pdf``, :func:`eqrec.compare.compare_figure`) and what the table does not hold
            (``.json``: the settings, the ``μ1`` of each guaranteed design, the bounds inside and outside the
            designed language, the other families' errors against the class engine's bound).  The settings
            of a system share one process (its imports, the compiled kernels and the plotting machinery are
            loaded once: about 3 s of CPU a pair on a 2-core machine), and the guaranteed designs of each loss
            budget they try (``compare_families(..., memo=)``: about 1.4 s of CPU a job) and the figure's panels
            (``compare_figure(..., memo=)``: about 1 s of CPU a job); each pair's files are
            those of a process of its own (the information limit's row cache is emptied before each pair).  The job's
            wall time and peak memory are its rule's benchmark (``results/timings/compare/<system>.tsv``),
            each pair's µs per step its ``results/timings/compare/<system>_<setting>.json``.
``table``   every pair's table in one, ``compare.csv`` (the columns ``system, setting, loss, burst,
            max_delay, horizon`` first, each cell as its job wrote it), and ``summary.json`` (the pairs'
            ``.json``), in the configuration's order; checks that the jobs cover the configured pairs
            exactly once.

The mathematics is in :mod:`eqrec.compare` (the traces, the families, the Monte Carlo, the table and the figure);
the plants are the package's models (:func:`eqrec.systems.examples.acc_system`, :func:`eqrec.systems.examples.batch_reactor`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import numpy as np

from eqrec.compare import FAMILIES, CompareResult, CompareSetup, compare_families, compare_figure, write_table
from eqrec.systems.examples import acc_system, batch_reactor
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError
from eqrec.io import atomic_path, compiled_once, gc_paused
from eqrec.studies.pipeline.logs import get_logger
from eqrec.studies.pipeline.outputs import read_json, write_json, write_text

log = get_logger("compare")

#: The plants a system's ``model`` names (``config/schemas/compare.schema.yaml``).
MODELS: dict[str, Callable[[], AffineSystem]] = {"acc": acc_system, "batch_reactor": batch_reactor}

#: The columns of ``compare.csv`` before those of :data:`eqrec.compare.COLUMNS`: which job wrote the row.
KEYS = ("system", "setting", "loss", "burst", "max_delay", "horizon")

#: The field of the ``compare`` section behind each :class:`~eqrec.compare.CompareSetup` argument.
_FIELDS = {"loss": "settings.{setting}.loss", "burst": "settings.{setting}.burst",
           "max_delay": "systems.{system}.max_delay", "horizon": "systems.{system}.horizon"}


def setup_of(cfg: dict, system: str, setting: str) -> CompareSetup:
    """The :class:`~eqrec.compare.CompareSetup` of one (system, setting) pair of the ``compare`` section.

    Parameters
    ----------
    cfg : dict
        The ``compare`` section.
    system, setting : str
        Keys of ``cfg["systems"]`` and ``cfg["settings"]``.

    Returns
    -------
    CompareSetup
        Loss and burst of the setting, ``D`` and ``T`` of the system, the section's runs, periods and seed.

    Raises
    ------
    InputError
        A value :class:`~eqrec.compare.CompareSetup` refuses, naming the field of the section.
    """
    plant, traces = cfg["systems"][system], cfg["settings"][setting]
    try:
        return CompareSetup(loss=traces["loss"], max_delay=plant["max_delay"], horizon=plant["horizon"],
                            runs=cfg["runs"], periods=cfg["periods"], burst=traces.get("burst"), seed=cfg["seed"],
                            exact_runs=cfg.get("exact_runs", 4))
    except InputError as exc:
        field = _FIELDS.get(exc.field or "", exc.field or "").format(system=system, setting=setting)
        raise InputError(str(exc).removeprefix(f"field '{exc.field}': "), field=field) from None


def _median(values: np.ndarray) -> float | None:
    return float(np.median(values)) if values.size else None


def summary_of(result: CompareResult) -> dict[str, Any]:
    """What ``compare.csv`` does not hold, per family: the guaranteed designs' ``μ1`` and bounds inside and
    outside the designed language, and every other family's error against the class engine's bound.

    Parameters
    ----------
    result : CompareResult
        One comparison.

    Returns
    -------
    dict
        ``designs``: per family its language in words (or why there is no design); ``max_lost``, ``coverage``
        and ``limit_median`` (the information limit); ``class_limit_identity``: how many class levels of the
        class engine were compared with the one-block information limit and whether all agree within 1e-9
        relative; ``guaranteed``: per family with a bound, its largest
        bound and largest error / bound (at most 1: the guarantee), and for the designs their ``mu1`` and the
        median bound of the steps inside and outside the design (``None`` where there is none);
        ``against_class_bound``: per other family the steps (of ``runs · steps``) whose error
        is above the class engine's bound of the same run and step, their fraction, and the largest
        error / that bound (the delayed-data paper's Fig. 1 asks this of its Kalman filters).
    """
    guaranteed = {}
    for family, bound in result.bounds.items():
        err, out = result.errors[family], result.outside.get(family)
        guaranteed[family] = {"largest_bound": float(bound.max()),
                              "largest_error_over_bound": float((err / bound).max()), **({} if out is None else {"mu1": result.mu1[family], "median_bound_outside": _median(
                                  bound[out]), "median_bound_in_design": _median(bound[~out])})}
    reference, against = result.bounds.get(FAMILIES[0]), {}
    for family in (f for f in FAMILIES[1:] if f in result.errors and reference is not None):
        err, ref = result.errors[family], reference[:len(result.errors[family])]  # the exact family: its runs
        above = err > ref
        against[family] = {"steps_above": int(above.sum()), "fraction_above": float(above.mean()),
                           "largest_error_over_bound": float((err / ref).max())}
    identity = {k: result.identity[k] for k in ("classes", "all_within_1e-9_relative") if k in result.identity}
    return {"designs": result.designs, "max_lost": result.setup.max_lost, "coverage": result.setup.coverage,
            "limit_median": float(np.median(result.limit)), "class_limit_identity": identity,
            "guaranteed": guaranteed, "against_class_bound": against}


def title_of(name: str, setup: CompareSetup) -> str:
    """The figure title: the plant in words and the settings."""
    burst = "independent losses" if setup.burst is None else f"bursts of {setup.burst:g} steps on average"
    return (f"{name}: loss {setup.loss:g} ({burst}), delays up to {setup.max_delay}, T = {setup.horizon}, "
            f"{setup.runs} runs")


# --------------------------------------------------------------------------- steps

def step_run(cfg, inputs, outputs, wildcards) -> list[dict]:
    """One system, every setting of the section: each pair's table, figure and summary.

    The outputs ``csv``, ``json``, ``png``, ``pdf`` and ``timings`` are lists of one file per setting, in one order
    (``<system>_<setting>.<ext>``: the settings are read from the names of the ``csv`` files; a section with one
    setting runs that pair alone, with the same files).
    """
    from eqrec.bounds import information  # here: the table step needs no LP modules

    system, keys = wildcards["system"], ("csv", "json", "png", "pdf", "timings")
    files = {key: [outputs[key]] if isinstance(outputs[key], str) else list(outputs[key]) for key in keys}
    settings = [Path(path).stem.removeprefix(f"{system}_") for path in files["csv"]]
    if sorted(settings) != sorted(cfg["settings"]) or any(len(paths) != len(settings) for paths in files.values()):
        raise InputError(f"the rule's outputs {files} are not one per setting of {sorted(cfg['settings'])}",
                         field="settings")
    reports, plant = [], cfg["systems"][system]
    # the guaranteed designs of a loss budget, made once for the settings that share it (compare_families' memo),
    # and the figure's panels, made once and drawn again for each setting (compare_figure's memo)
    model, memo, figures = MODELS[plant["model"]](), {}, {}
    with gc_paused():  # what stays to the end is not scanned again and again (about 0.3 s of CPU a job)
        for i, setting in enumerate(settings):
            information.clear_cache()  # an earlier pair's cached rows were solved warm from another basis
            out = {key: paths[i] for key, paths in files.items()}
            setup = setup_of(cfg, system, setting)
            with compiled_once():  # on a fresh clone the first job compiles the kernels, the others load them
                result = compare_families(model, setup, memo=memo,
                                          progress=lambda msg: log.info("%s %s: %s", system, setting, msg))
            with atomic_path(out["csv"]) as tmp:
                write_table(result, str(tmp))
            compare_figure(result, out["png"], out["pdf"], title=title_of(plant["name"], setup), memo=figures)
            write_json(out["timings"], {"us_per_step": {f: round(v, 1) for f, v in result.us_per_step.items()}})
            reports.append({"system": system, "setting": setting, "name": plant["name"], "model": plant["model"],
                            "n": model.n, "p": model.p, "setup": {key: getattr(setup, key) for key in (
                                "loss", "burst", "max_delay", "horizon", "runs", "periods", "steps", "seed", "sigmas",
                                "on_time_rate", "exact_subset")}, **summary_of(result)})
            write_json(out["json"], reports[-1])
            log.info("%s %s: %d runs x %d steps, %d families", system, setting, setup.runs, setup.steps, len(FAMILIES))
    return reports


def step_table(cfg, inputs, outputs, wildcards) -> None:
    """Every pair's table in ``compare.csv`` (cells as the jobs wrote them) and their summaries in
    ``summary.json``, in the order of the inputs (the rule lists them in the configuration's order); the jobs must
    cover the configured pairs exactly once."""
    import pandas as pd

    expected = sorted((s, k) for s in cfg["systems"] for k in cfg["settings"])
    jobs = [read_json(p) for p in inputs.json]
    found = [(j["system"], j["setting"]) for j in jobs]
    tables = [Path(p).name for p in inputs.csv]
    if sorted(found) != expected or tables != [f"{s}_{k}.csv" for s, k in found]:
        raise InputError(f"the jobs {found} (tables {tables}) do not cover the configured (system, setting) pairs "
                         f"{expected} exactly once, in the same order", field="settings")
    frames = []
    for job, path in zip(jobs, inputs.csv):  # the cells of KEYS as the job's settings print them
        setup = job["setup"]
        frames.append(pd.read_csv(path, dtype=str, keep_default_na=False).assign(
            system=job["system"], setting=job["setting"], loss=f"{setup['loss']:g}",
            burst="" if setup["burst"] is None else f"{setup['burst']:g}",
            max_delay=str(setup["max_delay"]), horizon=str(setup["horizon"])))
    table = pd.concat(frames, ignore_index=True).fillna("")
    write_text(outputs.csv, table[[*KEYS, *table.columns.drop(list(KEYS))]].to_csv(index=False, lineterminator="\n"))
    write_json(outputs.json, {"pairs": jobs})
    log.info("compare.csv: %d rows of %d (system, setting) pairs", len(table), len(found))
