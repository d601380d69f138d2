"""The pure road map read from the built network."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely

from sse_cosim.errors import UserError
from sse_cosim.world.roadmap import load_roadmap


def test_crossing(net_path: Path) -> None:
    (crossing,) = load_roadmap(net_path).crossings
    assert crossing.area.bounds == pytest.approx((198.0, -6.0, 202.0, 6.0))
    assert crossing.area.area == pytest.approx(48.0)
    assert (crossing.id, crossing.node) == (":C_c0", "C")


def test_sidewalks_include_walking_areas(net_path: Path) -> None:
    sidewalks = load_roadmap(net_path).sidewalks
    for x, y in ((186.0, -7.0), (200.0, -7.0), (200.0, 7.0), (250.0, 7.5), (10.0, -6.5)):
        assert sidewalks.contains(shapely.Point(x, y)), (x, y)
    for x, y in ((100.0, -3.0), (200.0, 0.0), (190.0, -5.0)):
        assert not sidewalks.contains(shapely.Point(x, y)), (x, y)
    assert sidewalks.area == pytest.approx(2 * 2.0 * 300.0)


def test_lanes_and_lengths(net_path: Path) -> None:
    roadmap = load_roadmap(net_path)
    assert set(roadmap.driving_lanes) == {"WC_2", "CE_2", "EC_2", "CW_2"}
    assert set(roadmap.parking_lanes) == {"WC_1", "CE_1", "EC_1", "CW_1"}
    assert roadmap.edge_lengths == pytest.approx({"WC": 198.0, "CE": 98.0, "EC": 98.0, "CW": 198.0})
    wc = roadmap.driving_lanes["WC_2"]
    assert wc.shape.shape == (2, 2)
    assert wc.shape == pytest.approx(np.array([[0.0, -1.75], [198.0, -1.75]]))
    assert (wc.width, wc.length) == pytest.approx((3.5, 198.0))
    assert roadmap.route_length(["WC", "CE"]) == pytest.approx(300.0)
    line = roadmap.route_line(["WC", "CE"])
    assert line.length == pytest.approx(300.0)
    assert np.asarray(line.coords)[[0, -1]] == pytest.approx(np.array([[0, -1.75], [300, -1.75]]))
    assert line.project(shapely.Point(200.0, -1.75)) == pytest.approx(200.0)
    west = roadmap.route_line(["EC", "CW"])
    assert np.asarray(west.coords)[[0, -1]] == pytest.approx(np.array([[300, 1.75], [0, 1.75]]))
    assert roadmap.lane_polygon("WC_1").bounds == pytest.approx((0.0, -6.0, 198.0, -3.5))


def test_cached_per_path(net_path: Path) -> None:
    assert load_roadmap(net_path) is load_roadmap(str(net_path))


def test_missing_net(tmp_path: Path) -> None:
    with pytest.raises(UserError, match="network file not found"):
        load_roadmap(tmp_path / "none.net.xml")
