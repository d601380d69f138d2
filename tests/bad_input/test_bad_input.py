"""Bad input of every kind ends with exit status 2 and one line: the file or argument, the field
and what to do -- never a traceback.

Each case writes its files into a temporary folder and runs the CLI in-process
(``sse_cosim.cli.main.main``); a few run it as a subprocess, as a user would. Cases that get
as far as the road network (actors off the network or off the sidewalk) stop before SUMO
starts: the checks run on the built network.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from sse_cosim.cli.main import EXIT_BAD_INPUT, main

ROOT = Path(__file__).resolve().parents[2]
S1 = ROOT / "scenarios" / "_s1.toml"  # a complete scenario to extend (absolute path)
S2 = ROOT / "scenarios" / "_s2.toml"  # the same with the connected car
S1_RUN = ROOT / "scenarios" / "s1_pedestrian.toml"


@dataclass(frozen=True)
class Case:
    """A bad scenario ``text`` (written to bad.toml, or none) and the command around it.

    ``args`` may use ``{file}`` (the scenario), ``{tmp}`` (the folder) and ``{s1}`` (a good
    scenario); ``words`` must all appear in the one line, besides the file's name.
    """

    id: str
    text: str | None
    words: tuple[str, ...]
    args: tuple[str, ...] = ("run", "{file}", "--out", "{tmp}/out")
    named: str = "bad.toml"  # the name the line must contain


def extend(body: str, base: Path = S1) -> str:
    return f'extends = "{base.as_posix()}"\n{body}'


def set_case(id: str, assignment: str, words: tuple[str, ...]) -> Case:
    """A good scenario run with one bad ``--set``: the line must name that option."""
    return Case(id, None, words, ("run", "{s1}", "--out", "{tmp}/out", "--set", assignment),
                named=f"sse-cosim: --set {assignment}: ")


CASES = [
    # --- the scenario file: syntax and schema ---
    Case("syntax", 'name = "x"\n[bus\n', ("syntax",)),
    Case("unknown key", extend("[automated.bus]\nnominal_speed = 3\n"),
         ("automated.bus.nominal_speed", "did you mean automated.bus.nominal_speed_mps?",
          "remove")),
    Case("misspelt keys in a named table and a table",
         extend("[sensors.bus_front]\nrangee_m = 50\n[simulaton]\nseed = 2\n"),
         ("sensors.bus_front.rangee_m", "did you mean sensors.bus_front.range_m?",
          "1 more problem(s) after this one: simulaton")),
    Case("wrong type", extend('[automated.bus]\nnominal_speed_mps = "fast"\n'),
         ("automated.bus.nominal_speed_mps", "number")),
    Case("negative noise bound", extend("[sensors.bus_front]\nnoise_bound_m = [-0.5, 0.5]\n"),
         ("sensors.bus_front.noise_bound_m", "greater than 0")),
    Case("zero noise bound", extend("[sensors.bus_front]\nnoise_bound_m = [0.5, 0.0]\n"),
         ("sensors.bus_front.noise_bound_m", "greater than 0")),
    Case("fov beyond 360", extend("[sensors.bus_front]\nfov_deg = 400\n"),
         ("sensors.bus_front.fov_deg", "360")),
    Case("range field on a camera", extend("[sensors.bus_front]\nrange_bound_m = 0.2\n"),
         ("sensors.bus_front.range_bound_m", "only used with kind = 'range'", "remove it")),
    Case("unknown sensor kind", extend('[sensors.bus_front]\nkind = "sonar"\n'),
         ("sensors.bus_front.kind", "unknown sensor kind 'sonar'", "camera, range")),
    Case("zero range", extend("[sensors.bus_front]\nrange_m = 0\n"),
         ("sensors.bus_front.range_m", "greater than 0")),
    Case("sensor on a missing node", extend('[sensors.side]\nnode = "drone"\n'),
         ("sensors.side.node", "drone", "use one of")),
    Case("unknown method", extend('[estimator]\ngain_method = "magic"\n'),
         ("estimator.gain_method", "frobenius")),
    Case("unknown state model", extend('[estimator]\nstate_model = "cv"\n'),
         ("estimator.state_model", "unknown state model 'cv'", "position, constant-velocity")),
    Case("speed levels out of order", extend("[controller]\nvery_slow_factor = 0.9\n"),
         ("controller", "very_slow_factor")),
    Case("no name", "[automated.bus]\nnominal_speed_mps = 10\n", ("name", "add this field")),
    Case("missing parent", 'extends = "missing.toml"\nname = "x"\n', ("extends", "not found")),
    Case("extends cycle", 'extends = "bad.toml"\nname = "x"\n', ("extends", "cycle")),
    Case("extends not a name", "extends = 3\n", ("extends", 'extends = "base.toml"')),
    # --- faults ---
    Case("fault on a missing sensor",
         extend('[faults.sensor.f]\nsensor = "radar"\nkind = "stuck"\n'),
         ("faults.sensor.f.sensor", "radar", "bus_front")),
    Case("fault ends before it starts",
         extend('[faults.sensor.f]\nsensor = "bus_front"\nkind = "stuck"\nstart_s = 5\n'
                "end_s = 4\n"), ("faults.sensor.f.end_s", "later than start_s")),
    Case("bias without offset", extend('[faults.sensor.f]\nsensor = "bus_front"\nkind = "bias"\n'),
         ("faults.sensor.f.bias_m", "non-zero")),
    Case("field of another fault kind",
         extend('[faults.sensor.f]\nsensor = "bus_front"\nkind = "dropout"\nbias_m = [1, 0]\n'),
         ("faults.sensor.f.bias_m", "only used with kind = 'bias'")),
    Case("dropout probability above 1",
         extend('[faults.sensor.f]\nsensor = "bus_front"\nkind = "dropout"\n'
                "dropout_probability = 1.5\n"), ("faults.sensor.f.dropout_probability",)),
    Case("node fault on the bus", extend('[faults.node.n]\nnode = "bus"\nkind = "shrink"\n'),
         ("faults.node.n.node", "sends to an automated vehicle", "add a connected vehicle")),
    Case("a fault beyond the bounds with anonymous detections",
         extend('breaks_assumptions = ["sensor_bounds"]\n[estimator]\n'
                'association = "anonymous"\n[faults.sensor.f]\nsensor = "bus_front"\n'
                'kind = "stuck"\n'),
         ("faults.sensor.f", "beyond the estimator's bounds", "association = 'anonymous'")),
    Case("Kalman baseline with anonymous detections",
         extend('[estimator]\nassociation = "anonymous"\nfilter = "kalman"\n'),
         ("estimator.filter", "person id", "filter = 'zonotope'")),
    # --- the estimator's assumptions: broken only when declared ---
    Case("pedestrian faster than the estimator's bound",
         extend("[pedestrians.pedestrian]\nwalking_speed_mps = 2.8\n"),
         ("pedestrians.pedestrian.walking_speed_mps", "max_pedestrian_speed_mps (2.5 m/s)",
          'add "pedestrian_speed" to breaks_assumptions')),
    Case("bias beyond the bound undeclared",
         extend('[faults.sensor.f]\nsensor = "bus_front"\nkind = "bias"\nbias_m = [3, 0]\n'),
         ("faults.sensor.f.kind", "bias", 'add "sensor_bounds" to breaks_assumptions')),
    Case("stuck sensor undeclared",
         extend('[faults.sensor.f]\nsensor = "bus_front"\nkind = "stuck"\n'),
         ("faults.sensor.f.kind", "stuck", 'add "sensor_bounds" to breaks_assumptions')),
    Case("phantom undeclared",
         extend('[faults.sensor.f]\nsensor = "bus_front"\nkind = "phantom"\n'
                "phantom_xy_m = [200, 0]\n"),
         ("faults.sensor.f.kind", "phantom", 'add "sensor_bounds" to breaks_assumptions')),
    Case("node fault undeclared",
         extend('[faults.node.n]\nnode = "car"\nkind = "shift"\nshift_m = [4, 0]\n', S2),
         ("faults.node.n.kind", "shift", 'add "shared_estimates" to breaks_assumptions')),
    Case("fault declared as another assumption",
         extend('breaks_assumptions = ["shared_estimates"]\n'
                '[faults.sensor.f]\nsensor = "bus_front"\nkind = "stuck"\n'),
         ("faults.sensor.f.kind", '"sensor_bounds"')),
    Case("unknown assumption", extend('breaks_assumptions = ["physics"]\n'),
         ("breaks_assumptions.0", "'sensor_bounds'")),
    # --- the scenario against the road network ---
    Case("actor off the network", extend('[automated.bus]\nroute_edges = ["WC", "XX"]\n'),
         ("automated.bus.route_edges", "no edge 'XX'")),
    Case("bus beyond its edge", extend("[automated.bus]\ndepart_pos_m = 500\n"),
         ("automated.bus.depart_pos_m", "beyond the end")),
    Case("pedestrian beyond its edge", extend("[pedestrians.pedestrian]\nstart_pos_m = 450\n"),
         ("pedestrians.pedestrian.start_pos_m", "beyond the end")),
    Case("pedestrian off the network", extend('[pedestrians.pedestrian]\nstart_edge = "NOPE"\n'),
         ("pedestrians.pedestrian.start_edge", "no edge 'NOPE'")),
    Case("truck off the parking strip", extend("[parked.truck]\nlane_index = 2\n"),
         ("parked.truck.lane_index", "not a parking strip")),
    Case("crossing time the walk cannot make",
         extend("[pedestrians.pedestrian]\nstart_pos_m = 184\nwalking_speed_mps = 1.2\n"
                "steps_onto_crossing_s = 5\n"),
         ("pedestrians.pedestrian.steps_onto_crossing_s", "cannot be reached",
          "13.9 s at the earliest", "use 13.9 s or later",
          "pedestrians.pedestrian.start_pos_m nearer the crossing")),
    Case("bus faster than the road", extend("[automated.bus]\nnominal_speed_mps = 30\n"),
         ("automated.bus.nominal_speed_mps", "above every speed limit on the route",
          "use at most 27.78 m/s")),
    Case("car faster than the road", extend("[vehicles.car]\nspeed_mps = 28\n", S2),
         ("vehicles.car.speed_mps", "speed limit of lane 'EC_2'", "use at most 27.78 m/s")),
    Case("missing network sources", extend('[network]\nsources_dir = "no_such_folder"\n'),
         ("network.sources_dir", "does not exist")),
    Case("network sources and net file", extend('[network]\nsources_dir = "a"\n'
                                                'net_file = "b.net.xml"\n'),
         ("network.net_file", "both set", "keep one")),
    Case("missing net file", extend('[network]\nnet_file = "no_such.net.xml"\n'),
         ("network.net_file", "not found", "SUMO .net.xml")),
    Case("net file that is no network", extend('[network]\nnet_file = "bad.toml"\n'),
         ("network.net_file", "cannot be read")),
    Case("missing route file", extend('[network]\nroute_files = ["no_such.rou.xml"]\n'),
         ("network.route_files", "not found")),
    Case("sensor on an undeclared type", extend('[sensors.cav_front]\ncarrier_type = "cav"\n'),
         ("sensors.cav_front.carrier_type", "declares the type 'cav'")),
    Case("sensor on a node and a type", extend('[sensors.bus_front]\ncarrier_type = "cav"\n'),
         ("sensors.bus_front.node", "exactly one of node")),
    # --- the command line ---
    set_case("set a path that does not exist", "bad.path=1", ("bad.path", "no table")),
    Case("set without a value", None, ("--set", "PATH=VALUE"),
         ("run", "{s1}", "--out", "{tmp}/out", "--set", "nonsense"), named="command line"),
    set_case("set an invalid value", "automated.bus.nominal_speed_mps=-3",
             ("automated.bus.nominal_speed_mps", "greater than 0")),
    set_case("set a word for a number", "sensors.bus_front.range_m=abc",
             ("sensors.bus_front.range_m", "valid number", "give a number")),
    set_case("set a glob to a wrong value", "sensors.*.noise=1",
             ("sensors.bus_front.noise:", "'uniform' or 'worst-case'")),
    set_case("set a glob that selects nothing", "sensors.*.nope=1", ("'nope' matches nothing",)),
    set_case("set a filter that selects nothing", "sensors.*[node=zzz].range_m=3",
             ("'*[node=zzz]' matches nothing",)),
    set_case("set a bus beyond its edge", "automated.bus.depart_pos_m=500",
             ("automated.bus.depart_pos_m", "beyond the end")),
    Case("a bad file is blamed on the file, --set or not",
         extend("[automated.bus]\nnominal_speed = 3\n"),
         ("automated.bus.nominal_speed", "remove"),
         ("run", "{file}", "--out", "{tmp}/out", "--set", "simulation.duration_s=2"),
         named="bad.toml: "),
    set_case("set a pedestrian faster than the estimator's bound",
             "pedestrians.pedestrian.walking_speed_mps=2.8",
             ("pedestrians.pedestrian.walking_speed_mps",
              'add "pedestrian_speed" to breaks_assumptions')),
    set_case("set a bound below the pedestrian's speed", "estimator.max_pedestrian_speed_mps=1",
             ("pedestrians.pedestrian.walking_speed_mps", "max_pedestrian_speed_mps (1 m/s)")),
    Case("output folder is a file", None, ("--out", "is a file"),
         ("run", "{s1}", "--out", "{tmp}/a_file"), named="a_file"),
    Case("output folder cannot be made", None, ("--out", "cannot write"),
         ("run", "{s1}", "--out", "/proc/sse-cosim-out"), named="/proc/sse-cosim-out"),
    Case("scenario file not found", None, ("not found",),
         ("run", "{tmp}/nothere.toml", "--out", "{tmp}/out"), named="nothere.toml"),
    Case("scheduler without dask", None, ("--scheduler", "--executor dask"),
         ("batch", "{s1}", "--out", "{tmp}/out", "--scheduler", "tcp://x:1"),
         named="command line"),
    Case("batch over nothing", None, ("no such file",),
         ("batch", "{tmp}/nowhere", "--out", "{tmp}/out"), named="nowhere"),
    Case("sweep over a path that does not exist", None, ("bad.path",),
         ("sweep", "{s1}", "--param", "bad.path=[1,2]", "--out", "{tmp}/out"),
         named="bad.path"),
    Case("sweep with an invalid --set value", None,
         ("sensors.bus_front.noise_bound_m", "greater than 0"),
         ("sweep", "{s1}", "--set", "sensors.*.noise_bound_m=[-1,1]", "--param",
          "v2x.latency_steps=[1]", "--out", "{tmp}/out"),
         named="sse-cosim: --set sensors.*.noise_bound_m=[-1,1] ("),
    Case("sweep with a --set that selects nothing", None, ("'nope' matches nothing",),
         ("sweep", "{s1}", "--set", "sensors.*.nope=1", "--param", "v2x.latency_steps=[1]",
          "--out", "{tmp}/out"),
         named="sse-cosim: --set sensors.*.nope=1 ("),
    Case("option with a wrong value", None, ("--workers",),
         ("batch", "{s1}", "--workers", "0"), named="sse-cosim batch"),
    Case("falsify file with an empty interval",
         '[[dims]]\npath = "pedestrians.pedestrian.walking_speed_mps"\nname = "walk"\n'
         'low = 2.0\nhigh = 1.0\n', ("dims[0].high", "must be above low"),
         ("falsify", "{s1}", "-f", "{file}", "--out", "{tmp}/out")),
    Case("falsify box beyond the speed bound",
         '[[dims]]\npath = "pedestrians.pedestrian.walking_speed_mps"\nname = "walk"\n'
         'low = 1.0\nhigh = 3.0\n[start_behind_truck]\nlow = 1.0\nhigh = 5.0\n',
         ("corner of the search box", "walking_speed_mps", "narrow the interval"),
         ("falsify", "{s1}", "-f", "{file}", "--out", "{tmp}/out")),
    Case("falsify with an unknown objective", None, ("--objective",),
         ("falsify", "{s1}", "--objective", "speed"), named="sse-cosim falsify"),
]


def materialize(case: Case, tmp: Path) -> list[str]:
    """Write the case's files into ``tmp``; its command line with the placeholders filled."""
    bad = tmp / "bad.toml"
    if case.text is not None:
        bad.write_text(case.text, encoding="utf-8")
    (tmp / "a_file").write_text("", encoding="utf-8")
    return [a.format(file=bad, tmp=tmp, s1=S1_RUN) for a in case.args]


