"""The compiled n-D volume gain (sets/volume_gain_kernels.py) against the LP it replaces
(``gains.volume_gain_lp``, cvxpy and HiGHS), an exact brute force over the vertices of the
arrangement, and the NumPy references of its cofactors and volumes.

The minima are compared within 1e-9 relative, plus 100 eps times a bound on the size of the
objective's terms before cancellation (:func:`term_size`): the rounding of evaluating f at a
vertex whose determinants cancel (nearly parallel generators) reaches that far, whichever
solver found the vertex. ``make test`` runs these tests again with numba's generic CPU (the
``kernels`` marker).
"""

from itertools import combinations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from sets_strategies import (
    EPS,
    SETTINGS,
    point_in,
    random_generators,
    strip_intersection_points,
    zonotopes,
)

from sse_cosim.sets import Strips, Zonotope, gains, intersect_strips
from sse_cosim.sets import volume_gain_kernels as kernels
from sse_cosim.sets.zonotope import (
    cofactor_vectors,
    full_rank,
    generator_volume,
    generator_volume_reference,
)

pytestmark = pytest.mark.kernels

WELL_CONDITIONED = ("well", "zero-and-parallel", "axis", "grid")
ILL_CONDITIONED = ("elongated", "near-parallel")  # nearly flat or nearly parallel
NORMALS = ("random", "axis", "generator", "across")
RADII = (0.0, 1e-6, 0.05, 0.3, 0.9, 1.5)  # fractions of Z's half-width along h


def generators_of(rng: np.random.Generator, n: int, e: int, kind: str) -> np.ndarray:
    """(n, e) generators of a full-rank kind of sets_strategies, or ``axis`` (random columns
    and an axis-aligned box, as a Girard reduction leaves them) or ``grid`` (entries in
    {-2, ..., 2}: many exactly coincident vertices)."""
    if kind == "axis":
        return np.hstack([rng.normal(size=(n, e - n)), np.diag(rng.uniform(0.1, 2.0, n))])
    if kind == "grid":
        g = rng.integers(-2, 3, size=(n, e)).astype(float)
        g[:, :n] += 5.0 * np.eye(n)  # full rank
        return g
    return random_generators(rng, n, e, kind)


def normal_of(rng: np.random.Generator, g: np.ndarray, kind: str) -> np.ndarray:
    """A unit strip normal: random, a coordinate axis, along g_0, or across g_0 and g_1."""
    n = g.shape[0]
    if kind == "axis":
        return np.eye(n)[rng.integers(n)]
    if kind == "generator":
        h = g[:, 0]
    elif kind == "across":
        h = np.linalg.qr(np.hstack([g[:, :2], rng.normal(size=(n, n - 2))]))[0][:, -1]
    else:
        h = rng.normal(size=n)
    return h / np.linalg.norm(h)


@st.composite
def gain_problems(draw: st.DrawFn, kinds: tuple[str, ...], dims: tuple[int, ...] = (3, 4, 5),
                  max_generators: int = 14) -> tuple[np.ndarray, np.ndarray, float]:
    """(G, h, r): G (n, e), 4 <= e <= max_generators, full rank, at scales 1e-3 .. 1e3; h a
    unit normal; r a fraction of Z's half-width along h."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n = draw(st.sampled_from(dims))
    e = draw(st.integers(max(4, n), max_generators))
    g = generators_of(rng, n, e, draw(st.sampled_from(kinds)))
    g = g * draw(st.sampled_from([1e-3, 1.0, 1e3]))
    h = normal_of(rng, g, draw(st.sampled_from(NORMALS)))
    return g, h, float(np.abs(h @ g).sum() * draw(st.sampled_from(RADII)))


def term_size(g: np.ndarray, h: np.ndarray, r: float, lam: np.ndarray) -> float:
    """A bound on f's terms at λ before cancellation: Hadamard's bound Π‖g_j‖ on every
    |det G_T| times (1 + |hᵀλ|), plus r times Hadamard's bound on every ‖d_S‖ times ‖λ‖."""
    n, e = g.shape
    norms = np.linalg.norm(g, axis=0)
    full = sum(np.prod(norms[list(t)]) for t in combinations(range(e), n))
    cuts = sum(np.prod(norms[list(s)]) for s in combinations(range(e), n - 1))
    return full * (1.0 + abs(h @ lam)) + r * cuts * np.linalg.norm(lam)


