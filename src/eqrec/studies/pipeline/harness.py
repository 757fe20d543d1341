"""The study harness: runs one pipeline step, and nothing else.

Every Snakemake rule runs ``workflow/scripts/run_step.py``, which calls
:func:`run_from_snakemake`; the rule's ``params`` name the step by the path of
its function (``step="eqrec.studies.p1.steps:step_designs"``, resolved with
:func:`pkgutil.resolve_name`; the study is the folder of :mod:`eqrec.studies` it
is in) and carry ``cfg``, the configuration keys that step reads (nested as
in the study's section, validated once by the Snakefile,
:mod:`eqrec.studies.pipeline.configuration`; picked by ``step_config`` in
``workflow/rules/common.smk``).  A key the rule does not give raises
:class:`MissingConfigKey` naming it.

A step is a plain function ``step(cfg, inputs, outputs, wildcards)``.  Outside Snakemake::

    from eqrec.studies.pipeline import configuration, harness
    cfg = configuration.load_config("p1", "config/config.yaml")
    harness.run_step("eqrec.studies.p1.steps:step_designs", cfg,
                     outputs={"json": "designs.json", "timings": "t.json"})

The harness owns what every step shares: the log (``[p1] message`` lines in
the rule's log file; the loggers and progress lines are in
:mod:`eqrec.studies.pipeline.logs`), the check that every declared output was written,
and the exit status (a failing step exits 1 with one line naming the step and,
for a configuration problem, the file and field).  The writers a step uses are
in :mod:`eqrec.studies.pipeline.outputs`.  The modules a rule lists as code inputs come
from :mod:`eqrec.studies.pipeline.code`.
"""

from __future__ import annotations

import contextlib
import logging
import os
import pkgutil
import sys
import time
import traceback
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Mapping, Sequence

from eqrec.errors import InputError, StepError
from eqrec.studies.pipeline.configuration import SECTIONS, ConfigError
from eqrec.studies.pipeline.logs import get_logger

Step = Callable[[dict, "Files", "Files", "Wildcards"], Any]


# --------------------------------------------------------------------------- files and wildcards

class Files(list):
    """A step's inputs or outputs: positional paths plus named entries (a path or a list of paths).

    ``files.json``, ``files["json"]`` and ``files[0]`` work as on Snakemake's
    ``input``/``output`` objects.
    """

    def __init__(self, items: Iterable[str] = (), **named: str | Sequence[str]):
        super().__init__(map(str, items))
        self._named: dict[str, str | list[str]] = {}
        for key, val in named.items():
            one = isinstance(val, (str, os.PathLike))
            paths = [str(v) for v in ([val] if one else val)]
            self._named[key] = paths[0] if one else paths
            self.extend(paths)

    @classmethod
    def of(cls, obj: "Files | Mapping[str, Any] | Sequence[str] | None") -> "Files":
        """Files from a mapping (named), a sequence (positional), a Snakemake ``Namedlist`` or ``None``."""
        if obj is None or isinstance(obj, (str, os.PathLike)):
            return cls([] if obj is None else [obj])
        if isinstance(obj, Files):
            return obj
        if isinstance(obj, Mapping):
            return cls(**obj)
        if hasattr(obj, "_names"):  # snakemake.io.Namedlist: its named entries, the others positional
            named = {k: (v if isinstance(v, str) else list(v)) for k, v in obj.items()}
            in_named = set(Files(**named))
            return cls([p for p in obj if p not in in_named], **named)
        return cls(obj)

    def __getattr__(self, name: str) -> str | list[str]:
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return self._named[name]
        except KeyError:
            raise AttributeError(f"no file named {name!r} (declared: {sorted(self._named)})") from None

    def __getitem__(self, key):  # type: ignore[override]
        return self.__getattr__(key) if isinstance(key, str) else super().__getitem__(key)


class Wildcards(dict):
    """The wildcards of a job (``wildcards.chunk`` or ``wildcards["chunk"]``)."""

    def __getattr__(self, name: str) -> str:
        try:
            return self[name]
        except KeyError:
            raise AttributeError(f"no wildcard {name!r} (have: {sorted(self)})") from None


