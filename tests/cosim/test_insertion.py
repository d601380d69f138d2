"""A bus inserted at speed starts from the messages in the air (issue: live on real streets).

On the paper's road with S3's road-side units, the bus enters at 20 m/s 78 m before the
zebra, 5 s into the run, when the units have been sending for 5 s. Its V2X link listened
from the start, from where SUMO inserts it, so its first picture holds both units' latest
views of the zebra and it drives on at its nominal speed: no emergency brake at insertion,
with nobody in the scene. Before, the units' messages reached only vehicles already in the
world, the bus's first picture had its own view alone (60 m, short of the zebra), and it
braked in emergency for one step. (A bus inserted at t = 0 has no message to start from: no
node has sent one yet.)"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo
SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "s3_no_pedestrian.toml"


def test_a_bus_inserted_at_speed_has_the_units_views_at_once(tmp_path: Path) -> None:
    overrides = {"automated.bus.depart_s": 5.0, "automated.bus.depart_pos_m": 120.0,
                 "simulation.duration_s": 12.0}
    summary = run_scenario_file(SCENARIO, tmp_path, overrides, plots=False)
    trace = pd.read_csv(tmp_path / "trace.csv")
    first = trace.iloc[0]
    assert first["t"] == pytest.approx(5.0) and first["bus_speed"] == pytest.approx(20.0)
    assert first["senders"] == 2  # rsu1 and rsu2, sent at 4.9 s
    assert first["level"] == "nominal"
    assert summary["level_share"].get("emergency", 0.0) == 0.0
    assert summary["containment_violations"] == 0 and summary["collisions"] == 0
