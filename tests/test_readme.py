"""The README works as written: each Python block runs alone (in a fresh namespace, with its own
imports) and prints what it claims, its ``my.toml`` example runs, its robot headline example is
admissible as printed, and its first lines give the commands and their times.

Claims: a ``print(...)`` line carries the expected output after ``# -> `` at the end of the
line, or on the comment line just below it (``# -> ...``). Every ``print`` in the README must
carry one, and prints exactly one line. A block whose first line is
``# readme-test: skip`` is not run (keep that rare: only for genuinely slow blocks).
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
SKIP = "# readme-test: skip"


def _blocks(lang: str) -> list[str]:
    text = README.read_text(encoding="utf-8")
    return re.findall(rf"^```{lang}\n(.*?)^```", text, flags=re.S | re.M)


def _claims(block: str) -> list[str]:
    """Expected output lines of the block's prints, in order."""
    lines = block.splitlines()
    claims = []
    for i, line in enumerate(lines):
        if not line.lstrip().startswith("print("):
            continue
        m = re.search(r"#.*?-> (.*)$", line)
        if m is None and i + 1 < len(lines):
            m = re.match(r"\s*# -> (.*)$", lines[i + 1])
        assert m is not None, f"README print without a '# -> output' claim: {line!r}"
        claims.append(m.group(1).rstrip())
    return claims


def test_readme_has_python_blocks_with_claims() -> None:
    blocks = _blocks("python")
    assert len(blocks) >= 4
    assert sum(len(_claims(b)) for b in blocks) >= 10


def _run_alone(block: str, name: str) -> list[str]:
    """Run ``block`` in a fresh namespace (as a reader pasting only it would); its printed lines."""
    namespace: dict[str, object] = {"__name__": "__readme__"}
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(block, name, "exec"), namespace)
    return [line.rstrip() for line in out.getvalue().splitlines()]


@pytest.mark.parametrize("k", range(len(_blocks("python"))))
def test_readme_python_block_runs_alone_and_prints_what_it_claims(k: int) -> None:
    block = _blocks("python")[k]
    if block.startswith(SKIP):
        pytest.skip("README block marked '# readme-test: skip'")
    printed = _run_alone(block, f"README.md python block {k + 1}")
    assert printed == _claims(block), f"README python block {k + 1}"


def test_a_block_that_leans_on_another_fails_alone() -> None:
    """The namespaces really are fresh: a block using a name another block imported fails."""
    _run_alone("import numpy as np\n", "first")
    with pytest.raises(NameError, match="np"):
        _run_alone("print(np.pi)  # -> 3.141592653589793\n", "second")


def test_claim_checker_catches_a_wrong_claim() -> None:
    block = "print(1 + 1)  # -> 3\n"
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(block, {})
    assert out.getvalue().splitlines() != _claims(block)


def test_readme_own_walker_example_runs(tmp_path: Path) -> None:
    """The ``my.toml`` block: copy a shipped walker, then use it (run in a fresh directory)."""
    blocks = [b for b in _blocks("console") if "my.toml" in b and "> my.toml" in b]
    assert len(blocks) == 1
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    outputs = []
    for line in blocks[0].strip().splitlines():
        cmd = line.split("  #")[0].strip()
        if cmd.split()[0] == "python":  # the interpreter running the tests
            cmd = shlex.quote(sys.executable) + cmd[len("python"):]
        res = subprocess.run(cmd, shell=True, cwd=tmp_path, env=env, capture_output=True,
                             text=True, timeout=300)
        assert res.returncode == 0, (cmd, res.stderr)
        outputs.append(res.stdout)
    copied = (tmp_path / "my.toml").read_text(encoding="utf-8")
    from importlib.resources import files

    shipped = files("heelstrike").joinpath("walkers/kneed.toml").read_text(encoding="utf-8")
    assert copied == shipped
    assert outputs[-1].startswith("heel strike of 'kneed'")
    energies = dict(re.findall(r"^\s+(T|T_c|T_a)\s+(\S+) J$", outputs[-1], flags=re.M))
    assert float(energies["T"]) == pytest.approx(
        float(energies["T_c"]) + float(energies["T_a"]), abs=2e-6)


def test_readme_first_lines_give_install_test_and_full_commands_with_times() -> None:
    first = _blocks("")[0]
    lines = [ln for ln in first.splitlines() if ln.strip()]
    assert lines[0].startswith("pip install . && heelstrike reproduce --out figures")
    assert lines[1].startswith("pip install '.[test]' && pytest")
    assert any("pytest --runslow" in ln for ln in lines[2:])
    for line in lines[:3]:
        assert re.search(r"\d+\s*(s|min)\b", line), f"no time given: {line!r}"
    ci = (README.parent / ".ci" / "run").read_text(encoding="utf-8")
    assert re.search(r"^pytest --runslow\b", ci, flags=re.M)


def test_readme_robot_headline_example_is_admissible_as_printed(tmp_path: Path) -> None:
    """The robot block (``robot state`` then ``impact --robot ... --json``) runs, its impact is
    admissible, and the numbers the text gives after it are the ones printed."""
    if importlib.util.find_spec("pinocchio") is None and not os.environ.get("CI"):
        pytest.skip("needs the robots extra: pip install '.[robots]'")
    blocks = [b for b in _blocks("console") if "impact --robot" in b and "robot state" in b]
    assert len(blocks) == 1
    lines = [ln.split("  #")[0].strip() for ln in blocks[0].strip().splitlines()]
    commands = [ln for ln in lines if ln.startswith("heelstrike ")]
    assert [c.split()[1] for c in commands] == ["robot", "robot", "impact"]
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    res = None
    for cmd in commands:
        res = subprocess.run(shlex.split(cmd), cwd=tmp_path, env=env, capture_output=True,
                             text=True, timeout=300)
        assert res.returncode == 0, (cmd, res.stderr)
    assert res is not None
    out = json.loads(res.stdout)
    assert out["admissible"] is True and out["pulling_contacts"] == [], out["pulling_contacts"]
    assert "not admissible" not in res.stderr, res.stderr
    kept = [c for c in out["contacts"] if c["role"] == "keep"]
    assert len(kept) == 1 and kept[0]["force_impulse"][2] > 0
    assert all(c["mode"] == "stick" for c in out["contacts"])
    text = README.read_text(encoding="utf-8")
    after = text[text.index(blocks[0]) + len(blocks[0]):]
    assert '"admissible": true' in after
    assert f"normal impulse is +{kept[0]['force_impulse'][2]:.3f} N s" in after
    assert f"`T` = {out['T']:.4f} J" in after and f"`T_c` = {out['T_c']:.4f} J" in after
