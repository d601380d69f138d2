"""The recorder's compiled kernels (reporting/recorder_kernels.py) against their references.

Both sides do the same IEEE 754 operations in the same order (the reference in Python floats,
its sums from the left; the position arrays in NumPy's elementwise ufuncs), so they must agree
bit for bit, signs of zeros included, and the containment verdicts exactly: the recorder's
check gives the same answer on every CPU. ``make test`` runs these tests a second time with
NumPy's AVX-512 code and numba's host CPU features switched off (the ``kernels`` marker).
"""

from __future__ import annotations

import numpy as np
import pytest

from sse_cosim.reporting.recorder import (
    CONTAINMENT_TOL_M,
    position_arrays,
    zonotope_2d_contains,
    zonotope_2d_halfspaces_reference,
)
from sse_cosim.reporting.recorder_kernels import halfspaces_2d
from sse_cosim.reporting.replay import _encode, encode_reference

pytestmark = pytest.mark.kernels

KINDS = ("spread", "flat", "parallel", "one", "none", "tiny", "huge")


def generators_of(kind: str, rng: np.random.Generator) -> np.ndarray:
    """(2, e) generators of one family: spread directions, flat (all within 30°, a corner
    case of the half-spaces), exactly parallel, a single one, none at all, and scales whose
    squares underflow or that come near overflow; some columns zero of either sign."""
    e = 1 if kind == "one" else int(rng.integers(1, 12))
    if kind == "spread":
        g = rng.normal(size=(2, e))
    elif kind in ("flat", "parallel"):
        angles = rng.uniform(-0.25, 0.25, size=e) if kind == "flat" else np.zeros(e)
        g = rng.uniform(-3.0, 3.0, size=e) * np.array([np.cos(angles), np.sin(angles)])
        g = np.array([[np.cos(1.0), -np.sin(1.0)], [np.sin(1.0), np.cos(1.0)]]) @ g
    elif kind == "none":
        g = np.zeros((2, e))
    else:
        g = rng.normal(size=(2, e)) * {"one": 1.0, "tiny": 1e-160, "huge": 1e150}[kind]
    zero = rng.random(e) < 0.2
    g[:, zero] = np.where(rng.random((2, int(zero.sum()))) < 0.5, 0.0, -0.0)
    return g * 10.0 ** rng.integers(-3, 4)


def bits(values: np.ndarray) -> bytes:
    """The exact bits of a float64 array (-0.0 and 0.0 differ)."""
    return np.ascontiguousarray(values, dtype=np.float64).tobytes()


def reference_contains(center: np.ndarray, generators: np.ndarray, point: np.ndarray) -> bool:
    """The containment test in Python floats, on the reference's half-spaces."""
    x, y = float(point[0]) - float(center[0]), float(point[1]) - float(center[1])
    return all(abs(dx * x + dy * y) <= bound for dx, dy, bound in
               zonotope_2d_halfspaces_reference(generators, CONTAINMENT_TOL_M))


@pytest.mark.parametrize("kind", KINDS)
def test_compiled_halfspaces_are_the_reference_bit_for_bit(kind):
    rng = np.random.default_rng(KINDS.index(kind))
    for _ in range(200):
        g = generators_of(kind, rng)
        expected = np.array(zonotope_2d_halfspaces_reference(g, CONTAINMENT_TOL_M))
        got = halfspaces_2d(g, CONTAINMENT_TOL_M)
        assert got.shape == expected.shape
        assert bits(got) == bits(expected)


@pytest.mark.parametrize("kind", KINDS)
def test_compiled_containment_is_the_references_verdict(kind):
    # points on both sides of the set's boundary, and some within rounding of it
    rng = np.random.default_rng(100 + KINDS.index(kind))
    for _ in range(100):
        g = generators_of(kind, rng)
        center = rng.normal(size=2) * 100
        betas = rng.uniform(-1.05, 1.05, size=(g.shape[1], 16))
        betas[:, :4] = np.sign(betas[:, :4])  # vertices: on the boundary
        points = center + (g @ betas).T + rng.normal(size=(16, 2)) * CONTAINMENT_TOL_M
        for point in points:
            assert zonotope_2d_contains(center, g, point, CONTAINMENT_TOL_M) \
                == reference_contains(center, g, point)


@pytest.mark.parametrize("jitter", [0.0, 0.646, 1.2])
@pytest.mark.parametrize("dim", [2, 4])
def test_compiled_position_arrays_are_numpys_bit_for_bit(dim, jitter):
    """⟨c[:2], [G[:2], jitter I]⟩ + 0.0 by NumPy's ufuncs: the same values and zeros' signs."""
    rng = np.random.default_rng(dim * 10 + int(jitter * 1000))
    for _ in range(50):
        center = rng.normal(size=dim) * 100
        generators = rng.normal(size=(dim, int(rng.integers(0, 9))))
        generators[rng.random(generators.shape) < 0.3] = -0.0
        center[rng.random(dim) < 0.3] = -0.0
        box = [np.eye(2) * jitter] if jitter else []
        expected = np.concatenate([generators[:2], *box], axis=1) + 0.0
        got_center, got_generators = position_arrays(center, generators, jitter)
        assert bits(got_center) == bits(center[:2] + 0.0)
        assert got_generators.shape == expected.shape
        assert bits(got_generators) == bits(expected)


@pytest.mark.parametrize("seed", range(20))
def test_the_replays_compiled_encoding_is_the_references_byte_for_byte(seed):
    """Integer results: the same bytes on every CPU. Repeated points (dropped), points half
    a centimetre off the grid (rounded half to even) and UTM-sized coordinates included."""
    rng = np.random.default_rng(seed)
    points = rng.uniform(-50, 50, size=(int(rng.integers(1, 40)), 2))
    points[::3] = points[::3].round(2) + 0.005  # halves of a centimetre
    if len(points) > 2:
        points[1] = points[0]  # a repeated point
    for offset in (0.0, 512345.0, -5712345.0):
        assert _encode(points + offset) == encode_reference(points + offset)
