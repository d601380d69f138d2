"""Reading scenario files: TOML, ``extends`` inheritance, dotted overrides, one-line errors.

A scenario file may name one or more parent files with ``extends = "parent.toml"`` (or a
list); parents are merged first, tables merge key by key, any other value is replaced.
Paths inside a file (``network.sources_dir``, ``network.net_file``, ``network.route_files``)
are relative to the file that sets them. ``network.sources_dir`` and ``network.net_file`` are
alternatives: a file (or a ``--set`` override) that sets one drops the other inherited one.
"""

from __future__ import annotations

import copy
import difflib
import tomllib
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from sse_cosim.errors import UserError
from sse_cosim.scenario.base import TAG_MARK
from sse_cosim.scenario.fields import field_docs
from sse_cosim.scenario.model import Scenario

EXTENDS_KEY = "extends"
RELATIVE_PATH_FIELDS = (("network", "sources_dir"), ("network", "net_file"),
                        ("network", "route_files"))
# (table, key) -> the alternative it replaces when set
ALTERNATIVE_FIELDS = {("network", "sources_dir"): "net_file",
                      ("network", "net_file"): "sources_dir"}


def load_scenario(path: str | Path, overrides: Mapping[str, Any] | None = None) -> Scenario:
    """Read, merge and validate the scenario at ``path``, then apply dotted ``overrides``."""
    data = load_scenario_data(path)
    if overrides:
        data = apply_overrides(data, overrides, source=str(path))
    return validate_scenario(data, source=str(path))


def load_scenario_data(path: str | Path) -> dict[str, Any]:
    """The merged, unvalidated content of a scenario file and its parents."""
    return _load_merged(Path(path), chain=())


def validate_scenario(data: Mapping[str, Any], source: str) -> Scenario:
    """Validate merged scenario data; a problem becomes a one-line :class:`UserError`."""
    try:
        return Scenario.model_validate(data)
    except ValidationError as exc:
        raise _user_error(exc, source) from None


def apply_overrides(
    data: Mapping[str, Any], overrides: Mapping[str, Any], source: str
) -> dict[str, Any]:
    """A copy of ``data`` with each dotted path (``sensors.bus_front.range_m``) set to a value.

    The path must name a field that the schema knows: every part but the last must exist
    in ``data`` or be a field of the schema's model at that place.
    """
    result = copy.deepcopy(dict(data))
    for dotted, value in overrides.items():
        _check_path(dotted, source)
        _drop_alternatives(result, {tuple(dotted.split("."))})
        node: dict[str, Any] = result
        parts = dotted.split(".")
        for depth, part in enumerate(parts[:-1]):
            child = node.get(part)
            if child is None:
                if not _schema_has_table(parts[: depth + 1]):
                    raise UserError(
                        source, dotted, f"there is no table {'.'.join(parts[: depth + 1])!r}",
                        "check the path against the scenario file (see sse-cosim fields)",
                    )
                child = node[part] = {}
            if not isinstance(child, dict):
                raise UserError(
                    source, dotted, f"{'.'.join(parts[: depth + 1])!r} is a value, not a table",
                    "check the path against the scenario file",
                )
            node = child
        node[parts[-1]] = value
    return result


def _check_path(dotted: str, source: str) -> None:
    if not dotted or any(not part for part in dotted.split(".")):
        raise UserError(source, dotted or "(empty)", "is not a dotted path",
                        "write it as table.field, e.g. sensors.bus_front.range_m")


def _schema_has_table(parts: list[str]) -> bool:
    """Whether the schema has a table at ``parts`` (dict-valued fields accept any key; in a
    union of tables, such as the sensor kinds, any member's table counts)."""
    models: list[Any] = [Scenario]
    for part in parts:
        found: list[Any] = []
        for model in models:
            if isinstance(model, _DictOf):
                found += _members(model.value)  # any key: the entry has the dict's value type
                continue
            fields = getattr(model, "model_fields", None)
            if fields is None or part not in fields:
                continue
            annotation = fields[part].annotation
            origin = getattr(annotation, "__origin__", None)
            found += [_DictOf(typing.get_args(annotation)[1])] if origin is dict \
                else _members(annotation)
        models = found
    return any(isinstance(m, _DictOf) or hasattr(m, "model_fields") for m in models)


def _members(annotation: Any) -> list[Any]:
    """The types an annotation admits: a union's members, an ``Annotated`` type's own."""
    if typing.get_origin(annotation) is typing.Annotated:
        return _members(typing.get_args(annotation)[0])
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return [m for arg in typing.get_args(annotation) for m in _members(arg)]
    return [annotation]


@dataclass(frozen=True)
class _DictOf:
    """A dict-valued schema field (``sensors``, ``faults.sensor``): its value type."""

    value: Any


def _load_merged(path: Path, chain: tuple[Path, ...]) -> dict[str, Any]:
    path = path.resolve()
    if path in chain:
        cycle = " -> ".join(p.name for p in (*chain, path))
        raise UserError(str(path), EXTENDS_KEY, f"files extend each other in a cycle ({cycle})",
                        "remove one of the extends")
    raw = _read_toml(path)
    parents = raw.pop(EXTENDS_KEY, [])
    if isinstance(parents, str):
        parents = [parents]
    if not isinstance(parents, list) or not all(isinstance(p, str) for p in parents):
        raise UserError(str(path), EXTENDS_KEY, "must be a file name or a list of file names",
                        'write extends = "base.toml"')
    _absolutize_paths(raw, path.parent)
    merged: dict[str, Any] = {}
    for parent in parents:
        parent_path = path.parent / parent
        if not parent_path.is_file():
            raise UserError(str(path), EXTENDS_KEY, f"parent file {parent!r} not found",
                            f"create it or fix the name (looked in {path.parent})")
        merged = deep_merge(merged, _load_merged(parent_path, (*chain, path)))
    _drop_alternatives(merged, {(table, key) for table, section in raw.items()
                                if isinstance(section, dict) for key in section})
    return deep_merge(merged, raw)


