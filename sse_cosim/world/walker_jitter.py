"""How far SUMO's walkers stray from a speed-bounded path on a network: measured, and cached
with the network.

The estimator assumes every pedestrian's position is a path with steps of at most v dt plus a
jitter of at most eps (:mod:`sse_cosim.world.assumptions`). SUMO's striping model keeps that
on a straight sidewalk, but re-places a walker where it enters or leaves a walking area: it may
move farther in one step than its speed allows (0.80 m in 0.1 s at 2.5 m/s on the paper road,
1.2 to 1.5 m on converted town networks). How much jitter covers that depends on the geometry
of each walking area, so it is measured on the network itself:

* **Walks.** For every walking area of the scene (every one of the network for
  :func:`measure_network`) and every ordered pair (a, b) of distinct lanes it joins (sidewalks
  and crossings), one walker walks from :data:`LEAD_M` before the walking area on a through it
  to :data:`LEAD_M` along b. A walk that enters by a crossing starts on a sidewalk before the
  crossing's other walking area; one that leaves by a crossing ends on a sidewalk after it.
  So every passage a walker can take is walked, with the sidewalk before and after it --
  except a turn back (:func:`_turns_back`): a walk that ends on the sidewalk it began on (in
  over one crossing and back over another), or that crosses nothing and ends on a sidewalk
  leading back to the same node (the two sides of a street at a dead end, a loop). On such
  walking areas SUMO reports walkers up to tens of metres away from the walking area (86 m
  in one step in the converted Bad Hersfeld): no jitter covers that. The scenarios' walks
  cross the street over a zebra and do not turn back; a walker that does (a person from a
  route file) stops its run at that jump.
* **Alone, at the bound.** Every walker walks at the speed bound v, the run's step length and
  SUMO's options of a run (:func:`sse_cosim.world.walk_probe.walk_alone`); walkers whose walks
  share an edge never walk at the same time (slots of :func:`_slots`), so none is pushed by
  another. Crowds are not measured: a scenario with several pedestrians near each other sets
  its own, larger jitter.
* **Least jitter.** Each walk's least jitter (:func:`~sse_cosim.world.assumptions.least_jitter`,
  proven by inner polygons, at most 0.13 % + 2 mm above the least) at the speed bound; a
  junction's jitter is the largest over the passages of its walking areas (walks whose
  upper bound, :func:`~sse_cosim.world.assumptions.path_jitter`, is no larger than the
  largest found need no more and are not bisected).

* **Off the ground.** While a walker is on a junction's walking areas and crossings, SUMO
  moves it on a curve from the end of one lane to the start of the next, which can leave the
  road map's plain ground (sidewalks, walking areas and crossings): the wedge between a
  crossing's rectangle and its walking area's kerb, a corner cut short (up to 2.9 m off on
  the town cut). Each junction's *ground patch* covers every stretch a walker spent off the
  plain ground there, with the positions before and after it, widened by
  :data:`GROUND_BAND_M` (0.25 m: room for a walker on another stripe or at another speed
  whose curve runs close beside the lone walker's; one that strays farther is stopped by the
  world's check, never missed); the road map adds the patches to its walkable ground
  (:attr:`sse_cosim.world.roadmap.RoadMap.walkable`), so it holds every position measured,
  and the world checks every step that each pedestrian is on it. The plain ground is given
  as geometry.

* **Bounded acceleration.** For the ``bounded-acceleration`` model (:func:`measure` given
  its a_max) the walkers' speeds are ramped within a_max as in its runs
  (:class:`~sse_cosim.world.sumo_setup.SpeedRamp`), each walk's least jitter is the one a
  path keeping the speed and the acceleration bounds needs
  (:func:`~sse_cosim.world.acceleration_assumption.needed_jitter`: one convex program, exact
  up to its tolerance, rounded up to 1 mm), and the ground patches are those of the ramped
  walks; the cache keys these entries by a_max too, apart from the speed-bounded models'
  (whose measurement is unchanged). On the paper road at 2.5 m/s and a body of 0.3 m:
  0.645 m against 0.646 m for the position model (the largest jump dominates both); on the
  junction's network 0.711 m against 0.707 m (``measure_walkers(net, load_roadmap(net),
  None, 2.5, 0.1, 0.3, 3.2)``, and without the 3.2, on ``build_network`` of ``sumo_net`` and
  ``sumo_net/junction``).

A run takes the largest over the junctions of the walking areas in its scene's extent
(:mod:`sse_cosim.world.extent`: the pedestrians of a run cannot walk beyond it before the run
ends) that the jitter's scope holds: where the scene's walkers walk, and near the automated
vehicles' routes (:class:`~sse_cosim.world.extent.JitterScope`). Every step of every run still
checks the assumption on the true walk, so a walker that strays more than measured (a crowd, a
stripe the measurement did not walk) stops the run with exit status 5 and never goes
unnoticed; so does a walker off the walkable ground with its patches
(:class:`sse_cosim.world.sumo.SumoWorld`).

Cache: a JSON file per network, the built network's folder for one built from sources
(``walker_jitter.json`` beside ``road.net.xml``), else ``$XDG_CACHE_HOME/sse-cosim`` by the
hash of the ``.net.xml`` (:func:`net_digest`: converting the same sources again keeps it); its
entries are keyed by SUMO's version, the step length, the speed bound and the pedestrian's size
(and a_max for the bounded-acceleration model), and hold each junction's jitter and the walk
that needed it, and the walk's pieces off the plain ground (exact, as hex WKB; an entry written
before they were kept has none and is measured again). The cache keeps what SUMO did, not what
the code makes of it: the ground patch is drawn from those pieces at every load, so a change to
the patch's band or to the Region layer's dilation takes effect without a stale patch. It is
written atomically; only the junctions not measured yet are walked.
"""

