"""Sweeps in real SUMO through the CLI: rows, Dask, kill and resume, failures, the report.

Runs are cut to 3 simulated seconds; each worker process pays its start-up once.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import pytest

from sse_cosim.reporting.sweep_report import FIGURES

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parents[2]
S2 = str(ROOT / "scenarios" / "s2_pedestrian.toml")
SHORT = ["--set", "simulation.duration_s=3.0", "--workers", "2"]
SWEEP = [S2, "--param", "sensors.*.noise_bound_m=[[0.5,0.5],[1.0,1.0]]", "--seeds", "[1,2]",
         *SHORT]


def cli(*args: str, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "sse_cosim", *args], capture_output=True,
                          text=True, cwd=ROOT, check=False, **kwargs)


def run_folders(out: Path) -> list[str]:
    """Every entry of ``runs/``, hidden staging folders included."""
    return sorted(p.name for p in (out / "runs").iterdir())


def finished(out: Path) -> list[Path]:
    """Summaries of published runs (not of staging folders)."""
    return [p for p in out.glob("runs/*/summary.json") if not p.parent.name.startswith(".")]


@pytest.fixture(scope="module")
def local_sweep(tmp_path_factory) -> Path:
    """The reference: 1 scenario x 2 noise bounds x 2 seeds on the local pool."""
    out = tmp_path_factory.mktemp("local")
    proc = cli("sweep", *SWEEP, "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    return out


def test_a_sweep_writes_one_row_per_run(local_sweep):
    table = pd.read_csv(local_sweep / "sweep.csv")
    assert len(table) == 4
    assert list(table.columns[:6]) == ["key", "scenario", "seed", "sensors.*.noise_bound_m",
                                       "status", "error"]
    assert set(FIGURES) <= set(table.columns)
    assert "level_share_nominal" in table.columns
    assert list(table["seed"]) == [1, 2, 1, 2]
    assert list(table["sensors.*.noise_bound_m"]) == ["[0.5, 0.5]"] * 2 + ["[1.0, 1.0]"] * 2
    assert (table["status"] == "ok").all()
    assert table["travel_time_s"].notna().all()
    assert run_folders(local_sweep) == sorted(table["key"])
    assert (local_sweep / "sweep_average_speed_mps.png").is_file()
    assert all((local_sweep / "runs" / key / name).is_file()
               for key in table["key"] for name in ("trace.csv", "replay.html"))


def test_a_sweep_says_what_its_seeds_leave_uncertain(local_sweep, capsys):
    """sweep_uncertainty.md has each responding figure's interval over the two seeds and its
    difference between the two noise bounds; the end of the sweep says how many of them
    exceed the seeds' spread, and --detect how many seeds a stated difference needs."""
    from sse_cosim.cli.sweep_commands import _finish_sweep

    text = (local_sweep / "sweep_uncertainty.md").read_text(encoding="utf-8")
    for label in ("## average speed (m/s)", "## time stopped (s)",
                  "## min distance bus pedestrian (m)"):
        assert label in text
    assert "| s2_pedestrian | 0.5 × 0.5 | 2 |" in text
    assert "s2_pedestrian: average speed (m/s) from sensors.*.noise_bound_m = 0.5 × 0.5 to 1 × 1" \
        in text
    _finish_sweep(local_sweep, [("average_speed_mps", 0.5)])
    out = capsys.readouterr().out
    assert "average speed (m/s): " in out and "exceed the seeds' spread" in out
    assert "to tell apart 0.5 in average speed (m/s): " in out


def test_a_detection_needs_a_figure_and_a_positive_difference(tmp_path):
    proc = cli("sweep", S2, "--detect", "speed=0.1", "--out", str(tmp_path / "out"))
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1
    assert "'speed' is no figure of sweep.csv" in proc.stderr
    proc = cli("sweep", S2, "--detect", "average_speed_mps=-1", "--out", str(tmp_path / "out"))
    assert proc.returncode == 2 and "needs a positive difference" in proc.stderr
    assert not (tmp_path / "out").exists()


