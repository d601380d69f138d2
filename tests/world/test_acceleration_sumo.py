"""The bounded-acceleration model's world in real SUMO, on the paper road: the adapter ramps
every walker's speed within a_max (read back from SUMO), S1's pedestrian still steps onto
its crossing on time and keeps the model's check; the lone walkers' jitter for the model is
measured with the same ramp, cached apart from the position model's, and is the least the
worst walk needs; a break stops the run in one line naming what broke and the jitter
needed, or is counted in a study that lists 'pedestrian_speed'."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from world_helpers import REPO, run_world, scenario

from sse_cosim.errors import AssumptionBroken
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world import walker_jitter
from sse_cosim.world.acceleration_assumption import (
    AccelerationBounds,
    AccelerationCheck,
    needed_jitter,
)
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap
from sse_cosim.world.sumo import SumoWorld, measure_walkers, sumo_version
from sse_cosim.world.walk_probe import Walker, walk_alone

pytestmark = pytest.mark.sumo
MODEL = {"estimator.state_model": "bounded-acceleration"}
SPEED, ACCEL, STEP, RADIUS = 2.5, 3.2, 0.1, 0.3


def test_s1_ramps_its_pedestrian_and_steps_it_onto_the_crossing_on_time(tmp_path) -> None:
    """S1 to just after its pedestrian steps onto the zebra (11.5 s): the world's checks (on
    time within one step, the acceleration model's witness, the walkable ground) raise
    otherwise. SUMO's speed never rises by more than a_max dt in a step, and on the straight
    sidewalk the positions' second differences stay within a_max dt² -- the ramp is used to
    its bound, from 0 to 1.5 m/s in five steps."""
    sc = scenario("s1_pedestrian", **MODEL, **{"simulation.duration_s": 12.0})
    run = run_world(sc, tmp_path)
    plan = run.pedestrian_plans["pedestrian"]
    assert abs(plan.steps_on_s - 11.5) <= STEP / 2 + 1e-6
    assert any(s.persons["pedestrian"].on_crossing for s in run.snapshots)
    speeds = np.array([s.persons["pedestrian"].speed for s in run.snapshots])
    assert np.diff(speeds).max() <= ACCEL * STEP + 1e-9
    xy = np.array([s.persons["pedestrian"].position for s in run.snapshots])
    sidewalk = xy[: np.flatnonzero(np.abs(xy[:, 1] - xy[0, 1]) > 1e-9)[0]]
    second = np.linalg.norm(np.diff(sidewalk, n=2, axis=0), axis=1)
    assert second.max() == pytest.approx(ACCEL * STEP * STEP)
    steps = np.linalg.norm(np.diff(sidewalk, axis=0), axis=1) / STEP
    first = np.flatnonzero(steps > 0)[0]
    assert steps[first:first + 6] == pytest.approx([0.32, 0.64, 0.96, 1.28, 1.5, 1.5])


@pytest.fixture
def paper(tmp_path, monkeypatch) -> Path:
    """A copy of the paper road, its measurements cached in the test's own folder."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    net_path = tmp_path / "paper.net.xml"
    shutil.copyfile(build_network(REPO / "sumo_net"), net_path)
    return net_path


def test_the_models_jitter_is_measured_with_the_ramp_and_cached_apart(paper) -> None:
    """The position model's entry is written as before and left as it is by the
    acceleration model's measurement, which is keyed by a_max; the measured jitter is the
    least the worst ramped walk needs: the check passes it at that jitter and breaks it 5 mm
    below."""
    roadmap = load_roadmap(paper)
    position = measure_walkers(paper, roadmap, None, SPEED, STEP, RADIUS)
    cache = walker_jitter.cache_path(paper)
    before = json.loads(cache.read_text("utf-8"))
    measured = measure_walkers(paper, roadmap, None, SPEED, STEP, RADIUS, ACCEL)
    after = json.loads(cache.read_text("utf-8"))
    key = walker_jitter.cache_key(sumo_version(), STEP, SPEED, RADIUS)
    assert set(after) == {key, walker_jitter.cache_key(sumo_version(), STEP, SPEED, RADIUS,
                                                       ACCEL)}
    assert after[key] == before[key] and list(before) == [key]
    assert measure_walkers(paper, roadmap, None, SPEED, STEP, RADIUS) == position
    assert measured.worst is not None and measured.worst.junction == "C"
    assert 0.3 < measured.jitter_m < 1.0
    worst = Walker("w", measured.worst.walk, *_ends(paper, measured.worst.walk), SPEED,
                   radius_m=RADIUS)
    trace = walk_alone(paper, [worst], STEP, paper.parent / "probe", accel_mps2=ACCEL)["w"]
    speeds = np.linalg.norm(np.diff(trace.xy[:6], axis=0), axis=1) / STEP
    assert speeds == pytest.approx([0.32, 0.64, 0.96, 1.28, 1.6])  # ramped from standstill
    at = AccelerationBounds(SPEED, ACCEL, 0.0, STEP)
    assert needed_jitter(trace.xy, at) == measured.jitter_m
    assert _breaks(trace.xy, measured.jitter_m) == []
    assert _breaks(trace.xy, measured.jitter_m - 0.005) != []


