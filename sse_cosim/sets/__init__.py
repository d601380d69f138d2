"""Pure-math set library: zonotopes, strips, Propositions 1 and 2 of the paper.

See ``docs/method.md`` for the map from the paper's equations to these functions.
"""

from sse_cosim.sets.fusion import (
    FUSION_METHODS,
    available_fusion_methods,
    fuse,
    fuse_with_weights,
)
from sse_cosim.sets.gains import (
    CORRECTION_METHODS,
    GAIN_METHODS,
    apply_gain,
    available_gain_methods,
    intersect_block_strips,
    intersect_strips,
)
from sse_cosim.sets.overlap import (
    have_common_point,
    projection_interval,
    strip_covers,
    strip_disjoint,
    zonotopes_disjoint,
)
from sse_cosim.sets.reduction import REDUCTION_METHODS
from sse_cosim.sets.strips import Strips, zonotope_facet_strips
from sse_cosim.sets.zonotope import Zonotope

__all__ = [
    "CORRECTION_METHODS",
    "FUSION_METHODS",
    "GAIN_METHODS",
    "REDUCTION_METHODS",
    "Strips",
    "Zonotope",
    "apply_gain",
    "available_fusion_methods",
    "available_gain_methods",
    "fuse",
    "fuse_with_weights",
    "have_common_point",
    "intersect_block_strips",
    "intersect_strips",
    "projection_interval",
    "strip_covers",
    "strip_disjoint",
    "zonotope_facet_strips",
    "zonotopes_disjoint",
]
