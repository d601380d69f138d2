"""A lurch on the real town, in SUMO: the bus stands before a junction's overlapping walking
areas, with walkers in view, and must not move off onto ground it could not clear.

The falsifier's second search of the town (CMA-ES's evaluation 10) found it. The bus stood
before a walking area whose walker in view was 5.4 s away: holding nominal speed it would
clear that area in time, so the old rule let it move off, but two more walking areas lie
inside that clearing distance with walkers in view 1.4 s and 3.3 s away; a step later the bus
could neither clear them nor stop before them, so it stopped, stood, and moved off again:
seven times between 37.0 and 38.7 s (5 cm a time). From a standstill the bus now moves off
only if it clears every walking area it enters on the way before the walkers in view
(``SafePolicy._gives_way``).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo

CASE = Path(__file__).with_name("town_lurch.toml")


def test_the_bus_does_not_move_off_onto_walking_areas_it_cannot_clear(tmp_path: Path):
    run_scenario_file(CASE, tmp_path, plots=False, summary_only=True)
    summary = json.loads((tmp_path / "summary.json").read_text())
    # one restart, the creep at 30.4 s (the old rule: eight, seven of them from 37.0 s on)
    assert summary["restarts"] == 1
    assert summary["time_stopped_s"] > 10.0  # it does stand for the walkers
    assert summary["collisions"] == 0
    assert summary["containment_violations"] == 0
