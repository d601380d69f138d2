"""The raster representation (sse_cosim/regions/raster.py): how far it reaches beyond what the
contract asks (the cost of coarseness, bounded by the cell), its predicates against shapely on
its own cells, its masks, and its compiled kernels against their NumPy references.

The contract itself (sound outer, inner, dilation, erosion, overlays, distance) is checked
for every kind in KINDS by test_polygon.py. The kernels' tests carry the ``kernels`` marker:
``make test`` runs them again with numba's host CPU features and NumPy's AVX-512 code off.
"""

import math

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st
from test_polygon import (
    DISTANCES,
    ROUNDING_M,
    SETTINGS,
    covered,
    flat_parts,
    points_in,
    shape_pairs,
    shapes,
)

from sse_cosim.regions import KINDS, PolygonKind, RasterKind
from sse_cosim.regions import raster_kernels as kernels
from sse_cosim.regions.raster import (
    MAX_CELLS,
    SLACK_M,
    RasterRegion,
    box_rings_reference,
    combine_reference,
    contains_points_reference,
    dilate_reference,
    erode_reference,
    least_gap_reference,
    placed_reference,
    rasterize_reference,
    reach_widths,
    row_runs_reference,
    set_bounds_reference,
    shape_edges,
    shape_window,
)

CELLS = st.sampled_from([0.05, 0.1, 0.25])
SEEDS = st.integers(0, 2**32 - 1)


def cell_centres(region) -> np.ndarray:
    """The centres (n, 2) of a raster region's set cells."""
    rows, cols = np.nonzero(region.mask)
    return (np.column_stack([cols + region.offset[0], rows + region.offset[1]]) + 0.5) \
        * region.cell


def depth(shape: shapely.Geometry, points: np.ndarray) -> np.ndarray:
    """How far each point of ``shape`` (n, 2) lies from its boundary."""
    return shapely.distance(shape.boundary, shapely.points(points))


@SETTINGS
@given(shapes(), CELLS)
def test_an_outer_raster_keeps_only_cells_that_meet_the_shape(shape, cell):
    # each kept square (grown by the slack) meets the shape: its centre is within half a
    # diagonal (and the slack) of it
    centres = cell_centres(RasterKind(cell).outer(shape))
    reach = cell * math.sqrt(0.5) + 2 * SLACK_M
    assert (shapely.distance(shape, shapely.points(centres)) <= reach).all()


@SETTINGS
@given(shapes(), CELLS, SEEDS)
def test_an_inner_raster_holds_every_point_a_diagonal_inside(shape, cell, seed):
    points = points_in(shape, np.random.default_rng(seed))
    if shape.area == 0 or not len(points):
        return
    deep = points[depth(shape, points) > cell * math.sqrt(2) + 2 * SLACK_M]
    assert RasterKind(cell).inner(shape).contains_points(deep).all()


@SETTINGS
@given(shapes(), DISTANCES, CELLS)
def test_a_raster_dilation_reaches_no_farther_than_its_kind_says(shape, distance, cell):
    kind = RasterKind(cell)
    region = kind.outer(shape)
    dilated = region.dilate(distance)
    corners = shapely.points(shapely.get_coordinates(dilated.geometry()))
    far = shapely.distance(region.geometry(), corners)
    assert (far <= kind.reach_of(distance) + ROUNDING_M).all()
    assert shapely.MultiPoint(dilated.hull_points()).convex_hull.covers(dilated.geometry())


@SETTINGS
@given(shapes(), DISTANCES, CELLS, SEEDS)
def test_a_raster_erosion_keeps_every_point_deep_enough(shape, distance, cell, seed):
    # a cell whose every point lies farther than d + 2 diagonals inside has every cell within
    # d inside the shape (so in the inner raster), and the erosion keeps it
    points = points_in(shape, np.random.default_rng(seed))
    if shape.area == 0 or not len(points):
        return
    deep = points[depth(shape, points) > distance + 2 * cell * math.sqrt(2) + 3 * SLACK_M]
    assert RasterKind(cell).inner(shape).erode(distance).contains_points(deep).all()


def raster_pair(pair: tuple[shapely.Geometry, shapely.Geometry], cell: float, how: int):
    """Two raster regions of one grid from two shapes: outer, inner or dilated outer ones."""
    kind = RasterKind(cell)
    make = (kind.outer, kind.inner, lambda s: kind.outer(s).dilate(0.3))[how]
    return make(pair[0]), make(pair[1])


