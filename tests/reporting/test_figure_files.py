"""Figures are stored as palette PNGs (reporting/plots.py, ``save_figure``): at most 256
colours, the figure's own colours kept, the same bytes every time, and about a third of
matplotlib's RGBA file (the committed results' size, issue: reports that answer)."""

from __future__ import annotations

import io
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from PIL import Image

from sse_cosim.reporting import plots


def figure() -> plt.Figure:
    fig, ax = plt.subplots(figsize=(6, 4))
    x = np.linspace(0.0, 10.0, 200)
    for k in range(4):
        ax.plot(x, np.sin(x + k), **plots.curve_style(k, len(x)), label=f"curve {k}")
    ax.fill_between(x, -0.5, 0.5, color="tab:red", alpha=0.2)
    ax.add_patch(plt.Rectangle((4.0, -0.2), 2.0, 0.4, color=(0.0, 0.5, 1.0)))
    ax.legend()
    return fig


def test_a_figure_is_a_palette_png_with_its_colours_the_same_bytes_and_smaller(
        tmp_path: Path) -> None:
    first = plots.save_figure(figure(), tmp_path / "a.png")
    second = plots.save_figure(figure(), tmp_path / "b.png")
    assert first.read_bytes() == second.read_bytes()
    image = Image.open(first)
    assert image.mode == "P" and len(image.getcolors(256)) <= plots.PALETTE_COLOURS
    rgba = io.BytesIO()
    figure().savefig(rgba, format="png", dpi=plots.DPI, bbox_inches="tight")
    plt.close("all")
    reference = np.asarray(Image.open(rgba).convert("RGB"), dtype=int)
    stored = np.asarray(image.convert("RGB"), dtype=int)
    assert stored.shape == reference.shape
    # all but a few antialiased edge pixels within a few levels of matplotlib's own (this
    # figure: 62 of 271,545 off by more than 24 levels, at most 69); its main colours exactly
    off = np.abs(stored - reference).max(axis=2)
    assert (off <= 24).mean() > 0.999 and off.mean() < 1.0
    colours, counts = np.unique(reference.reshape(-1, 3), axis=0, return_counts=True)
    for solid in colours[np.argsort(counts)[-4:]]:  # white, the band, the patch, ... exactly
        area = (reference == solid).all(axis=2)
        assert (stored[area] == solid).all()
    assert len(first.read_bytes()) < 0.6 * len(rgba.getvalue())
