"""The falsifier's parts without SUMO: the box, its decoding, the objectives, the searchers."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from sse_cosim.cli.main import main
from sse_cosim.errors import UserError
from sse_cosim.falsify.job import (
    CODE_FIELD,
    check_same_code,
    code_digest,
    plan_document,
    prepare,
    recorded_outcomes,
    write_case,
)
from sse_cosim.falsify.objectives import (
    OBJECTIVES,
    OPEN_DEPTH_M,
    OPEN_DISTANCE_M,
    OPEN_TTC_S,
    broken,
    first_break_t,
    promises_broken,
)
from sse_cosim.falsify.search import Recorded, evaluation_key
from sse_cosim.falsify.searchers import SEARCHERS, generation_size
from sse_cosim.falsify.space import (
    COUNTED_BREAKS,
    CrossingEntry,
    DimEntry,
    FalsifyFile,
    LatencyEntry,
    LossEntry,
    PresentEntry,
    build_space,
    load_falsify_file,
    scenario_of,
)
from sse_cosim.files import write_json_atomic, write_text_atomic
from sse_cosim.reporting.falsify_report import EVALUATIONS, FALSIFY_PLAN
from sse_cosim.runner.safety import ActorPlanner
from sse_cosim.scenario.loader import (
    apply_overrides,
    load_scenario,
    load_scenario_data,
    validate_scenario,
)

ROOT = Path(__file__).resolve().parents[2]
SPACE = ROOT / "sweeps" / "falsify.toml"
S1 = ROOT / "scenarios" / "s1_pedestrian.toml"
S3 = ROOT / "scenarios" / "s3_pedestrian.toml"
CROWD = ROOT / "scenarios" / "crowd.toml"
JUNCTION = ROOT / "scenarios" / "junction.toml"
TOWN = ROOT / "scenarios" / "town.toml"


def _space(scenario: Path, spec: FalsifyFile | None = None):
    return build_space(spec or load_falsify_file(SPACE), load_scenario_data(scenario),
                       str(scenario), str(SPACE))


def test_the_box_of_s3_holds_the_pedestrian_every_sensor_and_every_sender():
    space = _space(S3)
    names = [d.name for d in space.dims]
    assert names[:3] == ["walk_mps", "wait_s", "behind_m"]
    sensors = {"bus_front", "bus_near", "rsu1_cam", "rsu2_cam"}
    assert {n for n in names if n.startswith("noise_")} == {
        f"noise_{s}_{axis}" for s in sensors for axis in ("fwd", "lat")}
    assert {n for n in names if n.startswith("loss_")} == {
        f"loss_{node}_{what}" for node in ("rsu1", "rsu2") for what in ("start_s", "length_s")}


def _walk_7_3_s(scenario, source):
    return {"pedestrian": 7.3}


def test_a_point_decodes_into_overrides_that_keep_the_noise_within_its_bound():
    space = _space(S3)
    unit = np.linspace(0.0, 1.0, space.size)
    values, overrides, scenario = scenario_of(space, load_scenario_data(S3), unit, str(S3),
                                              _walk_7_3_s)
    truck_front = scenario.parked["truck"].end_pos_m
    assert overrides["pedestrians.pedestrian.start_pos_m"] == pytest.approx(
        truck_front - values["behind_m"])
    # it steps out after its walk and its wait
    step_out = 7.3 + values["wait_s"]
    assert overrides["pedestrians.pedestrian.steps_onto_crossing_s"] == pytest.approx(step_out)
    assert values["steps_onto_crossing_s"] == pytest.approx(step_out)
    assert scenario.pedestrians["pedestrian"].steps_onto_crossing_s == pytest.approx(step_out)
    for name, sensor in scenario.sensors.items():
        fault = scenario.faults.sensor.get(f"falsify_{name}")
        if fault is None:
            continue
        assert fault.within_bound  # clipped to the bound: A2 holds
        np.testing.assert_allclose(
            np.abs(fault.bias_m), 2 * np.abs([values[f"noise_{name}_fwd"],
                                              values[f"noise_{name}_lat"]])
            * np.asarray(sensor.noise_bound_m), atol=1e-6)
    assert set(COUNTED_BREAKS) <= set(scenario.breaks_assumptions)


def test_a_loss_shorter_than_a_step_adds_no_fault_and_a_longer_one_a_burst():
    space = _space(S3)
    values = space.values(np.full(space.size, 0.5))
    values["loss_rsu1_length_s"] = 0.05
    values["loss_rsu2_length_s"] = 2.0
    overrides = space.overrides(values)
    assert "faults.link.falsify_rsu1" not in overrides
    burst = overrides["faults.link.falsify_rsu2"]
    assert burst["kind"] == "loss"
    assert burst["end_s"] - burst["start_s"] == pytest.approx(2.0)


def test_a_latency_window_decodes_into_a_latency_fault_in_whole_steps():
    spec = load_falsify_file(SPACE).model_copy(deep=True)
    spec.latency = LatencyEntry(longest_s=5.0, most_steps=8)
    space = _space(S3, spec)
    names = [d.name for d in space.dims]
    assert names[-6:] == [f"late_{node}_{what}" for node in ("rsu1", "rsu2")
                          for what in ("start_s", "length_s", "steps")]
    values = space.values(np.full(space.size, 0.5))
    values.update(late_rsu1_steps=0.4, late_rsu2_steps=2.6, late_rsu2_length_s=3.0)
    overrides = space.overrides(values)
    assert "faults.link.falsify_late_rsu1" not in overrides  # rounds to no added step
    late = overrides["faults.link.falsify_late_rsu2"]
    assert late["kind"] == "latency" and late["extra_latency_steps"] == 3
    assert late["end_s"] - late["start_s"] == pytest.approx(3.0)
    _, _, scenario = scenario_of(space, load_scenario_data(S3), np.full(space.size, 0.5),
                                 str(S3), _walk_7_3_s)
    assert scenario.faults.link["falsify_late_rsu2"].extra_latency_steps == 4
    assert set(scenario.breaks_assumptions) == set(COUNTED_BREAKS)  # nothing more declared


def test_the_crowd_box_chooses_who_of_its_pedestrians_steps_out():
    spec = FalsifyFile(present=PresentEntry(pedestrians="*"),
                       dims=[DimEntry(path="pedestrians.*.walking_speed_mps", name="walk_mps",
                                      low=1.0, high=1.5)])
    space = _space(CROWD, spec)
    pedestrians = [d.name.removeprefix("present_") for d in space.dims[1:]]
    assert len(pedestrians) == 21 and "pedestrian" in pedestrians
    unit = np.full(space.size, 0.8)
    unit[1::2] = 0.3  # every other one stays at home
    _, overrides, scenario = scenario_of(space, load_scenario_data(CROWD), unit, str(CROWD),
                                         _walk_7_3_s)
    kept = [pid for pid, ped in scenario.pedestrians.items() if ped.present]
    assert kept == pedestrians[1::2] and overrides["pedestrians.pedestrian.present"] is False


def _crossing_space(scenario: Path, pedestrians: str, planner: ActorPlanner):
    spec = FalsifyFile(crossing=CrossingEntry(pedestrians=pedestrians),
                       loss=LossEntry(longest_s=1.0))
    return build_space(spec, load_scenario_data(scenario), str(scenario), "box",
                       planner.crossings)


def test_a_crossing_box_chooses_each_pedestrians_zebra_among_those_over_the_route():
    planner = ActorPlanner()
    space = _crossing_space(JUNCTION, "w*", planner)
    names = [d.name for d in space.dims]
    assert [n for n in names if n.startswith("crossing_")] == [
        "crossing_w1", "crossing_w2", "crossing_w3"]
    zebras = planner.crossings(load_scenario(JUNCTION), str(JUNCTION), "w1")
    assert len(zebras) == 4 and zebras[0] == ":J_c3"  # its own west arm: the shortest walk
    data, at = load_scenario_data(JUNCTION), names.index("crossing_w1")
    for value, index in ((0.0, 0), (0.3, 1), (0.74, 2), (1.0, 3)):
        unit = np.zeros(space.size)
        unit[at] = value
        _, overrides, scenario = scenario_of(space, data, unit, str(JUNCTION), _walk_7_3_s)
        assert scenario.pedestrians["w1"].crossing == zebras[index]
        assert overrides["pedestrians.w2.crossing"] == zebras[0]


def test_a_pedestrian_with_one_zebra_over_the_route_has_no_crossing_to_choose():
    names = [d.name for d in _crossing_space(S3, "*", ActorPlanner()).dims]
    assert not any(n.startswith("crossing_") for n in names) and len(names) == 4


@pytest.mark.sumo
def test_a_zebra_the_pedestrian_cannot_reach_by_its_step_out_is_not_feasible():
    # w1 steps out at 22 s from the west arm's sidewalk: over its own zebra it can; over the
    # farthest, the one walk that takes no other zebra goes round the block
    planner = ActorPlanner()
    space, data = _crossing_space(JUNCTION, "w1", planner), load_scenario_data(JUNCTION)
    own, farthest = space.crossings[0].choices[0], space.crossings[0].choices[-1]
    reasons = {}
    for value in (0.0, 1.0):
        _, _, scenario = scenario_of(space, data, np.full(space.size, value), str(JUNCTION),
                                     _walk_7_3_s)
        reasons[scenario.pedestrians["w1"].crossing] = planner(scenario, str(JUNCTION))
    assert own == ":J_c3" and reasons[own] is None
    assert "steps onto it at" in reasons[farthest] and farthest in reasons[farthest]


def test_a_step_out_pedestrian_left_out_of_the_scene_gets_no_step_out():
    spec = load_falsify_file(SPACE).model_copy(deep=True)
    spec.present = PresentEntry(pedestrians="pedestrian")
    space = _space(S3, spec)
    assert space.dims[-1].name == "present_pedestrian"
    unit = np.full(space.size, 0.5)
    unit[-1] = 0.2
    values, _, scenario = scenario_of(space, load_scenario_data(S3), unit, str(S3),
                                      lambda sc, source: {})  # nobody walks
    assert not scenario.pedestrians["pedestrian"].present
    assert "steps_onto_crossing_s" not in values


def test_s1_has_no_sender_to_lose_and_no_shared_sensor():
    names = [d.name for d in _space(S1).dims]
    assert not any(n.startswith("loss_") for n in names)
    assert {n for n in names if n.startswith("noise_")} == {
        "noise_bus_front_fwd", "noise_bus_front_lat", "noise_bus_near_fwd", "noise_bus_near_lat"}


def test_a_box_beyond_the_speed_bound_is_refused_at_its_corner():
    spec = load_falsify_file(SPACE).model_copy(deep=True)
    spec.dims[0].high = 3.0  # above estimator.max_pedestrian_speed_mps = 2.5
    with pytest.raises(UserError, match="corner of the search box"):
        _space(S1, spec)


def test_a_step_out_searched_twice_is_refused():
    spec = load_falsify_file(SPACE).model_copy(deep=True)
    spec.dims.append(DimEntry(path="pedestrians.*.steps_onto_crossing_s", name="step_s",
                              low=7.0, high=16.0))
    with pytest.raises(UserError, match="searched by \\[\\[dims\\]\\] too"):
        _space(S3, spec)


@pytest.mark.sumo
def test_every_point_of_the_box_can_happen():
    """The planner times the walk, so no candidate steps out before its walk allows."""
    planner = ActorPlanner()
    space, data = _space(S3), load_scenario_data(S3)
    for unit in np.random.default_rng(3).uniform(size=(12, space.size)):
        values, _, scenario = scenario_of(space, data, unit, str(S3), planner.walk_times)
        assert planner(scenario, str(S3)) is None
        assert values["steps_onto_crossing_s"] >= values["wait_s"]


@pytest.mark.sumo
def test_a_step_out_glob_times_every_pedestrian_so_that_any_zebra_can_be_reached():
    """On the junction each pedestrian waits its own time beyond its walk to the zebra the
    search gives it: at the box's corners (every pedestrian at its own zebra, every one at
    its farthest) and inside, the planner refuses no candidate."""
    planner = ActorPlanner()
    box = ROOT / "sweeps" / "falsify_junction.toml"
    data = load_scenario_data(JUNCTION)
    space = build_space(load_falsify_file(box), data, str(JUNCTION), str(box),
                        planner.crossings)
    everyone = sorted(load_scenario(JUNCTION).pedestrians)
    assert sorted(w.pedestrian for w in space.step_outs) == everyone
    names = [d.name for d in space.dims]
    assert {f"{pid}_wait_s" for pid in everyone} <= set(names)
    units = [np.zeros(space.size), np.ones(space.size),
             *np.random.default_rng(5).uniform(size=(3, space.size))]
    for unit in units:
        values, _, scenario = scenario_of(space, data, unit, str(JUNCTION), planner.walk_times)
        assert planner(scenario, str(JUNCTION)) is None
        for pid in everyone:
            step_out = scenario.pedestrians[pid].steps_onto_crossing_s
            assert values[f"{pid}_steps_onto_crossing_s"] == step_out
            assert step_out >= values[f"{pid}_wait_s"]
    farthest = scenario_of(space, data, np.ones(space.size), str(JUNCTION),
                           planner.walk_times)[2]
    assert farthest.pedestrians["w1"].crossing == space.crossings[0].choices[-1]


def test_a_falsify_file_with_a_bad_field_is_one_line_naming_it(tmp_path: Path):
    bad = tmp_path / "bad.toml"
    bad.write_text('[[dims]]\npath = "x"\nname = "x"\nlow = 2.0\nhigh = 1.0\n')
    with pytest.raises(UserError, match=r"dims\[0\]\.high: must be above low"):
        load_falsify_file(bad)


def _summary(**changes):
    base = {"collisions": 0, "contact_steps": 0, "min_distance_bus_pedestrian_m": 2.5,
            "containment_violations": 0, "violations": [], "route_completed": True,
            "longest_needless_hold_s": 0.5, "travel_time_s": 30.0, "steps": 300,
            "level_share": {"emergency": 0.0},
            "margins": {"moving_distance": {"least_m": 2.5}}}
    return {**base, **changes}


def test_the_objectives_read_their_margins_and_failures():
    distance, emergency, standstill = (OBJECTIVES[n] for n in
                                       ("distance", "emergency", "standstill"))
    assert distance.margin(_summary()) == 2.5
    # the distance while the bus moves, not the least of the run
    assert distance.margin(_summary(min_distance_bus_pedestrian_m=0.4)) == 2.5
    unmet = _summary(margins={"moving_distance": {"least_m": None}})
    assert distance.margin(unmet) == OPEN_DISTANCE_M == emergency.margin(unmet)
    hit = _summary(collisions=1, min_distance_bus_pedestrian_m=0.1, first_collision_t_s=11.9)
    assert distance.margin(hit) == 0.0 and distance.failed(hit)
    assert distance.failed_at(hit) == 11.9
    braking = _summary(level_share={"emergency": 0.01})
    assert emergency.margin(braking) == pytest.approx(-0.3)
    assert emergency.failed(braking) and not emergency.failed(_summary())
    assert standstill.margin(_summary()) == pytest.approx(2.5)
    assert standstill.failed(_summary(longest_needless_hold_s=3.5))
    assert standstill.failed(_summary(route_completed=False))


def test_a_walk_in_into_the_standing_bus_fails_no_objective_and_is_listed():
    distance, emergency, ttc = (OBJECTIVES[n] for n in ("distance", "emergency", "ttc"))
    walk_in = _summary(collisions=1, min_distance_bus_pedestrian_m=0.26, first_collision_t_s=37.4,
                       collisions_moving=0, first_moving_collision_t_s=None,
                       margins={"time_to_collision": {"least_s": 0.0},
                                "moving_distance": {"least_m": 3.1}})
    assert distance.margin(walk_in) == 3.1  # the walker came near only the standing bus
    assert not (distance.failed(walk_in) or emergency.failed(walk_in) or ttc.failed(walk_in))
    assert distance.failed_at(walk_in) is None
    assert broken(walk_in) == ["1 walk-in(s) into the standing bus"]
    # a walk-in, then the bus drives off while in contact: a collision from that step on
    both = {**walk_in, "collisions": 2, "collisions_moving": 1, "first_moving_collision_t_s": 40.1}
    assert distance.margin(both) == 0.0 and distance.failed_at(both) == 40.1
    assert broken(both) == ["1 collision(s)", "1 walk-in(s) into the standing bus"]
    # as the ledger holds them: only a broken promise makes the search exit with status 4
    assert not promises_broken("; ".join(broken(walk_in))) and not promises_broken("")
    assert promises_broken("; ".join(broken(both)))


def test_the_time_to_collision_objective_asks_for_its_margin_and_caps_it():
    ttc = OBJECTIVES["ttc"]
    assert ttc.margins == ("time_to_collision",)
    assert OBJECTIVES["distance"].margins == OBJECTIVES["emergency"].margins == (
        "moving_distance",)
    assert OBJECTIVES["standstill"].margins == ()

    def timed(least, **changes):
        return _summary(margins={"time_to_collision": {"least_s": least}}, **changes)

    assert ttc.margin(timed(2.3)) == 2.3 and not ttc.failed(timed(2.3))
    assert ttc.margin(timed(None)) == OPEN_TTC_S == ttc.margin(timed(40.0))
    hit = timed(0.0, collisions=1, first_collision_t_s=11.9)
    assert ttc.margin(hit) == 0.0 and ttc.failed(hit) and ttc.failed_at(hit) == 11.9
    # the moving bus's: its own margin, the same cap and failure
    moving = OBJECTIVES["moving_ttc"]
    assert moving.margins == ("moving_time_to_collision",)
    both = _summary(margins={"time_to_collision": {"least_s": 0.4},
                             "moving_time_to_collision": {"least_s": 3.2}})
    assert moving.margin(both) == 3.2 and ttc.margin(both) == 0.4
    assert moving.margin(_summary(margins={"moving_time_to_collision": {"least_s": None}})) \
        == OPEN_TTC_S
    assert moving.failed(hit) and moving.margin(hit) == 0.0


def _deep(sets, regions, accounted=0.01, **changes):
    return _summary(margins={"containment_depth": {"sets": {"least_m": sets},
                                                   "regions": {"least_m": regions},
                                                   "accounted": {"least_m": accounted}},
                             "accounted_depth": {"least_m": accounted}},
                    **changes)


def test_the_depth_objective_takes_the_shallower_of_sets_and_regions():
    depth = OBJECTIVES["depth"]
    assert depth.margins == ("containment_depth",)
    # (the accounted area's 0.01 m is the accounted objective's, not this one's)
    assert depth.margin(_deep(1.2, 0.04)) == 0.04 and not depth.failed(_deep(1.2, 0.04))
    assert depth.margin(_deep(None, None)) == OPEN_DEPTH_M  # no set held anyone
    missed = _deep(-0.1, 0.3, containment_violations=1, violations=[{"t": 4.2}])
    assert depth.margin(missed) == -0.1 and depth.failed(missed)
    assert depth.failed_at(missed) == 4.2


def test_the_accounted_objective_takes_the_area_the_controller_accounts_for():
    accounted = OBJECTIVES["accounted"]
    assert accounted.margins == ("accounted_depth",)
    assert accounted.margin(_deep(1.2, 0.04, 0.3)) == 0.3
    assert accounted.margin(_deep(1.2, 0.04, None)) == OPEN_DEPTH_M  # nobody in the window
    lost = _deep(0.5, 0.3, -0.2, containment_violations=1, violations=[{"t": 3.0}])
    assert accounted.margin(lost) == -0.2 and accounted.failed(lost)
    assert accounted.failed_at(lost) == 3.0


def test_the_depth_objective_refuses_anonymous_detections(tmp_path: Path):
    anonymous = tmp_path / "anonymous.toml"
    anonymous.write_text(f'extends = "{S3.as_posix()}"\n[estimator]\nassociation = "anonymous"\n')
    walk_only = tmp_path / "walk.toml"  # no sensor faults: an anonymous run refuses them
    walk_only.write_text('[step_out]\nhigh = 5.0\n[start_behind_truck]\nlow = 1.0\nhigh = 9.0\n')
    with pytest.raises(UserError, match="containment_depth margin needs sets that name"):
        prepare(anonymous, walk_only, "depth", ("cma",), budget=4, seed=1)
    prepare(anonymous, walk_only, "distance", ("cma",), budget=4, seed=1)  # no labelled one
    prepare(anonymous, walk_only, "accounted", ("cma",), budget=4, seed=1)  # no set's name


def test_the_depth_objective_refuses_a_box_that_makes_the_detections_anonymous(tmp_path: Path):
    """The falsify file's [set] is part of every run: the check sees it."""
    box = tmp_path / "anonymous_box.toml"
    box.write_text('[set]\n"estimator.association" = "anonymous"\n'
                   '[step_out]\nhigh = 5.0\n[start_behind_truck]\nlow = 1.0\nhigh = 9.0\n')
    with pytest.raises(UserError, match="containment_depth margin needs sets that name"):
        prepare(S3, box, "depth", ("cma",), budget=4, seed=1)
    prepare(S3, box, "accounted", ("cma",), budget=4, seed=1)


