"""Faults within the estimator's bounds with anonymous detections: they need no screening per
person id, so a scenario with anonymous tracks keeps them (the falsifier's noise and loss
boxes in anonymous mode), and S3 stays sound and safe under all three kinds at once, with the
accounted depth the falsifier drives down measured."""

from __future__ import annotations

from pathlib import Path

import pytest
from anonymous_checks import assert_sound_in_every_set_kind

from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo
S3 = Path(__file__).resolve().parents[2] / "scenarios" / "s3_pedestrian.toml"

WITHIN_BOUNDS = {
    "estimator.association": "anonymous",
    # the bus camera's every error on its bound's corner, from the start to the zebra
    "faults.sensor.b": {"sensor": "bus_front", "kind": "bias", "bias_m": [1.0, -1.0],
                        "within_bound": True},
    "faults.sensor.d": {"sensor": "rsu2_cam", "kind": "dropout", "start_s": 4.0,
                        "end_s": 9.0},
    "faults.link.l": {"node": "rsu1", "kind": "loss", "start_s": 6.0, "end_s": 10.0},
}


def test_s3_with_anonymous_tracks_is_sound_under_faults_within_the_bounds(tmp_path):
    summary = run_scenario_file(S3, tmp_path, WITHIN_BOUNDS, plots=False,
                                margins=("accounted_depth",))
    assert_sound_in_every_set_kind(summary, tmp_path)
    # the falsifier's accounted objective reads no set's name: anonymous runs give it
    assert summary["margins"]["accounted_depth"]["least_m"] > 0.0
    assert {f["fault"] for f in summary["faults"]} == {"sensor.b", "sensor.d", "link.l"}
    assert all(f["first_active_step"] is not None for f in summary["faults"])
    assert all(f["first_beyond_bounds_step"] is None for f in summary["faults"])
    assert summary["vehicles"]["bus"]["route_completed"]
