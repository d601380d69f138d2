"""Margins on demand (reporting.margins): the time to collision's exact ray test against a
brute-force march; the containment depth on known sets; a real S3 run's margins checked again
from the files it wrote (shapely polygons of the written sets, a march for the time)."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
import shapely

from sse_cosim.files import read_text
from sse_cosim.pipeline.result import StepResult
from sse_cosim.reporting.margins import (
    ContainmentDepth,
    CrossingBlocked,
    MovingDistance,
    MovingTimeToCollision,
    TimeToCollision,
    time_to_contact,
)
from sse_cosim.reporting.recorder import REFINED, UNOBSERVED, RegionLog, RegionRecord
from sse_cosim.runner.run import run_scenario_file
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.sets.zonotope import Zonotope
from sse_cosim.world.snapshot import Footprint, PersonState, Pose, Snapshot, VehicleState

ROOT = Path(__file__).resolve().parents[2]
S3 = ROOT / "scenarios" / "s3_pedestrian.toml"
SIDEWAYS_STEP = Path(__file__).with_name("s3_ttc_sideways_step.toml")
MARCH_STEP_S = 1e-3


def _marched(p: np.ndarray, w: np.ndarray, half: np.ndarray, radius: float,
             horizon_s: float) -> float:
    """The first time on a fine grid at which the point is within ``radius`` of the box."""
    box = shapely.box(-half[0], -half[1], half[0], half[1])
    times = np.arange(0.0, horizon_s, MARCH_STEP_S)
    distance = shapely.distance(box, shapely.points(p + np.outer(times, w)))
    touching = np.flatnonzero(distance <= radius)
    return float(times[touching[0]]) if touching.size else np.inf


def test_the_exact_time_agrees_with_a_fine_march_on_random_approaches():
    rng = np.random.default_rng(7)
    half = np.array([6.0, 1.275])
    p = rng.uniform(-25.0, 25.0, size=(300, 2))
    w = rng.uniform(-8.0, 8.0, size=(300, 2))
    radius = rng.uniform(0.1, 0.5, size=300)
    exact = time_to_contact(p, w, half, radius)
    marched = np.array([_marched(p[i], w[i], half, radius[i], 12.0) for i in range(300)])
    finite = np.isfinite(marched)
    assert finite.sum() > 30 and (~finite).sum() > 30  # both kinds of approach occur
    # the march finds contact at most one of its steps after the exact time (and never before)
    assert np.all(marched[finite] - exact[finite] >= -1e-9)
    assert np.all(marched[finite] - exact[finite] <= MARCH_STEP_S + 1e-9)
    assert np.all(exact[~finite] > 12.0 - MARCH_STEP_S)


def test_the_edge_cases_of_the_ray():
    half = np.array([6.0, 1.275])
    r = np.array([0.3])
    # already touching, at a corner's rounding
    assert time_to_contact(np.array([[6.2, 1.4]]), np.zeros((1, 2)), half, r)[0] == 0.0
    # standing beside the box, or moving along it: never
    assert time_to_contact(np.array([[10.0, 3.0]]), np.array([[-5.0, 0.0]]), half, r)[0] == np.inf
    # moving away: never
    assert time_to_contact(np.array([[10.0, 0.0]]), np.array([[1.0, 0.0]]), half, r)[0] == np.inf
    # head on: the gap (10 - 6 - 0.3 m) at 2 m/s
    assert time_to_contact(np.array([[10.0, 0.0]]), np.array([[-2.0, 0.0]]), half, r)[0] == (
        pytest.approx(1.85))
    # a corner's disc: the point passes the corner diagonally
    hit = time_to_contact(np.array([[8.0, 3.275]]), np.array([[-1.0, -1.0]]), half, r)[0]
    assert hit == pytest.approx(2.0 - 0.3 / np.sqrt(2.0))


def test_the_depth_is_the_distance_to_the_boundary_inside_and_minus_it_outside():
    square = (np.zeros(2), np.array([[1.0, 0.0, 0.5], [0.0, 1.0, 0.5]]))  # 3 x 3, a hexagon
    recorder = SimpleNamespace(
        truth_rows=[{"t": 0.0, "pedestrian": "p", "x": 0.2, "y": -0.1},
                    {"t": 0.1, "pedestrian": "p", "x": 2.0, "y": 0.0}],
        set_records=[(0.0, "bus", "rsu1", "p", "local", *square),
                     (0.1, "bus", "rsu1", "p", "local", *square),
                     (0.1, "bus", "bus", "someone else", "fused", *square)],
        regions=RegionLog(records=[
            RegionRecord(0.0, REFINED, "p", shapely.box(-1, -1, 1, 1), "bus"),
            RegionRecord(0.0, UNOBSERVED, None, shapely.box(0.5, -3, 3, 3), "bus"),
            # outside the window the regions claim nothing: not a depth
            RegionRecord(0.1, REFINED, "p", shapely.box(-1, -1, 1, 1), "bus"),
            RegionRecord(0.1, UNOBSERVED, None, shapely.box(0.5, -3, 3, 3), "bus",
                         outside=frozenset({"p"}))]))
    depth = ContainmentDepth(load_scenario(S3)).value(recorder)
    hexagon = shapely.Polygon(Zonotope.unchecked(*square).vertices())
    expected = -hexagon.boundary.distance(shapely.Point(2.0, 0.0))
    assert depth["sets"]["least_m"] == pytest.approx(expected)
    assert depth["sets"]["t"] == 0.1 and depth["sets"]["node"] == "rsu1"
    assert depth["regions"]["least_m"] == pytest.approx(0.8)  # 1 - 0.2 to the right side
    # in both boxes together, nearest the refined box's bottom left of the unobserved one
    assert depth["accounted"] == {"least_m": pytest.approx(0.9), "t": 0.0, "vehicle": "bus",
                                  "pedestrian": "p"}


@pytest.mark.sumo
def test_a_run_reports_its_margins_only_when_asked_and_the_files_agree(tmp_path: Path):
    plain = run_scenario_file(S3, tmp_path / "plain", plots=False, summary_only=True)
    assert "margins" not in plain

    out = tmp_path / "asked"
    summary = run_scenario_file(S3, out, plots=False,
                                margins=("time_to_collision", "containment_depth",
                                         "moving_distance", "crossing_blocked",
                                         "moving_time_to_collision"))
    _the_time_agrees_with_the_files(summary, out)
    _the_depth_agrees_with_the_files(summary, out)
    trace = pd.read_csv(out / "trace.csv")
    moving = trace[trace["bus_speed"] >= 0.1]
    least = summary["margins"]["moving_distance"]
    assert least["least_m"] == pytest.approx(moving["distance_bus_pedestrian"].min())
    assert least["least_m"] >= summary["min_distance_bus_pedestrian_m"]
    moving_ttc = summary["margins"]["moving_time_to_collision"]["least_s"]
    assert moving_ttc >= summary["margins"]["time_to_collision"]["least_s"]
    # the bus stops before the zebra, never on it
    assert summary["margins"]["crossing_blocked"] == {"longest_s": 0.0, "total_s": 0.0}


def _the_time_agrees_with_the_files(summary: dict, out: Path) -> None:
    least = summary["margins"]["time_to_collision"]
    assert 0.0 < least["least_s"] < 10.0 and least["vehicle"] == "bus"
    # again from what the run wrote: the bus along the road (S3's is straight, heading east)
    # at its speed, the pedestrian along its heading at its speed
    trace = pd.read_csv(out / "trace.csv").set_index("t")
    truth = pd.read_csv(out / "truth.csv")
    truth = truth[truth["pedestrian"] == least["pedestrian"]].set_index("t")
    scenario = json.loads((out / "scenario.json").read_text())
    bus = scenario["automated"]["bus"]
    t = least["t"]
    row = trace.loc[t]
    centre = np.array([row["bus_x"] - bus["length_m"] / 2, row["bus_y"]])
    now = truth.loc[t, ["x", "y"]].to_numpy(float)
    speed, heading = truth.loc[t, ["speed", "heading"]].to_numpy(float)
    relative = speed * np.array([np.cos(heading), np.sin(heading)]) - np.array(
        [row["bus_speed"], 0.0])
    radius = scenario["pedestrians"][least["pedestrian"]]["radius_m"]
    half = np.array([bus["length_m"], bus["width_m"]]) / 2
    assert _marched(now - centre, relative, half, radius, 10.0) == pytest.approx(
        least["least_s"], abs=MARCH_STEP_S + 1e-9)


def _the_depth_agrees_with_the_files(summary: dict, out: Path) -> None:
    """Every written set and refined region again as a shapely polygon: the least distance
    from the truth to its boundary (inside) is the summary's. (regions.jsonl.gz does not hold
    the window outside which a region claims nothing; in this run the least comes inside it.)"""
    depth = summary["margins"]["containment_depth"]
    truth = {(row.t, row.pedestrian): shapely.Point(row.x, row.y)
             for row in pd.read_csv(out / "truth.csv").itertuples()}
    least = np.inf
    for line in read_text(out / "sets.jsonl.gz").splitlines():
        record = json.loads(line)
        z = Zonotope.unchecked(np.array(record["center"]), np.array(record["generators"]))
        point = truth.get((record["t"], record["track"]))
        if point is None:  # a set held after the pedestrian left the scene: nothing to hold
            continue
        polygon = shapely.Polygon(z.vertices())
        assert polygon.covers(point)
        least = min(least, polygon.boundary.distance(point))
    assert depth["sets"]["least_m"] == pytest.approx(least, abs=1e-6)
    least = np.inf
    for line in read_text(out / "regions.jsonl.gz").splitlines():
        record = json.loads(line)
        if record["kind"] != REFINED:
            continue
        region = shapely.MultiPolygon([shapely.Polygon(p[0], p[1:])
                                       for p in record["polygons"]])
        point = truth.get((record["t"], record["track"]))
        if point is not None:
            least = min(least, region.boundary.distance(point))
    assert depth["regions"]["least_m"] == pytest.approx(least, abs=1e-5)
    # the area accounted for at the step of its least: every region of that step, together
    accounted = depth["accounted"]
    union = shapely.union_all([
        shapely.Polygon(p[0], p[1:])
        for line in read_text(out / "regions.jsonl.gz").splitlines()
        if (record := json.loads(line))["t"] == accounted["t"] for p in record["polygons"]])
    point = truth[(accounted["t"], accounted["pedestrian"])]
    assert union.covers(point) and accounted["least_m"] >= 0.0
    assert accounted["least_m"] == pytest.approx(union.boundary.distance(point), abs=1e-5)


def test_the_moving_distance_leaves_out_the_steps_a_vehicle_stood():
    rows = [{"t": 0.1 * i, "vehicle": "bus", "bus_speed": v, "distance_bus_pedestrian": d}
            for i, (v, d) in enumerate([(5.0, None), (2.0, 3.0), (0.09, 0.2), (0.0, 0.1),
                                        (0.1, 2.5), (4.0, 6.0)])]
    margin = MovingDistance(load_scenario(S3))
    assert margin.value(SimpleNamespace(rows=rows)) == {  # type: ignore[arg-type]
        "least_m": 2.5, "t": pytest.approx(0.4), "vehicle": "bus"}
    assert margin.value(SimpleNamespace(rows=rows[2:4])) == {  # type: ignore[arg-type]
        "least_m": None}


def test_the_moving_time_to_collision_leaves_out_the_standing_bus():
    scenario = load_scenario(S3)
    bus = Footprint(Pose(200.0, -1.6, 0.0), 12.0, 2.5)  # front at the zebra, heading east
    walker = PersonState("pedestrian", (196.0, -7.6), 1.0, heading=np.pi / 2)  # toward it
    every, moving = TimeToCollision(scenario), MovingTimeToCollision(scenario)
    for margin in (every, moving):
        margin(_step(0, bus, walker))  # the bus stands
    assert every.least_s < 10.0 and moving.least_s == np.inf
    still = _step(1, bus, walker)
    under_way = _step(1, bus, walker, speed=0.1)
    moving(still)
    assert moving.least_s == np.inf
    moving(under_way)  # at 0.1 m/s the bus moves: the walker is on a collision course
    assert 0.0 < moving.least_s < 10.0 and moving.at["t"] == pytest.approx(0.1)


def test_a_crossing_counts_as_blocked_while_both_stand_the_vehicle_on_it():
    """A step counts while the vehicle stands on a crossing and a walker stands with that
    crossing next on its walk; the longest stretch is one vehicle's, the total every one's."""
    margin = CrossingBlocked(load_scenario(S3))
    on_zebra, off = (":C_c0",), ()
    steps = [  # (bus speed, its crossings, walker speed, walker's next crossing)
        (0.0, on_zebra, 0.0, ":C_c0"),  # counts
        (0.0, on_zebra, 0.05, ":C_c0"),  # counts (both below 0.1 m/s)
        (0.0, on_zebra, 1.2, ":C_c0"),  # the walker walks: the stretch ends
        (0.0, on_zebra, 0.0, ":C_c0"),  # counts, a new stretch
        (0.0, on_zebra, 0.0, ":C_c1"),  # bound for another crossing
        (0.0, off, 0.0, ":C_c0"),  # the bus off the crossing
        (0.5, on_zebra, 0.0, ":C_c0"),  # the bus moves
        (0.0, on_zebra, 0.0, None),  # the walker on no walking area
        (0.0, on_zebra, 0.0, ":C_c0"),  # counts
        (0.0, on_zebra, 0.0, ":C_c0"),  # counts
        (0.0, on_zebra, 0.0, ":C_c0"),  # counts: the longest, 3 steps from 0.8 s
    ]
    front = Footprint(Pose(200.0, -1.6, 0.0), 12.0, 2.5)
    for k, (v, crossings, w, bound) in enumerate(steps):
        walker = PersonState("pedestrian", (196.0, -5.0), w, next_crossing=bound)
        margin(_step(k, front, walker, speed=v, on_crossings=crossings))
    assert margin.value(None) == {  # type: ignore[arg-type]
        "longest_s": pytest.approx(0.3), "total_s": pytest.approx(0.6), "t": pytest.approx(0.8),
        "vehicle": "bus", "crossings": [":C_c0"], "pedestrians": ["pedestrian"]}


def test_a_walker_held_on_the_crossing_itself_counts_as_waiting_at_it():
    """SUMO may stop a walker on the crossing's own lane, short of the vehicle standing on it
    (the junction's standoff, CMA-ES's 349th run): that counts as waiting at it, as the
    walking area's kerb does; a walker on another crossing, or walking, does not."""
    margin = CrossingBlocked(load_scenario(S3))
    front = Footprint(Pose(200.0, -1.6, 0.0), 12.0, 2.5)
    steps = [  # (walker speed, the crossing it is on)
        (0.0, ":C_c0"),  # counts
        (0.0, ":C_c0"),  # counts
        (0.4, ":C_c0"),  # SUMO moves it on, jammed: the stretch ends
        (0.0, ":C_c1"),  # on another crossing
        (0.0, None),  # on no crossing, bound for none
    ]
    for k, (w, crossing) in enumerate(steps):
        walker = PersonState("pedestrian", (196.0, -5.0), w, crossing=crossing)
        margin(_step(k, front, walker, on_crossings=(":C_c0",)))
    assert margin.value(None) == {  # type: ignore[arg-type]
        "longest_s": pytest.approx(0.2), "total_s": pytest.approx(0.2), "t": pytest.approx(0.0),
        "vehicle": "bus", "crossings": [":C_c0"], "pedestrians": ["pedestrian"]}


