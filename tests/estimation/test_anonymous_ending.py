"""Anonymous tracks that join no detection end, and their pedestrians go to the unobserved
area (:class:`~sse_cosim.estimation.observer.AnonymousNodeObserver`,
:class:`~sse_cosim.estimation.occupancy.UnobservedArea`,
:class:`~sse_cosim.estimation.v2x.V2XLink`).

A pedestrian walks along a closed sidewalk in and out of a node's camera view; a second
camera sees the rest of the sidewalk for the first steps only, so that no undetected
pedestrian can be anywhere on it. The automated vehicle sees nothing itself and learns of the
pedestrian from the node's messages: at every step it must lie in a track of the node's newest
message (predicted to now) or in the vehicle's unobserved area."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from sse_cosim.estimation import motion
from sse_cosim.estimation.association import AnonymousDetection
from sse_cosim.estimation.motion import MotionModel
from sse_cosim.estimation.observer import (
    END_AFTER_STEPS,
    ENDED_KEPT_STEPS,
    AnonymousNodeObserver,
    EstimatorSettings,
    LocalTracks,
    NodeScan,
)
from sse_cosim.estimation.occupancy import EndedTrack, UnobservedArea
from sse_cosim.estimation.v2x import Message, V2XLink
from sse_cosim.regions import PolygonRegion as R
from sse_cosim.regions import kind
from sse_cosim.scenario.model import V2X, Estimator
from sse_cosim.sets import Strips, Zonotope

DT = 0.5
SPEED = 1.5  # m/s: at most 0.75 m per step
JITTER = 0.2  # m
NOISE = 0.3  # m: strip half-width
SETTINGS = EstimatorSettings("enclose", "girard", 8)
SIDEWALK = shapely.box(0.0, 0.0, 40.0, 2.0)  # the walkable ground
VIEW = shapely.box(-1.0, -1.0, 10.0, 3.0)  # the node's camera: x < 10
FAR = shapely.box(10.0, -1.0, 41.0, 3.0)  # its second camera, on for the first FAR_STEPS
FAR_STEPS = 5
K = kind("polygon")
EMPTY = K.empty()


def motion_model() -> MotionModel:
    config = Estimator(state_model="position", max_pedestrian_speed_mps=SPEED,
                       position_jitter_m=JITTER)
    return motion.motion_model(config, DT)


def walk(rng: np.random.Generator, steps: int) -> np.ndarray:
    """Positions (steps, 2) on the sidewalk's middle line: from x = 5 out to x = 30 and back,
    again and again, each step at most SPEED * DT (out of view for tens of steps each time)."""
    x, heading, path = 5.0, 1.0, []
    for _ in range(steps):
        path.append((x, 1.0))
        x += heading * SPEED * DT * rng.uniform(0.5, 1.0)
        if not 5.0 < x < 30.0:
            x, heading = min(max(x, 5.0), 30.0), -heading
    return np.array(path)


def views(step: int) -> dict[str, shapely.Geometry]:
    return {"cam": VIEW, "far": FAR} if step < FAR_STEPS else {"cam": VIEW}


def scan(rng: np.random.Generator, step: int, position: np.ndarray) -> NodeScan:
    """The cameras' detections of the pedestrian where they see it (A2), with noise
    |v| <= NOISE."""
    noise = rng.uniform(-NOISE, NOISE, 2)
    found = tuple(AnonymousDetection(name, Strips(np.eye(2), position + noise,
                                                  np.full(2, NOISE)))
                  for name, view in views(step).items()
                  if view.contains(shapely.Point(position)))
    return NodeScan(found, {name: R(view) for name, view in views(step).items()})


def message(step: int, tracks: LocalTracks) -> Message:
    return Message("rsu", step, {key: t.estimate for key, t in tracks.items()},
                   R(shapely.union_all(list(views(step).values()))),
                   frozenset(key for key, t in tracks.items() if t.detected), False,
                   tracks.ended, tracks.ended_since)


def held(model: MotionModel, estimates, position: np.ndarray) -> bool:
    return any(model.position(z).contains(position, tol=1e-7) for z in estimates)


def test_a_track_that_joins_no_detection_ends_and_is_listed_while_kept():
    """Once the pedestrian has left the view, its track ends END_AFTER_STEPS steps after its
    last detection, holding the pedestrian then, and nothing lingers; the node lists what it
    ended for ENDED_KEPT_STEPS steps. (In view, R8's possibility that the pedestrian is
    hidden beyond the view's edge ends END_AFTER_STEPS steps after it split off.)"""
    rng = np.random.default_rng(3)
    model = motion_model()
    observer = AnonymousNodeObserver("rsu", model, SETTINGS, K)
    last_seen, ends = None, []
    for k, position in enumerate(walk(rng, 120)):
        tracks = observer.step(k, scan(rng, k, position))
        if VIEW.contains(shapely.Point(position)):
            last_seen = k
        elif tracks.ended_at(k):
            ended = tracks.ended_at(k)
            assert held(model, [t.estimate for t in ended], position), k
            ends.append(k - last_seen)
        if last_seen is not None and k - last_seen >= END_AFTER_STEPS:
            assert not tracks, k  # nothing lingers
        assert tracks.ended_since == k - ENDED_KEPT_STEPS + 1
        assert all(k - ENDED_KEPT_STEPS < t.step <= k for t in tracks.ended)
    assert ends == [END_AFTER_STEPS] * 2  # each walk out of view ends the track


@pytest.mark.parametrize(("latency", "silent"), [(0, ()), (2, ()), (1, range(8, 70))])
def test_the_vehicle_holds_a_handed_over_pedestrian_in_its_unobserved_area(latency, silent):
    """Over a link with latency (and a sender out of range for 62 steps: more than its
    messages list, so the vehicle hands over every track of the one it kept), the pedestrian
    is in a track of the node's newest message or in the vehicle's unobserved area at every
    step; without the handover it is in neither at some step (what the test would catch)."""
    rng = np.random.default_rng(5)
    model = motion_model()
    observer = AnonymousNodeObserver("rsu", model, SETTINGS, K)
    link = V2XLink(V2X(latency_steps=latency), np.random.default_rng(0))
    handed = UnobservedArea(R(SIDEWALK), model, latency, K)
    without = UnobservedArea(R(SIDEWALK), model, latency, K)
    missed = 0
    for k, position in enumerate(walk(rng, 200)):
        tracks = observer.step(k, scan(rng, k, position))
        if k not in silent:
            link.send(message(k, tracks), 0.0)
        fresh = [m.visible_region for m in link.deliver(k) if k - m.sent_step == latency]
        ended = link.take_ended()
        assert all(t.step <= k - latency for t in ended)
        unobserved = handed.update(k, EMPTY, fresh, ended)
        bare = without.update(k, EMPTY, fresh)
        shared = link.picture(k, model)
        estimates = [z for by_sender in shared.estimates.values() for z in by_sender.values()]
        point = shapely.Point(position)
        in_track = held(model, estimates, position)
        assert in_track or unobserved.shape.distance(point) <= 1e-7, k
        missed += not (in_track or bare.shape.distance(point) <= 1e-7)
    assert missed > 0


def test_a_new_newest_message_hands_over_what_it_lists_or_everything_kept():
    """The link hands over the tracks a sender ended after its kept message; if the new one
    does not list every step since, every track of the kept one too; a first message none."""
    link = V2XLink(V2X(latency_steps=0), np.random.default_rng(0))
    kept, listed, older = (Zonotope(np.full(2, float(i)), np.eye(2)) for i in range(3))
    link.send(Message("rsu", 3, {"rsu:0": kept}, R(VIEW),
                      ended=(EndedTrack(2, older),), ended_since=0), 0.0)
    link.deliver(3)
    assert link.take_ended() == []
    link.send(Message("rsu", 5, {}, R(VIEW), ended=(EndedTrack(2, older), EndedTrack(4, listed)),
                      ended_since=1), 0.0)
    link.deliver(5)
    assert [(t.step, t.estimate) for t in link.take_ended()] == [(4, listed)]
    link.send(Message("rsu", 9, {}, R(VIEW), ended=(), ended_since=7), 0.0)
    link.deliver(9)
    assert link.take_ended() == []  # steps 6-8 unlisted, but message 5 held no track
    link.send(Message("rsu", 10, {"rsu:1": kept}, R(VIEW), ended_since=10), 0.0)
    link.send(Message("rsu", 14, {}, R(VIEW), ended=(EndedTrack(13, listed),), ended_since=12),
              0.0)
    link.deliver(14)
    assert [(t.step, t.estimate) for t in link.take_ended()] == [(13, listed), (10, kept)]
