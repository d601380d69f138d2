"""The paper's Propositions 1 and 2 reproduced literally on hand-worked examples."""

import numpy as np
import pytest

from sse_cosim.sets import Strips, Zonotope, apply_gain, fuse, fuse_with_weights, intersect_strips


def test_proposition_1_eqs_C_lambda_and_G_lambda_by_hand():
    """Z = ⟨(1, 2), [[2, 1], [0, 1]]⟩; S1: |x1 - 2| <= 0.5, S2: |x2 - 3| <= 1;
    λ1 = (0.5, 0.25), λ2 = (0, 0.5).

    C_lambda: c' = c + λ1(y1 - h1ᵀc) + λ2(y2 - h2ᵀc) = (1, 2) + (0.5, 0.25)·1 + (0, 0.5)·1
            = (1.5, 2.75).
    G_lambda: I - λ1h1ᵀ - λ2h2ᵀ = [[0.5, 0], [-0.25, 0.5]], times G = [[1, 0.5], [-0.5, 0.25]];
              λ1 r1 = (0.25, 0.125), λ2 r2 = (0, 0.5).
    """
    z = Zonotope([1.0, 2.0], [[2.0, 1.0], [0.0, 1.0]])
    strips = Strips([[1.0, 0.0], [0.0, 1.0]], [2.0, 3.0], [0.5, 1.0])
    gain = np.array([[0.5, 0.0], [0.25, 0.5]])  # columns λ1, λ2
    result = apply_gain(z, strips, gain)
    assert np.allclose(result.center, [1.5, 2.75])
    assert np.allclose(result.generators, [[1.0, 0.5, 0.25, 0.0], [-0.5, 0.25, 0.125, 0.5]])


def test_volume_gain_on_a_square_is_exact_and_beats_frobenius():
    """Square ⟨0, I⟩ (area 4) and the strip |x1| <= 0.5 (exact intersection: area 2).

    volume: candidates λ = 0 (vol/4 = 1) and λ = g1/(hᵀg1) = (1, 0), where
            vol/4 = |1 - 1|·1 + 0.5·(|d1ᵀλ| + |d2ᵀλ|) = 0.5·(0 + 1) = 0.5 -> area 2 (exact).
    frobenius: λ = P h / (hᵀPh + r²) = (0.8, 0) -> x half-width 0.2 + 0.4 -> area 4·0.6 = 2.4.
    """
    square = Zonotope([0.0, 0.0], np.eye(2))
    strip = Strips([1.0, 0.0], 0.0, 0.5)
    volume = intersect_strips(square, strip, "volume")
    assert volume.volume() == pytest.approx(2.0)
    assert np.allclose(volume.interval_hull(), ([-0.5, -1.0], [0.5, 1.0]))
    assert intersect_strips(square, strip, "frobenius").volume() == pytest.approx(2.4)


def test_proposition_2_eqs_cdiff_and_gdiff_by_hand():
    """Z1 = ⟨(0, 0), I⟩, Z2 = ⟨(1, 1), [2; 2]⟩, w = (1, 3), Σw = 4.

    cdiff: ĉ = (1·(0, 0) + 3·(1, 1)) / 4 = (0.75, 0.75).
    gdiff: Ĝ = [1·I, 3·(2, 2)ᵀ] / 4 = [[0.25, 0, 1.5], [0, 0.25, 1.5]].
    frobenius weights: ‖G1‖² = 2, ‖G2‖² = 8 -> w ∝ (1/2, 1/8) = (0.8, 0.2):
    ĉ = (0.2, 0.2), Ĝ = [[0.8, 0, 0.4], [0, 0.8, 0.4]].
    """
    z1 = Zonotope([0.0, 0.0], np.eye(2))
    z2 = Zonotope([1.0, 1.0], [[2.0], [2.0]])
    fused = fuse_with_weights([z1, z2], [1.0, 3.0])
    assert np.allclose(fused.center, [0.75, 0.75])
    assert np.allclose(fused.generators, [[0.25, 0.0, 1.5], [0.0, 0.25, 1.5]])
    frobenius = fuse([z1, z2], "frobenius")
    assert np.allclose(frobenius.center, [0.2, 0.2])
    assert np.allclose(frobenius.generators, [[0.8, 0.0, 0.4], [0.0, 0.8, 0.4]])


def test_fusion_never_grows_unlike_the_papers_example():
    """The paper fuses sets of area 50.3 and 123.1 into 94.0 (larger than one input); with the
    hand example above, frobenius gives area 4·(0.64 + 2·0.32) = 5.12 > area(Z1) = 4, while
    volume and strips stay within the smallest input."""
    z1 = Zonotope([0.0, 0.0], np.eye(2))
    z2 = Zonotope([1.0, 1.0], [[2.0], [2.0]])
    assert fuse([z1, z2], "frobenius").volume() == pytest.approx(5.12)
    assert fuse([z1, z2], "volume").volume() <= 4.0
    assert fuse([z1, z2], "strips").volume() <= 4.0
