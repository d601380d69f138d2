"""The step's stages between the snapshot and the picture, on hand-made inputs (no SUMO)."""

from __future__ import annotations

import numpy as np
import shapely

from sse_cosim.estimation.bus_screen import BusScreen
from sse_cosim.estimation.flags import StepFlags
from sse_cosim.estimation.fusion_centre import BusEstimate
from sse_cosim.estimation.motion import motion_model
from sse_cosim.estimation.observer import Track
from sse_cosim.estimation.occupancy import OccupancyTracker
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.estimation.v2x import SharedPicture
from sse_cosim.pipeline.stages import (
    RefinedRegions,
    clear_regions,
    detected_now,
    detections_by_node,
    second_level,
    views_by_node,
    views_of,
)
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import kind
from sse_cosim.scenario.model import Estimator
from sse_cosim.sensors import Detection, SensorObservation
from sse_cosim.sets import Strips, Zonotope
from sse_cosim.world.snapshot import Pose

BUS = "bus"  # the automated vehicle's id (its node)
K = kind("polygon")

DT = 0.1
STRIPS = Strips(np.eye(2), np.zeros(2), np.ones(2))


def observation(sensor: str, node: str, seen: tuple[str, ...], box,
                pose: Pose | None = None) -> SensorObservation:
    detections = {pid: Detection(sensor, node, 0.0, pid, STRIPS) for pid in seen}
    return SensorObservation(sensor, node, 0.0, pose, detections, R(shapely.box(*box)),
                             R(shapely.box(box[0], box[1], box[0] + 0.5, box[1] + 0.5)))


def test_each_node_views_the_union_of_its_present_sensors():
    here = Pose(0.0, 0.0, 0.0)
    observations = {"front": observation("front", BUS, (), (0, 0, 2, 1), here),
                    "rear": observation("rear", BUS, (), (1, 0, 3, 2), here),
                    "gone": observation("gone", BUS, (), (10, 10, 11, 11)),  # carrier absent
                    "cam": observation("cam", "rsu1", (), (5, 5, 6, 6), here)}
    views = views_by_node(observations, K)
    assert set(views) == {BUS, "rsu1"}
    assert views[BUS].visible.shape.equals_exact(
        shapely.union_all([shapely.box(0, 0, 2, 1), shapely.box(1, 0, 3, 2)]), 0.0)
    assert views[BUS].occluded.area == 0.5
    assert views["rsu1"].visible.area == 1.0


def test_detections_are_grouped_by_node_pedestrian_and_sensor():
    observations = {"front": observation("front", BUS, ("a",), (0, 0, 1, 1)),
                    "near": observation("near", BUS, ("a", "b"), (0, 0, 1, 1)),
                    "cam": observation("cam", "rsu1", ("b",), (0, 0, 1, 1))}
    grouped = detections_by_node(observations)
    assert {n: {p: list(s) for p, s in d.items()} for n, d in grouped.items()} == {
        BUS: {"a": ["front", "near"], "b": ["near"]}, "rsu1": {"b": ["cam"]}}
    assert [o.sensor for o in views_of(BUS, observations)] == ["front", "near"]


def test_clear_regions_and_detections_join_the_bus_and_the_senders():
    views = [observation("front", BUS, ("a",), (0, 0, 1, 1)),
             observation("near", BUS, (), (5, 5, 6, 6))]
    z = Zonotope(np.zeros(2), np.eye(2))
    own = {"a": Track("a", z, 3, True)}
    shared = SharedPicture({"b": {"rsu1": z}}, {"rsu1": R(shapely.box(9, 9, 10, 10))},
                           {"rsu1": 1}, {"rsu1": frozenset({"b"})})
    clear = clear_regions(views, own, shared)
    assert [(c.region.bounds, c.age) for c in clear["a"]] == [
        ((5, 5, 6, 6), 0), ((9, 9, 10, 10), 1)]
    assert [(c.region.bounds, c.age) for c in clear["b"]] == [((0, 0, 1, 1), 0), ((5, 5, 6, 6), 0)]
    assert detected_now(own, shared) == {"a", "b"}


def test_the_pedestrians_in_view_are_those_some_node_detects_now():
    """The bus detects "a" now, not "c" (known from earlier); rsu1's newest message reports
    "b" detected: "a" and "b" are in view, "c" is only known."""
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    fusion = second_level("labelled", model, EstimatorSettings("enclose", "girard", 8), "enclose",
                          ["front"], BUS, K)
    z = Zonotope(np.zeros(2), np.eye(2))
    own = {"a": Track("a", z, 3, True), "c": Track("c", z + np.array([9.0, 0.0]), 1, False)}
    shared = SharedPicture({"b": {"rsu1": z + np.array([0.0, 9.0])}},
                           {"rsu1": R(shapely.box(-1, 8, 1, 10))}, {"rsu1": 1},
                           {"rsu1": frozenset({"b"})})
    front = observation("front", BUS, ("a",), (-1, -1, 1, 1))
    estimate, _ = fusion.step({BUS: own, "rsu1": {}}, shared, [front], front.visible)
    assert set(estimate.fused) == {"a", "b", "c"}
    assert estimate.in_view == {"a", "b"}


def test_refined_regions_forget_their_history_when_the_picture_turns_inconsistent():
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    walkable = R(shapely.box(-20, -20, 20, 20))
    small = {"ped": Zonotope(np.zeros(2), np.eye(2) * 0.5)}
    large = {"ped": Zonotope(np.zeros(2), np.eye(2) * 3.0)}

    def estimate(fused, inconsistent: bool) -> BusEstimate:
        return BusEstimate(BusScreen(), fused, StepFlags(inconsistent=inconsistent), {})

    regions = RefinedRegions(OccupancyTracker(model, K, walkable))
    regions.update(0, {}, estimate(small, False), {})
    kept = regions.update(1, {}, estimate(large, False), {})["ped"].area
    regions.update(2, {}, estimate(small, False), {})
    forgot = regions.update(3, {}, estimate(large, True), {})["ped"].area
    assert kept < forgot  # the small set's history no longer cuts the large one
    regions.update(4, {}, estimate(small, True), {})  # still inconsistent: nothing new to forget
    assert regions.update(5, {}, estimate(large, True), {})["ped"].area < forgot
