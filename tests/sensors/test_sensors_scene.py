"""Hand-worked visibility in the paper's scene (numbers worked out in the comments)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from sensors_scene import (
    BUS_Y,
    CAR_FRONT,
    RSU1,
    RSU2,
    TRUCK_FRONT,
    bus,
    car,
    paper_specs,
    snapshot,
    truck,
)

from sse_cosim.regions import kind
from sse_cosim.scenario.model import AutomatedVehicle, RoadSideUnit, Scenario, SensorMount
from sse_cosim.sensors import (
    Boxes,
    Camera,
    SensorSpec,
    in_sector,
    line_of_sight,
    observe,
    sector_polygon,
    seen_mask,
    specs_from_scenario,
    visibility_regions,
)
from sse_cosim.sensors.kinds import CameraConfig
from sse_cosim.world.snapshot import Pose

K = kind("polygon")

PED = (190.0, -7.0)  # on the south sidewalk, level with the truck's middle
CURB_PED = (190.0, -6.5)  # same x, 0.5 m from the kerb (closer to the truck)
BUS_FOV, BUS_RANGE = math.radians(90), 60.0


def bus_sees(bus_x: float, point: tuple[float, float]) -> bool:
    """Whether the bus's front sensor at (bus_x, -1.75) sees ``point`` past the truck."""
    boxes = Boxes.from_footprints([truck().footprint])
    pose = Pose(bus_x, BUS_Y, 0.0)
    return bool(seen_mask(pose, BUS_FOV, BUS_RANGE, np.array([point]), boxes)[0])


def test_truck_footprint_is_the_parking_strip_box():
    corners = truck().footprint.corners()
    assert np.allclose(corners.min(axis=0), [184.0, -6.0])
    assert np.allclose(corners.max(axis=0), [194.0, -3.5])


def test_bus_at_150_is_not_yet_blinded_for_the_sidewalk_point():
    # The brief expected (190, -7) hidden from the bus front at x = 150. The geometry says
    # otherwise: the segment (150, -1.75) -> (190, -7) has slope -5.25/40, so at the truck's
    # rear x = 184 it is at y = -1.75 - 5.25 * 34 / 40 = -6.2125, 0.2125 m south of the truck's
    # rear-right corner (184, -6): it runs along the sidewalk, under the truck. The point is
    # 40.34 m away at 7.5° off the boresight, so it is seen.
    assert bus_sees(150.0, PED)
    # Closer to the kerb the truck does hide it: to (190, -6.5) the segment is at
    # y = -1.75 - 4.75 * 34 / 40 = -5.7875 at x = 184, inside the truck's y in [-6, -3.5].
    assert not bus_sees(150.0, CURB_PED)


def test_bus_is_blinded_for_the_sidewalk_point_from_x_158_5():
    # The segment to (190, -7) touches the corner (184, -6) when
    # 5.25 * (184 - x) = 4.25 * (190 - x), i.e. x = 158.5; beyond, the truck hides the point
    # until the bus is beside the truck.
    assert bus_sees(158.0, PED)
    for x in (159.0, 165.0, 170.0, 180.0):
        assert not bus_sees(x, PED), x


def test_oncoming_car_sees_the_point_behind_the_truck():
    # Car front at (240, 1.75) heading west, 100° FOV: (190, -7) is at (-50, -8.75), 50.76 m,
    # 9.93° off the boresight. At the truck's front x = 194 the segment is at
    # y = 1.75 - 8.75 * 46 / 50 = -6.3 < -6: it passes south of the truck.
    pose, fov = CAR_FRONT, math.radians(100)
    boxes = Boxes.from_footprints([truck().footprint])
    target = np.array([PED])
    assert math.isclose(math.hypot(50.0, 8.75), 50.760, abs_tol=1e-3)
    assert in_sector(pose, fov, 60.0, target)[0]
    assert line_of_sight(pose.position, target, boxes)[0]
    # ... but not the kerb point: y = 1.75 - 8.25 * 46 / 50 = -5.84 at x = 194 (in the truck).
    assert not line_of_sight(pose.position, np.array([CURB_PED]), boxes)[0]