def test_a_collision_after_the_world_broke_an_assumption_is_not_a_broken_promise():
    breaks = {"count": 1, "first": [{"t": 17.2}]}
    before = _summary(collisions=1, first_collision_t_s=11.9, assumption_breaks=breaks)
    after = _summary(collisions=1, first_collision_t_s=18.0, assumption_breaks=breaks,
                     containment_violations=3, violations=[{"t": 17.3}])
    assert first_break_t(before) == 17.2
    assert broken(before) == ["1 collision(s)"]
    assert broken(after) == []
    ground = {"count": 2, "first": [{"t": 5.0}, {"t": 5.1}]}
    assert first_break_t(_summary(assumption_breaks=breaks, ground_breaks=ground)) == 5.0


@pytest.mark.parametrize("method", sorted(SEARCHERS))
def test_a_searcher_from_the_same_seed_told_the_same_margins_proposes_the_same_points(method):
    size = generation_size(5)

    def points(seed: int) -> list[np.ndarray]:
        searcher = SEARCHERS[method](5, seed, size)
        out = []
        for _ in range(3):
            batch = searcher.ask()
            assert batch.shape == (size, 5)
            assert np.all((batch >= 0.0) & (batch <= 1.0))
            searcher.tell(batch, [float(np.sum((p - 0.2) ** 2)) for p in batch])
            out.append(batch)
        return out

    first, again, other = points(7), points(7), points(8)
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not np.array_equal(first[0], other[0])


