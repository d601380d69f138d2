"""Sub-commands of ``sse-cosim``; each is a thin layer over ``sse_cosim.runner`` and friends."""

from __future__ import annotations

from pathlib import Path

import click

from sse_cosim.cli.main import TargetsMissed, cli
from sse_cosim.cli.options import OUT_HELP, check_scheduler, execution_options, writable_folder
from sse_cosim.reporting.margins import MARGINS


@cli.command()
@click.argument("scenario", type=click.Path(path_type=Path, dir_okay=False))
@click.option("--out", "out_dir", type=click.Path(path_type=Path, file_okay=False),
              default=None, help="Output folder (default: runs/<scenario name>).")
@click.option("--scene-at", "scene_times", type=float, multiple=True,
              help="Also draw the scene at this time (s); repeatable. The first shared "
                   "fusion is always drawn.")
@click.option("--set", "overrides", multiple=True, metavar="PATH=VALUE",
              help="Override a scenario field; repeatable. PATH takes the patterns of "
                   "`sweep --param` (globs, [field=glob] filters), and every field it "
                   "selects takes VALUE; a pattern that selects nothing is an error. "
                   "E.g. --set sensors.bus_front.range_m=40, "
                   "--set 'sensors.*[node!=bus].noise_bound_m=[1,1]'.")
@click.option("--margin", "margins", multiple=True, type=click.Choice(list(MARGINS)),
              help="Also report this margin under summary.json's `margins` (repeatable): "
                   + "; ".join(f"{name}: {m.help}" for name, m in MARGINS.items()) + ".")
def run(scenario: Path, out_dir: Path | None, scene_times: tuple[float, ...],
        overrides: tuple[str, ...], margins: tuple[str, ...]) -> None:
    """Run one SCENARIO file in SUMO and write its folder.

    The folder holds trace.csv (one row per step), sets.jsonl.gz (every local and fused
    position set), summary.json (speeds, detections, set sizes, violations, and the
    margins asked for with --margin), scenario.json (the resolved scenario) and plots
    (speed, set areas, scenes). On a terminal a bar shows the simulated time as it runs.
    """
    from sse_cosim.errors import UserError
    from sse_cosim.runner.parameters import blame_assignments, load_with_assignments
    from sse_cosim.runner.run import run_scenario

    out_dir = writable_folder(out_dir or Path("runs") / scenario.stem, "--out")
    resolved, owners = load_with_assignments(scenario, overrides)
    try:
        summary = run_scenario(resolved, str(scenario), out_dir, scene_times=scene_times,
                               margins=margins, progress=True)
    except UserError as exc:  # a check on the road network: --set may have set the field
        raise blame_assignments(exc, owners, always=False) from None
    _echo_summary(summary, out_dir)


@cli.command()
@click.argument("paths", nargs=-1, type=click.Path(path_type=Path))
@click.option("--out", "out_dir", type=click.Path(path_type=Path, file_okay=False),
              default=Path("results"), show_default=True, help=OUT_HELP)
@execution_options("Skip scenarios whose run folder is complete.")
@click.option("--scene-at", "scene_times", type=float, multiple=True,
              help="Also draw every scene at this time (s); repeatable.")
def batch(paths: tuple[Path, ...], out_dir: Path, workers: int | None, executor: str,
          scheduler: str | None, resume: bool, scene_times: tuple[float, ...]) -> None:
    """Run every scenario under PATHS (default: scenarios/) and write the paper's tables.

    Each run goes to OUT/runs/<file name>/; then OUT gets table1.csv and table1.md (average
    speeds beside the paper's Table I), fig7_set_sizes.csv/png (set sizes at the first
    shared fusion beside the paper's Fig. 7) and speed_profiles.png (Fig. 6).

    The last lines name every run with a collision or a containment violation and say
    whether its scenario breaks an assumption on purpose (breaks_assumptions, as the fault
    studies do); exit status 4 if one does not, 3 if a run failed (a run the world's motion
    check stopped is a failed run: its error.json names the assumption).
    """
    from sse_cosim.reporting.outputs import RUNS_FOLDER
    from sse_cosim.reporting.paper import read_run_folders, write_paper_report
    from sse_cosim.runner.batch import run_batch
    from sse_cosim.runner.executors import Execution

    check_scheduler(executor, scheduler)
    out_dir = writable_folder(out_dir, "--out")
    outcomes = run_batch(list(paths) or [Path("scenarios")], out_dir,
                         Execution(workers, executor, scheduler, resume), scene_times)
    runs = read_run_folders([out_dir / RUNS_FOLDER / o.key for o in outcomes if o.ok])
    written = write_paper_report(out_dir, runs)
    _echo_outcomes(outcomes, written)
    _check_guarantee(runs)


def _echo_summary(summary: dict, out_dir: Path) -> None:
    from sse_cosim.reporting.recorder import walk_ins

    standing = walk_ins(summary)
    least = summary["min_distance_bus_pedestrian_m"]
    click.echo(
        f"{summary['scenario']}: average speed {summary['average_speed_mps']:.2f} m/s, "
        + ("no pedestrian in the scene" if least is None else f"least distance {least:.2f} m")
        + f", containment violations {summary['containment_violations']}, "
        f"collisions {summary['collisions']}"
        + (f" ({standing} with the bus standing)" if standing else "") + f" -> {out_dir}"
    )


