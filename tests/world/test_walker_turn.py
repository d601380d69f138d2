"""A pedestrian who turns back on the zebra, waits at its near end and then crosses after all
(pedestrians.<id>.turn_back_after_s, turn_back_wait_s): the walk along the crossing's lane on
its own (speeds within the walking speed and, with a bound, changing by at most a_max dt a
step); in real SUMO the world places the walker on the lane step by step and removes it at the
far end, within the estimator's assumptions (the world's checks raise otherwise), and a whole
S3 run with the turn in front of the bus stays sound and safe."""

from __future__ import annotations

import math

import numpy as np
import pytest
from world_helpers import REPO, run_world, scenario

from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.model import Pedestrian
from sse_cosim.world.walker_turn import CrossingWalker, StraightLane, TurnBack, stopping_speed

STEP, ACCEL = 0.1, 3.2


def _walk(walker: CrossingWalker) -> tuple[np.ndarray, np.ndarray]:
    """Positions and velocities of ``walker`` at every step until it leaves."""
    at, velocity = [walker.at_m], [walker.velocity_mps]
    for _ in range(10_000):
        if walker.step() is None:
            return np.array(at), np.array(velocity)
        at.append(walker.at_m)
        velocity.append(walker.velocity_mps)
    raise AssertionError("the walker never left")


def test_no_turn_without_its_time_and_the_turn_comes_when_due():
    assert TurnBack.of(Pedestrian()) is None
    turn = TurnBack.of(Pedestrian(walking_speed_mps=2.0, turn_back_after_s=1.5,
                                  turn_back_wait_s=3.0))
    assert turn == TurnBack(2.0, 1.5, 3.0)
    assert [turn.due(s) for s in (None, 0.0, 1.4, 1.5 - 1e-9, 1.5, 4.0)] == [
        False, False, False, True, True, True]


@pytest.mark.parametrize("rise", [ACCEL * STEP, None])
def test_it_goes_back_waits_then_crosses_and_leaves_within_its_bounds(rise):
    """Walking at 2 m/s toward the lane's end (12 m) from 5 m: back to 0.05 m, 1 s there,
    then to 11.65 m."""
    walker = CrossingWalker(5.0, 2.0, 0.05, 11.65, 2.0, 1.0, STEP, rise)
    at, velocity = _walk(walker)
    assert np.abs(velocity).max() <= 2.0 + 1e-12
    assert np.allclose(np.diff(at), velocity[1:] * STEP)  # each step moves by its speed
    if rise is not None:
        assert np.abs(np.diff(velocity)).max() <= rise + 1e-12
    stands = np.flatnonzero((at == 0.05) & (velocity == 0.0))
    assert stands.size >= round(1.0 / STEP)  # it waits at the near end
    turn = int(np.argmax(at[:stands[0]]))  # it slows ahead (with a bound), then goes back
    assert np.all(np.diff(at[:turn + 1]) >= 0) and np.all(np.diff(at[turn:stands[0] + 1]) <= 0)
    assert (turn > 0) == (rise is not None)
    assert np.all(np.diff(at[stands[-1]:]) >= 0) and at[-1] == 11.65 and velocity[-1] == 0.0


def test_without_an_acceleration_bound_it_turns_at_once():
    walker = CrossingWalker(5.0, 2.0, 0.05, 11.65, 2.0, 0.0, STEP, None)
    walker.step()
    assert walker.velocity_mps == -2.0 and walker.at_m == pytest.approx(4.8)


def test_the_stopping_speed_stops_the_walker_where_it_is_meant_to():
    rise = ACCEL * STEP
    for distance in (0.01, 0.3, 1.0, 4.0):
        speed, left = stopping_speed(distance, rise, STEP), distance
        while speed > 1e-12:  # slowing by rise a step from there covers the distance exactly
            left -= speed * STEP
            speed = max(speed - rise, 0.0)
        assert left == pytest.approx(0.0, abs=1e-9)


def test_a_straight_lane_gives_points_along_it_and_to_its_left():
    lane = StraightLane((200.0, 6.0), (200.0, -6.0))  # a crossing drawn southward
    assert lane.length == 12.0 and lane.heading == pytest.approx(-math.pi / 2)
    assert lane.along((200.4, -3.0)) == pytest.approx(9.0)
    assert lane.lateral((200.4, -3.0)) == pytest.approx(0.4)  # east: left of southward


