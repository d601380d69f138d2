"""Compiled kernels (numba, cached on disk) of the raster representation's per-cell work.

A mask (rows, cols) of bool holds the cells of a window of the global grid: ``mask[r, k]`` is
the closed square of column ``col0 + k`` and row ``row0 + r`` (:mod:`~sse_cosim.regions.raster`).
Every grid line is :func:`grid_line`, ``float(index) * cell``, here and in
:mod:`~sse_cosim.regions.raster`, so all of them agree on where a cell lies.

Each kernel has a NumPy reference in :mod:`~sse_cosim.regions.raster` (``*_reference``), and
``tests/regions/test_raster.py`` checks one against the other: the integer ones (dilation,
erosion, overlays, covers, least gap, runs, boxes, point queries) exactly; the rasterisation,
whose decisions depend on rounded products, between the reference with the slack lowered and
raised by far more than that rounding.

numba caches the machine code in ``__pycache__`` next to this file (ignored by git).
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

UNION, INTERSECTION, DIFFERENCE = 0, 1, 2
"""The overlays of :func:`combine`."""


@njit(cache=True)
def grid_line(index: int, cell: float) -> float:
    """Where grid line ``index`` lies (m): ``float(index) * cell``."""
    return float(index) * cell


@njit(cache=True)
def _centre(index: int, cell: float) -> float:
    """The centre of cell ``index`` along one axis (m)."""
    return (float(index) + 0.5) * cell


@njit(cache=True)
def _mark_segment(touched: BoolArray, x0: float, y0: float, x1: float, y1: float, col0: int,
                  row0: int, cell: float, slack: float, value: bool) -> None:
    """Set to ``value`` every cell of ``touched`` whose square grown by ``slack`` meets the
    segment (x0, y0)-(x1, y1): row by row, the segment's part within the grown row's band,
    then the columns whose grown squares meet that part's x range."""
    rows, cols = touched.shape
    y_low, y_high = min(y0, y1), max(y0, y1)
    first = max(int(np.floor((y_low - slack) / cell)) - 1 - row0, 0)
    last = min(int(np.floor((y_high + slack) / cell)) + 1 - row0, rows - 1)
    for r in range(first, last + 1):
        band0 = grid_line(row0 + r, cell) - slack
        band1 = grid_line(row0 + r + 1, cell) + slack
        if y_high < band0 or y_low > band1:
            continue
        if y0 == y1:
            xa, xb = min(x0, x1), max(x0, x1)
        else:
            ta, tb = (band0 - y0) / (y1 - y0), (band1 - y0) / (y1 - y0)
            ta, tb = max(min(ta, tb), 0.0), min(max(ta, tb), 1.0)
            xa, xb = x0 + ta * (x1 - x0), x0 + tb * (x1 - x0)
            xa, xb = min(xa, xb), max(xa, xb)
        k_first = max(int(np.floor((xa - slack) / cell)) - 1 - col0, 0)
        k_last = min(int(np.floor((xb + slack) / cell)) + 1 - col0, cols - 1)
        for k in range(k_first, k_last + 1):
            if (grid_line(col0 + k, cell) - slack <= xb
                    and grid_line(col0 + k + 1, cell) + slack >= xa):
                touched[r, k] = value


@njit(cache=True)
def _crossed_rows(y0: float, y1: float, row0: int, rows: int, cell: float) -> tuple[int, int]:
    """A range of rows (first, stop) holding every row whose centre line the edge crosses
    (the caller tests each row: a few more are harmless)."""
    y_low, y_high = min(y0, y1), max(y0, y1)
    first = max(int(np.floor(y_low / cell - 0.5)) - 1 - row0, 0)
    stop = min(int(np.floor(y_high / cell - 0.5)) + 2 - row0, rows)
    return first, stop


@njit(cache=True)
def _sort_in_place(values: FloatArray) -> None:
    """Sort ``values`` (n,) ascending in place, by insertion (a row's few crossings)."""
    for i in range(1, values.shape[0]):
        value, j = values[i], i - 1
        while j >= 0 and values[j] > value:
            values[j + 1] = values[j]
            j -= 1
        values[j + 1] = value


