"""The association's candidate test (rule R1) in one compiled call per prediction (numba,
cached on disk).

:func:`candidate_tests` tests one prediction's path set against every detection of the step:
whether their boxes come within the tolerance, whether the set meets the detection's strips
widened by it (exact clipping of the set's polygon, as
:func:`~sse_cosim.estimation.association.meets_reference`), and whether the detection's set lies
inside it with that margin (as :func:`~sse_cosim.estimation.association.inside_reference`, after the
box test). It calls the same compiled clipping, vertex, rank and containment kernels as those
functions, which stay the reference (``tests/estimation/test_association_kernels.py``); the
centre's projection on a strip normal is summed here, so a result may differ from theirs only
where a vertex lies within rounding of a widened strip's edge (the tolerance errs towards
"meets" either way).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from sse_cosim.sets.enclosure_kernels import clip_to_strips, zonotope_vertices
from sse_cosim.sets.kernels import contains_2d, full_rank_2d

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


@njit(cache=True)
def candidate_tests(center: FloatArray, generators: FloatArray, normals: FloatArray,
                    values: FloatArray, radii: FloatArray, rows: IntArray,
                    corners: FloatArray, corner_rows: IntArray, lo: FloatArray,
                    hi: FloatArray, tol: float) -> tuple[BoolArray, BoolArray]:
    """A 2-D path set ⟨c, G⟩ (``center`` (2,), G (2, e)) against k detections: (meets (k,),
    inside (k,)).

    Detection d's strips (unit normals) are rows ``rows[d]:rows[d + 1]`` of ``normals``
    (m, 2), ``values`` and ``radii`` (m,); its set's vertices are rows
    ``corner_rows[d]:corner_rows[d + 1]`` of ``corners`` (v, 2), its box ``lo[d]``,
    ``hi[d]`` (k, 2). ``meets[d]``: the boxes come within ``tol`` and the set meets the strips
    widened by ``tol``; ``inside[d]``: it meets, its box lies in the set's and every vertex
    lies at least ``tol`` inside the (full-rank) set.
    """
    k = rows.shape[0] - 1
    meets = np.zeros(k, dtype=np.bool_)
    inside = np.zeros(k, dtype=np.bool_)
    shape = zonotope_vertices(generators)
    radius = np.zeros(2)
    for j in range(generators.shape[1]):
        radius[0] += abs(generators[0, j])
        radius[1] += abs(generators[1, j])
    low, high = center - radius, center + radius
    rank = full_rank_2d(generators)
    for d in range(k):
        if (lo[d, 0] > high[0] + tol or lo[d, 1] > high[1] + tol
                or hi[d, 0] < low[0] - tol or hi[d, 1] < low[1] - tol):
            continue
        first, last = rows[d], rows[d + 1]
        shifted = np.empty(last - first)
        for i in range(first, last):
            shifted[i - first] = values[i] - (normals[i, 0] * center[0]
                                              + normals[i, 1] * center[1])
        if clip_to_strips(shape, normals[first:last], shifted,
                          radii[first:last] + tol).shape[0] == 0:
            continue
        meets[d] = True
        if rank and lo[d, 0] >= low[0] and lo[d, 1] >= low[1] and hi[d, 0] <= high[0] \
                and hi[d, 1] <= high[1]:
            inside[d] = contains_2d(center, generators,
                                    corners[corner_rows[d]:corner_rows[d + 1]], -tol).all()
    return meets, inside
