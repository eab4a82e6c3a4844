"""The package-level public API: :mod:`heelstrike.analysis` and :mod:`heelstrike.plots`
re-export their submodules' public names lazily (issue 9, item 5)."""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys

import pytest

import heelstrike.analysis
import heelstrike.plots

HEAVY = ("scipy.integrate", "numba", "matplotlib")


def _submodules(package: object) -> list[str]:
    path = package.__path__  # type: ignore[attr-defined]
    return [m.name for m in pkgutil.iter_modules(path) if not m.name.startswith("_")]


@pytest.mark.parametrize("name", heelstrike.analysis.__all__)
def test_every_analysis_name_resolves_to_its_definition(name: str) -> None:
    value = getattr(heelstrike.analysis, name)
    owners = [
        m
        for m in _submodules(heelstrike.analysis)
        if name in getattr(importlib.import_module(f"heelstrike.analysis.{m}"), "__all__", ())
    ]
    assert len(owners) == 1, owners
    assert value is getattr(importlib.import_module(f"heelstrike.analysis.{owners[0]}"), name)


def test_analysis_all_is_a_short_list_of_its_submodules_public_names() -> None:
    """Issue #32, item 6: the package exports at most 40 names, entry points, results and
    errors, no tuning constants; each is public in its submodule, and every other public name
    of a submodule is importable there only."""
    union: set[str] = set()
    for m in _submodules(heelstrike.analysis):
        union |= set(importlib.import_module(f"heelstrike.analysis.{m}").__all__)
    # a function named like its submodule (gait_map, sweep, cost_study) stays the submodule
    union -= set(_submodules(heelstrike.analysis))
    names = heelstrike.analysis.__all__
    assert {"find_limit_cycle", "heel_strike_study", "find_powered_gait"} <= set(names)
    assert set(names) <= union
    assert len(names) == len(set(names)) <= 40
    constants = [n for n in names if n.isupper()]  # ALL_CAPS: a constant
    assert constants == []
    for name in sorted(union - set(names)):  # e.g. OUTCOMES, BYTES_PER_POINT, hanging_links
        with pytest.raises(AttributeError, match=name):
            getattr(heelstrike.analysis, name)
    assert {"OUTCOMES", "BYTES_PER_POINT", "ENERGY_BOOKS_RTOL"} <= union - set(names)


@pytest.mark.parametrize("name", ["gait_map", "sweep", "cost_study"])
def test_names_shared_with_a_submodule_stay_the_submodule(name: str) -> None:
    module = importlib.import_module(f"heelstrike.analysis.{name}")
    assert getattr(heelstrike.analysis, name) is module
    assert callable(getattr(module, name))
    assert name not in heelstrike.analysis.__all__


def test_unknown_names_raise_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no_such_function"):
        _ = heelstrike.analysis.no_such_function  # type: ignore[attr-defined]
    with pytest.raises(AttributeError, match="no_such_figure"):
        _ = heelstrike.plots.no_such_figure  # type: ignore[attr-defined]


def test_plots_reexports_the_paper_figures() -> None:
    from heelstrike.plots import figure3b, paper

    assert figure3b is paper.figure3b
    for name in heelstrike.plots.__all__:
        assert getattr(heelstrike.plots, name) is getattr(paper, name)
    assert set(heelstrike.plots.__all__) == set(paper.__all__)


def test_importing_the_packages_is_cheap() -> None:
    code = (
        "import sys, heelstrike.analysis, heelstrike.plots; "
        f"print([m for m in {HEAVY!r} if m in sys.modules])"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "[]"
