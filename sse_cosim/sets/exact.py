"""Exact 2-D reference sets as shapely geometries (tests and the reference filter).

Geometries are convex: a Polygon, or a LineString / Point for degenerate sets.
"""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import ArrayLike
from shapely.geometry import MultiPoint, Polygon
from shapely.geometry.base import BaseGeometry

from sse_cosim.sets import portable
from sse_cosim.sets.portable import matmul
from sse_cosim.sets.strips import Strips
from sse_cosim.sets.zonotope import Zonotope


def zonotope_polygon(zonotope: Zonotope) -> BaseGeometry:
    """The 2-D zonotope as a Polygon, or a LineString / Point when degenerate.

    ``vertices()`` are already the convex polygon's corners in order, so a full-dimensional
    set needs no hull; a degenerate one has at most two distinct vertices.
    """
    vertices = zonotope.vertices()
    if len(vertices) >= 3:
        return Polygon(vertices)
    return MultiPoint(vertices).convex_hull


def predict_exact(geometry: BaseGeometry, state_matrix: ArrayLike, noise: Zonotope) -> BaseGeometry:
    """F·P ⊕ Q: convex hull of F v + q over the vertices v of P and q of Q (F (2, 2))."""
    f = np.asarray(state_matrix, dtype=np.float64)
    mapped = matmul(shapely.get_coordinates(geometry), f.T)
    sums = mapped[:, None, :] + noise.vertices()[None, :, :]
    return MultiPoint(sums.reshape(-1, 2)).convex_hull


def _strip_polygon(
    normal: np.ndarray, value: float, radius: float, bounds: tuple[float, ...]
) -> Polygon:
    """{x : |hᵀx - y| <= r} cut to a rectangle covering the box ``bounds`` (x0, y0, x1, y1)."""
    norm = float(portable.hypot(normal[0], normal[1]))
    across = normal / norm
    along = np.array([-across[1], across[0]])
    mid = np.array([(bounds[0] + bounds[2]) / 2, (bounds[1] + bounds[3]) / 2])
    reach = float(portable.hypot(bounds[2] - bounds[0], bounds[3] - bounds[1])) + 1.0
    lo, hi = (value - radius) / norm, (value + radius) / norm
    t0 = matmul(along, mid)
    corners = [s * across + t * along for s, t in
               ((lo, t0 - reach), (hi, t0 - reach), (hi, t0 + reach), (lo, t0 + reach))]
    return Polygon(corners)


def intersect_strips_exact(geometry: BaseGeometry, strips: Strips) -> BaseGeometry:
    """P ∩ S_1 ∩ ... ∩ S_m, clipping P with each strip (possibly empty)."""
    result = geometry
    for normal, value, radius in zip(strips.normals, strips.values, strips.radii, strict=True):
        if result.is_empty:
            break
        result = result.intersection(_strip_polygon(normal, value, radius, result.bounds))
    return result
