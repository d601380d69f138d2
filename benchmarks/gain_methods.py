"""Item 2: Proposition 1 gains, closed form against cvxpy compiled once (DPP, re-solved with new
parameter values) against cvxpy rebuilt on every call, µs per call on the loop's typical
problem (a 2-D set with 8 generators cut by one sensor's two strips)."""

from __future__ import annotations

import numpy as np

from benchmarks.common import time_calls
from sse_cosim.sets import Strips, Zonotope, gains, intersect_strips


def typical_problem(seed: int = 0) -> tuple[Zonotope, Strips]:
    rng = np.random.default_rng(seed)
    z = Zonotope(rng.normal(size=2), rng.normal(size=(2, 8)) * 0.8)
    angle = rng.uniform(0, np.pi)
    h = np.array([[np.cos(angle), np.sin(angle)], [-np.sin(angle), np.cos(angle)]])
    return z, Strips(h, h @ z.center + rng.uniform(-0.3, 0.3, 2), np.array([0.8, 0.8]))


def _rebuilt(method: str):
    """The cvxpy method with its problem built (and compiled) anew on every call."""

    def call(z: Zonotope, strips: Strips) -> Zonotope:
        gains.PROBLEM_CACHE.clear()
        return intersect_strips(z, strips, method)

    return call


def run(number: int = 200, repeats: int = 5) -> dict:
    z, strips = typical_problem()
    cases = {
        "frobenius (closed form)": lambda: intersect_strips(z, strips, "frobenius"),
        "cvxpy-frobenius (compiled once)": lambda: intersect_strips(z, strips, "cvxpy-frobenius"),
        "cvxpy-frobenius (rebuilt every call)": lambda: _rebuilt("cvxpy-frobenius")(z, strips),
        "volume (closed form, 2-D vertices)": lambda: intersect_strips(z, strips, "volume"),
        "cvxpy-volume (compiled once)": lambda: intersect_strips(z, strips, "cvxpy-volume"),
        "cvxpy-volume (rebuilt every call)": lambda: _rebuilt("cvxpy-volume")(z, strips),
        "enclose (exact polygon, enclosure; volume too)":
            lambda: intersect_strips(z, strips, "enclose"),
    }
    us = {}
    for name, call in cases.items():
        call()  # compiles a cached problem before timing (a rebuilt one compiles every call)
        calls = number if "cvxpy" not in name else max(number // 10, 3)
        if "rebuilt" in name:
            calls = max(number // 50, 2)
        us[name] = 1e6 * time_calls(call, calls, repeats)
    ratios = {
        "cvxpy-frobenius compiled / closed form": us["cvxpy-frobenius (compiled once)"]
        / us["frobenius (closed form)"],
        "cvxpy-frobenius rebuilt / compiled": us["cvxpy-frobenius (rebuilt every call)"]
        / us["cvxpy-frobenius (compiled once)"],
        "cvxpy-volume compiled / closed form": us["cvxpy-volume (compiled once)"]
        / us["volume (closed form, 2-D vertices)"],
        "cvxpy-volume rebuilt / compiled": us["cvxpy-volume (rebuilt every call)"]
        / us["cvxpy-volume (compiled once)"],
        "enclose / volume": us["enclose (exact polygon, enclosure; volume too)"]
        / us["volume (closed form, 2-D vertices)"],
    }
    areas = {name.split(" ")[0]: intersect_strips(z, strips, name.split(" ")[0]).volume()
             for name in cases if "rebuilt" not in name}
    return {"problem": "2-D zonotope, 8 generators, 2 strips (one sensor)", "us_per_call": us,
            "ratios": ratios, "result_area_m2": areas}
