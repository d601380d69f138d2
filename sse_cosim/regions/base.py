"""The Region protocol: every "where can someone be" and "what is seen" set of the estimator
and the controller, in network coordinates (m), whatever represents it.

A representation is a :class:`RegionKind` (how regions are made from shapes) and its
:class:`Region` values (what can be done with them). Every layer above the sensors' own
geometry speaks this protocol; a new representation is one module of :mod:`sse_cosim.regions`.

Soundness contract (closed sets; ``exact`` is the set a region stands for):

- A region made with :meth:`RegionKind.outer` contains its shape; one made with
  :meth:`RegionKind.inner` lies inside it. A representation may approximate (a raster), but
  only in the direction asked for: "where may someone be" is built ``outer``, "seen clear"
  ``inner``.
- :meth:`Region.dilate` contains ``exact (+) disc(d)`` (every point within d);
  :meth:`Region.erode` lies inside ``{p : disc(p, d) ⊆ exact}``. This is the only dilation
  anywhere above the sensors: no layer widens a shape any other way.
- ``a.union(b)``, ``a.intersection(b)`` keep the direction of both operands; ``a.difference(b)``
  of an outer ``a`` and an inner ``b`` is outer (less is removed than may be).
- The predicates are exact on the representation: ``covers``, ``intersects``,
  ``contains_points``, ``distance``, ``area`` answer for the region as represented.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Protocol, runtime_checkable

import numpy as np
import shapely


@runtime_checkable
class Region(Protocol):
    """An immutable planar set (m) of one representation. Operations between regions take
    regions of the same kind."""

    @property
    def is_empty(self) -> bool: ...

    @property
    def area(self) -> float:
        """Area (m²)."""
        ...

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1); (0, 0, -1, -1) for an empty region."""
        ...

    def union(self, other: Region) -> Region: ...

    def intersection(self, other: Region) -> Region: ...

    def difference(self, other: Region) -> Region: ...

    def dilate(self, distance: float) -> Region:
        """A region containing self (+) disc(distance) (self for distance <= 0)."""
        ...

    def erode(self, distance: float) -> Region:
        """A region inside {p : disc(p, distance) ⊆ self} (self for distance <= 0)."""
        ...

    def coarsen(self, tolerance: float) -> Region:
        """A region containing self, within a few times ``tolerance`` of it (each kind says
        how far), simpler to compute with (fewer vertices or cells; may be self)."""
        ...

    def covers(self, other: Region) -> bool:
        """Whether every point of ``other`` is in self (closed)."""
        ...

    def intersects(self, other: Region) -> bool:
        """Whether self and ``other`` share a point (closed)."""
        ...

    def contains_points(self, points: np.ndarray) -> np.ndarray:
        """Whether each point (n, 2) lies in self (closed), shape (n,) of bool."""
        ...

    def distance(self, other: Region) -> float:
        """The least distance between a point of self and one of ``other`` (m; 0 if they meet;
        inf if either is empty)."""
        ...

    def support(self, directions: np.ndarray) -> np.ndarray:
        """max over the region of n.x for each direction n of ``directions`` (K, 2), shape
        (K,); -inf for an empty region."""
        ...

    def hull_points(self) -> np.ndarray:
        """Points (k, 2) whose convex hull contains the region ((0, 2) if empty)."""
        ...

    def geometry(self) -> shapely.Geometry:
        """The region as shapely polygons (for outputs, plots and checks); contains the
        region for an approximating representation."""
        ...

    def parts(self) -> list[Region]:
        """Its connected pieces (none if empty), whose union is the region."""
        ...

    def same(self, other: Region) -> bool:
        """Whether ``other`` is represented exactly as self is (every coordinate or cell the
        same): then every operation gives both the same result."""
        ...


class RegionKind(Protocol):
    """How one representation makes regions."""

    name: str

    def outer(self, shape: shapely.Geometry) -> Region:
        """A region containing ``shape`` (where someone may be)."""
        ...

    def inner(self, shape: shapely.Geometry) -> Region:
        """A region inside ``shape`` (what is seen clear)."""
        ...

    def empty(self) -> Region: ...

    def reach_of(self, distance: float) -> float:
        """How far from a region a point of its :meth:`Region.dilate` by ``distance`` may lie
        (>= distance): bounding boxes grown by it hold the dilation."""
        ...

    def union_all(self, regions: Iterable[Region]) -> Region:
        """The union of ``regions`` (empty if none)."""
        ...

    def union_apart(self, regions: Sequence[Region]) -> Region:
        """The union of ``regions`` that share no point (each apart from the others): the
        same set as :meth:`union_all`, made without an overlay where the representation
        allows."""
        ...

    def convex_outer(self, points: np.ndarray) -> Region:
        """A region containing the convex hull of ``points`` (k, 2) (a zonotope's vertices)."""
        ...

    def distances(self, sources: Sequence[Region], targets: Sequence[Region]) -> np.ndarray:
        """Least distance of each source to each target, shape (s, t) (inf for empty ones)."""
        ...


def apart(first: Region, second: Region, margin: float = 0.0) -> bool:
    """Whether the bounding boxes of two regions are more than ``margin`` apart (or one is
    empty): then ``second`` misses ``first`` dilated by anything up to ``margin`` (with none,
    their intersection is empty and their difference ``first``)."""
    if first.is_empty or second.is_empty:
        return True
    a, b = first.bounds, second.bounds
    return (a[0] - margin > b[2] or b[0] > a[2] + margin
            or a[1] - margin > b[3] or b[1] > a[3] + margin)
