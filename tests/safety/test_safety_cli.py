"""``sse-cosim safety`` through the CLI: its help, and ``--quick`` in real SUMO (2 runs)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.cli.main import main

ROOT = Path(__file__).resolve().parents[2]


def test_help_says_what_it_proves_and_writes(capsys):
    main(["safety", "--help"])
    text = capsys.readouterr().out
    assert text.startswith("Usage: sse-cosim safety")
    for words in ("no collision", "finishes its route", "safety.csv", "Exit status 4"):
        assert words in " ".join(text.split())


@pytest.mark.sumo
def test_quick_runs_writes_the_report_and_says_which_targets_hold(tmp_path):
    out = tmp_path / "safety"
    proc = subprocess.run(
        [sys.executable, "-m", "sse_cosim", "safety", "--quick", "--out", str(out),
         "--workers", "2"],
        capture_output=True, text=True, cwd=ROOT, check=False, timeout=120)
    assert proc.returncode == 0, proc.stderr  # every target met on the quick runs
    assert re.search(r"^safety: the runs took \d\d:\d\d$", proc.stdout, re.M), proc.stdout
    table = pd.read_csv(out / "safety.csv")
    assert table["status"].value_counts().to_dict() == {"ok": 2, "not feasible": 2}
    assert len(list((out / "runs").iterdir())) == 2
    for key in table.loc[table["status"] == "ok", "key"]:
        written = {p.name for p in (out / "runs" / key).iterdir()}
        assert {"scenario.json", "summary.json"} <= written and "trace.csv" not in written
    for figure in ("average_speed", "min_distance"):
        assert (out / f"safety_s3_pedestrian_{figure}.png").is_file()
    report = (tmp_path / "safety.md").read_text(encoding="utf-8")
    assert f"Made by `sse-cosim safety --out {out} --quick`" in report
    assert "cannot be reached" in report  # the planner's reason for those not run
    assert report.count("| met |") == 4
