"""A run folder's files and summary figures, from a recorder filled by hand (no SUMO)."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
import shapely

from sse_cosim.files import portable_path, read_text
from sse_cosim.reporting.outputs import (
    REGIONS,
    SETS,
    SUMMARY,
    TRACE,
    TRUTH,
    RegionFile,
    write_run,
)
from sse_cosim.reporting.recorder import REFINED, UNOBSERVED, RegionLog, RegionRecord, RunRecorder
from sse_cosim.scenario.loader import load_scenario

SCENARIO = Path(__file__).resolve().parents[2] / "scenarios" / "s3_pedestrian.toml"
DONE, NOT_DONE = {"bus": True}, {"bus": False}  # whether the bus reached its route's end


def recorder_with(speeds: list[float], contact: list[bool], clear: list[bool] | None = None,
                  commanded: list[float] | None = None, levels: list[str] | None = None,
                  truly_clear: list[bool] | None = None) -> RunRecorder:
    """A recorder whose rows hold the bus's speed, contact with the pedestrian, whether its
    path was clear in its picture (default: always) and in truth (default: as in the
    picture), its commanded speed (default: its speed) and level (default: nominal), every
    0.1 s; the pedestrian is in the scene from the second step on."""
    recorder = RunRecorder(load_scenario(SCENARIO))
    clear = clear or [True] * len(speeds)
    steps = list(enumerate(zip(speeds, contact, clear, commanded or speeds,
                               levels or ["nominal"] * len(speeds), truly_clear or clear,
                               strict=True)))
    recorder.rows = [
        {"t": round(0.1 * i, 6), "vehicle": "bus", "bus_x": 2.0 * i, "bus_y": -1.75,
         "bus_speed": v, "commanded_speed": u, "level": level,
         "distance_bus_pedestrian": None, "inconsistent": False, "collision": c,
         "path_clear": p, "truly_clear": truly}
        for i, (v, c, p, u, level, truly) in steps
    ]
    recorder.truth_rows = [{"t": round(0.1 * i, 6), "pedestrian": "pedestrian",
                            "x": 183.123456789, "y": -7.6, "speed": 1.3,
                            "heading": 0.0 if i > 1 else None} for i, _ in steps if i]
    recorder.pedestrian_rows = [
        {"t": round(0.1 * i, 6), "vehicle": "bus", "pedestrian": "pedestrian",
         "contained_fused": None, "contained_refined": None, "accounted_for": True,
         "distance": 0.0 if c else 5.0}
        for i, (_, c, *_) in steps
    ]
    return recorder


def test_longest_standstill_after_clear_counts_stopped_steps_with_a_clear_path_in_a_row():
    speeds = [0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0]
    clear = [False, False, True, True, True, True, True, True]
    summary = recorder_with(speeds, [False] * 8, clear).summary()
    assert summary["longest_standstill_after_clear_s"] == pytest.approx(0.3)


def test_a_bus_told_to_go_that_sumo_holds_is_not_a_standstill_of_the_controller():
    speeds = [0.0] * 6
    commanded = [0.0, 0.0, 5.0, 5.0, 5.0, 0.0]  # SUMO holds it (a car's right of way)
    summary = recorder_with(speeds, [False] * 6, None, commanded).summary()
    assert summary["longest_standstill_after_clear_s"] == pytest.approx(0.2)
    assert summary["time_stopped_s"] == pytest.approx(0.6)


def test_the_needless_hold_counts_held_steps_in_a_row_while_the_truth_left_the_path_clear():
    """Liveness from the truth: a creep, a stop or an emergency brake counts while no true
    pedestrian could have reached a zone before the bus cleared it; the controller's own
    picture (here never clear) does not matter."""
    levels = ["stop", "stop", "creep", "emergency", "nominal", "stop", "stop", "slow"]
    truly = [False, True, True, True, True, True, True, True]
    summary = recorder_with([0.0] * 8, [False] * 8, [False] * 8, levels=levels,
                            truly_clear=truly).summary()
    assert summary["longest_needless_hold_s"] == pytest.approx(0.3)
    assert summary["longest_standstill_after_clear_s"] == 0.0  # the picture's: blind to it


def test_the_truth_leaves_the_path_clear_while_nobody_can_reach_a_zone_in_its_clear_time():
    """(d - 2 eps) / v against the zone's clear time, for every zone and true pedestrian; on a
    red crossing's own ground, no sooner than its light can change for a walker off it."""
    from sse_cosim.reporting.recorder import _TruePoints
    from sse_cosim.world.signals import CrossingLights, Phase, Program, SignalState

    recorder = RunRecorder(load_scenario(SCENARIO, {"estimator.position_jitter_m": 0.5}))
    zone = SimpleNamespace(ground=shapely.box(0.0, 0.0, 4.0, 4.0), clear_s=2.0, lit=())
    ego = SimpleNamespace(picture=SimpleNamespace(zones=(zone,)))
    v = recorder.scenario.estimator.max_pedestrian_speed_mps

    def clear_with_one_at(distance: float, on: str | None = None, light: str = "G") -> bool:
        step = SimpleNamespace(snapshot=SimpleNamespace(
            persons={"p": SimpleNamespace(crossing=on)},
            signals={"L": SignalState("0", 0, light, 0.0)}))
        return recorder._truly_clear(ego, _TruePoints.of({"p": np.array([4.0 + distance,
                                                                         2.0])}), step)

    assert clear_with_one_at(2.0 * v + 1.0 + 0.01)  # arrives 0.004 s after it clears
    assert not clear_with_one_at(2.0 * v + 1.0 - 0.01)
    assert recorder._truly_clear(ego, _TruePoints.of({}), None)  # nobody in the scene
    lights = CrossingLights((("L", 0),), {("L", "0"): Program("0", (Phase("r", 10.0),
                                                                     Phase("G", 5.0)))})
    zone.lit = (("c", shapely.box(0.0, 0.0, 4.0, 4.0), lights),)
    assert clear_with_one_at(0.5, on=None, light="r")  # waits 10 s at its red
    assert not clear_with_one_at(0.5, on="c", light="r")  # on it already
    assert not clear_with_one_at(0.5, on=None, light="G")