def test_the_pedestrian_keeps_the_heading_sumo_walks_it_through_a_sideways_step():
    """SUMO moves a walker sideways between the lanes of a walking area in one step (0.36 m
    in the S3 falsification's worst cases) while it walks on along the sidewalk: the time to
    collision follows its heading, not that step's displacement, which would read as a turn
    toward the road."""
    scenario = load_scenario(S3)
    bus = Footprint(Pose(200.0, -1.6, 0.0), 12.0, 2.5)  # front at the zebra, heading east
    margin = TimeToCollision(scenario)
    for step, (x, y) in enumerate([(196.0, -7.6), (196.2, -7.24)]):  # the sideways step
        walker = PersonState("pedestrian", (x, y), speed=2.0, heading=0.0)
        margin(_step(step, bus, walker))
    assert margin.least_s == np.inf  # walking east beside a bus standing still: never touch
    waiting = PersonState("pedestrian", (196.4, -7.24), 2.0, heading=None)  # (on no lane)
    margin(_step(2, bus, waiting))
    assert margin.least_s == np.inf
    margin(_step(3, bus, PersonState("pedestrian", (196.4, -7.24), 2.0, heading=np.pi / 2)))
    radius = scenario.person_radius_m("pedestrian")
    bus_right_m = -1.6 - 2.5 / 2  # now walking north, toward the bus's right side
    assert margin.least_s == pytest.approx((bus_right_m - radius + 7.24) / 2.0)
    assert margin.at == {"t": pytest.approx(0.3), "vehicle": "bus", "pedestrian": "pedestrian"}


