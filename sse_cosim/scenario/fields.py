"""Every scenario field with its default and meaning, read from the schema itself."""

from __future__ import annotations

import typing
from collections.abc import Iterator
from dataclasses import dataclass

from pydantic import BaseModel

from sse_cosim.scenario.model import Scenario


@dataclass(frozen=True)
class FieldDoc:
    path: str
    default: str
    description: str


def field_docs(model: type[BaseModel] = Scenario, prefix: str = "") -> Iterator[FieldDoc]:
    """Depth-first over the schema; tables keyed by name (sensors, rsus) show ``<name>``.

    A union of tables (the sensor kinds) lists the fields all its members share once, then
    each member's own, their meaning led by ``[<kind>]``.
    """
    for name, info in model.model_fields.items():
        path = f"{prefix}{name}"
        annotation = info.annotation
        nested = _models_of(annotation)
        if typing.get_origin(annotation) is dict and nested:
            path = f"{path}.<{_key_name(name)}>."
        elif nested:
            path = f"{path}."
        else:
            default = "required" if info.is_required() else repr(info.get_default(
                call_default_factory=True))
            yield FieldDoc(path, default, _with_accepted(info.description or "", annotation))
            continue
        shared = [d for d in field_docs(nested[0], path)
                  if all(d in field_docs(other, path) for other in nested[1:])]
        yield from shared
        for member in nested if len(nested) > 1 else ():
            tag = typing.get_args(member.model_fields["kind"].annotation)[0]  # its Literal's value
            yield from (FieldDoc(d.path, d.default, f"[{tag}] {d.description}")
                        for d in field_docs(member, path) if d not in shared)


def fields_markdown() -> str:
    """The field table as Markdown (``sse-cosim fields``; the docs site's scenario fields
    page, docs/reference/fields.md, is made from it)."""
    rows = ["| field | default | meaning |", "|---|---|---|"]
    rows += [f"| `{d.path}` | `{d.default}` | {_escape(d.description)} |" for d in field_docs()]
    return "\n".join(rows) + "\n"


def _escape(text: str) -> str:
    """Keep Markdown table cells whole."""
    return text.replace("|", "\\|")


def _with_accepted(description: str, annotation) -> str:
    """``description`` followed by the values an enumerated field accepts, from its type."""
    values = _literal_values(annotation)
    if not values:
        return description
    accepted = "Accepted values: " + ", ".join(f"`{v}`" for v in values) + "."
    return f"{description} {accepted}".strip()


def _literal_values(annotation) -> list:
    """The values of the ``Literal`` an annotation holds (alone, in a union or as a list's
    items), in order."""
    if typing.get_origin(annotation) is typing.Literal:
        return list(typing.get_args(annotation))
    return [v for arg in typing.get_args(annotation) for v in _literal_values(arg)]


def _models_of(annotation) -> list[type[BaseModel]]:
    """The models an annotation holds (a union's members, a dict's values), in order."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return [m for arg in typing.get_args(annotation) for m in _models_of(arg)]


def _key_name(field_name: str) -> str:
    names = {"sensors": "sensor name", "rsus": "unit id", "sensor": "fault name",
             "node": "fault name", "link": "fault name", "automated": "vehicle id",
             "parked": "vehicle id", "vehicles": "vehicle id", "pedestrians": "pedestrian id"}
    return names.get(field_name, "key")