def test_cma_closes_in_on_a_minimum_that_random_search_only_stumbles_near():
    """The search learns from its margins: on a smooth bowl, CMA-ES's best after 10
    generations is far below random search's with the same budget and seed."""
    dims, size = 6, generation_size(6)
    target = np.full(dims, 0.3)
    best = {}
    for method in ("cma", "random"):
        searcher = SEARCHERS[method](dims, 3, size)
        values = []
        for _ in range(10):
            batch = searcher.ask()
            margins = [float(np.linalg.norm(p - target)) for p in batch]
            searcher.tell(batch, margins)
            values += margins
        best[method] = min(values)
    assert best["cma"] < 0.5 * best["random"]


@pytest.mark.parametrize("box, scenario", [
    ("falsify.toml", S3), ("falsify_pause.toml", S3), ("falsify_turn.toml", S3),
    ("falsify_crowd.toml", CROWD), ("falsify_crossing.toml", TOWN),
    ("falsify_junction.toml", JUNCTION)])
def test_every_committed_box_builds_and_its_corners_are_scenarios(box, scenario):
    """Each falsify file of sweeps/ on the scenario its header names: the box builds (its
    corners validated), and a point decodes into a scenario with the box's fields."""
    path = ROOT / "sweeps" / box
    spec = load_falsify_file(path)
    space = build_space(spec, load_scenario_data(scenario), str(scenario), str(path),
                        ActorPlanner().crossings)
    values, _, decoded = scenario_of(space, load_scenario_data(scenario),
                                     np.full(space.size, 0.5), str(scenario), _walk_7_3_s)
    assert {d.name for d in spec.dims} <= values.keys()
    if box == "falsify_crossing.toml":
        assert [c.pedestrian for c in space.crossings] == ["pedestrian"]
        assert len(space.crossings[0].choices) == 8
    if box == "falsify_turn.toml":
        ped = decoded.pedestrians["pedestrian"]
        assert ped.turn_back_after_s == 3.0 and ped.turn_back_wait_s == 4.0


