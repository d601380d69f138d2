"""The fault scenarios in real SUMO, each cut shortly after its fault (runs of a few seconds).

Beyond-the-bounds faults are flagged within 3 steps and the fused set holds the pedestrian
from the flag on; faults within the bounds raise no flag and cost no containment.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from sse_cosim.reporting.recorder import RunRecorder
from sse_cosim.runner.simulation import simulate
from sse_cosim.scenario.loader import load_scenario

FAULTS = Path(__file__).resolve().parents[2] / "scenarios" / "faults"
KINDS = {("sensor", "bias"), ("sensor", "stuck"), ("sensor", "dropout"), ("sensor", "phantom"),
         ("node", "shift"), ("node", "shrink"), ("link", "loss"), ("link", "latency")}
# scenario file -> simulated seconds (a little past the fault and its detection)
RUNS = {
    "s3_bias_rsu1_second_camera": 6.5,
    "s1_bias_bus": 12.5,
    "s3_phantom_rsu1": 4.0,
    "s3_shift_rsu2": 7.5,
    "s3_stuck_rsu1": 10.5,
}
HARMLESS = {  # every fault that stays within the bounds, together in one S3 run
    "faults.sensor.rsu2_dropout.sensor": "rsu2_cam", "faults.sensor.rsu2_dropout.kind": "dropout",
    "faults.sensor.rsu2_dropout.start_s": 4.0,
    "faults.link.burst.node": "rsu1", "faults.link.burst.kind": "loss",
    "faults.link.burst.start_s": 4.0, "faults.link.burst.end_s": 5.0,
    "faults.link.late.node": "rsu2", "faults.link.late.kind": "latency",
    "faults.link.late.start_s": 5.5, "faults.link.late.end_s": 7.0,
    "simulation.duration_s": 8.0,
}


def test_every_fault_kind_has_a_scenario_that_loads():
    found = set()
    for path in sorted(FAULTS.glob("[!_]*.toml")):
        scenario = load_scenario(path)
        for table in ("sensor", "node", "link"):
            found |= {(table, f.kind) for f in getattr(scenario.faults, table).values()}
    assert found == KINDS


def run(path: Path, tmp: Path, overrides: dict) -> dict:
    scenario = load_scenario(path, overrides)
    recorder = RunRecorder(scenario)
    simulate(scenario, tmp / path.stem, path.stem, recorder, on_start=recorder.start)
    return recorder.summary()


@pytest.fixture(scope="module")
def summaries(tmp_path_factory) -> dict[str, dict]:
    tmp = tmp_path_factory.mktemp("faults")
    result = {name: run(FAULTS / f"{name}.toml", tmp, {"simulation.duration_s": seconds})
              for name, seconds in RUNS.items()}
    result["harmless"] = run(FAULTS / "s3_bias_within_bound.toml", tmp, HARMLESS)
    return result


def fused_violations_after(summary: dict, t: float) -> list:
    return [v for v in summary["violations"] if v["node"] in ("fused", "possible") and v["t"] >= t]


@pytest.mark.sumo
@pytest.mark.parametrize("name", ["s3_bias_rsu1_second_camera", "s1_bias_bus", "s3_phantom_rsu1",
                                  "s3_shift_rsu2"])
def test_a_fault_beyond_the_bounds_is_flagged_within_three_steps(summaries, name):
    (fault,) = summaries[name]["faults"]
    assert fault["first_beyond_bounds_step"] == fault["first_active_step"], fault
    assert fault["detection_delay_steps"] <= 3, fault
    assert fault["fused_violations_after_detection"] == 0, fault
    assert summaries[name]["inconsistent_steps"] > 0  # the controller fell back


@pytest.mark.sumo
def test_fig4_second_camera_keeps_the_node_itself_sound(summaries):
    summary = summaries["s3_bias_rsu1_second_camera"]
    assert summary["containment_violations"] == 0
    assert summary["flag_counts"] == {"rsu1_cam: left out": summary["faults"][0]["flagged_steps"]}


@pytest.mark.sumo
def test_the_bus_near_field_sensor_outvotes_its_biased_front_camera(summaries):
    summary = summaries["s1_bias_bus"]
    assert summary["containment_violations"] == 0
    assert summary["flag_counts"]["bus_front: left out"] == summary["faults"][0]["flagged_steps"]


@pytest.mark.sumo
def test_a_stuck_camera_is_caught_at_the_bus_and_left_out(summaries):
    summary = summaries["s3_stuck_rsu1"]
    (fault,) = summary["faults"]
    assert fault["detected_step"] is not None
    assert fault["first_beyond_bounds_step"] > fault["first_active_step"]  # it drifts out
    assert fault["fused_violations_after_detection"] == 0
    assert set(summary["containment_violations_by_set"]) <= {"rsu1", "fused", "possible",
                                                              "unaccounted"}


@pytest.mark.sumo
def test_faults_within_the_bounds_raise_no_flag_and_cost_no_containment(summaries):
    summary = summaries["harmless"]
    assert summary["containment_violations"] == 0
    assert summary["flag_counts"] == {} and summary["inconsistent_steps"] == 0
    faults = {f["fault"]: f for f in summary["faults"]}
    assert faults["sensor.rsu1_small_bias"]["first_beyond_bounds_step"] is None
    assert faults["sensor.rsu1_small_bias"]["detected_step"] is None
    assert faults["sensor.rsu2_dropout"]["detected_step"] is None
    for link in ("link.burst", "link.late"):  # noticed as stale messages, not as a fault
        assert faults[link]["detection_delay_steps"] <= 3, faults[link]
