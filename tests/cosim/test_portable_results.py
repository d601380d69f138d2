"""Results that travel: a run computed with another CPU's machine code writes the same files.

The second run picks what another x86-64 CPU would: OpenBLAS's kernels for a CPU without
AVX or FMA, NumPy's baseline SIMD loops only (no AVX2, no AVX-512) and numba compiling for
a generic CPU. The run's arithmetic goes through ``sets/portable.py`` and compiled kernels,
so every file it writes is the same byte for byte (same code, same inputs: exact equality
is the claim here, not luck).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.sumo

ROOT = Path(__file__).resolve().parents[2]
SSE_COSIM = Path(sys.executable).with_name("sse-cosim")
OTHER_CPU = {
    "OPENBLAS_CORETYPE": "Nehalem",
    "NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL AVX512_SPR",
    "NUMBA_CPU_NAME": "generic",
}
WRITTEN = ("trace.csv", "truth.csv", "pedestrians.csv", "sets.jsonl", "regions.jsonl",
           "summary.json")


def _run(out: Path, env: dict[str, str]) -> None:
    """``sse-cosim run`` of S3 to 16 s into ``out``, with ``env`` instead of any CPU setting."""
    base = {k: v for k, v in os.environ.items() if k not in OTHER_CPU}
    subprocess.run(
        [str(SSE_COSIM), "run", str(ROOT / "scenarios" / "s3_pedestrian.toml"), "--out", str(out),
         "--set", "simulation.duration_s=16"],
        check=True, capture_output=True, text=True, env={**base, **env}, cwd=ROOT)


def test_a_run_writes_the_same_files_with_another_cpus_machine_code(tmp_path):
    here, other = tmp_path / "here", tmp_path / "other"
    _run(here, {})
    _run(other, OTHER_CPU)
    for name in WRITTEN:
        assert (here / name).read_bytes() == (other / name).read_bytes(), name
