"""Bad input on a user's own network (docs/own_network.md): one line naming the file, the field
and the fix, exit status 2, never a traceback.

The network is tests/networks/osm/tiny.osm (two 30 km/h streets crossing) converted by
netconvert as an OpenStreetMap extract is: every road lane admits ``custom1``, so "admits a
parked vehicle" is no parking strip there. Without ``--sidewalks.guess`` its road lanes admit
pedestrians too, and the road map finds no driving lane. Each case runs the CLI in-process
(``sse_cosim.cli.main.main``) as tests/bad_input/test_bad_input.py does; the checks run before
SUMO starts.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from sse_cosim.cli.main import EXIT_BAD_INPUT, main
from sse_cosim.world.network import netconvert_path
from sse_cosim.world.roadmap import load_roadmap

ROOT = Path(__file__).resolve().parents[2]
S1 = ROOT / "scenarios" / "_s1.toml"
OSM = ROOT / "tests" / "networks" / "osm" / "tiny.osm"
GUESS = ("--sidewalks.guess", "--crossings.guess")
# the bus drives the west-east street (way 10) eastwards, 10#0 then 10#1; the pedestrian
# waits on the south sidewalk of the west arm and crosses way 10 to the north sidewalk
BASE = """
[simulation]
duration_s = 1.0
[automated.bus]
route_edges = ["10#0", "10#1"]
nominal_speed_mps = 8.0
[parked.truck]
present = false
[pedestrians.pedestrian]
start_edge = "10#0"
start_pos_m = 80.0
end_edge = "-10#0"
end_pos_m = 80.0
steps_onto_crossing_s = 12.0
"""


def convert(folder: Path, *options: str) -> Path:
    """tiny.osm converted with the command of docs/own_network.md section 3 (its guesses:
    ``options``)."""
    out = folder / "tiny.net.xml"
    subprocess.run([str(netconvert_path()), "--osm-files", str(OSM), *options,
                    "--junctions.join", "--geometry.remove", "--no-turnarounds",
                    "--output-file", str(out)], capture_output=True, check=True, timeout=120)
    return out


@pytest.fixture(scope="module")
def town(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return convert(tmp_path_factory.mktemp("osm"), *GUESS)


@pytest.fixture(scope="module")
def bare(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The same extract converted without sidewalks or crossings."""
    return convert(tmp_path_factory.mktemp("bare"))


def scenario(folder: Path, net: Path, body: str = "") -> Path:
    """bad.toml: S1 on ``net`` with the actors of :data:`BASE` (scene.toml), then ``body``
    (TOML tables)."""
    scene = folder / "scene.toml"
    scene.write_text(f'extends = "{S1.as_posix()}"\n[network]\nnet_file = "{net.as_posix()}"\n'
                     f"{BASE}", encoding="utf-8")
    path = folder / "bad.toml"
    path.write_text(f'extends = "scene.toml"\n{body}', encoding="utf-8")
    return path


def refused(args: list[str], capsys: pytest.CaptureFixture[str], *words: str) -> str:
    """Run the CLI: exit status 2 and one line, no traceback, holding every word."""
    with pytest.raises(SystemExit) as info:
        main(args)
    err = capsys.readouterr().err
    assert info.value.code == EXIT_BAD_INPUT, err
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    for word in words:
        assert word in lines[0], (word, lines[0])
    return lines[0]


def run_args(path: Path, tmp_path: Path, *more: str) -> list[str]:
    return ["run", str(path), "--out", str(tmp_path / "out"), *more]


def test_a_parked_vehicle_on_a_driving_lane(town, tmp_path, capsys):
    """Every OSM road lane admits custom1: the truck on the bus's own lane is refused."""
    body = ('[parked.truck]\npresent = true\nedge = "10#0"\nlane_index = 1\n'
            "end_pos_m = 60.0\n")
    refused(run_args(scenario(tmp_path, town, body), tmp_path), capsys,
            "bad.toml: parked.truck.lane_index: lane 1 of edge '10#0' is not a parking "
            "strip: it admits vClass passenger and bus",
            "edge '10#0' has no parking strip", 'allow="custom1"',
            "parked.truck.present = false")