LEDGER_HEAD = "method,evaluation,generation,key,margin,failed,failed_outside,first_break_t," \
              "broken,not_feasible,error"


def test_a_ledger_gives_its_runs_outcomes_and_only_to_the_same_search(tmp_path: Path):
    setup = prepare(S3, SPACE, "distance", ("cma",), budget=2, seed=1)
    plan = plan_document(setup, "test", tmp_path)
    write_json_atomic(tmp_path / FALSIFY_PLAN, plan)
    write_text_atomic(
        tmp_path / EVALUATIONS, LEDGER_HEAD + ",route_unfinished\n"
        + "cma,0,0,k0,2.5,False,False,,,,,False\n"
        + "cma,1,0,k1,0.0,True,False,12.5,1 collision(s); 2 containment violation(s),,,True\n"
        + "cma,2,0,k2,,False,False,,,cannot reach the zebra,,\n"
        + "cma,3,0,k3,,False,False,,,,run failed: boom,\n")
    assert recorded_outcomes(tmp_path, plan) == {
        "k0": Recorded(2.5, False, False, None, (), unfinished=False),
        "k1": Recorded(0.0, True, False, 12.5,
                       ("1 collision(s)", "2 containment violation(s)"), unfinished=True)}
    assert recorded_outcomes(tmp_path, {**plan, "objective": "ttc"}) == {}
    assert recorded_outcomes(tmp_path, {**plan, "scenario_sha256": "0" * 64}) == {}
    write_text_atomic(tmp_path / EVALUATIONS, LEDGER_HEAD + "\ncma,0,0,k0,2.5,False,False,,,,\n")
    assert recorded_outcomes(tmp_path, plan) == {  # a ledger from before the column
        "k0": Recorded(2.5, False, False, None, (), unfinished=None)}


