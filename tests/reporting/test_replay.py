"""The replay's compact data (no SUMO, no browser): polygons in centimetres stored once, strip
bands, the page's embedding, and the choice of a run's key moments."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
import shapely

from sse_cosim.control.speed import SpeedLevel
from sse_cosim.reporting.paper import RunFolder, replay_links
from sse_cosim.reporting.recorder import KeyMoments
from sse_cosim.reporting.replay import (
    DATA_MARK,
    POLYGONS_MARK,
    REPLAY,
    PolygonPool,
    ReplayLog,
    _band,
    replay_page,
)
from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap

ROOT = Path(__file__).resolve().parents[2]
SOURCES, SCENARIO = ROOT / "sumo_net", ROOT / "scenarios" / "s3_pedestrian.toml"


def points(ring: list[int]) -> np.ndarray:
    """An encoded ring's points in m, shape (k, 2), as the page decodes them."""
    return np.cumsum(np.reshape(ring, (-1, 2)), axis=0) / 100.0


def polygon(rings: list[list[int]]) -> shapely.Polygon:
    return shapely.Polygon(points(rings[0]), [points(hole) for hole in rings[1:]])


def decoded(pool: PolygonPool, index: int) -> list[np.ndarray]:
    """Polygon ``index``'s rings in m, each shape (k, 2)."""
    return [points(ring) for ring in pool.rings(index)]


def test_a_polygon_with_a_hole_comes_back_to_the_centimetre():
    outer = shapely.box(183.123, -7.6049, 190.0, -1.0)
    region = outer.difference(shapely.box(185.0, -5.0, 186.0, -4.0))
    pool = PolygonPool()
    (index,) = pool.add(region)
    exterior, hole = decoded(pool, index)
    back = shapely.Polygon(exterior, [hole])
    assert back.symmetric_difference(region).area < 0.01 * region.length
    assert np.abs(exterior - shapely.get_coordinates(region.exterior)[:-1]).max() <= 0.005


def test_equal_geometry_is_stored_once_and_lines_hold_no_area():
    pool = PolygonPool()
    parts = shapely.MultiPolygon([shapely.box(0, 0, 1, 1), shapely.box(2, 0, 3, 1)])
    first = pool.add(parts)
    assert pool.add(shapely.box(2, 0, 3, 1)) == [first[1]]
    assert pool.add(shapely.box(0, 0, 1, 1.001)) == [first[0]]  # the same to the centimetre
    assert pool.add(shapely.LineString([(0, 0), (1, 1)])) == []
    assert pool.add(None) == pool.add(shapely.Polygon()) == []
    assert len(pool.polygons) == 2


def test_zonotope_vertices_keep_their_order():
    vertices = np.array([[0.0, 0.0], [2.0, 0.5], [2.5, 2.0], [0.5, 1.5]])
    pool = PolygonPool()
    (ring,) = decoded(pool, pool.add_vertices(vertices))
    np.testing.assert_allclose(ring, vertices)


@pytest.mark.parametrize("normal", [np.array([1.0, 0.0]), np.array([0.6, -1.3])])
def test_a_band_is_its_strip_inside_the_box(normal):
    box = shapely.box(-10, -10, 10, 10)
    band = shapely.Polygon(_band(normal, 2.0, 0.5, box.bounds))
    grid = np.stack(np.meshgrid(np.linspace(-9.9, 9.9, 60), np.linspace(-9.9, 9.9, 60)), -1)
    points = grid.reshape(-1, 2)
    gap = np.abs(points @ normal - 2.0) - 0.5
    inside = shapely.contains_xy(band, points[:, 0], points[:, 1])
    assert inside[gap < -1e-6].all() and not inside[gap > 1e-6].any()
    assert (gap < -1e-6).any()
    assert band.within(box.buffer(1e-9))


def test_the_page_holds_the_data_and_the_map_and_nothing_ends_its_scripts_early():
    title = "a </script><script>alert(1)</script>"
    roadmap = load_roadmap(build_network(SOURCES))
    page = replay_page(ReplayLog(), load_scenario(SCENARIO), roadmap, title)
    assert DATA_MARK not in page and POLYGONS_MARK not in page
    scripts = dict(re.findall(r'<script id="(replay-\w+)" type="application/json">(.*?)</script>',
                              page, re.S))
    data, polygons = json.loads(scripts["replay-data"]), json.loads(scripts["replay-polygons"])
    assert (data["title"], data["frames"], data["automated"]) == (title, [], ["bus"])
    walkable = shapely.union_all([polygon(polygons[i]) for i in data["walkable"]])
    assert walkable.symmetric_difference(roadmap.walkable).area < 0.01 * roadmap.walkable.length


def test_key_moments_are_firsts_except_the_closest_approach():
    moments = KeyMoments()
    steps = [  # level, distance, detected, shared fusion
        (SpeedLevel.NOMINAL, None, False, False),
        (SpeedLevel.NOMINAL, 30.0, True, False),
        (SpeedLevel.SLOW, 20.0, True, True),
        (SpeedLevel.NOMINAL, 25.0, True, False),
        (SpeedLevel.SLOW, 10.0, False, False),
        (SpeedLevel.STOP, 12.0, False, False),
    ]
    due = [moments.due(*step) for step in steps]
    assert due == [
        ["start"],
        ["first detection", "closest approach"],
        ["first shared fusion", "first slow-down", "closest approach"],
        [],
        ["closest approach"],  # a second slow-down is not a first one
        ["first stop"],
    ]


def test_a_run_that_starts_slow_has_no_slow_down():
    moments = KeyMoments()
    assert moments.due(SpeedLevel.STOP, None, False, False) == ["start", "first stop"]
    assert moments.due(SpeedLevel.SLOW, None, False, False) == []


def test_table1_links_each_runs_replay_relative_to_the_table(tmp_path):
    """The batch's Table I names every run's replay.html by its path from the table's folder;
    a run that kept none (summaries only) gets no link."""
    with_page, without = tmp_path / "runs" / "s1_pedestrian", tmp_path / "runs" / "s2_pedestrian"
    for folder in (with_page, without):
        folder.mkdir(parents=True)
    (with_page / REPLAY).write_text("<html></html>", encoding="utf-8")
    runs = [RunFolder(with_page, {"scenario": "S1", "pedestrian": True}, {}),
            RunFolder(without, {"scenario": "S2", "pedestrian": True}, {})]
    text = replay_links(runs, tmp_path)
    assert "[S1 with pedestrian](runs/s1_pedestrian/replay.html)" in text
    assert "S2" not in text
    assert replay_links(runs[1:], tmp_path) == ""


def test_a_strip_that_misses_the_box_draws_no_band_and_one_over_it_draws_the_box():
    box = (-10.0, -10.0, 10.0, 10.0)
    assert len(_band(np.array([0.6, -1.3]), 40.0, 0.5, box)) == 0
    whole = shapely.Polygon(_band(np.array([1.0, 0.0]), 0.0, 50.0, box))
    assert whole.equals(shapely.box(*box))
    assert len(_band(np.array([1.0, 0.0]), 0.0, 1.0, None)) == 0
