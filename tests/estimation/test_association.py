"""Association of anonymous detections: every pedestrian ever detected stays inside a track
set, at a node (:func:`associate`) and across nodes (:func:`associate_nodes`)."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Point, Polygon, box
from shapely.geometry.base import BaseGeometry
from shapely.ops import unary_union

from sse_cosim.estimation import motion
from sse_cosim.estimation.anonymous_fusion import AnonymousFusionCentre
from sse_cosim.estimation.association import (
    AnonymousDetection,
    LocalTrack,
    NodeTracks,
    associate,
    associate_nodes,
)
from sse_cosim.estimation.bus_fusion import fuse_sets
from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.observer import AnonymousNodeObserver, NodeScan
from sse_cosim.estimation.occupancy import OccupancyTracker
from sse_cosim.estimation.settings import EstimatorSettings
from sse_cosim.estimation.v2x import Message, V2XLink
from sse_cosim.pipeline.stages import RefinedRegions, detected_now
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import kind
from sse_cosim.scenario.model import V2X, Estimator
from sse_cosim.sets import Strips, Zonotope

DT = 0.5
SPEED = 1.5  # m/s: at most 0.75 m per step
NOISE = 0.3  # m: strip half-width
SETTINGS = EstimatorSettings("enclose", "girard", 8)
K = kind("polygon")


def fusion(sets):
    """Proposition 2 as the bus does it (``enclose``), for :func:`associate_nodes`."""
    return fuse_sets(sets, "enclose", SETTINGS, motion_model())


def motion_model(jitter: float = 0.0) -> MotionModel:
    config = Estimator(state_model="position", max_pedestrian_speed_mps=SPEED,
                       position_jitter_m=jitter)
    return motion.motion_model(config, DT)


@dataclass(frozen=True)
class Sensor:
    name: str
    region: BaseGeometry


def detections(rng: np.random.Generator, positions: np.ndarray, sensors: list[Sensor]
               ) -> list[AnonymousDetection]:
    """Every position (n, 2) inside a sensor's region is detected by it (A2): strips along a
    random heading with noise |v| <= NOISE (A1); each sensor's detections come shuffled."""
    found = []
    for sensor in sensors:
        seen = [p for p in positions if sensor.region.contains(Point(p))]
        for index in rng.permutation(len(seen)):
            angle = rng.uniform(0, 2 * np.pi)
            h = np.array([[np.cos(angle), np.sin(angle)], [-np.sin(angle), np.cos(angle)]])
            noise = rng.uniform(-NOISE, NOISE, 2)
            found.append(AnonymousDetection(
                sensor.name, Strips(h, h @ seen[index] + noise, np.full(2, NOISE))))
    return found


@dataclass
class Node:
    """One node's association state over a run."""

    sensors: list[Sensor]
    model: MotionModel
    tracks: tuple[LocalTrack, ...] = ()
    next_id: int = 0
    seen: set[int] = field(default_factory=set)  # pedestrians detected so far
    most_tracks: int = 0

    def step(self, rng: np.random.Generator, k: int, observed: np.ndarray) -> None:
        found = detections(rng, observed, self.sensors)
        self.seen |= {i for i, p in enumerate(observed)
                      if any(s.region.contains(Point(p)) for s in self.sensors)}
        result = associate(self.model, SETTINGS, self.tracks, found,
                           {s.name: R(s.region) for s in self.sensors}, k, self.next_id, K)
        self.tracks, self.next_id = result.tracks, result.next_id
        self.most_tracks = max(self.most_tracks, len(self.tracks))

    @property
    def visible(self) -> BaseGeometry:
        return unary_union([s.region for s in self.sensors])


def covered(model: MotionModel, sets, point: np.ndarray) -> bool:
    return any((model.position_matrix @ z).contains(point, tol=1e-7) for z in sets)


