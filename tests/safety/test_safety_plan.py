"""Safety campaign planning: the campaign file, the grid, the feasibility filter (no SUMO run;
the real demand planner reads the road network, built once in about a second)."""

from __future__ import annotations

from pathlib import Path

import pytest
from safety_helpers import (
    BEHIND,
    NOISE,
    PARAMS,
    campaign_file,
    everything_feasible,
    slow_walkers_cannot,
)

from sse_cosim.cli.safety_commands import safety as safety_cli
from sse_cosim.errors import UserError
from sse_cosim.runner.safety import (
    START_PATH,
    TRUCK_FRONT_PATH,
    ActorPlanner,
    load_campaign,
    plan_campaign,
)
from sse_cosim.runner.sweep import SEED_PATH, run_key

ROOT = Path(__file__).resolve().parents[2]
DEFAULT = ROOT / "sweeps" / "safety.toml"
def test_the_grid_varies_what_applies_to_each_scenario(tmp_path):
    plan = plan_campaign(load_campaign(campaign_file(tmp_path)), everything_feasible)
    s1 = [r for r in plan.runs if Path(r.scenario).stem == "s1_pedestrian"]
    s2 = [r for r in plan.runs if Path(r.scenario).stem == "s2_pedestrian"]
    # S1 has no sensor off the bus: its noise axis is not varied.
    assert len(s1) == 2 * 2 * 2 * 2 * 2 and len(s2) == len(s1) * 2
    assert not plan.not_feasible
    assert all("noise_m" not in r.values for r in s1)
    assert {tuple(r.values["noise_m"]) for r in s2} == {(0.5, 0.5), (1.5, 1.5)}
    assert all(r.overrides["sensors.car_front.noise_bound_m"] == r.values["noise_m"]
               for r in s2)
    # plan order: scenario, then the axes in file order, the start offset, the seed
    first = s2[:4]
    assert [(r.values["behind_m"], r.seed) for r in first] == [(1.0, 1), (1.0, 2),
                                                                (5.0, 1), (5.0, 2)]
    assert [r.values["step_s"] for r in s2] == sorted(r.values["step_s"] for r in s2)


def test_the_start_follows_the_truck_and_keys_follow_the_sweeps_scheme(tmp_path):
    plan = plan_campaign(load_campaign(campaign_file(tmp_path)), everything_feasible)
    for run in plan.runs:
        overrides = run.overrides
        assert overrides[START_PATH] == overrides[TRUCK_FRONT_PATH] - run.values["behind_m"]
        assert overrides[SEED_PATH] == run.seed
        stem = Path(run.scenario).stem
        assert run.key == run_key(stem, list(run.values.items()), run.seed, overrides)
    assert len({r.key for r in plan.runs}) == len(plan.runs)
    key = plan.runs[0].key
    assert key.startswith("s1_pedestrian__step_s=8__walk_mps=1__truck_m=186__behind_m=1__seed1__")


def test_the_filter_leaves_out_what_the_planner_refuses(tmp_path):
    plan = plan_campaign(load_campaign(campaign_file(tmp_path)), slow_walkers_cannot)
    assert all(r.values["walk_mps"] == 2.5 for r in plan.runs)
    assert {n.run.values["walk_mps"] for n in plan.not_feasible} == {1.0}
    assert len(plan.runs) == len(plan.not_feasible) == 48
    assert plan.not_feasible[0].reason == "too slow (1 m/s)"


def test_the_real_planner_refuses_a_pedestrian_that_cannot_reach_the_zebra(tmp_path):
    """Truck front 186 m, 5 m behind it: 19.8 m to walk; at 1 m/s neither 8 s nor 12 s can
    be made, at 2.5 m/s both can. Truck front 192 m, 1 m behind it, 1 m/s: 9.8 m, so 12 s
    can be made and 8 s cannot."""
    plan = plan_campaign(load_campaign(campaign_file(tmp_path, scenarios=("s2",))),
                         ActorPlanner())
    refused = {(n.run.values["truck_m"], n.run.values["behind_m"], n.run.values["walk_mps"],
                n.run.values["step_s"]) for n in plan.not_feasible}
    assert (186.0, 5.0, 1.0, 8.0) in refused and (186.0, 5.0, 1.0, 12.0) in refused
    assert (192.0, 1.0, 1.0, 8.0) in refused and (192.0, 1.0, 1.0, 12.0) not in refused
    assert not any(walk == 2.5 for _, _, walk, _ in refused)
    assert all("cannot be reached" in n.reason for n in plan.not_feasible)


def test_other_refusals_of_the_planner_stop_the_campaign(tmp_path):
    params = PARAMS.replace("values = [186.0, 192.0]", "values = [186.0, 400.0]")
    with pytest.raises(UserError, match=r"parked.truck.end_pos_m: 400 m does not fit"):
        plan_campaign(load_campaign(campaign_file(tmp_path, params=params)), ActorPlanner())


