"""Runs every benchmark and writes ``benchmarks.json`` and ``benchmarks.md``.

``python -m benchmarks.run --out results/`` (from the repository root) or ``sse-cosim bench``.
``--quick`` runs a tiny version of each (the smoke test in ``tests/benchmarks``).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path

from benchmarks import (
    arrivals,
    baseline,
    campaign,
    cluster,
    crowd,
    gain_methods,
    kernels,
    loop_cost,
    report,
    scaling,
    soundness,
    throughput,
    tightness,
)
from benchmarks.common import machine
from sse_cosim.files import write_text_atomic

TARGETS = {
    "loop_default_ratio_to_libsumo": 150.0,
    "loop_b_ratio_to_a": 20.0,
    "anonymous_ratio_to_labelled": 1.5,
    "crowd_ms": 15.0,
    "safety_minutes_2_cores": 60.0,
    "kernels_ratio_to_zonoopt": 2.0,
    "kernels_ratio_to_shapely": 1.5,
    "kernel_targets": ["intersection", "reduction", "area", "enclose intersection"],
    "scaling_exponent": 1.0,
    "scaling_largest_ms": 30.0,
    "throughput_speedup_2_workers": 1.8,
    "cluster_ratio_to_local": 0.9,
    "tightness_best_mean": 1.3,
    "arrivals_ratio_of_means": 0.95,
    "soundness_node_steps": 100_000,
    "soundness_violations": 0,
}


def run_all(out: Path, quick: bool = False, log: Callable[[str], None] = print,
            only: set[str] | None = None, command: str = "sse-cosim bench") -> dict:
    """Run the benchmarks (all, or the names in ``only``) and write the two files."""
    started = time.perf_counter()
    results: dict = {
        "command": command + (" --quick" if quick else ""),
        "machine": machine(),
        "quick": quick,
        "targets": TARGETS,
        "seconds": {},
    }

    def stage(name: str, call: Callable[[], dict]) -> None:
        if only is not None and name not in only:
            return
        log(f"bench: {name} ...")
        t0 = time.perf_counter()
        results[name] = call()
        results["seconds"][name] = time.perf_counter() - t0
        log(f"bench: {name} done in {results['seconds'][name]:.1f} s")

    stage("gain_methods", lambda: gain_methods.run(number=20 if quick else 200,
                                                   repeats=2 if quick else 5))
    stage("kernels", lambda: kernels.run(number=50 if quick else 2000,
                                         repeats=2 if quick else 5))
    stage("loop_cost", lambda: loop_cost.run(
        repeats=1 if quick else 3,
        configs={name: loop_cost.CONFIGS[name] for name in (
            "a_frobenius", "b_cvxpy_frobenius", loop_cost.DEFAULT, loop_cost.ANONYMOUS)}
        if quick else None,
        duration_s=1.5 if quick else None, profile=not quick))
    recordings, summaries = [], {}
    if only is None or {"tightness", "baseline"} & only:
        log("bench: recording the scenarios' measurement streams ...")
        paths = ["scenarios/s3_pedestrian.toml"] if quick else tightness.SCENARIOS
        for path in paths:
            rec, summary, _ = tightness.record(
                path, {"simulation.duration_s": 8.0} if quick else None)
            recordings.append(rec)
            summaries[rec.scenario] = summary
    stage("tightness", lambda: tightness.run(
        recordings, gains=("frobenius", "volume") if quick else tightness.GAINS,
        workers=1 if quick else 2))
    stage("baseline", lambda: baseline.run(recordings, summaries, quick=quick))
    stage("arrivals", lambda: arrivals.run_all(
        ["scenarios/s3_pedestrian.toml"] if quick else arrivals.SCENARIOS,
        {"simulation.duration_s": 8.0} if quick else None))
    stage("soundness", lambda: soundness.run(node_steps=300 if quick else 100_000,
                                             steps=50 if quick else 200,
                                             workers=1 if quick else 2))
    stage("scaling", lambda: scaling.run(pedestrians=(1, 4) if quick else scaling.PEDESTRIANS,
                                         sensors=(1, 2) if quick else scaling.SENSORS,
                                         steps=1 if quick else 5, warmup=1 if quick else 2))
    stage("crowd", lambda: crowd.run(pedestrians=crowd.PEDESTRIANS, repeats=1 if quick else 2,
                                      duration_s=1.0 if quick else 20.0))
    stage("throughput", lambda: throughput.run(runs=2 if quick else 16,
                                               duration_s=1.0 if quick else None,
                                               dask=not quick))
    stage("cluster", lambda: cluster.run(runs=10 if quick else 1000,
                                         duration_s=0.5 if quick else 3.0))
    stage("campaign", lambda: campaign.run(quick=quick, duration_s=1.0 if quick else None))
    results["total_seconds"] = time.perf_counter() - started
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "benchmarks.json", json.dumps(results, indent=2, default=float) + "\n")
    write_text_atomic(out / "benchmarks.md", report.markdown(results))
    log(f"bench: wrote {out / 'benchmarks.json'} and {out / 'benchmarks.md'} "
        f"({results['total_seconds']:.0f} s)")
    return results


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", type=Path, default=Path("results"))
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--only", nargs="*", default=None)
    args = parser.parse_args(argv)
    run_all(args.out, args.quick, only=set(args.only) if args.only else None,
            command="python -m benchmarks.run")
    return 0


if __name__ == "__main__":
    sys.exit(main())
