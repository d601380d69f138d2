"""A crowd pushes walkers off a walking area; the junctions' ground margin holds them.

Found by the safety campaign on the crowd (step-out at 10 s at 1 m/s, the truck at 192 m, the
pedestrian 1 m behind it, every noise bound and seed): the campaign's pedestrian, reaching the
north walking area of the zebra at 1 m/s, met s6 waiting there to step onto the zebra, and
SUMO pushed s6 0.081 m off the walking area at 26.2 s; the world stopped all six runs
(``walkable_ground``). The lone walkers that measure the ground walk alone, so a scene whose
walkers meet on a walking area sets ``estimator.junction_ground_margin_m`` (the crowd: 0.5 m),
as it sets a larger jitter.
"""

from __future__ import annotations

import pytest
from world_helpers import REPO

from sse_cosim.errors import AssumptionBroken
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.loader import load_scenario

pytestmark = pytest.mark.sumo
CROWD = REPO / "scenarios" / "crowd.toml"
PUSHED = {  # the campaign's run, to just past the push
    "simulation.duration_s": 26.5,
    "pedestrians.pedestrian.crossing_tolerance_s": 5.0,
    "pedestrians.pedestrian.steps_onto_crossing_s": 10.0,
    "pedestrians.pedestrian.walking_speed_mps": 1.0,
    "parked.truck.end_pos_m": 192.0,
    "pedestrians.pedestrian.start_pos_m": 191.0,
}


def test_without_a_margin_the_pushed_walker_stops_the_run(tmp_path) -> None:
    with pytest.raises(AssumptionBroken, match=r"pedestrian 's6' at t=26\.20 s .* 0\.081 m off "
                       r".*junction_ground_margin_m \(now 0 m\)"):
        run_scenario_file(CROWD, tmp_path, {**PUSHED, "estimator.junction_ground_margin_m": 0.0},
                          plots=False, summary_only=True)


def test_the_crowds_margin_holds_the_pushed_walker(tmp_path) -> None:
    assert load_scenario(CROWD).estimator.junction_ground_margin_m == 0.5
    summary = run_scenario_file(CROWD, tmp_path, PUSHED, plots=False, summary_only=True)
    assert summary["containment_violations"] == 0 and summary["collisions"] == 0