@pytest.mark.parametrize(("field", "body"), [
    ("automated.bus.route_edges", '[automated.bus]\nroute_edges = ["10#0", "10#l"]\n'),
    ("parked.truck.edge", '[parked.truck]\npresent = true\nedge = "-10#O"\n'),
    ("pedestrians.pedestrian.start_edge", '[pedestrians.pedestrian]\nstart_edge = "10#9"\n'),
    ("pedestrians.pedestrian.end_edge", '[pedestrians.pedestrian]\nend_edge = "-10"\n'),
], ids=["route", "parked", "start", "end"])
def test_a_mistyped_edge_gets_the_nearest_ids(town, tmp_path, capsys, field, body):
    line = refused(run_args(scenario(tmp_path, town, body), tmp_path), capsys,
                   f"bad.toml: {field}: the network has no edge",
                   "use an edge id of the network; the nearest: ")
    nearest = line.split("the nearest: ")[1].split(", ")
    edges = set(load_roadmap(town).edge_lengths)
    assert 1 <= len(nearest) <= 5 and set(nearest) <= edges, line
    assert not edges <= set(nearest)  # not the whole list (8 edges)


def test_a_mistyped_edge_on_a_town_answers_in_one_short_line(tmp_path, capsys):
    """On a network of 20,000 edges the answer stays five ids long."""
    rows = "".join(f'    <edge id="e{i}" from="n{i}" to="n{i + 1}" priority="1">\n'
                   f'        <lane id="e{i}_0" index="0" speed="10" length="1" '
                   f'shape="{i},0 {i + 1},0"/>\n    </edge>\n' for i in range(20000))
    net = tmp_path / "many.net.xml"
    net.write_text(f'<net version="1.20">\n{rows}</net>\n', encoding="utf-8")
    body = ('[automated.bus]\nroute_edges = ["e1234x"]\n'
            "[pedestrians.pedestrian]\npresent = false\n")
    line = refused(run_args(scenario(tmp_path, net, body), tmp_path), capsys,
                   "bad.toml: automated.bus.route_edges: the network has no edge 'e1234x'",
                   "the nearest: e1234")
    assert len(line) < 300, line


def test_a_walk_that_misses_the_route(town, tmp_path, capsys):
    """The end on the pedestrian's own side of the bus's street: its one zebra crosses the
    other street, not the bus's route."""
    body = '[pedestrians.pedestrian]\nend_edge = "10#1"\nend_pos_m = 20.0\n'
    refused(run_args(scenario(tmp_path, town, body), tmp_path), capsys,
            "bad.toml: pedestrians.pedestrian.end_edge: the walk from '10#0' to '10#1'",
            "crosses at :1_c1", "over '-11#0', '11#0'", "no automated vehicle's route",
            "steps_onto_crossing_s", "end the pedestrian on the far side of the route's street",
            "so that its walk takes a zebra over the route: :1_c0, :1_c2")


def test_a_network_without_sidewalks(bare, tmp_path, capsys):
    """No pedestrian, no truck: the bus's route has no driving lane (pedestrians walk on the
    road lanes) -- a refusal, not a KeyError."""
    body = "[pedestrians.pedestrian]\npresent = false\n"
    refused(run_args(scenario(tmp_path, bare, body), tmp_path), capsys,
            "bad.toml: automated.bus.route_edges: edge '10#0' (highway.residential) has no "
            "driving lane", "pedestrians walk on its road lanes",
            "route the vehicle over streets with sidewalks", "netconvert --sidewalks.guess")


def test_the_road_map_refuses_a_lookup_it_cannot_answer(bare):
    """Below the scenario's checks, the road map's own lookups refuse with the network file,
    the edge and the fix (the CLI prints it as one line, exit status 2)."""
    from sse_cosim.errors import UserError

    roadmap = load_roadmap(bare)
    for lookup in (roadmap.route_line, roadmap.route_length):
        with pytest.raises(UserError) as info:
            lookup(["10#0", "10#1"])
        text = info.value.one_line()
        assert text.startswith(f"{bare}: normal edge '10#0': is not a driving lane "), text
        assert "--sidewalks.guess" in text
    with pytest.raises(UserError, match="edge 'nowhere': is not a driving lane"):
        roadmap.route_length(["nowhere"])


