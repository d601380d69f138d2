"""Figures: speed profiles (paper Fig. 6), set areas, scene snapshots and the key moments of a
run (Figs. 5 and 7)."""

from __future__ import annotations

import io
from collections.abc import Mapping, Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import shapely
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from PIL import Image

from sse_cosim.files import atomic_path
from sse_cosim.reporting.recorder import SceneFrame
from sse_cosim.sets.portable import matmul
from sse_cosim.world.roadmap import RoadMap

NODE_COLORS = {"bus": "tab:blue", "car": "tab:orange", "fused": "black"}
KIND_COLORS = {"automated": "tab:blue", "parked": "tab:red", "vehicle": "gold"}
KIND_LABELS = {"automated": "automated vehicle", "parked": "parked vehicle",
               "vehicle": "moving vehicle"}
RSU_COLORS = ["tab:green", "tab:cyan", "tab:olive", "tab:pink"]
VIEW_PAD_M = 5.0  # scene plots: room around what they show (m)
VIEW_MIN_M = (60.0, 28.0)  # scene plots: the least width and height shown (m)
LINE_STYLES = ("-", "--", ":", "-.")  # curves in turn: every one shows where they overlap
MARKERS = ("o", "s", "^", "D", "v", "P")
MARKS_PER_CURVE = 12  # a long curve is marked at about this many points
COINCIDE_ATOL = 0.01  # curves this close at every point are said to coincide (their units)
DPI = 120
PALETTE_COLOURS = 256  # a figure is stored with this many colours (PNG palette)


