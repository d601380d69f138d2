"""netconvert builds the road from sumo_net/, with the agreed geometry, and caches it."""

from __future__ import annotations

import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from world_helpers import SOURCES_DIR

from sse_cosim.errors import UserError
from sse_cosim.world import network
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap

EDGES = ("WC", "CE", "EC", "CW")
WIDTHS = (2.0, 2.5, 3.5)


def _net(net_path: Path) -> ET.Element:
    return ET.parse(net_path).getroot()


def _copy_sources(tmp_path: Path) -> Path:
    dst = tmp_path / "sumo_net"
    dst.mkdir()
    for src in SOURCES_DIR.iterdir():
        if src.is_file():
            shutil.copy(src, dst / src.name)
    return dst


def test_nodes_keep_their_coordinates(net_path: Path) -> None:
    root = _net(net_path)
    assert root.find("location").get("netOffset") == "0.00,0.00"
    junctions = {j.get("id"): (float(j.get("x")), float(j.get("y"))) for j in root.iter("junction")}
    assert junctions["W"] == (0.0, 0.0)
    assert junctions["C"] == (200.0, 0.0)
    assert junctions["E"] == (300.0, 0.0)


def test_cross_section_of_every_edge(net_path: Path) -> None:
    root = _net(net_path)
    edges = {e.get("id"): e for e in root.iter("edge") if e.get("function") is None}
    assert set(edges) == set(EDGES)
    for edge_id, edge in edges.items():
        lanes = edge.findall("lane")
        assert [float(ln.get("width")) for ln in lanes] == list(WIDTHS), edge_id
        assert [ln.get("allow") for ln in lanes[:2]] == ["pedestrian", "custom1"], edge_id
        driving = lanes[2].get("allow").split()
        assert {"bus", "passenger"} <= set(driving) and "pedestrian" not in driving
        assert all(float(ln.get("speed")) >= 25.0 for ln in lanes[1:]), edge_id


def test_lane_positions(net_path: Path) -> None:
    roadmap = load_roadmap(net_path)
    expected = {0: (-8.0, -6.0), 1: (-6.0, -3.5), 2: (-3.5, 0.0)}
    for edge_id, sign in (("WC", 1), ("CE", 1), ("EC", -1), ("CW", -1)):
        for index, (lo, hi) in expected.items():
            _, ymin, _, ymax = roadmap.lane_polygon(f"{edge_id}_{index}").bounds
            want = (lo, hi) if sign > 0 else (-hi, -lo)
            assert (ymin, ymax) == pytest.approx(want, abs=1e-6), f"{edge_id}_{index}"


def test_priority_crossing_and_walking_areas(net_path: Path) -> None:
    root = _net(net_path)
    crossings = [e for e in root.iter("edge") if e.get("function") == "crossing"]
    assert len(crossings) == 1
    crossing = crossings[0]
    assert set(crossing.get("crossingEdges").split()) == {"WC", "CW"}
    walking = {e.get("id") for e in root.iter("edge") if e.get("function") == "walkingarea"}
    assert {":C_w0", ":C_w1"} <= walking
    conns = list(root.iter("connection"))
    # pedestrians have the right of way on the crossing ("M" = major) ...
    onto = [c for c in conns if c.get("to") == crossing.get("id")]
    assert onto and all(c.get("state") == "M" for c in onto)
    # ... and vehicles over it yield ("m" = minor), both directions
    for a, b in (("WC", "CE"), ("EC", "CW")):
        states = {c.get("state") for c in conns if (c.get("from"), c.get("to")) == (a, b)}
        assert states == {"m"}, (a, b)


def test_cache_is_reused_and_rebuilt_on_change(tmp_path: Path) -> None:
    sources = _copy_sources(tmp_path)
    first = build_network(sources)
    stamp = first.stat().st_mtime_ns
    assert build_network(sources) == first
    assert first.stat().st_mtime_ns == stamp
    edg = sources / "road.edg.xml"
    edg.write_text(edg.read_text().replace('speed="27.78"', 'speed="30.00"'))
    second = build_network(sources)
    assert second != first and second.is_file()
    assert 'speed="30.00"' in second.read_text()
    assert first.is_file()  # the old build stays (another run may still use it)
    assert not list((sources / "build").glob(".*.part"))  # no half-built leftovers


def test_netconvert_failure_names_folder_and_error(tmp_path: Path) -> None:
    sources = _copy_sources(tmp_path)
    (sources / "road.edg.xml").write_text(
        (sources / "road.edg.xml").read_text().replace('to="C"', 'to="NOPE"', 1))
    with pytest.raises(UserError) as info:
        build_network(sources)
    text = str(info.value)
    assert str(sources) in text and "netconvert failed" in text and "Error" in text
    assert "NOPE" in text
    assert not (sources / "build").exists() or not any(
        p.name.endswith(".part") for p in (sources / "build").iterdir())


def test_missing_sources(tmp_path: Path) -> None:
    with pytest.raises(UserError, match="does not exist"):
        build_network(tmp_path / "nowhere")
    sources = _copy_sources(tmp_path)
    (sources / "road.nod.xml").unlink()
    with pytest.raises(UserError, match=r"no \*\.nod\.xml file") as info:
        build_network(sources)
    assert str(sources) in str(info.value)


def test_missing_netconvert(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    import sumo

    monkeypatch.setattr(sumo, "SUMO_HOME", str(tmp_path))
    monkeypatch.delenv("SUMO_HOME", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(UserError, match="netconvert was not found") as info:
        network.netconvert_path()
    assert "pip install eclipse-sumo" in str(info.value)
