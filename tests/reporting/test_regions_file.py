"""``regions.jsonl.gz``: the regions the controller used, checkable from outside the recorder.

The serialisation round trip is a fast unit test; the soundness re-check runs real SUMO and
reads the run folder only (``regions.jsonl.gz`` and ``trace.csv``), with shapely of its own.
"""

from __future__ import annotations

import gzip
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import shapely

from sse_cosim.reporting.outputs import (
    REGIONS,
    TRACE,
    TRUTH,
    RegionFile,
    region_line,
)
from sse_cosim.reporting.recorder import RegionRecord
from sse_cosim.runner.run import run_scenario_file

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
TOLERANCE_M = 1e-5  # coordinates are written to 1e-6 m


def polygons_of(polygons: list) -> list[shapely.Polygon]:
    """The polygons of one ``polygons`` field (rings: exterior first, then holes)."""
    return [shapely.Polygon(rings[0], rings[1:]) for rings in polygons]


def distance(polygons: list[shapely.Polygon], point: shapely.Point) -> float:
    """Distance from ``point`` to the union of ``polygons`` (inf if there are none)."""
    return float(np.min(shapely.distance(polygons, point))) if polygons else np.inf


def region_polygons(geometry: shapely.Geometry) -> list:
    """The ``polygons`` field of the line written for ``geometry``, read back."""
    return json.loads(region_line(RegionRecord(0.0, "unobserved", None, geometry, "bus")))[
        "polygons"]


def round_trip(geometry: shapely.Geometry) -> shapely.Geometry:
    polygons = region_polygons(geometry)
    return shapely.union_all(polygons_of(polygons))


def test_polygon_with_hole_keeps_its_hole():
    square = shapely.Polygon([(0, 0), (4, 0), (4, 4), (0, 4)], [[(1, 1), (2, 1), (2, 2)]])
    polygons = region_polygons(square)
    assert len(polygons) == 1 and len(polygons[0]) == 2  # exterior and one hole
    back = round_trip(square)
    assert back.area == pytest.approx(16 - 0.5)
    assert shapely.symmetric_difference(back, square).area < 1e-12
    assert not back.contains(shapely.Point(1.6, 1.3))  # inside the hole


def test_multipolygon_keeps_every_part():
    parts = shapely.MultiPolygon([shapely.box(0, 0, 1, 1), shapely.box(3, 0, 5, 2)])
    assert len(region_polygons(parts)) == 2
    assert shapely.symmetric_difference(round_trip(parts), parts).area < 1e-12


def test_empty_region_is_an_empty_list():
    assert region_polygons(shapely.Polygon()) == []
    assert region_polygons(shapely.GeometryCollection()) == []
    assert region_polygons(shapely.MultiPolygon()) == []


def test_collection_keeps_polygonal_parts_at_any_depth_and_drops_lines_and_points():
    inner = shapely.MultiPolygon([shapely.box(0, 0, 1, 1), shapely.box(2, 0, 3, 1)])
    collection = shapely.GeometryCollection([
        inner, shapely.LineString([(5, 5), (6, 6)]), shapely.Point(7, 7),
        shapely.GeometryCollection([shapely.box(10, 10, 12, 11)]), shapely.Polygon(),
    ])
    polygons = region_polygons(collection)
    assert len(polygons) == 3
    assert round_trip(collection).area == pytest.approx(collection.area) == pytest.approx(4.0)


def test_coordinates_are_rounded_to_a_micrometre():
    triangle = shapely.Polygon([(0.123456789, 0), (1, 0), (1, 2.000000449)])
    ring = region_polygons(triangle)[0][0]
    assert ring[0] == [0.123457, 0.0]
    assert ring[2] == [1.0, 2.0]
    assert ring[0] == ring[-1]  # closed


def test_a_polygon_written_at_the_step_before_is_written_as_it_was(tmp_path: Path):
    """The file writes a polygon it wrote at the step before from that step's text: the lines
    are each record's own, whatever repeats, comes back later, or moves by a rounding."""
    a, b = shapely.box(0, 0, 1, 1), shapely.box(5, 0, 6.25, 2)
    moved = shapely.box(5, 0, 6.25 + 1e-9, 2)  # the same once written to 1e-6 m
    steps = [[("unobserved", None, shapely.MultiPolygon([a, b]))],
             [("unobserved", None, shapely.MultiPolygon([a, moved])), ("refined", "p1", b)],
             [("unobserved", None, shapely.MultiPolygon([b, a])), ("refined", "p1", a)],
             [("unobserved", None, shapely.Polygon())]]
    records = [[RegionRecord(k / 10, kind, track, region, "bus") for kind, track, region in step]
               for k, step in enumerate(steps)]
    written = RegionFile(tmp_path / REGIONS)
    for step in records:
        written.add(step)
    written.finish()
    text = gzip.decompress((tmp_path / REGIONS).read_bytes()).decode()
    assert text == "".join(region_line(r) for step in records for r in step)
    lines = [json.loads(line) for line in text.splitlines()]
    assert [len(line["polygons"]) for line in lines] == [2, 2, 1, 2, 1, 0]
    assert lines[1]["polygons"][1] == lines[0]["polygons"][1]


@pytest.mark.sumo
@pytest.mark.parametrize("name", ["s1_pedestrian", "s2_pedestrian", "s3_pedestrian"])
def test_pedestrian_is_in_its_refined_region_or_the_unobserved_area(tmp_path, name):
    """At every step: the truth lies in its own track's refined region when it has one, and
    always in the union of the unobserved area and every refined region (the pedestrian's
    walk stays within the interest radius of the crossing, where the unobserved area is kept).
    """
    run_scenario_file(SCENARIOS / f"{name}.toml", tmp_path, plots=False)
    trace = pd.read_csv(tmp_path / TRACE)
    refined: dict[float, dict[str, list[shapely.Polygon]]] = {}
    unobserved: dict[float, list[shapely.Polygon]] = {}
    for text in gzip.decompress((tmp_path / REGIONS).read_bytes()).decode().splitlines():
        line = json.loads(text)
        t = round(line["t"], 6)
        if line["kind"] == "unobserved":
            assert line["track"] is None
            unobserved[t] = polygons_of(line["polygons"])
        else:
            assert line["kind"] == "refined"
            refined.setdefault(t, {})[line["track"]] = polygons_of(line["polygons"])
    assert sorted(unobserved) == sorted(round(t, 6) for t in trace["t"])  # one per step
    tracked = 0
    for row in pd.read_csv(tmp_path / TRUTH).itertuples():
        t = round(row.t, 6)
        truth = shapely.Point(row.x, row.y)
        own = refined.get(t, {}).get(row.pedestrian)
        if own is not None:
            tracked += 1
            assert distance(own, truth) <= TOLERANCE_M, (name, t, "refined")
        anywhere = unobserved[t] + [p for regions in refined.get(t, {}).values() for p in regions]
        assert distance(anywhere, truth) <= TOLERANCE_M, (name, t, "neither")
    assert tracked > 0, "the pedestrian is tracked at some step"
