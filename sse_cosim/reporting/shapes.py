"""Geometry as the output files store it: the polygons a region is made of."""

from __future__ import annotations

import shapely


def polygon_parts(geometry: shapely.Geometry) -> list[shapely.Polygon]:
    """The non-empty polygons in ``geometry``, at any depth of nesting (lines and points hold
    no area and are left out)."""
    if isinstance(geometry, shapely.Polygon):
        return [] if geometry.is_empty else [geometry]
    if isinstance(geometry, shapely.MultiPolygon | shapely.GeometryCollection):
        return [p for part in shapely.get_parts(geometry) for p in polygon_parts(part)]
    return []