def check_line(stderr: str, case: Case) -> None:
    assert "Traceback" not in stderr, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1, stderr
    line = lines[0]
    for word in (case.named, *case.words):
        assert word in line, (word, line)


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input_is_one_line_and_exit_status_2(case, tmp_path, capsys):
    args = materialize(case, tmp_path)
    with pytest.raises(SystemExit) as info:
        main(args)
    assert info.value.code == EXIT_BAD_INPUT, capsys.readouterr()
    check_line(capsys.readouterr().err, case)


def test_a_pedestrian_on_an_edge_without_sidewalk(tmp_path, capsys):
    """A network whose extra edge has no sidewalk: starting the pedestrian there is refused."""
    net = tmp_path / "net"
    shutil.copytree(ROOT / "sumo_net", net, ignore=shutil.ignore_patterns("build", "*.md"))
    nodes = (net / "road.nod.xml").read_text(encoding="utf-8")
    (net / "road.nod.xml").write_text(nodes.replace(
        "</nodes>", '    <node id="X" x="300.0" y="100.0" type="dead_end"/>\n</nodes>'))
    edges = (net / "road.edg.xml").read_text(encoding="utf-8")
    (net / "road.edg.xml").write_text(edges.replace("</edges>", (
        '    <edge id="EX" from="E" to="X" numLanes="1" speed="13.9">\n'
        '        <lane index="0" width="3.5" allow="passenger"/>\n    </edge>\n</edges>')))
    case = Case("no sidewalk", extend(f'[network]\nsources_dir = "{net.as_posix()}"\n'
                                      '[pedestrians.pedestrian]\nstart_edge = "EX"\n'),
                ("pedestrians.pedestrian.start_edge", "no sidewalk"))
    with pytest.raises(SystemExit) as info:
        main(materialize(case, tmp_path))
    assert info.value.code == EXIT_BAD_INPUT
    check_line(capsys.readouterr().err, case)


