"""What the configuration schemas cannot say: the cross-field checks of each study's section.

:func:`eqrec.studies.pipeline.configuration.validate_config` runs ``CHECKS[section]`` after
the schema (``config/schemas/config.schema.yaml``, which refers to
``<section>.schema.yaml``).  This module imports only light modules (no
solver, no SciPy statistics): the Snakefile validates the configuration at
every start, and Snakemake starts once per job.
A check raises :class:`~eqrec.errors.InputError` naming the field relative
to the section; the harness adds the file and the section.
"""

from __future__ import annotations

from typing import Callable

from eqrec.arrivals.words import parse_delay_word, parse_delays, validate_language
from eqrec.errors import InputError
from eqrec.lmv.plant import plant_of


def check_p1(cfg: dict) -> None:
    """What the schema cannot say: one word length in L1, ordered M1 ranges."""
    validate_language(cfg["language"], field_name="language")
    ext = cfg["extensions"]
    if not ext["M1_min_plot"] < ext["M1_max"]:
        raise InputError("must be below extensions.M1_max", field="extensions.M1_min_plot")


def check_p2(cfg: dict) -> None:
    """What the schema cannot say: words of length T, at most one heat-map chunk per θ."""
    T = int(cfg["T"])
    for key in ("f1_words", "f2_words"):
        validate_language(cfg[key], length=T, field_name=key)
    if len(cfg["heatmap"]["word"]) != T:
        raise InputError(f"word length {len(cfg['heatmap']['word'])}, expected T = {T}", field="heatmap.word")
    if int(cfg["heatmap"]["chunks"]) > int(cfg["heatmap"]["n_theta"]):
        raise InputError(f"{cfg['heatmap']['chunks']} chunks for {cfg['heatmap']['n_theta']} values of theta",
                         field="heatmap.chunks")


def check_p3(cfg: dict) -> None:
    """What the schema cannot say: word lengths equal to the horizon, delays within the bound."""
    br = cfg["batch_reactor"]
    f1 = cfg["kalman"]
    if len(f1["true_pattern"]) != br["horizon"]:
        raise InputError(f"has length {len(f1['true_pattern'])}, not the horizon batch_reactor.horizon = "
                         f"{br['horizon']}", field="kalman.true_pattern")
    parse_delays(f1["true_pattern"], br["max_delay"], field_name="kalman.true_pattern")
    acc = cfg["acc"]
    lengths = {len(w) for w in acc["language"]}
    if len(lengths) != 1:
        raise InputError(f"words of mixed lengths {sorted(lengths)}", field="acc.language")
    if len(acc["true_pattern"]) not in lengths:
        raise InputError("must have the length of the words of acc.language", field="acc.true_pattern")
    if parse_delay_word(acc["true_pattern"]) not in set(map(parse_delay_word, acc["language"])):
        raise InputError("is not a word of acc.language (up to its event sequence)", field="acc.true_pattern")


def check_p4(cfg: dict) -> None:
    """What the schema cannot say: plants build, the tracking example exists, grids and chunks fit."""
    for name in cfg["examples"]:
        try:
            plant_of(cfg, name)
        except InputError as exc:
            raise InputError(str(exc), field=f"examples.{name}") from None
    if cfg["tracking"]["example"] not in cfg["examples"]:
        raise InputError(f"unknown example {cfg['tracking']['example']!r} (examples: {list(cfg['examples'])})",
                         field="tracking.example")
    if not int(cfg["smoother_lag"]) < int(cfg["T"]):
        raise InputError(f"smoother lag {cfg['smoother_lag']} must be below T = {cfg['T']}", field="smoother_lag")
    for g in ("sweep_eta", "sweep_q"):
        grid_ = cfg[g]
        if int(grid_["chunks"]) > int(grid_["num"]):
            raise InputError(f"{grid_['chunks']} chunks for {grid_['num']} grid points", field=f"{g}.chunks")
        if not grid_["lo"] <= grid_["hi"]:
            raise InputError("need lo <= hi", field=f"{g}.lo")


def check_compare(cfg: dict) -> None:
    """What the schema cannot say: a burst setting whose average loss the Gilbert channel can give.

    The same conditions as :class:`eqrec.compare.CompareSetup` (which imports pandas; too heavy for every start of
    the workflow): a burst needs a positive loss, and mean bursts of ``b`` steps give at most an average loss
    ``b / (b + 1)`` (the channel enters a burst with probability ``loss / (1 - loss) / b <= 1``).
    ``tests/test_compare_study.py`` checks that both accept the same settings.
    """
    for name, setting in cfg["settings"].items():
        if "burst" not in setting:
            continue
        loss, burst = float(setting["loss"]), float(setting["burst"])
        if loss == 0:
            raise InputError("a burst length needs a positive loss", field=f"settings.{name}.burst")
        if loss / (1 - loss) / burst > 1:
            raise InputError(f"a mean burst of {burst:g} steps cannot give an average loss of {loss:g} (the channel "
                             f"would have to enter a burst with probability > 1)", field=f"settings.{name}.burst")


#: The check of each configuration section.
CHECKS: dict[str, Callable[[dict], None]] = {"p1": check_p1, "p2": check_p2, "p3": check_p3, "p4": check_p4,
                                             "compare": check_compare}
