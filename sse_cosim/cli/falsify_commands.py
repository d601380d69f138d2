"""``sse-cosim falsify``: an adversarial search for the world that breaks the guarantee."""

from __future__ import annotations

import shlex
import time
from pathlib import Path

import click
from tqdm import tqdm

from sse_cosim.cli.main import TargetsMissed, cli
from sse_cosim.cli.options import check_scheduler, execution_options, writable_folder
from sse_cosim.cli.sweep_commands import RunsFailed
from sse_cosim.falsify.objectives import OBJECTIVES, promises_broken
from sse_cosim.falsify.searchers import SEARCHERS

SPACE_FILE = Path("sweeps/falsify.toml")
OUT = Path("results/falsify")
DEFAULT_METHODS = ("cma", "random")
DEFAULT_BUDGET = 100
DEFAULT_SEED = 1


def _case(text: str) -> tuple[str, int]:
    """``METHOD:N`` as (method, N); click.BadParameter if it is not that."""
    method, _, number = text.partition(":")
    if method not in SEARCHERS or not number.isdigit() or int(number) < 1:
        raise click.BadParameter(f"{text!r} is not METHOD:N (METHOD one of "
                                 f"{', '.join(SEARCHERS)}, N from 1), e.g. cma:27")
    return method, int(number)


def _cases(_ctx: click.Context, _param: click.Parameter,
           values: tuple[str, ...]) -> tuple[tuple[str, int], ...]:
    return tuple(_case(text) for text in values)


@cli.command()
@click.argument("scenario", type=click.Path(path_type=Path, dir_okay=False, exists=True))
@click.option("-f", "--file", "space_file", type=click.Path(path_type=Path, dir_okay=False),
              default=SPACE_FILE, show_default=True,
              help="Falsify file: the free choices searched (TOML; see sweeps/falsify.toml).")
@click.option("--objective", type=click.Choice(list(OBJECTIVES)), default="distance",
              show_default=True,
              help="The margin driven down: "
                   + "; ".join(f"{name}: {o.help}" for name, o in OBJECTIVES.items()) + ".")
@click.option("--method", "methods", multiple=True, type=click.Choice(list(SEARCHERS)),
              help="Search method (repeatable; default: cma, with random search beside it "
                   "on the same budget and seed).")
@click.option("--budget", type=click.IntRange(min=2), default=DEFAULT_BUDGET,
              show_default=True,
              help="Evaluations per method (rounded up to whole generations).")
@click.option("--seed", type=click.IntRange(min=0), default=DEFAULT_SEED, show_default=True,
              help="Seed of every method: the same seed, the same search.")
@click.option("--out", "out_dir", type=click.Path(path_type=Path, file_okay=False),
              default=None, help=f"Search folder (default {OUT}/<scenario file name>).")
@click.option("--case", "cases", multiple=True, metavar="METHOD:N", callback=_cases,
              help="Run nothing: write METHOD's evaluation N (from 1, as the report counts) "
              "of the search in OUT as a scenario file, OUT/case_<method>_<N>.toml, that "
              "`sse-cosim run` reproduces (repeatable; give the search's falsify file, "
              "objective and seed).")
@execution_options("Keep finished runs of an earlier search with the same seed and go on "
                   "where it stopped.")