def test_a_pedestrian_on_a_road_without_sidewalk(town, tmp_path, capsys):
    """A lane that admits pedestrians and cars is no sidewalk: starting there is refused."""
    net = tmp_path / "shared.net.xml"
    text = town.read_text(encoding="utf-8")
    net.write_text(text.replace('<lane id="10#0_0" index="0" allow="pedestrian"',
                                '<lane id="10#0_0" index="0" allow="pedestrian passenger"'),
                   encoding="utf-8")
    refused(run_args(scenario(tmp_path, net), tmp_path), capsys,
            "bad.toml: pedestrians.pedestrian.start_edge: edge '10#0' has no sidewalk",
            "start and end the pedestrian on an edge with a sidewalk")


def test_the_scene_itself_is_accepted(town, tmp_path):
    """The base scene of these cases passes every check (so each case fails on its own
    field): planning the actors on the converted net raises nothing."""
    from sse_cosim.scenario.loader import load_scenario
    from sse_cosim.world.demand import plan_actors

    path = scenario(tmp_path, town)
    plan = plan_actors(load_scenario(path), town, load_roadmap(town), str(path))
    assert ":1_c2" in plan.pedestrians["pedestrian"].path


def test_a_set_path_is_relative_to_the_working_directory(town, tmp_path):
    """``--set network.net_file=...`` is read where the user types it, as the message says:
    the scenario lives in ``sub/``, the net in the working directory."""
    sub = tmp_path / "sub"
    sub.mkdir()
    path = scenario(sub, town, "[pedestrians.pedestrian]\npresent = false\n")
    (tmp_path / "here.net.xml").write_bytes(town.read_bytes())
    from sse_cosim.runner.parameters import load_with_assignments

    cwd = Path.cwd()
    try:
        os.chdir(tmp_path)
        resolved, _ = load_with_assignments(path, ["network.net_file=here.net.xml"])
    finally:
        os.chdir(cwd)
    assert resolved.network.net_file == str(tmp_path / "here.net.xml")
    # a missing one: the user's own command, one line naming --set, the field, the path
    # looked for (in the working directory, not beside the scenario) and the rule
    proc = subprocess.run([sys.executable, "-m", "sse_cosim", "run", str(path), "--out",
                           str(tmp_path / "out"), "--set", "network.net_file=gone.net.xml"],
                          capture_output=True, text=True, cwd=tmp_path, check=False,
                          timeout=300)
    assert proc.returncode == EXIT_BAD_INPUT, proc.stderr
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    for word in ("sse-cosim: --set network.net_file=gone.net.xml: network.net_file: "
                 f"'{tmp_path / 'gone.net.xml'}' not found",
                 "given with --set, relative to the working directory"):
        assert word in lines[0], (word, lines[0])


def test_the_documented_parking_strip_is_accepted(town, tmp_path):
    """docs/own_network.md's patch adds a parking strip to the converted net: the truck the
    first case refuses stands there, and the bus keeps its route."""
    text = (ROOT / "docs" / "own_network.md").read_text(encoding="utf-8")
    start = text.index("  cat > strip.edg.xml")
    block = textwrap.dedent(text[start:text.index("  ```", start)])
    (tmp_path / "map.net.xml").write_bytes(town.read_bytes())
    script = block.replace("netconvert ", f"{netconvert_path()} ", 1)
    subprocess.run(["bash", "-ec", script], cwd=tmp_path, check=True, capture_output=True,
                   timeout=120)
    net = tmp_path / "map_strip.net.xml"
    body = ('[parked.truck]\npresent = true\nedge = "10#0"\nlane_index = 1\n'
            "end_pos_m = 60.0\n")
    path = scenario(tmp_path, net, body)
    from sse_cosim.scenario.loader import load_scenario
    from sse_cosim.world.demand import plan_actors

    plan = plan_actors(load_scenario(path), net, load_roadmap(net), str(path))
    assert plan.automated_lanes["bus"].index == 2