def values_and_slack(g: np.ndarray, h: np.ndarray, r: float, *lams: np.ndarray
                     ) -> tuple[np.ndarray, float]:
    """f at each λ (``gains.strip_gain_volume``) and the rounding slack 100 eps · term_size."""
    slack = 100 * EPS * max(term_size(g, h, r, lam) for lam in lams)
    return gains.strip_gain_volume(g, h, r, np.vstack(lams)), slack


def brute_force_minimum(g: np.ndarray, h: np.ndarray, r: float) -> float:
    """min f over λ = 0 and every vertex of the arrangement on hᵀλ = 1 (h and n - 1
    independent rows of D): the exact minimum (min f = min(V, r·min φ on the plane), and φ,
    piecewise linear and bounded below, is least at a vertex when D has rank n)."""
    n = g.shape[0]
    d = cofactor_vectors(g)
    d = d[np.any(d != 0, axis=1)]
    subsets = np.array(list(combinations(range(len(d)), n - 1)))
    bases = np.concatenate([np.broadcast_to(h, (len(subsets), 1, n)), d[subsets]], axis=1)
    scale = np.prod(np.linalg.norm(bases, axis=2), axis=1)
    regular = np.abs(np.linalg.det(bases)) > 1e-12 * scale
    rhs = np.broadcast_to(np.eye(n)[0], (int(regular.sum()), n))[..., None]
    vertices = np.linalg.solve(bases[regular], rhs)[..., 0]
    return float(gains.strip_gain_volume(g, h, r, np.vstack([np.zeros(n), vertices])).min())


@SETTINGS
@given(gain_problems(WELL_CONDITIONED + ILL_CONDITIONED))
def test_simplex_gain_is_never_above_the_lp(problem):
    # Equal to the LP's minimum wherever HiGHS finds it; but HiGHS stops within its
    # feasibility tolerance (1e-7) of problems scaled by tiny determinants, and in random
    # cases it returned up to 90 % above the minimum (of the ill-conditioned kinds, about one
    # case in five; of the others, a few in a thousand), a minimum the brute force below
    # confirms. So the comparison with the LP is one-sided, and the one with the exact
    # minimum two-sided.
    g, h, r = problem
    lam, lp = gains.volume_gain_simplex(g, h, r), gains.volume_gain_lp(g, h, r)
    (simplex, solved), slack = values_and_slack(g, h, r, lam, lp)
    assert simplex <= solved * (1 + 1e-9) + slack, (simplex, solved)


@SETTINGS
@given(st.one_of(gain_problems(WELL_CONDITIONED + ILL_CONDITIONED, dims=(3,), max_generators=7),
                 gain_problems(WELL_CONDITIONED + ILL_CONDITIONED, dims=(4,), max_generators=6),
                 gain_problems(WELL_CONDITIONED + ILL_CONDITIONED, dims=(5,), max_generators=6)))
def test_simplex_gain_is_the_exact_minimum_over_the_vertices(problem):
    # Up to C(21, 2), C(20, 3) and C(15, 4) vertices: every one of them tried.
    g, h, r = problem
    lam = gains.volume_gain_simplex(g, h, r)
    (simplex,), slack = values_and_slack(g, h, r, lam)
    exact = brute_force_minimum(g, h, r)
    assert abs(simplex - exact) <= 1e-9 * exact + slack, (simplex, exact)


@SETTINGS
@given(gain_problems(WELL_CONDITIONED + ILL_CONDITIONED))
def test_the_solver_certifies_its_minimum_for_full_rank_sets(problem):
    # Without a certificate the gain would be the last vertex reached (or λ = 0): for a
    # full-rank G (D of rank n) the simplex method always ends with one.
    g, h, _ = problem
    scaled = g / np.abs(g).max()
    rows, weights = kernels.unit_rows(kernels.cofactor_rows(scaled))
    mu, certified = kernels.plane_l1_minimizer(rows, weights, h)
    assert certified
    assert abs(h @ mu - 1.0) <= 1e-9 * np.abs(h * mu).sum()


