"""``replay.html``: every step of a run, played back in the browser.

:class:`ReplayLog` turns each :class:`~sse_cosim.pipeline.result.StepResult` into a compact
frame of plain lists (no shapely object is kept): footprints, pedestrians, the sensors'
sectors and shadows, the strips as bands, every node's local sets, and per automated vehicle
its fused sets (paper Proposition 2), refined regions, unobserved area, speed, command and
level. Polygons are stored once in a :class:`PolygonPool` (integer centimetres, each ring as
its first point and then steps to the next), and frames name them by index, so that geometry
that does not change (the road, parked vehicles, road-side units' sectors) costs one number
per frame. :func:`replay_page` fills the page template (``replay_template.html``, plain
JavaScript and SVG, nothing loaded from the network) with that data.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from sse_cosim.control.speed import SpeedLevel
from sse_cosim.regions import Region
from sse_cosim.reporting.recorder_kernels import encoded_cm
from sse_cosim.reporting.shapes import polygon_parts
from sse_cosim.scenario.model import Scenario, present
from sse_cosim.sets import Zonotope
from sse_cosim.sets.enclosure_kernels import clip_to_strips
from sse_cosim.world.roadmap import RoadMap

if TYPE_CHECKING:  # only the types: the recorder reads results, it does not make them
    from sse_cosim.pipeline.ego import EgoStep
    from sse_cosim.pipeline.result import StepResult

REPLAY = "replay.html"
TEMPLATE = "replay_template.html"
DATA_MARK = "/*REPLAY_DATA*/"  # where the template takes the data (a JSON object)
POLYGONS_MARK = "/*REPLAY_POLYGONS*/"  # and the polygons (a JSON array)
CM = 100.0  # coordinates are stored in integer centimetres
STRIP_MARGIN_M = 5.0  # a strip is drawn over its sensor's view box widened by this much

def replay_href(folder: Path, out_dir: Path, summary: Mapping[str, Any] | None = None
                ) -> str | None:
    """The link from a report in ``out_dir`` to ``folder``'s replay (POSIX, relative), at the
    run's key moment (``#t=``, :func:`opening_s` of its ``summary``) where it has one; None
    if the run kept no replay (a summaries-only sweep)."""
    page = folder / REPLAY
    if not page.is_file():
        return None
    at = opening_s(summary or {})
    anchor = "" if at is None else f"#t={at:g}"
    return Path(os.path.relpath(page, out_dir)).as_posix() + anchor


def opening_s(summary: Mapping[str, Any]) -> float | None:
    """The run's key moment, where its replay opens: the first detection of a pedestrian by
    any node (s; ``summary.json``'s ``first_detection``); None without one (the replay opens
    at the start). A page's ``#t=<s>`` or ``#step=<n>`` opens it elsewhere."""
    times = [entry["t"] for entry in (summary.get("first_detection") or {}).values()
             if isinstance(entry, Mapping) and entry.get("t") is not None]
    return float(min(times)) if times else None


LocalSet = tuple[str, str, Zonotope, bool]  # node, pedestrian, position set, detected now
Rings = tuple[bytes, ...]  # a polygon's encoded rings, each as int32 bytes (see PolygonPool)