def _pedestrian(run) -> tuple[np.ndarray, np.ndarray, int]:
    """The pedestrian's positions and speeds while it is in the scene, and its first step on
    the zebra."""
    there = [s.persons["pedestrian"] for s in run.snapshots if "pedestrian" in s.persons]
    xy = np.array([p.position for p in there])
    on = next(i for i, p in enumerate(there) if p.on_crossing)
    return xy, np.array([p.speed for p in there]), on


@pytest.mark.sumo
@pytest.mark.parametrize("model", ["position", "bounded-acceleration"])
def test_sumo_turns_the_walker_back_and_it_crosses_after_its_wait(tmp_path, model):
    """S1's pedestrian walks north over the zebra (x 200.4); 1.5 s on, it turns back, waits
    2 s at the south end and crosses; the world's motion and ground checks hold every step."""
    sc = scenario("s1_pedestrian", **{"estimator.state_model": model,
                                      "pedestrians.pedestrian.turn_back_after_s": 1.5,
                                      "pedestrians.pedestrian.turn_back_wait_s": 2.0,
                                      "simulation.duration_s": 30.0})
    run = run_world(sc, tmp_path)
    xy, speeds, on = _pedestrian(run)
    y = xy[on:, 1]
    back = int(np.argmax(y[:40]))  # where it turned: north of where it stepped on
    assert back >= round(1.5 / STEP) and y[back] > y[0] + 1.0
    assert y[back + 20] < y[back]  # it walked back south
    stands = np.flatnonzero(speeds[on:] == 0.0)
    assert stands.size >= round(2.0 / STEP)
    assert np.allclose(xy[on:][stands, 0], 200.4)  # on the zebra, where it walked
    assert y[-1] > 5.5 and "pedestrian" not in run.snapshots[-1].persons  # crossed, then left
    if model == "bounded-acceleration":
        assert np.abs(np.diff(speeds[on:])).max() <= ACCEL * STEP + 1e-9


@pytest.mark.sumo
def test_a_turn_in_front_of_the_bus_keeps_the_run_sound_and_safe(tmp_path):
    """S3's pedestrian turns back 2 s onto the zebra at the speed bound, waits 1 s, and
    crosses: the bus waits and finishes its route."""
    summary = run_scenario_file(REPO / "scenarios" / "s3_pedestrian.toml", tmp_path, {
        "pedestrians.pedestrian.walking_speed_mps": 2.5,
        "pedestrians.pedestrian.turn_back_after_s": 2.0,
        "pedestrians.pedestrian.turn_back_wait_s": 1.0}, plots=False, summary_only=True)
    assert summary["containment_violations"] == 0 and summary["collisions"] == 0
    assert summary["route_completed"]


@pytest.mark.sumo
def test_a_pedestrian_off_the_zebra_by_its_turn_does_not_turn(tmp_path):
    """Due 20 s after stepping on, long after it crossed: it walks on to its destination."""
    plain = run_world(scenario("s1_pedestrian", **{"simulation.duration_s": 30.0}), tmp_path)
    late = run_world(scenario("s1_pedestrian", **{
        "pedestrians.pedestrian.turn_back_after_s": 20.0, "simulation.duration_s": 30.0}),
        tmp_path / "late")
    assert [s.persons.get("pedestrian") for s in late.snapshots] == [
        s.persons.get("pedestrian") for s in plain.snapshots]


@pytest.mark.sumo
def test_a_pedestrian_paused_when_its_turn_comes_goes_back_to_its_own_side(tmp_path):
    """Standing still on the zebra (a pause) when it turns, it has no heading of its own to
    turn from: it goes back to the end on its start's side (south), then crosses."""
    run = run_world(scenario("s1_pedestrian", **{
        "pedestrians.pedestrian.pause_after_s": 1.0, "pedestrians.pedestrian.pause_for_s": 5.0,
        "pedestrians.pedestrian.turn_back_after_s": 2.0, "simulation.duration_s": 30.0}),
        tmp_path)
    xy, _, on = _pedestrian(run)
    y = xy[on:, 1]
    south = int(np.argmin(y[20:])) + 20  # after the turn it went south, back to its side
    assert y[south] == pytest.approx(-5.65) and y[south] < y[20] - 0.5 and y[-1] > 5.5
