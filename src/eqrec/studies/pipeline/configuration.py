"""The workflow's configuration: sections, one schema, overrides, validation.

Snakemake merges the configuration files (``configfile:``), ``--configfile``
and ``--config``; the Snakefile then calls :func:`type_cli_config` (nested
``--config`` values arrive as text) and :func:`validate_config`: one
``snakemake.utils.validate(config, "config/schemas/config.schema.yaml",
set_default=True)`` of the whole configuration (the top-level schema refers to
one schema per section; every object is closed, so an unknown section or key
is refused like a bad value), then the study's cross-field checks
(:mod:`eqrec.studies.pipeline.checks`).  Errors name the file (default file,
``--configfile`` or ``--config``) and the field.  Outside Snakemake::

    from eqrec.studies.pipeline import configuration
    cfg = configuration.load_config("p1", "config/config.yaml", "my.yaml", overrides={"p1": {"mu1": 1.5}})
"""

from __future__ import annotations

import contextlib
import copy
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Mapping, Sequence

import yaml

from eqrec.errors import InputError

#: The schema of the whole configuration (relative to the workflow root); it refers to ``<section>.schema.yaml``.
SCHEMA = "config/schemas/config.schema.yaml"


@dataclass(frozen=True)
class Section:
    """A configuration section and its default file (relative to the workflow root)."""

    name: str
    config_file: str


#: The configuration sections; the Snakefile loads the same files (``configfile:``).
SECTIONS: dict[str, Section] = {s.name: s for s in (
    Section("p1", "config/config.yaml"), Section("p2", "config/p2.yaml"), Section("p3", "config/p3.yaml"),
    Section("p4", "config/p4.yaml"), Section("compare", "config/compare.yaml"))}

#: The module of a study (a section) whose ``@reason`` functions word its claims, where it has one
#: (:mod:`eqrec.studies.claims.reasons`; the claims table imports it by name).
CLAIMS_MODULE = "eqrec.studies.{}.claims"


class ConfigError(InputError):
    """A configuration value that is invalid; the message names the file and the field."""


def _schema_errors(config: Mapping, root: str | Path) -> Any:
    """Every error of ``config`` against :data:`SCHEMA` (jsonschema's ``iter_errors``; no defaults filled in)."""
    import jsonschema
    import referencing

    schemas = Path(root, SCHEMA).parent
    registry = referencing.Registry(  # the section schemas, by the relative name the top-level schema gives
        retrieve=lambda uri: referencing.Resource.from_contents(yaml.safe_load((schemas / uri).read_text())))
    top = yaml.safe_load(Path(root, SCHEMA).read_text())
    return jsonschema.Draft202012Validator(top, registry=registry).iter_errors(config)


def type_cli_config(config: dict, cli_config: Mapping | None, root: str | Path = ".") -> dict:
    """Give nested ``--config`` values the types their schema asks for (in place).

    Snakemake reads a nested ``--config p1='{mu1: 1.5}'`` with YAML's base
    loader, so ``1.5`` arrives as the text ``"1.5"``.  Where the schema refuses
    such a text for its type (a ``type``, ``anyOf`` or ``oneOf`` error at or
    above it) and the text reads as a number, boolean or null, the resolved
    value becomes that; everything else is left for the validation to judge
    (``abc`` stays text and fails).  Values from config files are untouched: a
    quoted ``"0.1"`` there is text and is rejected.
    """
    wrong = [tuple(e.absolute_path) for e in _schema_errors(config, root) if e.validator in ("type", "anyOf", "oneOf")]
    for path, text in _leaves(cli_config or {}):
        if isinstance(text, str) and _at(config, path) == text and any(path[:len(w)] == w for w in wrong):
            with contextlib.suppress(yaml.YAMLError):
                val = yaml.safe_load(text)
                if val is None or isinstance(val, (int, float)):  # a bool is an int
                    _at(config, path[:-1])[path[-1]] = val
    return config


def _leaves(data: Any, path: tuple = ()) -> Iterator[tuple[tuple, Any]]:
    """``(path, value)`` of every leaf of nested mappings and lists."""
    if not isinstance(data, (Mapping, list)):
        yield path, data
        return
    for key, val in (data.items() if isinstance(data, Mapping) else enumerate(data)):
        yield from _leaves(val, (*path, key))


#: What :func:`_at` gives for a path the data does not have.
_ABSENT = object()


def _at(data: Any, path: Sequence[Any]) -> Any:
    """The value at ``path`` of nested mappings and lists, or :data:`_ABSENT`."""
    for p in path:
        try:
            data = data[p]
        except (KeyError, IndexError, TypeError):
            return _ABSENT
    return data


def _display(path: str | Path) -> str:
    p = Path(path)
    with contextlib.suppress(ValueError):
        return str(p.resolve().relative_to(Path.cwd().resolve()))
    return str(p)


def field_source(path: Sequence[Any], configfiles: Sequence[str | Path] = (), overrides: Mapping | None = None) -> str:
    """Where the value at ``path`` (section first) comes from: ``--config``, the last ``--configfile`` setting it,
    or the section's default file."""
    if overrides and _at(overrides, path) is not _ABSENT:
        return "--config"
    for f in reversed(list(configfiles)):
        with contextlib.suppress(OSError, yaml.YAMLError):
            if _at(yaml.safe_load(Path(f).read_text()) or {}, path) is not _ABSENT:
                return _display(f)
    return SECTIONS[path[0]].config_file if path and path[0] in SECTIONS else "the configuration"


