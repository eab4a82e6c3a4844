"""Long commands show progress on stderr whether or not it is a terminal (issue 35).

The bars asserted on here are not time-delayed: tqdm prints a bar when it opens and its final
count when it closes, however fast the machine is.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from heelstrike.cli import main


def test_basin_counts_its_chunks_on_stderr(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["basin", "--grid", "3x4", "--steps", "2", "--out", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    assert "basin of attraction" in captured.err
    # one chunk per q3 row here (3 rows): the bar ends at 3 of 3
    assert re.search(r"basin of attraction: 100%.*\b3/3\b", captured.err)
    assert not re.search(r"basin of attraction: +\d+%", captured.out)  # stdout: results only
