"""What every sensor sees at one step: detections and, on request, visible/occluded regions."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from sse_cosim.regions import Region, RegionKind
from sse_cosim.sensors.geometry import (
    Boxes,
    in_sector,
    line_of_sight,
    sight_masks,
    visibility_regions,
)
from sse_cosim.sensors.measurement import Detection
from sse_cosim.sensors.spec import SensorSpec, locate, sensor_instances
from sse_cosim.world.snapshot import Pose, Snapshot


@dataclass(frozen=True)
class SensorObservation:
    """One sensor at one step.

    ``pose`` is None when the carrier is not in the scene (then nothing is seen);
    ``detections`` by person id; ``visible``/``occluded`` are None unless regions were
    requested (empty when the carrier is absent): ``visible`` lies inside what the sensor
    sees (made ``inner``); ``occluded`` is its polygonal sector's part in the occluders'
    shadows (made ``outer``).
    """

    sensor: str
    node: str
    time: float
    pose: Pose | None
    detections: dict[str, Detection] = field(default_factory=dict)
    visible: Region | None = None
    occluded: Region | None = None


def seen_mask(
    pose: Pose, fov_rad: float, range_m: float, targets: np.ndarray, occluders: Boxes
) -> np.ndarray:
    """Whether each target (k, 2) is in the sector with a clear line of sight, (k,) bool.

    ``occluders`` must already exclude the sensor's own carrier.
    """
    t = np.asarray(targets, dtype=float).reshape(-1, 2)
    seen = in_sector(pose, fov_rad, range_m, t)
    if np.any(seen) and len(occluders):
        seen[seen] = line_of_sight(pose.position, t[seen], occluders)
    return seen


def observe(
    snapshot: Snapshot,
    sensor_specs: Mapping[str, SensorSpec],
    rng: np.random.Generator,
    regions: RegionKind | None = None,
) -> dict[str, SensorObservation]:
    """Every sensor's observation at this snapshot, by sensor name (``sensor_specs`` order;
    a ``carrier_type`` sensor as its instances on the vehicles in the scene, in its place:
    :func:`~sse_cosim.sensors.spec.sensor_instances`).

    A person is detected iff its centre is in the sensor's field of view (its kind's sector)
    and the segment to it misses every footprint but the carrier's. The tests run for all
    sensors × persons × footprints in one vectorized pass; the kinds' strips draw from ``rng``
    sensor by sensor (in order), persons in snapshot order, so a seeded generator reproduces
    them. Regions are only computed when a ``regions`` kind is given.
    """
    vehicles = list(snapshot.vehicles.values())
    index = {v.id: i for i, v in enumerate(vehicles)}
    boxes = Boxes.from_footprints([v.footprint for v in vehicles])
    person_ids = list(snapshot.persons)
    positions = np.zeros((len(person_ids), 2))  # (k, 2)
    for row, pid in enumerate(person_ids):
        positions[row] = snapshot.persons[pid].position

    sensor_specs = sensor_instances(sensor_specs, snapshot)
    names = list(sensor_specs)
    result: dict[str, SensorObservation] = {}
    here: list[tuple[str, SensorSpec, Pose, int]] = []  # (name, spec, pose, carrier box or -1)
    for name in names:
        spec = sensor_specs[name]
        where = locate(spec, snapshot)
        if where is None:  # carrier not (or no longer) in the scene: sees nothing
            empty = None if regions is None else regions.empty()
            result[name] = SensorObservation(name, spec.node, snapshot.time, None, {}, empty, empty)
        else:
            pose, carrier_id = where
            here.append((name, spec, pose, -1 if carrier_id is None else index[carrier_id]))

    data = np.array(
        [(p.x, p.y, p.heading, sp.fov_rad, sp.range_m, c) for _, sp, p, c in here], dtype=float
    ).reshape(-1, 6)  # (s, 6)
    seen, occluders = sight_masks(
        data[:, 0:2], data[:, 2], data[:, 3], data[:, 4], data[:, 5].astype(int), positions, boxes
    )  # (s, k), (s, m)
    hits_of: dict[int, list[int]] = {}
    for row, col in zip(*np.nonzero(seen), strict=True):  # row-major: sensor, then person
        hits_of.setdefault(int(row), []).append(int(col))
    for row, (name, spec, pose, _) in enumerate(here):
        hits = hits_of.get(row, [])
        detections: dict[str, Detection] = {}
        if hits:
            strips = spec.kind.measure(pose, positions[hits], rng)
            detections = {
                person_ids[h]: Detection(name, spec.node, snapshot.time, person_ids[h], st)
                for h, st in zip(hits, strips, strict=True)
            }
        visible = occluded = None
        if regions is not None:
            shown, hidden = visibility_regions(
                pose,
                spec.fov_rad,
                spec.range_m,
                boxes.subset(occluders[row]),
                resolution=spec.resolution,
                sector=spec.sector(pose),
                kept=spec.views if spec.is_static else None,
            )
            visible, occluded = regions.inner(shown), regions.outer(hidden)
        result[name] = SensorObservation(
            name, spec.node, snapshot.time, pose, detections, visible, occluded
        )
    return {name: result[name] for name in names}
