"""The CLI explains itself, and the README's field table is the schema's."""

from __future__ import annotations

from pathlib import Path

import pytest

from sse_cosim.cli.main import main
from sse_cosim.scenario.fields import fields_markdown

ROOT = Path(__file__).resolve().parents[2]


def test_readme_field_table_is_generated_from_the_schema():
    assert fields_markdown() in (ROOT / "README.md").read_text(encoding="utf-8")


@pytest.mark.parametrize("command", [[], ["run"], ["batch"], ["fields"], ["network"]])
def test_help_explains_every_command(command, capsys):
    main([*command, "--help"])
    text = capsys.readouterr().out
    assert text.startswith("Usage: sse-cosim")
    assert len(text.splitlines()) > 5