def test_resuming_a_search_that_other_code_made_is_refused(tmp_path: Path):
    setup = prepare(S3, SPACE, "distance", ("cma",), budget=2, seed=1)
    plan = plan_document(setup, "test", tmp_path)
    assert plan[CODE_FIELD] == code_digest() and len(plan[CODE_FIELD]) == 64
    check_same_code(tmp_path, plan)  # nothing to resume: nothing to refuse
    write_json_atomic(tmp_path / FALSIFY_PLAN, plan)
    check_same_code(tmp_path, plan)  # the same code
    write_json_atomic(tmp_path / FALSIFY_PLAN, {**plan, CODE_FIELD: "0" * 64})
    with pytest.raises(UserError, match=r"code_sha256.*other code than this checkout"):
        check_same_code(tmp_path, plan)
    write_json_atomic(tmp_path / FALSIFY_PLAN, {k: v for k, v in plan.items() if k != CODE_FIELD})
    with pytest.raises(UserError, match=r"code_sha256.*code it does not name"):
        check_same_code(tmp_path, plan)


def test_resuming_a_longer_search_with_a_smaller_budget_is_refused(tmp_path: Path):
    setup = prepare(S3, SPACE, "distance", ("cma",), budget=2, seed=1)
    plan = plan_document(setup, "test", tmp_path)
    write_json_atomic(tmp_path / FALSIFY_PLAN, plan)
    write_text_atomic(tmp_path / EVALUATIONS, LEDGER_HEAD + "\ncma,40,3,k40,2.5,False,False,,,,\n")
    with pytest.raises(UserError, match=r"records 4 generations.*--budget 2"):
        recorded_outcomes(tmp_path, plan)


