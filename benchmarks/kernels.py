"""Issue 13's kernels, per operation: the compiled kernel, its NumPy reference and ZonoOpt
(a C++/Eigen zonotope library, ``pip install -e ".[bench]"``) timed in the same process, µs
per call: intersection with 2 strips (Frobenius gain), order reduction 20 -> 8 generators and
the area of a 2-D zonotope (8 generators, as the loop keeps). ``area`` builds a new Zonotope
per call: :meth:`Zonotope.volume` caches its value."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from benchmarks.common import time_calls
from benchmarks.gain_methods import typical_problem
from sse_cosim.sets import Strips, Zonotope, intersect_strips
from sse_cosim.sets.gains import apply_gain, frobenius_gain_reference
from sse_cosim.sets.reduction import girard_reduce_reference
from sse_cosim.sets.zonotope import generator_volume_reference


def _zonoopt_cases(z: Zonotope, strips: Strips, big: Zonotope) -> dict[str, Callable[[], object]]:
    """ZonoOpt's calls for the same problems: the generalized intersection with the strips' box
    over R = H, enclosed in a zonotope (``to_zono_approx``); ``reduce_order``; ``get_volume``."""
    import zonoopt
    from scipy.sparse import csc_matrix, diags

    unit = strips.normalized()
    zo = zonoopt.Zono(csc_matrix(z.generators), z.center)
    box = zonoopt.Zono(diags(unit.radii, format="csc"), unit.values)
    h = csc_matrix(unit.normals)
    zo_big = zonoopt.Zono(csc_matrix(big.generators), big.center)
    return {
        "intersection": lambda: zonoopt.intersection(zo, box, h).to_zono_approx(),
        "reduction": lambda: zo_big.reduce_order(8),
        "area": lambda: zo.get_volume(),
    }


def run(number: int = 2000, repeats: int = 5) -> dict:
    z, strips = typical_problem()
    big = Zonotope(np.zeros(2), np.random.default_rng(1).normal(size=(2, 20)))
    unit = strips.normalized()
    ours = {
        "intersection": lambda: intersect_strips(z, strips, "frobenius"),
        "reduction": lambda: big.reduce(8, "girard"),
        "area": lambda: Zonotope.unchecked(z.center, z.generators).volume(),
    }
    reference = {
        "intersection": lambda: apply_gain(z, unit, frobenius_gain_reference(z, unit)),
        "reduction": lambda: Zonotope.unchecked(big.center, girard_reduce_reference(
            big.generators, 8)),
        "area": lambda: generator_volume_reference(z.generators),
    }
    try:
        zonoopt = _zonoopt_cases(z, strips, big)
    except ImportError:
        zonoopt = {}
    us: dict[str, dict[str, float]] = {}
    for op in ours:
        sides = {"compiled": ours[op], "reference": reference[op]}
        if op in zonoopt:
            sides["zonoopt"] = zonoopt[op]
        us[op] = {}
        for side, call in sides.items():
            call()  # compiles (or loads) the kernel before timing
            us[op][side] = 1e6 * time_calls(call, number, repeats)
    ratios = {op: {"compiled / zonoopt": t["compiled"] / t["zonoopt"] if "zonoopt" in t
                   else None, "reference / compiled": t["reference"] / t["compiled"]}
              for op, t in us.items()}
    return {"problems": {"intersection": "2-D, 8 generators, 2 strips (normalized inside)",
                         "reduction": "2-D, 20 -> 8 generators", "area": "2-D, 8 generators"},
            "zonoopt": bool(zonoopt), "us_per_call": us, "ratios": ratios}
