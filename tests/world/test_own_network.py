"""A scenario's own network: an existing .net.xml (``network.net_file``) as the alternative to
plain-XML sources, its route files (``network.route_files``), and the checks that refuse what
would not run or not be deterministic -- one line naming the field and the fix."""

from __future__ import annotations

import gzip
import shutil
from pathlib import Path

import pytest
from world_helpers import REPO, SOURCES_DIR

from sse_cosim.errors import UserError
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.scenario.model import Network
from sse_cosim.world.network import build_network, scenario_net_path
from sse_cosim.world.roadmap import load_roadmap, require_pedestrian_ground
from sse_cosim.world.route_files import read_route_files

GIVEN = REPO / "tests" / "networks" / "given_net"
GIVEN_NET = GIVEN / "road.net.xml"
GIVEN_SCENARIO = GIVEN / "scenario.toml"
S1 = REPO / "scenarios" / "s1_pedestrian.toml"
JUNCTION = REPO / "sumo_net" / "junction"
RESERVED = ("bus", "truck", "car", "pedestrian")


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def routes(body: str) -> str:
    return f'<?xml version="1.0" encoding="UTF-8"?>\n<routes>\n{body}\n</routes>\n'


DETERMINISTIC_CAR = '<vType id="cav" vClass="passenger" speedDev="0" sigma="0"/>'


# --- the schema and the loader -----------------------------------------------------------


def test_a_scenario_names_an_existing_net_and_route_files_relative_to_its_file() -> None:
    sc = load_scenario(GIVEN_SCENARIO)
    # the parent's sources_dir is replaced by the child's net_file, not kept beside it
    assert sc.network.sources_dir is None
    assert Path(sc.network.net_file) == GIVEN_NET
    assert [Path(p) for p in sc.network.route_files] == [GIVEN / "traffic.rou.xml"]


def test_without_either_the_default_sources_are_used() -> None:
    assert Network().sources_dir == "../sumo_net"
    assert Network().net_file is None


def test_one_file_setting_both_is_refused(tmp_path: Path) -> None:
    bad = write(tmp_path / "bad.toml", f'extends = "{S1.as_posix()}"\n[network]\n'
                'sources_dir = "x"\nnet_file = "y.net.xml"\n')
    with pytest.raises(UserError) as info:
        load_scenario(bad)
    assert info.value.field == "network.net_file"
    assert "keep one of them" in info.value.one_line()


def test_an_override_replaces_the_alternative() -> None:
    sc = load_scenario(S1, {"network.net_file": str(GIVEN_NET)})
    assert sc.network.sources_dir is None and sc.network.net_file == str(GIVEN_NET)
    back = load_scenario(GIVEN_SCENARIO, {"network.sources_dir": str(SOURCES_DIR)})
    assert back.network.net_file is None and back.network.sources_dir == str(SOURCES_DIR)


# --- the network file --------------------------------------------------------------------


def test_the_given_net_is_used_as_it_is_also_gzipped(tmp_path: Path) -> None:
    assert scenario_net_path(Network(net_file=str(GIVEN_NET)), "s") == GIVEN_NET
    packed = tmp_path / "road.net.xml.gz"
    packed.write_bytes(gzip.compress(GIVEN_NET.read_bytes()))
    assert scenario_net_path(Network(net_file=str(packed)), "s") == packed
    assert len(load_roadmap(packed).crossings) == 1


def test_the_given_net_is_the_road_built_from_the_sources() -> None:
    given, built = load_roadmap(GIVEN_NET), load_roadmap(build_network(SOURCES_DIR))
    assert [(c.id, c.area.bounds) for c in given.crossings] == \
        [(c.id, c.area.bounds) for c in built.crossings]
    assert given.edge_lengths == built.edge_lengths
    assert sorted(given.driving_lanes) == sorted(built.driving_lanes)
    assert given.sidewalks.equals(built.sidewalks)


@pytest.mark.parametrize(("content", "problem"), [
    (None, "not found"),
    ("this is no XML", "cannot be read"),
    ('<?xml version="1.0"?>\n<routes/>\n', "is no SUMO network"),
])
def test_a_bad_net_file_is_one_line_naming_the_field(tmp_path: Path, content: str | None,
                                                     problem: str) -> None:
    path = tmp_path / "x.net.xml"
    if content is not None:
        write(path, content)
    with pytest.raises(UserError) as info:
        scenario_net_path(Network(net_file=str(path)), "scenario.toml")
    line = info.value.one_line()
    assert info.value.source == "scenario.toml" and info.value.field == "network.net_file"
    assert problem in line and "network.net_file at a SUMO .net.xml" in line
    assert "\n" not in line


