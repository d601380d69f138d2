"""Anonymous detections in real SUMO (``estimator.association = "anonymous"``): a shortened
crowd stays sound and safe with no person id in the estimation, and the labelled default is
unchanged."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
CROWD = ROOT / "scenarios" / "crowd.toml"
S3 = ROOT / "scenarios" / "s3_pedestrian.toml"
KEPT = {"pedestrian", "n1", "s1"}  # two cross north, one walks up to cross south
DROPPED = {f"{wave}{i}" for wave, count in (("n", 6), ("s", 7), ("m", 7))
           for i in range(1, count + 1)} - KEPT
SHORT_CROWD = {"estimator.association": "anonymous", "simulation.duration_s": 18.0,
               **{f"pedestrians.{pid}.present": False for pid in DROPPED}}


@pytest.fixture(scope="module")
def crowd(tmp_path_factory) -> tuple[dict, Path]:
    out = tmp_path_factory.mktemp("anonymous_crowd")
    return run_scenario_file(CROWD, out, SHORT_CROWD, plots=False), out


def test_a_short_crowd_is_sound_and_safe_with_anonymous_tracks(crowd):
    summary, out = crowd
    assert set(summary["pedestrians"]) == KEPT
    assert summary["containment_violations"] == 0, summary["violations"]
    assert summary["collisions"] == summary["contact_steps"] == 0
    checks = pd.read_csv(out / "pedestrians.csv")
    for column in ("contained_fused", "contained_refined"):
        checked = checks[column].dropna()
        assert len(checked) > 0 and checked.astype(bool).all(), column
    assert set(checks.dropna(subset=["contained_fused"])["pedestrian"]) == KEPT


def test_no_set_is_named_after_a_pedestrian(crowd):
    """Sets are the nodes' tracks ('<node>:<id>') and the fused tracks made of them."""
    _, out = crowd
    lines = [json.loads(line) for line in (out / "sets.jsonl").open()]
    local = {line["track"] for line in lines if line["kind"] == "local"}
    fused = {line["track"] for line in lines if line["kind"] == "fused"}
    assert all(":" in track for track in local)
    assert all(set(track.split("+")) <= local for track in fused)
    assert not (local | fused) & KEPT


def test_the_labelled_default_reproduces_the_published_s3_run(tmp_path):
    """Without the setting nothing changed: S3's trace and sets are byte for byte those of
    results/runs/s3_pedestrian."""
    run_scenario_file(S3, tmp_path, {}, plots=False)
    published = ROOT / "results" / "runs" / "s3_pedestrian"
    for name in ("trace.csv", "sets.jsonl", "regions.jsonl"):
        assert (tmp_path / name).read_bytes() == (published / name).read_bytes(), name
