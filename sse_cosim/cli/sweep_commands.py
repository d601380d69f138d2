"""``sse-cosim sweep`` and ``sse-cosim report``: parameter sweeps and the HTML report."""

from __future__ import annotations

import math
import shlex
import sys
from pathlib import Path

import click

from sse_cosim.cli.main import EXIT_SIMULATION_FAILED, cli
from sse_cosim.cli.options import OUT_HELP, check_scheduler, execution_options, writable_folder

SUMMARY_ROWS_MAX = 40  # above this, the terminal summary combines runs per scenario only


class RunsFailed(click.ClickException):
    """Some runs of a sweep failed: the sweep finished, the exit status says so."""

    exit_code = EXIT_SIMULATION_FAILED


@cli.command()
@click.argument("scenarios", nargs=-1, type=click.Path(path_type=Path))
@click.option("-f", "--file", "sweep_file", type=click.Path(path_type=Path, dir_okay=False),
              default=None, help="Sweep file (TOML: scenarios, seeds, set, params); the "
                                 "command line adds to it (see sweeps/noise.toml).")
@click.option("--param", "params", multiple=True, metavar="PATH=VALUES",
              help="A swept parameter; repeatable (see above).")
@click.option("--seeds", default=None, metavar="VALUES",
              help="Seeds, written into simulation.seed: [1,2,3] or range(1,4) "
                   "(default: each scenario's own seed).")
@click.option("--set", "fixed", multiple=True, metavar="PATH=VALUE",
              help="A fixed override for every run, e.g. --set simulation.duration_s=20; "
                   "PATH takes the patterns below and must select a field in every scenario.")
@click.option("--out", "out_dir", type=click.Path(path_type=Path, file_okay=False),
              default=Path("results/sweep"), show_default=True, help=OUT_HELP)
@execution_options("Keep finished runs; redo failed and unfinished ones.")
@click.option("--summaries-only", "summary_only", is_flag=True,
              help="Runs write summary.json and scenario.json only (no trace, sets or "
                   "plots): for large sweeps.")
@click.option("--detect", "detect", multiple=True, metavar="FIGURE=DIFFERENCE",
              callback=lambda _ctx, _param, texts: [_detection(t) for t in texts],
              help="After the sweep, say how many seeds per level tell apart a difference "
                   "of DIFFERENCE in FIGURE (a column of sweep.csv, e.g. "
                   "average_speed_mps=0.1), from how the seeds spread here; repeatable.")
def sweep(scenarios: tuple[Path, ...], sweep_file: Path | None, params: tuple[str, ...],
          seeds: str | None, fixed: tuple[str, ...], out_dir: Path, workers: int | None,
          executor: str, scheduler: str | None, resume: bool, summary_only: bool,
          detect: list[tuple[str, float]]) -> None:
    """Run SCENARIOS (files or folders) for every combination of parameter values and seeds.

    PATH is a dotted scenario path. A part may be a glob over names, and may end in a
    filter [field=glob] or [field!=glob] on the tables it selects; every field selected
    takes the same value. VALUES is a TOML list (a list field's values are lists),
    range(start,stop[,step]) (integers, stop excluded) or linspace(start,stop,num) (both
    ends included; integers if all are whole):

    \b
      --param v2x.latency_steps=range(0,5)
      --param 'estimator.max_pedestrian_speed_mps=linspace(1.5,3.5,5)'
      --param 'sensors.bus_front.noise_bound_m=[[0.25,0.25],[0.5,0.5],[1.0,1.0]]'
      --param 'sensors.*_cam.noise_bound_m=[[0.5,0.5],[1,1]]'       (glob over names)
      --param 'sensors.*[node!=bus].noise_bound_m=[[0.5,0.5],[1,1]]' (every shared sensor)

    A path that matches nothing, or a --set value a scenario refuses, stops the sweep before
    any run (exit status 2); a combination whose value is invalid (a negative noise bound) is
    a failed run. OUT gets
    sweep.json (the plan), runs/<key>/ per run, sweep.csv (one row per run; sweep.parquet
    too when pyarrow imports), sweep_<figure>.png and sweep_uncertainty.md (each figure's mean
    with its 95 % interval over seeds, and which differences between levels exceed the
    seeds' spread). Exit status 3 if any run failed.
    """
    from sse_cosim.runner.executors import Execution
    from sse_cosim.runner.parameters import parse_assignment
    from sse_cosim.runner.sweep import (
        combine,
        load_sweep_file,
        parse_parameter,
        parse_seeds,
        plan_sweep,
        run_sweep,
    )

    check_scheduler(executor, scheduler)
    assignments = [(text, *parse_assignment(text, "--set")) for text in fixed]
    spec = combine(
        load_sweep_file(sweep_file) if sweep_file else None,
        scenarios=list(scenarios),
        parameters=[parse_parameter(text) for text in params],
        seeds=parse_seeds(seeds) if seeds is not None else None,
        fixed={path: value for _, path, value in assignments},
        fixed_given={path: f"--set {text}" for text, path, _ in assignments},
    )
    runs = plan_sweep(spec)
    out_dir = writable_folder(out_dir, "--out")
    invalid = sum(run.error is not None for run in runs)
    click.echo(f"sweep: {len(runs)} runs -> {out_dir}"
               + (f" ({invalid} with invalid values, recorded as failed)" if invalid else ""))
    run_sweep(spec, runs, out_dir, _command(), summary_only,
              Execution(workers, executor, scheduler, resume))
    _finish_sweep(out_dir, detect)


