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
    """Depth-first over the schema; tables keyed by name (sensors, rsus) show ``<name>``."""
    for name, info in model.model_fields.items():
        path = f"{prefix}{name}"
        annotation = info.annotation
        nested = _model_of(annotation)
        if typing.get_origin(annotation) is dict and nested is not None:
            yield from field_docs(nested, f"{path}.<{_key_name(name)}>.")
        elif nested is not None:
            yield from field_docs(nested, f"{path}.")
        else:
            default = "required" if info.is_required() else repr(info.get_default(
                call_default_factory=True))
            yield FieldDoc(path, default, info.description or "")


def fields_markdown() -> str:
    """The field table as Markdown (the README's scenario-field section)."""
    rows = ["| field | default | meaning |", "|---|---|---|"]
    rows += [f"| `{d.path}` | `{d.default}` | {_escape(d.description)} |" for d in field_docs()]
    return "\n".join(rows) + "\n"


def _escape(text: str) -> str:
    """Keep Markdown table cells whole."""
    return text.replace("|", "\\|")


def _model_of(annotation) -> type[BaseModel] | None:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in typing.get_args(annotation):
        found = _model_of(arg)
        if found is not None:
            return found
    return None


def _key_name(field_name: str) -> str:
    names = {"sensors": "sensor name", "rsus": "unit id", "sensor": "fault name",
             "node": "fault name", "link": "fault name"}
    return names.get(field_name, "key")