def _echo_outcomes(outcomes, written) -> None:
    for outcome in outcomes:
        if outcome.ok:
            s = outcome.summary
            click.echo(f"  {outcome.key:<24} {s['average_speed_mps']:6.2f} m/s  "
                       f"violations {s['containment_violations']}  collisions {s['collisions']}")
        else:
            click.echo(f"  {outcome.key:<24} FAILED: {outcome.error}")
    for path in written:
        click.echo(f"wrote {path}")
    failed = [o.key for o in outcomes if not o.ok]
    if failed:  # exit status 3, as the docstring, sweep and safety say (it was click's 1)
        from sse_cosim.cli.sweep_commands import RunsFailed

        raise RunsFailed(f"{len(failed)} run(s) failed: {', '.join(failed)}")


def _check_guarantee(runs) -> None:
    """The batch's last lines: every run with a collision or a containment violation, and
    whether its scenario breaks an assumption on purpose (``breaks_assumptions``). A run that
    breaks the guarantee without declaring it ends the batch with exit status 4."""
    unexpected = []
    for run in sorted(runs, key=lambda r: r.path.name):
        s = run.summary
        if not (s["collisions"] or s["containment_violations"]):
            continue
        declared = run.scenario.get("breaks_assumptions") or []
        why = (f"expected: the study breaks {', '.join(declared)}" if declared
               else "UNEXPECTED: the scenario breaks no assumption")
        click.echo(f"  {run.path.name}: {s['collisions']} collision(s), "
                   f"{s['containment_violations']} containment violation(s) -- {why}")
        if not declared:
            unexpected.append(run.path.name)
    if unexpected:
        raise TargetsMissed(f"{len(unexpected)} run(s) broke the guarantee under the model's "
                            f"assumptions: {', '.join(unexpected)}")


@cli.command()
def fields() -> None:
    """List every scenario field with its default and meaning (Markdown table)."""
    from sse_cosim.scenario.fields import fields_markdown

    click.echo(fields_markdown(), nl=False)


@cli.command()
@click.argument("network_path", metavar="SOURCES_OR_NET",
                type=click.Path(path_type=Path, exists=True), default=Path("sumo_net"))
@click.option("--step-length-s", type=click.FloatRange(min=0.001), default=None,
              help="Step length (s) the walkers are measured at [default: a scenario's, 0.1].")
@click.option("--speed-mps", type=click.FloatRange(min=0.01), default=None,
              help="Speed bound (m/s) the walkers walk at [default: the estimator's, 2.5].")
@click.option("--accel-mps2", type=click.FloatRange(min=0.01), default=None,
              help="Ramp the walkers' speed within this acceleration bound (m/s²), as runs "
                   "with estimator.state_model = 'bounded-acceleration' do (its bound: "
                   "estimator.max_pedestrian_accel_mps2, 3.2) [default: no ramp, as the "
                   "position model's runs].")
def network(network_path: Path, step_length_s: float | None, speed_mps: float | None,
            accel_mps2: float | None) -> None:
    """Build the road network and measure the position jitter its walkers need.

    SOURCES_OR_NET is a folder of plain-XML sources (default: sumo_net/; netconvert from the
    eclipse-sumo package builds it and caches the .net.xml under SOURCES/build/, and a run
    rebuilds it by itself when a source changes) or an existing SUMO .net.xml. Prints the
    network's path, then the jitter SUMO's lone walkers need at the speed bound on every
    walking area of the network, with the junction and the step that need the most, and the
    ground patches: where the lone walkers strayed off the sidewalks, walking areas and
    crossings, which the walkable ground takes in (sse_cosim/world/walker_jitter.py;
    measured once per network and setting, then read from the cache). A run whose scenario leaves
    estimator.position_jitter_m out takes the value measured on its scene's part of the
    network: the junctions its walkers walk through and those near its automated vehicles'
    routes (sse_cosim/world/extent.py, "The jitter's scope").
    """
    from sse_cosim.scenario.model import Estimator, Pedestrian, Simulation
    from sse_cosim.world.network import build_network, check_net_file
    from sse_cosim.world.roadmap import load_roadmap
    from sse_cosim.world.sumo import measure_walkers

    if network_path.is_dir():
        net_path = build_network(network_path)
    else:
        net_path = check_net_file(network_path, str(network_path))
    click.echo(net_path)
    step = step_length_s or Simulation.model_fields["step_length_s"].default
    speed = speed_mps or Estimator.model_fields["max_pedestrian_speed_mps"].default
    roadmap = load_roadmap(net_path)
    measured = measure_walkers(net_path, roadmap, None, speed, step,
                               Pedestrian.model_fields["radius_m"].default, accel_mps2)
    ramp = "" if accel_mps2 is None else f", ramped within {accel_mps2:g} m/s²"
    click.echo(f"walker jitter: {measured.jitter_m:.3f} m at {speed:g} m/s{ramp} and {step:g} s "
               f"steps over {measured.junctions} junctions with walking areas; the most "
               f"{measured.where()}")
    patches = measured.ground_patches
    beyond = roadmap.with_ground_patches(patches).walkable.area - roadmap.ground.area
    click.echo(f"ground patches: {beyond:.1f} m² beyond the sidewalks, walking areas and "
               f"crossings, at {len(patches)} of {measured.junctions} junctions")