@dataclass
class PolygonPool:
    """Distinct polygons, each stored once; ``add`` answers their indices.

    A polygon is a list of rings (exterior first, then holes); a ring is a flat list of
    integer centimetres ``[x0, y0, dx1, dy1, ...]``: its first point, then the step to each
    next one (the closing point is left out). Rings are kept as int32 bytes (4 bytes a
    number, a long run holds millions) and become JSON only when the page is written.
    """

    polygons: list[Rings] = field(default_factory=list)
    _index: dict[Rings, int] = field(default_factory=dict)  # the same tuples, not copies

    def rings(self, index: int) -> list[list[int]]:
        """Polygon ``index``'s rings as lists of numbers."""
        return [np.frombuffer(ring, dtype=np.int32).tolist() for ring in self.polygons[index]]

    def to_json(self) -> str:
        """Every polygon as one JSON array (of polygons, of rings), one polygon at a time."""
        return "[" + ",".join(json.dumps(self.rings(i), separators=(",", ":"))
                              for i in range(len(self.polygons))) + "]"

    def add(self, geometry: shapely.Geometry | None) -> list[int]:
        """The indices of ``geometry``'s polygons (none for an empty or missing one; lines
        and points hold no area and are left out)."""
        if geometry is None:
            return []
        return [self._add_rings([polygon.exterior, *polygon.interiors])
                for polygon in polygon_parts(geometry)]

    def add_vertices(self, vertices: np.ndarray) -> int:
        """The index of the polygon with ``vertices``, shape (k, 2), in order."""
        return self._add_encoded((_encode(vertices),))

    def _add_rings(self, rings: Sequence[shapely.LinearRing]) -> int:
        return self._add_encoded(tuple(_encode(shapely.get_coordinates(r)[:-1]) for r in rings))

    def _add_encoded(self, rings: Rings) -> int:
        index = self._index.get(rings)
        if index is None:
            index = self._index[rings] = len(self.polygons)
            self.polygons.append(rings)
        return index


def _encode(points: np.ndarray) -> bytes:
    """Points, shape (k >= 1, 2), in m as integer cm: the first point, then the steps between
    neighbours, flattened, as int32 bytes; repeated points are dropped (compiled:
    :func:`~sse_cosim.reporting.recorder_kernels.encoded_cm`; reference
    :func:`encode_reference`)."""
    xy = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 2)
    return encoded_cm(xy, CM).tobytes()


def encode_reference(points: np.ndarray) -> bytes:
    """:func:`_encode` in NumPy, the compiled kernel's reference."""
    cm = np.rint(np.asarray(points, dtype=float).reshape(-1, 2) * CM).astype(np.int32)
    steps = np.diff(cm, axis=0)
    return np.concatenate([cm[0], steps[steps.any(axis=1)].ravel()]).tobytes()


def _cm(value: float) -> int:
    return round(value * CM)


@dataclass
class ReplayLog:
    """Every step of a run as a compact frame (see the module docstring)."""

    pool: PolygonPool = field(default_factory=PolygonPool)
    frames: list[dict[str, Any]] = field(default_factory=list)
    sensors: dict[str, str] = field(default_factory=dict)  # sensor -> the node that carries it

    def add(self, result: StepResult, local: Sequence[LocalSet]) -> None:
        """Record one step; ``local``: every node's position set of each pedestrian."""
        snap = result.snapshot
        self.sensors.update((name, o.node) for name, o in result.observations.items())
        self.frames.append({
            "t": round(snap.time, 6),
            "vehicles": [[v.id, v.kind, self.pool.add(v.footprint.polygon())[0],
                          round(v.speed, 2)] for v in snap.vehicles.values()],
            "pedestrians": [[p.id, _cm(p.position[0]), _cm(p.position[1]), round(p.speed, 2)]
                            for _, p in sorted(snap.persons.items())],
            "sectors": [[name, self.pool.add(_shape(o.visible)), self.pool.add(_shape(o.occluded))]
                        for name, o in result.observations.items() if o.pose is not None],
            "strips": self._strips(result),
            "local": [[node, pid, self.pool.add_vertices(z.vertices()), int(detected)]
                      for node, pid, z, detected in local],
            "ego": {vid: self._ego(result, ego) for vid, ego in result.vehicles.items()},
        })

    def _strips(self, result: StepResult) -> list[list[Any]]:
        """Each detection's strips ``|n·x - y| <= r`` (paper eq. senmodel) as bands over its
        sensor's view box: [sensor, pedestrian, [polygon, ...]]."""
        bands = []
        for name, obs in result.observations.items():
            box = _view_box(_shape(obs.visible), _shape(obs.occluded))
            for pid, detection in obs.detections.items():
                s = detection.strips
                clipped = (_band(normal, value, radius, box)
                           for normal, value, radius in zip(s.normals, s.values, s.radii,
                                                            strict=True))
                bands.append([name, pid, [self.pool.add_vertices(band) for band in clipped
                                          if len(band) >= 3]])
        return bands

    def _ego(self, result: StepResult, ego: EgoStep) -> dict[str, Any]:
        """One automated vehicle's speed, command and level, fused sets, refined regions and
        unobserved area."""
        speed = result.snapshot.vehicles[ego.vehicle].speed
        return {
            "speed": round(speed, 3),
            "command": round(ego.decision.command_mps, 3),
            "level": int(ego.decision.level),
            "fused": [[pid, self.pool.add_vertices(result.model.position(z).vertices())]
                      for pid, z in sorted(ego.estimate.fused.items())],
            "refined": [[pid, self.pool.add(region.geometry())]
                        for pid, region in sorted(ego.possible.items())],
            "unobserved": self.pool.add(ego.unobserved.geometry()),
        }