def _search_with_one_evaluation(folder: Path, walk_mps: float | None = None):
    """S3's search (distance, seed 1) whose ledger in ``folder`` holds cma's evaluation 5:
    the setup, and the overrides that evaluation ran with (its walk timed at 6.1 s)."""
    setup = prepare(S3, SPACE, "distance", ("cma",), budget=2, seed=1)
    write_json_atomic(folder / FALSIFY_PLAN, plan_document(setup, "test", folder))
    values, overrides, _ = scenario_of(setup.space, setup.data, np.full(setup.space.size, 0.3),
                                       str(S3), lambda scenario, source: {"pedestrian": 6.1})
    row = {"method": "cma", "evaluation": 4, "generation": 0,
           "key": evaluation_key(setup, "cma", 4, overrides), **values, "margin": 3.25,
           "failed": False, "failed_outside": False, "first_break_t": None, "broken": "",
           "not_feasible": None, "error": None}
    if walk_mps is not None:
        row["walk_mps"] = walk_mps
    pd.DataFrame([row]).to_csv(folder / EVALUATIONS, index=False)
    return setup, overrides


def test_an_evaluation_of_the_ledger_becomes_the_scenario_file_of_its_run(tmp_path: Path):
    setup, overrides = _search_with_one_evaluation(tmp_path)
    case = write_case(setup, tmp_path, "cma", 5)
    assert case == tmp_path / "case_cma_5.toml"
    assert "cma's evaluation 5 (distance margin 3.250 m)" in case.read_text()
    ran = validate_scenario(apply_overrides(setup.data, overrides, str(S3)), str(S3))
    assert overrides["pedestrians.pedestrian.steps_onto_crossing_s"] == round(
        6.1 + 0.3 * 10.0, 6)  # the step-out as recorded, not timed again
    assert load_scenario(case).model_dump(exclude={"description"}) == ran.model_dump(
        exclude={"description"})


