"""A search that travels: CMA-ES proposes the same points with another CPU's machine code.

A run writes the same files on every x86-64 CPU (tests/cosim/test_portable_results.py), so a
search proposes the same points, and so makes the same runs, if its searcher does. CMA-ES's
eigenvectors come from LAPACK, whose kernels differ by CPU; :class:`PortableCMA` samples
with the symmetric square root and the points are rounded (``searchers.POINT_DECIMALS``).
The test asks 40 generations of the crowd's box size (41 values, 15 a generation) on a bowl,
here and with OpenBLAS's and NumPy's kernels for another CPU, and compares every point bit
for bit: the same points are the claim (they name the runs and their keys), not a bound.
Without the symmetric square root the two searches part within a few generations, and
without the rounding their points differ in the last digits.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
from other_cpu import environment

from sse_cosim.falsify.searchers import SEARCHERS, generation_size

DIMS = 41
GENERATIONS = 40
SEARCH = f"""
import hashlib, sys
import numpy as np
from sse_cosim.falsify.searchers import SEARCHERS, generation_size
searcher = SEARCHERS["cma"]({DIMS}, 5, generation_size({DIMS}))
digest = hashlib.sha256()
for _ in range({GENERATIONS}):
    points = searcher.ask()
    digest.update(points.tobytes())
    searcher.tell(points, [float(np.sum((p - 0.3) ** 2)) for p in points])
sys.stdout.write(digest.hexdigest())
"""


def _proposed(other: bool) -> str:
    """The digest of every point the search proposes, on another CPU's code if ``other``."""
    done = subprocess.run([sys.executable, "-c", SEARCH], check=True, capture_output=True,
                          text=True, env=environment(other))
    return done.stdout


def test_cma_proposes_the_same_points_with_another_cpus_machine_code():
    assert _proposed(False) == _proposed(True)


def test_cmas_points_are_rounded_and_keep_to_the_unit_cube():
    searcher = SEARCHERS["cma"](DIMS, 5, generation_size(DIMS))
    for _ in range(3):
        points = searcher.ask()
        assert np.all((points >= 0.0) & (points <= 1.0))
        np.testing.assert_array_equal(points, np.round(points, 6))
        searcher.tell(points, [float(np.sum((p - 0.3) ** 2)) for p in points])
