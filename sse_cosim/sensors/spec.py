"""Sensor specifications and mounting: where a sensor is, given its carrier."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Literal

import numpy as np
import shapely

from sse_cosim.sensors.geometry import cached_sector_polygon, sector_polygon
from sse_cosim.world.snapshot import Pose, Snapshot, VehicleState

if TYPE_CHECKING:  # the schema is only needed for type checking
    from sse_cosim.scenario.model import RoadSideUnit, Scenario, Sensor

NoiseKind = Literal["uniform", "worst-case"]


@dataclass(frozen=True)
class SensorSpec:
    """One sensor: its carrier, mounting, sector and noise.

    ``node`` is the carrier: a vehicle role ('bus', 'car', ...) or vehicle id, or, when
    ``static_pose`` is set, a road-side unit standing at that pose. The mount offsets are in
    the carrier's frame from its reference point (a vehicle's front bumper centre, a unit's
    position); ``yaw_rad`` turns the boresight CCW. ``noise_bound_m`` is (forward, lateral)
    in the sensor's frame; ``resolution`` is the number of arc chords per quarter turn of
    the sector polygon.
    """

    name: str
    node: str
    fov_rad: float = 0.5 * math.pi
    range_m: float = 60.0
    noise_bound_m: tuple[float, float] = (0.5, 0.5)
    noise: NoiseKind = "uniform"
    forward_m: float = 0.0
    left_m: float = 0.0
    yaw_rad: float = 0.0
    static_pose: Pose | None = None
    resolution: int = 16

    @classmethod
    def from_config(
        cls, name: str, sensor: Sensor, rsus: Mapping[str, RoadSideUnit] | None = None
    ) -> SensorSpec:
        """The spec of scenario sensor ``name``; ``rsus`` (by id) give static carriers."""
        unit = (rsus or {}).get(sensor.node)
        static = None if unit is None else Pose(unit.x_m, unit.y_m, math.radians(unit.heading_deg))
        return cls(
            name=name,
            node=sensor.node,
            fov_rad=math.radians(sensor.fov_deg),
            range_m=float(sensor.range_m),
            noise_bound_m=(float(sensor.noise_bound_m[0]), float(sensor.noise_bound_m[1])),
            noise=sensor.noise,
            forward_m=float(sensor.mount.forward_m),
            left_m=float(sensor.mount.left_m),
            yaw_rad=math.radians(sensor.mount.yaw_deg),
            static_pose=static,
        )

    @property
    def is_static(self) -> bool:
        """Whether the carrier is a road-side unit (fixed pose)."""
        return self.static_pose is not None

    @property
    def bounds(self) -> np.ndarray:
        """Noise bounds r (forward, lateral), shape (2,)."""
        return np.asarray(self.noise_bound_m, dtype=float)

    def mounted_on(self, carrier: Pose) -> Pose:
        """The sensor's world pose on a carrier at ``carrier`` (its reference pose).

        Same as ``carrier.compose(forward_m, left_m, yaw_rad)``, in scalar arithmetic.
        """
        c, s = math.cos(carrier.heading), math.sin(carrier.heading)
        return Pose(
            carrier.x + self.forward_m * c - self.left_m * s,
            carrier.y + self.forward_m * s + self.left_m * c,
            carrier.heading + self.yaw_rad,
        )

    @cached_property
    def static_sensor_pose(self) -> Pose | None:
        """The world pose of a static sensor (computed once), None on a vehicle."""
        return None if self.static_pose is None else self.mounted_on(self.static_pose)

    def sector(self, pose: Pose) -> shapely.Polygon:
        """The field-of-view polygon at ``pose``; memoised for static sensors."""
        if self.is_static:
            return cached_sector_polygon(pose, self.fov_rad, self.range_m, self.resolution)
        return sector_polygon(pose, self.fov_rad, self.range_m, self.resolution)


def specs_from_scenario(scenario: Scenario) -> dict[str, SensorSpec]:
    """Every sensor of a scenario as a spec, by name (scenario order)."""
    return {
        name: SensorSpec.from_config(name, sensor, scenario.rsus)
        for name, sensor in scenario.sensors.items()
    }


def find_carrier(snapshot: Snapshot, node: str) -> VehicleState | None:
    """The vehicle carrying ``node``'s sensors: first by role, then by id; None if absent."""
    return snapshot.role(node) or snapshot.vehicles.get(node)


def locate(spec: SensorSpec, snapshot: Snapshot) -> tuple[Pose, str | None] | None:
    """``(sensor pose, carrier vehicle id or None for a unit)``, or None if the carrier is gone."""
    static = spec.static_sensor_pose
    if static is not None:
        return static, None
    carrier = find_carrier(snapshot, spec.node)
    if carrier is None:
        return None
    return spec.mounted_on(carrier.footprint.front), carrier.id
