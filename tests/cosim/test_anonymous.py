"""Anonymous detections in real SUMO (``estimator.association = "anonymous"``): the whole
crowd (21 pedestrians, 90 s) over three seeds stays sound and safe with no person id in the
estimation, and the labelled default is unchanged.

The crowd's seed 1 is issue #60's traced case: n4, n5 and n6 walk abreast 1 m apart at
x = 187.5-189.5 on the south sidewalk, 0.1-0.3 m inside the edge of bus_front's view. The
bus's tracks holding them lay wholly within the jitter (1.2 m) of that edge, where the camera
cuts nothing, and they joined none of its three detections; the bus took its own view as
clear of them and cut them out of every refined region at t = 7.0 and 7.1 s (12 violations;
6 on seeds 2 and 3). A track now joins every candidate of such a sensor (rule R3 of
:mod:`sse_cosim.estimation.association`)."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest
from anonymous_checks import assert_sound_in_every_set_kind

from sse_cosim.files import read_text
from sse_cosim.runner.run import run_scenario_file

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
CROWD = ROOT / "scenarios" / "crowd.toml"
S3 = ROOT / "scenarios" / "s3_pedestrian.toml"


@pytest.fixture(scope="module", params=[1, 2, 3])
def crowd(request, tmp_path_factory) -> tuple[dict, Path]:
    out = tmp_path_factory.mktemp(f"anonymous_crowd_{request.param}")
    summary = run_scenario_file(CROWD, out, {"estimator.association": "anonymous",
                                             "simulation.seed": request.param}, plots=False)
    return summary, out


def test_the_whole_crowd_is_sound_and_safe_with_anonymous_tracks(crowd):
    summary, out = crowd
    assert len(summary["pedestrians"]) == 21
    assert_sound_in_every_set_kind(summary, out)
    assert summary["vehicles"]["bus"]["route_completed"]


def test_the_pedestrians_abreast_at_the_views_edge_stay_accounted_for(crowd):
    """The traced steps: n4-n6 in a refined region at 7.0 and 7.1 s (seed 1 lost all three)."""
    _, out = crowd
    checks = pd.read_csv(out / "pedestrians.csv")
    traced = checks[checks["t"].isin([7.0, 7.1]) & checks["pedestrian"].isin(["n4", "n5", "n6"])]
    assert len(traced) == 6
    assert traced["contained_refined"].astype(bool).all()
    assert traced["accounted_for"].astype(bool).all()


def test_no_set_is_named_after_a_pedestrian(crowd):
    """Sets are the nodes' tracks ('<node>:<id>') and the fused tracks made of them."""
    summary, out = crowd
    lines = [json.loads(line) for line in read_text(out / "sets.jsonl.gz").splitlines()]
    local = {line["track"] for line in lines if line["kind"] == "local"}
    fused = {line["track"] for line in lines if line["kind"] == "fused"}
    assert all(":" in track for track in local)
    assert all(set(track.split("+")) <= local for track in fused)
    assert not (local | fused) & set(summary["pedestrians"])


def test_the_labelled_default_reproduces_the_published_s3_run(tmp_path):
    """Without the setting nothing changed: S3's trace and sets are byte for byte those of
    results/runs/s3_pedestrian."""
    run_scenario_file(S3, tmp_path, {}, plots=False)
    published = ROOT / "results" / "runs" / "s3_pedestrian"
    for name in ("trace.csv", "sets.jsonl.gz", "regions.jsonl.gz"):
        assert (tmp_path / name).read_bytes() == (published / name).read_bytes(), name