def _breaks(positions: np.ndarray, jitter_m: float) -> list:
    """The acceleration model's check along a walk (k, 2) with this jitter: its breaks."""
    check = AccelerationCheck(AccelerationBounds(SPEED, ACCEL, jitter_m, STEP))
    return [found for k, xy in enumerate(positions)
            for found in check.step(STEP * k, {"w": (xy[0], xy[1])})]


def _ends(net_path: Path, walk: tuple[str, ...]) -> tuple[float, float]:
    """The depart and arrival positions the measurement gave ``walk``."""
    import sumolib

    net = sumolib.net.readNet(str(net_path), withInternal=True, withPedestrianConnections=True)
    areas = [e for e in net.getEdges(withInternal=True) if e.getFunction() == "walkingarea"]
    return next((depart, arrival) for _, edges, depart, arrival
                in walker_jitter.passages(net, areas) if edges == walk)


def test_a_break_stops_the_run_in_one_line_or_is_counted(tmp_path, paper) -> None:
    """S1 on a copy of the paper road whose cached measurement for the model says 0.05 m (as
    if it had missed the walking area's jump): the world stops at the jump, in one line with
    the pedestrian, the time, what broke and the jitter its walk needs. A study that lists
    'pedestrian_speed' and sets 0.05 m itself runs on and counts the breaks."""
    key = walker_jitter.cache_key(sumo_version(), STEP, SPEED, RADIUS, ACCEL)
    measure_walkers(paper, load_roadmap(paper), None, SPEED, STEP, RADIUS, ACCEL)
    cache = walker_jitter.JitterCache(paper)
    cache.add(key, [replace(j, jitter_m=0.05) for j in cache.junctions(key).values()])
    on_copy = tmp_path / "on_copy.toml"
    on_copy.write_text(f'extends = "{(REPO / "scenarios" / "s1_pedestrian.toml").as_posix()}"'
                       f'\n[network]\nnet_file = "{paper.as_posix()}"\n', encoding="utf-8")
    with pytest.raises(AssumptionBroken) as info:
        run_world(load_scenario(on_copy, MODEL), tmp_path / "stopped", steps=110)
    text = str(info.value)
    assert "\n" not in text and info.value.assumption == "pedestrian_speed"
    for words in ("pedestrian 'pedestrian' at t=", "its mean velocity changing by",
                  "estimator.position_jitter_m = 0.05 m", "acceleration bound 3.2 m/s²",
                  "its walk breaks ", "raise estimator.position_jitter_m to at least 0."):
        assert words in text, (words, text)
    declared = load_scenario(on_copy, {**MODEL, "estimator.position_jitter_m": 0.05,
                                       "breaks_assumptions": ["pedestrian_speed"]})
    with SumoWorld(declared, tmp_path / "counted", "counted") as world:
        for _ in range(110):
            world.step()
        breaks = world.breaks["assumption_breaks"]
    assert breaks["count"] >= 1 and breaks["first"][0]["pedestrian"] == "pedestrian"
    assert breaks["first"][0]["beyond_m"] > 0.0


def test_the_network_command_measures_the_ramped_walkers_with_accel(paper, capsys) -> None:
    """`sse-cosim network NET --accel-mps2 A` prints the jitter and patches the ramped
    walkers need (the runs of the acceleration model take the same), and says so; without
    the option it prints the position model's."""
    from sse_cosim.cli.main import main

    roadmap = load_roadmap(paper)
    for accel, said in ((ACCEL, f"at {SPEED:g} m/s, ramped within {ACCEL:g} m/s² and"),
                        (None, f"at {SPEED:g} m/s and")):
        main(["network", str(paper), *(["--accel-mps2", str(accel)] if accel else [])])
        line = capsys.readouterr().out.splitlines()[1]
        measured = measure_walkers(paper, roadmap, None, SPEED, STEP, RADIUS, accel)
        assert line.startswith(f"walker jitter: {measured.jitter_m:.3f} m {said}")
