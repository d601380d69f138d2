"""Files named ``*.gz`` (the campaign's plan, the falsifier's ledger) are written gzipped,
the same bytes for the same text, and read back; a folder an older version wrote them plain
in is refused in one line (issue: reports that answer the user's question: committed results
under 10 MB)."""

from __future__ import annotations

import gzip
from pathlib import Path

import pytest

from sse_cosim.errors import UserError
from sse_cosim.files import (
    AtomicGzip,
    read_plan,
    read_text,
    write_json_atomic,
    write_text_atomic,
)
from sse_cosim.reporting.falsify_report import EVALUATIONS
from sse_cosim.reporting.safety_report import SAFETY_PLAN


def test_a_gz_file_is_gzipped_the_same_bytes_every_time_and_reads_back(tmp_path: Path):
    text = "method,margin\n" + "cma,1.25\n" * 500
    first = write_text_atomic(tmp_path / "a" / EVALUATIONS, text).read_bytes()
    second = write_text_atomic(tmp_path / "b" / EVALUATIONS, text).read_bytes()
    assert first == second  # no name or time in the header
    assert gzip.decompress(first).decode() == text and len(first) < len(text) // 10
    assert read_text(tmp_path / "a" / EVALUATIONS) == text
    plain = write_text_atomic(tmp_path / "plain.csv", text)
    assert plain.read_text() == text == read_text(plain)


def test_a_gz_file_written_in_pieces_is_the_file_written_whole(tmp_path: Path):
    """A file written piece by piece (a run's regions, step by step) has the bytes of the whole
    text written at once, which are gzip's own (time 0, level 9); it is in place only once
    finished, and a discarded one leaves nothing."""
    pieces = [f'{{"t":{k / 10},"polygons":[[[{k},0],[1,{k}]]]}}\n' * (k % 7) for k in range(3000)]
    text = "".join(pieces)
    whole = write_text_atomic(tmp_path / "whole.jsonl.gz", text).read_bytes()
    assert whole == gzip.compress(text.encode(), compresslevel=9, mtime=0)
    streamed = AtomicGzip(tmp_path / "streamed.jsonl.gz")
    for piece in pieces:
        streamed.write(piece)
    assert not (tmp_path / "streamed.jsonl.gz").exists()
    assert streamed.finish().read_bytes() == whole
    streamed.discard()  # after finish: nothing to remove
    assert (tmp_path / "streamed.jsonl.gz").read_bytes() == whole
    dropped = AtomicGzip(tmp_path / "dropped" / "r.jsonl.gz")
    dropped.write(text)
    dropped.discard()
    assert list((tmp_path / "dropped").iterdir()) == []


@pytest.mark.parametrize("level", [1, 6])
def test_a_gz_file_at_another_level_is_gzip_s_own_at_that_level(tmp_path: Path, level: int):
    """A file written faster (a run's regions, at level 1) has gzip's own bytes at its level,
    header flag included."""
    text = "".join(f'{{"t":{k / 10},"polygons":[[[{k},0],[1,{k}]]]}}\n' for k in range(3000))
    written = AtomicGzip(tmp_path / "r.jsonl.gz", level)
    for start in range(0, len(text), 777):
        written.write(text[start:start + 777])
    assert written.finish().read_bytes() == gzip.compress(text.encode(), level, mtime=0)


def test_a_plan_reads_back_and_an_older_plain_one_is_refused_in_one_line(tmp_path: Path):
    write_json_atomic(tmp_path / "new" / SAFETY_PLAN, {"runs": [1, 2]})
    assert read_plan(tmp_path / "new" / SAFETY_PLAN, "sse-cosim safety") == {"runs": [1, 2]}
    old = tmp_path / "old"
    old.mkdir()
    (old / "safety.json").write_text('{"runs": []}')
    with pytest.raises(UserError) as caught:
        read_plan(old / SAFETY_PLAN, "sse-cosim safety")
    line = str(caught.value)
    assert "\n" not in line and "older sse-cosim" in line and "gzip" in line
    assert str(old / "safety.json") in line
    (tmp_path / "broken.json.gz").write_bytes(b"not gzip")
    with pytest.raises(UserError, match="cannot be read"):
        read_plan(tmp_path / "broken.json.gz", "sse-cosim safety")
