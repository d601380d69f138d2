"""The world's motion check in real SUMO, on the paper road (S1): a pedestrian that leaves the
estimator's model stops the run with exit status 5 and one line; a study that lists
``pedestrian_speed`` runs on and counts the breaks; in a batch the stopped run is a failed run
whose error.json names the assumption, and the other runs go on.

A jitter below the measured one is refused (tests/world/test_walker_jitter.py), so the runs
that must break here run on a copy of the paper road whose cached measurement says 0.05 m (as
if the measurement had missed the jump): the run's own check still stops them."""

from __future__ import annotations

import json
import shutil
from dataclasses import replace
from pathlib import Path

import pytest
from world_helpers import REPO

from sse_cosim.cli.main import EXIT_ASSUMPTION_BROKEN, main
from sse_cosim.reporting.outputs import RUNS_FOLDER
from sse_cosim.runner.batch import run_batch
from sse_cosim.runner.executors import Execution
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world import walker_jitter
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap
from sse_cosim.world.sumo import measure_walkers, sumo_version

pytestmark = pytest.mark.sumo
S1 = Path(__file__).resolve().parents[2] / "scenarios" / "s1_pedestrian.toml"
MISSED_M = 0.05  # what the planted measurement says


@pytest.fixture
def missed(tmp_path, monkeypatch) -> Path:
    """A copy of the paper road whose cached walker measurement says every junction needs
    only 0.05 m (the cache in a folder of the test's own; where walkers leave the ground as
    measured)."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    net = tmp_path / "paper.net.xml"
    shutil.copyfile(build_network(REPO / "sumo_net"), net)
    scenario = load_scenario(S1)
    key = walker_jitter.cache_key(sumo_version(), scenario.simulation.step_length_s,
                                  scenario.estimator.max_pedestrian_speed_mps,
                                  scenario.pedestrian_radius_m())
    road = build_network(REPO / "sumo_net")  # its own measurement, with where walkers leave
    measure_walkers(road, load_roadmap(road), None, scenario.estimator.max_pedestrian_speed_mps,
                    scenario.simulation.step_length_s, scenario.pedestrian_radius_m())
    walker_jitter.JitterCache(net).add(key, [replace(measured, jitter_m=MISSED_M) for measured
                                             in walker_jitter.JitterCache(road).junctions(key)
                                             .values()])
    return net


def _on(net: Path, folder: Path) -> Path:
    """S1 for 10 s on the network ``net``: its scenario file in ``folder``."""
    path = folder / "broken.toml"
    path.write_text(f'extends = "{S1.as_posix()}"\n[simulation]\nduration_s = 10\n'
                    f'[network]\nnet_file = "{net.as_posix()}"\n', encoding="utf-8")
    return path


def test_a_jump_beyond_a_small_jitter_stops_the_run_with_one_line(tmp_path, capsys, missed):
    """SUMO's striping model moves the walker 0.39 m in one step where it enters the walking
    area (WC_0 -> :C_w1_0): beyond 2.5 m/s x 0.1 s and a jitter of 0.05 m."""
    with pytest.raises(SystemExit) as info:
        main(["run", str(_on(missed, tmp_path)), "--out", str(tmp_path / "out")])
    assert info.value.code == EXIT_ASSUMPTION_BROKEN
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    for words in ("broke an assumption of the estimator", "pedestrian 'pedestrian'",
                  "t=9.80 s", "'WC_0' -> ':C_w1_0'", "estimator.position_jitter_m",
                  "raise estimator.position_jitter_m to at least 0.07",
                  "list 'pedestrian_speed' in breaks_assumptions"):
        assert words in err, (words, err)
    assert not (tmp_path / "out" / "summary.json").exists()


def test_a_study_that_lists_the_assumption_runs_on_and_counts_the_breaks(tmp_path, capsys):
    """A pedestrian faster than the bound (3 m/s against 2.5 m/s), declared: exit 0, and
    summary.json counts the breaks with the first few."""
    out = tmp_path / "out"
    main(["run", str(S1), "--out", str(out), "--set", "simulation.duration_s=16",
          "--set", "pedestrians.pedestrian.walking_speed_mps=3.0",
          "--set", 'breaks_assumptions=["pedestrian_speed"]'])
    summary = json.loads((out / "summary.json").read_text())
    breaks = summary["assumption_breaks"]
    assert breaks["count"] >= 1
    first = breaks["first"][0]
    assert first["pedestrian"] == "pedestrian" and first["distance_m"] >= 0.3  # beyond eps
    assert {"t", "distance_m", "step_m", "lane_before", "lane_after"} <= set(first)
    assert len(breaks["first"]) == min(breaks["count"], 5)


def test_in_a_batch_the_stopped_run_is_a_failed_run_naming_the_assumption(tmp_path, missed):
    broken = _on(missed, tmp_path)
    good = tmp_path / "good.toml"
    good.write_text(f'extends = "{S1.as_posix()}"\n[simulation]\nduration_s = 1\n',
                    encoding="utf-8")
    out = tmp_path / "batch"
    outcomes = {o.key: o for o in run_batch([broken, good], out,
                                            Execution(workers=2, progress=False))}
    assert outcomes["good"].ok and "assumption_breaks" not in outcomes["good"].summary
    assert "broke an assumption of the estimator" in outcomes["broken"].error
    error = json.loads((out / RUNS_FOLDER / "broken" / "error.json").read_text())
    assert error["assumption"] == "pedestrian_speed" and "\n" not in error["error"]
