"""``sse-cosim safety``: the safety campaign over the hard cases, and its report."""

from __future__ import annotations

import shlex
import time
from pathlib import Path

import click

from sse_cosim.cli.main import TargetsMissed, cli
from sse_cosim.cli.options import check_scheduler, execution_options, writable_folder
from sse_cosim.cli.sweep_commands import RunsFailed

CAMPAIGN_FILE = Path("sweeps/safety.toml")
OUT = Path("results/safety")
QUICK_OUT = Path("results/safety-quick")


@cli.command()
@click.option("-f", "--file", "campaign_file", type=click.Path(path_type=Path, dir_okay=False),
              default=CAMPAIGN_FILE, show_default=True,
              help="Campaign file (TOML: a sweep file's fields plus [start_behind_truck] and "
                   "[quick]; see sweeps/safety.toml).")
@click.option("--out", "out_dir", type=click.Path(path_type=Path, file_okay=False),
              default=None, help=f"Campaign folder (created if missing; default {OUT}, "
                                 f"{QUICK_OUT} with --quick). The report goes beside it.")
@execution_options("Keep finished runs; redo failed and unfinished ones.")
@click.option("--quick", is_flag=True,
              help="Only the few runs of the file's [quick] table (a check that it works).")
@click.option("--scenario", "only", multiple=True, metavar="NAME",
              help="Only this scenario of the file, by file name without .toml (repeatable; "
                   "default: every one), e.g. --scenario s1_pedestrian.")
def safety(campaign_file: Path, out_dir: Path | None, workers: int | None, executor: str,
           scheduler: str | None, resume: bool, quick: bool, only: tuple[str, ...]) -> None:
    """Safety campaign: does the bus stay safe and live on the hard cases?

    The claim under the model's assumptions: no collision with a pedestrian that steps
    onto the zebra in front of the bus at any walking speed up to the estimator's bound
    (estimator.max_pedestrian_speed_mps), and the bus always finishes its route. The
    campaign runs every scenario of the file for every step-out time, walking speed,
    start behind the parked truck, truck position, noise bound of the shared sensors and
    seed (1,917 runs with sweeps/safety.toml, measured on two cores: S1 to S3's 1,095
    about 31 minutes, scenarios/town.toml's 270 about 44, scenarios/junction.toml's 114
    about 109 and scenarios/crowd.toml's 438, whose 498 of before issue #61 took about
    92; sse-cosim bench projects it).
    Combinations in which the pedestrian cannot reach the zebra by the step-out time
    (the demand planner refuses them) are not run; the report lists them.

    \b
    Targets, from each run's summary.json:
      collisions (events)                          0
      containment violations (every set, region)   0
      runs that never finish the route             0
      longest standstill after the path is clear   <= 3 s
    and, reported: minimum distance bus-pedestrian (any pedestrian, and the campaign's
    own, "pedestrian"), average speed, time stopped.

    OUT gets safety.json.gz (the plan), runs/<key>/ (summary.json and scenario.json),
    safety.csv (one row per combination, those not run included) and two heat maps per
    scenario over step-out time x walking speed (safety_<scenario>_average_speed.png,
    safety_<scenario>_min_distance.png). The report, <OUT>.md (results/safety.md by
    default), goes beside OUT: the command, the grid, the counts, each target met or
    missed, a table per scenario and overall, the worst runs, the runs not feasible.

    Exit status 4 if a target is missed, or not shown because a summary lacks its key
    (the last lines name the runs); otherwise 3 if a run failed; 0 if every target is met.
    """
    from sse_cosim.reporting.safety_report import write_safety_report
    from sse_cosim.runner.executors import Execution
    from sse_cosim.runner.safety import load_campaign, plan_campaign, run_campaign

    check_scheduler(executor, scheduler)
    campaign = load_campaign(campaign_file, quick, only)
    plan = plan_campaign(campaign)
    out_dir = writable_folder(out_dir or (QUICK_OUT if quick else OUT), "--out")
    click.echo(f"safety: {len(plan.runs) + len(plan.not_feasible)} combinations: "
               f"{len(plan.runs)} runs, {len(plan.not_feasible)} not feasible (not run) "
               f"-> {out_dir}")
    started = time.perf_counter()
    run_campaign(campaign, plan, out_dir, _command(campaign_file, out_dir, quick, only),
                 Execution(workers, executor, scheduler, resume))
    click.echo(f"safety: the runs took {_duration(time.perf_counter() - started)}")
    report = write_safety_report(out_dir)
    for target in report.targets:
        click.echo(f"  {target.verdict:9} {target.label}: {target.measured}")
    click.echo(f"wrote {report.markdown} and {len(report.written) - 1} file(s) in {out_dir}")
    for key, error in report.failed:
        click.echo(f"  FAILED {key}: {error}")
    broken = [t for t in report.targets if t.met is not True]
    for target in broken:
        for line in target.breaking_lines():
            click.echo(line)
    if broken:
        raise TargetsMissed(f"{len(broken)} safety target(s) not met"
                            + (f"; {len(report.failed)} run(s) failed" if report.failed else "")
                            + f" -- see {report.markdown}")
    if report.failed:
        raise RunsFailed(f"{len(report.failed)} of {report.runs} run(s) failed; their errors "
                         f"are in {out_dir}/runs/<key>/error.json")


def _command(campaign_file: Path, out_dir: Path, quick: bool, only: tuple[str, ...]) -> str:
    """The command as it bears on the results: options that only choose where runs execute
    (workers, executor, scheduler, resume) are left out, so any machine writes the same
    report."""
    args = ["sse-cosim", "safety"]
    if campaign_file != CAMPAIGN_FILE:
        args += ["--file", str(campaign_file)]
    if out_dir != (QUICK_OUT if quick else OUT):
        args += ["--out", str(out_dir)]
    for stem in only:
        args += ["--scenario", stem]
    return shlex.join([*args, *(["--quick"] if quick else [])])


def _duration(seconds: float) -> str:
    """``seconds`` as h:mm:ss or mm:ss (tqdm's format, as in the progress bar)."""
    from tqdm import tqdm

    return tqdm.format_interval(seconds)
