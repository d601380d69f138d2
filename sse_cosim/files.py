"""Crash-safe file output: every file is written whole or not at all (write, then rename); a
file named ``*.gz`` is written gzipped (:func:`write_text_atomic`) and read back as text
(:func:`read_text`); and the reading of the TOML files that plan work (sweeps, campaigns,
searches), with one-line errors."""

from __future__ import annotations

import contextlib
import gzip
import json
import os
import struct
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
    tmp = _part_beside(target)
    try:
        yield tmp
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        _put_in_place(tmp, target)
    finally:
        if tmp.exists():
            tmp.unlink()


def _part_beside(target: Path) -> Path:
    """A new empty temporary file beside ``target`` (see :func:`atomic_path`)."""
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(
        prefix=f".{target.stem}.", suffix=f".part{target.suffix}", dir=target.parent
    )
    os.close(fd)
    return Path(tmp_name)


def _put_in_place(tmp: Path, target: Path) -> None:
    """Give the written ``tmp`` a plain file's mode and rename it onto ``target``."""
    tmp.chmod(0o666 & ~_umask())
    os.replace(tmp, target)


def _umask() -> int:
    """The process's umask (read by setting it and setting it back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


GZIP_SUFFIX = ".gz"
"""A file whose name ends so is written and read gzipped."""


def _gzip_header(level: int) -> bytes:
    """The header of a gzip file written here at ``level``: deflate, no name, time 0, the
    level's flag (XFL 2 at 9, 4 at 1, else 0) and Unix: the bytes ``gzip.compress(data, level,
    mtime=0)`` of Python 3.11 writes."""
    flag = {9: 2, 1: 4}.get(level, 0)
    return b"\x1f\x8b\x08\x00" + bytes(4) + bytes([flag, 3])


class AtomicGzip:
    """A gzipped text file written in pieces (:meth:`write`) and renamed onto ``target`` by
    :meth:`finish` alone, as :func:`atomic_path` does: only the compressed text is held, and
    the bytes are those of the whole text at once (deflate's output does not depend on how
    its input is cut). A run that stops before :meth:`finish` calls :meth:`discard`, which
    removes the part written. ``level``: deflate's, 9 (the smallest file) unless a file
    written while a run goes has its reason to trade size for speed."""

    def __init__(self, target: str | os.PathLike[str], level: int = 9) -> None:
        self.target = Path(target)
        self._tmp = _part_beside(self.target)
        self._file = open(self._tmp, "wb")  # noqa: SIM115 -- closed by finish or discard
        self._file.write(_gzip_header(level))
        self._deflate = zlib.compressobj(level, zlib.DEFLATED, -zlib.MAX_WBITS)
        self._crc = 0
        self._size = 0

    def write(self, text: str) -> None:
        """Append ``text`` (UTF-8)."""
        data = text.encode("utf-8")
        self._crc = zlib.crc32(data, self._crc)
        self._size += len(data)
        self._file.write(self._deflate.compress(data))

    def finish(self) -> Path:
        """Close the file and put it in place; returns the target path."""
        self._file.write(self._deflate.flush())
        self._file.write(struct.pack("<II", self._crc, self._size & 0xFFFFFFFF))
        self._file.flush()
        os.fsync(self._file.fileno())
        self._file.close()
        _put_in_place(self._tmp, self.target)
        return self.target

    def discard(self) -> None:
        """Close and remove what was written, unless :meth:`finish` put it in place."""
        self._file.close()
        self._tmp.unlink(missing_ok=True)


def write_text_atomic(target: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``target`` atomically and return the target path; gzipped if
    ``target`` ends in :data:`GZIP_SUFFIX` (:class:`AtomicGzip`), with no name or time in the
    header, so that the same text gives the same bytes every time (committed results stay
    unchanged)."""
    if Path(target).suffix == GZIP_SUFFIX:
        gz = AtomicGzip(target)
        try:
            gz.write(text)
            return gz.finish()
        finally:
            gz.discard()
    with atomic_path(target) as tmp:
        tmp.write_bytes(text.encode("utf-8"))
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
