"""Walkable ground where a crossing meets a walking area, on the town cut (sumo_net/town/).

SUMO walks a pedestrian over a walking area on a curve from the end of one lane to the start
of the next; at ``:cluster_8989139931_8989139951_c1`` that curve runs through the wedge
between the crossing's rectangle and the walking area's kerb, which the plain ground
(sidewalk lanes, walking areas, crossing rectangles) leaves out. The positions below are where
SUMO put the scene's second pedestrian (``scenarios/town.toml`` with
``pedestrians.walker.steps_onto_crossing_s=25`` and
``pedestrians.walker.crossing=:cluster_8989139931_8989139951_c1``, truth.csv, 1.2 m/s),
0.009 to 0.197 m outside the plain ground; before the walkable ground held the junctions'
measured patches, that run counted them as six ``unaccounted`` containment violations. The
walkable ground with the patches where the lone walkers (2.5 m/s,
sse_cosim/world/walker_jitter.py) left the plain ground holds them.
"""

from __future__ import annotations

import shapely
from world_helpers import REPO

from sse_cosim.scenario.loader import load_scenario
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import WALKABLE_COARSEN_M, load_roadmap
from sse_cosim.world.sumo import measure_walkers

# (t, x, y): SUMO's positions of the walker entering and leaving the crossing (m)
WALKER_AT_THE_JOINS = [
    (24.9, 176.98188, 188.541668),
    (25.0, 177.070736, 188.461026),
    (25.1, 177.15957, 188.380404),
    (25.2, 177.248404, 188.299782),
    (30.6, 182.045487, 183.946127),
    (30.7, 182.134347, 183.86548),
]


def _measured_town():
    net_path = build_network(REPO / "sumo_net" / "town")
    roadmap = load_roadmap(net_path)
    scenario = load_scenario(REPO / "scenarios" / "town.toml")
    return roadmap, measure_walkers(net_path, roadmap, None,
                                    scenario.estimator.max_pedestrian_speed_mps,
                                    scenario.simulation.step_length_s,
                                    scenario.pedestrian_radius_m())


def test_the_walkable_ground_holds_sumos_walker_where_a_crossing_meets_a_walking_area() -> None:
    roadmap, measured = _measured_town()
    xy = [(x, y) for _, x, y in WALKER_AT_THE_JOINS]
    x, y = zip(*xy, strict=True)
    assert not shapely.intersects_xy(roadmap.ground, x, y).any()  # the wedge
    walkable = roadmap.with_ground_patches(measured.ground_patches).walkable
    outside = {t: round(float(d), 3) for (t, _, _), d
               in zip(WALKER_AT_THE_JOINS, shapely.distance(walkable, shapely.points(xy)),
                      strict=True) if d > 0.0}
    assert not outside, f"off the walkable ground (s: m): {outside}"


def test_the_walkable_ground_holds_its_parts_within_nanometres_in_far_fewer_vertices() -> None:
    """The patches' union with the ground leaves corners that stray from a straight edge by
    nanometres; the walkable ground is coarsened by WALKABLE_COARSEN_M: it holds the union of
    its parts, lies within six times that of it (a corner mitred at GEOS's limit of five
    times the growth, then simplified), and has less than half its vertices."""
    roadmap, measured = _measured_town()
    walkable = roadmap.with_ground_patches(measured.ground_patches).walkable
    parts = shapely.union_all([roadmap.ground, *measured.ground_patches.values()])
    assert walkable.covers(parts)
    assert shapely.buffer(parts, 6.0 * WALKABLE_COARSEN_M, join_style="mitre",
                          mitre_limit=10.0).covers(walkable)
    assert not shapely.buffer(parts, WALKABLE_COARSEN_M, join_style="mitre",
                              mitre_limit=10.0).covers(walkable)  # it did coarsen
    assert shapely.get_num_coordinates(walkable) < 0.5 * shapely.get_num_coordinates(parts)