@njit(cache=True)
def _fill_part(filled: BoolArray, edges: FloatArray, first_edge: int, stop_edge: int,
               col0: int, row0: int, cell: float) -> None:
    """Set the cells of ``filled`` whose centre the polygon of edges ``first_edge`` ..
    ``stop_edge`` (its rings) holds by the even-odd rule: on each row's centre line, the
    crossings of the edges with one end at or below the line and the other above, sorted, and
    the centres between pairs of them."""
    rows, cols = filled.shape
    counts = np.zeros(rows + 1, dtype=np.int64)
    for e in range(first_edge, stop_edge):
        y0, y1 = edges[e, 1], edges[e, 3]
        first, stop = _crossed_rows(y0, y1, row0, rows, cell)
        for r in range(first, stop):
            yc = _centre(row0 + r, cell)
            if (y0 <= yc) != (y1 <= yc):
                counts[r + 1] += 1
    for r in range(rows):
        counts[r + 1] += counts[r]
    crossings = np.empty(counts[rows])
    fill = counts[:rows].copy()
    for e in range(first_edge, stop_edge):
        x0, y0, x1, y1 = edges[e, 0], edges[e, 1], edges[e, 2], edges[e, 3]
        first, stop = _crossed_rows(y0, y1, row0, rows, cell)
        for r in range(first, stop):
            yc = _centre(row0 + r, cell)
            if (y0 <= yc) != (y1 <= yc):
                crossings[fill[r]] = x0 + (yc - y0) * (x1 - x0) / (y1 - y0)
                fill[r] += 1
    for r in range(rows):
        line = crossings[counts[r]:counts[r + 1]]
        _sort_in_place(line)
        for m in range(0, line.shape[0] - 1, 2):
            k_first = max(int(np.ceil(line[m] / cell - 0.5)) - col0, 0)
            k_stop = min(int(np.ceil(line[m + 1] / cell - 0.5)) - col0, cols)
            filled[r, k_first:max(k_first, k_stop)] = True


@njit(cache=True)
def rasterize(edges: FloatArray, part_ptr: IntArray, strokes: FloatArray, col0: int, row0: int,
              rows: int, cols: int, cell: float, slack: float, inner: bool) -> BoolArray:
    """The cells (rows, cols) of the window at (col0, row0) that a shape covers.

    ``edges`` (m, 4) are the ring edges (x0, y0, x1, y1) of its polygons, polygon p's
    ``part_ptr[p]:part_ptr[p + 1]``; ``strokes`` (q, 4) its line segments and points (a point
    is a segment of length 0), which have no inside. A cell is filled when a polygon holds its
    centre (even-odd over that polygon's rings, any polygon), touched when its square grown by
    ``slack`` meets an edge or a stroke. A cell neither touched nor filled misses the shape,
    one filled and untouched lies inside it (its square meets no boundary). So the outer
    raster is the filled cells then every touched one set, the inner one (``inner``) the
    filled cells then every touched one cleared."""
    out = np.zeros((rows, cols), dtype=np.bool_)
    for p in range(part_ptr.shape[0] - 1):
        _fill_part(out, edges, part_ptr[p], part_ptr[p + 1], col0, row0, cell)
    for e in range(edges.shape[0]):
        _mark_segment(out, edges[e, 0], edges[e, 1], edges[e, 2], edges[e, 3], col0, row0,
                      cell, slack, not inner)
    for s in range(strokes.shape[0]):
        _mark_segment(out, strokes[s, 0], strokes[s, 1], strokes[s, 2], strokes[s, 3],
                      col0, row0, cell, slack, not inner)
    return out


@njit(cache=True)
def dilate(mask: BoolArray, widths: IntArray) -> BoolArray:
    """The cells within reach of a set cell of ``mask`` (rows, cols), over the window grown by
    R = len(widths) - 1 rows and widths[0] columns on each side, shape (rows + 2R,
    cols + 2 widths[0]): cell (r + dr, k + dk) is within reach of (r, k) when
    |dr| <= R and |dk| <= widths[|dr|]. Each row's run, widened, is set in each row within
    reach."""
    rows, cols = mask.shape
    reach, wide = widths.shape[0] - 1, widths[0]
    out = np.zeros((rows + 2 * reach, cols + 2 * wide), dtype=np.bool_)
    for r in range(rows):
        k = 0
        while k < cols:
            if not mask[r, k]:
                k += 1
                continue
            start = k
            while k < cols and mask[r, k]:
                k += 1
            for dr in range(-reach, reach + 1):
                width = widths[abs(dr)]
                out[r + reach + dr, start + wide - width:k + wide + width] = True
    return out