from __future__ import annotations

import fcntl
import hashlib
import json
import os
import re
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from functools import cached_property, partial
from pathlib import Path

import numpy as np
import shapely
import sumolib

from sse_cosim.errors import SimulationError
from sse_cosim.files import write_text_atomic
from sse_cosim.regions import PolygonRegion
from sse_cosim.world.acceleration_assumption import AccelerationBounds, needed_jitter
from sse_cosim.world.assumptions import MotionBounds, admits, least_jitter, path_jitter
from sse_cosim.world.extent import JitterScope, SceneExtent
from sse_cosim.world.network import BUILD_DIR_NAME, NET_FILE_NAME
from sse_cosim.world.walk_probe import (
    Walker,
    WalkTrace,
    longest_cycle_s,
    slot_s,
    walk_alone_kept_on_error,
)

LEAD_M = 3.0  # how far a walk starts before a walking area and ends beyond it (m)
CACHE_FILE_NAME = "walker_jitter.json"
_EPS_M = 1e-9  # steps longer than v dt by rounding only need no jitter
GROUND_BAND_M = 0.25  # how far a ground patch reaches around a lone walker's stretch off it (m)
MEET_RETRIES = 3  # walkers that met walk again alone this many times at most
_PROLOG_PART = re.compile(rb"\s*(?:<\?xml.*?\?>|<!--.*?-->)", re.DOTALL)
"""A part of an XML file before its first element: its declaration or a comment."""


def _off_ground(ground: shapely.Geometry, runs: Sequence[np.ndarray]) -> shapely.Geometry:
    """Where the walk pieces ``runs`` (each (k, 2)) are off the plain ``ground``: each stretch
    of consecutive positions off it (apart from it: neither in it nor on its boundary), with
    the position before and after, as a line (a point for a single position); empty if none
    is off. ``ground`` is prepared here (in place) for the point tests."""
    shapely.prepare(ground)
    lines = []
    for xy in runs:
        xy = xy.reshape(-1, 2)
        off = ~shapely.intersects_xy(ground, xy[:, 0], xy[:, 1])
        for first, last in _stretches(off):
            piece = xy[max(first - 1, 0):last + 2]
            lines.append(shapely.LineString(piece) if len(piece) > 1
                         else shapely.Point(piece[0]))
    return shapely.union_all(lines) if lines else shapely.Polygon()