def crossing_walks(rng: np.random.Generator, people: int, steps: int) -> np.ndarray:
    """Paths (steps, people, 2) from a circle of radius 3.5 m through the middle, at most
    SPEED * DT per step (Euclidean): they cross, and their sets overlap."""
    angles = rng.uniform(0, 2 * np.pi, people)
    start = 3.5 * np.column_stack([np.cos(angles), np.sin(angles)])
    paths = np.zeros((steps, people, 2))
    paths[0] = start
    for k in range(1, steps):
        towards = -start + rng.normal(0, 1.0, (people, 2))
        unit = towards / np.linalg.norm(towards, axis=1, keepdims=True)
        paths[k] = paths[k - 1] + unit * rng.uniform(0, SPEED * DT, (people, 1))
    return paths


def abreast_walks(rng: np.random.Generator, people: int, steps: int) -> np.ndarray:
    """Paths (steps, people, 2) of a group walking side by side 1 m apart (as the crowd's
    n4-n6), from 6 m out across the middle at one pace within the bound: they enter and
    leave the views together. Half the time one of them stops on the way and stays there (a
    neighbour's track ends while its own goes on)."""
    angle = rng.uniform(0, 2 * np.pi)
    heading = -np.array([np.cos(angle), np.sin(angle)])
    side = np.array([-heading[1], heading[0]])
    lateral = (np.arange(people) - (people - 1) / 2 + rng.uniform(-2, 2))[:, None] * side
    stops = np.full(people, steps)
    if rng.random() < 0.5:
        stops[rng.integers(people)] = rng.integers(steps // 4, 3 * steps // 4)
    paths = np.zeros((steps, people, 2))
    paths[0] = -6.0 * heading + lateral
    for k in range(1, steps):
        pace = rng.uniform(0.5, 1.0) * SPEED * DT
        paths[k] = paths[k - 1] + (k < stops)[:, None] * pace * heading
    return paths


WALKS = {"crossing": crossing_walks, "abreast": abreast_walks}


def random_sensor(rng: np.random.Generator, name: str) -> Sensor:
    """A disc or a half-plane (cut to a large box)."""
    if rng.random() < 0.5:
        center = rng.uniform(-4, 4, 2)
        return Sensor(name, Point(center).buffer(rng.uniform(2.0, 5.0)))
    angle = rng.uniform(0, 2 * np.pi)
    normal = np.array([np.cos(angle), np.sin(angle)])
    along = np.array([-normal[1], normal[0]])
    offset = rng.uniform(-2, 2)
    corners = [offset * normal + s * along + t * normal
               for s, t in ((-50, 0), (50, 0), (50, 50), (-50, 50))]
    return Sensor(name, Polygon(corners))


def gap_sensor(rng: np.random.Generator, name: str) -> Sensor:
    """A view through a gap between occluders: a strip 1 to 3.5 m wide near the middle (cut
    to a large box), narrower than a set widened by a large jitter."""
    angle = rng.uniform(0, 2 * np.pi)
    normal = np.array([np.cos(angle), np.sin(angle)])
    along = np.array([-normal[1], normal[0]])
    offset, width = rng.uniform(-3, 3), rng.uniform(1.0, 3.5)
    corners = [(offset + t) * normal + s * along
               for s, t in ((-50, 0), (50, 0), (50, width), (-50, width))]
    return Sensor(name, Polygon(corners))


SENSORS = {"open": random_sensor, "gap": gap_sensor}


def jittered(rng: np.random.Generator, path: np.ndarray, jitter: float) -> np.ndarray:
    """Simulated positions p = s + e with |e| <= jitter."""
    angles = rng.uniform(0, 2 * np.pi, len(path))
    sizes = rng.uniform(0, jitter, len(path))
    return path + sizes[:, None] * np.column_stack([np.cos(angles), np.sin(angles)])


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), people=st.integers(2, 4), count=st.integers(1, 3),
       jitter=st.sampled_from([0.0, 0.1]))
