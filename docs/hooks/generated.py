"""MkDocs hooks: the reference pages generated from the code.

- The scenario fields page gets its table from the schema, the one source ``sse-cosim
  fields`` prints too (docs/reference/fields.md holds only the marker).
- The command line page (mkdocs-click) reads the ``sse-cosim`` group after every sub-command
  module has attached itself, as ``sse-cosim`` does when it starts.
"""

from __future__ import annotations

from typing import Any

from sse_cosim.cli.main import register_commands
from sse_cosim.scenario.fields import fields_markdown

MARKER = "<!-- sse-cosim fields: docs/hooks/generated.py puts the table here -->"


def on_config(config: Any) -> Any:
    """Attach the sub-commands before any page is read."""
    register_commands()
    return config


def on_page_markdown(markdown: str, **_: Any) -> str:
    """``markdown`` with the marker replaced by the field table."""
    return markdown.replace(MARKER, fields_markdown())
