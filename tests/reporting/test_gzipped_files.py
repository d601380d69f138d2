"""Files named ``*.gz`` (the campaign's plan, the falsifier's ledger) are written gzipped,
the same bytes for the same text, and read back; a folder an older version wrote them plain
in is refused in one line (issue: reports that answer the user's question: committed results
under 10 MB)."""

from __future__ import annotations

import gzip
from pathlib import Path

import pytest

from sse_cosim.errors import UserError
from sse_cosim.files import read_plan, read_text, write_json_atomic, write_text_atomic
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
