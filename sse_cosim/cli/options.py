"""Options and checks that several sub-commands share."""

from __future__ import annotations

import tempfile
from pathlib import Path

from sse_cosim.errors import UserError

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