def polygonal(shape: shapely.Geometry) -> shapely.Geometry:
    """The polygons of a shape (its lines and points left out)."""
    parts = flat_parts(shape)
    return shapely.union_all(parts[shapely.get_type_id(parts) == 3])


@SETTINGS
@given(shape_pairs(), CELLS, st.integers(0, 2))
def test_raster_overlays_and_predicates_are_exact_on_the_cells(pair, cell, how):
    # exact up to the edges where two regions' cells only touch (the module docstring)
    a, b = raster_pair(pair, cell, how)
    ga, gb = a.geometry(), b.geometry()
    for region, exact in ((a.union(b), shapely.union(ga, gb)),
                          (a.intersection(b), shapely.intersection(ga, gb)),
                          (a.difference(b), shapely.difference(ga, gb))):
        assert math.isclose(region.area, exact.area, rel_tol=1e-9, abs_tol=ROUNDING_M)
        assert covered(region.geometry(), polygonal(exact))
        assert covered(exact, region.geometry())
    assert a.intersects(b) == shapely.intersects(ga, gb) == (a.distance(b) == 0.0)
    if not (a.is_empty or b.is_empty):
        assert math.isclose(a.distance(b), shapely.distance(ga, gb), abs_tol=ROUNDING_M)
        assert a.covers(b) == ga.covers(gb)
        assert a.union(b).covers(a) and a.covers(a.intersection(b))


@SETTINGS
@given(shapes(), CELLS)
def test_a_raster_is_its_cells_cropped_read_only_and_its_geometry_is_them(shape, cell):
    region = RasterKind(cell).outer(shape)
    mask = region.mask
    assert mask[0].any() and mask[-1].any() and mask[:, 0].any() and mask[:, -1].any()
    assert not mask.flags.writeable
    with pytest.raises(ValueError, match="read-only"):
        mask[0, 0] = False
    geometry = region.geometry()
    assert math.isclose(geometry.area, region.area, rel_tol=1e-9)
    x0, y0, x1, y1 = region.bounds
    assert np.allclose(geometry.bounds, (x0, y0, x1, y1), rtol=0, atol=0)
    assert mask.shape[1] <= (shape.bounds[2] - shape.bounds[0]) / cell + 3
    assert mask.shape[0] <= (shape.bounds[3] - shape.bounds[1]) / cell + 3


def test_a_small_region_far_away_stays_small():
    region = RasterKind(0.1).outer(shapely.box(12345.61, -9876.54, 12346.0, -9876.2))
    assert region.mask.shape == (5, 5)
    assert region.offset == (123456, -98766)
    moved = region.dilate(0.25).difference(RasterKind(0.1).inner(shapely.box(0, 0, 1, 1)))
    assert moved.mask.shape == (11, 11)


def test_regions_of_other_grids_or_kinds_do_not_combine():
    fine, coarse = RasterKind(0.05), RasterKind(0.1)
    square = shapely.box(0, 0, 1, 1)
    with pytest.raises(ValueError, match=r"cells of 0\.05 m combines only .* cells of 0\.1 m"):
        fine.outer(square).union(coarse.outer(square))
    with pytest.raises(ValueError, match="not with PolygonRegion"):
        fine.outer(square).intersection(PolygonKind().outer(square))
    with pytest.raises(ValueError, match="cell_m must be finite and > 0"):
        RasterKind(0.0)
    with pytest.raises(ValueError, match=f"over the limit of {MAX_CELLS} cells"):
        RasterKind(0.01).outer(shapely.box(0, 0, 1000, 1000))
    with np.errstate(invalid="ignore"):  # (shapely warns of the NaN)
        broken = shapely.LineString([(0, 0), (math.nan, 1)])
    with pytest.raises(ValueError, match="finite coordinates"):
        fine.outer(broken)


def test_the_registry_holds_the_raster_kind():
    assert KINDS["raster"] == RasterKind() and RasterKind().cell_m == 0.1


@SETTINGS
@given(st.lists(shapes(), min_size=1, max_size=4), CELLS)
def test_union_all_is_the_union_of_all(parts, cell):
    kind = RasterKind(cell)
    regions = [kind.outer(p) for p in parts]
    together, folded = kind.union_all(regions), regions[0]
    for region in regions[1:]:
        folded = folded.union(region)
    assert together.offset == folded.offset and np.array_equal(together.mask, folded.mask)


