"""Every install command the project prints or documents works from a clone (issue 35, item 5).

heelstrike is not on a package index: ``pip install 'heelstrike[scale]'`` finds nothing (or
someone else's package). Hints must say ``pip install '.[EXTRA]'`` (run in the clone), and
EXTRA must be an extra that ``pyproject.toml`` defines.
"""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

from heelstrike._optional import MissingExtraError, install_hint, require

ROOT = Path(__file__).resolve().parents[1]
EXTRAS = set(tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
             ["project"]["optional-dependencies"])
# the installs a reader or a user of the messages is told to run
INSTALL = re.compile(r"pip install\s+(['\"]?)([^\s'\"`)]+)\1")


def _texts() -> list[Path]:
    files = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.rst"))]
    for folder in ("src", "examples", "benchmarks"):
        files += sorted((ROOT / folder).rglob("*.py"))
    files += sorted((ROOT / "benchmarks").glob("*.md"))
    return [f for f in files if "_build" not in f.parts]


def _bad_installs(text: str) -> list[str]:
    """Installs of heelstrike by name, or of the clone with an extra it does not define.

    Other packages (``pip install drake``, a peer in the benchmarks) are not heelstrike's to
    judge; ``<extra>`` and ``{extra}`` are the placeholders of the message helpers.
    """
    bad = []
    for m in INSTALL.finditer(text):
        target = m.group(2)
        if target.startswith("heelstrike"):
            bad.append(m.group(0))
            continue
        extras = re.fullmatch(r"\.\[([^\]]*)\]", target)
        if extras is None or extras.group(1) in ("<extra>", "{extra}"):
            continue
        if not set(extras.group(1).split(",")) <= EXTRAS:
            bad.append(m.group(0))
    return bad


def test_every_install_command_is_one_that_works_from_a_clone() -> None:
    files = _texts()
    assert len(files) > 50
    found = {}
    for f in files:
        bad = _bad_installs(f.read_text(encoding="utf-8"))
        if bad:
            found[str(f.relative_to(ROOT))] = bad
    assert not found, found


def test_the_checker_catches_an_index_install() -> None:
    assert _bad_installs("needs it: pip install 'heelstrike[scale]'") == [
        "pip install 'heelstrike[scale]'"]
    assert _bad_installs("pip install '.[no_such_extra]'") == ["pip install '.[no_such_extra]'"]
    assert _bad_installs("pip install '.[dev,robots,docs]' and pip install .") == []


def test_missing_extra_error_names_the_clone_install() -> None:
    assert "scale" in EXTRAS and "robots" in EXTRAS
    with pytest.raises(MissingExtraError) as info:
        require("heelstrike_no_such_module", "a sweep store", "robots")
    assert str(info.value) == (
        "a sweep store needs the 'robots' extra: pip install '.[robots]' in a clone of heelstrike")
    assert install_hint("scale") == "pip install '.[scale]' in a clone of heelstrike"
