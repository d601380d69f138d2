"""Files written whole or not at all (sse_cosim/files.py) get the mode a plain ``open`` gives,
0666 less the umask, not the 0600 of the temporary file they are written to (issue: reports
that answer the user's question: every output was 0600 whatever the umask)."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

from sse_cosim.files import write_text_atomic


@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o002, 0o664), (0o077, 0o600)])
def test_a_written_file_has_the_mode_the_umask_gives(tmp_path: Path, umask: int,
                                                     mode: int) -> None:
    before = os.umask(umask)
    try:
        path = write_text_atomic(tmp_path / "out" / "summary.json", "{}\n")
    finally:
        os.umask(before)
    assert stat.S_IMODE(path.stat().st_mode) == mode
    assert [p.name for p in path.parent.iterdir()] == ["summary.json"]  # no .part left