@pytest.mark.parametrize("n", [3, 4, 5])
def test_flat_sets_zero_generators_and_zero_normals_get_lambda_zero(n):
    # V = 0 for a flat set: λ = 0 is optimal (f >= 0 = f(0)). With a zero row every n-minor
    # is exactly 0, so nothing beats λ = 0; a rank-1 G's minors are 0 only up to rounding, so
    # there the gain is λ = 0 or a λ just as good. A zero G or normal has nothing to choose.
    rng = np.random.default_rng(n)
    flat = rng.normal(size=(n, n + 3))
    flat[-1] = 0.0
    h = rng.normal(size=n)
    h /= np.linalg.norm(h)
    for g, normal in [(flat, h), (flat, np.eye(n)[-1]),  # h ⊥ every generator
                      (np.zeros((n, 5)), h), (rng.normal(size=(n, n + 2)), np.zeros(n))]:
        assert np.array_equal(gains.volume_gain_simplex(g, normal, 0.3), np.zeros(n))
    thin = np.outer(rng.normal(size=n), rng.normal(size=n + 2))
    lam = gains.volume_gain_simplex(thin, h, 0.3)
    (value,), slack = values_and_slack(thin, h, 0.3, lam)
    assert value <= slack


@pytest.mark.parametrize("n", [3, 4, 5])
def test_a_covering_strip_gets_lambda_zero_and_a_hyperplane_a_flat_set(n):
    rng = np.random.default_rng(10 + n)
    g = rng.normal(size=(n, n + 4))
    h = rng.normal(size=n)
    h /= np.linalg.norm(h)
    width = np.abs(h @ g).sum()
    # r >= the half-width: Z ∩ S = Z, so f >= V everywhere and r·m >= 1.5 V > V
    assert np.array_equal(gains.volume_gain_simplex(g, h, 1.5 * width), np.zeros(n))
    lam = gains.volume_gain_simplex(g, h, 0.0)  # r = 0: any λ with hᵀλ = 1 flattens Z
    (value,), slack = values_and_slack(g, h, 0.0, lam)
    assert value <= slack


def test_a_4d_set_of_the_bounded_acceleration_model():
    # A set of the S3 run (position and velocity, generators with entries down to 1e-273)
    # and a velocity strip: the LP's minimum.
    g = np.array([
        [2.2204460492503131e-16, -5.5511151231257827e-17, -9.2425952044279274e-274, 0.0, 0.0,
         -1.0194935404950370e-35, 0.0, -4.5410226010201930e-19, 0.0, 0.0,
         -1.5899139100718063, -4.2601614823874956e-01],
        [0.0, 0.0, -3.6970380817711710e-273, -4.0332382775966673e-34,
         -1.3605008155072058e-33, 0.0, -4.5410226010201930e-19, 0.0, 0.0, 0.0,
         4.2601614823874956e-01, -1.5899139100718063],
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.5, 0.0, 3.2000000000000006e-01, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.5, 0.0, 3.2000000000000006e-01, 0.0, 0.0],
    ])
    for h, r in ((np.array([0.0, 0.0, 1.0, 0.0]), 2.5), (np.array([0.0, 0.0, 1.0, 1.0]) / 2**0.5,
                                                          0.4), (np.eye(4)[0], 0.1)):
        lam, lp = gains.volume_gain_simplex(g, h, r), gains.volume_gain_lp(g, h, r)
        (simplex, solved), slack = values_and_slack(g, h, r, lam, lp)
        assert abs(simplex - solved) <= 1e-9 * solved + slack, (h, simplex, solved)


