"""``key_moments.png`` (the paper's Fig. 5) from scenes made by hand on the paper's road: one
panel per distinct moment, in time order, and the same bytes every time."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import shapely

from sse_cosim.reporting import plots
from sse_cosim.reporting.recorder import KeyMoments, SceneFrame
from sse_cosim.sets import Zonotope
from sse_cosim.world.network import build_network
from sse_cosim.world.roadmap import load_roadmap

SOURCES = Path(__file__).resolve().parents[2] / "sumo_net"


def scene_at(t: float, bus_x: float) -> SceneFrame:
    """The bus at ``bus_x``, the truck, one camera's sector and shadow, one strip pair, the
    camera's and the fused set of the pedestrian at (195, -7.6)."""
    pedestrian = np.array([195.0, -7.6])
    sector = shapely.Polygon([(bus_x, -1.75), (bus_x + 40, -20), (bus_x + 40, 17)])
    shadow = shapely.box(186.0, -12.0, 195.0, -6.0).intersection(sector)
    return SceneFrame(
        time=t,
        footprints={"bus": ("automated", shapely.box(bus_x - 12, -3.0, bus_x, -0.5)),
                    "truck": ("parked", shapely.box(176.0, -6.0, 186.0, -3.5))},
        sectors={"bus_front": ("bus", sector.difference(shadow), shadow)},
        strips=[("bus", np.array([1.0, 0.0]), 195.0, 0.5)],
        local_sets=[("bus", Zonotope(pedestrian, np.diag([0.6, 0.5])))],
        fused_sets={"pedestrian": Zonotope(pedestrian, np.diag([0.5, 0.4]))},
        truths={"pedestrian": (195.0, -7.6)},
        unobserved=shapely.box(186.0, -9.0, 190.0, -6.0),
    )


def test_key_moments_draw_one_panel_per_scene_and_the_same_bytes_twice(tmp_path):
    roadmap = load_roadmap(build_network(SOURCES))
    moments = KeyMoments()
    start, slow = scene_at(0.0, 60.0), scene_at(8.1, 150.0)
    moments.frames = {"start": start, "first detection": start, "first slow-down": slow}
    scenes = moments.scenes()
    assert [(names, frame.time) for names, frame in scenes] == [
        ("start, first detection", 0.0), ("first slow-down", 8.1)]
    written = []
    for name in ("a.png", "b.png"):
        figure = plots.key_moments(scenes, roadmap, ["bus", "rsu1"], "S3 with pedestrian")
        titles = [ax.get_title() for ax in figure.axes if ax.axison]
        written.append(plots.save_figure(figure, tmp_path / name).read_bytes())
    assert titles == ["t = 0.0 s: start, first detection", "t = 8.1 s: first slow-down"]
    assert written[0] == written[1]
