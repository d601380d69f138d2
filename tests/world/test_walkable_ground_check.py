"""The world checks every step that each pedestrian's true centre lies on the walkable ground
(sse_cosim/world/sumo.py, ``walkable_ground``).

On the town cut (sumo_net/town/) SUMO walks the scene's pedestrian over the walking area
``:1384946487_w1`` onto the zebra on a curve that leaves the plain ground (sidewalks, walking
areas, crossing rectangles) by up to 0.21 m at 15.8 to 16.1 s. The lone walkers' measurement
(sse_cosim/world/walker_jitter.py) gives that junction a ground patch and the walkable ground
holds them; on a copy of the network whose cached measurement gives every junction an empty
patch the run stops there -- or, in a study that lists ``walkable_ground``, counts.

A walker exactly on the ground's edge is on it: with the safety campaign's start 37 m along its
sidewalk, SUMO walks the pedestrian along an edge of ``:1384946487_w1`` at 4.4 s, 6.9e-14 m
outside it by the rounding of its positions, which stopped every such run before the check
took the tolerance ``WALKABLE_TOL_M``.
"""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from pathlib import Path

import pytest
import shapely
from world_helpers import REPO

from sse_cosim.cli.main import EXIT_ASSUMPTION_BROKEN, main
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world import walker_jitter
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import WALKABLE_TOL_M, load_roadmap
from sse_cosim.world.sumo import measure_walkers, sumo_version

pytestmark = pytest.mark.sumo
TOWN = REPO / "scenarios" / "town.toml"


@pytest.fixture
def plain(tmp_path, monkeypatch) -> Path:
    """A copy of the town cut whose cached measurement keeps the jitter and gives every
    junction an empty ground patch (the cache in a folder of the test's own)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    road = build_network(REPO / "sumo_net" / "town")
    scenario = load_scenario(TOWN)
    speed = scenario.estimator.max_pedestrian_speed_mps
    step, radius = scenario.simulation.step_length_s, scenario.pedestrian_radius_m()
    measure_walkers(road, load_roadmap(road), None, speed, step, radius)  # cached with the build
    key = walker_jitter.cache_key(sumo_version(), step, speed, radius)
    net = tmp_path / "town.net.xml"
    shutil.copyfile(road, net)
    walker_jitter.JitterCache(net).add(key, [
        replace(measured, off_ground=shapely.Polygon())
        for measured in walker_jitter.JitterCache(road).junctions(key).values()])
    return net


def _on(net: Path, folder: Path, *lines: str) -> Path:
    """The town scene for 17 s on the network ``net``: its scenario file in ``folder``."""
    path = folder / "plain.toml"
    path.write_text("\n".join([f'extends = "{TOWN.as_posix()}"', *lines, "[simulation]",
                               "duration_s = 17", "[network]", f'net_file = "{net.as_posix()}"',
                               ""]), encoding="utf-8")
    return path


def test_a_pedestrian_off_the_walkable_ground_stops_the_run_with_one_line(tmp_path, capsys,
                                                                        plain) -> None:
    capsys.readouterr()  # the fixture's measurement, when the build had none cached yet
    with pytest.raises(SystemExit) as info:
        main(["run", str(_on(plain, tmp_path)), "--out", str(tmp_path / "out")])
    assert info.value.code == EXIT_ASSUMPTION_BROKEN
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    for words in ("broke an assumption of the estimator (walkable_ground)",
                  "pedestrian 'pedestrian' at t=15.80 s", "lane ':1384946487_w1_0'",
                  "m off the walkable ground",
                  "list 'walkable_ground' in breaks_assumptions"):
        assert words in err, (words, err)
    assert not (tmp_path / "out" / "summary.json").exists()


def test_a_study_that_lists_walkable_ground_runs_on_and_counts(tmp_path, plain) -> None:
    out = tmp_path / "out"
    main(["run", str(_on(plain, tmp_path, 'breaks_assumptions = ["walkable_ground"]')),
          "--out", str(out)])
    breaks = json.loads((out / "summary.json").read_text())["ground_breaks"]
    assert breaks["count"] == 4
    assert [(b["t"], b["lane"]) for b in breaks["first"][:2]] == [
        (15.8, ":1384946487_w1_0"), (15.9, ":1384946487_w1_0")]
    assert 0.2 < max(b["off_m"] for b in breaks["first"]) < 0.25


def test_a_walker_on_the_edge_of_a_walking_area_to_rounding_is_on_the_ground(tmp_path) -> None:
    summary = run_scenario_file(TOWN, tmp_path, {
        "simulation.duration_s": 5.0, "pedestrians.pedestrian.start_pos_m": 37.0,
        "pedestrians.pedestrian.steps_onto_crossing_s": 7.0,
        "pedestrians.pedestrian.walking_speed_mps": 2.0}, plots=False, summary_only=True)
    assert summary["containment_violations"] == 0
    assert 1e-13 < WALKABLE_TOL_M <= 1e-7  # above coordinate rounding, within the recorder's
