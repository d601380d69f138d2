"""The ``sse-cosim`` command: one sub-command per job, one-line errors for bad input."""

from __future__ import annotations

import sys

import click

from sse_cosim import __version__
from sse_cosim.errors import AssumptionBroken, SimulationError, UserError

EXIT_BAD_INPUT = 2
EXIT_SIMULATION_FAILED = 3
EXIT_TARGET_MISSED = 4
EXIT_ASSUMPTION_BROKEN = 5  # the simulated world broke an assumption of the estimator


class TargetsMissed(click.ClickException):
    """A run broke the guarantee (a collision, a containment violation) without declaring a
    broken assumption, or a safety target is missed or not shown."""

    exit_code = EXIT_TARGET_MISSED


@click.group(context_settings={"help_option_names": ["-h", "--help"], "max_content_width": 100})
@click.version_option(__version__, prog_name="sse-cosim")
def cli() -> None:
    """Set-membership estimation in shared situational awareness, co-simulated in SUMO.

    An automated bus approaches a zebra crossing hidden behind a parked truck. Its own
    sensor, an oncoming connected car and road-side units measure a pedestrian with
    bounded noise; zonotope set-membership estimation fuses what they see, and the
    bus's speed follows the guaranteed picture. Start with ``sse-cosim batch scenarios/``.
    """


def register_commands() -> None:
    """Attach every sub-command module (each adds itself to :data:`cli`)."""
    from sse_cosim.cli import (  # noqa: F401
        bench_commands,
        commands,
        falsify_commands,
        safety_commands,
        sweep_commands,
    )


def main(argv: list[str] | None = None) -> None:
    """Run the CLI; bad input ends with one line on stderr and exit status 2, no traceback."""
    register_commands()
    try:
        cli.main(args=argv, prog_name="sse-cosim", standalone_mode=False)
    except click.exceptions.Abort:
        click.echo("sse-cosim: aborted", err=True)
        sys.exit(130)
    except click.UsageError as exc:
        where = f"{exc.ctx.command_path}: " if exc.ctx is not None else "sse-cosim: "
        click.echo(f"{where}{exc.format_message()} -- see --help", err=True)
        sys.exit(EXIT_BAD_INPUT)
    except click.ClickException as exc:
        click.echo(f"sse-cosim: {exc.format_message()}", err=True)
        sys.exit(exc.exit_code)
    except UserError as exc:
        click.echo(f"sse-cosim: {exc.one_line()}", err=True)
        sys.exit(EXIT_BAD_INPUT)
    except AssumptionBroken as exc:
        click.echo(f"sse-cosim: {exc}", err=True)
        sys.exit(EXIT_ASSUMPTION_BROKEN)
    except SimulationError as exc:
        click.echo(f"sse-cosim: {exc}", err=True)
        sys.exit(EXIT_SIMULATION_FAILED)
    except KeyboardInterrupt:
        click.echo("sse-cosim: interrupted", err=True)
        sys.exit(130)
