"""The town scene (scenarios/town.toml) with anonymous detections, in real SUMO (issue #26 item
7): Bismarckstrasse in Bad Hersfeld, one run of the whole scene.

The pedestrian stands behind the parked truck in the road-side camera rsu1's view until 7.6 s,
walks along the sidewalk and steps onto the zebra at node 1384946487 at 16.2 s; rsu1 sees it
from 0 s to 18.0 s and again from 24.6 s until its walk ends at 25.8 s (the bus from 11.6 s
to 12.3 s and from 15.8 s). The second pedestrian (``walker``) stays over 120 m from rsu1 and
nobody detects it. Measured on this run: rsu1 keeps one track that joined a detection while
it sees the pedestrian (the same one at every step); it starts three tracks in all, the two
others R8's possibility that the pedestrian stepped into the truck's shadow (at 0.1 s and at
24.6 s, when it comes back into view), which no detection ever joins. That possibility
outlives the walk (under A4 only a view into the shadow could end it) and grows at the speed
bound; after the walk its bus region meets the zebra from 31.5 s, once the bus has passed it
(its front leaves it at 28.8 s), up to 24.3 m² of its 25.6 m², but no view: the regions reach
at most 2.49 m into rsu1's view (its messages one step old; the clear regions allow 2.54 m
with the town's jitter of 1.02 m), and not into the bus's own
(:mod:`sse_cosim.estimation.anonymous_fusion`). Before rsu1's and the bus's own stale tracks
stopped keeping their views from being clear, the regions covered 710 m² of the bus's view the
step after the walk, and the bus did not finish its route in the scene's 45 s."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import shapely

from sse_cosim.estimation.occupancy import ARC_SAFETY, COARSEN_M
from sse_cosim.pipeline.result import StepResult
from sse_cosim.pipeline.stages import union_or_empty, views_of
from sse_cosim.reporting.recorder import RunRecorder
from sse_cosim.runner.simulation import simulate
from sse_cosim.scenario.loader import load_scenario

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
TOWN = ROOT / "scenarios" / "town.toml"
CAMERA = "rsu1"
PEDESTRIAN = "pedestrian"  # the one behind the truck; rsu1 sees no other
IN_VIEW_TOL_M2 = 1e-3  # an overlap of a region and a view below this is rounding


@dataclass(frozen=True)
class TownRun:
    """The run's summary, the recorder's per-pedestrian checks (``pedestrians.csv``'s rows),
    every step's result and the step length (s)."""

    summary: dict
    checks: pd.DataFrame = field(repr=False)
    steps: list[StepResult] = field(repr=False)
    step_length: float


@pytest.fixture(scope="module")
def town(tmp_path_factory: pytest.TempPathFactory) -> TownRun:
    scenario = load_scenario(TOWN, {"estimator.association": "anonymous"})
    recorder = RunRecorder(scenario)
    steps: list[StepResult] = []

    def on_step(result: StepResult) -> None:
        recorder(result)
        steps.append(result)

    info = simulate(scenario, tmp_path_factory.mktemp("town_anonymous"), "town", on_step,
                    on_start=recorder.start)
    return TownRun(recorder.summary(info.arrived), pd.DataFrame(recorder.pedestrian_rows),
                   steps, info.scenario.simulation.step_length_s)


def _time(result: StepResult) -> float:
    return round(result.snapshot.time, 6)


def _seen_by(node: str, result: StepResult) -> set[str]:
    """The pedestrians ``node``'s sensors detect at this step."""
    return {pid for o in views_of(node, result.observations) for pid in o.detections}


def _holds(result: StepResult, node: str, key: str, pid: str) -> bool:
    """Whether ``node``'s track ``key`` holds ``pid``'s true position (its position set)."""
    position = result.model.position(result.tracks[node][key].estimate)
    return bool(position.contains(np.asarray(result.snapshot.persons[pid].position),
                                  tol=1e-7))


def _reach_into_view(result: StepResult, age: int, step_length: float) -> float:
    """How far (m) a refined region may reach into a view taken ``age`` steps ago that no
    detected track meets: the path set is cut to within the jitter plus the walk since then of
    the ground outside the view, then widened by the jitter (each as a polygon circumscribing
    the disc) and coarsened (grown by COARSEN_M with mitred corners, up to five times that at
    sharp ones, and simplified by it; :class:`~sse_cosim.estimation.occupancy.OccupancyTracker`).
    """
    model = result.model
    slack = model.jitter + model.max_speed * step_length * age
    return ARC_SAFETY * (slack + model.jitter) + 6.0 * COARSEN_M


def test_the_town_scene_stays_sound_and_safe_with_anonymous_detections(town):
    summary = town.summary
    assert summary["collisions"] == summary["contact_steps"] == 0
    assert summary["containment_violations"] == 0, summary["violations"]
    assert summary["route_completed"]
    for column in ("contained_fused", "contained_refined"):
        checked = town.checks[column].dropna()
        assert len(checked) > 0 and checked.astype(bool).all(), column


def test_a_pedestrian_in_the_cameras_view_keeps_one_track(town):
    """While rsu1 sees the pedestrian (standing, then walking to the zebra) one of its tracks
    that joined a detection holds it at every step, the same one all along: rsu1 keeps as many
    detected tracks as pedestrians it sees (one)."""
    pedestrians = {pid for r in town.steps for pid in _seen_by(CAMERA, r)}
    assert pedestrians == {PEDESTRIAN}
    seen = [r for r in town.steps if PEDESTRIAN in _seen_by(CAMERA, r)]
    start = np.asarray(town.steps[0].snapshot.persons[PEDESTRIAN].position)
    standing = [r for r in seen
                if np.allclose(r.snapshot.persons[PEDESTRIAN].position, start, atol=1e-6)]
    assert len(standing) >= 70 and len(seen) >= 190  # 76 standing, 194 in view
    detected = {_time(r): sorted(key for key, track in r.tracks[CAMERA].items()
                                 if track.detected) for r in seen}
    many = {t: keys for t, keys in detected.items() if len(keys) != 1}
    assert not many, many  # one per pedestrian in view at every step
    missed = [_time(r) for r in seen if not _holds(r, CAMERA, detected[_time(r)][0], PEDESTRIAN)]
    assert not missed, missed
    ever = {key for r in town.steps for key, track in r.tracks[CAMERA].items() if track.detected}
    assert len(ever) == len(pedestrians), ever  # the same track all along
    started = {key for r in town.steps for key in r.tracks[CAMERA]}
    assert len(started) <= 3, started  # and R8's shadow, split off at each entry into view


def test_the_track_left_behind_keeps_no_view_from_being_clear(town):
    """After the walk has ended nobody is in any view, and what is left of the pedestrian's
    tracks (where it may have stepped into the truck's shadow) grows on; the bus's regions of
    it reach into no view taken after the walk beyond what the clear regions allow, the bus's
    own view not at all."""
    assert town.summary["containment_violations"] == 0
    gone = max(_time(r) for r in town.steps if PEDESTRIAN in r.snapshot.persons)
    after = [r for r in town.steps if _time(r) > gone]
    step_length = town.step_length
    assert len(after) >= 100  # 146 steps, 14.6 s
    assert not any(_seen_by(node, r) for r in after for node in r.tracks)
    left = {key for r in after for key in r.tracks[CAMERA]}
    assert len(left) == 1, left  # the shadow's track, never detected again
    checked = 0
    for result in after:
        ego = result.vehicles["bus"]
        views = [(union_or_empty(o.visible for o in views_of("bus", result.observations)), 0)]
        views += [(view, ego.shared.ages[sender]) for sender, view in ego.shared.regions.items()
                  if _time(result) - ego.shared.ages[sender] * step_length > gone + 1e-6]
        for view, age in views:
            inner = shapely.buffer(view, -_reach_into_view(result, age, step_length))
            for key, region in ego.possible.items():
                overlap = shapely.intersection(region, inner if age else view).area
                assert overlap < IN_VIEW_TOL_M2, (_time(result), key, age, overlap)
                checked += 1
    assert checked >= 400  # the bus's own view and rsu1's, for every region