@SETTINGS
@given(zonotopes(4), st.integers(0, 2**32 - 1))
def test_volume_correction_in_4d_is_never_above_cvxpy_volume(zonotope, seed):
    # One strip: both corrections are min(f(λ), the Frobenius gain's, V) · 2ⁿ with their own λ.
    rng = np.random.default_rng(seed)
    h = rng.normal(size=4)
    h /= np.linalg.norm(h)
    width = np.abs(h @ zonotope.generators).sum()
    strip = Strips(h, h @ zonotope.center + rng.uniform(-0.5, 0.5) * width,
                   width * rng.uniform(0.05, 1.2))
    fast = intersect_strips(zonotope, strip, "volume").volume()
    solved = intersect_strips(zonotope, strip, "cvxpy-volume").volume()
    slack = 16 * 100 * EPS * term_size(zonotope.generators, h, strip.radii[0], np.zeros(4))
    assert fast <= solved * (1 + 1e-9) + slack


@st.composite
def generator_matrices(draw: st.DrawFn) -> np.ndarray:
    """(n, e) generators, 3 <= n <= 6, e >= 0 columns of every kind, some all zero, at
    scales 1e-3 .. 1e3."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n = draw(st.integers(3, 6))
    e = draw(st.integers(0, 10))
    kind = draw(st.sampled_from(("well", "elongated", "near-parallel", "zero-and-parallel")))
    g = random_generators(rng, n, e, kind) if e else np.zeros((n, 0))
    if draw(st.booleans()):
        g = np.hstack([g, np.zeros((n, draw(st.integers(1, 2))))])
    return g * draw(st.sampled_from([1e-3, 1.0, 1e3]))


@SETTINGS
@given(generator_matrices())
def test_compiled_cofactors_and_volume_are_the_references_within_rounding(g):
    # Each cofactor is a (n-1)-minor, each determinant of the volume an n-minor: elimination
    # (or the closed form for orders 2 and 3) here, LAPACK's LU and QR there. Both are
    # backward stable, each within a few k² eps (k the order) of Hadamard's bound Π‖g_j‖ on
    # its columns.
    n, e = g.shape
    norms = np.linalg.norm(g, axis=0)
    got, expected = kernels.cofactor_rows(g), cofactor_vectors(g)
    assert got.shape == expected.shape
    if len(expected):
        bound = np.array([np.prod(norms[list(s)]) for s in combinations(range(e), n - 1)])
        assert (np.abs(got - expected) <= 16 * n * n * EPS * bound[:, None]).all()
    full = sum(np.prod(norms[list(t)]) for t in combinations(range(e), n))
    reference = generator_volume_reference(g)
    assert abs(generator_volume(g) - reference) <= 2**n * 16 * n * n * EPS * full
    assert generator_volume(Zonotope(np.zeros(n), g).generators) == generator_volume(g)


def test_singular_values_and_the_rank_test_match_lapacks():
    # One-sided Jacobi against LAPACK's SVD, both backward stable: each singular value within
    # a few eps·s_max of the exact one (within 7.1 of each other over 5000 such matrices;
    # 4n allowed). numpy's matrix_rank tolerance s_min > e·eps·s_max then gives the same
    # answer wherever s_min is more than 4 eps·s_max from it (near it either answer is
    # right: s_min is rounding there); a zero row stays exactly zero under the rotations.
    rng = np.random.default_rng(4)
    compared = deficient = 0
    for _ in range(2000):
        n = int(rng.integers(3, 7))
        e = int(rng.integers(n, n + 8))
        kind = ("well", "elongated", "near-parallel", "zero-and-parallel", "flat",
                "rank-one")[rng.integers(6)]
        if kind == "flat":
            g = rng.normal(size=(n, e))
            g[rng.integers(n)] = 0.0
        elif kind == "rank-one":
            g = np.outer(rng.normal(size=n), rng.normal(size=e))
        else:
            g = random_generators(rng, n, e, kind)
        g *= 10.0 ** rng.integers(-3, 4)
        s = np.linalg.svd(g, compute_uv=False)
        got = np.sort(kernels.singular_values(g))[::-1]
        assert np.abs(got - s).max() <= 4 * n * EPS * s[0]
        if abs(s[-1] - e * EPS * s[0]) <= 4 * EPS * s[0]:
            continue
        rank_n = np.linalg.matrix_rank(g) == n
        assert kernels.full_rank_nd(g) == full_rank(g) == rank_n
        compared += 1
        deficient += not rank_n
    assert compared > 1800 and deficient > 500
    assert not full_rank(rng.normal(size=(4, 3))) and not full_rank(np.zeros((3, 5)))


@st.composite
def corrections(draw: st.DrawFn) -> tuple[Zonotope, Strips, bool, bool]:
    """(Z, S, flat, common): a 3-D or 4-D Z, full rank or ``flat`` (a zero row, or rank one),
    and 1..8 strips with normals of any length that cut it or cover it, all through one point
    of Z (``common``), or with some that barely touch it or miss it (Z ∩ S empty)."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n = draw(st.sampled_from((3, 4)))
    zonotope = draw(zonotopes(n, max_generators=n + 5))
    flat = draw(st.sampled_from(("", "zero-row", "rank-one")))
    g = zonotope.generators
    if flat == "zero-row":
        g = g.copy()
        g[rng.integers(n)] = 0.0
    elif flat == "rank-one":
        g = np.outer(g[:, 0], np.linspace(0.5, 1.5, g.shape[1]))
    zonotope = Zonotope(zonotope.center, g)
    m = draw(st.integers(1, 8))
    normals = rng.normal(size=(m, n)) * rng.uniform(0.5, 3.0, (m, 1))
    if draw(st.booleans()):  # along the axes, as the motion models' strips
        normals = np.eye(n)[rng.integers(n, size=m)] * rng.uniform(0.5, 3.0, (m, 1))
    width = np.abs(normals @ g).sum(axis=1)
    kind = rng.choice(("cut", "cover", "touch", "miss"), size=m,
                      p=draw(st.sampled_from(((1, 0, 0, 0), (0.6, 0.2, 0.1, 0.1)))))
    radii = np.where(kind == "cover", 1.5, rng.uniform(0.05, 0.8, m)) * width + 1e-3
    inner = normals @ point_in(zonotope, rng) + rng.uniform(-1, 1, m) * radii
    edge = normals @ zonotope.center + width
    values = np.select([kind == "touch", kind == "miss"],
                       [edge + radii * (1 - 1e-9), edge + 2 * radii], inner)
    common = not np.isin(kind, ("touch", "miss")).any()
    return zonotope, Strips(normals, values, radii), bool(flat), common


