"""Progress bars: shown on a terminal only, so nothing a command writes to a file or a pipe
depends on how fast the machine ran it (HEELSTRIKE_PROGRESS overrides)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from heelstrike._progress import progress_bar, progress_disabled


@pytest.mark.parametrize(("value", "expected"), [
    ("", None), ("1", False), ("always", False), ("yes", False), ("0", True), ("never", True),
    ("maybe", None),
])
def test_the_environment_variable_decides(monkeypatch: pytest.MonkeyPatch, value: str,
                                          expected: bool | None) -> None:
    monkeypatch.setenv("HEELSTRIKE_PROGRESS", value)
    assert progress_disabled() is expected


def test_a_captured_stream_gets_no_bar_however_slow_the_work(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("HEELSTRIKE_PROGRESS", raising=False)
    with progress_bar(total=3, desc="work", delay=0.0) as bar:  # as if the work took forever
        for _ in range(3):
            bar.update(1)
    assert capsys.readouterr().err == ""
    monkeypatch.setenv("HEELSTRIKE_PROGRESS", "1")
    with progress_bar(total=3, desc="work", delay=0.0, leave=True) as bar:
        for _ in range(3):
            bar.update(1)
    err = capsys.readouterr().err
    assert "work" in err and "3/3" in err
    with progress_bar(total=3, desc="work", delay=0.0, enabled=False) as bar:
        bar.update(3)
    assert capsys.readouterr().err == ""


def test_basin_counts_its_chunks_on_stderr(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    # issue 35: basin --grid 400x400 computed for 38 s with no progress; the bar is not
    # time-delayed (it prints when it opens and its count when it closes), shown here on a
    # captured stream as on a terminal
    from heelstrike.cli import main

    monkeypatch.setenv("HEELSTRIKE_PROGRESS", "1")
    assert main(["basin", "--grid", "3x4", "--steps", "2", "--out", str(tmp_path)]) == 0
    captured = capsys.readouterr()
    assert "basin of attraction" in captured.err
    # one chunk per q3 row here (3 rows): the bar ends at 3 of 3
    assert re.search(r"basin of attraction: 100%.*\b3/3\b", captured.err)
    assert not re.search(r"basin of attraction: +\d+%", captured.out)  # stdout: results only
