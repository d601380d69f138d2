"""The compiled polygon recursion (world/assumption_kernels.py) against its NumPy/shapely
reference (world/assumptions.py: ``advance``, ``admits_reference``), and ``admits`` and
``least_jitter`` on SUMO's walks.

The two sides compute the same sets with different rounding -- the kernel sector vertices
a_j + r U_j and Sutherland-Hodgman's points, the reference cumulative sums of edges and GEOS
-- each within about 1e-13 m of the exact recursion for the walks here (coordinates up to
200 m). So they are compared by a sandwich, never bit for bit: with both bounds moved by
DELTA = 1e-9 m, four orders of magnitude above both roundings, the reference's set for
eps - DELTA, v dt - DELTA lies in the kernel's set for eps, v dt, and the kernel's set in the
reference's for eps + DELTA, v dt + DELTA (the exact sets nest with a margin of
DELTA cos(pi/N), so these hold with room to spare however thin the sets); the same for the
decisions of ``admits``.
"""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import shapely
import sumolib
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from world_helpers import REPO

from sse_cosim.world import assumptions, walker_jitter
from sse_cosim.world.assumption_kernels import disc, polygon_step
from sse_cosim.world.assumptions import (
    MotionBounds,
    admits,
    admits_reference,
    advance,
    least_jitter,
    unit_polygon,
)
from sse_cosim.world.network import build_network
from sse_cosim.world.walk_probe import Walker, walk_alone

pytestmark = pytest.mark.kernels

SETTINGS = settings(derandomize=True, deadline=None, database=None, max_examples=40,
                    suppress_health_check=[HealthCheck.too_slow])
DELTA = 1e-9  # m, moved bounds of the sandwich
STEP_S = 0.1


def _mids(sides: int) -> np.ndarray:
    unit = unit_polygon(sides)
    return 0.5 * (unit + np.roll(unit, -1, axis=0))


def _moved(bounds: MotionBounds, by: float) -> MotionBounds:
    """Jitter and step length both moved by ``by`` (m)."""
    return MotionBounds((bounds.step_m + by) / bounds.step_s, bounds.jitter_m + by,
                        bounds.step_s)


def _polygon(sectors: np.ndarray) -> np.ndarray:
    """The vertices (k, 2) of a polygon given by its sector vertices (N, 2): consecutive
    repeats dropped."""
    keep = np.any(sectors != np.roll(sectors, 1, axis=0), axis=1)
    return sectors[keep] if keep.any() else sectors[:1]


def _within(points: np.ndarray, polygon: np.ndarray) -> bool:
    """Whether every point (k, 2) lies in the convex set with vertices ``polygon`` (n, 2)."""
    shape = (shapely.Polygon(polygon) if len(polygon) >= 3 else
             shapely.LineString(polygon) if len(polygon) == 2 else shapely.Point(polygon[0]))
    shapely.prepare(shape)
    return bool(shapely.intersects_xy(shape, points[:, 0], points[:, 1]).all())