def test_every_detected_pedestrian_stays_in_a_track_set(seed, people, count, jitter):
    rng = np.random.default_rng(seed)
    model = motion_model(jitter)
    paths = crossing_walks(rng, people, 16)
    node = Node([random_sensor(rng, f"s{i}") for i in range(count)], model)
    for k, path in enumerate(paths):
        node.step(rng, k, jittered(rng, path, jitter))
        for i in node.seen:
            assert covered(model, [t.estimate for t in node.tracks], path[i]), (k, i)
    assert node.most_tracks <= 3 * people


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), people=st.integers(2, 4))
def test_fusion_across_nodes_keeps_every_detected_pedestrian(seed, people):
    rng = np.random.default_rng(seed)
    model = motion_model()
    paths = crossing_walks(rng, people, 14)
    nodes = [Node([random_sensor(rng, f"{n}s{i}") for i in range(2)], model) for n in "ab"]
    for k, path in enumerate(paths):
        for node in nodes:
            node.step(rng, k, path)
        fused = associate_nodes(
            [NodeTracks(name, {t.track_id: t.estimate for t in node.tracks}, R(node.visible))
             for name, node in zip("ab", nodes, strict=True)], model, fusion, K)
        sources = sorted(s for f in fused for s in f.sources)
        assert sources == sorted((name, t.track_id) for name, node in zip("ab", nodes,
                                                                          strict=True)
                                 for t in node.tracks)
        for i in nodes[0].seen | nodes[1].seen:
            assert covered(model, [f.estimate for f in fused], path[i]), (k, i)


def run(model: MotionModel, sensors: list[Sensor], paths: np.ndarray, seed: int = 0,
        ) -> list[tuple[LocalTrack, ...]]:
    """The tracks of one node at every step, checked for soundness on the way."""
    rng = np.random.default_rng(seed)
    node = Node(sensors, model)
    history = []
    for k, path in enumerate(paths):
        node.step(rng, k, path)
        for i in node.seen:
            assert covered(model, [t.estimate for t in node.tracks], path[i]), (k, i)
        history.append(node.tracks)
    return history


def straight(start, end, steps: int) -> np.ndarray:
    """A straight walk (steps, 2) from ``start`` to ``end``, within the speed bound."""
    walk = np.linspace(np.asarray(start, float), np.asarray(end, float), steps)
    assert (np.linalg.norm(np.diff(walk, axis=0), axis=1) <= SPEED * DT).all()
    return walk


WIDE = Sensor("wide", box(-20, -20, 20, 20))


def test_two_pedestrians_crossing_end_with_one_tight_track_each():
    model = motion_model()
    paths = np.stack([straight((-4, -0.2), (4, -0.2), 17), straight((4, 0.2), (-4, 0.2), 17)],
                     axis=1)
    history = run(model, [WIDE, Sensor("second", box(-20, -20, 20, 20))], paths)
    final = history[-1]
    assert len(final) == 2
    for i in range(2):
        holding = [t for t in final if covered(model, [t.estimate], paths[-1, i])]
        assert len(holding) == 1 and holding[0].occupied
        assert model.position(holding[0].estimate).volume() < (2 * NOISE) ** 2 * 2


def test_pedestrian_hidden_then_reappearing():
    """Behind an occluder the set grows; back in sight the pedestrian gets a tight track, and
    a set for the occluded box stays (anonymous: the one who went in may still hide there)."""
    model = motion_model()
    occluder = box(0, -1, 2, 1)
    region = Sensor("around", box(-20, -20, 20, 20).difference(occluder))
    path = np.concatenate([straight((-3, 0), (1, 0), 7), np.tile([[1.0, 0.0]], (4, 1)),
                           straight((1, 0), (-3, 0), 7)])
    history = run(model, [region], path[:, None, :])
    assert all(len(tracks) <= 2 for tracks in history)
    hidden = [k for k, p in enumerate(path) if p[0] > 0 and k < 11]
    areas = [model.position(history[k][0].estimate).volume() for k in hidden]
    assert all(len(history[k]) == 1 for k in hidden)
    assert all(later >= earlier - 1e-9 for earlier, later in pairwise(areas))  # grows hidden
    final = history[-1]
    holding = [t for t in final if covered(model, [t.estimate], path[-1])]
    assert len(holding) == 1
    assert model.position(holding[0].estimate).volume() < (2 * NOISE) ** 2 * 2
    for track in final:
        if track is not holding[0]:  # the occluded box's set, nothing visible
            assert occluder.buffer(1e-5).covers(K.convex_outer(track.estimate.vertices()).shape)


