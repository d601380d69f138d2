"""SUMO failures: one line naming the scenario, exit status 3, SUMO closed, files whole; in a
batch the failure is recorded and the other runs go on."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from sse_cosim.cli.main import EXIT_SIMULATION_FAILED, main
from sse_cosim.runner.batch import RUNS_FOLDER, run_batch
from sse_cosim.world import sumo
from sse_cosim.world.snapshot import Snapshot

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
S1 = ROOT / "scenarios" / "_s1.toml"


def scenario_file(folder: Path, name: str, body: str, duration_s: float = 1.0) -> Path:
    """S1 run for ``duration_s`` with ``body`` (TOML tables) added."""
    path = folder / f"{name}.toml"
    path.write_text(f'extends = "{S1.as_posix()}"\n[simulation]\nduration_s = {duration_s}\n'
                    f"{body}", encoding="utf-8")
    return path


def run_cli(args: list[str], capsys) -> tuple[int, str]:
    with pytest.raises(SystemExit) as info:
        main(args)
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return info.value.code, lines[0]


def test_an_error_inside_sumo_names_the_scenario_and_closes_sumo(tmp_path, capsys):
    """SUMO refuses the bus's departure speed (above the road's limit) at the first step."""
    path = scenario_file(tmp_path, "too_fast", "[bus]\nnominal_speed_mps = 70.0\n")
    out = tmp_path / "out"
    code, line = run_cli(["run", str(path), "--out", str(out)], capsys)
    assert code == EXIT_SIMULATION_FAILED
    assert "too_fast.toml" in line and "simulation failed" in line and "Departure speed" in line
    assert not sumo.libsumo.isLoaded()
    for name in ("scenario.rou.xml", "sumo.sumocfg"):  # written before SUMO started: whole
        assert (out / "sumo" / name).read_text().rstrip().endswith(">")
    assert not (out / "summary.json").exists()


def test_a_failed_run_leaves_the_files_of_an_earlier_run_whole(tmp_path, capsys):
    good = scenario_file(tmp_path, "run", "")
    out = tmp_path / "out"
    main(["run", str(good), "--out", str(out)])
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    capsys.readouterr()
    bad = scenario_file(tmp_path, "run", "[bus]\nnominal_speed_mps = 70.0\n")
    code, _ = run_cli(["run", str(bad), "--out", str(out)], capsys)
    assert code == EXIT_SIMULATION_FAILED
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
    assert json.loads((out / "summary.json").read_text())["steps"] > 0


def test_a_network_that_does_not_build_names_the_scenario(tmp_path, capsys):
    net = tmp_path / "net"
    shutil.copytree(ROOT / "sumo_net", net, ignore=shutil.ignore_patterns("build", "*.md"))
    edges = (net / "road.edg.xml").read_text(encoding="utf-8")
    (net / "road.edg.xml").write_text(edges.replace('from="W" to="C"', 'from="W" to="Q"'))
    path = scenario_file(tmp_path, "broken_net", f'[network]\nsources_dir = "{net.as_posix()}"\n')
    code, line = run_cli(["run", str(path), "--out", str(tmp_path / "out")], capsys)
    assert code == EXIT_SIMULATION_FAILED
    assert "broken_net.toml" in line and "does not build" in line and "netconvert" in line
    assert not list((net / "build").glob("*/road.net.xml"))  # no half-built net is cached


def test_a_bus_that_is_never_inserted_stops_the_run(tmp_path, capsys, monkeypatch):
    """SUMO keeps a vehicle waiting when there is no room to insert it; the run gives up."""
    real_step = sumo.SumoWorld.step

    def step_without_bus(world):
        snapshot = real_step(world)
        world._bus_seen = False
        return Snapshot(snapshot.time, {}, snapshot.persons)

    monkeypatch.setattr(sumo.SumoWorld, "step", step_without_bus)
    path = scenario_file(tmp_path, "blocked", "", duration_s=5.0)
    code, line = run_cli(["run", str(path), "--out", str(tmp_path / "out")], capsys)
    assert code == EXIT_SIMULATION_FAILED
    assert "blocked.toml" in line and "could not insert the bus" in line
    assert not sumo.libsumo.isLoaded()


def test_a_batch_records_each_failure_and_finishes_the_other_runs(tmp_path):
    good = scenario_file(tmp_path, "good", "")
    sumo_error = scenario_file(tmp_path, "sumo_error", "[bus]\nnominal_speed_mps = 70.0\n")
    bad_input = scenario_file(tmp_path, "bad_input", "[pedestrian]\nstart_pos_m = 450.0\n")
    out = tmp_path / "out"
    outcomes = {o.key: o for o in run_batch([good, sumo_error, bad_input], out, workers=3,
                                            progress=False)}
    assert outcomes["good"].ok and outcomes["good"].summary["steps"] == 10
    assert "simulation failed" in outcomes["sumo_error"].error
    assert "pedestrian.start_pos_m" in outcomes["bad_input"].error
    for key in ("sumo_error", "bad_input"):
        error = json.loads((out / RUNS_FOLDER / key / "error.json").read_text())
        assert error["key"] == key and "\n" not in error["error"]
    assert (out / RUNS_FOLDER / "good" / "summary.json").is_file()
