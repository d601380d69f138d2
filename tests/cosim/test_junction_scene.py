"""scenarios/junction.toml's hard cases in real SUMO, the first 20 s: a pedestrian steps onto
the zebra in front of each bus at the speed bound (2.5 m/s) while the twelve others wait at
the curbs and traffic comes from every arm. Each bus stops before its zebra and stays behind
it while its pedestrian crosses, without an emergency brake; nobody is hit and every set
holds its pedestrian. (The whole 100 s run, in which both buses finish, is in `make run`.)"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo
JUNCTION = Path(__file__).resolve().parents[2] / "scenarios" / "junction.toml"
ROAD_HALF_WIDTH_M = 3.5
# where each bus's hard case crosses in front of it: (bus, pedestrian, axis the bus drives
# along, the zebra's near edge on that axis)
CASES = [("bus_we", "pedestrian", "x", -7.5), ("bus_sn", "s0", "y", -7.5)]


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> tuple[dict, pd.DataFrame, pd.DataFrame]:
    out = tmp_path_factory.mktemp("junction")
    summary = run_scenario_file(JUNCTION, out, {"simulation.duration_s": 20.0}, plots=False)
    return summary, pd.read_csv(out / "trace.csv"), pd.read_csv(out / "truth.csv")


def test_nobody_is_hit_and_every_set_holds_its_pedestrian(run):
    summary, _, _ = run
    assert summary["collisions"] == summary["contact_steps"] == 0
    assert summary["containment_violations"] == 0, summary["violations"]
    for figures in summary["vehicles"].values():
        assert figures["level_share"]["emergency"] == 0.0


@pytest.mark.parametrize(("bus", "pedestrian", "axis", "zebra"), CASES)
def test_each_bus_waits_behind_its_zebra_while_its_pedestrian_crosses(run, bus, pedestrian,
                                                                      axis, zebra):
    _, trace, truth = run
    other = "y" if axis == "x" else "x"
    walker = truth[truth["pedestrian"] == pedestrian].set_index("t")
    on_road = walker[other].abs() < ROAD_HALF_WIDTH_M  # on the zebra, across the road
    assert on_road.any()
    front = trace[trace["vehicle"] == bus].set_index("t")[f"bus_{axis}"]
    assert (front.loc[walker.index[on_road].intersection(front.index)] < zebra).all()
    assert front.min() < zebra - 20.0 and front.max() > zebra - 3.0  # it came up to the zebra
