"""The shapely reference: prediction F·P ⊕ Q and strip clipping."""

import numpy as np
import pytest
from hypothesis import given
from sets_strategies import SETTINGS, zonotopes
from shapely.geometry import Polygon

from sse_cosim.sets import Strips, Zonotope
from sse_cosim.sets.exact import (
    intersect_strips_exact,
    predict_exact,
    zonotope_polygon,
)


@SETTINGS
@given(zonotopes(2, max_generators=5), zonotopes(2, min_generators=0, max_generators=3))
def test_predict_exact_equals_the_zonotope_prediction(z, noise):
    """Predicted state set F Z ⊕ Z_Q: exact for zonotopes, so both must agree."""
    f = np.array([[1.0, 0.1], [0.0, 1.0]])
    exact = predict_exact(zonotope_polygon(z), f, noise)
    predicted = zonotope_polygon(f @ z + noise)
    assert exact.symmetric_difference(predicted).area <= 1e-9 * predicted.area
    assert exact.area == pytest.approx((f @ z + noise).volume(), rel=1e-9)


def test_strip_clipping_by_hand():
    square = Polygon([(-1, -1), (1, -1), (1, 1), (-1, 1)])
    diagonal = Strips([1.0, 1.0], 0.0, 0.5)  # |x + y| <= 0.5
    clipped = intersect_strips_exact(square, diagonal)
    assert clipped.area == pytest.approx(4.0 - 2 * 0.5 * 1.5**2)
    far = Strips([0.0, 1.0], 5.0, 1.0)
    assert intersect_strips_exact(square, Strips.stack([diagonal, far])).is_empty
    point = zonotope_polygon(Zonotope([0.1, 0.2], []))
    assert intersect_strips_exact(point, diagonal).area == 0.0
    assert not intersect_strips_exact(point, diagonal).is_empty
