"""Earliest arrivals at a signalised crossing while its light holds its walkers (issue: live on
real streets), on tests/networks/two_lanes/ (junction J, its crossing ':J_c0' across x -2..2,
y -6.4..6.4; a bus on WJ's right lane, whose zone there is the crossing's own ground).

A walker off the crossing does not step on before its light can change (``pedestrian_lights``,
checked by the world every step), so its arrival in a zone on the crossing's own ground is no
sooner than that. A region that reaches onto the crossing's area may hold a walker already on
it: the usual arrival. A pedestrian once seen off the crossing at red stays off until the
release, whatever its region does later (``LightClaims``)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
import shapely

from sse_cosim.control.picture import LightClaims, SceneContext, Source, assess
from sse_cosim.estimation.motion import motion_model
from sse_cosim.regions import kind
from sse_cosim.scenario.model import AutomatedVehicle, Controller, Estimator
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap
from sse_cosim.world.signals import SignalState

TWO_LANES = Path(__file__).resolve().parents[1] / "networks" / "two_lanes"
K = kind("polygon")
JITTER_M = 0.3
SPEED_MPS = 2.5
NOBODY = Source(K.empty())
WALKERS_RED = SignalState("0", 0, "GGGGr", 10.0)  # 67 s of the cars' green, 3 s of yellow
WALKERS_GREEN = SignalState("0", 2, "rrrrG", 1.0)


@pytest.fixture(scope="module")
def context() -> SceneContext:
    roadmap = load_roadmap(build_network(TWO_LANES))
    bus = AutomatedVehicle(route_edges=["WJ", "JE"], nominal_speed_mps=8.0)
    model = motion_model(Estimator(position_jitter_m=JITTER_M), 0.1)
    return SceneContext.build(roadmap, bus.route_edges, bus, Controller(), model, 0.3, 0.1, K)


def arrival(context: SceneContext, light: SignalState, *sources: Source) -> float:
    """The zone's earliest arrival, the bus 10 m before it at 8 m/s (within the plans' reach:
    ``SceneContext.within_reach``)."""
    front = context.zone_drives[0][0] - 10.0
    picture = assess(context, context.path.point_at(front)[0], 8.0, K.empty(), NOBODY, sources,
                     signals={"J": light}, route_m=front)
    assert [zone.index for zone in picture.zones] == [0]
    return picture.zones[0].arrival_s


def walker(x: float, y: float, radius: float = 0.5, off_s: float = 0.0) -> Source:
    return Source(K.outer(shapely.Point(x, y).buffer(radius)), off_s=(off_s,))


@pytest.mark.sumo
def test_the_zone_lies_on_the_crossings_own_ground(context):
    assert len(context.lit) == 1 and context.lit[0].id == ":J_c0"
    assert [zone.lit for zone in context.zones] == [(0,)]


@pytest.mark.sumo
def test_a_walker_waiting_beside_a_red_crossing_arrives_no_sooner_than_its_green(context):
    far = walker(-1.0, 7.5)  # at the far kerb, its region clear of the crossing
    usual = (shapely.distance(context.zones[0].ground, shapely.Point(-1.0, 7.5)) - 0.5
             - 2 * JITTER_M) / SPEED_MPS
    assert arrival(context, WALKERS_GREEN, far) == pytest.approx(usual, abs=1e-6)
    assert arrival(context, WALKERS_RED, far) == pytest.approx(70.0)


@pytest.mark.sumo
def test_a_region_reaching_onto_the_crossing_may_hold_a_walker_on_it(context):
    onto = walker(-1.0, 6.6)  # its region reaches 0.3 m onto the crossing's area
    assert arrival(context, WALKERS_RED, onto) == pytest.approx(
        arrival(context, WALKERS_GREEN, onto), abs=1e-9)
    claimed = walker(-1.0, 6.6, off_s=40.0)  # seen off the crossing at red before: it waits
    assert arrival(context, WALKERS_RED, claimed) == pytest.approx(70.0)


@pytest.mark.sumo
def test_claims_are_made_at_red_from_regions_clear_of_the_crossing_and_expire(context):
    claims = LightClaims(context)
    approaching = K.outer(shapely.Point(-1.0, 9.0).buffer(0.5))
    at_kerb = K.outer(shapely.Point(-1.0, 6.6).buffer(0.5))
    assert claims.update(10.0, {"w": at_kerb}, [67.0], False) == {"w": (0.0,)}
    assert claims.update(10.1, {"w": approaching}, [66.9], False)["w"] == (pytest.approx(66.9),)
    assert claims.update(20.0, {"w": at_kerb}, [57.0], False)["w"] == (pytest.approx(57.0),)
    assert claims.update(20.1, {"w": at_kerb}, [0.0], True) == {}  # inconsistent: dropped
    assert claims.update(20.2, {"w": at_kerb}, [56.8], False) == {"w": (0.0,)}
    assert math.isclose(claims.update(30.0, {"v": approaching}, [0.0], False)["v"][0], 0.0)