def save_figure(fig: Figure, target: Path) -> Path:
    """Write ``fig`` to ``target`` atomically as a PNG of :data:`PALETTE_COLOURS` colours
    (median cut, no dithering: about a third of matplotlib's RGBA file, and no difference a
    reader sees in these figures' few colours) and close it."""
    rendered = io.BytesIO()
    fig.savefig(rendered, format="png", dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    image = Image.open(rendered).convert("RGB").quantize(
        PALETTE_COLOURS, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    with atomic_path(target) as tmp:
        image.save(tmp, format="PNG", optimize=True)
    return target


def curve_style(index: int, points: int) -> dict[str, object]:
    """The ``index``-th curve's colour, line style and marker (marking about
    :data:`MARKS_PER_CURVE` of its ``points``, each curve from another offset), so that
    curves lying on one another all show."""
    every = max(1, points // MARKS_PER_CURVE)
    return {"color": f"C{index}", "linestyle": LINE_STYLES[index % len(LINE_STYLES)],
            "marker": MARKERS[index % len(MARKERS)], "markersize": 5,
            "markevery": (index % every, every)}


def coinciding_labels(curves: Sequence[tuple[str, np.ndarray, np.ndarray]]) -> list[str]:
    """Each curve's legend label (``curves``: label, x (k,), y (k,)), with "coincides with
    ..." where it lies on an earlier curve: the same x, and y within
    :data:`COINCIDE_ATOL` at every point."""
    labels = []
    for i, (label, x, y) in enumerate(curves):
        same = next((other for other, ox, oy in curves[:i] if len(ox) == len(x)
                     and np.allclose(ox, x) and np.allclose(oy, y, rtol=0.0,
                                                            atol=COINCIDE_ATOL)), None)
        labels.append(label if same is None else f"{label} (coincides with {same})")
    return labels


def node_color(node: str, order: Sequence[str] = ()) -> str:
    """A stable colour per node: bus blue, car orange, fused black, units in turn."""
    if node in NODE_COLORS:
        return NODE_COLORS[node]
    others = [n for n in order if n not in NODE_COLORS] or [node]
    index = others.index(node) if node in others else 0
    return RSU_COLORS[index % len(RSU_COLORS)]


def speed_profile(traces: Mapping[str, pd.DataFrame], title: str) -> Figure:
    """Actual (solid) and commanded (dotted) bus speed over time, one colour per run."""
    fig, ax = plt.subplots(figsize=(8, 4))
    for i, (label, trace) in enumerate(traces.items()):
        color = f"C{i}"
        ax.plot(trace["t"], trace["bus_speed"], color=color, label=f"{label}")
        ax.plot(trace["t"], trace["commanded_speed"], color=color, linestyle=":", linewidth=1)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("bus speed (m/s)")
    ax.set_title(title)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(title="solid: actual, dotted: commanded", fontsize=8)
    return fig


def set_areas(trace: pd.DataFrame, nodes: Sequence[str], title: str) -> Figure:
    """Area of every node's position set and of the fused set over time (log scale)."""
    fig, ax = plt.subplots(figsize=(8, 4))
    for node in [*nodes, "fused"]:
        column = f"{node}_area"
        if column in trace and trace[column].notna().any():
            style = "-" if node == "fused" else "--"
            ax.plot(trace["t"], trace[column], style, color=node_color(node, nodes), label=node)
    ax.set_yscale("log")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("position set area (m²)")
    ax.set_title(title)
    ax.grid(alpha=0.3, which="both")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)
    else:
        ax.text(0.5, 0.5, "no pedestrian set", transform=ax.transAxes, ha="center")
    return fig


def scene(frame: SceneFrame, roadmap: RoadMap, nodes: Sequence[str], title: str) -> Figure:
    """Footprints, fields of view, shadows, strips, local and fused zonotopes at one time."""
    fig, ax = plt.subplots(figsize=(10, 5))
    draw_scene(ax, frame, roadmap, nodes, f"{title}, t = {frame.time:.1f} s")
    return fig


def key_moments(scenes: Sequence[tuple[str, SceneFrame]], roadmap: RoadMap,
                nodes: Sequence[str], title: str) -> Figure:
    """The paper's Fig. 5: the scene at each key moment (``scenes``: the moments' names and
    their scene), two panels a row, one legend below them all."""
    rows = max(1, -(-len(scenes) // 2))
    fig, axes = plt.subplots(rows, 2, figsize=(13, 2.9 * rows + 0.6), squeeze=False,
                             layout="constrained")
    for ax, (moments, frame) in zip(axes.flat, scenes, strict=False):
        draw_scene(ax, frame, roadmap, nodes, f"t = {frame.time:.1f} s: {moments}", legend=False)
    for ax in axes.flat[len(scenes):]:
        ax.set_axis_off()
    entries = _legend_entries(axes.flat)
    fig.legend(entries.values(), entries.keys(), fontsize=7, loc="outside lower center", ncol=6)
    fig.suptitle(f"Key moments: {title}")
    return fig


def draw_scene(ax: Axes, frame: SceneFrame, roadmap: RoadMap, nodes: Sequence[str], title: str,
               legend: bool = True) -> None:
    """Draw ``frame`` (footprints, fields of view, shadows, strips, local and fused
    zonotopes, the true positions) on ``ax``."""
    _fill(ax, roadmap.walkable, "0.85", "walkable ground")
    _fill(ax, roadmap.crossing_area, "w", "zebra", hatch="||")
    for _name, (node, visible, occluded) in frame.sectors.items():
        color = node_color(node, nodes)
        _fill(ax, visible, color, None, alpha=0.12)
        _fill(ax, occluded, "tab:red", None, alpha=0.18)
    _fill(ax, frame.unobserved, "none", "unobserved walkable area", hatch="xxx")
    for vid, (kind, polygon) in frame.footprints.items():
        _fill(ax, polygon, KIND_COLORS.get(kind, "0.5"), KIND_LABELS.get(kind, "vehicle"),
              alpha=0.8)
        x, y = polygon.centroid.coords[0]
        ax.annotate(vid, (x, y), fontsize=6, ha="center", va="center")
    view = _view_box(frame)
    for node, normal, value, radius in frame.strips:
        _draw_strip(ax, normal, value, radius, view, node_color(node, nodes))
    for node, zonotope in frame.local_sets:
        _outline(ax, zonotope.vertices(), node_color(node, nodes), f"{node} set", "--")
    for fused in frame.fused_sets.values():
        _outline(ax, fused.vertices(), "black", "fused set", "-")
    for pid, truth in frame.truths.items():
        ax.plot(*truth, "s", color="tab:red", markersize=6, label="pedestrian (truth)")
        ax.annotate(pid, truth, fontsize=6, xytext=(3, 3), textcoords="offset points")
    ax.set_xlim(view[0], view[2])
    ax.set_ylim(view[1], view[3])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title)
    if legend:
        entries = _legend_entries([ax])
        ax.legend(entries.values(), entries.keys(), fontsize=7, loc="upper left", ncol=3)


def _legend_entries(axes) -> dict[str, object]:
    """Each label drawn on ``axes`` once (where it first appears), with its last handle."""
    entries: dict[str, object] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            entries[label] = handle
    return entries


def _view_box(frame: SceneFrame) -> tuple[float, float, float, float]:
    """A window (x0, y0, x1, y1, m) around the automated vehicles, the pedestrians, their fused
    sets and the hidden walkable ground near the crossings, padded by :data:`VIEW_PAD_M` and
    at least :data:`VIEW_MIN_M` wide and high (on any network)."""
    parts = [p for kind, p in frame.footprints.values() if kind == "automated"]
    parts += [shapely.Point(t) for t in frame.truths.values()]
    parts += [shapely.MultiPoint(z.vertices()) for z in frame.fused_sets.values()]
    if not frame.unobserved.is_empty:
        parts.append(frame.unobserved)
    if not parts:
        return (-VIEW_MIN_M[0] / 2, -VIEW_MIN_M[1] / 2, VIEW_MIN_M[0] / 2, VIEW_MIN_M[1] / 2)
    x0, y0, x1, y1 = shapely.total_bounds(parts)
    (x0, x1), (y0, y1) = (_widen(x0, x1, VIEW_MIN_M[0]), _widen(y0, y1, VIEW_MIN_M[1]))
    return (x0, y0, x1, y1)


def _widen(low: float, high: float, least: float) -> tuple[float, float]:
    """[low, high] padded by VIEW_PAD_M on each side, then widened about its middle to
    ``least`` if shorter."""
    low, high = low - VIEW_PAD_M, high + VIEW_PAD_M
    extra = max(0.0, least - (high - low)) / 2
    return low - extra, high + extra


def _fill(ax, geometry, color, label, alpha: float = 1.0, hatch: str | None = None) -> None:
    if geometry is None or geometry.is_empty:
        return
    for polygon in getattr(geometry, "geoms", [geometry]):
        if isinstance(polygon, shapely.Polygon):
            x, y = polygon.exterior.xy
            ax.fill(x, y, facecolor=color, alpha=alpha, label=label, hatch=hatch,
                    edgecolor="0.4" if hatch else color, linewidth=0.5)
            label = None


def _outline(ax, vertices: np.ndarray, color: str, label: str, style: str) -> None:
    closed = np.vstack([vertices, vertices[:1]])
    ax.plot(closed[:, 0], closed[:, 1], style, color=color, linewidth=1.5, label=label)


def _draw_strip(ax, normal: np.ndarray, value: float, radius: float, view, color: str) -> None:
    """The two lines n·x = y ± r, clipped to the view."""
    box = shapely.box(*view)
    direction = np.array([-normal[1], normal[0]])
    span = 200.0
    for offset in (value - radius, value + radius):
        base = normal * offset / float(matmul(normal, normal))
        line = shapely.LineString([base - span * direction, base + span * direction])
        clipped = line.intersection(box)
        if not clipped.is_empty:
            x, y = clipped.xy
            ax.plot(x, y, color=color, linewidth=0.6, alpha=0.6)


def speed_panels(
    with_pedestrian: Mapping[str, pd.DataFrame], without_pedestrian: Mapping[str, pd.DataFrame]
) -> Figure:
    """Paper Fig. 6: the scenarios' speed profiles with (left) and without (right) pedestrian."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 4), sharey=True)
    for ax, traces, title in ((axes[0], with_pedestrian, "with pedestrian"),
                              (axes[1], without_pedestrian, "without pedestrian")):
        curves = [(label.split()[0], trace["t"].to_numpy(), trace["bus_speed"].to_numpy())
                  for label, trace in traces.items()]
        for i, ((_, t, speed), label) in enumerate(zip(curves, coinciding_labels(curves),
                                                       strict=True)):
            ax.plot(t, speed, label=label, **curve_style(i, len(t)))
        ax.set_title(f"Bus speed, {title}")
        ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[0].set_ylabel("bus speed (m/s)")
    axes[0].set_ylim(bottom=0)
    return fig


def set_size_bars(sizes: pd.DataFrame) -> Figure:
    """Paper Fig. 7: areas of the local and fused sets at the first shared fusion."""
    scenarios = list(dict.fromkeys(sizes["scenario"]))
    fig, axes = plt.subplots(1, len(scenarios), figsize=(5 * len(scenarios), 3.5), squeeze=False)
    for ax, name in zip(axes[0], scenarios, strict=True):
        rows = sizes[sizes["scenario"] == name]
        x = np.arange(len(rows))
        ax.bar(x - 0.2, rows["area_m2"], width=0.4, label="sse-cosim")
        ax.bar(x + 0.2, rows["paper_area"].fillna(0), width=0.4, label="paper", alpha=0.6)
        ax.set_xticks(x, rows["set"])
        ax.set_ylabel("area (m²)")
        ax.set_title(f"{name}: sets at first shared fusion (t = {rows['t'].iloc[0]:.1f} s)")
        ax.legend(fontsize=8)
    return fig
