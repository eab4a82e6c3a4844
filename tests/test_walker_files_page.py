"""The walker-file reference page (docs/walker_files.rst) cannot rot (issue 35, item 5).

Every ``.. code-block:: toml`` on the page is a complete walker file. One whose first line is
``# refused: MESSAGE`` must be refused by :func:`heelstrike.models.builder.load_walker` (which
reads, checks and builds) with a message starting with ``MESSAGE``;
every other one must be read by :func:`heelstrike.models.description.read_description` and
built by :func:`heelstrike.models.builder.load_walker` into a walker whose mass matrix is
symmetric positive definite. The page's tables must name every key the loader accepts.
"""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import numpy as np
import pytest

from heelstrike.models import description as desc_module
from heelstrike.models.builder import load_walker
from heelstrike.models.description import ModelDescriptionError, read_description

PAGE = Path(__file__).resolve().parents[1] / "docs" / "walker_files.rst"
REFUSED = "# refused: "


def _toml_blocks(text: str) -> list[str]:
    """The bodies of the page's ``.. code-block:: toml`` directives, dedented."""
    blocks = []
    lines = text.splitlines()
    for i, line in enumerate(lines):
        if line.strip() != ".. code-block:: toml":
            continue
        body: list[str] = []
        for nxt in lines[i + 1:]:
            if nxt.strip() and not nxt.startswith(" "):
                break
            body.append(nxt)
        blocks.append(textwrap.dedent("\n".join(body)).strip() + "\n")
    return blocks


BLOCKS = _toml_blocks(PAGE.read_text(encoding="utf-8"))
ACCEPTED = [b for b in BLOCKS if not b.startswith(REFUSED)]
REFUSED_BLOCKS = [b for b in BLOCKS if b.startswith(REFUSED)]


def test_page_has_examples_of_each_kind() -> None:
    assert len(ACCEPTED) >= 4
    assert len(REFUSED_BLOCKS) >= 4
    features = "\n".join(ACCEPTED)
    for key in ("lockable", "centre_offset", "com_offset", "[control.", "[powered]",
                "constraints", "[[point_mass]]", "inertia", "[events]", "heel_strike",
                "trailing_foot"):
        assert key in features, f"no example on the page uses {key}"


def test_block_extraction_sees_every_toml_block() -> None:
    text = PAGE.read_text(encoding="utf-8")
    assert len(BLOCKS) == text.count(".. code-block:: toml")
    assert all("[[link]]" in b for b in BLOCKS)


@pytest.mark.parametrize("block", ACCEPTED, ids=lambda b: re.findall(r'name = "(\w+)"', b)[0])
def test_page_example_reads_and_builds(block: str, tmp_path: Path) -> None:
    path = tmp_path / "walker.toml"
    path.write_text(block, encoding="utf-8")
    description = read_description(path)
    walker = load_walker(path)
    n = len(description.coordinate_names)
    mass = np.asarray(walker.mass_matrix(np.full(n, 0.1)))
    assert mass.shape == (n, n)
    np.testing.assert_allclose(mass, mass.T, atol=1e-12)
    assert np.linalg.eigvalsh(mass).min() > 0


@pytest.mark.parametrize("block", REFUSED_BLOCKS, ids=lambda b: b.splitlines()[0][11:40])
def test_page_refused_example_is_refused_as_it_says(block: str, tmp_path: Path) -> None:
    expected = block.splitlines()[0][len(REFUSED):].strip()
    path = tmp_path / "walker.toml"
    path.write_text(block, encoding="utf-8")
    with pytest.raises(ModelDescriptionError) as info:
        load_walker(path)  # reads the file (read_description), then builds the walker
    assert str(info.value).startswith(expected), (str(info.value), expected)


def test_page_documents_every_key_the_loader_accepts() -> None:
    text = PAGE.read_text(encoding="utf-8")
    sets = {
        "top": desc_module._TOP_KEYS, "link": desc_module._LINK_KEYS,
        "joint": desc_module._JOINT_KEYS, "foot": desc_module._FOOT_KEYS,
        "point_mass": desc_module._PM_KEYS, "control": desc_module._CONTROL_KEYS,
        "powered": desc_module._POWERED_KEYS, "events": desc_module._EVENTS_KEYS,
    }
    # a key is documented when it is the first cell of a table row: "   * - ``key``"
    documented = set(re.findall(r"^\s*\* - ``(\w+)``", text, flags=re.M))
    documented |= {k for row in re.findall(r"^\s*\* - ``(\w+)``, ``(\w+)``", text, flags=re.M)
                   for k in row}
    for where, keys in sets.items():
        missing = {k for k in keys if k not in documented and f"``[[{k}]]``" not in text
                   and f"``[{k}]``" not in text and f"``[{k}.<name>]``" not in text}
        assert not missing, f"{where} keys not in the page's tables: {sorted(missing)}"
