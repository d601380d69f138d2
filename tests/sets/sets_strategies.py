"""Hypothesis strategies and exact references shared by the set-library tests."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from scipy.optimize import linprog
from shapely import get_coordinates
from shapely.geometry import Point
from shapely.geometry.base import BaseGeometry

from sse_cosim.sets import Strips, Zonotope

SETTINGS = settings(
    derandomize=True,
    deadline=None,
    database=None,
    max_examples=40,
    suppress_health_check=[HealthCheck.too_slow],
)

KINDS = ("well", "elongated", "near-parallel", "zero-and-parallel")

EPS = float(np.finfo(np.float64).eps)


def sum_rtol(count: int) -> float:
    """How far apart, relatively, two sums of the same ``count`` nonnegative terms may be when
    they add them in different orders (numpy's pairwise order, a compiled loop, another NumPy
    build): each is within (count - 1)·eps/2 of the exact sum, so together within count·eps."""
    return max(count, 1) * EPS


def rank_decision_is_clear(generators: np.ndarray) -> bool:
    """Whether the 2-D rank test of ``zonotope.full_rank`` and ``kernels.full_rank_2d``
    (s_min·s_max > e·eps·s_max², from 2×2 minors) is decided by more than the rounding of two
    implementations of it can move it.

    Each computes s_min·s_max within eps·(p + q)/√2 of the exact value of its arrays (p, q the
    squared row norms: every cross product a_i b_j - b_i a_j is within eps(|a_i b_j| +
    |b_i a_j|), with or without FMA, and those bounds have a Euclidean norm <= 2 eps √(pq)),
    plus e²·eps relative for the sum and the root; the threshold moves far less (e²·eps²).
    Two of them may thus disagree only within 2 eps (p + q) + e² eps s_min·s_max of it. Fewer
    than two columns, or all zero, is decided without rounding."""
    a, b = generators
    e = generators.shape[1]
    p, q, r = float(np.dot(a, a)), float(np.dot(b, b)), float(np.dot(a, b))
    if e < 2 or p + q == 0.0:
        return True
    s_max2 = 0.5 * (p + q) + np.sqrt(0.25 * (p - q) ** 2 + r * r)
    cross = a[:, None] * b - b[:, None] * a
    s_prod = np.sqrt(0.5 * (cross * cross).sum())
    return bool(abs(s_prod - e * EPS * s_max2) > 2 * EPS * (p + q) + e * e * EPS * s_prod)


def random_generators(rng: np.random.Generator, n: int, e: int, kind: str) -> np.ndarray:
    """(n, e) generators: well-conditioned or one of three ill-conditioned families."""
    g = rng.normal(size=(n, e))
    if kind == "elongated":
        rotation = np.linalg.qr(rng.normal(size=(n, n)))[0]
        g = rotation @ (np.logspace(0, -3, n)[:, None] * g)
    elif kind == "near-parallel":
        g = np.outer(rng.normal(size=n), rng.normal(size=e)) + 1e-3 * g
    elif kind == "zero-and-parallel":
        g = np.hstack([g, np.zeros((n, 1)), -2.5 * g[:, :1]])
    return g


@st.composite
def zonotopes(draw: st.DrawFn, n: int, min_generators: int | None = None,
              max_generators: int = 7) -> Zonotope:
    """Random full-rank n-D zonotopes, well- and ill-conditioned, at scales 1e-2 .. 1e2."""
    low = n if min_generators is None else min_generators
    seed = draw(st.integers(0, 2**32 - 1))
    kind = draw(st.sampled_from(KINDS))
    e = draw(st.integers(low, max_generators))
    scale = draw(st.sampled_from([1e-2, 1.0, 1e2]))
    rng = np.random.default_rng(seed)
    return Zonotope(scale * rng.uniform(-10, 10, n), scale * random_generators(rng, n, e, kind))


def point_in(zonotope: Zonotope, rng: np.random.Generator) -> np.ndarray:
    """A random point of Z (random β in [-1, 1]^e)."""
    return zonotope.center + zonotope.generators @ rng.uniform(-1, 1, zonotope.n_generators)


@st.composite
def cutting_strips(draw: st.DrawFn, zonotope: Zonotope, max_strips: int = 3) -> Strips:
    """1..max_strips strips narrower than Z that all contain one common point of Z; normals
    random (unnormalized) or nearly parallel."""
    seed = draw(st.integers(0, 2**32 - 1))
    m = draw(st.integers(1, max_strips))
    parallel = draw(st.booleans())
    rng = np.random.default_rng(seed)
    n = zonotope.dim
    normals = rng.normal(size=(m, n))
    if parallel:
        normals = normals[:1] + 1e-3 * normals
    normals *= rng.uniform(0.5, 3.0, (m, 1))
    width = np.abs(normals @ zonotope.generators).sum(axis=1)
    radii = width * rng.uniform(0.05, 0.8, m)
    values = normals @ point_in(zonotope, rng) + rng.uniform(-1, 1, m) * radii
    return Strips(normals, values, radii)


@st.composite
def zonotope_with_strips(draw: st.DrawFn, n: int, max_strips: int = 3
                         ) -> tuple[Zonotope, Strips]:
    zonotope = draw(zonotopes(n))
    return zonotope, draw(cutting_strips(zonotope, max_strips))


@st.composite
def overlapping_zonotopes(draw: st.DrawFn, n: int, max_inputs: int = 4) -> list[Zonotope]:
    """2..max_inputs zonotopes of similar size that share a common point."""
    seed = draw(st.integers(0, 2**32 - 1))
    m = draw(st.integers(2, max_inputs))
    kinds = draw(st.lists(st.sampled_from(KINDS), min_size=m, max_size=m))
    rng = np.random.default_rng(seed)
    common = rng.uniform(-10, 10, n)
    result = []
    for kind in kinds:
        g = random_generators(rng, n, int(rng.integers(n, n + 4)), kind)
        result.append(Zonotope(common - g @ rng.uniform(-1, 1, g.shape[1]), g))
    return result


def tolerance(*sets: Zonotope) -> float:
    """1e-9 scaled by the size and position of the sets."""
    size = max(max(np.abs(z.center).max(), np.abs(z.generators).sum(axis=1).max()) for z in sets)
    return 1e-9 * max(1.0, size)


def polygon_points(geometry: BaseGeometry, rng: np.random.Generator, count: int = 200
                   ) -> np.ndarray:
    """The vertices of a 2-D geometry plus points rejection-sampled inside it."""
    x0, y0, x1, y1 = geometry.bounds
    samples = rng.uniform([x0, y0], [x1, y1], size=(count, 2))
    inside = np.array([p for p in samples if geometry.covers(Point(p))]).reshape(-1, 2)
    return np.vstack([get_coordinates(geometry), inside])


def extreme_points(
    equality: tuple[np.ndarray, np.ndarray],
    inequality: tuple[np.ndarray, np.ndarray],
    to_state: tuple[np.ndarray, np.ndarray],
    rng: np.random.Generator,
    count: int = 30,
) -> np.ndarray:
    """Maximizers x = a + Bβ of random linear functions over {β ∈ [-1, 1]^k : Eβ = f, Aβ <= b}:
    vertices of an exact set, the hardest points for a soundness check."""
    a_eq, b_eq = equality
    a_ub, b_ub = inequality
    offset, basis = to_state
    k = basis.shape[1]
    points = []
    for _ in range(count):
        direction = rng.normal(size=basis.shape[0])
        result = linprog(
            -(direction @ basis),
            A_ub=a_ub if len(a_ub) else None,
            b_ub=b_ub if len(b_ub) else None,
            A_eq=a_eq if len(a_eq) else None,
            b_eq=b_eq if len(b_eq) else None,
            bounds=[(-1, 1)] * k,
            method="highs",
            options={"primal_feasibility_tolerance": 1e-10},
        )
        assert result.status == 0, result.message
        points.append(offset + basis @ np.clip(result.x, -1, 1))
    return np.array(points)


def strip_intersection_points(zonotope: Zonotope, strips: Strips, rng: np.random.Generator
                              ) -> np.ndarray:
    """Extreme points of the exact Z ∩ S (n-D), strips shrunk by 1e-8 against LP tolerance."""
    h, c, g = strips.normals, zonotope.center, zonotope.generators
    radii = strips.radii * (1 - 1e-8)
    a_ub = np.vstack([h @ g, -(h @ g)])
    b_ub = np.concatenate([strips.values + radii - h @ c, -(strips.values - radii - h @ c)])
    none = (np.zeros((0, g.shape[1])), np.zeros(0))
    return extreme_points(none, (a_ub, b_ub), (c, g), rng)


def zonotope_intersection_points(sets: list[Zonotope], rng: np.random.Generator) -> np.ndarray:
    """Extreme points of the exact ∩_j Z_j (n-D): c_1 + G_1β_1 = c_j + G_jβ_j for every j."""
    sizes = [z.n_generators for z in sets]
    blocks = np.split(np.arange(sum(sizes)), np.cumsum(sizes)[:-1])
    n, k = sets[0].dim, sum(sizes)
    rows, rhs = [], []
    for z, block in zip(sets[1:], blocks[1:], strict=True):
        row = np.zeros((n, k))
        row[:, blocks[0]] = sets[0].generators
        row[:, block] = -z.generators
        rows.append(row)
        rhs.append(z.center - sets[0].center)
    basis = np.zeros((n, k))
    basis[:, blocks[0]] = sets[0].generators
    none = (np.zeros((0, k)), np.zeros(0))
    equality = (np.vstack(rows), np.concatenate(rhs))
    return extreme_points(equality, none, (sets[0].center, basis), rng)