def test_a_case_the_ledger_does_not_hold_or_ran_otherwise_is_refused(tmp_path: Path):
    setup, _ = _search_with_one_evaluation(tmp_path)
    with pytest.raises(UserError, match=r"--case.*no evaluation 6 of cma.*from 1 to 1"):
        write_case(setup, tmp_path, "cma", 6)
    with pytest.raises(UserError, match=r"--case.*no evaluation 1 of random.*\(cma\)"):
        write_case(setup, tmp_path, "random", 1)
    other = prepare(S3, SPACE, "ttc", ("cma",), budget=2, seed=1)
    with pytest.raises(UserError, match=r"falsify.json: objective: is another search's"):
        write_case(other, tmp_path, "cma", 5)
    with pytest.raises(UserError, match=r"no search's ledger is here"):
        write_case(setup, tmp_path / "elsewhere", "cma", 5)
    setup, _ = _search_with_one_evaluation(tmp_path, walk_mps=1.234567)  # not what it ran
    with pytest.raises(UserError, match=r"evaluations.csv.gz: key: cma's evaluation 5 ran with"):
        write_case(setup, tmp_path, "cma", 5)
    assert not list(tmp_path.glob("case_*.toml"))


@pytest.mark.parametrize("case", ["cma:0", "cma", "annealing:3", "cma:x"])
def test_a_case_that_is_not_method_and_number_is_one_line(case, capsys):
    with pytest.raises(SystemExit) as stop:
        main(["falsify", str(S3), "--case", case])
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"'{case}' is not METHOD:N" in err


