"""The sidewalk hidden behind the truck's front corner in S2 without the pedestrian
(docs/results.md, "The scene the paper describes"): the bus's unobserved area near the truck
when the bus leaves its nominal speed with the truck's front at 186 m (5.9 s), for the
truck's front at 186 m and at 183 m.

    sse-cosim run scenarios/s2_no_pedestrian.toml --set parked.truck.end_pos_m=186 \
        --out runs/wedge_186
    sse-cosim run scenarios/s2_no_pedestrian.toml --out runs/wedge_183
    python docs/figures/hidden_wedge.py runs/wedge_186 runs/wedge_183 --t 5.9

Each panel reads the run's regions.jsonl.gz (the unobserved area the controller used) and its
scenario.json (the truck's front and length; the paper road's parking strip spans y = -6 to
-3.5 m, the zebra x = 198 to 202 m).
"""

from __future__ import annotations

import argparse
import gzip
import json
from pathlib import Path

import matplotlib.pyplot as plt
import shapely
from matplotlib.patches import Rectangle

STRIP_Y = (-6.0, -3.5)  # the parking strip (m)
ZEBRA_X = (198.0, 202.0)  # the zebra (m)


def unobserved_at(run: Path, t: float) -> shapely.Geometry:
    """The unobserved area of ``run`` at time ``t`` (s), as regions.jsonl.gz holds it."""
    for line in gzip.decompress((run / "regions.jsonl.gz").read_bytes()).decode().splitlines():
        record = json.loads(line)
        if record["kind"] == "unobserved" and abs(record["t"] - t) < 1e-6:
            return shapely.MultiPolygon([shapely.Polygon(p[0], p[1:]) for p in
                                         record["polygons"]])
    raise SystemExit(f"{run}/regions.jsonl: no unobserved area at t = {t} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="run folders (sse-cosim run --out)")
    parser.add_argument("--t", type=float, required=True, help="time (s)")
    parser.add_argument("--out", type=Path, default=Path("docs/figures/hidden_wedge.png"))
    args = parser.parse_args()
    fig, axes = plt.subplots(len(args.runs), 1, figsize=(9, 2.6 * len(args.runs)),
                             squeeze=False, layout="constrained")
    for ax, run in zip(axes[:, 0], args.runs, strict=True):
        truck = json.loads((run / "scenario.json").read_text())["parked"]["truck"]
        front, length = truck["end_pos_m"], truck["length_m"]
        hidden = unobserved_at(run, args.t)
        for polygon in hidden.geoms:
            ax.fill(*polygon.exterior.xy, facecolor="none", edgecolor="tab:red", hatch="xxx",
                    linewidth=0.8, label="hidden walkable ground (unobserved area)")
        ax.add_patch(Rectangle((front - length, STRIP_Y[0]), length, STRIP_Y[1] - STRIP_Y[0],
                               color="tab:red", alpha=0.6, label=f"truck, front at {front:g} m"))
        ax.axvspan(*ZEBRA_X, color="0.8", label="zebra")
        ax.set_xlim(165, 205)
        ax.set_ylim(-9, -2)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.set_title(f"{run.name}: t = {args.t:g} s")
        handles, labels = ax.get_legend_handles_labels()
        unique = dict(zip(labels, handles, strict=True))
        ax.legend(unique.values(), unique.keys(), fontsize=7, loc="lower left")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