def test_the_default_campaign_has_at_least_1000_feasible_runs():
    plan = plan_campaign(load_campaign(DEFAULT))
    # S1-S3: 1,095 and 825; crowd: 438 and 330; junction: 114 and 78; town: 270 and 114
    assert len(plan.runs) == 1917 and len(plan.not_feasible) == 1347
    assert {Path(r.scenario).stem for r in plan.runs} == {
        *(f"s{i}_pedestrian" for i in (1, 2, 3)), "crowd", "junction", "town"}
    speeds = {r.values["walk_mps"] for r in plan.runs}
    assert max(speeds) == 2.5  # the estimator's bound
    # `sse-cosim safety --help` tells the user the same count
    assert f"({len(plan.runs):,} runs with sweeps/safety.toml" in " ".join(
        safety_cli.help.split())


def test_a_scenario_without_a_truck_keeps_its_pedestrians_start():
    runs = plan_campaign(load_campaign(DEFAULT, only=("junction",))).runs  # no truck axis
    assert runs and all("behind_m" not in r.values and "truck_m" not in r.values
                        and START_PATH not in r.overrides for r in runs)
    at_the_bound = {r.values["step_s"] for r in runs if r.values["walk_mps"] == 2.5}
    assert at_the_bound == {7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0}


def test_a_campaign_can_be_limited_to_some_of_its_scenarios():
    plan = plan_campaign(load_campaign(DEFAULT, only=("s1_pedestrian", "s3_pedestrian")))
    assert {Path(r.scenario).stem for r in plan.runs} == {"s1_pedestrian", "s3_pedestrian"}
    with pytest.raises(UserError, match=r"^--scenario: s4: is not a scenario of .*safety.toml "
                                        r"-- choose from s1_pedestrian, .*crowd, junction, town$"):
        load_campaign(DEFAULT, only=("s4",))


def test_quick_keeps_a_few_runs_of_the_grid():
    plan = plan_campaign(load_campaign(DEFAULT, quick=True))
    assert len(plan.runs) == 2 and len(plan.not_feasible) == 2
    assert {Path(r.scenario).stem for r in plan.runs} == {"s3_pedestrian"}


def test_quick_must_pick_values_of_the_grid(tmp_path):
    quick = '[quick]\nseeds = [1]\nvalues = { walk_mps = [2.5], step_s = [12.0] }\n'
    campaign = load_campaign(campaign_file(tmp_path, behind=BEHIND + quick), quick=True)
    assert campaign.seeds == (1,)
    assert [p.values for p in campaign.parameters[:2]] == [(12.0,), (2.5,)]
    bad = '[quick]\nvalues = { walk_mps = [3.0] }\n'
    with pytest.raises(UserError, match=r"quick: walk_mps: 3.0 is not among"):
        load_campaign(campaign_file(tmp_path, behind=BEHIND + bad), quick=True)
    unknown = '[quick]\nvalues = { speed = [1.0] }\n'
    with pytest.raises(UserError, match=r"values.speed: is not an axis"):
        load_campaign(campaign_file(tmp_path, behind=BEHIND + unknown), quick=True)


@pytest.mark.parametrize(("params", "extra", "message"), [
    (PARAMS.replace('"pedestrians.pedestrian.walking_speed_mps"',
                    '"pedestrians.pedestrian.radius_m"'), "",
     r"params: add a parameter with path = 'pedestrians.pedestrian.walking_speed_mps'"),
    (PARAMS.replace(NOISE, "sensors.*[node=rsu*].noise_bound_m"), "",
     r"matches nothing"),
    (PARAMS, '[set]\n"pedestrians.pedestrian.start_pos_m" = 180.0\n',
     r"sets pedestrians.pedestrian.start_pos_m, which start_behind_truck sets too"),
    (PARAMS.replace("values = [1.0, 2.5]", "values = [-1.0, 2.5]"), "",
     r"pedestrians.pedestrian.walking_speed_mps"),
])
def test_a_bad_grid_stops_before_any_run(tmp_path, params, extra, message):
    with pytest.raises(UserError, match=message):
        plan_campaign(load_campaign(campaign_file(tmp_path, params=params, extra=extra)),
                      everything_feasible)


def test_the_default_campaign_covers_the_grid_of_the_brief():
    campaign = load_campaign(DEFAULT)
    axes = {p.pattern: p.values for p in campaign.axes}
    assert axes["pedestrians.pedestrian.walking_speed_mps"] == (1.0, 1.5, 2.0, 2.5)
    step_out = axes["pedestrians.pedestrian.steps_onto_crossing_s"]
    assert {7.0, 8.0, 9.0, 10.0, 11.0, 12.0} <= set(step_out)
    assert axes[NOISE] == ([0.5, 0.5], [1.5, 1.5])
    assert campaign.behind_truck.values == (1.0, 5.0)
