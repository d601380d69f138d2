"""Issue 13's kernels, per operation: the compiled kernel, its NumPy reference and a peer timed in
the same process, µs per call. Peers: ZonoOpt (a C++/Eigen zonotope library,
``pip install -e ".[bench]"``) for the intersection with 2 strips (Frobenius gain), the order
reduction 20 -> 8 generators and the area of a 2-D zonotope (8 generators, as the loop keeps);
shapely (GEOS) clipping the same polygons for the ``enclose`` intersection with 2 strips and the
``enclose`` fusion of 3 sets (the exact polygon only: shapely does not enclose it). ``area``
builds a new Zonotope per call: :meth:`Zonotope.volume` caches its value."""

from __future__ import annotations

import contextlib
from collections.abc import Callable

import numpy as np
import shapely

from benchmarks.common import time_calls
from benchmarks.gain_methods import typical_problem
from sse_cosim.sets import (
    Strips,
    Zonotope,
    enclosure_kernels,
    fuse,
    intersect_strips,
    kernels,
    zonotope_facet_strips,
)
from sse_cosim.sets.enclosure import enclose_intersection_reference
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


def _fusion_inputs() -> list[Zonotope]:
    """Three 2-D sets of 8 generators sharing a point, as the bus fuses them."""
    rng = np.random.default_rng(2)
    return [Zonotope(rng.uniform(-0.3, 0.3, 2), rng.normal(size=(2, 8)) * 0.8) for _ in range(3)]


def _strip_polygon(strips: Strips) -> shapely.Polygon:
    """The 2 strips' intersection (a parallelogram) as a polygon, for shapely's clip."""
    unit = strips.normalized()
    corners = [np.linalg.solve(unit.normals, unit.values + np.array([a, b]) * unit.radii)
               for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return shapely.Polygon(corners)


def _shapely_cases(z: Zonotope, strips: Strips, inputs: list[Zonotope]
                   ) -> dict[str, Callable[[], object]]:
    """shapely's exact clip of the same polygons (prepared outside the timing)."""
    polygon = shapely.Polygon(z.vertices())
    strip_polygon = _strip_polygon(strips)
    polygons = [shapely.Polygon(x.vertices()) for x in inputs]
    return {
        "enclose intersection": lambda: shapely.intersection(polygon, strip_polygon),
        "enclose fusion of 3": lambda: shapely.intersection_all(polygons),
    }


def run(number: int = 2000, repeats: int = 5) -> dict:
    z, strips = typical_problem()
    big = Zonotope(np.zeros(2), np.random.default_rng(1).normal(size=(2, 20)))
    unit = strips.normalized()
    directions = np.hstack([z.generators, np.stack([-unit.normals[:, 1], unit.normals[:, 0]])])
    inputs = _fusion_inputs()
    others = Strips.stack([zonotope_facet_strips(x) for x in inputs[1:]])
    every_direction = np.hstack([x.generators for x in inputs])
    ours = {
        "intersection": lambda: intersect_strips(z, strips, "frobenius"),
        "reduction": lambda: big.reduce(8, "girard"),
        "area": lambda: Zonotope.unchecked(z.center, z.generators).volume(),
        "enclose intersection": lambda: intersect_strips(z, strips, "enclose"),
        "enclose fusion of 3": lambda: fuse(inputs, "enclose"),
    }
    reference = {
        "intersection": lambda: apply_gain(z, unit, frobenius_gain_reference(z, unit)),
        "reduction": lambda: Zonotope.unchecked(big.center, girard_reduce_reference(
            big.generators, 8)),
        "area": lambda: generator_volume_reference(z.generators),
        "enclose intersection": lambda: enclose_intersection_reference(z, unit, directions),
        "enclose fusion of 3": lambda: enclose_intersection_reference(inputs[0], others,
                                                                      every_direction),
    }
    # the compiled kernel called on arrays, without the public function's Python around it
    alone = {
        "intersection": lambda: kernels.intersect_frobenius(
            z.center, z.generators, unit.normals, unit.values, unit.radii),
        "enclose intersection": lambda: enclosure_kernels.enclose_or_volume(
            z.center, z.generators, unit.normals, unit.values, unit.radii),
    }
    peers: dict[str, tuple[str, Callable[[], object]]] = {
        op: ("shapely", call) for op, call in _shapely_cases(z, strips, inputs).items()}
    with contextlib.suppress(ImportError):
        peers |= {op: ("zonoopt", call) for op, call in _zonoopt_cases(z, strips, big).items()}
    us: dict[str, dict[str, float]] = {}
    for op in ours:
        sides = {"compiled": ours[op], "reference": reference[op]}
        if op in alone:
            sides["kernel alone"] = alone[op]
        if op in peers:
            sides[peers[op][0]] = peers[op][1]
        us[op] = {}
        for side, call in sides.items():
            call()  # compiles (or loads) the kernel before timing
            us[op][side] = 1e6 * time_calls(call, number, repeats)
    ratios = {op: {"peer": peers[op][0] if op in peers else None,
                   "compiled / peer": t["compiled"] / t[peers[op][0]] if op in peers else None,
                   "reference / compiled": t["reference"] / t["compiled"]}
              for op, t in us.items()}
    return {"problems": {"intersection": "2-D, 8 generators, 2 strips (normalized inside)",
                         "reduction": "2-D, 20 -> 8 generators", "area": "2-D, 8 generators",
                         "enclose intersection": "the intersection's problem, exact polygon "
                         "enclosed (the public function: the volume gain's set is also built "
                         "when the enclosure is not exact)",
                         "enclose fusion of 3": "3 sets of 8 generators sharing a point"},
            "zonoopt": any(peer == "zonoopt" for peer, _ in peers.values()),
            "us_per_call": us, "ratios": ratios}
