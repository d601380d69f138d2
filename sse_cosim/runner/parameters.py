"""Dotted scenario parameters given on the command line: ``PATH=VALUE``."""

from __future__ import annotations

import tomllib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from sse_cosim.errors import UserError
from sse_cosim.scenario.loader import (
    RELATIVE_PATH_FIELDS,
    apply_overrides,
    load_scenario_data,
    validate_scenario,
)
from sse_cosim.scenario.model import Scenario
from sse_cosim.scenario.paths import expand_pattern, is_pattern, top_level_positions


def parse_value(text: str) -> Any:
    """A TOML value (number, boolean, list, quoted string); anything else is a plain string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def split_assignment(text: str) -> tuple[str, str] | None:
    """``PATH=VALUE`` split at the first ``=`` outside brackets (a filter such as
    ``sensors.*[node!=bus]`` holds one), both sides stripped; None if a side is empty."""
    positions = top_level_positions(text, "=")
    if not positions:
        return None
    path, value = text[:positions[0]].strip(), text[positions[0] + 1:].strip()
    return (path, value) if path and value else None


def parse_assignment(text: str, option: str) -> tuple[str, Any]:
    """``"sensors.bus_front.range_m=40"`` -> ``("sensors.bus_front.range_m", 40)``."""
    parts = split_assignment(text)
    if parts is None:
        raise UserError("command line", option, f"{text!r} is not PATH=VALUE",
                        "write it like sensors.bus_front.range_m=40")
    return parts[0], command_line_path(parts[0], parse_value(parts[1]))


def command_line_path(path: str, value: Any) -> Any:
    """``value`` of field ``path``; a path field's (``network.net_file``, ``sources_dir``,
    ``route_files``) made absolute against the working directory, where the user typed it
    (in a scenario file such a path is relative to that file), so that the message of a
    missing file and ``scenario.json`` show where it was looked for."""
    if tuple(path.split(".")) not in RELATIVE_PATH_FIELDS:
        return value
    if isinstance(value, str):
        return str(Path(value).resolve())
    if isinstance(value, list):
        return [str(Path(v).resolve()) if isinstance(v, str) else v for v in value]
    return value


def load_with_assignments(
    path: Path, texts: Sequence[str], option: str = "--set"
) -> tuple[Scenario, dict[str, str]]:
    """The scenario at ``path`` with each ``PATH=VALUE`` of ``option`` applied, and for each
    field set, the assignment that set it (``"--set sensors.*.range_m=40"``).

    The file is validated first, so that its own errors name the file. A pattern (a glob or
    a filter, as ``sweep --param`` takes) is expanded against the file's resolved fields and
    must select something; a plain path is set as written (it may add a table, a fault for
    example). Any error after that is the assignments' own and names them, not the file.
    """
    data = load_scenario_data(path)
    fields = validate_scenario(data, str(path)).model_dump(mode="json")
    owners: dict[str, str] = {}
    for text in texts:
        pattern, value = parse_assignment(text, option)
        blame = f"{option} {text}"
        targets = ([found for found, _ in expand_pattern(pattern, fields, blame)]
                   if is_pattern(pattern) else [pattern])
        data = apply_overrides(data, dict.fromkeys(targets, value), blame)
        owners.update(dict.fromkeys(targets, blame))
    try:
        return validate_scenario(data, str(path)), owners
    except UserError as exc:
        raise blame_assignments(exc, owners, always=True) from None


def blame_assignments(exc: UserError, owners: Mapping[str, str], always: bool) -> UserError:
    """``exc`` named after the assignments that set its field, or after all of them when
    ``always`` (an error that only they can have caused); else ``exc`` as it is."""
    blamed = sorted({blame for field, blame in owners.items() if _related(field, exc.field)})
    if not blamed and always:
        blamed = sorted(set(owners.values()))
    if not blamed:
        return exc
    return UserError(", ".join(blamed), exc.field, exc.problem, exc.fix)


def _related(field: str, other: str) -> bool:
    """Whether one dotted path is the other or lies inside it."""
    return field == other or field.startswith(f"{other}.") or other.startswith(f"{field}.")