@njit(cache=True)
def erode(mask: BoolArray, widths: IntArray) -> BoolArray:
    """The cells of ``mask`` (rows, cols) all of whose cells within reach (as in
    :func:`dilate`) are set, cells outside the mask counting as unset, shape (rows, cols).

    Row r keeps the columns that every row r + dr within reach holds with widths[|dr|] to
    spare on both sides: the intersection of those rows' runs, each narrowed by its width."""
    rows, cols = mask.shape
    reach = widths.shape[0] - 1
    ptr, starts, stops = row_runs(mask)
    out = np.zeros((rows, cols), dtype=np.bool_)
    kept = np.empty((cols + 1, 2), dtype=np.int64)
    meet = np.empty((cols + 1, 2), dtype=np.int64)
    for r in range(reach, rows - reach):
        n = 0
        width = widths[reach]
        for i in range(ptr[r - reach], ptr[r - reach + 1]):
            if starts[i] + width < stops[i] - width:
                kept[n, 0], kept[n, 1] = starts[i] + width, stops[i] - width
                n += 1
        for dr in range(1 - reach, reach + 1):
            width, row = widths[abs(dr)], r + dr
            m, i, j = 0, 0, ptr[row]
            while i < n and j < ptr[row + 1]:
                low = max(kept[i, 0], starts[j] + width)
                high = min(kept[i, 1], stops[j] - width)
                if low < high:
                    meet[m, 0], meet[m, 1] = low, high
                    m += 1
                if kept[i, 1] < stops[j] - width:
                    i += 1
                else:
                    j += 1
            kept, meet, n = meet, kept, m
        for i in range(n):
            out[r, kept[i, 0]:kept[i, 1]] = True
    return out


@njit(cache=True)
def _cell(mask: BoolArray, col0: int, row0: int, col: int, row: int) -> bool:
    """Whether global cell (col, row) is set in ``mask`` at (col0, row0) (unset outside)."""
    r, k = row - row0, col - col0
    return 0 <= r < mask.shape[0] and 0 <= k < mask.shape[1] and mask[r, k]


@njit(cache=True)
def _shared(col0: int, row0: int, rows: int, cols: int, mask: BoolArray, m_col: int,
            m_row: int) -> tuple[int, int, int, int]:
    """The rows and columns (r0, r1, k0, k1) of a window at (col0, row0) that ``mask`` at
    (m_col, m_row) holds (none: r0 == r1, or k0 == k1)."""
    r0, r1 = max(m_row - row0, 0), min(m_row + mask.shape[0] - row0, rows)
    k0, k1 = max(m_col - col0, 0), min(m_col + mask.shape[1] - col0, cols)
    return r0, max(r0, r1), k0, max(k0, k1)


@njit(cache=True)
def combine(a: BoolArray, a_col: int, a_row: int, b: BoolArray, b_col: int, b_row: int,
            operation: int, col0: int, row0: int, rows: int, cols: int) -> BoolArray:
    """``a`` (at (a_col, a_row)) :data:`UNION`, :data:`INTERSECTION` or :data:`DIFFERENCE`
    ``b`` cell by cell over the window (rows, cols) at (col0, row0): the cells both windows
    hold and-ed; otherwise a's cells copied in, then b's or-ed or cleared."""
    out = np.zeros((rows, cols), dtype=np.bool_)
    r0, r1, k0, k1 = _shared(col0, row0, rows, cols, a, a_col, a_row)
    if operation == INTERSECTION:
        s0, s1, j0, j1 = _shared(col0, row0, rows, cols, b, b_col, b_row)
        r0, r1, k0, k1 = max(r0, s0), min(r1, s1), max(k0, j0), min(k1, j1)
    for r in range(r0, r1):
        target = out[r, k0:k1]
        source = a[row0 + r - a_row, col0 + k0 - a_col:col0 + k1 - a_col]
        if operation == INTERSECTION:
            other = b[row0 + r - b_row, col0 + k0 - b_col:col0 + k1 - b_col]
            for k in range(k1 - k0):
                target[k] = source[k] & other[k]
        else:
            target[:] = source
    if operation == INTERSECTION:
        return out
    r0, r1, k0, k1 = _shared(col0, row0, rows, cols, b, b_col, b_row)
    for r in range(r0, r1):
        target, source = out[r, k0:k1], b[row0 + r - b_row, col0 + k0 - b_col:col0 + k1 - b_col]
        for k in range(k1 - k0):
            if operation == UNION:
                target[k] = target[k] | source[k]
            else:
                target[k] = target[k] & ~source[k]
    return out