def _patch_of(off_ground: shapely.Geometry) -> shapely.Geometry:
    """The ground patch that holds the pieces ``off_ground`` (:func:`_off_ground`): them
    dilated by :data:`GROUND_BAND_M` (a polygon holding the disc dilation,
    :meth:`~sse_cosim.regions.PolygonRegion.dilate`); empty if there are none."""
    if off_ground.is_empty:
        return shapely.Polygon()
    return PolygonRegion(off_ground).dilate(GROUND_BAND_M).shape


def _stretches(flags: np.ndarray) -> list[tuple[int, int]]:
    """The (first, last) indices of each run of True in ``flags`` (k,)."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(),
                    (np.flatnonzero(edges == -1) - 1).tolist(), strict=True))


@dataclass(frozen=True)
class JunctionJitter:
    """The jitter (m) SUMO's walkers need at one junction, and the walk (its edges) that
    needed the most there, with the lanes of its largest step (from, to) and that step (m);
    ``off_ground`` where its walkers left the plain ground (module docstring; None: not
    measured, an old entry)."""

    junction: str
    jitter_m: float
    walk: tuple[str, ...]
    step_lanes: tuple[str, str]
    step_m: float
    off_ground: shapely.Geometry | None = None

    @cached_property
    def ground_patch(self) -> shapely.Geometry:
        """The ground its walkers need beyond the plain ground (:func:`_patch_of`)."""
        if self.off_ground is None:
            raise ValueError(f"junction {self.junction!r} has no measured walk off the ground")
        return _patch_of(self.off_ground)

    def as_dict(self) -> dict[str, object]:
        off = None if self.off_ground is None else shapely.to_wkb(self.off_ground, hex=True)
        return {"jitter_m": self.jitter_m, "walk": list(self.walk),
                "step_lanes": list(self.step_lanes), "step_m": self.step_m,
                "off_ground": off}


@dataclass(frozen=True)
class NetworkJitter:
    """The measured jitter over a set of junctions (the worst one named; 0.0 and no junction
    where no walking area was found), the settings it was measured with, and each junction's
    ground patch by id."""

    jitter_m: float
    worst: JunctionJitter | None
    junctions: int
    speed_mps: float
    step_s: float
    ground_patches: dict[str, shapely.Geometry]

    def where(self) -> str:
        """Where the worst jump happened, for messages."""
        if self.worst is None:
            return "no walking area in the scene"
        w = self.worst
        return (f"at junction {w.junction!r}: a {w.step_m:.2f} m step from {w.step_lanes[0]!r} "
                f"to {w.step_lanes[1]!r}")


class JitterCache:
    """The measured junctions of one network (see the module docstring), read once, written
    after every measurement. Runs in parallel (a sweep's workers) measure different
    junctions of one network: each adds its own to what the file holds when it writes, under
    a lock, so none is lost."""

    def __init__(self, net_path: Path) -> None:
        self.path = cache_path(net_path)
        self.entries = self._read()

    def _read(self) -> dict[str, dict[str, dict]]:
        try:
            return json.loads(self.path.read_text("utf-8"))
        except (OSError, ValueError):
            return {}

    def junctions(self, key: str) -> dict[str, JunctionJitter]:
        return {jid: JunctionJitter(jid, e["jitter_m"], tuple(e["walk"]), tuple(e["step_lanes"]),
                                    e["step_m"], _from_wkb(e.get("off_ground")))
                for jid, e in self.entries.get(key, {}).items()}

    def add(self, key: str, found: Iterable[JunctionJitter]) -> None:
        """Add the ``found`` junctions under ``key`` to the file as it is now (class
        docstring)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with open(self.path.with_name(self.path.name + ".lock"), "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
            self.entries = self._read()
            self.entries.setdefault(key, {}).update({j.junction: j.as_dict() for j in found})
            write_text_atomic(self.path,
                              json.dumps(self.entries, indent=1, sort_keys=True) + "\n")


def cache_path(net_path: Path) -> Path:
    """Where the measurements of the network at ``net_path`` are kept: a build's folder, or
    the user cache by :func:`net_digest`."""
    net_path = Path(net_path).resolve()
    if net_path.name == NET_FILE_NAME and net_path.parent.parent.name == BUILD_DIR_NAME:
        return net_path.parent / CACHE_FILE_NAME  # a build: its folder is keyed by content
    root = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return root / "sse-cosim" / f"{net_digest(net_path)[:16]}.{CACHE_FILE_NAME}"


def net_digest(net_path: Path) -> str:
    """The SHA-256 (hex) of a network file's bytes from its first element on: netconvert
    writes the time and its options in a comment before it, so converting the same sources
    again keeps the measurements."""
    data = Path(net_path).read_bytes()
    start = 0
    while match := _PROLOG_PART.match(data, start):
        start = match.end()
    return hashlib.sha256(data[start:].lstrip()).hexdigest()


def measure(net_path: Path, net: sumolib.net.Net | None, extent: SceneExtent | None,
            ground: shapely.Geometry, speed_mps: float, step_s: float, radius_m: float,
            sumo_version: str, accel_mps2: float | None = None,
            scope: JitterScope | None = None) -> NetworkJitter:
    """The jitter SUMO's walkers need on the walking areas of ``net`` (the network at
    ``net_path``, read here if None) in ``extent`` (all of them for None) at the junctions of
    ``scope`` (every one for None), and each junction's patch beyond the plain ``ground``,
    measured where the cache lacks a junction or its patch; with ``accel_mps2``, for the
    bounded-acceleration model (module docstring)."""
    if net is None:
        net = sumolib.net.readNet(str(net_path), withInternal=True,
                                  withPedestrianConnections=True)
    areas = [e for e in net.getEdges(withInternal=True) if e.getFunction() == "walkingarea"
             and (extent is None or extent.holds(e))]
    if scope is not None:
        held = scope.junctions(net, areas)
        areas = [area for area in areas if _junction(area) in held]
    wanted = sorted({_junction(area) for area in areas})
    cache = JitterCache(net_path)
    key = cache_key(sumo_version, step_s, speed_mps, radius_m, accel_mps2)
    known = cache.junctions(key)
    missing = [jid for jid in wanted
               if jid not in known or known[jid].off_ground is None]
    if missing:
        todo = [area for area in areas if _junction(area) in set(missing)]
        started = time.perf_counter()
        print(f"measuring how far SUMO's walkers jump on {len(todo)} walking areas of "
              f"{net_path.name} (once per network, step length and speed bound)...",
              file=sys.stderr, flush=True)
        found = _walk_junctions(net_path, net, todo, ground, speed_mps, step_s, radius_m,
                                accel_mps2)
        print(f"measured {len(found)} junctions ({time.perf_counter() - started:.1f} s)",
              file=sys.stderr, flush=True)
        cache.add(key, found)
        known.update({j.junction: j for j in found})
    measured = [known[jid] for jid in wanted]
    worst = max(measured, key=lambda j: (j.jitter_m, j.junction), default=None)
    return NetworkJitter(jitter_m=0.0 if worst is None else worst.jitter_m, worst=worst,
                         junctions=len(measured), speed_mps=speed_mps, step_s=step_s,
                         ground_patches={j.junction: j.ground_patch for j in measured
                                         if not j.ground_patch.is_empty})


def cache_key(sumo_version: str, step_s: float, speed_mps: float, radius_m: float,
              accel_mps2: float | None = None) -> str:
    """The cache entry of measurements with these settings (``accel_mps2``: the
    bounded-acceleration model's, None for a speed-bounded model)."""
    key = (f"sumo {sumo_version}|step {step_s:.10g} s|speed {speed_mps:.10g} m/s"
           f"|radius {radius_m:.10g} m")
    return key if accel_mps2 is None else f"{key}|accel {accel_mps2:.10g} m/s2"


def _junction(area: sumolib.net.edge.Edge) -> str:
    return str(area.getFromNode().getID())


def passages(net: sumolib.net.Net, areas: Sequence[sumolib.net.edge.Edge]
             ) -> list[tuple[str, tuple[str, ...], float, float]]:
    """One walk (junction, edges, depart pos, arrival pos) per passage of each walking area
    (module docstring); passages no sidewalk leads to or from are left out."""
    walks = []
    for area in areas:
        neighbours = sorted({e.getID(): e for e in (*area.getIncoming(), *area.getOutgoing())
                             }.values(), key=lambda e: e.getID())
        for a in neighbours:
            for b in neighbours:
                if a is b:
                    continue
                head = _into(a, area)
                tail = _out_of(b, area)
                if head is None or tail is None:
                    continue
                edges = (*head, area.getID(), *tail)
                if _turns_back(net, edges, _junction(area)):
                    continue
                walks.append((_junction(area), edges,
                              _lead(net.getEdge(edges[0]), toward=_node_of(net, edges[1])),
                              _lead(net.getEdge(edges[-1]), toward=_node_of(net, edges[-2]))))
    return walks


def _turns_back(net: sumolib.net.Net, edges: Sequence[str], junction: str) -> bool:
    """Whether the walk ``edges`` through a walking area of ``junction`` ends where it began:
    on the sidewalk it started on (in over one crossing, back over another to the same
    corner), or, over no crossing, on a sidewalk that leads from ``junction`` to the same
    node as the first (the two sides of a street at a dead end, a loop)."""
    first, last = net.getEdge(edges[0]), net.getEdge(edges[-1])
    if first.getID() == last.getID():
        return True
    if len(edges) > 3:  # a crossing on the way: it crosses a street
        return False
    return _far_end(first, junction) == _far_end(last, junction)


def _far_end(edge: sumolib.net.edge.Edge, junction: str) -> str:
    ends = (edge.getFromNode().getID(), edge.getToNode().getID())
    return ends[1] if ends[0] == junction else ends[0]


def _into(lane_edge: sumolib.net.edge.Edge, area: sumolib.net.edge.Edge
          ) -> tuple[str, ...] | None:
    """The edges of a walk into ``area`` by ``lane_edge``: a sidewalk alone, or a sidewalk,
    the other walking area and the crossing."""
    if lane_edge.getFunction() != "crossing":
        return (lane_edge.getID(),)
    other = _other_area(lane_edge, area)
    side = None if other is None else _a_sidewalk(other)
    return None if side is None else (side, other.getID(), lane_edge.getID())


def _out_of(lane_edge: sumolib.net.edge.Edge, area: sumolib.net.edge.Edge
            ) -> tuple[str, ...] | None:
    head = _into(lane_edge, area)
    return None if head is None else tuple(reversed(head))


def _other_area(crossing: sumolib.net.edge.Edge, area: sumolib.net.edge.Edge
                ) -> sumolib.net.edge.Edge | None:
    others = [e for e in (*crossing.getIncoming(), *crossing.getOutgoing())
              if e.getFunction() == "walkingarea" and e.getID() != area.getID()]
    return min(others, key=lambda e: e.getID(), default=None)


def _a_sidewalk(area: sumolib.net.edge.Edge) -> str | None:
    sides = sorted(e.getID() for e in (*area.getIncoming(), *area.getOutgoing())
                   if e.getFunction() not in ("crossing", "walkingarea"))
    return sides[0] if sides else None


def _node_of(net: sumolib.net.Net, area_id: str) -> str:
    return str(net.getEdge(area_id).getFromNode().getID())


def _lead(edge: sumolib.net.edge.Edge, toward: str) -> float:
    """The position (m) on sidewalk ``edge`` :data:`LEAD_M` from its end at node ``toward``."""
    length = edge.getLength()
    lead = min(LEAD_M, 0.5 * length)
    return length - lead if edge.getToNode().getID() == toward else lead


def _walk_junctions(net_path: Path, net: sumolib.net.Net,
                    areas: Sequence[sumolib.net.edge.Edge], ground: shapely.Geometry,
                    speed_mps: float, step_s: float, radius_m: float,
                    accel_mps2: float | None) -> list[JunctionJitter]:
    walks = passages(net, areas)
    lengths = [sum(net.getEdge(e).getLength() for e in edges[1:-1]) + 2.0 * LEAD_M
               for _, edges, _, _ in walks]
    # a walk crosses at most two crossings (in by one, out by another): two whole cycles
    slot = slot_s(max(lengths, default=0.0) / speed_mps, step_s,
                  2.0 * longest_cycle_s(net_path))
    walkers = [Walker(id=f"w{i}", edges=edges, depart_pos_m=depart, arrival_pos_m=arrival,
                      speed_mps=speed_mps, depart_s=0.0, radius_m=radius_m)
               for i, (_, edges, depart, arrival) in enumerate(walks)]
    traces = _walk_apart(net_path, walkers, step_s, slot, accel_mps2)
    by_junction: dict[str, list[tuple[tuple[str, ...], WalkTrace]]] = {}
    for (junction, edges, _, _), walker in zip(walks, walkers, strict=True):
        by_junction.setdefault(junction, []).append((edges, traces[walker.id]))
    junctions = sorted({_junction(area) for area in areas})
    jitter_of: Callable[[str, list[tuple[tuple[str, ...], WalkTrace]]], JunctionJitter]
    if accel_mps2 is None:
        jitter_of = partial(_junction_jitter, bounds=MotionBounds(speed_mps, 0.0, step_s))
    else:
        jitter_of = partial(_accel_junction_jitter,
                            bounds=AccelerationBounds(speed_mps, accel_mps2, 0.0, step_s))
    return [replace(jitter_of(j, by_junction[j]),
                    off_ground=_walk_off_ground(net, by_junction[j], ground))
            if j in by_junction else JunctionJitter(j, 0.0, (), ("", ""), 0.0, shapely.Polygon())
            for j in junctions]


def _walk_off_ground(net: sumolib.net.Net, walks: list[tuple[tuple[str, ...], WalkTrace]],
                     ground: shapely.Geometry) -> shapely.Geometry:
    """Where the junction's walks left the plain ``ground`` (:func:`_off_ground`), over the
    stretches they spent on its walking areas and crossings."""
    inner = {e for edges, _ in walks for e in edges
             if net.getEdge(e).getFunction() in ("walkingarea", "crossing")}
    runs = []
    for _, trace in walks:
        on = np.array([lane.rpartition("_")[0] in inner for lane in trace.lanes])
        runs.extend(trace.xy[first:last + 1] for first, last in _stretches(on))
    return _off_ground(ground, runs)


def _from_wkb(text: str | None) -> shapely.Geometry | None:
    """A cached walk off the ground (hex WKB, exact), None for an entry without one."""
    return None if text is None else shapely.from_wkb(text)


def _junction_jitter(junction: str, walks: list[tuple[tuple[str, ...], WalkTrace]],
                     bounds: MotionBounds) -> JunctionJitter:
    """The largest least jitter of a junction's walks, in decreasing order of the jitter of a
    speed-bounded path built from each (:func:`~sse_cosim.world.assumptions.path_jitter`, an
    upper bound): a walk whose bound is no larger than the largest found so far, or that the
    largest admits (:func:`~sse_cosim.world.assumptions.admits`, proven), needs no more and is
    not bisected."""
    bounded = sorted(((path_jitter(trace.xy, bounds.step_m), edges, trace)
                      for edges, trace in walks), key=lambda w: -w[0])
    best = _walk_jitter(junction, bounded[0][1], bounded[0][2], bounds)
    for upper, edges, trace in bounded[1:]:
        if upper <= best.jitter_m:
            break
        at_best = replace(bounds, jitter_m=best.jitter_m)
        if admits(trace.xy, at_best):  # proven: it needs no more than the best
            continue
        found = _walk_jitter(junction, edges, trace, at_best)
        if found.jitter_m > best.jitter_m:
            best = found
    return best


def _accel_junction_jitter(junction: str, walks: list[tuple[tuple[str, ...], WalkTrace]],
                           bounds: AccelerationBounds) -> JunctionJitter:
    """The largest least jitter of a junction's walks for the bounded-acceleration model
    (:func:`~sse_cosim.world.acceleration_assumption.needed_jitter`: one program per walk, its
    least jitter verified), with the walk that needs it and that walk's largest step."""
    needed = [(needed_jitter(trace.xy, bounds), edges, trace) for edges, trace in walks]
    jitter, edges, trace = max(needed, key=lambda w: w[0])
    step_m, lanes = _largest_step(trace)
    return JunctionJitter(junction, jitter, edges, lanes, round(step_m, 3))


def _largest_step(trace: WalkTrace) -> tuple[float, tuple[str, str]]:
    """A walk's largest step (m) and the lanes it went from and to (0.0 and empty lanes for a
    walk of one position)."""
    steps = np.diff(trace.xy, axis=0)
    lengths = np.sqrt((steps * steps).sum(axis=1))  # (k - 1,)
    if not len(lengths):
        return 0.0, ("", "")
    k = int(np.argmax(lengths))
    return float(lengths[k]), (trace.lanes[k], trace.lanes[k + 1])


def _slots(walks: Sequence[tuple[str, ...]]) -> list[int]:
    """A slot per walk such that walks sharing an edge have different slots (first fit)."""
    used: list[set[str]] = []
    slots = []
    for edges in walks:
        mine = set(edges)
        slot = next((k for k, taken in enumerate(used) if not taken & mine), len(used))
        if slot == len(used):
            used.append(set())
        used[slot] |= mine
        slots.append(slot)
    return slots


def _walk_apart(net_path: Path, walkers: Sequence[Walker], step_s: float, slot_length_s: float,
                accel_mps2: float | None) -> dict[str, WalkTrace]:
    """Every walker's trace, walked alone: walkers that share an edge depart in different
    slots of ``slot_length_s`` (:func:`_slots`). SUMO may hold a walker longer than a slot (a
    light, a jam); walkers that met all the same walk again in a simulation of their own,
    with slots twice as long, up to :data:`MEET_RETRIES` times; then the measurement stops
    with one line (:class:`~sse_cosim.errors.SimulationError`)."""
    traces: dict[str, WalkTrace] = {}
    todo = list(walkers)
    for _ in range(MEET_RETRIES + 1):
        slots = _slots([w.edges for w in todo])
        placed = [replace(w, depart_s=round(k * slot_length_s, 6)) for w, k in zip(todo, slots,
                                                                             strict=True)]
        walked = walk_alone_kept_on_error(net_path, placed, step_s, "walker_jitter.",
                                          accel_mps2=accel_mps2)
        met = _met(placed, walked)
        traces.update({w.id: walked[w.id] for w in placed if w.id not in met})
        if not met:
            return traces
        todo, slot_length_s = [w for w in todo if w.id in met], 2.0 * slot_length_s
    first = sorted(met)[:4]
    raise SimulationError(net_path.name, f"walkers {', '.join(first)} of the jitter "
                          f"measurement still met after {MEET_RETRIES} walks in slots up to "
                          f"{slot_length_s / 2.0:g} s long (SUMO held them up): measure a smaller "
                          "scene (a cut of the network, docs/own_network.md), or set "
                          "estimator.position_jitter_m")


def _met(walkers: Sequence[Walker], traces: dict[str, WalkTrace]) -> set[str]:
    """The walkers that shared an edge with another at the same time (their traces may be
    pushed by each other's)."""
    spans = {w.id: (traces[w.id].times_s[0], traces[w.id].times_s[-1]) for w in walkers}
    by_edge: dict[str, list[Walker]] = {}
    for walker in walkers:
        for edge in set(walker.edges):
            by_edge.setdefault(edge, []).append(walker)
    met: set[str] = set()
    for sharing in by_edge.values():
        for i, first in enumerate(sharing):
            for second in sharing[i + 1:]:
                (a0, a1), (b0, b1) = spans[first.id], spans[second.id]
                if a0 <= b1 and b0 <= a1:
                    met.update((first.id, second.id))
    return met


def _walk_jitter(junction: str, edges: tuple[str, ...], trace: WalkTrace,
                 bounds: MotionBounds) -> JunctionJitter:
    """The least jitter of one walk (0.0 where no step exceeds v dt: the path is the walk)."""
    step_m, lanes = _largest_step(trace)
    needed = least_jitter(trace.xy, bounds) if step_m > bounds.step_m + _EPS_M else 0.0
    return JunctionJitter(junction, needed, edges, lanes, round(step_m, 3))