@SETTINGS
@given(corrections(), st.integers(0, 2**32 - 1))
def test_compiled_nd_volume_correction_matches_the_reference_and_is_sound(case, seed):
    # volume_correction_nd against gains.volume_correction_reference (NumPy and BLAS for the
    # sequential updates and the candidates' G'; the same compiled one-strip gain, volume
    # and rank test). The same set up to rounding: the same volume and the same support
    # in every direction (generators may differ by a column that cancels exactly on one
    # side and keeps a rounding's length on the other). A flat set's candidates may all
    # have volume 0 up to rounding, so there only the volume must agree, in units of
    # (2 max |g_ij|)ⁿ. Every extreme point of a nonempty Z ∩ S lies in the result. (Over 600
    # cases: volumes within 5e-13 relative, flat ones within 3e-17 of that unit, supports
    # within 3e-14 of the scale.)
    zonotope, strips, flat, common = case
    unit = strips.normalized()
    reference = gains.volume_correction_reference(zonotope, unit)
    compiled = intersect_strips(zonotope, strips, "volume")
    n = zonotope.dim
    size = np.abs(zonotope.generators).max()
    scale = max(size, np.abs(zonotope.center).max())
    gap = abs(compiled.volume() - reference.volume())
    assert gap <= (1e-12 * (2 * size) ** n if flat else 1e-9 * reference.volume())
    rng = np.random.default_rng(seed)
    if not flat:
        directions = rng.normal(size=(64, n))
        directions /= np.linalg.norm(directions, axis=1)[:, None]
        np.testing.assert_allclose(compiled.support(directions), reference.support(directions),
                                   rtol=0, atol=1e-9 * scale)
    if common:
        points = strip_intersection_points(zonotope, unit, rng)
        assert compiled.contains(points, tol=1e-9 * scale).all()