def test_dask_gives_the_same_rows_bit_for_bit(local_sweep, tmp_path):
    proc = cli("sweep", *SWEEP, "--executor", "dask", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "sweep.csv").read_bytes() == (local_sweep / "sweep.csv").read_bytes()


def test_a_killed_sweep_resumes_and_runs_each_run_once(local_sweep, tmp_path):
    args = [sys.executable, "-m", "sse_cosim", "sweep", *SWEEP, "--out", str(tmp_path)]
    proc = subprocess.Popen(args, cwd=ROOT, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.monotonic() + 120
    while not finished(tmp_path):
        assert proc.poll() is None and time.monotonic() < deadline, "no run finished"
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    survivors = {p: p.stat().st_mtime_ns for p in finished(tmp_path)}
    assert 1 <= len(survivors) < 4
    assert not (tmp_path / "sweep.csv").exists()

    resumed = cli("sweep", *SWEEP, "--out", str(tmp_path), "--resume")
    assert resumed.returncode == 0, resumed.stderr
    assert {p: p.stat().st_mtime_ns for p in survivors} == survivors  # not run again
    assert run_folders(tmp_path) == run_folders(local_sweep)  # no staging folder left
    assert (tmp_path / "sweep.csv").read_bytes() == (local_sweep / "sweep.csv").read_bytes()


def test_a_failing_combination_is_recorded_and_the_sweep_goes_on(tmp_path):
    proc = cli("sweep", S2, "--param", "sensors.bus_front.noise_bound_m=[[-1,-1],[0.5,0.5]]",
               "--summaries-only", *SHORT, "--out", str(tmp_path))
    assert proc.returncode == 3, proc.stderr
    assert "1 of 2 run(s) failed" in proc.stderr
    assert "FAILED s2_pedestrian__noise_bound_m=-1x-1__seed1__" in proc.stdout
    table = pd.read_csv(tmp_path / "sweep.csv")
    assert list(table["status"]) == ["failed", "ok"]
    assert "sensors.bus_front.noise_bound_m.0: Input should be greater than 0" in table["error"][0]
    ok = tmp_path / "runs" / table["key"][1]
    assert sorted(p.name for p in ok.iterdir() if p.is_file()) == ["scenario.json",
                                                                   "summary.json"]


def test_a_bad_path_exits_2_with_one_line_before_running(tmp_path):
    proc = cli("sweep", S2, "--param", "sensors.nope.noise_bound_m=[[1,1]]",
               "--out", str(tmp_path / "out"))
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1
    assert "sensors.nope.noise_bound_m: 'nope' matches nothing in sensors" in proc.stderr
    assert not (tmp_path / "out").exists()


def test_report_embeds_every_figure(local_sweep, tmp_path):
    single = tmp_path / "single"
    proc = cli("run", S2, "--set", "simulation.duration_s=3.0", "--out", str(single))
    assert proc.returncode == 0, proc.stderr
    proc = cli("report", str(single), str(local_sweep), "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr
    page = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert "Table I: average bus speed" in page
    assert f"Sweep: {local_sweep}" in page
    assert page.count('src="data:image/png;base64,') >= 6  # speeds, key moments, set areas,
    # sweep plots
    assert 'alt="Key moments (paper Fig. 5)"' in page
    assert "What the seeds leave uncertain" in page
    sweep_runs = os.path.relpath(local_sweep / "runs", tmp_path)
    replays = ["single/replay.html", *(f"{sweep_runs}/{key}/replay.html"
                                       for key in pd.read_csv(local_sweep / "sweep.csv")["key"])]
    assert [link for link in replays if f'class="replay" href="{link}' not in page] == []
    assert page.count("src=") == page.count('src="data:image/png;base64,')
    assert "<link" not in page and "<script" not in page
    assert (tmp_path / "table1.csv").is_file()