@pytest.mark.sumo
def test_the_searched_sideways_step_no_longer_reads_as_a_course_toward_the_bus(tmp_path: Path):
    """The falsifier's first least time to collision in S3 (2.254 s, with the heading taken
    from the walker's last step) came from SUMO's 0.36 m sideways step onto the walking area
    at 12.9 s; with the heading SUMO walks it the walker heads along the sidewalk there. (Since
    issue #61's arrival the bus of this case passes the zebra at its nominal speed before the
    walker steps out, and no time to collision is defined at all; the case still must not read
    the step as a course toward the bus.)"""
    summary = run_scenario_file(SIDEWAYS_STEP, tmp_path, plots=False, summary_only=True,
                                margins=("time_to_collision",))
    least = summary["margins"]["time_to_collision"]
    assert least["least_s"] is None or (least["least_s"] > 5.0
                                        and least["t"] not in (12.9, 13.0))


def _step(step: int, bus: Footprint, walker: PersonState, speed: float = 0.0,
          on_crossings: tuple[str, ...] = ()) -> StepResult:
    """Step ``step`` (0.1 s each) of one automated ``bus`` at ``speed`` (m/s), its body on
    ``on_crossings``, and one ``walker``."""
    snapshot = Snapshot(0.1 * step, {"bus": VehicleState("bus", "automated", bus, speed,
                                                         on_crossings=on_crossings)},
                        {walker.id: walker})
    return StepResult(step, snapshot, {}, {}, None, {}, {"bus": None})  # type: ignore[arg-type]