def test_rsu1_sees_the_point_behind_the_truck():
    # RSU1 at (212, -9.5) heading 165°, 90° FOV, 40 m: (190, -7) is at (-22, 2.5), 22.14 m,
    # bearing 173.5°, 8.5° off the boresight; the segment stays at y <= -7 (south of the
    # truck's y = -6 edge), e.g. y = -7.45 at x = 194.
    target = np.array([PED])
    boxes = Boxes.from_footprints([truck().footprint])
    assert in_sector(RSU1, math.radians(90), 40.0, target)[0]
    assert line_of_sight(RSU1.position, target, boxes)[0]


def test_observe_the_paper_scene():
    # Bus front at x = 170 (blinded, see above); RSU2 at (184, 9.5) heading -30° has the point
    # in its sector ((6, -16.5): 17.6 m, -70°, 40° off) but the truck is in the way: the
    # segment crosses y = -3.5 at x = 184 + 6 * 13 / 16.5 = 188.7, on the truck's top edge.
    snap = snapshot([bus(170.0), truck(), car()], {"p": PED}, time=3.0)
    obs = observe(snap, paper_specs(), np.random.default_rng(1))
    assert list(obs) == ["bus_front", "car_front", "rsu1_cam", "rsu2_cam"]
    assert {name: set(o.detections) for name, o in obs.items()} == {
        "bus_front": set(),
        "car_front": {"p"},
        "rsu1_cam": {"p"},
        "rsu2_cam": set(),
    }
    assert obs["bus_front"].pose == Pose(170.0, BUS_Y, 0.0)
    assert obs["rsu2_cam"].pose == RSU2
    det = obs["car_front"].detections["p"]
    assert (det.sensor, det.node, det.time, det.person_id) == ("car_front", "car", 3.0, "p")
    assert det.strips.contains(np.array(PED))
    assert all(o.visible is None and o.occluded is None for o in obs.values())


def test_out_of_range_or_outside_the_opening_is_not_seen():
    specs = {"bus_front": paper_specs()["bus_front"]}
    x0 = 150.0

    def at(bearing_deg: float, dist: float = 20.0) -> tuple[float, float]:
        b = math.radians(bearing_deg)
        return (x0 + dist * math.cos(b), BUS_Y + dist * math.sin(b))

    persons = {
        "range_in": (x0 + 59.9, BUS_Y),
        "range_out": (x0 + 60.1, BUS_Y),
        "angle_in": at(44.0),
        "angle_in_right": at(-44.0),
        "angle_out": at(46.0),
        "angle_out_right": at(-46.0),
        "behind": (x0 - 5.0, BUS_Y),
    }
    obs = observe(snapshot([bus(x0)], persons), specs, np.random.default_rng(0))["bus_front"]
    assert set(obs.detections) == {"range_in", "angle_in", "angle_in_right"}


def test_the_trucks_own_sensor_ignores_the_truck():
    # A sensor on the truck's front bumper looking back along it (yaw 180°): the segment to
    # (180, -4.75) runs through the truck's own body, which does not hide anything from it; the
    # same sensor on a unit standing there is blinded by the truck.
    rear = Camera(math.radians(90), 30.0)
    on_truck = SensorSpec("truck_rear", "truck", rear, yaw_rad=math.pi)
    on_unit = SensorSpec("unit", "unit", rear, yaw_rad=math.pi, static_pose=TRUCK_FRONT)
    snap = snapshot([truck(), bus(150.0)], {"p": (180.0, -4.75)})
    obs = observe(snap, {"a": on_truck, "b": on_unit}, np.random.default_rng(0), K)
    assert set(obs["a"].detections) == {"p"}
    assert not obs["b"].detections
    assert obs["a"].occluded.area == 0.0
    assert obs["b"].visible.area < 1e-9  # the unit stands on the truck's boundary: all hidden


def test_absent_carrier_sees_nothing():
    snap = snapshot([bus(170.0), truck()], {"p": PED})  # the car has not departed yet
    specs = paper_specs()
    obs = observe(snap, specs, np.random.default_rng(1), regions=K)["car_front"]
    assert obs.pose is None and not obs.detections
    assert obs.visible.is_empty and obs.occluded.is_empty
    plain = observe(snap, specs, np.random.default_rng(1))["car_front"]
    assert plain.visible is None and plain.occluded is None


