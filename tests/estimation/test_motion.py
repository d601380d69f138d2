"""The motion model's unchecked fast paths against the validated operations they replace."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sse_cosim.estimation.motion import motion_model
from sse_cosim.scenario.model import Estimator
from sse_cosim.sets import Strips, Zonotope, intersect_strips, portable

DT = 0.1


def random_strips(rng: np.random.Generator, m: int) -> Strips:
    """m strips (m, 2) with random normals of random lengths, values and radii."""
    return Strips(rng.normal(size=(m, 2)) * rng.uniform(0.1, 3.0, (m, 1)),
                  rng.normal(size=m) * 20, rng.uniform(0.05, 2.0, m))


@pytest.mark.parametrize("state_model", ["position", "constant-velocity"])
def test_path_and_state_strips_equal_the_validated_operations(state_model):
    model = motion_model(Estimator(state_model=state_model, position_jitter_m=0.3), DT)
    rng = np.random.default_rng(3)
    for m in (1, 2, 5):
        measured = random_strips(rng, m)
        path = model.path_strips(measured)
        widened = measured.radii + 0.3 * np.linalg.norm(measured.normals, axis=1)
        assert np.array_equal(path.radii, widened) and path.normals is measured.normals
        state = model.state_strips(path)
        pulled = path.pullback(model.position_matrix)
        for name in ("normals", "values", "radii"):
            assert np.array_equal(getattr(state, name), getattr(pulled, name))


@pytest.mark.parametrize("state_model", ["position", "constant-velocity"])
def test_initial_set_equals_the_validated_construction(state_model):
    """The parallelogram of the first two independent strips (parallel ones skipped), the
    rest intersected with it: the same bits as building it with the checked constructors."""
    model = motion_model(Estimator(state_model=state_model, position_jitter_m=0.3),
                         DT)
    rng = np.random.default_rng(4)
    for m in (2, 3, 4):
        strips = random_strips(rng, m)
        parallel = Strips(np.vstack([strips.normals[0], 2 * strips.normals[0], strips.normals[1:]]),
                          np.concatenate([strips.values[:1], strips.values]),
                          np.concatenate([strips.radii[:1], strips.radii]))
        start = model.initial_set(parallel, "frobenius")
        # H⁻¹ by its adjugate and H⁻¹y in index order, as the model computes them (LAPACK's
        # inverse and BLAS's product round otherwise, and by CPU): the checks are what differ.
        inverse = portable.inverse_2x2(strips.normals[:2])
        expected = Zonotope(portable.matmul(inverse, strips.values[:2]),
                            inverse * strips.radii[:2])
        rest = parallel.select(np.array([1, *range(3, m + 1)]))  # all but rows 0 and 2
        expected = intersect_strips(expected, rest, "frobenius")
        assert np.array_equal(start.center[:2], expected.center)
        assert np.array_equal(start.generators[:2, :expected.n_generators], expected.generators)
        if model.dim == 4:
            assert np.array_equal(start.generators[2:, -2:], np.eye(2) * model.max_speed)


def test_model_and_strips_beyond_the_fast_paths_assumptions_are_errors():
    model = motion_model(Estimator(position_jitter_m=0.3), DT)
    with pytest.raises(ValueError, match="first two entries"):
        dataclasses.replace(model, position_matrix=np.array([[0.0, 1.0], [1.0, 0.0]]))
    with pytest.raises(ValueError, match="jitter"):
        dataclasses.replace(model, jitter=float("inf"))
    with pytest.raises(ValueError, match="overflow"), np.errstate(over="ignore"):
        model.path_strips(Strips(np.full((2, 2), 1e200), np.zeros(2), np.ones(2)))
    with pytest.raises(ValueError, match="independent"):
        model.initial_set(Strips(np.ones((2, 2)), np.zeros(2), np.ones(2)), "frobenius")
