"""Zones beyond the plans' reach (``picture.within_reach``) change no decision: the safe policy
decides the same on the zones within reach as on every zone ahead, on random pictures; and
a reach one stopping margin short of it does change some (the bound is not loose by a
margin)."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from sse_cosim.control.kinematics import BusDynamics
from sse_cosim.control.picture import Picture, ZoneOutlook, within_reach
from sse_cosim.control.speed import SafePolicy
from sse_cosim.scenario.model import AutomatedVehicle, Controller

DT = 0.1
BUS = AutomatedVehicle()
CONFIG = Controller()
DYN = BusDynamics.of(BUS, CONFIG, DT)


def _picture(speed: float, zones: tuple[ZoneOutlook, ...]) -> Picture:
    return Picture(front_s=0.0, front_drive_m=0.0, speed_mps=speed, distance_to_crossing=0.0,
                   crossing_ahead=True, reach_radius_m=0.0, own_occluded_m2=0.0,
                   unresolved_occluded_m2=0.0, pedestrian_near_crossing=False,
                   pedestrian_near_path=False, pedestrian_in_stopping_distance=False,
                   zones=zones)


@st.composite
def _scenes(draw: st.DrawFn) -> tuple[float, tuple[ZoneOutlook, ...]]:
    speed = draw(st.floats(0.0, 1.3 * BUS.nominal_speed_mps))
    count = draw(st.integers(1, 12))
    gaps = draw(st.lists(st.floats(0.0, 60.0), min_size=count, max_size=count))
    lengths = draw(st.lists(st.floats(0.5, 30.0), min_size=count, max_size=count))
    arrivals = draw(st.lists(st.one_of(st.floats(0.0, 40.0), st.just(math.inf)),
                             min_size=count, max_size=count))
    in_view = draw(st.lists(st.one_of(st.floats(0.0, 40.0), st.just(math.inf)),
                            min_size=count, max_size=count))
    start, zones = draw(st.floats(-20.0, 5.0)), []
    for k in range(count):
        start += gaps[k]
        clear = start + lengths[k] + BUS.length_m
        zones.append(ZoneOutlook(k, start, clear, arrivals[k], max(arrivals[k], in_view[k]),
                                 DYN.travel_time(max(clear, 0.0), 0.0,
                                                 BUS.nominal_speed_mps)))
    return speed, tuple(z for z in zones if z.to_clear_m > 0.0)


def _decide(speed: float, zones: tuple[ZoneOutlook, ...]):
    return SafePolicy(DYN, BUS.nominal_speed_mps, CONFIG).decide(_picture(speed, zones))


def _kept(speed: float, zones: tuple[ZoneOutlook, ...], margin: float) -> tuple[ZoneOutlook, ...]:
    drives = [(z.to_start_m, z.to_clear_m) for z in zones]
    return tuple(zones[k] for k in within_reach(drives, 0.0, speed, DYN,
                                                BUS.nominal_speed_mps, margin))


@settings(max_examples=1500, deadline=None)
@given(_scenes())
def test_the_zones_beyond_the_reach_change_no_decision(scene) -> None:
    speed, zones = scene
    assert _decide(speed, _kept(speed, zones, CONFIG.stopping_margin_m)) == _decide(speed, zones)


def test_a_reach_a_margin_short_changes_decisions() -> None:
    """Within a stopping margin of the reach, a zone that cannot be stopped before decides:
    a reach that leaves it out lets the bus go on at its nominal speed."""
    speed = BUS.nominal_speed_mps
    reach = DYN.lookahead_distance(speed, speed) + DYN.stopping_distance(speed) \
        + CONFIG.stopping_margin_m
    zone = ZoneOutlook(0, reach - 0.5 * CONFIG.stopping_margin_m, reach + 20.0, 0.0, 0.0, 30.0)
    assert _kept(speed, (zone,), CONFIG.stopping_margin_m) == (zone,)
    assert _kept(speed, (zone,), 0.0) == ()
    assert _decide(speed, (zone,)) != _decide(speed, ())
