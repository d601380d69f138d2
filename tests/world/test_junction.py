"""The four-arm junction (sumo_net/junction/): it builds, has a zebra on every arm joined by
walking areas at the four corners, and its background traffic runs in SUMO."""

from __future__ import annotations

import subprocess
from pathlib import Path
from xml.etree import ElementTree

import pytest
import shapely
from world_helpers import REPO

from sse_cosim.world.network import build_network, netconvert_path
from sse_cosim.world.roadmap import RoadMap, load_roadmap
from sse_cosim.world.route_files import read_route_files

JUNCTION = REPO / "sumo_net" / "junction"
ARMS = {"W": (-1.0, 0.0), "E": (1.0, 0.0), "S": (0.0, -1.0), "N": (0.0, 1.0)}
ARM_LENGTH_M = 180.0


@pytest.fixture(scope="module")
def net_path() -> Path:
    return build_network(JUNCTION)


@pytest.fixture(scope="module")
def roadmap(net_path: Path) -> RoadMap:
    return load_roadmap(net_path)


def test_every_arm_has_a_zebra(roadmap: RoadMap) -> None:
    assert len(roadmap.crossings) == 4
    assert {c.node for c in roadmap.crossings} == {"J"}
    arms = set()
    for crossing in roadmap.crossings:
        centre = crossing.area.centroid
        # the zebra lies on one arm: off the centre along that arm's axis, on it across
        arm = next(a for a, (dx, dy) in ARMS.items()
                   if centre.x * dx + centre.y * dy > 2.0
                   and abs(centre.x * dy - centre.y * dx) < 1e-6)
        arms.add(arm)
        assert crossing.area.area == pytest.approx(4.0 * 7.0)  # 4 m wide, over both lanes
    assert arms == set(ARMS)


def test_the_corners_join_sidewalks_and_zebras(roadmap: RoadMap) -> None:
    assert len(roadmap.sidewalk_lanes) == 8  # one per edge, both directions of four arms
    assert len(roadmap.edge_lengths) == 8
    assert all(length == pytest.approx(ARM_LENGTH_M, abs=10.0)
               for length in roadmap.edge_lengths.values())
    # four walkable corners, each touching two zebras: one can walk around the junction
    corners = list(roadmap.sidewalks.geoms)
    assert len(corners) == 4
    for corner in corners:
        touching = [c for c in roadmap.crossings if corner.buffer(0.05).intersects(c.area)]
        assert len(touching) == 2
    walkable = shapely.union_all([roadmap.sidewalks.buffer(1e-6), roadmap.crossing_area])
    assert walkable.geom_type == "Polygon"


def test_vehicles_pass_in_every_direction(roadmap: RoadMap) -> None:
    ins = ("WJ", "EJ", "SJ", "NJ")
    outs = ("JW", "JE", "JS", "JN")
    turns = {(a, b) for a in ins for b in outs if a[0] != b[1]}
    assert set(roadmap.lane_links) == turns


def test_the_background_traffic_is_deterministic() -> None:
    files = read_route_files([str(JUNCTION / "traffic.rou.xml")],
                             ("bus", "truck", "car", "pedestrian"), "junction")
    assert files.type_ids == {"background"}


@pytest.mark.sumo
def test_the_background_traffic_runs(net_path: Path, tmp_path: Path) -> None:
    sumo = netconvert_path().with_name("sumo")
    result = subprocess.run(
        [str(sumo), "-n", str(net_path), "-r", str(JUNCTION / "traffic.rou.xml"), "--end", "300",
         "--no-step-log", "--duration-log.statistics", "--time-to-teleport", "-1",
         "--collision.action", "warn", "--seed", "1"],
        capture_output=True, text=True, timeout=120, check=False, cwd=tmp_path)
    log = result.stdout + result.stderr
    assert result.returncode == 0, log
    assert "Error" not in log and "Warning: Vehicle" not in log, log
    inserted = next(line for line in log.splitlines() if "Inserted:" in line)
    assert int(inserted.split()[1]) == _departures_before(JUNCTION / "traffic.rou.xml", 300.0)


def _departures_before(route_file: Path, end_s: float) -> int:
    """How many vehicles the route file's periodic flows send off before ``end_s``."""
    flows = ElementTree.parse(route_file).getroot().iter("flow")
    return sum(len(range(int(float(f.get("begin"))), int(min(end_s, float(f.get("end")))),
                         int(float(f.get("period"))))) for f in flows)
