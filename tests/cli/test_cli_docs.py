"""The CLI explains itself, and the field table (`sse-cosim fields`, the docs site's scenario
fields page: tests/reporting/test_docs_site.py) names what each field accepts."""

from __future__ import annotations

import pytest

from sse_cosim.cli.main import main
from sse_cosim.scenario.fields import fields_markdown


@pytest.mark.parametrize("command", [[], ["run"], ["batch"], ["fields"], ["network"],
                                     ["falsify"]])
def test_help_explains_every_command(command, capsys):
    main([*command, "--help"])
    text = capsys.readouterr().out
    assert text.startswith("Usage: sse-cosim")
    assert len(text.splitlines()) > 5


@pytest.mark.parametrize(("path", "values"), [
    ("sensors.<sensor name>.noise", ["uniform", "worst-case"]),
    ("estimator.state_model", ["position", "constant-velocity", "bounded-acceleration"]),
    ("breaks_assumptions", ["pedestrian_speed", "walkable_ground", "pedestrian_lights",
                            "sensor_bounds", "shared_estimates", "reaction_time"]),
])
def test_field_table_names_the_accepted_values_of_enumerated_fields(path, values):
    """Read from the field's type: the table never goes stale on, e.g., `worst-case`."""
    row = next(line for line in fields_markdown().splitlines() if line.startswith(f"| `{path}`"))
    assert "Accepted values: " + ", ".join(f"`{v}`" for v in values) + "." in row