def test_resuming_a_search_made_by_other_code(tmp_path, capsys):
    """--resume over a search whose falsify.json names other code: refused before any run."""
    out = tmp_path / "out"
    out.mkdir()
    (out / "falsify.json").write_text(json.dumps({"code_sha256": "0" * 64}))
    with pytest.raises(SystemExit) as info:
        main(["falsify", str(S1_RUN), "--budget", "2", "--resume", "--out", str(out)])
    assert info.value.code == EXIT_BAD_INPUT
    check_line(capsys.readouterr().err, Case("other code", None, (
        "code_sha256", "other code", "without --resume"), named="falsify.json"))
    assert sorted(p.name for p in out.iterdir()) == ["falsify.json"]  # nothing ran


@pytest.mark.parametrize("case", [c for c in CASES if c.id in (
    "syntax", "set a path that does not exist")], ids=lambda c: c.id)
def test_as_a_user_runs_it(case, tmp_path):
    """The installed command, in its own process: the same one line, exit status 2."""
    args = materialize(case, tmp_path)
    proc = subprocess.run([sys.executable, "-m", "sse_cosim", *args], capture_output=True,
                          text=True, cwd=tmp_path, check=False)
    assert proc.returncode == EXIT_BAD_INPUT, proc.stderr
    check_line(proc.stderr, case)


@pytest.mark.sumo
def test_a_declared_fault_runs(tmp_path, capsys):
    """The stuck sensor refused above runs once the scenario declares what it breaks."""
    path = tmp_path / "declared.toml"
    path.write_text(extend('breaks_assumptions = ["sensor_bounds"]\n[simulation]\n'
                           'duration_s = 1.0\n[faults.sensor.f]\nsensor = "bus_front"\n'
                           'kind = "stuck"\n'), encoding="utf-8")
    main(["run", str(path), "--out", str(tmp_path / "out")])
    assert json.loads((tmp_path / "out" / "scenario.json").read_text())[
        "breaks_assumptions"] == ["sensor_bounds"]
    assert (tmp_path / "out" / "summary.json").is_file()
    assert "sse-cosim" not in capsys.readouterr().err