def test_two_sensors_seeing_the_same_person_start_one_track():
    model = motion_model()
    rng = np.random.default_rng(3)
    found = detections(rng, np.array([[1.0, 1.0]]), [WIDE, Sensor("other", WIDE.region)])
    result = associate(model, SETTINGS, (), found, {"wide": R(WIDE.region),
                                                    "other": R(WIDE.region)}, 0, 0, K)
    assert len(result.tracks) == 1 and result.tracks[0].joined == (0, 1)
    track = result.tracks[0].estimate
    assert track.volume() < min(model.initial_set(model.path_strips(d.strips), "enclose")
                                .volume() for d in found)


def test_a_new_pedestrian_inside_a_hidden_track_starts_its_own_track():
    """The old pedestrian hides right of x = 0 while its set grows over the visible side; a
    new one appears inside that set. Correcting the old track with the new detection would
    lose the old pedestrian (the test fails on that rule)."""
    model = motion_model()
    region = Sensor("left", box(-20, -20, 0, 20))
    old = np.concatenate([straight((-0.5, 0), (1.0, 0), 4), np.tile([[1.0, 0.0]], (5, 1))])
    new = np.tile([[-0.4, 0.3]], (9, 1))
    paths = np.stack([old, new], axis=1)
    rng = np.random.default_rng(1)
    node = Node([region], model)
    for k, path in enumerate(paths):
        shown = path if k >= 5 else path[:1]  # the new pedestrian appears at step 5
        node.step(rng, k, shown)
        for i in node.seen:
            assert covered(model, [t.estimate for t in node.tracks], shown[i]), (k, i)
    assert node.seen == {0, 1}


def test_a_track_that_certainly_left_ends():
    model = motion_model()
    path = straight((0, 0), (1, 0), 4)[:, None, :]
    rng = np.random.default_rng(0)
    node = Node([WIDE], model)
    for k, p in enumerate(path):
        node.step(rng, k, p)
    node.step(rng, len(path), np.zeros((0, 2)))  # gone: wholly visible, nothing detected
    assert node.tracks == ()


def test_nodes_fuse_only_certain_pairs():
    model = motion_model()
    rng = np.random.default_rng(2)
    alone, close = np.array([[5.0, 5.0]]), np.array([[0.0, 0.0], [0.3, 0.0]])
    a, b = Node([WIDE], model), Node([Sensor("b", WIDE.region)], model)
    for k in range(2):
        a.step(rng, k, np.vstack([alone, close]))
        b.step(rng, k, alone)  # b sees only the lone pedestrian ... and not the close pair
    b.sensors = [Sensor("b", box(3, 3, 7, 7))]
    b.step(rng, 2, alone)
    a.step(rng, 2, np.vstack([alone, close]))
    fused = associate_nodes([NodeTracks("a", {t.track_id: t.estimate for t in a.tracks},
                                        R(a.visible)),
                             NodeTracks("b", {t.track_id: t.estimate for t in b.tracks},
                                        R(b.visible))], model, fusion, K)
    pairs = [f for f in fused if len(f.sources) == 2]
    assert len(pairs) == 1 and covered(model, [pairs[0].estimate], alone[0])
    assert all(len(f.sources) == 1 for f in fused if f is not pairs[0])
    for p in np.vstack([alone, close]):
        assert covered(model, [f.estimate for f in fused], p)


