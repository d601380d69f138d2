"""A pedestrian who hesitates on the zebra (pedestrians.<id>.pause_after_s, pause_for_s): the
timing alone; in real SUMO it stands still for the pause and walks on, within the
acceleration bound under the bounded-acceleration model (the world's checks raise
otherwise); a whole S3 run with the pause in front of the bus stays sound and safe."""

from __future__ import annotations

import numpy as np
import pytest
from world_helpers import REPO, run_world, scenario

from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.model import Pedestrian
from sse_cosim.world.walker_pause import Pause

STEP, ACCEL = 0.1, 3.2


def test_the_pause_stops_the_walker_from_its_start_for_its_length():
    assert Pause.of(Pedestrian(pause_after_s=2.0)) is None  # no length: no pause
    pause = Pause.of(Pedestrian(walking_speed_mps=2.0, pause_after_s=1.0, pause_for_s=0.5))
    assert pause is not None
    since = [None, 0.0, 0.9, 1.0, 1.2, 1.4, 1.5, 3.0]
    assert [pause.speed(s) for s in since] == [2.0, 2.0, 2.0, 0.0, 0.0, 0.0, 2.0, 2.0]
    assert pause.speed(1.0 - 1e-9) == 0.0 and pause.speed(1.5 - 1e-9) == 2.0  # step sums


def _walk(run) -> tuple[np.ndarray, np.ndarray, int]:
    """The pedestrian's speeds and positions at every step, and the first step on the zebra."""
    speeds = np.array([s.persons["pedestrian"].speed for s in run.snapshots])
    xy = np.array([s.persons["pedestrian"].position for s in run.snapshots])
    on = next(i for i, s in enumerate(run.snapshots) if s.persons["pedestrian"].on_crossing)
    return speeds, xy, on


@pytest.mark.sumo
def test_sumo_holds_the_walker_still_on_the_zebra_for_the_pause(tmp_path):
    sc = scenario("s1_pedestrian", **{"pedestrians.pedestrian.pause_after_s": 1.0,
                                      "pedestrians.pedestrian.pause_for_s": 2.0,
                                      "simulation.duration_s": 16.0})
    speeds, xy, on = _walk(run_world(sc, tmp_path))
    still = np.flatnonzero(speeds[on:] == 0.0) + on
    assert still[0] - on == pytest.approx(1.0 / STEP, abs=1)  # stops 1 s after stepping on
    assert still.size == round(2.0 / STEP) and np.all(np.diff(still) == 1)  # 2 s, at once
    assert np.all(xy[still] == xy[still[0]])  # where it stands
    assert speeds[still[-1] + 1] == pytest.approx(1.5)  # walks on at its speed
    assert np.linalg.norm(xy[-1] - xy[still[0]]) > 1.0


@pytest.mark.sumo
def test_under_the_acceleration_model_it_stops_and_starts_within_the_bound(tmp_path):
    """The world's ramp slows the walker by at most a_max dt a step, as it speeds it up; the
    acceleration model's check (run every step by the world) raises on a break."""
    sc = scenario("s1_pedestrian", **{"estimator.state_model": "bounded-acceleration",
                                      "pedestrians.pedestrian.pause_after_s": 1.0,
                                      "pedestrians.pedestrian.pause_for_s": 2.0,
                                      "simulation.duration_s": 16.0})
    speeds, _, on = _walk(run_world(sc, tmp_path))
    change = np.diff(speeds[on:])
    assert change.min() >= -ACCEL * STEP - 1e-9 and change.max() <= ACCEL * STEP + 1e-9
    # it came to a stop within the pause, after slowing from 1.5 m/s in ceil(1.5 / 0.32) steps
    assert (speeds[on:] == 0.0).sum() == round(2.0 / STEP) - np.ceil(1.5 / (ACCEL * STEP)) + 1


@pytest.mark.sumo
def test_a_pause_in_front_of_the_bus_keeps_the_run_sound_and_safe(tmp_path):
    """S3's pedestrian stops 1 s onto the zebra, in the bus's lane's path, for 3 s: the bus
    waits for it and goes on once it is across."""
    summary = run_scenario_file(REPO / "scenarios" / "s3_pedestrian.toml", tmp_path, {
        "pedestrians.pedestrian.pause_after_s": 1.0, "pedestrians.pedestrian.pause_for_s": 3.0},
        plots=False, summary_only=True)
    assert summary["containment_violations"] == 0 and summary["collisions"] == 0
    assert summary["route_completed"]