@njit(cache=True)
def paint(target: BoolArray, col0: int, row0: int, source: BoolArray, s_col: int,
          s_row: int) -> None:
    """Set in ``target`` (at (col0, row0)) every cell set in ``source`` (at (s_col, s_row)),
    which must lie in target's window."""
    first = s_col - col0
    for r in range(source.shape[0]):
        row = target[s_row - row0 + r, first:first + source.shape[1]]
        for k in range(source.shape[1]):  # (k >= 0: numba drops the wraparound, vectorises)
            row[k] = row[k] | source[r, k]


@njit(cache=True)
def set_bounds(mask: BoolArray) -> tuple[int, int, int, int]:
    """The rows and columns (r0, r1, k0, k1) (stops excluded) that hold the set cells of
    ``mask``; (0, 0, 0, 0) if none."""
    rows, cols = mask.shape
    r0 = 0
    while r0 < rows and not mask[r0].any():
        r0 += 1
    if r0 == rows:
        return 0, 0, 0, 0
    r1 = rows
    while not mask[r1 - 1].any():
        r1 -= 1
    held = np.zeros(cols, dtype=np.bool_)  # the columns any row holds (or-ed: vectorised)
    for r in range(r0, r1):
        row = mask[r]
        for k in range(cols):
            held[k] = held[k] | row[k]
    k0, k1 = 0, cols
    while not held[k0]:
        k0 += 1
    while not held[k1 - 1]:
        k1 -= 1
    return r0, r1, k0, k1


@njit(cache=True)
def covers(a: BoolArray, a_col: int, a_row: int, b: BoolArray, b_col: int, b_row: int) -> bool:
    """Whether every cell set in ``b`` is set in ``a``."""
    for r in range(b.shape[0]):
        for k in range(b.shape[1]):
            if b[r, k] and not _cell(a, a_col, a_row, b_col + k, b_row + r):
                return False
    return True


@njit(cache=True)
def row_runs(mask: BoolArray) -> tuple[IntArray, IntArray, IntArray]:
    """The runs of set cells of each row of ``mask`` (rows, cols): ``(ptr (rows + 1,),
    starts (n,), stops (n,))``, row r's runs ``ptr[r]:ptr[r + 1]``, columns start..stop - 1,
    left to right."""
    rows, cols = mask.shape
    ptr = np.zeros(rows + 1, dtype=np.int64)
    for r in range(rows):
        count = 0
        for k in range(cols):
            if mask[r, k] and (k == 0 or not mask[r, k - 1]):
                count += 1
        ptr[r + 1] = ptr[r] + count
    starts = np.empty(ptr[rows], dtype=np.int64)
    stops = np.empty(ptr[rows], dtype=np.int64)
    for r in range(rows):
        n = ptr[r]
        for k in range(cols):
            if mask[r, k] and (k == 0 or not mask[r, k - 1]):
                starts[n] = k
            if mask[r, k] and (k == cols - 1 or not mask[r, k + 1]):
                stops[n] = k + 1
                n += 1
    return ptr, starts, stops


@njit(cache=True)
def run_boxes(mask: BoolArray) -> IntArray:
    """The set cells of ``mask`` as disjoint boxes (n, 4) of (col_start, col_stop, row_start,
    row_stop) (stops excluded): each row run, merged with the same run of the rows above."""
    ptr, starts, stops = row_runs(mask)
    boxes = np.empty((starts.shape[0], 4), dtype=np.int64)
    box_of = np.empty(starts.shape[0], dtype=np.int64)
    n = 0
    for r in range(mask.shape[0]):
        above = ptr[r - 1] if r > 0 else 0
        for i in range(ptr[r], ptr[r + 1]):
            while above < ptr[r] and starts[above] < starts[i]:
                above += 1
            if r > 0 and above < ptr[r] and starts[above] == starts[i] \
                    and stops[above] == stops[i]:
                box_of[i] = box_of[above]
                boxes[box_of[i], 3] = r + 1
            else:
                boxes[n, 0], boxes[n, 1], boxes[n, 2], boxes[n, 3] = starts[i], stops[i], r, r + 1
                box_of[i] = n
                n += 1
    return boxes[:n]


@njit(cache=True)
def _edge_ends(boxes: IntArray, order: IntArray, rows: IntArray, row: int, start: int,
               stop: int, out: IntArray, n: int) -> int:
    """The columns strictly between ``start`` and ``stop`` where a box ``order[i]`` whose row
    ``rows[i]`` (ascending) is ``row`` begins or ends, written into ``out`` from ``n`` (if it
    is long enough; else only counted); returns ``n`` plus their number."""
    i = np.searchsorted(rows, row)
    while i < order.shape[0] and rows[i] == row:
        for col in (boxes[order[i], 0], boxes[order[i], 1]):
            if start < col < stop:
                if n < out.shape[0]:
                    out[n] = col
                n += 1
        i += 1
    return n