def _shape(region: Region | None) -> shapely.Geometry | None:
    """A region's polygons (None for None)."""
    return None if region is None else region.geometry()


def _view_box(*regions: shapely.Geometry | None) -> tuple[float, float, float, float] | None:
    """The bounds (x0, y0, x1, y1) of a sensor's sector (visible and occluded parts),
    widened by ``STRIP_MARGIN_M``; None without any."""
    bounds = np.array([shapely.bounds(r) for r in regions if r is not None and not r.is_empty])
    if not bounds.size:
        return None
    x0, y0 = bounds[:, :2].min(axis=0) - STRIP_MARGIN_M
    x1, y1 = bounds[:, 2:].max(axis=0) + STRIP_MARGIN_M
    return (float(x0), float(y0), float(x1), float(y1))


def _band(normal: np.ndarray, value: float, radius: float,
          box: tuple[float, float, float, float] | None) -> np.ndarray:
    """The vertices (k, 2), in order, of the strip ``|n·x - value| <= radius`` (``normal`` n,
    shape (2,)) clipped to the rectangle ``box`` (x0, y0, x1, y1): the rectangle cut by the
    strip's two half-planes (compiled Sutherland-Hodgman); none without a box."""
    if box is None:
        return np.zeros((0, 2))
    x0, y0, x1, y1 = box
    corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
    return clip_to_strips(corners, np.asarray(normal, dtype=float).reshape(1, 2),
                          np.array([value]), np.array([radius]))


def replay_page(log: ReplayLog, scenario: Scenario, roadmap: RoadMap, title: str,
                opens_at_s: float | None = None) -> str:
    """The self-contained page: the template with the run's data in place of ``DATA_MARK``
    and its polygons in place of ``POLYGONS_MARK``; it opens at the step nearest
    ``opens_at_s`` (the start for None)."""
    data = _replay_data(log, scenario, roadmap, title)  # adds the map to the pool: first
    data["opens_at_s"] = opens_at_s
    template = resources.files("sse_cosim.reporting").joinpath(TEMPLATE).read_text("utf-8")
    page = template.replace(DATA_MARK, _script_text(json.dumps(data, separators=(",", ":"))), 1)
    return page.replace(POLYGONS_MARK, _script_text(log.pool.to_json()), 1)


def _script_text(text: str) -> str:
    """JSON ``text`` safe inside a <script> element ("</" would end it early; the escape
    "\\u003c" is the same JSON string)."""
    return text.replace("<", "\\u003c")


def _replay_data(log: ReplayLog, scenario: Scenario, roadmap: RoadMap, title: str,
                ) -> dict[str, Any]:
    """Everything the page shows but the polygons (the map's are added to ``log.pool``), as
    one JSON-ready dict."""
    lanes = [*roadmap.driving_lanes.values(), *roadmap.internal_lanes.values()]
    return {
        "title": title,
        "dt": scenario.simulation.step_length_s,
        "levels": [level.label for level in SpeedLevel],
        "automated": list(present(scenario.automated)),
        "nodes": scenario.node_ids(),
        "sensors": log.sensors,
        "road": [i for lane in lanes for i in log.pool.add(lane.polygon())],
        "parking": [i for lane in roadmap.parking_lanes.values()
                    for i in log.pool.add(lane.polygon())],
        "walkable": log.pool.add(roadmap.walkable),
        "crossings": log.pool.add(roadmap.crossing_area),
        "frames": log.frames,
    }