def test_tracks_that_claim_the_same_pedestrian_both_keep_it():
    """Each track claims one sensor's detection of the same pedestrian and sees the other
    sensor only in part: if a claimer left out the other's claim, both would lose it."""
    model = motion_model()
    left, right = box(-20, -20, 0.5, 20), box(-0.5, -20, 20, 20)
    tracks = (LocalTrack(0, Zonotope(np.array([-0.3, 0.0]), 0.5 * np.eye(2)), 0, True),
              LocalTrack(1, Zonotope(np.array([0.3, 0.0]), 0.5 * np.eye(2)), 0, True))
    found = detections(np.random.default_rng(0), np.zeros((1, 2)),
                       [Sensor("left", left), Sensor("right", right)])
    result = associate(model, SETTINGS, tracks, found, {"left": R(left), "right": R(right)}, 0, 2,
                       K)
    assert [t.track_id for t in result.tracks if covered(model, [t.estimate], np.zeros(2))] \
        == [0, 1]


def test_near_duplicate_tracks_merge_into_a_set_that_covers_both():
    model = motion_model()
    first = Zonotope(np.array([0.0, 0.0]), 0.5 * np.eye(2))
    second = Zonotope(np.array([0.01, 0.0]), 0.5 * np.eye(2))
    tracks = (LocalTrack(0, first, 0, True), LocalTrack(1, second, 0, False))
    result = associate(model, SETTINGS, tracks, [], {}, 0, 2, K)
    assert len(result.tracks) == 1 and result.tracks[0].occupied
    merged = result.tracks[0].estimate
    assert merged.contains(np.vstack([first.vertices(), second.vertices()]), tol=1e-9).all()


def test_overlapping_tracks_of_pedestrians_the_other_node_cannot_see_are_kept_apart():
    """a sees only P1, b only P2; their sets meet, each the other's only one: without the
    visibility test their intersection would hold neither pedestrian."""
    model = motion_model()
    p1, p2 = np.array([0.0, 0.0]), np.array([0.6, 0.0])
    a = NodeTracks("a", {0: Zonotope(np.array([0.25, 0.0]), 0.3 * np.eye(2))},
                   R(Point(p1).buffer(0.2)))
    b = NodeTracks("b", {0: Zonotope(np.array([0.35, 0.0]), 0.3 * np.eye(2))},
                   R(Point(p2).buffer(0.2)))
    fused = associate_nodes([a, b], model, fusion, K)
    assert sorted(f.sources for f in fused) == [(("a", 0),), (("b", 0),)]
    assert all(covered(model, [f.estimate for f in fused], p) for p in (p1, p2))


def test_a_track_is_not_fused_with_a_larger_track_that_holds_someone_else():
    """b sees P1 and P2 in one set; a sees P1 only: a's track certainly belongs to b's, but
    b's also holds P2, whom a cannot see (the certain pair must hold both ways)."""
    model = motion_model()
    p1, p2 = np.array([0.0, 0.0]), np.array([1.0, 0.0])
    a = NodeTracks("a", {0: Zonotope(p1, 0.3 * np.eye(2))}, R(box(-3, -3, 0.7, 3)))
    b = NodeTracks("b", {0: Zonotope(np.array([0.5, 0.0]), np.diag([0.9, 0.5]))},
                   R(box(-3, -3, 3, 3)))
    fused = associate_nodes([a, b], model, fusion, K)
    assert sorted(f.sources for f in fused) == [(("a", 0),), (("b", 0),)]
    assert all(covered(model, [f.estimate for f in fused], p) for p in (p1, p2))
    b_alone = NodeTracks("b", {0: Zonotope(p1, 0.35 * np.eye(2))}, R(box(-3, -3, 3, 3)))
    assert [f.sources for f in associate_nodes([a, b_alone], model, fusion, K)] \
        == [(("a", 0), ("b", 0))]