@njit(cache=True)
def _sorted_distinct(values: IntArray, first: int, stop: int, to: int) -> int:
    """Sorts ``values[first:stop]`` in place and moves its distinct values to ``to`` on
    (``to <= first``); returns how many there are."""
    values[first:stop].sort()
    count = 0
    for i in range(first, stop):
        if count == 0 or values[i] != values[to + count - 1]:
            values[to + count] = values[i]
            count += 1
    return count


@njit(cache=True)
def _put(corners: IntArray, at: int, col: int, row: int) -> int:
    corners[at, 0], corners[at, 1] = col, row
    return at + 1


@njit(cache=True)
def box_rings(boxes: IntArray) -> tuple[IntArray, IntArray]:
    """The boxes (n, 4) of :func:`run_boxes` as rings noded for a coverage: ``(corners (m, 2)
    of (column, row) grid lines, ptr (n + 1,))``, box i's ring ``ptr[i]:ptr[i + 1]``,
    counter-clockwise and closed.

    A box's bottom edge holds every column inside it where a box ending on its bottom row
    begins or ends, and its top edge every such column of a box beginning on its top row, so
    that two boxes share each piece of a common edge corner for corner (a coverage union
    matches edges exactly). Their sides are never shared: a run's ends have unset cells
    beside them."""
    n = boxes.shape[0]
    by_top, by_bottom = np.argsort(boxes[:, 3]), np.argsort(boxes[:, 2])
    tops, bottoms = boxes[by_top, 3], boxes[by_bottom, 2]  # ascending
    none = np.empty(0, dtype=np.int64)
    ends_ptr = np.zeros(n + 1, dtype=np.int64)  # each box's ends below, then above
    for b in range(n):
        k0, k1, j0, j1 = boxes[b, 0], boxes[b, 1], boxes[b, 2], boxes[b, 3]
        count = _edge_ends(boxes, by_top, tops, j0, k0, k1, none, 0)
        count = _edge_ends(boxes, by_bottom, bottoms, j1, k0, k1, none, count)
        ends_ptr[b + 1] = ends_ptr[b] + count
    ends = np.empty(ends_ptr[n], dtype=np.int64)
    below = np.empty(n, dtype=np.int64)
    above = np.empty(n, dtype=np.int64)
    ptr = np.zeros(n + 1, dtype=np.int64)
    for b in range(n):
        k0, k1, j0, j1 = boxes[b, 0], boxes[b, 1], boxes[b, 2], boxes[b, 3]
        own = ends[ends_ptr[b]:ends_ptr[b + 1]]
        m = _edge_ends(boxes, by_top, tops, j0, k0, k1, own, 0)
        stop = _edge_ends(boxes, by_bottom, bottoms, j1, k0, k1, own, m)
        below[b] = _sorted_distinct(own, 0, m, 0)
        above[b] = _sorted_distinct(own, m, stop, below[b])
        ptr[b + 1] = ptr[b] + below[b] + above[b] + 5
    corners = np.empty((ptr[n], 2), dtype=np.int64)
    for b in range(n):
        k0, k1, j0, j1 = boxes[b, 0], boxes[b, 1], boxes[b, 2], boxes[b, 3]
        own = ends[ends_ptr[b]:ends_ptr[b + 1]]
        at = _put(corners, ptr[b], k0, j0)
        for i in range(below[b]):  # the bottom edge, left to right
            at = _put(corners, at, own[i], j0)
        at = _put(corners, _put(corners, at, k1, j0), k1, j1)
        for i in range(below[b] + above[b] - 1, below[b] - 1, -1):  # the top, right to left
            at = _put(corners, at, own[i], j1)
        _put(corners, _put(corners, at, k0, j1), k0, j0)
    return corners, ptr


@njit(cache=True)
def _row_gap(col: int, first: int, stop: int, starts: IntArray, stops: IntArray) -> int:
    """The least gap (whole cells between them) from column ``col`` to a run of
    ``first:stop`` (sorted); -1 if there is none."""
    if first == stop:
        return -1
    lo, hi = first, stop  # the first run starting after col
    while lo < hi:
        mid = (lo + hi) // 2
        if starts[mid] <= col:
            lo = mid + 1
        else:
            hi = mid
    best = -1
    if lo < stop:
        best = max(starts[lo] - col - 1, 0)
    if lo > first:
        gap = max(col - stops[lo - 1], 0)
        best = gap if best < 0 else min(best, gap)
    return best