def test_the_progress_line_tells_the_pace_of_the_runs_that_were_made(monkeypatch):
    """A resumed search's recorded generations take no time, and one that ran again only a
    failed run took that run's time: the time left is the pace of the runs made times the
    runs still to come (30 a generation)."""
    from sse_cosim.cli import falsify_commands

    clock = iter([0.0, 0.5, 2.5, 62.5, 182.5, 182.5])  # start, recorded, 1 run, 60 s, 120 s
    monkeypatch.setattr(falsify_commands.time, "monotonic", lambda: next(clock))
    pace = falsify_commands._Pace(30)
    assert pace.lap(0, 5) == "recorded"
    assert pace.lap(1, 4) == "1 run(s) in 00:02, about 04:00 left"  # 2 s a run
    assert pace.lap(30, 3) == "30 run(s) in 01:00, about 03:00 left"
    assert pace.lap(30, 2) == "30 run(s) in 02:00, about 02:59 left"  # 182 s for 61 runs
    assert pace.lap(30, 0) == "30 run(s) in 00:00"


def test_a_ledger_an_older_version_wrote_plain_is_refused_not_started_over(tmp_path: Path):
    setup = prepare(S3, SPACE, "distance", ("cma",), budget=2, seed=1)
    plan = plan_document(setup, "test", tmp_path)
    write_json_atomic(tmp_path / FALSIFY_PLAN, plan)
    (tmp_path / "evaluations.csv").write_text(LEDGER_HEAD + "\ncma,0,0,k0,2.5,False,False,,,,\n")
    with pytest.raises(UserError, match=r"evaluations.csv: .*older sse-cosim.*gzip"):
        recorded_outcomes(tmp_path, plan)
