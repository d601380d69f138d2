"""``sse-cosim bench``: every benchmark, into ``benchmarks.json`` and ``benchmarks.md``."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from sse_cosim.cli.main import cli
from sse_cosim.errors import UserError

ROOT = Path(__file__).resolve().parents[2]


@cli.command()
@click.option("--out", "out_dir", type=click.Path(path_type=Path, file_okay=False),
              default=Path("results"), show_default=True, help="Output folder.")
@click.option("--quick", is_flag=True, help="A tiny version of each benchmark (smoke test).")
@click.option("--only", multiple=True,
              type=click.Choice(["gain_methods", "kernels", "loop_cost", "tightness", "baseline",
                                 "soundness", "scaling", "crowd", "throughput", "cluster",
                                 "campaign"]),
              help="Run only this benchmark; repeatable.")
def bench(out_dir: Path, quick: bool, only: tuple[str, ...]) -> None:
    """Benchmarks and validation: cost per step against bare SUMO, gain methods, scaling,
    sweep throughput, tightness against the exact filter, the soundness campaign, the
    Kalman-filter baseline, and make safety's wall time projected from one timed run per
    scenario (item 8).

    Writes OUT/benchmarks.json (every figure, the command and the machine) and
    OUT/benchmarks.md. Runs from a source checkout (it needs benchmarks/ and scenarios/);
    the full set takes about a quarter of an hour on two cores.
    """
    if not (ROOT / "benchmarks" / "run.py").is_file() or not (ROOT / "scenarios").is_dir():
        raise UserError(str(ROOT), "bench", "benchmarks/ or scenarios/ not found",
                        "run sse-cosim bench from a source checkout (pip install -e .)")
    import os

    out = out_dir.resolve()  # relative to where the command was given
    os.chdir(ROOT)
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    from benchmarks.run import run_all

    command = "sse-cosim bench --out " + str(out_dir) + "".join(f" --only {o}" for o in only)
    run_all(out, quick, log=lambda text: click.echo(text, err=True),
            only=set(only) or None, command=command)
