"""The portable arithmetic (sets/portable.py): NumPy's answers within a stated bound, and no
CPU-dispatched arithmetic left in the code that computes what a run writes."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

from sse_cosim.sets import portable

pytestmark = pytest.mark.kernels

EPS = np.finfo(np.float64).eps
PACKAGE = Path(portable.__file__).resolve().parents[1]


@pytest.mark.parametrize(("a_shape", "b_shape"), [
    ((3, 2), (2, 5)), ((2, 2), (2,)), ((4,), (4, 3)), ((6,), (6,)), ((5, 3, 2), (2, 4)),
    ((2, 9), (9, 2)), ((1, 1), (1, 1)), ((0, 2), (2, 3)),
])
def test_matmul_is_the_product_within_the_rounding_of_its_sums(a_shape, b_shape):
    rng = np.random.default_rng(7)
    a, b = rng.normal(size=a_shape), rng.normal(size=b_shape)
    got, want = portable.matmul(a, b), a @ b
    assert np.shape(got) == np.shape(want)
    # Both sum n products, each rounded: they differ by at most 2 n eps Σ|a_i b_i| (any order).
    n = b.shape[0]
    bound = 2 * n * EPS * (np.abs(a) @ np.abs(b))
    assert np.all(np.abs(got - want) <= bound)


def test_matmul_sums_in_index_order_below_eight_terms():
    a = np.array([1.0, 1e16, -1e16])
    b = np.ones(3)
    assert portable.matmul(a, b) == 0.0  # (1 + 1e16) - 1e16: the order, not the exact sum


def test_inverse_2x2_is_the_inverse_and_refuses_a_singular_matrix():
    m = np.array([[2.0, 1.0], [0.5, 3.0]])
    assert np.allclose(portable.inverse_2x2(m) @ m, np.eye(2), rtol=0, atol=8 * EPS)
    with pytest.raises(np.linalg.LinAlgError):
        portable.inverse_2x2([[1.0, 2.0], [2.0, 4.0]])


@pytest.mark.parametrize("name", ["sin", "cos", "tan"])
def test_angles_are_numpys_within_two_ulps(name):
    x = np.random.default_rng(3).uniform(-7.0, 7.0, 2000)
    got, want = getattr(portable, name)(x), getattr(np, name)(x)
    assert np.all(np.abs(got - want) <= 2 * np.spacing(np.abs(want)))


def test_arctan2_and_hypot_are_numpys_within_two_ulps():
    y, x = np.random.default_rng(5).normal(size=(2, 2000))
    for got, want in ((portable.arctan2(y, x), np.arctan2(y, x)),
                      (portable.hypot(x, y), np.hypot(x, y))):
        assert np.all(np.abs(got - want) <= 2 * np.spacing(np.abs(want)))
    assert portable.arctan2(0.0, -1.0) == np.pi


# NumPy calls whose machine code depends on the CPU: BLAS/LAPACK, and the SIMD
# transcendentals (AVX-512 builds of sin, cos, tan, arctan2, exp, log, power...).
_DISPATCHED = {"dot", "matmul", "inner", "vdot", "tensordot", "einsum", "sin", "cos", "tan",
               "arcsin", "arccos", "arctan", "arctan2", "hypot", "sinh", "cosh", "tanh", "exp",
               "exp2", "expm1", "log", "log2", "log10", "log1p", "power", "cbrt"}
# Where they stay, and why: compiled kernels call libm (numba's np.* in njit functions), the
# non-default gains, the pca reduction and the Kalman baseline solve with LAPACK and cvxpy
# (docs/results.md), and
# the n-D (n > 2) determinants of the constant-velocity model's 4-D sets.
_ALLOWED_MODULES = {"sets/gains.py", "estimation/kalman.py"}
_ALLOWED_FUNCTIONS = {("sets/zonotope.py", "abs_determinants"),
                      ("sets/zonotope.py", "cofactor_vectors"),
                      ("sets/reduction.py", "_pca_frame")}


def _compiled(node: ast.FunctionDef) -> bool:
    names = {ast.unparse(d).split("(")[0] for d in node.decorator_list}
    return bool(names & {"njit", "numba.njit", "jit", "vectorize"})


def _np_call(node: ast.AST) -> str | None:
    """``'sin'`` for ``np.sin(...)``, ``'linalg.inv'`` for ``np.linalg.inv(...)``."""
    if not isinstance(node, ast.Call):
        return None
    name = ast.unparse(node.func)
    if name.startswith("np.linalg."):
        return name[3:]
    if name.startswith("np.") and name[3:] in _DISPATCHED:
        return name[3:]
    return None


def _findings(path: Path) -> list[str]:
    module = path.relative_to(PACKAGE).as_posix()
    if module in _ALLOWED_MODULES or module == "sets/portable.py":
        return []
    found: list[str] = []

    def visit(node: ast.AST, function: str | None) -> None:
        if isinstance(node, ast.FunctionDef):
            if _compiled(node) or node.name.endswith("_reference") \
                    or (module, node.name) in _ALLOWED_FUNCTIONS:
                return
            function = node.name
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.MatMult):
            found.append(f"{module}:{node.lineno} ({function}): '@'")
        call = _np_call(node)
        if call is not None:
            found.append(f"{module}:{node.lineno} ({function}): np.{call}")
        for child in ast.iter_child_nodes(node):
            visit(child, function)

    visit(ast.parse(path.read_text(), filename=str(path)), None)
    return found


def test_no_cpu_dispatched_arithmetic_outside_the_kernels_and_references():
    """Every product and angle of a run goes through sets/portable.py or a compiled kernel,
    so its bits do not depend on the CPU (NumPy references, checked within bounds, may)."""
    findings = [f for path in sorted(PACKAGE.rglob("*.py")) for f in _findings(path)]
    assert findings == [], "use sse_cosim.sets.portable instead:\n" + "\n".join(findings)