@njit(cache=True)
def _on_edge(mask: BoolArray, r: int, k: int) -> bool:
    """Whether cell (r, k) has an unset cell among its 8 neighbours (cells outside the mask
    are unset)."""
    rows, cols = mask.shape
    for rr in range(r - 1, r + 2):
        for kk in range(k - 1, k + 2):
            if rr < 0 or rr >= rows or kk < 0 or kk >= cols or not mask[rr, kk]:
                return True
    return False


@njit(cache=True)
def _edge_gap(a: BoolArray, a_col: int, a_row: int, ptr: IntArray, starts: IntArray,
              stops: IntArray, b_col: int, b_row: int, best: int) -> int:
    """The least squared gap gx² + gy² (whole cells between columns and rows) from a set cell
    on a's edge to a run (:func:`row_runs`) of a mask at (b_col, b_row), or ``best`` if that
    is less (-1: none yet). Rows of b are visited outward from each cell's row until the row
    gap alone reaches the best."""
    rows_b = ptr.shape[0] - 1
    for ra in range(a.shape[0]):
        y = a_row + ra - b_row
        middle = min(max(y, 0), rows_b - 1)
        for ka in range(a.shape[1]):
            if not a[ra, ka] or not _on_edge(a, ra, ka):
                continue
            col = a_col + ka - b_col
            for direction in (-1, 1):
                rb = middle if direction < 0 else middle + 1
                while 0 <= rb < rows_b:
                    gy = max(abs(y - rb) - 1, 0)
                    if best >= 0 and gy * gy >= best:
                        break
                    gx = _row_gap(col, ptr[rb], ptr[rb + 1], starts, stops)
                    if gx >= 0 and (best < 0 or gx * gx + gy * gy < best):
                        best = gx * gx + gy * gy
                    rb += direction
            if best == 0:
                return 0
    return best


@njit(cache=True)
def least_gap(a: BoolArray, a_col: int, a_row: int, b: BoolArray, b_col: int, b_row: int
              ) -> float:
    """The least distance (in cells) between the squares of a set cell of ``a`` and one of
    ``b``: min sqrt(gx² + gy²) over pairs, gx and gy the whole cells between their columns
    and rows; inf if either has none.

    Only cells on an edge (:func:`_on_edge`) need be tried, a's against b's runs and b's
    against a's: two regions apart have their closest points on their edges, and the
    cells holding them are edge cells (a cell whose 8 neighbours are set holds only inner
    points); two that share cells have, in a row of shared cells, a last one whose right
    neighbour misses one of them, an edge cell of that one in the other; two that only touch
    meet at a point whose cells of each have a neighbour of the other."""
    b_ptr, b_starts, b_stops = row_runs(b)
    best = _edge_gap(a, a_col, a_row, b_ptr, b_starts, b_stops, b_col, b_row, -1)
    if best != 0:
        a_ptr, a_starts, a_stops = row_runs(a)
        best = _edge_gap(b, b_col, b_row, a_ptr, a_starts, a_stops, a_col, a_row, best)
    return np.inf if best < 0 else np.sqrt(float(best))


@njit(cache=True)
def contains_points(mask: BoolArray, col0: int, row0: int, cell: float, points: FloatArray
                    ) -> BoolArray:
    """Whether each point (n, 2) lies in a set cell's closed square (one on an edge or a
    corner: in any of the cells it touches), shape (n,)."""
    rows, cols = mask.shape
    inside = np.zeros(points.shape[0], dtype=np.bool_)
    x_low, x_high = grid_line(col0, cell), grid_line(col0 + cols, cell)
    y_low, y_high = grid_line(row0, cell), grid_line(row0 + rows, cell)
    for n in range(points.shape[0]):
        x, y = points[n, 0], points[n, 1]
        if not (x_low <= x <= x_high and y_low <= y <= y_high):
            continue  # (NaN too)
        col, row = int(np.floor(x / cell)), int(np.floor(y / cell))
        for j in range(row - 1, row + 2):
            if not grid_line(j, cell) <= y <= grid_line(j + 1, cell):
                continue
            for i in range(col - 1, col + 2):
                if grid_line(i, cell) <= x <= grid_line(i + 1, cell) \
                        and _cell(mask, col0, row0, i, j):
                    inside[n] = True
    return inside
