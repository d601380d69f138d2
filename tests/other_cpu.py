"""Another CPU's machine code, for tests that ask for the same results on every machine
(imported as ``other_cpu``: pytest puts tests/ on the path for its conftest.py).

:data:`OTHER_CPU` picks what another x86-64 CPU would: OpenBLAS's kernels for a CPU without
AVX or FMA, NumPy's baseline SIMD loops only (no AVX2, no AVX-512) and numba compiling for a
generic CPU. These are read when the libraries load, so they take a new process."""

from __future__ import annotations

import os

OTHER_CPU = {
    "OPENBLAS_CORETYPE": "Nehalem",
    "NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL AVX512_SPR",
    "NUMBA_CPU_NAME": "generic",
}


def environment(other: bool) -> dict[str, str]:
    """This process's environment without any CPU setting, with :data:`OTHER_CPU`'s if
    ``other``."""
    base = {k: v for k, v in os.environ.items() if k not in OTHER_CPU}
    return {**base, **OTHER_CPU} if other else base