@st.composite
def walks(draw: st.DrawFn, sides_from: tuple[int, ...] = (16, 64, 64, 4096)
          ) -> tuple[np.ndarray, MotionBounds, int]:
    """A walk (k, 2) 200 m or less from the origin, its bounds and the polygons' sides (one
    of ``sides_from``): steps
    of 0.95 to 1.03 v dt along a turning heading, with jumps (up to v dt + 2 eps, some in a
    normal's direction and exactly as long as the two polygons' inradii and the step
    allow, so that the set is a segment) and stops."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    sides = draw(st.sampled_from(sides_from))
    step_m = draw(st.sampled_from([0.05, 0.25, 0.5]))
    jitter = draw(st.sampled_from([0.02, 0.3, 1.0]))
    count = draw(st.integers(2, 12 if sides == 4096 else 30))
    kinds = rng.choice(4, size=count - 1, p=[0.7, 0.15, 0.1, 0.05])
    heading = rng.uniform(0.0, 2.0 * math.pi)
    steps = []
    for kind in kinds:
        heading += rng.normal(0.0, 0.3)
        length = step_m * rng.uniform(0.95, 1.03)
        angle = heading
        if kind == 1:
            length, angle = rng.uniform(step_m, step_m + 2 * jitter), rng.uniform(0, 7)
        elif kind == 2:
            length = 0.0
        elif kind == 3:
            # stand until the set is the whole polygon, then jump along a normal m_k so far
            # that the far edge of P_N(p, eps + v dt) is the near edge of the next P_N(p', eps)
            steps += [[0.0, 0.0]] * min(math.ceil(2 * jitter / step_m) + 1, 41)
            length = (2.0 * jitter + step_m) * math.cos(math.pi / sides)
            angle = 2.0 * math.pi * (rng.integers(sides) + 0.5) / sides + math.pi / 64
        steps.append([length * math.cos(angle), length * math.sin(angle)])
    origin = rng.uniform(-100.0, 100.0, 2)
    positions = origin + np.vstack([[0.0, 0.0], np.cumsum(steps, axis=0)])
    return positions, MotionBounds(step_m / STEP_S, jitter, STEP_S), sides


@SETTINGS
@given(walks())
def test_the_kernels_sets_lie_between_the_references_for_moved_bounds(walk):
    """Step by step from P_N(p_0, eps), no fast path: low ⊆ kernel ⊆ high (see above)."""
    positions, bounds, sides = walk
    unit, mids = unit_polygon(sides), _mids(sides)
    sectors = disc(positions[0], bounds.jitter_m, unit)
    low_bounds, high_bounds = _moved(bounds, -DELTA), _moved(bounds, DELTA)
    low: np.ndarray | None = assumptions.disc(positions[0], low_bounds.jitter_m, sides)
    high: np.ndarray | None = assumptions.disc(positions[0], high_bounds.jitter_m, sides)
    for position in positions[1:]:
        nonempty, whole = polygon_step(sectors, position, unit, mids, bounds.step_m,
                                       bounds.jitter_m)
        low = None if low is None else advance(low, position, low_bounds, sides)
        high = None if high is None else advance(high, position, high_bounds, sides)
        if low is not None:
            assert nonempty and _within(low, _polygon(sectors))
        if not nonempty:
            break
        assert high is not None and _within(_polygon(sectors), high)
        if whole:
            np.testing.assert_array_equal(sectors, disc(position, bounds.jitter_m, unit))


@SETTINGS
@given(walks(sides_from=(16, 64, 256)), st.sampled_from([-1e-8, -1e-10, 0.0, 1e-10, 1e-8]))
def test_admits_decides_as_the_reference_for_moved_bounds_also_at_the_least_jitter(walk, off):
    """``admits`` (the fast path and the recursion) at the least jitter the kernel admits
    (bisected to 1e-12 m) moved by ``off``: where the reference admits the walk with both
    bounds DELTA smaller, so does the kernel; where the kernel does, the reference does with
    both DELTA larger. (4096-gons: the test above, and SUMO's walks below.)"""
    positions, bounds, sides = walk
    low, high = 0.0, bounds.step_m + bounds.jitter_m + float(np.abs(np.diff(
        positions, axis=0)).sum())
    while high - low > 1e-12:
        middle = 0.5 * (low + high)
        if admits(positions, MotionBounds(bounds.speed_mps, middle, STEP_S), sides):
            high = middle
        else:
            low = middle
    at = MotionBounds(bounds.speed_mps, max(high + off, DELTA), STEP_S)
    got = admits(positions, at, sides)
    if admits_reference(positions, _moved(at, -DELTA), sides):
        assert got
    if got:
        assert admits_reference(positions, _moved(at, DELTA), sides)


def test_a_point_set_zero_jitter_is_the_speed_bound_alone():
    """eps = 0: P_N(p, 0) is the point p; a step just inside P_N(v dt) keeps it (the whole
    'polygon' again), one just outside empties the set; a walk with steps just longer than
    v dt is not admitted, as by the reference."""
    sides, bounds = 64, MotionBounds(2.5, 0.0, STEP_S)
    unit, mids = unit_polygon(sides), _mids(sides)
    start = np.array([3.0, -2.0])
    for factor, expected in ((1.0 - 1e-9, True), (1.0 + 1e-9, False)):
        sectors = disc(start, 0.0, unit)
        position = start + factor * bounds.step_m * unit[5]  # towards a vertex of P_N(v dt)
        assert polygon_step(sectors, position, unit, mids, bounds.step_m, 0.0) == (
            expected, expected)
        if expected:
            assert (sectors == position).all()
        walk = start + np.arange(3)[:, np.newaxis] * (position - start)
        assert admits(walk, bounds, sides) == admits_reference(walk, bounds, sides) == expected


@pytest.fixture(scope="module")
def paper_walks(tmp_path_factory) -> list[np.ndarray]:
    """Every passage of the paper road walked alone at 2.5 m/s in SUMO (as the jitter
    measurement walks them)."""
    work = tmp_path_factory.mktemp("paper_walks")
    net_path = work / "paper.net.xml"
    shutil.copyfile(build_network(REPO / "sumo_net"), net_path)
    net = sumolib.net.readNet(str(net_path), withInternal=True, withPedestrianConnections=True)
    areas = [e for e in net.getEdges(withInternal=True) if e.getFunction() == "walkingarea"]
    walkers = [Walker(f"w{i}", edges, depart, arrival, 2.5, depart_s=30.0 * i, radius_m=0.3)
               for i, (_, edges, depart, arrival)
               in enumerate(walker_jitter.passages(net, areas))]
    traces = walk_alone(net_path, walkers, STEP_S, Path(work / "probe"))
    return [traces[w.id].xy for w in walkers]


@pytest.mark.sumo
def test_least_jitter_on_sumos_walks_is_the_references(paper_walks, monkeypatch):
    """The least jitter of each walk, bisected by the kernel and by the reference: within
    1 mm (least_jitter rounds up to 1 mm; the two may differ only where a bisection's middle
    falls within DELTA of a walk's threshold)."""
    bounds = MotionBounds(2.5, 0.0, STEP_S)
    compiled = [least_jitter(xy, bounds) for xy in paper_walks]
    monkeypatch.setattr(assumptions, "admits", admits_reference)
    reference = [least_jitter(xy, bounds) for xy in paper_walks]
    assert max(compiled) > 0.1  # the walks do jump
    np.testing.assert_allclose(compiled, reference, rtol=0, atol=1e-3 + 1e-12)


@pytest.mark.sumo
def test_admits_on_sumos_walks_decides_as_the_reference(paper_walks):
    """Around each walk's least jitter (±5 mm with 64-gons; ±1 mm with 4096-gons for the walk
    that needs the most): the same decisions wherever the reference's is the same for both
    bounds moved by ±DELTA."""
    needed = [least_jitter(xy, MotionBounds(2.5, 0.0, STEP_S)) for xy in paper_walks]
    worst = int(np.argmax(needed))
    cases = [(xy, jitter, 64) for xy, least in zip(paper_walks, needed, strict=True)
             for jitter in least + np.array([-5e-3, -1e-3, 0.0, 1e-3, 5e-3]) if jitter > 0.0]
    cases += [(paper_walks[worst], needed[worst] + off, 4096) for off in (-1e-3, 1e-3)]
    compared = 0
    for xy, jitter, sides in cases:
        at = MotionBounds(2.5, jitter, STEP_S)
        low = admits_reference(xy, _moved(at, -DELTA), sides)
        if low == admits_reference(xy, _moved(at, DELTA), sides):
            assert admits(xy, at, sides) == low
            compared += 1
    assert compared >= 0.9 * len(cases)
