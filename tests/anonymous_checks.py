"""The soundness checks of a whole scene run with anonymous detections (tests/cosim)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

CHECKS = ("contained_fused", "contained_refined", "accounted_for")


def assert_sound_in_every_set_kind(summary: dict, out: Path) -> None:
    """0 containment violations in the nodes' tracks, the fused sets, the refined regions
    and the accounting (refined regions or the unobserved area), every check of every
    pedestrian at every step true, no collision."""
    assert summary["containment_violations"] == 0, summary["containment_violations_by_set"]
    assert summary["collisions"] == summary["contact_steps"] == 0
    checks = pd.read_csv(out / "pedestrians.csv")
    for column in CHECKS:
        checked = checks[column].dropna()
        assert len(checked) > 0 and checked.astype(bool).all(), column