def _config_error(err: Any, configfiles: Sequence[str | Path], overrides: Mapping | None) -> ConfigError:
    """The jsonschema error ``err`` as a :class:`ConfigError` naming the file and the field (an unknown key's own),
    with the failing field's ``description`` from the schema when it has one."""
    path, msg = list(err.absolute_path), err.message
    if err.validator == "additionalProperties":
        known = list(err.schema.get("properties", {}))
        path.append(min((k for k in err.instance if k not in known), key=str))
        msg = f"unknown {'configuration section' if len(path) == 1 else 'key'} {path[-1]!r} (known: {', '.join(known)})"
    elif "description" in err.schema:  # what the failing field is for, from the schema
        msg = f"{msg}: {err.schema['description']}"
    schema = f"config/schemas/{path[0]}.schema.yaml" if path and path[0] in SECTIONS else SCHEMA
    return ConfigError(f"{msg} (schema {schema})", field_source(path, configfiles, overrides), ".".join(map(str, path)))


def validate_config(config: dict, root: str | Path = ".", configfiles: Sequence[str | Path] = (),
                    overrides: Mapping | None = None) -> dict:
    """Validate a resolved configuration in place, filling in the schema defaults; no unknown section or key.

    One ``snakemake.utils.validate(config, SCHEMA, set_default=True)`` (what a
    Snakefile does; each section's defaults then filled from its own schema),
    then each section's cross-field checks (``checks.CHECKS``) for what a
    schema cannot say.  Raises :class:`ConfigError` naming
    the file (default file, ``--configfile`` or ``--config``) and the field.
    """
    from jsonschema import ValidationError
    from snakemake.exceptions import WorkflowError
    from snakemake.utils import validate

    top = Path(root, SCHEMA).resolve()
    try:
        validate(config, str(top), set_default=True)
        # jsonschema leaves snakemake's default-filling validator where a $ref enters a file that names its
        # $schema (python-jsonschema#1341): each section's defaults are filled from its own schema
        for section, data in config.items():
            validate(data, str(top.with_name(f"{section}.schema.yaml")), set_default=True)
    except WorkflowError as exc:
        if not isinstance(exc.__context__, ValidationError):  # an unreadable schema
            raise ConfigError(str(exc), SCHEMA) from None
        raise _config_error(exc.__context__, configfiles, overrides) from None
    from eqrec.studies.pipeline.checks import CHECKS  # light imports: the Snakefile runs this at every job start

    for section, data in config.items():
        try:
            CHECKS[section](data)
        except InputError as exc:
            path = [section, *(int(p) if p.isdigit() else p for p in (exc.field or "").split(".") if p)]
            raise ConfigError(str(exc).removeprefix(f"field '{exc.field}': "),
                              field_source(path, configfiles, overrides), ".".join(map(str, path))) from None
    return config


def validate_section(config: dict, section: str, root: str | Path = ".", configfiles: Sequence[str | Path] = (),
                     overrides: Mapping | None = None) -> dict:
    """Validate ``config[section]`` alone, in place with its defaults filled in (see :func:`validate_config`)."""
    if not isinstance(config.get(section), dict):
        raise ConfigError(f"section '{section}' missing or not a mapping", SECTIONS[section].config_file, section)
    validate_config({section: config[section]}, root, configfiles, overrides)
    return config[section]


def load_config(study: str, *files: str | Path, overrides: Mapping | None = None,
                root: str | Path = ".") -> dict:
    """The validated configuration section of ``study``, resolved as Snakemake would.

    ``files`` are merged in order (default: the section's file under ``root``;
    give it first and then your own files, like ``configfile:`` then
    ``--configfile``); ``overrides`` (like ``--config``) last.  Schema defaults
    are filled in; errors name the file and the field.
    """
    from snakemake.utils import update_config

    paths = [Path(f) for f in files] or [Path(root) / SECTIONS[study].config_file]
    merged: dict = {}
    for p in paths:
        try:
            data = yaml.safe_load(p.read_text()) or {}
        except OSError as exc:
            raise ConfigError(f"cannot read: {exc.strerror}", str(p)) from None
        if not isinstance(data, dict):
            raise ConfigError("must be a mapping of sections", str(p))
        update_config(merged, data)
    update_config(merged, copy.deepcopy(overrides or {}))
    return validate_section(merged, study, root, [str(p) for p in paths[1:]] or [str(paths[0])], overrides)


def step_params(config: Mapping, section: str, *keys: str) -> dict:
    """The configuration keys one step reads, as its rule's ``cfg`` param.

    ``keys`` name values of ``config[section]`` by their dotted path (``"mu1"``,
    ``"heatmap.solver"``, or a whole subtree such as ``"strategy.figure"``); the
    result keeps the section's nesting (the step reads ``cfg["strategy"]["figure"]``
    as before) with keys sorted recursively, so that a job is re-planned only
    when a value its step reads changes.  A key the section does not have
    raises :class:`ConfigError` (a misspelt key in a rule).  The rules call it
    through ``step_config(section, "mu1 heatmap.solver", strategy="figure")``
    (``workflow/rules/common.smk``: space-separated paths, keys of one subtree by name).
    """
    def canon(x):
        if isinstance(x, Mapping):
            return {k: canon(x[k]) for k in sorted(x)}
        if isinstance(x, list):
            return [canon(v) for v in x]
        return x

    out: dict = {}
    for key in keys:
        *parents, leaf = key.split(".")
        value = _at(config[section], (*parents, leaf))
        if value is _ABSENT:
            raise ConfigError(f"a rule asks for configuration key '{section}.{key}', which the section has not",
                              SECTIONS[section].config_file, f"{section}.{key}")
        dst = out
        for part in parents:
            dst = dst.setdefault(part, {})
        dst[leaf] = value
    return canon(out)
