"""SUMO failures: one line naming the scenario, exit status 3, SUMO closed, files whole; in a
batch the failure is recorded and the other runs go on. A vehicle SUMO does not insert at its
departure is a scenario that places it badly: one line naming the field, exit status 2."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from sse_cosim.cli.main import EXIT_BAD_INPUT, EXIT_SIMULATION_FAILED, main
from sse_cosim.reporting.outputs import RUNS_FOLDER
from sse_cosim.runner.batch import run_batch
from sse_cosim.runner.executors import Execution
from sse_cosim.world import sumo

pytestmark = pytest.mark.sumo
ROOT = Path(__file__).resolve().parents[2]
S1 = ROOT / "scenarios" / "_s1.toml"
S2 = ROOT / "scenarios" / "_s2.toml"


def scenario_file(folder: Path, name: str, body: str, duration_s: float = 1.0,
                  base: Path = S1) -> Path:
    """``base`` (S1) run for ``duration_s`` with ``body`` (TOML tables) added."""
    path = folder / f"{name}.toml"
    path.write_text(f'extends = "{base.as_posix()}"\n[simulation]\nduration_s = {duration_s}\n'
                    f"{body}", encoding="utf-8")
    return path


def broken_network(folder: Path) -> Path:
    """A copy of the network sources with an edge to a node that does not exist."""
    net = folder / "net"
    shutil.copytree(ROOT / "sumo_net", net, ignore=shutil.ignore_patterns("build", "*.md"))
    edges = (net / "road.edg.xml").read_text(encoding="utf-8")
    (net / "road.edg.xml").write_text(edges.replace('from="W" to="C"', 'from="W" to="Q"'))
    return net


def fail_at_third_step(monkeypatch) -> None:
    """SUMO raises in the third step of a run, as it does when something inside it breaks
    (the short sessions of lone walkers before it, walk_probe's, step as they always do)."""
    real_step, real_start = sumo.libsumo.simulationStep, sumo.libsumo.start
    calls = []

    def start(args: list[str], *rest: object, **kwargs: object) -> object:
        calls.clear()
        calls.append(sumo.CONFIG_FILE_NAME in args[-1] and Path(args[-1]).parent.name == "sumo")
        return real_start(args, *rest, **kwargs)

    def step() -> None:
        calls.append(1)
        if calls[0] and len(calls) == 4:
            raise sumo.libsumo.TraCIException("Vehicle 'bus' has no valid route")
        real_step()

    monkeypatch.setattr(sumo.libsumo, "start", start)
    monkeypatch.setattr(sumo.libsumo, "simulationStep", step)


def run_cli(args: list[str], capsys) -> tuple[int, str]:
    with pytest.raises(SystemExit) as info:
        main(args)
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return info.value.code, lines[0]


def test_an_error_inside_sumo_names_the_scenario_and_closes_sumo(tmp_path, capsys, monkeypatch):
    fail_at_third_step(monkeypatch)
    path = scenario_file(tmp_path, "broken", "")
    out = tmp_path / "out"
    code, line = run_cli(["run", str(path), "--out", str(out)], capsys)
    assert code == EXIT_SIMULATION_FAILED
    assert "broken.toml" in line and "simulation failed" in line and "no valid route" in line
    assert not sumo.libsumo.isLoaded()
    for name in ("scenario.rou.xml", "sumo.sumocfg"):  # written before SUMO started: whole
        assert (out / "sumo" / name).read_text().rstrip().endswith(">")
    assert not (out / "summary.json").exists()


def test_a_failed_run_leaves_the_files_of_an_earlier_run_whole(tmp_path, capsys, monkeypatch):
    path = scenario_file(tmp_path, "run", "")
    out = tmp_path / "out"
    main(["run", str(path), "--out", str(out)])
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    capsys.readouterr()
    fail_at_third_step(monkeypatch)
    code, _ = run_cli(["run", str(path), "--out", str(out)], capsys)
    assert code == EXIT_SIMULATION_FAILED
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before
    assert json.loads((out / "summary.json").read_text())["steps"] > 0


def test_a_network_that_does_not_build_names_the_scenario(tmp_path, capsys):
    net = broken_network(tmp_path)
    path = scenario_file(tmp_path, "broken_net", f'[network]\nsources_dir = "{net.as_posix()}"\n')
    code, line = run_cli(["run", str(path), "--out", str(tmp_path / "out")], capsys)
    assert code == EXIT_SIMULATION_FAILED
    assert "broken_net.toml" in line and "does not build" in line and "netconvert" in line
    assert not list((net / "build").glob("*/road.net.xml"))  # no half-built net is cached


def test_a_bus_that_is_never_inserted_is_bad_input(tmp_path, capsys, monkeypatch):
    """SUMO keeps a vehicle waiting when there is no room to insert it (here: it never
    reports the bus as departed); the run gives up, naming the bus's departure position."""
    real_departed = sumo.libsumo.simulation.getDepartedIDList
    monkeypatch.setattr(sumo.libsumo.simulation, "getDepartedIDList",
                        lambda: [v for v in real_departed() if v != "bus"])
    path = scenario_file(tmp_path, "blocked", "", duration_s=5.0)
    code, line = run_cli(["run", str(path), "--out", str(tmp_path / "out")], capsys)
    assert code == EXIT_BAD_INPUT
    assert line.startswith(f"sse-cosim: {path}: automated.bus.depart_pos_m: SUMO cannot insert "
                           "'bus' at 0 m on edge 'WC' (automated.bus.depart_s = 0 s) at its "
                           "departure")
    assert "-- move automated.bus.depart_pos_m" in line
    assert not sumo.libsumo.isLoaded()


def test_a_car_without_room_at_its_departure_is_bad_input(tmp_path, capsys):
    """The connected car departs where a slow bus still stands: SUMO cannot insert it."""
    path = scenario_file(tmp_path, "car_blocked", '[automated.bus]\nnominal_speed_mps = 0.5\n'
                         '[vehicles.car]\nroute_edges = ["WC", "CE"]\n'
                         '[pedestrians.pedestrian]\npresent = false\n',
                         duration_s=5.0, base=S2)
    code, line = run_cli(["run", str(path), "--out", str(tmp_path / "out")], capsys)
    assert code == EXIT_BAD_INPUT
    assert line.startswith(f"sse-cosim: {path}: vehicles.car.depart_pos_m: SUMO cannot insert "
                           "'car' at 0 m on edge 'WC' (vehicles.car.depart_s = 0 s) at its "
                           "departure")
    assert "vehicles.car.depart_s" in line.partition(" -- ")[2]
    assert not sumo.libsumo.isLoaded()


@pytest.mark.parametrize("depart_pos_m", [15.0, 60.0])
def test_a_car_ahead_of_the_bus_that_the_bus_could_not_brake_for_is_bad_input(
        depart_pos_m, tmp_path, capsys):
    """A car placed ahead of the bus on the bus's lane, slower than the bus and too close for
    it to brake: SUMO would insert it only once the bus has passed, i.e. behind the bus (at
    15 m within two seconds). The run is refused at the car's departure instead."""
    path = scenario_file(tmp_path, "car_ahead", '[vehicles.car]\nroute_edges = ["WC", "CE"]\n'
                         f"depart_pos_m = {depart_pos_m}\n", duration_s=5.0, base=S2)
    code, line = run_cli(["run", str(path), "--out", str(tmp_path / "out")], capsys)
    assert code == EXIT_BAD_INPUT
    assert line.startswith(f"sse-cosim: {path}: vehicles.car.depart_pos_m: SUMO cannot insert "
                           f"'car' at {depart_pos_m:g} m on edge 'WC' (vehicles.car.depart_s = "
                           "0 s) at its departure: no room there, or the vehicle behind it could "
                           "not brake")
    assert "far enough ahead of it to brake" in line.partition(" -- ")[2]
    assert not sumo.libsumo.isLoaded()


def test_a_batch_records_each_failure_and_finishes_the_other_runs(tmp_path):
    good = scenario_file(tmp_path, "good", "")
    sumo_error = scenario_file(tmp_path, "sumo_error", "[network]\nsources_dir = "
                               f'"{broken_network(tmp_path).as_posix()}"\n')
    bad_input = scenario_file(tmp_path, "bad_input",
                              "[pedestrians.pedestrian]\nstart_pos_m = 450.0\n")
    out = tmp_path / "out"
    outcomes = {o.key: o for o in run_batch([good, sumo_error, bad_input], out,
                                            Execution(workers=3, progress=False))}
    assert outcomes["good"].ok and outcomes["good"].summary["steps"] == 10
    assert "simulation failed" in outcomes["sumo_error"].error
    assert "pedestrians.pedestrian.start_pos_m" in outcomes["bad_input"].error
    for key in ("sumo_error", "bad_input"):
        error = json.loads((out / RUNS_FOLDER / key / "error.json").read_text())
        assert error["key"] == key and "\n" not in error["error"]
    assert (out / RUNS_FOLDER / "good" / "summary.json").is_file()