# --------------------------------------------------------------------------- the step and its configuration


class MissingConfigKey(KeyError):
    """A step read a configuration key its rule does not give it."""

    def __str__(self) -> str:
        return str(self.args[0])


class StepConfig(dict):
    """The configuration a rule gives its step: the keys the step reads, nested as in the study's section.

    Reading a key that is not there raises :class:`MissingConfigKey` naming
    the full key (``p3.strategy.figure.window``) and where a rule lists the
    keys of its step, rather than a bare ``KeyError``.
    """

    def __init__(self, data: Mapping[str, Any] = (), where: str = "", path: tuple = ()):
        super().__init__((k, StepConfig(v, where, (*path, k)) if isinstance(v, Mapping) else v)
                         for k, v in dict(data).items())
        self._where, self._path = where, path

    def __missing__(self, key):
        name = ".".join(map(str, (*self._path, key)))
        raise MissingConfigKey(f"configuration key '{name}' is not among the keys the rule of step {self._where} "
                               f"gives it: add it to its params cfg=step_config(...) (workflow/rules/*.smk)")


# --------------------------------------------------------------------------- logging

class _StudyFormatter(logging.Formatter):
    """``[p1] message``: the study is the folder of :mod:`eqrec.studies` whose logger wrote the record."""

    def formatMessage(self, record: logging.LogRecord) -> str:
        return f"[{record.name.removeprefix('eqrec.studies.').split('.')[0]}] {record.message}"


@contextlib.contextmanager
def _log_handler(stream) -> Iterator[None]:
    """The studies' log records to ``stream`` as ``[study] message``; every logger as it was afterwards."""
    root = logging.getLogger("eqrec.studies")
    handler = logging.StreamHandler(stream)
    handler.setFormatter(_StudyFormatter())
    with contextlib.ExitStack() as restore:  # its callbacks run last first
        # a logging.config call elsewhere in this process (dictConfig's disable_existing_loggers, e.g. Snakemake's
        # API) may have disabled the studies' loggers: a step's log lines go out whatever ran before it
        for name, logger in list(logging.root.manager.loggerDict.items()):
            if name.startswith("eqrec.studies") and isinstance(logger, logging.Logger):
                restore.callback(setattr, logger, "disabled", logger.disabled)
                logger.disabled = False
        restore.callback(setattr, root, "propagate", root.propagate)
        restore.callback(root.setLevel, root.level)
        restore.callback(root.removeHandler, handler)
        root.addHandler(handler)
        root.setLevel(logging.INFO)
        root.propagate = False
        yield


@contextlib.contextmanager
def _fds_to(log_path: str | Path | None) -> Iterator[Any]:
    """Send standard output and error to ``log_path``: file descriptors 1 and 2 (solver output) and
    ``sys.stdout``/``sys.stderr`` (Python output).

    Yields a writable stream on the original standard error (for the one-line
    failure message), or ``sys.stderr`` when there is no log.
    """
    if log_path is None:
        yield sys.stderr
        return
    Path(log_path).parent.mkdir(parents=True, exist_ok=True)
    sys.stdout.flush()
    sys.stderr.flush()
    with contextlib.ExitStack() as stack:  # its callbacks run last first: Python's streams, fds, files
        stream = stack.enter_context(open(log_path, "w", buffering=1))
        terminal = stack.enter_context(os.fdopen(os.dup(2), "w"))
        for fd in (1, 2):
            saved = os.dup(fd)
            stack.callback(os.close, saved)
            stack.callback(os.dup2, saved, fd)
            os.dup2(stream.fileno(), fd)
        stack.enter_context(contextlib.redirect_stdout(stream))
        stack.enter_context(contextlib.redirect_stderr(stream))
        yield terminal


# --------------------------------------------------------------------------- running a step

def step_names(step: str) -> tuple[str, str]:
    """``(study, name)`` of a step path: ``"eqrec.studies.p1.steps:step_designs"`` -> ``("p1", "designs")``."""
    module, _, function = step.partition(":")
    parts = module.split(".")
    return parts[2] if len(parts) > 2 else module, function.removeprefix("step_")


