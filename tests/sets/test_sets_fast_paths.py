"""The set library's fast paths against the general code and the exact references."""

import numpy as np
import pytest
import shapely

from sse_cosim.sets import Strips, Zonotope, gains, intersect_strips, zonotope_facet_strips
from sse_cosim.sets.exact import intersect_strips_exact, zonotope_polygon
from sse_cosim.sets.zonotope import facet_normals, full_rank, generator_volume


def random_generators(rng, e):
    g = rng.normal(size=(2, e)) * 10 ** rng.uniform(-4, 4)
    if e > 1 and rng.random() < 0.3:
        g[:, -1] = g[:, 0] * rng.normal()  # parallel columns
    if rng.random() < 0.2:
        g[1] = g[0] * rng.normal()  # rank one
    if rng.random() < 0.1:
        g[:, 0] = 0.0
    return g


def test_full_rank_matches_numpy_matrix_rank():
    # Two implementations of one test, s_min > max(2, e)·eps·s_max: the closed form (2×2
    # minors) and LAPACK's SVD (whose kernels round by CPU). Each finds s_min within a few
    # eps·s_max of the exact value (LAPACK within 1.8 over these matrices here, the closed form
    # within 1.5 by its error bound): where s_min lies within 4 eps·s_max of the threshold either
    # answer is right, and those (columns parallel up to rounding) are left out.
    eps = np.finfo(np.float64).eps
    rng = np.random.default_rng(1)
    compared = deficient = 0
    for _ in range(3000):
        g = random_generators(rng, int(rng.integers(1, 10)))
        s = np.linalg.svd(g, compute_uv=False)
        threshold = max(g.shape) * eps * s[0]
        if g.shape[1] >= 2 and s[0] > 0 and abs(s[-1] - threshold) <= 4 * eps * s[0]:
            continue
        rank_two = np.linalg.matrix_rank(g) == 2
        assert full_rank(g) == rank_two
        compared += 1
        deficient += not rank_two
    assert compared > 2500 and deficient > 400  # rank-one sets among them, away from the edge
    g3 = rng.normal(size=(3, 5))
    assert full_rank(g3) and not full_rank(np.zeros((3, 5)))


def test_2d_facet_normals_and_volume_match_the_general_formulas():
    rng = np.random.default_rng(2)
    for _ in range(500):
        g = random_generators(rng, int(rng.integers(2, 10)))
        d = np.stack([-g[1], g[0]], axis=1)
        norms = np.linalg.norm(d, axis=1)
        units = d[norms > 0] / norms[norms > 0, None]
        rounded = np.round(units, 12) + 0.0
        first = np.argmax(rounded != 0, axis=1)
        sign = np.sign(rounded[np.arange(len(units)), first])
        _, keep = np.unique(rounded * sign[:, None] + 0.0, axis=0, return_index=True)
        expected = units[np.sort(keep)] * sign[np.sort(keep), None]
        np.testing.assert_array_equal(facet_normals(g), expected)
        nz = g[:, np.any(g != 0, axis=0)]
        cross = np.outer(nz[0], nz[1]) - np.outer(nz[1], nz[0])
        assert generator_volume(g) == pytest.approx(2.0 * np.abs(cross).sum(), rel=1e-12)


def test_2d_vertex_gain_scores_like_the_general_volume_function():
    rng = np.random.default_rng(3)
    for _ in range(300):
        g = rng.normal(size=(2, int(rng.integers(2, 9))))
        h = rng.normal(size=2)
        h /= np.linalg.norm(h)
        r = float(rng.uniform(0.05, 2.0))
        fast = gains.volume_gain_vertices(g, h, r)
        hg = h @ g
        candidates = np.vstack([np.zeros(2), (g / hg).T])
        values = gains.strip_gain_volume(g, h, r, candidates)
        assert gains.strip_gain_volume(g, h, r, fast)[0] == pytest.approx(values.min(),
                                                                          rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("method", ["volume", "frobenius"])
def test_fast_updates_contain_the_exact_shapely_intersection(method):
    rng = np.random.default_rng(4)
    for _ in range(150):
        z = Zonotope(rng.normal(size=2), rng.normal(size=(2, int(rng.integers(2, 9)))))
        truth = z.center + z.generators @ rng.uniform(-1, 1, z.n_generators)
        angle = rng.uniform(0, np.pi)
        h = np.array([[np.cos(angle), np.sin(angle)], [-np.sin(angle), np.cos(angle)]])
        radii = rng.uniform(0.05, 1.5, 2)
        strips = Strips(h, h @ truth + rng.uniform(-1, 1, 2) * radii, radii)
        result = intersect_strips(z, strips, method)
        exact = intersect_strips_exact(zonotope_polygon(z), strips)
        points = shapely.get_coordinates(exact)
        assert result.contains(points, tol=1e-7).all()
        assert result.volume() <= z.volume() * (1 + 1e-9) or method == "frobenius"


def test_internal_constructors_stay_read_only_and_volume_is_cached():
    z = Zonotope([0.0, 0.0], np.eye(2)) + Zonotope([1.0, 0.0], [[1.0], [1.0]])
    assert not z.center.flags.writeable and not z.generators.flags.writeable
    assert z.volume() == pytest.approx(generator_volume(z.generators))
    assert z.volume() is z.volume()
    s = zonotope_facet_strips(z)
    assert not s.normals.flags.writeable and len(s) == 3
    with pytest.raises(ValueError, match="finite"):
        np.array([[np.nan, 0.0], [0.0, 1.0]]) @ z