def test_collisions_count_entries_into_contact_and_contact_steps_every_step():
    contact = [False, True, True, True, False, False, True, True]
    summary = recorder_with([5.0] * len(contact), contact).summary()
    assert summary["collisions"] == 2
    assert summary["contact_steps"] == 5


def test_a_run_that_starts_in_contact_counts_that_collision():
    summary = recorder_with([0.0] * 3, [True, True, False]).summary()
    assert (summary["collisions"], summary["contact_steps"]) == (1, 2)


def test_time_stopped_sums_the_steps_below_a_tenth_of_a_metre_per_second():
    speeds = [20.0, 5.0, 0.09, 0.0, 0.1, 0.05, 3.0]
    summary = recorder_with(speeds, [False] * len(speeds)).summary()
    assert summary["time_stopped_s"] == pytest.approx(0.3)
    assert recorder_with([], []).summary()["time_stopped_s"] == 0.0


def test_the_first_stop_is_the_first_standstill_after_moving():
    """A bus standing at its departure has not stopped yet; the first step below 0.1 m/s
    after it moved is its first stop (the sweeps' distance at the first stop reads it)."""
    speeds = [0.0, 0.0, 5.0, 0.09, 0.0, 3.0, 0.0]
    stop = recorder_with(speeds, [False] * len(speeds)).summary()["first_stop"]
    assert stop is not None and stop["t"] == pytest.approx(0.3)
    assert recorder_with([5.0, 5.0], [False, False]).summary()["first_stop"] is None


def test_route_completed_comes_from_the_caller():
    recorder = recorder_with([20.0], [False])
    assert recorder.summary(DONE)["route_completed"] is True
    assert recorder.summary(NOT_DONE)["route_completed"] is False
    assert recorder.summary()["route_completed"] is None


def test_run_folder_holds_regions_and_the_summary_figures(tmp_path):
    recorder = recorder_with([20.0, 0.0], [False, True])
    recorder.regions.add([
        RegionRecord(0.0, UNOBSERVED, None, shapely.box(0, 0, 2, 1), "bus"),
        RegionRecord(0.1, REFINED, "pedestrian", shapely.Polygon(), "bus"),
        RegionRecord(0.1, UNOBSERVED, None, shapely.box(0, 0, 1, 1), "bus"),
    ])
    summary = write_run(tmp_path, recorder.scenario, recorder, None, "test", DONE,
                        plots_wanted=False)
    lines = [json.loads(line) for line in read_text(tmp_path / REGIONS).splitlines()]
    assert [(line["t"], line["kind"], line["track"]) for line in lines] == [
        (0.0, "unobserved", None), (0.1, "refined", "pedestrian"), (0.1, "unobserved", None)]
    assert lines[1]["polygons"] == []
    (square,) = lines[2]["polygons"]
    assert shapely.Polygon(square[0], square[1:]).equals(shapely.box(0, 0, 1, 1))
    on_disk = json.loads((tmp_path / SUMMARY).read_text())
    assert on_disk == summary
    assert (summary["route_completed"], summary["collisions"], summary["time_stopped_s"]) == (
        True, 1, 0.1)