def resolve_step(step: str, rule: str | None = None) -> Step:
    """The function of a step path (``"module:function"``, :func:`pkgutil.resolve_name`); a
    :class:`~eqrec.errors.StepError` naming the rule and the step otherwise."""
    where = f"rule {rule}: " if rule else ""
    if not step.startswith("eqrec.studies.") or ":" not in step:
        raise StepError(f"{where}step {step!r} is not the path of a step function, "
                        f"'eqrec.studies.<study>.<module>:<function>'")
    try:
        fn = pkgutil.resolve_name(step)
    except (ImportError, AttributeError) as exc:
        raise StepError(f"{where}step {step!r} does not resolve: {type(exc).__name__}: {exc}") from exc
    if not callable(fn):
        raise StepError(f"{where}step {step!r} is not a function")
    return fn


def run_step(step: str, cfg: Mapping[str, Any] | None = None, inputs=None, outputs=None,
             wildcards: Mapping[str, Any] | None = None, log: str | Path | None = None,
             rule: str | None = None) -> Any:
    """Run one step (as its rule would) and return what the step returns.

    ``step``: the path of the step's function (``"eqrec.studies.p1.steps:step_model"``).
    ``inputs``/``outputs``: mappings of names to paths (or lists), sequences, or
    :class:`Files`.  Output folders are created; after the step every declared
    output must exist.  With ``log``, the step's output goes to that file.
    Exceptions propagate (``run_from_snakemake`` turns them into an exit status).
    """
    fn = resolve_step(step, rule)
    study, name = step_names(step)
    outs = Files.of(outputs)
    wc = Wildcards({k: str(v) for k, v in (wildcards or {}).items()})
    for p in outs:
        Path(p).parent.mkdir(parents=True, exist_ok=True)
    log_ = get_logger(study)
    with _fds_to(log), _log_handler(sys.stderr):
        t0 = time.perf_counter()
        log_.info("step %s%s", name, "".join(f" {k}={v}" for k, v in wc.items()))
        given = StepConfig(cfg or {}, f"{study}.{name}", (study,) if study in SECTIONS else ())
        result = fn(given, Files.of(inputs), outs, wc)
        missing = [p for p in outs if not Path(p).exists()]
        if missing:
            raise StepError(f"step {study}.{name} did not write its declared outputs {missing}")
        log_.info("step %s done in %.2f s", name, time.perf_counter() - t0)
    return result


def failure_message(study: str, step: str, exc: BaseException) -> str:
    """One line naming the step and, for a configuration problem, the file and field."""
    head = f"[{study}] step {step} failed: "
    if isinstance(exc, InputError) and exc.field and study in SECTIONS and not isinstance(exc, ConfigError):
        field = exc.field if exc.field.startswith(f"{study}.") else f"{study}.{exc.field}"
        return (head + f"{exc} (configuration field '{field}' of {SECTIONS[study].config_file} "
                       f"or of a --configfile/--config override)")
    return head + f"{type(exc).__name__}: {exc}"


def run_from_snakemake(smk) -> None:
    """Entry point of ``workflow/scripts/run_step.py``: run the step its rule names; exit 1 on failure.

    The step's output (Python and solvers alike) goes to the rule's log file;
    a failure is logged with its traceback and reported on the terminal in
    one line (step, and for a configuration problem the file and field).
    """
    step = getattr(smk.params, "step", None)
    if step is None:  # the Snakefile's template, asked for by name (snakemake step)
        sys.exit(f"rule {smk.rule} runs no step of its own: it is the template of the rules that do "
                 "(use rule step as ... with:); ask for one of them, e.g. `snakemake p1`")
    with _fds_to(smk.log[0] if len(smk.log) else None) as terminal:
        try:
            run_step(step, getattr(smk.params, "cfg", {}), smk.input, smk.output, dict(smk.wildcards.items()),
                     rule=getattr(smk, "rule", None))
        except Exception as exc:
            msg = failure_message(*step_names(step), exc)
            traceback.print_exc()
            print(msg, file=sys.stderr, flush=True)
            if terminal is not sys.stderr:
                print(msg, file=terminal, flush=True)
            raise SystemExit(1) from None
