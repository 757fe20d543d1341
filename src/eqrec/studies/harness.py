"""The study harness: one entry point for every pipeline step.

Every Snakemake rule runs ``workflow/scripts/run_step.py``, which calls
:func:`run_from_snakemake`; the rule's ``params`` name the step
(``study``, ``step``) and carry ``cfg``, the study's configuration section
as Snakemake resolved it (config files, then ``--configfile``, then
``--config``; validated once, with the schema defaults filled in, by the
Snakefile through :func:`validate_config`).  Because ``cfg`` is a param, a
changed value re-plans exactly the jobs of that study.

A step is a plain function ``step(cfg, inputs, outputs, wildcards)`` listed
in its study module's ``STEPS`` table; :func:`registry` maps
``(study, step)`` to it.  Outside Snakemake::

    from eqrec.studies import harness
    cfg = harness.load_config("p1", "config/config.yaml", "my.yaml", overrides={"p1": {"mu1": 1.5}})
    harness.run_step("p1", "designs", cfg, outputs={"json": "designs.json"})

The harness owns what every step shares: the log (``[p1] message`` lines in
the rule's log file, progress lines on long sweeps), atomic writers (JSON,
NPZ, CSV, text, figures: a temporary file in the target's directory, then
``os.replace``; the temporary file is removed on failure; timing and memory
fields go to the step's ``timings`` output under ``results/timings/``, see
:data:`TIMING_KEYS`, so that everything else is byte-identical from run to
run), and the exit
status (a failing step exits 1 with one line naming the step and, for a
configuration problem, the file and field).
"""

from __future__ import annotations

import ast
import contextlib
import copy
import functools
import importlib
import json
import logging
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Iterator, Mapping, Sequence

import yaml

from eqrec.errors import EqrecError, InputError

#: Studies with pipeline steps (``claims`` builds the comparison table, ``notebooks`` executes the notebooks).
STUDIES = ("p1", "p2", "p3", "p4", "claims", "notebooks")


@dataclass(frozen=True)
class Section:
    """A configuration section: its default file and its JSON schema (paths relative to the workflow root)."""

    name: str
    config_file: str
    schema: str


#: The configuration sections; the Snakefile loads the same files (``configfile:``).
SECTIONS: dict[str, Section] = {
    "p1": Section("p1", "config/config.yaml", "config/schemas/p1.schema.yaml"),
    "p2": Section("p2", "config/p2.yaml", "config/schemas/p2.schema.yaml"),
    "p3": Section("p3", "config/p3.yaml", "config/schemas/p3.schema.yaml"),
    "p4": Section("p4", "config/p4.yaml", "config/schemas/p4.schema.yaml"),
}

Step = Callable[[dict, "Files", "Files", "Wildcards"], Any]


class ConfigError(InputError):
    """A configuration value that is invalid; the message names the file and the field."""


class StepError(EqrecError):
    """A step that did not do what its rule declares (e.g. an output not written)."""


# --------------------------------------------------------------------------- files and wildcards

class Files(Sequence[str]):
    """A step's inputs or outputs: positional paths plus named entries (a path or a list of paths).

    ``files.json``, ``files["json"]`` and ``files[0]`` work as on Snakemake's
    ``input``/``output`` objects.
    """

    def __init__(self, items: Iterable[str] = (), **named: str | Sequence[str]):
        self._named: dict[str, str | list[str]] = {}
        self._items = [str(p) for p in items]
        for key, val in named.items():
            if isinstance(val, (str, os.PathLike)):
                self._named[key] = str(val)
                self._items.append(str(val))
            else:
                self._named[key] = [str(v) for v in val]
                self._items.extend(self._named[key])

    @classmethod
    def of(cls, obj: "Files | Mapping[str, Any] | Sequence[str] | None") -> "Files":
        """Files from a mapping (named), a sequence (positional), a Snakemake ``Namedlist`` or ``None``."""
        if obj is None:
            return cls()
        if isinstance(obj, Files):
            return obj
        if isinstance(obj, Mapping):
            return cls(**obj)
        if hasattr(obj, "_names"):  # snakemake.io.Namedlist
            named = {k: (v if isinstance(v, str) else list(v)) for k, v in obj.items()}
            seen = {p for v in named.values() for p in ([v] if isinstance(v, str) else v)}
            return cls([p for p in obj if p not in seen], **named)
        if isinstance(obj, (str, os.PathLike)):
            return cls([obj])
        return cls(obj)

    def __getattr__(self, name: str) -> str | list[str]:
        if name.startswith("_"):
            raise AttributeError(name)
        try:
            return self._named[name]
        except KeyError:
            raise AttributeError(f"no file named {name!r} (declared: {sorted(self._named)})") from None

    def __getitem__(self, key):  # type: ignore[override]
        if isinstance(key, str):
            return self.__getattr__(key)
        return self._items[key]

    def __len__(self) -> int:
        return len(self._items)

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def names(self) -> list[str]:
        return list(self._named)

    def __repr__(self) -> str:
        return f"Files({self._items!r}, named={sorted(self._named)})"


