"""``--set PATH=VALUE``: the patterns of ``sweep --param``, and errors that name the option."""

from __future__ import annotations

from pathlib import Path

from sse_cosim.runner.parameters import load_with_assignments, parse_assignment

S3 = Path(__file__).resolve().parents[2] / "scenarios" / "s3_pedestrian.toml"


def test_set_expands_globs_and_filters_as_sweep_param_does():
    scenario, owners = load_with_assignments(
        S3, ["sensors.*[node!=bus].noise_bound_m=[1.0, 1.0]", "sensors.*.noise=worst-case"])
    shared = {name for name, sensor in scenario.sensors.items() if sensor.node != "bus"}
    assert shared
    for name, sensor in scenario.sensors.items():
        assert (list(sensor.noise_bound_m) == [1.0, 1.0]) == (name in shared), name
        assert sensor.noise == "worst-case"
        assert owners[f"sensors.{name}.noise"] == "--set sensors.*.noise=worst-case"


def test_a_plain_path_may_still_add_a_table():
    """``--set faults.sensor.f.kind=...`` adds a fault the file does not have (docs/faults.md)."""
    scenario, owners = load_with_assignments(S3, [
        "faults.sensor.f.sensor=bus_front", "faults.sensor.f.kind=bias",
        "faults.sensor.f.bias_m=[3.0, 0.0]", "faults.sensor.f.within_bound=true"])
    assert scenario.faults.sensor["f"].kind == "bias"
    assert owners["faults.sensor.f.kind"] == "--set faults.sensor.f.kind=bias"


def test_a_filter_value_may_hold_an_equals_sign():
    assert parse_assignment("sensors.*[node!=bus].range_m=40", "--set") == (
        "sensors.*[node!=bus].range_m", 40)