def test_occluded_area_behind_the_truck_by_hand():
    # From (150, -1.75) the truck's silhouette corners are (184, -6) and (194, -3.5) (bearings
    # -atan(4.25/34) and -atan(1.75/44)); the near faces are x = 184 and y = -3.5. Occluded =
    # circular sector between the bearings (R = 60) minus the quadrilateral
    # (150,-1.75), (184,-6), (184,-3.5), (194,-3.5) of area 51.25:
    # 1800 * (0.124355 - 0.039752) - 51.25 = 101.04 m².
    pose = Pose(150.0, BUS_Y, 0.0)
    dtheta = math.atan2(4.25, 34.0) - math.atan2(1.75, 44.0)
    expected = 0.5 * 60.0**2 * dtheta - 51.25
    assert math.isclose(expected, 101.04, abs_tol=0.01)
    boxes = Boxes.from_footprints([truck().footprint, bus(150.0).footprint])
    own = np.array([True, False])  # the bus's own footprint is left out
    visible, occluded = visibility_regions(
        pose, BUS_FOV, BUS_RANGE, boxes.subset(own), resolution=256
    )
    assert occluded.area == pytest.approx(expected, abs=0.01)
    quarter_disc = math.pi * 60.0**2 / 4
    assert visible.area + occluded.area == pytest.approx(quarter_disc, rel=1e-4)


def test_static_sectors_are_cached_and_moving_ones_are_not():
    specs = paper_specs()
    rsu = specs["rsu1_cam"]
    assert rsu.sector(RSU1) is rsu.sector(RSU1)
    moving = specs["bus_front"]
    pose = Pose(150.0, BUS_Y, 0.0)
    assert moving.sector(pose) is not moving.sector(pose)
    assert moving.sector(pose).equals(sector_polygon(pose, BUS_FOV, BUS_RANGE, 16))


def test_specs_from_the_scenario_schema_and_mounting():
    scenario = Scenario(
        name="t",
        automated={"bus": AutomatedVehicle()},
        rsus={"rsu1": RoadSideUnit(x_m=212.0, y_m=-9.5, heading_deg=165.0)},
        sensors={
            "bus_side": CameraConfig(
                node="bus",
                mount=SensorMount(forward_m=-2.0, left_m=1.0, yaw_deg=90.0),
                fov_deg=120.0,
                range_m=30.0,
                noise_bound_m=(0.3, 0.7),
                noise="worst-case",
            ),
            "rsu1_cam": CameraConfig(node="rsu1", fov_deg=360.0, range_m=40.0),
        },
    )
    specs = specs_from_scenario(scenario)
    side = specs["bus_side"]
    assert (side.node, side.kind.noise, side.kind.noise_bound_m, side.range_m) == (
        "bus",
        "worst-case",
        (0.3, 0.7),
        30.0,
    )
    assert side.fov_rad == pytest.approx(math.radians(120)) and not side.is_static
    carrier = Pose(170.0, BUS_Y, 0.3)
    got, want = side.mounted_on(carrier), carrier.compose(-2.0, 1.0, math.pi / 2)
    assert (got.x, got.y, got.heading) == pytest.approx((want.x, want.y, want.heading))
    cam = specs["rsu1_cam"]
    assert cam.is_static and cam.static_pose == RSU1
    assert cam.static_sensor_pose == RSU1
    # A 360° sector is the disc: everything within 40 m of the unit, any bearing.
    disc = cam.sector(RSU1)
    assert disc.area == pytest.approx(math.pi * 40.0**2, rel=2e-3)
    assert in_sector(RSU1, cam.fov_rad, 40.0, np.array([[252.0, -9.5], [172.0, -9.5]])).all()


def test_empty_scenes():
    specs = paper_specs()
    rng = np.random.default_rng(0)
    only_person = observe(snapshot([], {"p": PED}), specs, rng, regions=K)
    assert set(only_person["rsu1_cam"].detections) == {"p"}  # no vehicle: nothing in the way
    assert only_person["rsu1_cam"].occluded.is_empty
    assert only_person["bus_front"].pose is None
    nobody = observe(snapshot([bus(170.0), truck()], {}), specs, rng, regions=K)
    assert all(not o.detections for o in nobody.values())
    assert nobody["bus_front"].occluded.area > 0.0