@pytest.mark.parametrize("state_model", ["position", "constant-velocity"])
def test_anonymous_node_observer_keeps_every_pedestrian(state_model):
    config = Estimator(state_model=state_model, max_pedestrian_speed_mps=SPEED,
                       max_velocity_change_mps=2 * SPEED, position_jitter_m=0.3)
    model = motion.motion_model(config, DT)
    observer = AnonymousNodeObserver("car", model, SETTINGS, K)
    rng = np.random.default_rng(4)
    sensors = [Sensor("front", Point(-1, 0).buffer(3.0)), Sensor("side", box(-1, -20, 20, 20))]
    paths = crossing_walks(rng, 3, 14)
    seen: set[int] = set()
    for k, path in enumerate(paths):
        seen |= {i for i, p in enumerate(path)
                 if any(s.region.contains(Point(p)) for s in sensors)}
        tracks = observer.step(k, NodeScan(tuple(detections(rng, path, sensors)),
                                           {s.name: R(s.region) for s in sensors}))
        assert all(key == t.person_id and key.startswith("car:") and t.step == k
                   for key, t in tracks.items())
        for i in seen:
            assert covered(model, [t.estimate for t in tracks.values()], path[i]), (k, i)
    assert seen == {0, 1, 2}


def test_a_track_off_the_walkable_ground_ends():
    model = motion_model()
    ground = box(-5, -1, 5, 1)
    tracks = (LocalTrack(0, Zonotope(np.array([0.0, 0.0]), 0.3 * np.eye(2)), 0, True),
              LocalTrack(1, Zonotope(np.array([0.0, 4.0]), 0.3 * np.eye(2)), 0, True))
    result = associate(model, SETTINGS, tracks, [], {}, 1, 2, K, R(ground))
    assert [t.track_id for t in result.tracks] == [0]


VEHICLE_EXAMPLES = int(os.environ.get("SSE_ASSOCIATION_EXAMPLES", "8"))
"""How many examples the vehicle's property test draws (8 in every test run; issue #60 ran
2,000 once: ``SSE_ASSOCIATION_EXAMPLES=2000 pytest tests/estimation/test_association.py -k
vehicle_holds``)."""


@settings(max_examples=VEHICLE_EXAMPLES, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), people=st.integers(2, 4),
       walk=st.sampled_from(sorted(WALKS)), jitter=st.sampled_from([0.0, 0.3, 1.2]),
       second=st.sampled_from(sorted(SENSORS)))
def test_a_vehicle_holds_every_pedestrian_it_knows_of_in_a_fused_set_and_refined_region(
        seed, people, walk, jitter, second):
    """The vehicle's pipeline on crossing paths with overlapping sets, and on groups walking
    abreast 1 m apart through the views (one may stop while the others leave, so that tracks
    end beside a neighbour's), with simulated positions p = s + e, |e| <= jitter, the bus's
    second sensor open or seeing through a gap: :func:`vehicle_run`."""
    vehicle_run(seed, people, walk, jitter, 24, second)


