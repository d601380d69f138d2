"""Regions: where someone may be and what is seen, behind one protocol (:mod:`.base`).

A representation is one module here, registered by one entry in :data:`KINDS`:

- ``polygon`` (:mod:`.polygon`): exact shapely polygons, the reference.
- ``raster`` (:mod:`.raster`): cells of one global grid, sound in the direction asked.
"""

from __future__ import annotations

from sse_cosim.regions.base import Region, RegionKind, apart
from sse_cosim.regions.polygon import PolygonKind, PolygonRegion
from sse_cosim.regions.raster import RasterKind

KINDS: dict[str, RegionKind] = {kind.name: kind for kind in (PolygonKind(), RasterKind())}
DEFAULT_KIND = "polygon"


def kind(name: str = DEFAULT_KIND) -> RegionKind:
    """The representation registered as ``name``."""
    if name not in KINDS:
        raise ValueError(f"unknown region kind {name!r}; use one of {', '.join(KINDS)}")
    return KINDS[name]


__all__ = ["DEFAULT_KIND", "KINDS", "PolygonKind", "PolygonRegion", "Region", "RegionKind",
           "apart", "kind"]
