"""A pass the world holds back, on the junction in SUMO.

The falsifier's junction search found it (results/falsify.md, docs/controller.md): at 11.9 s
bus_sn proves a pass over the south zebra and the junction and goes nominal; SUMO then stops it
at the stop line for a car's right of way. Under the old commitment the bus stayed commanded
nominal for the 19 s SUMO held it and drove on into zones a pedestrian could already be in.
Now a commitment lasts only while the bus keeps to the pass, so the held bus plans again: it
is commanded to stop (or creep), never in emergency.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo

CASE = Path(__file__).with_name("junction_held_pass.toml")


def test_a_bus_held_at_the_stop_line_gives_up_its_pass(tmp_path: Path):
    run_scenario_file(CASE, tmp_path, plots=False)
    trace = pd.read_csv(tmp_path / "trace.csv")
    bus = trace[trace.vehicle == "bus_sn"]
    held = bus[(bus.t > 12.0) & (bus.bus_speed < 0.1)]
    assert len(held) > 5  # SUMO stops it at the stop line before 16 s
    assert set(held.level) <= {"stop", "creep"}  # not nominal: the pass is given up
    assert bus[bus.t > 12.0].level.iloc[0] == "nominal"  # the pass it was committed to
    assert "emergency" not in set(bus.level)