def vehicle_run(seed: int, people: int, walk: str, jitter: float, steps: int,
                second: str = "open") -> None:
    """Own and received tracks fused (AnonymousFusionCentre, over a V2X link with latency),
    refined with the clear regions of each fused track: every pedestrian the vehicle or the
    sender (by the step of its newest message) has detected has its path point in some fused
    set and its position in some refined region, or its path point in a track a node ended and
    handed over to the vehicle's unobserved area (its set predicted to now; fails if a view is
    taken as clear for a track that meets one of the viewer's detected tracks); every
    pedestrian a node detects now is in one of its tracks that joined a detection; every
    pedestrian the vehicle detects now is in a fused set it counts as in view."""
    rng = np.random.default_rng(seed)
    model = motion_model(jitter)
    sensors = {"bus": [random_sensor(rng, "bus_a"), SENSORS[second](rng, "bus_b")],
               "rsu": [random_sensor(rng, "rsu_a")]}
    observers = {node: AnonymousNodeObserver(node, model, SETTINGS, K) for node in sensors}
    views = {node: R(unary_union([s.region for s in mine])) for node, mine in sensors.items()}
    centre = AnonymousFusionCentre(model, SETTINGS, "enclose", ["bus_a", "bus_b"], "bus", K)
    link = V2XLink(V2X(latency_steps=1), np.random.default_rng(0))
    refined = RefinedRegions(OccupancyTracker(model, K), history=False)
    first_seen: dict[str, dict[int, int]] = {node: {} for node in sensors}
    handed: list[Zonotope] = []
    for k, paths in enumerate(WALKS[walk](rng, people, steps)):
        positions = jittered(rng, paths, jitter) if jitter else paths
        tracks = {}
        for node, mine in sensors.items():
            seen_now = [i for i, p in enumerate(positions)
                        if any(s.region.contains(Point(p)) for s in mine)]
            for i in seen_now:
                first_seen[node].setdefault(i, k)
            scan = NodeScan(tuple(detections(rng, positions, mine)),
                            {s.name: R(s.region) for s in mine})
            tracks[node] = observers[node].step(k, scan)
            detected = [t.estimate for t in tracks[node].values() if t.detected]
            for i in seen_now:
                assert covered(model, detected, paths[i]), (node, k, i)
        link.send(Message("rsu", k, {key: t.estimate for key, t in tracks["rsu"].items()},
                          views["rsu"],
                          frozenset(key for key, t in tracks["rsu"].items() if t.detected),
                          False, tracks["rsu"].ended, tracks["rsu"].ended_since),
                  0.0)
        link.deliver(k)
        # what the nodes ended is handed to the unobserved area: here its sets, moved to now
        handed = [model.predict(z) for z in handed]
        handed += [model.predict(t.estimate, k - t.step)
                   for t in (*tracks["bus"].ended_at(k), *link.take_ended())]
        shared = link.picture(k, model)
        estimate, clear = centre.step(tracks, shared, views["bus"],
                                      detected_now(tracks["bus"], shared))
        possible = refined.update(k, {}, estimate, clear)
        in_view = [estimate.fused[name] for name in estimate.in_view]
        for i, p in enumerate(positions):  # seen by the bus now: in a fused set in view
            if any(s.region.contains(Point(p)) for s in sensors["bus"]):
                assert covered(model, in_view, paths[i]), (k, i)
        rsu_step = k - shared.ages.get("rsu", k + 1)  # the step of its newest message
        known = set(first_seen["bus"]) | {
            i for i, first in first_seen["rsu"].items() if first <= rsu_step}
        for i in known:
            if covered(model, handed, paths[i]):
                continue
            assert covered(model, estimate.fused.values(), paths[i]), (k, i)
            assert any(r.shape.distance(Point(positions[i])) <= 1e-7
                       for r in possible.values()), (k, i)


@pytest.mark.parametrize(("seed", "people", "walk", "jitter", "second", "steps"), [
    (9, 3, "crossing", 0.0, "open", 12), (94, 2, "crossing", 0.0, "open", 12),
    (204, 2, "crossing", 0.0, "open", 12), (4, 3, "abreast", 1.2, "gap", 24),
    (17, 4, "crossing", 1.2, "gap", 24), (28, 2, "abreast", 1.2, "gap", 24),
    (40, 2, "abreast", 1.2, "gap", 24)])
def test_the_pipeline_keeps_the_pedestrians_of_the_cases_found_by_the_property(
        seed, people, walk, jitter, second, steps):
    """9 and 204: a refined region cut empty by GEOS's difference with the view now, though
    the pedestrian in it is 0.12 m (0.72 m) outside the view: the region's edges lay on the
    view's, from the same cut a moment before. 94: a piece X ∩ d marked occupied (R8) though
    d's pedestrian had been left out of X for another track's claim (R4); a step later the
    empty track claimed that pedestrian's detection and the track holding it left it out.
    4, 17, 28 and 40 (issue #60, 60 seeds of the widened property): a pedestrian seen
    through the gap, within the jitter of its edge, was in a track that joined no detection
    (the sensor's region shrunk by the jitter missed the track)."""
    vehicle_run(seed, people, walk, jitter, steps, second)

