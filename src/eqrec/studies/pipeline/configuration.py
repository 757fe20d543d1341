"""The workflow's configuration: sections, schemas, overrides, validation.

Snakemake merges the configuration files (``configfile:``), ``--configfile``
and ``--config``; the Snakefile then calls :func:`type_cli_config` (nested
``--config`` values arrive as text), :func:`check_sections` (no unknown
section) and :func:`validate_section` per section: the section's JSON schema
with its defaults filled in, then the study's cross-field checks
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
from typing import Any, Iterable, Mapping, Sequence

import yaml

from eqrec.errors import InputError

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
    "compare": Section("compare", "config/compare.yaml", "config/schemas/compare.schema.yaml"),
}


class ConfigError(InputError):
    """A configuration value that is invalid; the message names the file and the field."""


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
    from eqrec.studies.pipeline.checks import CHECKS  # light imports: the Snakefile runs this at every job start

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
    """Refuse a top-level configuration key that is not a section (``p1`` .. ``p4``, ``compare``), naming where it
    came from.

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


def step_params(config: Mapping, section: str, *keys: str) -> dict:
    """The configuration keys one step reads, as its rule's ``cfg`` param.

    ``keys`` name values of ``config[section]`` by their dotted path (``"mu1"``,
    ``"heatmap.solver"``, or a whole subtree such as ``"strategy.figure"``); the
    result keeps the section's nesting (the step reads ``cfg["strategy"]["figure"]``
    as before) with keys sorted recursively, so that a job is re-planned only
    when a value its step reads changes.  A key the section does not have
    raises :class:`ConfigError` (a misspelt key in a rule).  The rules call it
    as ``step_config(section, *keys)`` (``workflow/rules/common.smk``).
    """
    def canon(x):
        if isinstance(x, Mapping):
            return {k: canon(x[k]) for k in sorted(x)}
        if isinstance(x, list):
            return [canon(v) for v in x]
        return x

    out: dict = {}
    for key in keys:
        src, dst, path = config[section], out, key.split(".")
        for i, part in enumerate(path):
            if not isinstance(src, Mapping) or part not in src:
                raise ConfigError(f"a rule asks for configuration key '{section}.{key}', which the section has not",
                                  SECTIONS[section].config_file, f"{section}.{key}")
            src = src[part]
            if i < len(path) - 1:
                dst = dst.setdefault(part, {})
        dst[path[-1]] = src
    return canon(out)