def test_regions_streamed_while_the_run_goes_are_the_same_file(tmp_path):
    """A run's regions go to regions.jsonl.gz step by step and are not kept: the file is byte
    for byte the one written from kept regions at the end, and it is not in place (nor is
    anything but its hidden part) until write_run puts it there; a run that stops leaves
    nothing."""
    steps = [[RegionRecord(0.1 * k, UNOBSERVED, None, shapely.box(0, 0, 1 + k, 1), "bus"),
              RegionRecord(0.1 * k, REFINED, "p", shapely.box(k, 0, k + 0.5, 0.5), "bus")]
             for k in range(300)]
    kept = recorder_with([20.0], [False])
    for records in steps:
        kept.regions.add(records)
    write_run(tmp_path / "kept", kept.scenario, kept, None, "test", DONE, plots_wanted=False)
    out = tmp_path / "streamed"
    streamed = recorder_with([20.0], [False])
    streamed.regions = RegionLog(RegionFile(out / REGIONS), keep=False)
    for records in steps:
        streamed.regions.add(records)
    assert streamed.regions.records == [] and not (out / REGIONS).exists()
    write_run(out, streamed.scenario, streamed, None, "test", DONE, plots_wanted=False)
    assert (out / REGIONS).read_bytes() == (tmp_path / "kept" / REGIONS).read_bytes()
    assert len(read_text(out / REGIONS).splitlines()) == 600
    assert sorted(p.name for p in out.iterdir()) == sorted(
        p.name for p in (tmp_path / "kept").iterdir())
    stopped = RegionFile(tmp_path / "stopped" / REGIONS)
    stopped.add(steps[0])
    stopped.discard()
    assert list((tmp_path / "stopped").iterdir()) == []


def test_trace_positions_keep_a_micrometre(tmp_path):
    recorder = recorder_with([20.0, 20.0, 20.0], [False, False, False])
    write_run(tmp_path, recorder.scenario, recorder, None, "test", DONE, plots_wanted=False)
    trace = pd.read_csv(tmp_path / TRACE)
    truth = pd.read_csv(tmp_path / TRUTH)
    assert list(truth.columns) == ["t", "pedestrian", "x", "y", "speed", "heading"]
    assert (truth["t"][0], truth["x"][0]) == (0.1, 183.123457)
    assert np.isnan(truth["heading"][0]) and truth["heading"][1] == 0.0  # empty: waiting
    assert trace["bus_x"][1] == 2.0


def test_summary_only_writes_no_trace_sets_or_regions(tmp_path):
    recorder = recorder_with([20.0], [False])
    recorder.regions.add([RegionRecord(0.0, UNOBSERVED, None, shapely.box(0, 0, 1, 1), "bus")])
    write_run(tmp_path, recorder.scenario, recorder, None, "test", NOT_DONE, plots_wanted=False,
              summary_only=True)
    assert not any((tmp_path / name).exists() for name in (TRACE, SETS, REGIONS))
    assert json.loads((tmp_path / SUMMARY).read_text())["route_completed"] is False


def test_run_folder_records_no_machine_path(tmp_path, monkeypatch):
    """Paths relative to the current folder (the repository) and to the run folder: a results
    folder made on another machine is byte for byte the same."""
    repo = SCENARIO.parents[1]
    monkeypatch.chdir(repo)
    assert portable_path(SCENARIO) == "scenarios/s3_pedestrian.toml"
    assert portable_path(tmp_path) == str(tmp_path)  # outside the folder: kept as given
    out = tmp_path / "run"
    recorder = recorder_with([20.0], [False])
    write_run(out, recorder.scenario, recorder, None, portable_path(SCENARIO), DONE,
              plots_wanted=False)
    scenario = json.loads((out / "scenario.json").read_text())
    assert not Path(scenario["network"]["sources_dir"]).is_absolute()
    sources = (out / scenario["network"]["sources_dir"]).resolve()
    assert sources == (repo / "sumo_net").resolve()


def test_restarts_count_orders_to_move_that_follow_an_order_to_stop():
    speeds = [5.0, 2.0, 0.0, 0.0, 0.2, 0.0, 0.3, 1.0]
    commanded = [5.0, 0.0, 0.0, 8.0, 0.0, 8.0, 8.0, 0.5]  # stop, go, stop, go, slow down
    summary = recorder_with(speeds, [False] * len(speeds), None, commanded).summary()
    assert summary["restarts"] == 2
    assert summary["vehicles"]["bus"]["restarts"] == 2
    assert recorder_with([3.0] * 4, [False] * 4).summary()["restarts"] == 0
