"""Options and checks that several sub-commands share."""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import click

from sse_cosim.errors import UserError

F = TypeVar("F", bound=Callable)

OUT_HELP = "Output folder (created if missing)."
WORKERS_HELP = "Worker processes (default: the number of cores)."


def writable_folder(path: Path, option: str) -> Path:
    """``path`` created if needed; a one-line error if it cannot be written."""
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):  # anonymous: nothing is left behind
            pass
    except OSError as exc:
        raise UserError(str(path), option, f"cannot write there ({exc.strerror})",
                        "choose a folder you can write to") from None
    return path


def check_scheduler(executor: str, scheduler: str | None) -> None:
    """A Dask scheduler address only goes with the Dask executor."""
    if scheduler and executor != "dask":
        raise UserError("command line", "--scheduler", "is only used with --executor dask",
                        "add --executor dask or drop --scheduler")


RESUME_CHECK = (" A finished run is kept only if its scenario.json is what its scenario file "
                "and overrides give today (an edited file's runs are made again).")


def execution_options(resume_help: str) -> Callable[[F], F]:
    """``--workers``, ``--executor``, ``--scheduler`` and ``--resume``: where the runs of a
    batch, a sweep or a campaign execute (the same for each)."""
    def decorate(command: F) -> F:
        for option in reversed([
            click.option("--workers", type=click.IntRange(min=1), default=None,
                         help=WORKERS_HELP),
            click.option("--executor", type=click.Choice(["local", "dask"]), default="local",
                         show_default=True, help="Where runs execute."),
            click.option("--scheduler", default=None,
                         help="Dask scheduler address (tcp://host:port); default: a local "
                              "cluster of --workers single-threaded processes."),
            click.option("--resume", is_flag=True, help=resume_help + RESUME_CHECK),
        ]):
            command = option(command)
        return command
    return decorate