@SETTINGS
@given(shapes(), st.sampled_from([0.0, 0.5, 3.0]))
def test_a_raster_is_coarsened_to_itself(shape, tolerance):
    region = RasterKind().outer(shape)
    assert region.coarsen(tolerance) is region


@SETTINGS
@given(shapes(), CELLS, SEEDS)
def test_the_support_is_the_cells_farthest_corner(shape, cell, seed):
    rng = np.random.default_rng(seed)
    region = RasterKind(cell).outer(shape)
    directions = np.vstack([rng.normal(size=(6, 2)), np.eye(2), -np.eye(2)])
    corners = shapely.get_coordinates(region.geometry())
    farthest = (corners[:, :1] * directions[:, 0] + corners[:, 1:] * directions[:, 1]).max(axis=0)
    assert np.array_equal(region.support(directions), farthest)
    assert np.isneginf(RasterKind(cell).empty().support(directions)).all()
    assert region.support(np.zeros((0, 2))).shape == (0,)


# The kernels against their NumPy references.


@st.composite
def masks(draw: st.DrawFn, max_side: int = 24) -> tuple[np.ndarray, tuple[int, int]]:
    """A random mask (rows, cols) of bool, sparse to full, some of it empty, and an offset."""
    rng = np.random.default_rng(draw(SEEDS))
    rows, cols = draw(st.integers(0, max_side)), draw(st.integers(0, max_side))
    density = draw(st.sampled_from([0.02, 0.3, 0.7, 0.97, 1.0]))
    offset = (int(rng.integers(-40, 40)), int(rng.integers(-40, 40)))
    return rng.random((rows, cols)) < density, offset


def window_around(*placed: tuple[np.ndarray, tuple[int, int]], rng: np.random.Generator
                  ) -> tuple[int, int, int, int]:
    """A random window (col0, row0, cols, rows) about the masks'."""
    col0 = min(o[0] for _, o in placed) + int(rng.integers(-3, 4))
    row0 = min(o[1] for _, o in placed) + int(rng.integers(-3, 4))
    cols = max(o[0] + m.shape[1] for m, o in placed) - col0 + int(rng.integers(-3, 4))
    rows = max(o[1] + m.shape[0] for m, o in placed) - row0 + int(rng.integers(-3, 4))
    return col0, row0, max(cols, 0), max(rows, 0)


@pytest.mark.kernels
@SETTINGS
@given(shapes(), CELLS, st.booleans())
def test_rasterize_lies_between_the_references_with_the_slack_moved(shape, cell, inner):
    # Both sides round products of coordinates (< 1e-12 m here): raising or lowering the
    # reference's slack by 1e-9 m moves it past every decision that rounding can turn.
    edges, part_ptr, strokes = shape_edges(shape)
    window = shape_window(shape, cell)
    col0, row0, cols, rows = window
    got = kernels.rasterize(edges, part_ptr, strokes, col0, row0, rows, cols, cell, SLACK_M,
                            inner)
    less = rasterize_reference(edges, part_ptr, strokes, window, cell, SLACK_M - 1e-9, inner)
    more = rasterize_reference(edges, part_ptr, strokes, window, cell, SLACK_M + 1e-9, inner)
    small, large = (more, less) if inner else (less, more)
    assert not (small & ~got).any() and not (got & ~large).any()


@pytest.mark.kernels
@SETTINGS
@given(masks(), st.floats(0.0, 2.0), st.sampled_from([0.1, 0.3, 1.0]))
def test_dilate_and_erode_are_the_references(placed, distance, cell):
    # integer work on both sides: exactly the same cells
    mask, _ = placed
    widths = reach_widths(distance, cell)
    assert np.array_equal(kernels.dilate(mask, widths), dilate_reference(mask, widths))
    assert np.array_equal(kernels.erode(mask, widths), erode_reference(mask, widths))


