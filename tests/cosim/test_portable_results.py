"""Results that travel: a run computed with another CPU's machine code writes the same files.

The second run picks what another x86-64 CPU would (``other_cpu.OTHER_CPU``). The run's
arithmetic goes through ``sets/portable.py`` and compiled kernels, so every file it writes
is the same byte for byte (same code, same inputs: exact equality is the claim here, not
luck). Both with the default 2-D position model and with the 4-D
``bounded-acceleration`` model (n-D sets: the compiled n-D volume correction and rank test).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from other_cpu import environment

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parents[2]
SSE_COSIM = Path(sys.executable).with_name("sse-cosim")
WRITTEN = ("trace.csv", "truth.csv", "pedestrians.csv", "sets.jsonl.gz", "regions.jsonl.gz",
           "summary.json")


def _run(out: Path, other: bool, settings: tuple[str, ...]) -> None:
    """``sse-cosim run`` of S3 to 16 s into ``out`` with ``--set`` ``settings``, on another
    CPU's machine code if ``other``."""
    overrides = [arg for setting in ("simulation.duration_s=16", *settings)
                 for arg in ("--set", setting)]
    subprocess.run(
        [str(SSE_COSIM), "run", str(ROOT / "scenarios" / "s3_pedestrian.toml"), "--out", str(out),
         *overrides],
        check=True, capture_output=True, text=True, env=environment(other), cwd=ROOT)


@pytest.mark.parametrize("settings", [(), ("estimator.state_model=bounded-acceleration",)],
                         ids=["position", "bounded-acceleration"])
def test_a_run_writes_the_same_files_with_another_cpus_machine_code(tmp_path, settings):
    here, other = tmp_path / "here", tmp_path / "other"
    _run(here, False, settings)
    _run(other, True, settings)
    for name in WRITTEN:
        assert (here / name).read_bytes() == (other / name).read_bytes(), name
