"""What SUMO does at a lower speed limit, which the controller's passes rely on
(control/limits.py, docs/controller.md "Speed limits"): a vehicle that follows
``vehicle.setSpeed`` under speed mode 31 is held to the limit of the lane its front is on and
brakes ahead of a lower one at its deceleration b, never below sqrt(l^2 + 2 b g) a gap g
before it (``RouteLimits.least``). Entering the lower limit it may be above it for the one
step its braking takes to act (passes need only the lower bound). Measured on a lone bus,
200 m at ``fast`` m/s, 100 m at ``slow``, 200 m at ``fast`` again, always told its maximum
speed."""

from __future__ import annotations

import subprocess
from pathlib import Path

import libsumo
import numpy as np
import pytest
import shapely

from sse_cosim.control.limits import RouteLimits
from sse_cosim.control.swept import RoutePath
from sse_cosim.world.network import netconvert_path
from sse_cosim.world.roadmap import load_roadmap

pytestmark = pytest.mark.sumo
ROUTE = ["ab", "bc", "cd"]


def three_limits(folder: Path, fast: float, slow: float) -> Path:
    (folder / "n.nod.xml").write_text(
        '<nodes><node id="a" x="0" y="0"/><node id="b" x="200" y="0"/>'
        '<node id="c" x="300" y="0"/><node id="d" x="500" y="0"/></nodes>')
    (folder / "n.edg.xml").write_text(
        f'<edges><edge id="ab" from="a" to="b" speed="{fast}" allow="bus"/>'
        f'<edge id="bc" from="b" to="c" speed="{slow}" allow="bus"/>'
        f'<edge id="cd" from="c" to="d" speed="{fast}" allow="bus"/></edges>')
    net = folder / "n.net.xml"
    subprocess.run([str(netconvert_path()), "-n", "n.nod.xml", "-e", "n.edg.xml", "-o",
                    net.name], cwd=folder, check=True, capture_output=True, timeout=60)
    return net


def speeds(folder: Path, net: Path, fast: float, decel: float, dt: float) -> np.ndarray:
    """Each step's front (x, y) and speed, shape (k, 3)."""
    (folder / "r.rou.xml").write_text(
        f'<routes><vType id="bus" vClass="bus" accel="1.0" decel="{decel}" '
        f'maxSpeed="{fast}" speedFactor="1" speedDev="0" sigma="0"/>'
        f'<vehicle id="v" type="bus" depart="0" departSpeed="max">'
        f'<route edges="{" ".join(ROUTE)}"/></vehicle></routes>')
    libsumo.start(["sumo", "-n", str(net), "-r", str(folder / "r.rou.xml"), "--step-length",
                   str(dt), "--no-step-log", "--no-warnings"])
    try:
        libsumo.simulationStep()
        libsumo.vehicle.setSpeedMode("v", 31)
        rows = []
        while "v" in libsumo.vehicle.getIDList():
            libsumo.vehicle.setSpeed("v", fast)
            libsumo.simulationStep()
            if "v" in libsumo.vehicle.getIDList():
                rows.append([*libsumo.vehicle.getPosition("v"), libsumo.vehicle.getSpeed("v")])
    finally:
        libsumo.close()
    return np.array(rows)


@pytest.mark.parametrize(("fast", "slow"), [(13.89, 2.0), (13.89, 8.33), (20.0, 5.0),
                                            (20.0, 11.0)])
def test_sumo_holds_the_front_to_its_lane_and_brakes_no_sooner_than_the_bound(
        tmp_path: Path, fast: float, slow: float) -> None:
    net = three_limits(tmp_path, fast, slow)
    roadmap = load_roadmap(net)
    limits = RouteLimits.of_lanes(roadmap.route_lanes(ROUTE))
    path = RoutePath.of_route(roadmap.route_lanes(ROUTE))
    line = roadmap.route_line(ROUTE)
    for decel in (1.0, 2.0, 4.5):
        for dt in (0.1, 0.2):
            rows = speeds(tmp_path, net, fast, decel, dt)
            along = np.array([path.drive(s) for s in shapely.line_locate_point(
                line, shapely.points(rows[:, :2]))])  # SUMO's distance, as the limits
            speed = rows[:, 2]
            # held to the limit where the front is, once its braking step has acted
            assert (speed <= np.array([limits.at(s) for s in along]) + decel * dt + 1e-9).all()
            # and never slower than the bound from where the step began (SUMO applies the
            # limit of the lane the front was on then), or the ramp up from the step before
            bound = np.array([limits.least(a, b, decel)
                              for a, b in zip(np.r_[along[0], along[:-1]], along, strict=True)])
            ramp = np.r_[fast, speed[:-1] + 1.0 * dt]
            assert (speed >= np.minimum(bound, ramp) - 1e-9).all(), (decel, dt)
            assert speed.min() == pytest.approx(slow)  # it met the limit
