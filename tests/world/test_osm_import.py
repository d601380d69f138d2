"""The OpenStreetMap import documented in docs/own_network.md works: the command, read from the
document, converts a tiny hand-written extract (tests/networks/osm/tiny.osm) into a network
with sidewalks, a zebra on each of its four arms and walking areas; without guessing, the same
extract has none, and a scenario with a pedestrian is refused on it."""

from __future__ import annotations

import shlex
import subprocess
from pathlib import Path

import pytest
import shapely
from world_helpers import REPO

from sse_cosim.errors import UserError
from sse_cosim.scenario.model import Network
from sse_cosim.world.network import netconvert_path, scenario_net_path
from sse_cosim.world.roadmap import load_roadmap, require_pedestrian_ground

DOC = REPO / "docs" / "own_network.md"
OSM = REPO / "tests" / "networks" / "osm" / "tiny.osm"


def documented_command(start: str = "netconvert --osm-files") -> list[str]:
    """The command of docs/own_network.md that starts with ``start``, as arguments."""
    text = DOC.read_text(encoding="utf-8").replace("\\\n", " ")
    line = next(ln for ln in text.splitlines() if ln.startswith(start))
    return shlex.split(line)


def convert(tmp_path: Path, args: list[str], inputs: dict[str, Path] | None = None) -> Path:
    """Run netconvert with ``args`` (the document's file names replaced by ``inputs``, the
    tiny extract by default); the converted net."""
    out = tmp_path / "out.net.xml"
    files = {"map.osm": OSM, **(inputs or {}), "map.net.xml": out, "new.net.xml": out}
    args = [str(files[a]) if a in files else a for a in args]
    result = subprocess.run([str(netconvert_path()), *args[1:]], capture_output=True,
                            text=True, timeout=120, check=False, cwd=tmp_path)
    assert result.returncode == 0 and out.is_file(), result.stdout + result.stderr
    return out


def test_the_documented_command_yields_sidewalks_and_a_zebra_on_every_arm(
        tmp_path: Path) -> None:
    args = documented_command()
    assert {"--sidewalks.guess", "--crossings.guess", "map.osm", "map.net.xml"} <= set(args)
    net = scenario_net_path(Network(net_file=str(convert(tmp_path, args))), "osm")
    roadmap = load_roadmap(net)
    assert len(roadmap.crossings) == 4
    assert len({c.node for c in roadmap.crossings}) == 1  # all at the one junction
    assert len(roadmap.sidewalk_lanes) == 8 and len(roadmap.driving_lanes) == 8
    # sidewalks, walking areas and zebras form one walkable ground (up to the millimetre
    # seams netconvert leaves between the lanes of a projected map)
    walkable = shapely.union_all([roadmap.sidewalks.buffer(0.01), roadmap.crossing_area])
    assert walkable.geom_type == "Polygon"
    require_pedestrian_ground(roadmap, "osm", "network.net_file")


def test_without_guessing_the_extract_has_no_ground_for_a_pedestrian(tmp_path: Path) -> None:
    args = [a for a in documented_command() if a not in ("--sidewalks.guess",
                                                         "--crossings.guess")]
    roadmap = load_roadmap(convert(tmp_path, args))
    assert not roadmap.crossings and not roadmap.sidewalk_lanes
    with pytest.raises(UserError, match="no sidewalk and no crossing"):
        require_pedestrian_ground(roadmap, "osm", "network.net_file")
    # the document's fix: netconvert completes the converted net
    plain = roadmap.net_path.rename(tmp_path / "old.net.xml")
    fixed = load_roadmap(convert(tmp_path, documented_command("netconvert --sumo-net-file"),
                                 {"old.net.xml": plain}))
    assert len(fixed.crossings) == 4 and len(fixed.sidewalk_lanes) == 8