def _detection(text: str) -> tuple[str, float]:
    """``FIGURE=DIFFERENCE`` of ``--detect``: a numeric column of sweep.csv and a positive
    difference."""
    from sse_cosim.reporting.sweep_report import FIGURES

    figure, _, number = text.partition("=")
    numeric = sorted(f for f in FIGURES if f != "route_completed")
    if figure not in numeric:
        raise click.BadParameter(f"{figure!r} is no figure of sweep.csv; use one of "
                                 f"{', '.join(numeric)}", param_hint="--detect")
    try:
        difference = float(number)
    except ValueError:
        difference = -1.0
    if not difference > 0.0:
        raise click.BadParameter(f"{text!r} needs a positive difference after '=', e.g. "
                                 f"{figure}=0.1", param_hint="--detect")
    return figure, difference


@cli.command()
@click.argument("folders", nargs=-1, required=True,
                type=click.Path(path_type=Path, exists=True, file_okay=False))
@click.option("--out", "out_dir", type=click.Path(path_type=Path, file_okay=False),
              default=None, help="Where report.html and the paper's tables go "
                                 "(default: the first FOLDER).")
def report(folders: tuple[Path, ...], out_dir: Path | None) -> None:
    """Rebuild tables and figures from finished run folders and write one report.html.

    FOLDERS are searched for runs (`run`, `batch`) and sweeps (`sweep`); nothing is
    simulated. OUT gets table1.csv/.md, fig7_set_sizes.csv/png, speed_profiles.png and
    report.html: one self-contained page (figures embedded) with Table I, the speed
    profiles, the set sizes, each run's set areas and every sweep's plots and table.
    Each sweep's sweep.csv and plots are rebuilt in its own folder.
    """
    from sse_cosim.reporting.html import REPORT, write_report

    out_dir = writable_folder(out_dir or folders[0], "--out")
    written = write_report(list(folders), out_dir, _command())
    click.echo(f"rebuilt {len(written) - 1} tables and figures; wrote {out_dir / REPORT}")


def _finish_sweep(out_dir: Path, detect: list[tuple[str, float]]) -> None:
    """Rebuild the sweep's table and plots, print a short summary, which differences exceed
    the seeds' spread and the seeds each ``detect`` needs; fail if a run failed."""
    from sse_cosim.reporting.sweep_report import (
        SWEEP_UNCERTAINTY,
        figure_label,
        read_sweep,
        summary_table,
        sweep_table,
        uncertainty,
        write_sweep_report,
    )
    from sse_cosim.reporting.uncertainty import MAX_SEEDS, seeds_needed

    written = write_sweep_report(out_dir)
    sweep = read_sweep(out_dir)
    table = sweep_table(sweep)
    summary = summary_table(table, sweep.columns)
    if len(summary) > SUMMARY_ROWS_MAX:
        summary = summary_table(table, [])
    click.echo(summary.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    for item in uncertainty(sweep, table):
        exceed = sum(d.exceeds for d in item.differences)
        click.echo(f"{figure_label(item.figure)}: {exceed} of {len(item.differences)} "
                   "differences between neighbouring levels exceed the seeds' spread "
                   f"({out_dir / SWEEP_UNCERTAINTY})")
    for figure, difference in detect:
        found = uncertainty(sweep, table, [figure])
        sigma = found[0].sigma if found else math.nan
        needed = seeds_needed(sigma, difference)
        if math.isnan(sigma):
            answer = "cannot say: run at least 2 seeds a combination to measure their spread"
        else:
            answer = (f"{needed} seeds per level" if needed else
                      f"more than {MAX_SEEDS:,} seeds per level") + (
                f" (the seeds spread by {sigma:.3g} here; 95 % confidence, 80 % power)")
        click.echo(f"to tell apart {difference:g} in {figure_label(figure)}: {answer}")
    failed = table[table["status"] != "ok"]
    for row in failed.itertuples():
        click.echo(f"  FAILED {row.key}: {row.error or row.status}")
    click.echo(f"wrote {out_dir / 'sweep.csv'} and {len(written) - 1} more file(s) in {out_dir}")
    if not failed.empty:
        raise RunsFailed(f"{len(failed)} of {len(table)} run(s) failed; their errors are in "
                         f"{out_dir}/runs/<key>/error.json")


def _command() -> str:
    """The command line as typed, recorded beside the numbers it produced."""
    return shlex.join(["sse-cosim", *sys.argv[1:]])
