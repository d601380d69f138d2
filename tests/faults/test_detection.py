"""Faults beyond the bounds are flagged within 3 steps and the faulty source is left out;
faults within the bounds are not flagged and harm nothing (synthetic, no SUMO)."""

from __future__ import annotations

import numpy as np
import shapely
from synthetic import DT, PED, Harness, SensorSetup, axes, contains

from sse_cosim.estimation.bus_screen import BusScreener
from sse_cosim.estimation.motion import motion_model
from sse_cosim.estimation.occupancy import ClearRegion
from sse_cosim.estimation.vote import READMIT_STEPS
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import kind
from sse_cosim.scenario.model import Estimator
from sse_cosim.sets import Strips, Zonotope

K = kind("polygon")

BUS = "bus"  # the automated vehicle's id (its node)

ONSET = 20
STEPS = 50
FIG4 = {  # paper Fig. 4: a node with two sensors, a third node, and the bus
    "bus_front": SensorSetup("bus", 0.3, 0.5),
    "rsu1_a": SensorSetup("rsu1", 2.0, 1.0),
    "rsu1_b": SensorSetup("rsu1", 2.6, 1.0),
    "rsu2_a": SensorSetup("rsu2", 4.0, 1.0),
}


def biased(sensor: str, offset: float, start: int = ONSET, end: int | None = None,
           within_bound: bool = False):
    """A strip hook adding ``offset`` metres along ``sensor``'s forward axis in [start, end)."""
    def hook(step: int, name: str, strips: Strips, truth: np.ndarray) -> Strips:
        if name != sensor or step < start or (end is not None and step >= end):
            return strips
        values = strips.values + np.array([offset, 0.0])
        if within_bound:
            exact = strips.normals @ truth
            values = exact + np.clip(values - exact, -strips.radii, strips.radii)
        return Strips(strips.normals, values, strips.radii)
    return hook


def first_flag(records, key: str, kind: str = "sensor") -> int | None:
    for r in records:
        if (r.flags.sensors.get(key) if kind == "sensor" else r.flags.nodes.get(key)):
            return r.step
    return None


def test_paper_fig4_a_biased_sensor_is_left_out_and_its_node_stays_sound():
    for seed in range(3):
        harness = Harness(FIG4, seed=seed, strip_hook=biased("rsu1_a", 8.0))
        records = harness.run(STEPS)
        assert first_flag(records, "rsu1_a") - ONSET <= 3, seed
        for r in records[ONSET:]:
            assert r.flags.sensors["rsu1_a"] and not r.flags.sensors["rsu1_b"], (seed, r.step)
            assert not r.tracks["rsu1"][PED].conflict  # attributed: no hull needed
            assert contains(harness.model, r.tracks["rsu1"][PED].estimate, r.truth)
            assert contains(harness.model, r.fused[PED], r.truth)


def test_a_single_sensor_cannot_be_blamed_its_node_keeps_both_hypotheses():
    sensors = {"bus_front": SensorSetup("bus", 0.3, 0.5)}
    for seed in range(3):
        harness = Harness(sensors, seed=seed, strip_hook=biased("bus_front", 6.0))
        records = harness.run(STEPS)
        assert first_flag(records, BUS, "node") - ONSET <= 3, seed
        for r in records[ONSET + 3:]:
            track = r.tracks[BUS][PED]
            assert track.conflict and r.flags.nodes[BUS] == "conflict" and r.flags.inconsistent
            assert contains(harness.model, track.estimate, r.truth), (seed, r.step)


def test_a_bias_within_the_bound_is_not_flagged_and_harms_nothing():
    harness = Harness(FIG4, seed=4, strip_hook=biased("rsu1_a", 0.8, within_bound=True))
    for r in harness.run(STEPS):
        assert not any(r.flags.sensors.values()) and not any(r.flags.nodes.values())
        assert contains(harness.model, r.fused[PED], r.truth)


def test_a_sensor_comes_back_after_its_fault_ends_and_a_probation():
    end = ONSET + 10
    harness = Harness(FIG4, seed=5, strip_hook=biased("rsu1_a", 8.0, end=end))
    records = harness.run(end + READMIT_STEPS + 5)
    flagged = [r.step for r in records if r.flags.sensors["rsu1_a"]]
    assert flagged[0] == ONSET or flagged[0] - ONSET <= 3
    assert flagged[-1] == end + READMIT_STEPS - 1  # agreeing from `end` on, used after probation
    assert all(contains(harness.model, r.fused[PED], r.truth) for r in records)


