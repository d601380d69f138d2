"""Linear programs (scipy's HiGHS), with scipy.optimize imported on first use.

Importing scipy.optimize takes about half a second, paid by every worker process at start-up,
while the exact 2-D paths (:mod:`sse_cosim.sets.kernels`) answer the loop's queries without
an LP; the LPs are the general-dimension and degenerate fallbacks.
"""

from __future__ import annotations

from typing import Any


def linprog(*args: Any, **kwargs: Any) -> Any:
    """``scipy.optimize.linprog(*args, **kwargs)``."""
    from scipy.optimize import linprog as solve

    return solve(*args, **kwargs)