class Wildcards(dict):
    """The wildcards of a job (``wildcards.chunk`` or ``wildcards["chunk"]``)."""

    def __getattr__(self, name: str) -> str:
        try:
            return self[name]
        except KeyError:
            raise AttributeError(f"no wildcard {name!r} (have: {sorted(self)})") from None


# --------------------------------------------------------------------------- registry

def _study_module(study: str):
    if study not in STUDIES:
        raise StepError(f"unknown study {study!r}; choose from {list(STUDIES)}")
    return importlib.import_module(f"eqrec.studies.{study}")


def registry(studies: Iterable[str] = STUDIES) -> dict[tuple[str, str], Step]:
    """``(study, step) -> function`` for every step of the given studies."""
    return {(s, name): fn for s in studies for name, fn in _study_module(s).STEPS.items()}


def get_step(study: str, step: str) -> Step:
    steps = _study_module(study).STEPS
    if step not in steps:
        raise StepError(f"study {study!r} has no step {step!r}; steps: {sorted(steps)}")
    return steps[step]


# --------------------------------------------------------------------------- logging

class _StudyFormatter(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        parts = record.name.split(".")
        study = parts[2] if len(parts) > 2 and parts[:2] == ["eqrec", "studies"] else parts[-1]
        msg = record.getMessage()
        if record.exc_info:
            msg += "\n" + self.formatException(record.exc_info)
        return f"[{study}] {msg}"


def get_logger(study: str) -> logging.Logger:
    """The logger of a study's steps; the harness prints its records as ``[study] message``."""
    return logging.getLogger(f"eqrec.studies.{study}")


class Progress:
    """Progress lines for a long sweep: ``[p2] heat map theorem2 chunk 0: 31/124 points (2.1 s)``.

    Logs at every tenth of the work (and at the end).
    """

    def __init__(self, log: logging.Logger, total: int, what: str, unit: str = "points"):
        self.log, self.total, self.what, self.unit = log, max(int(total), 0), what, unit
        self.done, self.t0 = 0, time.perf_counter()
        self._next = 1 if self.total else 0
        self._stride = max(1, self.total // 10)

    def advance(self, n: int = 1) -> None:
        self.done += n
        if self.done >= self._next or self.done >= self.total:
            self._next = self.done + self._stride
            self.log.info("%s: %d/%d %s (%.1f s)", self.what, self.done, self.total, self.unit,
                          time.perf_counter() - self.t0)


@contextlib.contextmanager
def _log_handler(stream) -> Iterator[None]:
    root = logging.getLogger("eqrec.studies")
    handler = logging.StreamHandler(stream)
    handler.setFormatter(_StudyFormatter())
    old_level, old_propagate = root.level, root.propagate
    root.addHandler(handler)
    root.setLevel(logging.INFO)
    root.propagate = False
    try:
        yield
    finally:
        handler.flush()
        root.removeHandler(handler)
        root.setLevel(old_level)
        root.propagate = old_propagate


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
    Path(log_path).write_text("")
    sys.stdout.flush()
    sys.stderr.flush()
    saved_fds = os.dup(1), os.dup(2)
    saved_streams = sys.stdout, sys.stderr
    fd = os.open(log_path, os.O_WRONLY | os.O_APPEND)
    stream = open(log_path, "a", buffering=1)
    terminal = os.fdopen(os.dup(saved_fds[1]), "w")
    try:
        os.dup2(fd, 1)
        os.dup2(fd, 2)
        sys.stdout = sys.stderr = stream
        yield terminal
    finally:
        stream.flush()
        sys.stdout, sys.stderr = saved_streams
        os.dup2(saved_fds[0], 1)
        os.dup2(saved_fds[1], 2)
        for f in (*saved_fds, fd):
            os.close(f)
        stream.close()
        terminal.close()


# --------------------------------------------------------------------------- running a step

def run_step(study: str, step: str, cfg: Mapping[str, Any] | None = None, inputs=None, outputs=None,
             wildcards: Mapping[str, Any] | None = None, log: str | Path | None = None) -> Any:
    """Run one step (as its rule would) and return what the step returns.

    ``inputs``/``outputs``: mappings of names to paths (or lists), sequences, or
    :class:`Files`.  Output folders are created; after the step every declared
    output must exist.  With ``log``, the step's output goes to that file.
    Exceptions propagate (``run_from_snakemake`` turns them into an exit status).
    """
    fn = get_step(study, step)
    ins, outs = Files.of(inputs), Files.of(outputs)
    wc = Wildcards({k: str(v) for k, v in (wildcards or {}).items()})
    for p in outs:
        Path(p).parent.mkdir(parents=True, exist_ok=True)
    log_ = get_logger(study)
    with _fds_to(log) as _, _log_handler(sys.stderr):
        t0 = time.perf_counter()
        log_.info("step %s%s", step, "".join(f" {k}={v}" for k, v in wc.items()))
        result = fn(dict(cfg or {}), ins, outs, wc)
        missing = [p for p in outs if not Path(p).exists()]
        if missing:
            raise StepError(f"step {study}.{step} did not write its declared outputs {missing}")
        log_.info("step %s done in %.2f s", step, time.perf_counter() - t0)
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
    study, step = smk.params.study, smk.params.step
    cfg = smk.params.cfg if "cfg" in smk.params.keys() else {}
    log = smk.log[0] if len(smk.log) else None
    with _fds_to(log) as terminal:
        try:
            run_step(study, step, cfg, smk.input, smk.output, dict(smk.wildcards.items()))
        except Exception as exc:
            import traceback

            msg = failure_message(study, step, exc)
            traceback.print_exc()
            print(msg, file=sys.stderr, flush=True)
            if terminal is not sys.stderr:
                print(msg, file=terminal, flush=True)
            failed = True
        else:
            failed = False
    if failed:
        raise SystemExit(1)


# --------------------------------------------------------------------------- configuration

def deep_merge(base: dict, update: Mapping) -> dict:
    """Merge ``update`` into ``base`` recursively, in place (as Snakemake merges config files)."""
    for key, val in update.items():
        if isinstance(val, Mapping) and isinstance(base.get(key), dict):
            deep_merge(base[key], val)
        else:
            base[key] = copy.deepcopy(val) if isinstance(val, (dict, list)) else val
    return base


def _resolve_ref(schema: Mapping, root: Mapping) -> dict:
    """A schema with ``$ref`` (to ``#/$defs/...``) merged with its own keywords; ``properties`` merged per key."""
    base = dict(root.get("$defs", {}).get(schema["$ref"].split("/")[-1], {}))
    own = {k: v for k, v in schema.items() if k != "$ref"}
    props = {**base.get("properties", {})}
    for key, sub in own.get("properties", {}).items():
        props[key] = {**props.get(key, {}), **sub}
    return {**base, **own, **({"properties": props} if props else {})}


def _schema_types(schema: Mapping, root: Mapping) -> set[str]:
    """JSON types a (sub)schema admits (through ``$ref`` and ``anyOf``/``oneOf``)."""
    if "$ref" in schema:
        return _schema_types(_resolve_ref(schema, root), root)
    types = schema.get("type", [])
    out = set([types] if isinstance(types, str) else types)
    for alt in schema.get("anyOf", []) + schema.get("oneOf", []):
        out |= _schema_types(alt, root)
    return out


def _subschema(schema: Mapping, root: Mapping, key: Any) -> Mapping:
    if "$ref" in schema:
        schema = _resolve_ref(schema, root)
    if isinstance(key, int):
        return schema.get("items", {}) if isinstance(schema.get("items"), Mapping) else {}
    props = schema.get("properties", {})
    if key in props:
        return props[key]
    extra = schema.get("additionalProperties")
    return extra if isinstance(extra, Mapping) else {}


def type_cli_config(config: dict, cli_config: Mapping | None, root: str | Path = ".") -> dict:
    """Give nested ``--config`` values the types their schema asks for (in place).

    Snakemake reads a nested ``--config p1='{mu1: 1.5}'`` with YAML's base
    loader, so ``1.5`` arrives as the text ``"1.5"``.  Where the schema of the
    field wants a number (integer, boolean) and the text reads as one, the
    resolved value becomes that number; everything else is left for the schema
    to judge (``abc`` stays text and fails).  Values from config files are
    untouched: a quoted ``"0.1"`` there is text and is rejected.
    """
    def walk(cli: Any, cur: Any, schema: Mapping, top: Mapping) -> Any:
        if isinstance(cli, Mapping) and isinstance(cur, dict):
            for k, v in cli.items():
                if k in cur:
                    cur[k] = walk(v, cur[k], _subschema(schema, top, k), top)
            return cur
        if isinstance(cli, list) and isinstance(cur, list) and len(cli) == len(cur):
            return [walk(a, b, _subschema(schema, top, i), top) for i, (a, b) in enumerate(zip(cli, cur))]
        if isinstance(cli, str) and cur == cli:
            wanted = _schema_types(schema, top)
            with contextlib.suppress(yaml.YAMLError):
                val = yaml.safe_load(cli)
                if isinstance(val, bool):
                    return val if "boolean" in wanted else cur
                if isinstance(val, int) and wanted & {"integer", "number"}:
                    return val
                if isinstance(val, float) and "number" in wanted:
                    return val
        return cur

    for section, sec in SECTIONS.items():
        if cli_config and section in cli_config and section in config:
            schema = yaml.safe_load((Path(root) / sec.schema).read_text())
            walk(cli_config[section], config[section], schema, schema)
    return config


def _has_path(data: Any, path: Sequence[Any]) -> bool:
    for p in path:
        if isinstance(data, Mapping) and p in data:
            data = data[p]
        elif isinstance(data, list) and isinstance(p, int) and p < len(data):
            data = data[p]
        else:
            return False
    return True


def _display(path: str | Path) -> str:
    p = Path(path)
    with contextlib.suppress(ValueError):
        return str(p.resolve().relative_to(Path.cwd().resolve()))
    return str(p)


def field_source(section: str, path: Sequence[Any], configfiles: Sequence[str | Path] = (),
                 overrides: Mapping | None = None) -> str:
    """Where the value at ``section.path`` comes from: ``--config``, the last ``--configfile`` setting it,
    or the section's default file."""
    full = [section, *path]
    if overrides and _has_path(overrides, full):
        return "--config"
    for f in reversed(list(configfiles)):
        with contextlib.suppress(OSError, yaml.YAMLError):
            if _has_path(yaml.safe_load(Path(f).read_text()) or {}, full):
                return _display(f)
    return SECTIONS[section].config_file


def _schema_error(data: dict, schema_path: Path):
    """The structured first error jsonschema reports (to name the field)."""
    import jsonschema

    schema = yaml.safe_load(schema_path.read_text())
    errors = sorted(jsonschema.Draft202012Validator(schema).iter_errors(data), key=lambda e: list(e.absolute_path))
    return errors[0] if errors else None


def validate_section(config: dict, section: str, root: str | Path = ".", configfiles: Sequence[str | Path] = (),
                     overrides: Mapping | None = None) -> dict:
    """Validate ``config[section]`` in place against its schema, filling in the schema defaults.

    Uses ``snakemake.utils.validate(..., set_default=True)`` (what a Snakefile
    does), then the study's ``check_config`` for what a schema cannot say
    (cross-field conditions).  Raises :class:`ConfigError` naming the file
    (default file, ``--configfile`` or ``--config``) and the field.
    """
    from snakemake.exceptions import WorkflowError
    from snakemake.utils import validate

    sec = SECTIONS[section]
    schema = (Path(root) / sec.schema).resolve()
    data = config.get(section)
    if not isinstance(data, dict):
        raise ConfigError(f"section '{section}' missing or not a mapping", sec.config_file, section)
    try:
        validate(data, str(schema), set_default=True)
    except WorkflowError as exc:
        err = _schema_error(data, schema)
        if err is None:
            raise ConfigError(f"does not satisfy {sec.schema}: {exc}", sec.config_file, section) from None
        path = list(err.absolute_path)
        field = ".".join([section, *map(str, path)])
        where = field_source(section, path, configfiles, overrides)
        raise ConfigError(f"{err.message} (schema {sec.schema})", where, field) from None
    from eqrec.studies.config_checks import CHECKS  # light imports: the Snakefile runs this at every job start

    check = CHECKS.get(section)
    if check is not None:
        try:
            check(data)
        except InputError as exc:
            rel = exc.field or ""
            path = [int(p) if p.isdigit() else p for p in rel.split(".") if p]
            msg = str(exc)
            if exc.field and msg.startswith(f"field '{exc.field}': "):
                msg = msg[len(f"field '{exc.field}': "):]
            raise ConfigError(msg, field_source(section, path, configfiles, overrides),
                              ".".join([section, *map(str, path)])) from None
    return data


def check_sections(config: Mapping, configfiles: Sequence[str | Path] = (), overrides: Mapping | None = None) -> None:
    """Refuse a top-level configuration key that is not a section (``p1`` .. ``p4``), naming where it came from.

    Snakemake merges every ``--configfile`` and ``--config`` into one
    mapping; a misspelt section (``p2x:``) or an unknown one (``--config
    p5=...``) would otherwise be ignored silently.
    """
    unknown = sorted(set(config) - set(SECTIONS), key=str)
    if not unknown:
        return
    key = unknown[0]
    source = "--config" if overrides and key in overrides else "the configuration"
    if source != "--config":
        for f in configfiles:
            try:
                data = yaml.safe_load(Path(f).read_text()) or {}
            except (OSError, yaml.YAMLError):
                continue
            if isinstance(data, Mapping) and key in data:
                source = _display(f)
    more = f" (and {', '.join(map(repr, unknown[1:]))})" if len(unknown) > 1 else ""
    raise ConfigError(f"unknown configuration section {key!r}{more}; the sections are {list(SECTIONS)}",
                      source, str(key))


def validate_config(config: dict, root: str | Path = ".", configfiles: Sequence[str | Path] = (),
                    overrides: Mapping | None = None, sections: Iterable[str] = tuple(SECTIONS)) -> dict:
    """Validate every section of a resolved configuration (in place, defaults filled in); no unknown section."""
    check_sections(config, configfiles, overrides)
    for s in sections:
        validate_section(config, s, root, configfiles, overrides)
    return config


def load_config(study: str, *files: str | Path, overrides: Mapping | None = None,
                root: str | Path = ".") -> dict:
    """The validated configuration section of ``study``, resolved as Snakemake would.

    ``files`` are merged in order (default: the section's file under ``root``;
    give it first and then your own files, like ``configfile:`` then
    ``--configfile``); ``overrides`` (like ``--config``) last.  Schema defaults
    are filled in; errors name the file and the field.
    """
    paths = [Path(f) for f in files] or [Path(root) / SECTIONS[study].config_file]
    merged: dict = {}
    for p in paths:
        try:
            data = yaml.safe_load(p.read_text()) or {}
        except OSError as exc:
            raise ConfigError(f"cannot read: {exc.strerror}", str(p)) from None
        if not isinstance(data, dict):
            raise ConfigError("must be a mapping of sections", str(p))
        deep_merge(merged, data)
    deep_merge(merged, overrides or {})
    validate_section(merged, study, root, [str(p) for p in paths[1:]] or [str(paths[0])], overrides)
    return merged[study]


def section_params(config: Mapping, section: str) -> dict:
    """A section as a rule param: keys sorted recursively, so that only a changed value re-plans jobs."""
    def canon(x):
        if isinstance(x, Mapping):
            return {k: canon(x[k]) for k in sorted(x)}
        if isinstance(x, list):
            return [canon(v) for v in x]
        return x
    return canon(config[section])


# --------------------------------------------------------------------------- code inputs

def _package_root() -> Path:
    local = Path("src") / "eqrec"
    return local if local.is_dir() else Path(__file__).resolve().parents[1]


#: Modules the harness runs when the workflow is planned (configuration checks), never inside a step: not code
#: inputs of any rule (a changed check re-validates the configuration at the next start).
PLANNING_ONLY = frozenset({"eqrec.studies.config_checks"})


def code_inputs(study: str) -> list[str]:
    """Source files of ``eqrec.studies.<study>`` and of every ``eqrec`` module it imports, transitively,
    plus the harness that runs it.

    A rule lists these as inputs, so editing code a study does not import (e.g.
    the LMV code for P1) does not re-run its jobs.  Imports are read with
    :mod:`ast` (nothing is imported).
    """
    pkg = _package_root()

    def path_of(name: str) -> Path | None:
        parts = name.split(".")
        if parts[0] != "eqrec":
            return None
        base = pkg.joinpath(*parts[1:])
        for cand in (base.with_suffix(".py"), base / "__init__.py"):
            if cand.is_file():
                return cand
        return None

    seen: set[Path] = set()
    todo = [f"eqrec.studies.{study}", "eqrec.studies.harness"]
    while todo:
        name = todo.pop()
        if name in PLANNING_ONLY:
            continue
        path = path_of(name)
        if path is None or path in seen:
            continue
        seen.add(path)
        # a package's modules import their package's __init__ first
        parent = name.rpartition(".")[0]
        if parent:
            todo.append(parent)
        todo += _eqrec_imports(path, path.stat().st_mtime_ns)
    return sorted(str(p) for p in seen)


@functools.lru_cache(maxsize=None)
def _eqrec_imports(path: Path, mtime_ns: int) -> list[str]:
    """The ``eqrec`` modules (and imported names) one source file imports; parsed once per file version."""
    out: list[str] = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("eqrec"):
            out.append(node.module)
            out += [f"{node.module}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            out += [a.name for a in node.names if a.name.startswith("eqrec")]
    return out


# --------------------------------------------------------------------------- atomic writers

_UMASK = os.umask(0)
os.umask(_UMASK)


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success move it onto ``path``, on failure remove it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_UMASK)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def _json_default(obj: Any) -> Any:
    import numpy as np

    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return float(obj)
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (set, tuple)):
        return list(obj)
    raise TypeError(f"cannot write {type(obj).__name__} as JSON")


# --------------------------------------------------------------------------- timings

#: Keys of the values that change from run to run (wall-clock times, memory peaks).  A step
#: writes them to its ``timings`` output (under ``results/timings/``), never next to the
#: results, so that two runs give byte-identical ``results/`` outside ``results/timings/``.
TIMING_KEYS = frozenset({
    "build_s", "solve_s", "total_s", "time_s", "global_s", "ipopt_s", "run_time_s", "elapsed_s",
    "prefix_time_s", "time_time_s", "strategy_time_s",
    "build_time", "solve_time", "tree_time", "classes_time", "wall_time", "peak_mb",
})


#: ``write_csv(..., timings=INTERMEDIATE)``: a temporary output (a sweep chunk) keeps its timing columns;
#: the step that merges the chunks splits them off.
INTERMEDIATE = "intermediate"


def timings_of(paths: Iterable[str]) -> list[str]:
    """The timings file a step writes beside each of its results files: ``results/x`` -> ``results/timings/x``."""
    return [str(p).replace("results/", "results/timings/", 1) for p in paths]


def split_timings(data: Any) -> tuple[Any, Any]:
    """Split nested JSON-like ``data`` into ``(rest, timings)``.

    A mapping entry whose key is in :data:`TIMING_KEYS` goes, whole, to
    ``timings``, at the same place in the nesting (lists keep their length,
    with ``None`` where an item has no timing).  ``timings`` is ``None`` when
    ``data`` holds none.  :func:`merge_timings` undoes the split.
    """
    if isinstance(data, Mapping):
        rest, timed = {}, {}
        for key, val in data.items():
            if key in TIMING_KEYS:
                timed[key] = val
                continue
            rest[key], sub = split_timings(val)
            if sub is not None:
                timed[key] = sub
        return rest, (timed or None)
    if isinstance(data, (list, tuple)):
        parts = [split_timings(v) for v in data]
        timed_items = [t for _, t in parts]
        return [r for r, _ in parts], (timed_items if any(t is not None for t in timed_items) else None)
    return data, None


def merge_timings(data: Any, timings: Any) -> Any:
    """Put the ``timings`` written by :func:`split_timings` back into ``data`` (in place; returns ``data``)."""
    if timings is None:
        return data
    if isinstance(timings, Mapping) and isinstance(data, dict):
        for key, val in timings.items():
            if key in TIMING_KEYS or key not in data:
                data[key] = val
            else:
                data[key] = merge_timings(data[key], val)
        return data
    if isinstance(timings, list) and isinstance(data, list) and len(timings) == len(data):
        return [merge_timings(d, t) for d, t in zip(data, timings)]
    raise StepError("timings file does not match its results file (run the workflow again)")


def split_timing_columns(frame, keys: Sequence[str]):
    """``(rest, timings)`` of a table: the :data:`TIMING_KEYS` columns go to ``timings``, with the ``keys`` columns
    that identify a row."""
    timed = [c for c in frame.columns if c in TIMING_KEYS]
    return frame.drop(columns=timed), frame[[*keys, *timed]]


def write_text(path: str | Path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def _json_text(data: Any) -> str:
    return json.dumps(data, indent=2, default=_json_default) + "\n"


def write_json(path: str | Path, data: Any, timings: str | Path | None = None) -> None:
    """JSON with two-space indent and a final newline; numpy scalars and arrays as numbers and lists.

    Timing and memory entries (:data:`TIMING_KEYS`) go to the file ``timings``
    (the step's ``timings`` output, under ``results/timings/``), the rest to
    ``path``; a step that records timings without declaring where is an error.
    """
    rest, timed = split_timings(json.loads(_json_text(data)))
    if timed is not None and timings is None:
        keys = sorted(_timing_keys_in(timed))
        raise StepError(f"{path}: timing fields {keys} need a timings output (results/timings/...)")
    if timings is not None:
        write_text(timings, _json_text(timed if timed is not None else {}))
    write_text(path, _json_text(rest))


def _timing_keys_in(timed: Any) -> set[str]:
    if isinstance(timed, Mapping):
        return {k for k in timed if k in TIMING_KEYS} | {x for v in timed.values() for x in _timing_keys_in(v)}
    if isinstance(timed, list):
        return {x for v in timed for x in _timing_keys_in(v)}
    return set()


def read_json(path: str | Path, timings: str | Path | None = None) -> Any:
    """A results JSON file, with its timings (the file written by :func:`write_json`) put back when given."""
    data = json.loads(Path(path).read_text())
    if timings is not None:
        data = merge_timings(data, json.loads(Path(timings).read_text()))
    return data


def write_npz(path: str | Path, compressed: bool = False, **arrays: Any) -> None:
    import numpy as np

    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            (np.savez_compressed if compressed else np.savez)(fh, **arrays)


def write_csv(path: str | Path, frame, timings: str | Path | None = None, keys: Sequence[str] = (),
              **kwargs: Any) -> None:
    """A pandas frame as CSV (``index=False`` unless given).

    Timing and memory columns (:data:`TIMING_KEYS`) go to the CSV ``timings``
    with the ``keys`` columns that identify a row; the rest to ``path``.
    """
    kwargs.setdefault("index", False)
    if timings == INTERMEDIATE:
        with atomic_path(path) as tmp:
            frame.to_csv(tmp, **kwargs)
        return
    rest, timed = split_timing_columns(frame, keys)
    if timed.shape[1] > len(keys):
        if timings is None:
            raise StepError(f"{path}: timing columns {list(timed.columns[len(keys):])} need a timings output")
        with atomic_path(timings) as tmp:
            timed.to_csv(tmp, **kwargs)
    elif timings is not None:
        with atomic_path(timings) as tmp:
            timed.to_csv(tmp, **kwargs)
    with atomic_path(path) as tmp:
        rest.to_csv(tmp, **kwargs)


def save_figure(fig, *paths: str | Path) -> None:
    """Save a figure to each path (format from the suffix: PDF, PNG, ...) atomically, then close it.

    PDFs carry no creation date, so an unchanged figure is byte-identical.
    """
    import matplotlib.pyplot as plt

    try:
        for p in paths:
            fmt = Path(p).suffix.lstrip(".").lower()
            meta = {"CreationDate": None} if fmt == "pdf" else None
            with atomic_path(p) as tmp:
                fig.savefig(tmp, format=fmt, metadata=meta)
    finally:
        plt.close(fig)