def stuck(sensor: str, start: int = ONSET):
    frozen: dict[str, Strips] = {}

    def hook(step: int, name: str, strips: Strips, truth: np.ndarray) -> Strips:
        if name != sensor or step < start:
            return strips
        return frozen.setdefault(name, strips)
    return hook


def test_a_stuck_sensor_beside_a_healthy_one_is_caught_and_left_out():
    harness = Harness(FIG4, seed=6, speed=2.5, strip_hook=stuck("rsu1_a"))
    records = harness.run(80)
    caught = first_flag(records, "rsu1_a")
    assert caught is not None
    for r in records[caught:]:
        assert contains(harness.model, r.tracks["rsu1"][PED].estimate, r.truth), r.step
        assert contains(harness.model, r.fused[PED], r.truth), r.step


def shifted(sender: str, offset: tuple[float, float], start: int = ONSET):
    def hook(step: int, node: str, estimate: Zonotope) -> Zonotope:
        if node != sender or step < start:
            return estimate
        return estimate.translate(np.asarray(offset))
    return hook


def test_a_shifted_sender_is_outvoted_by_the_bus_and_the_other_node():
    harness = Harness(FIG4, seed=7, estimate_hook=shifted("rsu2", (6.0, 0.0)))
    records = harness.run(STEPS)
    caught = first_flag(records, "rsu2", "node")
    assert caught - (ONSET + harness.latency) <= 3
    for r in records[caught:]:
        assert r.flags.nodes["rsu2"] == "excluded" and "rsu2" not in r.screen.received[PED]
        assert contains(harness.model, r.fused[PED], r.truth)


def test_two_disagreeing_sources_give_a_conflict_and_the_hull_of_both():
    sensors = {"bus_front": SensorSetup("bus", 0.3, 0.5), "car_a": SensorSetup("car", 3.0, 1.0)}
    harness = Harness(sensors, seed=8, estimate_hook=shifted("car", (0.0, 7.0)))
    records = harness.run(STEPS)
    caught = first_flag(records, "car", "node")
    assert caught - (ONSET + harness.latency) <= 3
    assert records[caught].flags.nodes["car"] == "conflict"
    for r in records[caught:]:  # later a clear view may also contradict the shifted set
        assert r.flags.nodes["car"] in ("conflict", "excluded") and r.flags.inconsistent
        assert contains(harness.model, r.fused[PED], r.truth)


def test_a_claim_inside_a_clear_view_is_dropped_or_kept_in_conflict():
    """A phantom: beside a real claim it is left out; alone it is kept, flagged (it could be
    a real pedestrian placed wrong)."""
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    screener = BusScreener(model, K, BUS)
    ghost = Zonotope(np.array([0.0, 0.0]), np.eye(2))
    real = Zonotope(np.array([30.0, 0.0]), np.eye(2))
    view = [ClearRegion(R(shapely.box(-10, -10, 10, 10)), 1)]
    seen = frozenset({"p"})  # rsu1 reports it as detected
    alone = screener.screen({}, {"p": {"rsu1": ghost}}, {"p": view}, seen)
    assert alone.conflicts == {"p": {"rsu1"}} and "p" in alone.received
    beside = screener.screen({"p": real}, {"p": {"rsu1": ghost}}, {"p": view}, seen)
    assert beside.excluded == {"p": {"rsu1"}} and beside.own == {"p"}


def test_a_pedestrian_nobody_detects_whose_every_set_lies_in_a_clear_view_has_left():
    """SUMO removed it at its destination: no flag, no fused set, no refined region."""
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    screener = BusScreener(model, K, BUS)
    ghost = Zonotope(np.array([0.0, 0.0]), np.eye(2))
    view = [ClearRegion(R(shapely.box(-10, -10, 10, 10)), 0)]
    screen = screener.screen({"p": ghost}, {"p": {"rsu1": ghost}}, {"p": view})
    assert screen.gone == {"p"}
    assert not screen.flags() and not screen.own and not screen.received
    partly = [ClearRegion(R(shapely.box(-10, -10, 0.5, 10)), 0)]  # part of the set is unseen
    assert screener.screen({"p": ghost}, {}, {"p": partly}).gone == frozenset()


def test_strips_are_about_the_sensor_axes():
    h = axes(0.5)
    assert np.allclose(h @ h.T, np.eye(2))
