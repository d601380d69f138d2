"""A signalised crossing's own ground is cut by the ground near it only: the same ground as the
cut by the whole network's (the reference below), and never more, on hand-made ground with a
sidewalk that comes within the offset without touching the crossing."""

from __future__ import annotations

from pathlib import Path

import pytest
import shapely

from sse_cosim.world.roadmap import MITRE_LIMIT, OWN_GROUND_TOL_M, Crossing, RoadMap


def _roadmap(sidewalks: list[shapely.Polygon], crossings: list[Crossing],
             patches: dict[str, shapely.Geometry]) -> RoadMap:
    road = RoadMap(Path("hand_made.net.xml"), tuple(crossings), shapely.union_all(sidewalks),
                   {}, {}, {}, {}, {})
    return road.with_ground_patches(patches, junction_margin_m=0.4, stray_m=0.5)


def _reference(road: RoadMap, crossing: Crossing) -> shapely.Geometry:
    """The cut by every other piece of ground of the network (the definition)."""
    others = shapely.union_all([road.sidewalks, *(c.area for c in road.crossings
                                                  if c is not crossing),
                                *road.ground_patches.values()])
    grow = road.junction_margin_m + road.stray_m + OWN_GROUND_TOL_M
    return shapely.difference(crossing.area, others.buffer(grow, join_style="mitre",
                                                           mitre_limit=MITRE_LIMIT))


@pytest.mark.parametrize("gap_m", [0.0, 0.3, 0.85])
def test_a_crossing_s_own_ground_is_the_cut_by_the_whole_ground(gap_m: float) -> None:
    lit = Crossing("lit", "n", shapely.box(0.0, 0.0, 4.0, 10.0), (("tls", 0),))
    zebra = Crossing("zebra", "n", shapely.box(4.0 + gap_m, 2.0, 8.0, 3.0))
    near = shapely.box(-3.0, -3.0 - gap_m, 10.0, -gap_m)  # a kerb 'gap_m' off the crossing
    far = [shapely.box(1000.0 + 10 * k, 0.0, 1005.0 + 10 * k, 3.0) for k in range(20)]
    patch = shapely.Polygon([(0.0, 12.0 + gap_m), (2.0, 10.5 + gap_m), (4.0, 12.0 + gap_m)])
    road = _roadmap([near, *far], [lit, zebra], {"n": patch})
    own = road.own_grounds
    assert set(own) == {"lit"}  # an unlit crossing has no own ground
    reference = _reference(road, lit)
    assert own["lit"].area < lit.area.area - 0.1  # the kerb, the zebra and the patch cut it
    assert shapely.symmetric_difference(own["lit"], reference).area < 1e-9
    assert reference.buffer(1e-9).contains(own["lit"])


def test_ground_beyond_the_reach_cuts_nothing() -> None:
    lit = Crossing("lit", "n", shapely.box(0.0, 0.0, 4.0, 10.0), (("tls", 0),))
    grow = 0.4 + 0.5 + OWN_GROUND_TOL_M
    beyond = shapely.box(-3.0, -20.0, 10.0, -MITRE_LIMIT * grow - 1.5)
    road = _roadmap([beyond], [lit], {})
    assert shapely.equals(road.own_grounds["lit"], lit.area)
    assert shapely.equals(_reference(road, lit), lit.area)
