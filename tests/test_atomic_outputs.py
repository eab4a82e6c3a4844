"""Outputs are written whole or not at all, and an ``--out`` folder is one run's (issue 36)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from heelstrike.cli import main
from heelstrike.io import (
    CLAIM_FILE,
    DirectoryInUseError,
    atomic_path,
    claim_directory,
    save_figure,
    write_csv,
)


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if ".part" in p.name)


def test_a_failed_write_leaves_the_old_file_and_no_partial_one(tmp_path, monkeypatch):
    import pandas as pd

    target = tmp_path / "fig3b.csv"
    write_csv({"a": [1.0, 2.0, 3.0]}, target)
    before = target.read_bytes()

    def cut(self, path, *args, **kwargs):  # writes part of the rows, then dies
        Path(path).write_text("a\n1.0\n")
        raise RuntimeError("killed mid-write")

    monkeypatch.setattr(pd.DataFrame, "to_csv", cut)
    with pytest.raises(RuntimeError, match="mid-write"):
        write_csv({"a": list(range(1000))}, target)
    assert target.read_bytes() == before
    assert _leftovers(tmp_path) == []


def test_a_figure_is_saved_under_its_name_only_when_complete(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(1, 1))
    path = save_figure(fig, tmp_path / "basin.png", dpi=20)
    plt.close(fig)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert _leftovers(tmp_path) == []

    class Broken:
        def savefig(self, fname, **kwargs):
            Path(fname).write_bytes(b"\x89PNG half")
            raise OSError(28, "No space left on device")

    with pytest.raises(OSError):
        save_figure(Broken(), tmp_path / "basin.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert _leftovers(tmp_path) == []


def test_kill_9_mid_write_leaves_no_file_under_the_final_name(tmp_path):
    code = (
        "import sys, time\n"
        "from heelstrike.io import atomic_path\n"
        "with atomic_path(sys.argv[1]) as tmp:\n"
        "    fh = open(tmp, 'w'); fh.write('a\\n' * 1000); fh.flush()\n"
        "    print('writing', flush=True); time.sleep(60)\n"
    )
    target = tmp_path / "fig3b.csv"
    proc = subprocess.Popen([sys.executable, "-c", code, str(target)], stdout=subprocess.PIPE,
                            env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == b"writing"
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    assert not target.exists()


def test_a_second_claim_on_one_folder_is_refused_naming_it(tmp_path):
    code = (
        "import sys, time\n"
        "from heelstrike.io import claim_directory\n"
        "claim = claim_directory(sys.argv[1])\n"
        "print('claimed', flush=True); time.sleep(60)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", code, str(tmp_path)], stdout=subprocess.PIPE,
                            env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == b"claimed"
        with pytest.raises(DirectoryInUseError, match=str(proc.pid)):
            claim_directory(tmp_path)
        status = main(["basin", "--grid", "2x2", "--out", str(tmp_path)])
        assert status == 2
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    # the dead run's lock is taken over
    deadline = time.monotonic() + 30
    while True:
        try:
            claim = claim_directory(tmp_path)
            break
        except DirectoryInUseError:
            assert time.monotonic() < deadline
            time.sleep(0.1)
    assert (tmp_path / CLAIM_FILE).read_text().split()[0] == str(os.getpid())
    claim.release()
    assert not (tmp_path / CLAIM_FILE).exists()


def test_the_second_run_on_one_out_says_which_folder(tmp_path, capsys):
    claim = claim_directory(tmp_path / "out")  # this process holds the folder
    try:
        code = (
            "import sys\n"
            "from heelstrike.cli import main\n"
            "raise SystemExit(main(['basin', '--grid', '2x2', '--out', sys.argv[1]]))\n"
        )
        done = subprocess.run([sys.executable, "-c", code, str(tmp_path / "out")],
                              capture_output=True, text=True, timeout=120,
                              env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    finally:
        claim.release()
    assert done.returncode == 2
    assert "in use by another heelstrike run" in done.stderr
    assert str(tmp_path / "out") in done.stderr


def test_empty_out_and_store_are_refused_clearly(capsys):
    assert main(["basin", "--out", ""]) == 2
    assert "--out is empty" in capsys.readouterr().err
    assert main(["basin", "--store", "", "--out", "x"]) == 2
    assert "--store must name a directory" in capsys.readouterr().err


def test_atomic_path_keeps_the_suffix(tmp_path):
    with atomic_path(tmp_path / "a.nc") as tmp:
        assert tmp.suffix == ".nc" and tmp.parent == tmp_path
        tmp.write_bytes(b"x")
    assert (tmp_path / "a.nc").read_bytes() == b"x"
