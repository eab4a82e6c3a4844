"""Process-pool workers of a sweep end when their parent is killed (issue 36)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.scale
pytest.importorskip("dask")

SCRIPT = textwrap.dedent("""
    import os, sys, time
    import numpy as np
    from heelstrike.analysis.sweep import sweep

    def slow(a):
        open(os.path.join(sys.argv[1], str(os.getpid())), "w").close()
        time.sleep(120)
        return {"y": a}

    if __name__ == "__main__":
        sweep(slow, {"a": np.arange(2.0)}, chunks=1, units={"a": "1", "y": "1"},
              scheduler="processes", num_workers=2, progress=False)
""")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    # a zombie (dead, not yet reaped by its new parent) counts as gone
    try:
        return Path(f"/proc/{pid}/stat").read_text().split(") ")[1][0] != "Z"
    except (OSError, IndexError):
        return True


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
def test_killing_the_parent_ends_its_workers(tmp_path):
    script = tmp_path / "run.py"
    script.write_text(SCRIPT)
    marks = tmp_path / "workers"
    marks.mkdir()
    parent = subprocess.Popen([sys.executable, str(script), str(marks)],
                              env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)},
                              start_new_session=True)
    workers: list[int] = []
    try:
        deadline = time.monotonic() + 240  # spawning and importing, on a loaded machine
        while len(workers) < 1 and time.monotonic() < deadline and parent.poll() is None:
            time.sleep(0.2)
            workers = [int(p.name) for p in marks.iterdir()]
        assert workers, "no worker started"
    finally:
        parent.send_signal(signal.SIGKILL)
        parent.wait(timeout=30)
    deadline = time.monotonic() + 60  # generous: the workers poll every 0.5 s
    while any(_alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = [pid for pid in workers if _alive(pid)]
    for pid in left:  # do not leave them behind whatever the outcome
        os.kill(pid, signal.SIGKILL)
    assert not left, f"workers {left} outlived their parent"
