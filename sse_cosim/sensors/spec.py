"""Sensor specifications and mounting: where a sensor is, given its carrier, and its kind.

A sensor with a ``carrier_type`` is carried by every vehicle of that SUMO type
(route-file vehicles, ``network.route_files``): at each step :func:`sensor_instances` turns it
into one instance per such vehicle in the scene, named ``<sensor>@<vehicle id>``, whose node
is the vehicle id -- a connected node that exists while the vehicle is in the scene.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import TYPE_CHECKING

import shapely

from sse_cosim.memo import IdentityMemo
from sse_cosim.sensors.geometry import sector_polygon
from sse_cosim.sensors.kinds import Camera, SensorKind
from sse_cosim.world.snapshot import Pose, Snapshot, VehicleState

if TYPE_CHECKING:  # the schema is only needed for type checking
    from sse_cosim.scenario.model import RoadSideUnit, Scenario, Sensor


VIEWS_KEPT = 8  # a static sensor keeps its regions for this many sets of occluders


@dataclass(frozen=True)
class SensorSpec:
    """One sensor: its carrier, mounting and kind (what it sees and how it measures).

    ``node`` is the carrier: a vehicle's id ('bus', 'car', ...), or, when
    ``static_pose`` is set, a road-side unit standing at that pose. The mount offsets are in
    the carrier's frame from its reference point (a vehicle's front bumper centre, a unit's
    position); ``yaw_rad`` turns the boresight CCW. ``resolution`` is the number of arc
    chords per quarter turn of the field-of-view polygon. With ``carrier_type`` set the spec
    is a template carried by every vehicle of that type (``node`` is empty; see
    :func:`sensor_instances`).
    """

    name: str
    node: str
    kind: SensorKind = field(default_factory=Camera)
    forward_m: float = 0.0
    left_m: float = 0.0
    yaw_rad: float = 0.0
    static_pose: Pose | None = None
    resolution: int = 16
    carrier_type: str | None = None
    # a static sensor's newest visible and occluded regions, by occluders (visibility_regions)
    views: IdentityMemo[tuple[shapely.Geometry, shapely.Geometry]] = field(
        default_factory=lambda: IdentityMemo(VIEWS_KEPT), compare=False, repr=False)

    @classmethod
    def from_config(
        cls, name: str, sensor: Sensor, rsus: Mapping[str, RoadSideUnit] | None = None
    ) -> SensorSpec:
        """The spec of scenario sensor ``name``; ``rsus`` (by id) give static carriers."""
        unit = (rsus or {}).get(sensor.node)
        static = None if unit is None else Pose(unit.x_m, unit.y_m, math.radians(unit.heading_deg))
        return cls(
            name=name,
            node=sensor.node or "",
            kind=sensor.build(),
            forward_m=float(sensor.mount.forward_m),
            left_m=float(sensor.mount.left_m),
            yaw_rad=math.radians(sensor.mount.yaw_deg),
            static_pose=static,
            carrier_type=sensor.carrier_type,
        )

    @property
    def fov_rad(self) -> float:
        """Opening of the field of view (rad; >= 2 pi: all around)."""
        return self.kind.fov_rad

    @property
    def range_m(self) -> float:
        """Reach of the field of view (m)."""
        return self.kind.range_m

    @property
    def is_static(self) -> bool:
        """Whether the carrier is a road-side unit (fixed pose)."""
        return self.static_pose is not None

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

    @cached_property
    def static_sector(self) -> shapely.Polygon | None:
        """A static sensor's field-of-view polygon (computed once, prepared), None on a
        vehicle."""
        pose = self.static_sensor_pose
        if pose is None:
            return None
        polygon = sector_polygon(pose, self.fov_rad, self.range_m, self.resolution)
        shapely.prepare(polygon)
        return polygon

    def sector(self, pose: Pose) -> shapely.Polygon:
        """The field-of-view polygon at ``pose`` (a static sensor's, kept, at its pose)."""
        if self.is_static and pose == self.static_sensor_pose:
            return self.static_sector
        return sector_polygon(pose, self.fov_rad, self.range_m, self.resolution)


def specs_from_scenario(scenario: Scenario) -> dict[str, SensorSpec]:
    """Every sensor of a scenario as a spec, by name (scenario order)."""
    return {
        name: SensorSpec.from_config(name, sensor, scenario.rsus)
        for name, sensor in scenario.sensors.items()
    }


INSTANCE_MARK = "@"


def instance_name(sensor: str, vehicle_id: str) -> str:
    """The name of sensor ``sensor`` carried by vehicle ``vehicle_id``: ``<sensor>@<id>``."""
    return f"{sensor}{INSTANCE_MARK}{vehicle_id}"


def sensor_instances(specs: Mapping[str, SensorSpec],
                     snapshot: Snapshot) -> dict[str, SensorSpec]:
    """The sensors at this snapshot, by name: every spec with a node as it is, every
    ``carrier_type`` template as one instance per vehicle of that type in the scene (snapshot
    order), in the template's place."""
    result: dict[str, SensorSpec] = {}
    for name, spec in specs.items():
        if spec.carrier_type is None:
            result[name] = spec
            continue
        for vehicle in snapshot.vehicles.values():
            if vehicle.type_id == spec.carrier_type:
                instance = instance_name(name, vehicle.id)
                result[instance] = replace(spec, name=instance, node=vehicle.id,
                                           carrier_type=None)
    return result


def find_carrier(snapshot: Snapshot, node: str) -> VehicleState | None:
    """The vehicle carrying ``node``'s sensors (its id is the node's, also for a vehicle
    carrying sensors by type); None if absent."""
    return snapshot.vehicles.get(node)


def locate(spec: SensorSpec, snapshot: Snapshot) -> tuple[Pose, str | None] | None:
    """``(sensor pose, carrier vehicle id or None for a unit)``, or None if the carrier is gone."""
    static = spec.static_sensor_pose
    if static is not None:
        return static, None
    carrier = find_carrier(snapshot, spec.node)
    if carrier is None:
        return None
    return spec.mounted_on(carrier.footprint.front), carrier.id
