"""Results that travel: a run computed with another CPU's machine code writes the same files.

The second run picks what another x86-64 CPU would: OpenBLAS's kernels for a CPU without
AVX or FMA, NumPy's baseline SIMD loops only (no AVX2, no AVX-512) and numba compiling for
a generic CPU. The run's arithmetic goes through ``sets/portable.py`` and compiled kernels,
so every file it writes is the same byte for byte (same code, same inputs: exact equality
is the claim here, not luck). Both with the default 2-D position model and with the 4-D
``bounded-acceleration`` model (n-D sets: the compiled n-D volume correction and rank test).
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


def _run(out: Path, env: dict[str, str], settings: tuple[str, ...]) -> None:
    """``sse-cosim run`` of S3 to 16 s into ``out`` with ``--set`` ``settings``, with ``env``
    instead of any CPU setting."""
    base = {k: v for k, v in os.environ.items() if k not in OTHER_CPU}
    overrides = [arg for setting in ("simulation.duration_s=16", *settings)
                 for arg in ("--set", setting)]
    subprocess.run(
        [str(SSE_COSIM), "run", str(ROOT / "scenarios" / "s3_pedestrian.toml"), "--out", str(out),
         *overrides],
        check=True, capture_output=True, text=True, env={**base, **env}, cwd=ROOT)


@pytest.mark.parametrize("settings", [(), ("estimator.state_model=bounded-acceleration",)],
                         ids=["position", "bounded-acceleration"])
def test_a_run_writes_the_same_files_with_another_cpus_machine_code(tmp_path, settings):
    here, other = tmp_path / "here", tmp_path / "other"
    _run(here, {}, settings)
    _run(other, OTHER_CPU, settings)
    for name in WRITTEN:
        assert (here / name).read_bytes() == (other / name).read_bytes(), name