def _drop_alternatives(data: dict[str, Any], setting: set[tuple[str, ...]]) -> None:
    """Remove from ``data`` the alternatives of the (table, key) paths being set."""
    for (table, key), other in ALTERNATIVE_FIELDS.items():
        section = data.get(table)
        if (table, key) in setting and isinstance(section, dict):
            section.pop(other, None)


def _read_toml(path: Path) -> dict[str, Any]:
    if not path.is_file():
        raise UserError(str(path), "", "scenario file not found", "check the path")
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except tomllib.TOMLDecodeError as exc:
        raise UserError(
            str(path), "syntax", str(exc), "fix the TOML syntax at that place"
        ) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(str(path), "", f"cannot be read ({exc})", "check the file") from None


def _absolutize_paths(raw: dict[str, Any], base: Path) -> None:
    for table, key in RELATIVE_PATH_FIELDS:
        section = raw.get(table)
        if not isinstance(section, dict):
            continue
        value = section.get(key)
        if isinstance(value, str):
            section[key] = str((base / value).resolve())
        elif isinstance(value, list):
            section[key] = [str((base / v).resolve()) if isinstance(v, str) else v for v in value]


def deep_merge(base: Mapping[str, Any], override: Mapping[str, Any]) -> dict[str, Any]:
    """Tables merge key by key (recursively); any other value in ``override`` replaces."""
    result = copy.deepcopy(dict(base))
    for key, value in override.items():
        if isinstance(value, Mapping) and isinstance(result.get(key), Mapping):
            result[key] = deep_merge(result[key], value)
        else:
            result[key] = copy.deepcopy(value)
    return result


_FIXES = {
    "extra_forbidden": "remove it or fix its spelling (see sse-cosim fields)",
    "missing": "add this field",
    "greater_than": "use a larger value",
    "greater_than_equal": "use a larger value",
    "less_than": "use a smaller value",
    "less_than_equal": "use a smaller value",
    "literal_error": "use one of the values named",
    "too_short": "give at least one entry",
    "float_parsing": "give a number (no quotes)",
    "float_type": "give a number (no quotes)",
    "int_parsing": "give a whole number (no quotes)",
    "int_type": "give a whole number (no quotes)",
    "bool_parsing": "write true or false",
    "bool_type": "write true or false",
    "string_type": "write it in quotes",
    "list_type": "write a list, e.g. [1.0, 2.0]",
    "tuple_type": "write a list, e.g. [1.0, 2.0]",
    "model_type": "write it as a table ([name] or name = { ... })",
    "dict_type": "write it as a table ([name] or name = { ... })",
}


def _user_error(exc: ValidationError, source: str) -> UserError:
    """The first validation problem as a one-line error naming file, field and fix (a
    misspelt field's nearest name; the fields of any further problems)."""
    errors = exc.errors(include_url=False)
    err = errors[0]
    field = _dotted(err)
    message = str(err["msg"]).removeprefix("Value error, ")
    head, _, rest = message.partition(": ")
    if err["type"] == "value_error" and rest and " " not in head:
        # A model validator names the field it rejects: "field: problem" (dotted from the root
        # when the root validates, relative to the model otherwise).
        field, message = (f"{field}.{head}" if field else head), rest
    fix = _FIXES.get(err["type"], "")
    if err["type"] == "extra_forbidden":
        fix = f"{_nearest(field)}{fix}"
    if "input" in err and err["type"] not in ("missing", "extra_forbidden", "value_error"):
        message += f" (got {err['input']!r})"
    if len(errors) > 1:
        others = ", ".join(dict.fromkeys(_dotted(e) or "(the file)" for e in errors[1:]))
        fix = f"{fix}; {len(errors) - 1} more problem(s) after this one: {others}".lstrip("; ")
    return UserError(source, field, message, fix)


def _dotted(err: Mapping[str, Any]) -> str:
    """A validation problem's field, dotted (a tagged union, the sensor kinds, puts its tag,
    e.g. "kind=range", in the path: dropped)."""
    return ".".join(str(part) for part in err["loc"] if TAG_MARK not in str(part))


def _nearest(field: str) -> str:
    """"did you mean <field>? " for the schema's field nearest in spelling to an unknown
    ``field`` among those beside it (tables keyed by name match any name), else ""."""
    parts = field.split(".")
    beside = set()
    for doc in field_docs():
        known = doc.path.rstrip(".").split(".")
        if len(known) >= len(parts) and all(
                k == p or k.startswith("<") for k, p in zip(known, parts[:-1], strict=False)):
            beside.add(known[len(parts) - 1])
    close = difflib.get_close_matches(parts[-1], sorted(b for b in beside
                                                        if not b.startswith("<")), n=1)
    return f"did you mean {'.'.join([*parts[:-1], close[0]])}? " if close else ""
