"""Dotted path patterns into a scenario's resolved fields, as ``sweep --param`` and ``--set``
take them.

A part of the path may be a glob over the keys at that place (``sensors.*_cam.noise_bound_m``)
and may end in a filter on a field of the tables it selects (``sensors.*[node=rsu*].range_m``,
``sensors.*[node!=bus].noise_bound_m``). A pattern that selects nothing is an error.
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Mapping
from fnmatch import fnmatchcase
from typing import Any

from sse_cosim.errors import UserError

PART_FILTER = re.compile(r"^(?P<keys>.*)\[(?P<field>\w+)(?P<op>!?=)(?P<glob>[^\]]*)\]$")
PATTERN_CHARS = frozenset("*?[")


def is_pattern(path: str) -> bool:
    """Whether ``path`` has a glob or a filter (else it names one field as written)."""
    return not PATTERN_CHARS.isdisjoint(path)


def expand_pattern(pattern: str, fields: Mapping[str, Any], source: str) -> list[tuple[str, Any]]:
    """The concrete dotted paths in ``fields`` that ``pattern`` selects, with their values."""
    found: list[tuple[tuple[str, ...], Any]] = [((), fields)]
    for part in split_path(pattern, source):
        keys_glob, select = _part_filter(part)
        matched = [
            ((*prefix, key), node[key])
            for prefix, node in found if isinstance(node, Mapping)
            for key in node if fnmatchcase(key, keys_glob) and select(node[key])
        ]
        if not matched:
            raise _no_match(pattern, part, found, source)
        found = matched
    return [(".".join(path), value) for path, value in found]


def selected_paths(pattern: str, fields: Mapping[str, Any], source: str) -> list[str]:
    """The concrete paths ``pattern`` selects in ``fields``; none where it selects nothing (a
    campaign's or a search's pattern need not apply to every scenario)."""
    try:
        return [path for path, _ in expand_pattern(pattern, fields, source)]
    except UserError:
        return []


def expand_overrides(overrides: Mapping[str, Any], fields: Mapping[str, Any],
                     source: str) -> dict[str, Any]:
    """``overrides`` (pattern -> value) with each pattern replaced by the concrete paths it
    selects in ``fields``; a pattern that selects nothing is a :class:`UserError`."""
    return {path: value for pattern, value in overrides.items()
            for path, _ in expand_pattern(pattern, fields, source)}


def top_level_positions(text: str, separator: str) -> list[int]:
    """Where ``separator`` stands in ``text`` outside ``[...]`` (a filter may hold dots and
    ``=``)."""
    depth, positions = 0, []
    for i, char in enumerate(text):
        depth += {"[": 1, "]": -1}.get(char, 0)
        if char == separator and depth == 0:
            positions.append(i)
    return positions


def split_path(pattern: str, source: str = "command line") -> list[str]:
    """Dotted parts of ``pattern``; dots inside ``[...]`` belong to their part."""
    cuts = [-1, *top_level_positions(pattern, "."), len(pattern)]
    parts = [pattern[start + 1:end] for start, end in itertools.pairwise(cuts)]
    if not all(parts):
        raise UserError(source, pattern or "(empty)", "is not a dotted path",
                        "write it as table.field, e.g. sensors.bus_front.noise_bound_m")
    return parts


def _part_filter(part: str):
    """``keys_glob`` and a predicate on the selected value for ``glob[field=glob]``."""
    match = PART_FILTER.match(part)
    if match is None:
        return part, lambda _value: True
    name, op, glob = match["field"], match["op"], match["glob"]

    def select(value: Any) -> bool:
        hit = isinstance(value, Mapping) and fnmatchcase(str(value.get(name)), glob)
        return hit if op == "=" else isinstance(value, Mapping) and not hit

    return match["keys"], select


def _no_match(pattern: str, part: str, found, source: str) -> UserError:
    prefix, node = found[0]
    where = ".".join(prefix) or "the scenario"
    if not isinstance(node, Mapping):
        return UserError(source, pattern, f"{where} is a value, not a table",
                         "check the path (`sse-cosim fields` lists every field)")
    keys = ", ".join(list(node)[:12]) + (", ..." if len(node) > 12 else "")
    return UserError(source, pattern, f"{part!r} matches nothing in {where} (it has: {keys})",
                     "check the path (`sse-cosim fields` lists every field)")