@pytest.mark.kernels
@SETTINGS
@given(masks(), masks(), SEEDS)
def test_overlays_and_covers_are_the_references(first, second, seed):
    (a, a_offset), (b, b_offset) = first, second
    rng = np.random.default_rng(seed)
    window = window_around(first, second, rng=rng)
    col0, row0, cols, rows = window
    for operation in (kernels.UNION, kernels.INTERSECTION, kernels.DIFFERENCE):
        got = kernels.combine(a, *a_offset, b, *b_offset, operation, col0, row0, rows, cols)
        assert np.array_equal(got, combine_reference(a, a_offset, b, b_offset, operation, window))
    b_window = (*b_offset, b.shape[1], b.shape[0])
    expected = not (b & ~placed_reference(a, a_offset, b_window)).any()
    assert kernels.covers(a, *a_offset, b, *b_offset) == expected
    hull = window_around(first, second, rng=np.random.default_rng(0))
    target = np.zeros((hull[3] + 6, hull[2] + 6), dtype=bool)
    corner = (hull[0] - 3, hull[1] - 3)
    kernels.paint(target, *corner, a, *a_offset)
    expected = placed_reference(a, a_offset, (*corner, target.shape[1], target.shape[0]))
    assert np.array_equal(target, expected)


@pytest.mark.kernels
@SETTINGS
@given(masks())
def test_bounds_row_runs_and_boxes_are_the_references(placed):
    mask, _ = placed
    assert kernels.set_bounds(mask) == set_bounds_reference(mask)
    for got, expected in zip(kernels.row_runs(mask), row_runs_reference(mask), strict=True):
        assert np.array_equal(got, expected)
    painted = np.zeros(mask.shape, dtype=int)
    for col_start, col_stop, row_start, row_stop in kernels.run_boxes(mask):
        painted[row_start:row_stop, col_start:col_stop] += 1
    assert np.array_equal(painted, mask.astype(int))  # disjoint boxes, exactly the cells


@pytest.mark.kernels
@SETTINGS
@given(masks())
def test_box_rings_are_the_reference_and_their_union_is_the_cells(placed):
    mask, offset = placed
    boxes = kernels.run_boxes(mask)
    corners, ptr = kernels.box_rings(boxes)
    expected_corners, expected_ptr = box_rings_reference(boxes)
    assert np.array_equal(corners, expected_corners) and np.array_equal(ptr, expected_ptr)
    if not mask.any():
        return
    region = RasterRegion(0.1, mask, offset)
    rows, cols = np.nonzero(mask)
    cells = shapely.union_all(shapely.box(
        (cols + offset[0]) * 0.1, (rows + offset[1]) * 0.1,
        (cols + offset[0] + 1) * 0.1, (rows + offset[1] + 1) * 0.1))
    geometry = region.geometry()
    assert shapely.is_valid(geometry), shapely.is_valid_reason(geometry)
    assert shapely.equals(geometry, cells)


@pytest.mark.kernels
@SETTINGS
@given(masks(), masks())
def test_least_gap_is_the_reference(first, second):
    # squares of integers summed and rooted once on both sides: the same float
    # (and only edge cells tried against every pair: the same least gap)
    (a, a_offset), (b, b_offset) = first, second
    got = kernels.least_gap(a, *a_offset, b, *b_offset)
    assert got == least_gap_reference(a, a_offset, b, b_offset)


@pytest.mark.kernels
@SETTINGS
@given(masks(), st.sampled_from([0.1, 0.3, 1.0]), SEEDS)
def test_contains_points_is_the_reference(placed, cell, seed):
    # the same comparisons with the same grid lines: the same answers, on edges and corners too
    mask, offset = placed
    rng = np.random.default_rng(seed)
    low = np.array(offset) - 2
    high = low + np.array(mask.shape[::-1]) + 4
    anywhere = rng.uniform(low * cell, high * cell, (200, 2))
    lines = rng.integers(low, high, (200, 2)).astype(float) * cell
    on_lines = np.where(rng.random((200, 2)) < 0.5, lines, anywhere)
    points = np.vstack([anywhere, on_lines, [[math.nan, 0.0]]])
    got = kernels.contains_points(mask, *offset, cell, points)
    assert np.array_equal(got, contains_points_reference(mask, offset, cell, points))


@pytest.mark.kernels
def test_least_gap_of_nested_touching_and_distant_regions():
    full = np.ones((20, 20), dtype=bool)
    speck = np.ones((2, 2), dtype=bool)
    for a, a_offset, b, b_offset, gap in (
            (full, (0, 0), speck, (9, 9), 0.0),  # inside the other, far from its edge
            (speck, (9, 9), full, (0, 0), 0.0),
            (full, (0, 0), speck, (20, 20), 0.0),  # corner to corner
            (full, (0, 0), speck, (23, 24), 5.0)):  # 3 and 4 whole cells between them
        assert kernels.least_gap(a, *a_offset, b, *b_offset) == gap
        assert least_gap_reference(a, a_offset, b, b_offset) == gap