def test_a_network_without_crossings_is_refused_for_a_pedestrian(tmp_path: Path) -> None:
    sources = tmp_path / "no_crossings"
    sources.mkdir()
    for name in ("junction.nod.xml", "junction.edg.xml", "netconvert.cfg"):
        shutil.copy(JUNCTION / name, sources / name)  # sidewalks, but no zebra
    roadmap = load_roadmap(build_network(sources))
    assert roadmap.sidewalk_lanes and not roadmap.crossings
    with pytest.raises(UserError) as info:
        require_pedestrian_ground(roadmap, "s.toml", "network.net_file")
    line = info.value.one_line()
    assert line.startswith("s.toml: network.net_file: the network has no crossing")
    assert "--sidewalks.guess --crossings.guess" in line
    require_pedestrian_ground(load_roadmap(GIVEN_NET), "s.toml", "network.net_file")


# --- route files -------------------------------------------------------------------------


def test_deterministic_route_files_pass_with_their_types(tmp_path: Path) -> None:
    files = read_route_files([str(GIVEN / "traffic.rou.xml"),
                              str(JUNCTION / "traffic.rou.xml")], RESERVED, "s")
    assert files.type_ids == {"cav", "background", "walker"}
    assert files.paths == (GIVEN / "traffic.rou.xml", JUNCTION / "traffic.rou.xml")
    assert files.walked_edges == {"EC"}  # the walking person's one edge; no other person


WALKER = '<vType id="w" vClass="pedestrian" speedDev="0" sigma="0"/>'


@pytest.mark.parametrize(("persons", "walked"), [
    ('<person id="p" type="w" depart="0"><stop lane="WC_0" duration="5"/>'
     '<walk edges="WC CE"/></person><person id="q" type="w" depart="0">'
     '<param key="k" value="v"/><walk edges="EC"/></person>', {"WC", "CE", "EC"}),
    ('<person id="p" type="w" depart="0"><walk edges="WC CE"/></person>'
     '<person id="q" type="w" depart="0"><walk from="EC" to="CW"/></person>', None),
    ('<person id="p" type="w" depart="0"><personTrip from="WC" to="CE"/></person>', None),
    ('<person id="p" type="w" depart="0"><stop busStop="s" duration="5"/>'
     '<walk edges="WC"/></person>', None),
])
def test_the_edges_persons_walk_are_known_unless_sumo_routes_them(
        tmp_path: Path, persons: str, walked: set[str] | None) -> None:
    """Walks given edge by edge (and stops on an edge or lane) tell where a route file's
    persons walk; a walk SUMO routes, a person trip or a stop at a stop's id does not."""
    path = write(tmp_path / "walkers.rou.xml", routes(WALKER + persons))
    assert read_route_files([str(path)], RESERVED, "s").walked_edges == walked


@pytest.mark.parametrize(("body", "words"), [
    ('<vType id="cav" vClass="passenger" sigma="0"/>',
     ("vType 'cav' leaves it unset", 'set speedDev="0" and sigma="0"')),
    ('<vType id="cav" vClass="passenger" speedDev="0" sigma="0.5"/>',
     ("vType 'cav' sets sigma='0.5'", 'set speedDev="0" and sigma="0"')),
    ('<vehicle id="v" depart="0"><route edges="WC"/></vehicle>',
     ("vehicle 'v' names no type", "declare a vType")),
    (f'{DETERMINISTIC_CAR}<person id="p" type="walker" depart="0"><walk edges="WC"/></person>',
     ("person 'p' has type 'walker', which no route file declares",)),
    (f'{DETERMINISTIC_CAR}<vehicle id="bus" type="cav" depart="0"><route edges="WC"/>'
     '</vehicle>', ("vehicle id 'bus' is reserved", "rename it")),
    ('<vType id="truck" speedDev="0" sigma="0"/>', ("type id 'truck' is reserved",)),
    ('<vType id="w" vClass="pedestrian" speedDev="0" sigma="0"/><person id="p" type="w" '
     'depart="5"><walk edges="WC"/></person>', ("person 'p' departs at '5', not at 0",
                                                 'set depart="0"')),
    ('<personFlow id="pf" begin="0" end="60" period="10"/>', ("personFlow 'pf' departs",)),
])
def test_a_route_file_that_is_not_deterministic_is_refused_naming_file_and_type(
        tmp_path: Path, body: str, words: tuple[str, ...]) -> None:
    path = write(tmp_path / "mine.rou.xml", routes(body))
    with pytest.raises(UserError) as info:
        read_route_files([str(path)], RESERVED, "s.toml")
    line = info.value.one_line()
    assert line.startswith(f"s.toml: network.route_files: {path}: ")
    for word in words:
        assert word in line, (word, line)


@pytest.mark.parametrize(("content", "problem"), [
    (None, "not found"), ("<routes>", "cannot be read"), ("<net/>", "is no SUMO route file"),
])
def test_a_missing_or_unreadable_route_file_is_refused(tmp_path: Path, content: str | None,
                                                       problem: str) -> None:
    path = tmp_path / "r.rou.xml"
    if content is not None:
        write(path, content)
    with pytest.raises(UserError) as info:
        read_route_files([str(path)], RESERVED, "s.toml")
    assert info.value.field == "network.route_files" and problem in info.value.problem
