"""Sweep parameters: value syntax, path patterns, planning and sweep files (no SUMO)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from sse_cosim.errors import UserError
from sse_cosim.reporting.sweep_report import parameter_scalar, summary_figures
from sse_cosim.runner.sweep import (
    SEED_PATH,
    Parameter,
    SweepSpec,
    combine,
    expand_pattern,
    linspace_values,
    load_sweep_file,
    parse_parameter,
    parse_seeds,
    parse_values,
    plan_sweep,
)
from sse_cosim.scenario.loader import load_scenario

ROOT = Path(__file__).resolve().parents[2]
S2 = ROOT / "scenarios" / "s2_pedestrian.toml"
S3 = ROOT / "scenarios" / "s3_pedestrian.toml"
NOISE = "sensors.*[node!=bus].noise_bound_m"


def fields(path: Path) -> dict:
    return load_scenario(path).model_dump(mode="json")


@pytest.mark.parametrize(("text", "values"), [
    ("[1, 2, 3]", [1, 2, 3]),
    ("[[0.25,0.25],[0.5,0.5]]", [[0.25, 0.25], [0.5, 0.5]]),
    ('["volume", "trace"]', ["volume", "trace"]),
    ("range(0,5)", [0, 1, 2, 3, 4]),
    ("range(1, 10, 4)", [1, 5, 9]),
    ("linspace(0,4,5)", [0, 1, 2, 3, 4]),
    ("linspace(0.2, 2.0, 4)", [0.2, 0.8, 1.4, 2.0]),
    ("linspace(1, 2, 3)", [1.0, 1.5, 2.0]),
    ("linspace(3, 3, 1)", [3]),
])
def test_values_are_lists_or_ranges(text, values):
    assert parse_values(text, "--param") == values


@pytest.mark.parametrize("text", ["0.5", "[]", "range(0.5, 2)", "linspace(0, 1)",
                                  "range(5, 0)", "linspace(0, 1, 0)", "[1, oops]"])
def test_bad_values_name_the_option_and_the_fix(text):
    with pytest.raises(UserError, match=r"^command line: --param: '.*' .* -- "):
        parse_values(text, "--param")


def test_linspace_rounds_away_float_noise():
    assert linspace_values(0.1, 0.3, 3) == [0.1, 0.2, 0.3]


def test_parameter_splits_at_the_first_equals_sign_outside_brackets():
    param = parse_parameter(f"{NOISE}=[[1,1],[2,2]]")
    assert param == Parameter(NOISE, ([1, 1], [2, 2]))
    assert param.column == NOISE
    with pytest.raises(UserError, match="is not PATH=VALUES"):
        parse_parameter("v2x.latency_steps")


def test_seeds_are_whole_numbers():
    assert parse_seeds("range(1,4)") == (1, 2, 3)
    with pytest.raises(UserError, match="seeds are whole numbers"):
        parse_seeds("[1.5]")


@pytest.mark.parametrize(("scenario", "pattern", "paths"), [
    (S3, "sensors.*_cam.noise_bound_m",
     ["sensors.rsu1_cam.noise_bound_m", "sensors.rsu2_cam.noise_bound_m"]),
    (S3, "sensors.*[node=rsu*].noise_bound_m",
     ["sensors.rsu1_cam.noise_bound_m", "sensors.rsu2_cam.noise_bound_m"]),
    (S3, NOISE, ["sensors.rsu1_cam.noise_bound_m", "sensors.rsu2_cam.noise_bound_m"]),
    (S2, NOISE, ["sensors.car_front.noise_bound_m"]),
    (S2, "sensors.*.noise_bound_m",
     ["sensors.bus_front.noise_bound_m", "sensors.bus_near.noise_bound_m",
      "sensors.car_front.noise_bound_m"]),
    (S2, "controller.*_factor",
     ["controller.cautious_factor", "controller.slow_factor", "controller.very_slow_factor"]),
    (S2, "v2x.latency_steps", ["v2x.latency_steps"]),
])
def test_patterns_expand_against_the_scenarios_keys(scenario, pattern, paths):
    assert [path for path, _ in expand_pattern(pattern, fields(scenario), "test")] == paths


def test_a_pattern_that_matches_nothing_names_the_part_and_what_is_there():
    with pytest.raises(UserError) as error:
        expand_pattern("sensors.*_cam.noise_bound_m", fields(S2), "s2.toml")
    assert str(error.value).startswith("s2.toml: sensors.*_cam.noise_bound_m: '*_cam' "
                                       "matches nothing in sensors (it has: bus_front, bus_near, "
                                       "car_front)")


def test_a_plan_crosses_scenarios_values_and_seeds_in_a_fixed_order():
    spec = SweepSpec((S2, S3), (Parameter(NOISE, ([0.5, 0.5], [1.0, 1.0], [2.0, 2.0])),),
                     seeds=(1, 2), fixed={"simulation.duration_s": 3.0})
    runs = plan_sweep(spec)
    assert len(runs) == 12
    assert [(Path(r.scenario).stem, r.values[NOISE], r.seed) for r in runs[:3]] == [
        ("s2_pedestrian", [0.5, 0.5], 1), ("s2_pedestrian", [0.5, 0.5], 2),
        ("s2_pedestrian", [1.0, 1.0], 1)]
    assert runs[6].overrides == {
        "simulation.duration_s": 3.0, "sensors.rsu1_cam.noise_bound_m": [0.5, 0.5],
        "sensors.rsu2_cam.noise_bound_m": [0.5, 0.5], SEED_PATH: 1}
    assert all(r.error is None for r in runs)
    assert [r.key for r in plan_sweep(spec)] == [r.key for r in runs]  # deterministic
    assert len({r.key for r in runs}) == 12
    assert runs[0].key.startswith("s2_pedestrian__noise_bound_m=0.5x0.5__seed1__")
    assert all(re.fullmatch(r"[A-Za-z0-9._=+-]+", r.key) for r in runs)


def test_keys_depend_on_the_run_only():
    one = plan_sweep(SweepSpec((S2,), (Parameter("v2x.latency_steps", (1, 2), "lat"),)))
    two = plan_sweep(SweepSpec((S2,), (Parameter("v2x.latency_steps", (2, 3)),)))
    assert one[1].key == two[0].key
    assert one[0].seed == 1  # the scenario's own seed when no seeds are given


def test_an_invalid_value_becomes_a_failed_run_not_an_error():
    runs = plan_sweep(SweepSpec((S2,), (Parameter(NOISE, ([-1.0, -1.0], [1.0, 1.0])),)))
    assert "sensors.car_front.noise_bound_m.0: Input should be greater than 0" in runs[0].error
    assert runs[1].error is None


@pytest.mark.parametrize(("parameter", "message"), [
    (Parameter("sensors.nope.noise_bound_m", ([1, 1],)), "'nope' matches nothing in sensors"),
    (Parameter("v2x.latency", (1,)), "'latency' matches nothing in v2x"),
    (Parameter("sensors.bus_front.noise_bound_m", (0.5,)),
     r"holds a list, got 0.5 -- each value of a list field is a list"),
    (Parameter("v2x.latency_steps", ([1, 2],)), "holds a single value"),
    (Parameter("sensors.bus_front", ({},)), "is a table, not a field"),
    (Parameter("v2x..range_m", (1,)), "is not a dotted path"),
])
def test_bad_paths_and_shapes_stop_the_sweep_before_it_runs(parameter, message):
    with pytest.raises(UserError, match=message):
        plan_sweep(SweepSpec((S2,), (parameter,)))


def test_two_sources_may_not_set_one_field():
    with pytest.raises(UserError, match=re.escape("sets sensors.car_front.noise_bound_m, which")):
        plan_sweep(SweepSpec((S2,), (Parameter(NOISE, ([1, 1],)),
                                     Parameter("sensors.car_front.noise_bound_m", ([2, 2],)))))
    with pytest.raises(UserError, match=re.escape("seeds: sets simulation.seed, which simulation")):
        plan_sweep(SweepSpec((S2,), (Parameter(SEED_PATH, (1, 2)),), seeds=(1,)))
    with pytest.raises(UserError, match="identical"):
        plan_sweep(SweepSpec((S2,), (Parameter("v2x.latency_steps", (1, 1)),)))


def test_the_example_sweep_file_loads():
    spec = load_sweep_file(ROOT / "sweeps" / "noise.toml")
    assert [p.stem for p in spec.scenarios] == ["s2_pedestrian", "s3_pedestrian"]
    assert spec.parameters[0].column == "shared_noise_bound_m"
    assert len(plan_sweep(spec)) == 16


@pytest.mark.parametrize(("text", "message"), [
    ('scenarios = ["x.toml"]\n[[params]]\npath = "v2x.latency_steps"\n',
     "params[0]: give values = [...] or all of start, stop and num"),
    ('scenarios = ["x.toml"]\nseed = [1]\n', "seed: Extra inputs are not permitted"),
    ('scenarios = ["x.toml"]\nseeds = [-1]\n', "seeds[0]: Input should be greater than"),
    ('scenarios = []\n', "scenarios: List should have at least 1 item"),
    ('scenarios = ["x.toml"\n', "syntax"),
])
def test_sweep_file_errors_name_the_file_and_field(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(UserError, match=re.escape(f"{path}: {message}")):
        load_sweep_file(path)


def test_sweep_file_ranges_and_command_line_additions(tmp_path):
    path = tmp_path / "lat.toml"
    path.write_text(f'scenarios = ["{S2}"]\nseeds = [3]\n[set]\n"simulation.duration_s" = 3.0\n'
                    '[[params]]\npath = "v2x.latency_steps"\nstart = 0\nstop = 4\nnum = 3\n')
    spec = load_sweep_file(path)
    assert spec.parameters == (Parameter("v2x.latency_steps", (0, 2, 4)),)
    both = combine(spec, parameters=[Parameter("v2x.latency_steps", (7,))], seeds=(1, 2),
                   fixed={"v2x.range_m": 100.0})
    assert both.parameters == (Parameter("v2x.latency_steps", (7,)),)
    assert both.seeds == (1, 2)
    assert both.fixed == {"simulation.duration_s": 3.0, "v2x.range_m": 100.0}
    with pytest.raises(UserError, match="no scenario to sweep"):
        combine(None)


def test_summaries_flatten_into_table_figures():
    row = summary_figures({
        "average_speed_mps": 16.5, "first_detection": {"fused": {
            "t": 3.4, "bus_distance_to_crossing_m": 130.0}},
        "set_area_m2": {"fused": {"mean": 313.1, "max": 1656.5},
                        "possible": {"mean": 40.2, "max": 96.0}},
        "level_share": {"nominal": 0.75, "very slow": 0.25},
    })
    assert row["first_detection_fused_bus_to_crossing_m"] == 130.0
    assert row["fused_area_max_m2"] == 1656.5
    assert row["refined_area_mean_m2"] == 40.2 and row["refined_area_max_m2"] == 96.0
    assert row["level_share_very_slow"] == 0.25
    assert row["collisions"] is None
    assert set(summary_figures(None)) <= set(row)


def test_list_values_sit_at_their_largest_component():
    assert parameter_scalar([0.5, 2.0]) == 2.0
    assert parameter_scalar([-3, 1]) == 3.0
    assert parameter_scalar(4) == 4.0
    assert parameter_scalar("volume") is None
