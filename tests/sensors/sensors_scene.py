"""The hand-worked scene of the sensor tests (network metres, headings rad CCW from east).

Road along x: eastbound bus lane y in [-3.5, 0] (bus centre line y = -1.75), parking strip
y in [-6, -3.5], south sidewalk y in [-8, -6]; the westbound lane mirrors it (y in [0, 3.5]).
The truck (10 m x 2.5 m) is parked with its front at x = 194: footprint x in [184, 194],
y in [-6, -3.5].
"""

from __future__ import annotations

import math

from hypothesis import HealthCheck, settings

from sse_cosim.sensors import Camera, SensorSpec
from sse_cosim.world.snapshot import Footprint, PersonState, Pose, Snapshot, VehicleState

SETTINGS = settings(
    derandomize=True,
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)

BUS_Y = -1.75
TRUCK_FRONT = Pose(194.0, -4.75, 0.0)
CAR_FRONT = Pose(240.0, 1.75, math.pi)
RSU1 = Pose(212.0, -9.5, math.radians(165.0))
RSU2 = Pose(184.0, 9.5, math.radians(-30.0))


def vehicle(vid: str, kind: str, front: Pose, length: float, width: float) -> VehicleState:
    """A vehicle with its front bumper centre at ``front``."""
    return VehicleState(vid, kind, Footprint(front, length, width), 0.0)


def bus(x: float) -> VehicleState:
    """The 12 m x 2.55 m bus driving east with its front at (x, -1.75)."""
    return vehicle("bus", "automated", Pose(x, BUS_Y, 0.0), 12.0, 2.55)


def truck() -> VehicleState:
    """The parked truck."""
    return vehicle("truck", "parked", TRUCK_FRONT, 10.0, 2.5)


def car(front: Pose = CAR_FRONT) -> VehicleState:
    """The oncoming 4.5 m x 1.8 m car driving west."""
    return vehicle("car", "vehicle", front, 4.5, 1.8)


def snapshot(
    vehicles: list[VehicleState], persons: dict[str, tuple[float, float]], time: float = 0.0
) -> Snapshot:
    """A snapshot of these vehicles and persons (by id: position)."""
    return Snapshot(
        time,
        {v.id: v for v in vehicles},
        {pid: PersonState(pid, xy, 1.2) for pid, xy in persons.items()},
    )


def paper_specs(noise: str = "uniform") -> dict[str, SensorSpec]:
    """The four sensors of scenarios S1-S3 (bus, car, two road-side units)."""
    return {
        "bus_front": SensorSpec(
            "bus_front", "bus", Camera(math.radians(90), 60.0, (0.5, 0.5), noise)
        ),
        "car_front": SensorSpec(
            "car_front", "car", Camera(math.radians(100), 60.0, (1.0, 1.0), noise)
        ),
        "rsu1_cam": SensorSpec(
            "rsu1_cam", "rsu1", Camera(math.radians(90), 40.0, (1.0, 1.0), noise), static_pose=RSU1
        ),
        "rsu2_cam": SensorSpec(
            "rsu2_cam", "rsu2", Camera(math.radians(90), 40.0, (1.0, 1.0), noise), static_pose=RSU2
        ),
    }