def falsify(scenario: Path, space_file: Path, objective: str, methods: tuple[str, ...],
            budget: int, seed: int, out_dir: Path | None, cases: tuple[tuple[str, int], ...],
            workers: int | None, executor: str, scheduler: str | None, resume: bool) -> None:
    """Search for the world that breaks the guarantee, within its assumptions.

    Instead of a grid, a search steers every free choice of the scenario (the
    pedestrian's wait before it steps out, walking speed and start behind the truck, each
    sensor's error within its bound, a burst of lost V2X messages per sender: see the
    falsify file) toward the smallest margin of the objective. CMA-ES (the cmaes package)
    is the search; uniform random search runs beside it on the same budget and seed, so
    the report shows what the search buys. The step-out comes after the walk the demand
    planner times plus the wait, so every candidate can happen; a file that searches the
    step-out time directly may propose one the planner rules out (the pedestrian cannot
    reach the zebra in time): it is not run.

    \b
    OUT (results/falsify/<scenario>/ by default) gets:
      report.md              the box, each method's least margin and first failure,
                             the least margin so far by evaluations, the worst cases
      evaluations.csv.gz     one row per evaluation (after every generation; gzipped)
      falsify_progress.png   least margin against evaluations, per method
      worst_<method>.toml    the worst case, a scenario file: sse-cosim run reproduces it
      worst_<method>/        that run, with its replay
      runs/<key>/            every evaluation's summary.json
      case_<method>_<N>.toml with --case (and nothing else): that evaluation as a
                             scenario file, from the ledger

    Every run counts the world's breaks of A1 (SUMO moving a walker off the model or off
    the walkable ground) instead of stopping at them; a failure counts only if it began
    before the first break, and the report lists the breaks apart. A search is
    reproducible from its seed; --resume reads back the finished runs of a killed one and
    goes on where it stopped. evaluations.csv.gz is rewritten after every generation:
    --resume takes what it records (of the same scenario, objective, seed and box) without running
    it again, so a search committed part-way goes on where runs/ is gone. A search that
    other code made (falsify.json's code_sha256, a digest of the package's sources) is not
    resumed: exit status 2.

    Exit status 4 if a run broke the guarantee within the assumptions (a collision or a
    containment violation before any break), 3 if a run failed, otherwise 0 (a failure of
    the objective alone, such as an emergency brake, and a walk-in into the standing bus
    are findings in the report).
    """
    from sse_cosim.falsify.job import falsify as run_falsify
    from sse_cosim.falsify.job import prepare, write_case
    from sse_cosim.reporting.falsify_report import run_command
    from sse_cosim.runner.executors import Execution

    check_scheduler(executor, scheduler)
    methods = methods or DEFAULT_METHODS
    setup = prepare(scenario, space_file, objective, methods, budget, seed)
    if cases:
        for method, number in cases:
            case = write_case(setup, out_dir or OUT / scenario.stem, method, number)
            click.echo(f"wrote {case}: {run_command(case.as_posix(), setup.objective.margins)}")
        return
    out_dir = writable_folder(out_dir or OUT / scenario.stem, "--out")
    click.echo(f"falsify: {setup.scenario}: {setup.space.size} values searched, "
               f"{', '.join(methods)}, {setup.generations} generation(s) of "
               f"{setup.generation} each -> {out_dir}")

    pace = _Pace(setup.generation * len(methods))

    def progress(round_: int, rounds: int, least: dict[str, float | None], ran: int) -> None:
        found = ", ".join(f"{m} {'—' if v is None else f'{v:.3f}'}" for m, v in least.items())
        click.echo(f"  generation {round_}/{rounds}: least {objective} margin {found} "
                   f"({pace.lap(ran, rounds - round_)})")

    outcome = run_falsify(setup, out_dir, Execution(workers, executor, scheduler, resume,
                                                    progress=False),
                          _command(scenario, space_file, objective, methods, budget, seed,
                                   out_dir), progress)
    for case in outcome.worst:
        click.echo(f"  worst ({case.method}): margin {case.margin:.3f} -> {case.file}")
    click.echo(f"wrote {outcome.report}")
    table = outcome.table
    broke = table[table["broken"].map(promises_broken)]
    if not broke.empty:
        raise TargetsMissed(f"{len(broke)} run(s) broke the guarantee (first: "
                            f"{broke.iloc[0]['key']}: {broke.iloc[0]['broken']}) -- see "
                            f"{outcome.report}")
    failed = table[table["error"].notna()]
    if not failed.empty:
        raise RunsFailed(f"{len(failed)} run(s) failed (first: {failed.iloc[0]['key']}: "
                         f"{failed.iloc[0]['error']}) -- see {outcome.report}")


class _Pace:
    """The wall time of the runs made so far, and what is left at that pace: ``per_round``
    runs a generation. A resumed search's recorded generations take no time and do not
    count, and a generation that ran again only the runs that failed counts as those runs."""

    def __init__(self, per_round: int) -> None:
        self._per_round = per_round
        self._last = time.monotonic()
        self._spent_s = 0.0
        self._ran = 0

    def lap(self, ran: int, left: int) -> str:
        """How the round just ended went (``ran`` runs), and the time ``left`` more rounds
        take."""
        now = time.monotonic()
        took, self._last = now - self._last, now
        if not ran:
            return "recorded"
        self._spent_s += took
        self._ran += ran
        done = f"{ran} run(s) in {tqdm.format_interval(took)}"
        if not left:
            return done
        rest_s = self._spent_s / self._ran * self._per_round * left
        return f"{done}, about {tqdm.format_interval(rest_s)} left"


def _command(scenario: Path, space_file: Path, objective: str, methods: tuple[str, ...],
             budget: int, seed: int, out_dir: Path) -> str:
    """The command as it bears on the results (where runs execute is left out)."""
    args = ["sse-cosim", "falsify", scenario.as_posix()]
    if space_file != SPACE_FILE:
        args += ["--file", space_file.as_posix()]
    if objective != "distance":
        args += ["--objective", objective]
    if methods != DEFAULT_METHODS:
        for method in methods:
            args += ["--method", method]
    args += ["--budget", str(budget), "--seed", str(seed)]
    if out_dir != OUT / scenario.stem:
        args += ["--out", out_dir.as_posix()]
    return shlex.join(args)
