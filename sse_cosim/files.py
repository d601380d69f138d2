"""Crash-safe file output: every file is written whole or not at all (write, then rename); a
file named ``*.gz`` is written gzipped (:func:`write_text_atomic`) and read back as text
(:func:`read_text`); and the reading of the TOML files that plan work (sweeps, campaigns,
searches), with one-line errors."""

from __future__ import annotations

import contextlib
import gzip
import json
import os
import tempfile
import tomllib
import zlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from sse_cosim.errors import UserError

M = TypeVar("M", bound=BaseModel)


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; rename it onto ``target`` only on success.

    A crash or exception at any moment leaves either the old ``target`` or the new one,
    never a half-written file. The temporary name starts with ``.`` and ends in ``.part``
    (plus the target's suffix, so that writers that look at suffixes still work). The file
    gets the mode a plain ``open`` gives (0666 less the umask), not the temporary file's 0600.
    """
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(
        prefix=f".{target.stem}.", suffix=f".part{target.suffix}", dir=target.parent
    )
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        tmp.chmod(0o666 & ~_umask())
        os.replace(tmp, target)
    finally:
        if tmp.exists():
            tmp.unlink()


def _umask() -> int:
    """The process's umask (read by setting it and setting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


GZIP_SUFFIX = ".gz"
"""A file whose name ends so is written and read gzipped."""


def write_text_atomic(target: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``target`` atomically and return the target path; gzipped if
    ``target`` ends in :data:`GZIP_SUFFIX`, with no name or time in the header, so that the
    same text gives the same bytes every time (committed results stay unchanged)."""
    data = text.encode("utf-8")
    if Path(target).suffix == GZIP_SUFFIX:
        data = gzip.compress(data, compresslevel=9, mtime=0)
    with atomic_path(target) as tmp:
        tmp.write_bytes(data)
    return Path(target)


def refuse_plain(path: Path) -> None:
    """Refuse in one line (:class:`UserError`) a folder whose ``path`` (``*.gz``) is missing
    but that holds it plain: an older sse-cosim wrote it so."""
    plain = path.with_suffix("")
    if path.suffix == GZIP_SUFFIX and not path.exists() and plain.is_file():
        raise UserError(str(plain), "", "was written by an older sse-cosim, which did not "
                        f"gzip it (this one reads {path.name})",
                        f"gzip it (gzip {plain}) and run the command again")


def read_text(path: str | os.PathLike[str]) -> str:
    """The text (UTF-8) of the file at ``path``, un-gzipped if its name ends in
    :data:`GZIP_SUFFIX` (:func:`write_text_atomic`)."""
    data = Path(path).read_bytes()
    if Path(path).suffix == GZIP_SUFFIX:
        data = gzip.decompress(data)
    return data.decode("utf-8")


def write_json_atomic(target: str | os.PathLike[str], data: Any) -> Path:
    """Write ``data`` as indented JSON to ``target`` atomically."""
    return write_text_atomic(target, json.dumps(data, indent=2, sort_keys=False) + "\n")


def portable_path(path: str | os.PathLike[str], start: str | os.PathLike[str] | None = None) -> str:
    """``path`` as committed results should record it: relative to ``start`` (default: the
    current folder, the repository for ``make run``) when it lies below it, else as given.

    Absolute paths of one machine in a results file would change it on every other machine.
    """
    base = Path(start if start is not None else Path.cwd()).resolve()
    target = Path(path)
    resolved = (target if target.is_absolute() else Path.cwd() / target).resolve()
    if resolved.is_relative_to(base):
        return resolved.relative_to(base).as_posix()
    return str(path)


def read_plan(path: Path, command: str) -> dict[str, Any]:
    """The JSON plan a command wrote (``sweep.json``, ``safety.json.gz``); a one-line error
    naming ``command`` when it is missing or broken (:func:`refuse_plain`)."""
    refuse_plain(path)
    try:
        return json.loads(read_text(path))
    except (OSError, EOFError, zlib.error, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise UserError(str(path), "", f"cannot be read ({exc})",
                        f"name a folder written by `{command}`") from None


def read_toml_model(path: Path, model: type[M], what: str, missing_fix: str,
                    example_fix: str) -> M:
    """The TOML file at ``path`` validated as ``model``; a :class:`UserError` naming the file
    and the field (``params[0].values``) otherwise. ``what`` names the file in the error when
    it is missing ("sweep file"), ``missing_fix`` and ``example_fix`` are the fixes offered."""
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise UserError(str(path), "", f"{what} not found", missing_fix) from None
    except tomllib.TOMLDecodeError as exc:
        raise UserError(str(path), "syntax", str(exc), "fix the TOML syntax there") from None
    try:
        return model.model_validate(raw)
    except ValidationError as exc:
        err = exc.errors(include_url=False)[0]
        where = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in err["loc"])
        message = str(err["msg"]).removeprefix("Value error, ")
        raise UserError(str(path), where.lstrip("."), message, example_fix) from None
