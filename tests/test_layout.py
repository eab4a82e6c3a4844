"""The package layout holds (issue 9, item 5): ``plots/`` draws only, ``io`` alone writes data.

Checked on the source with :mod:`ast`, so a violation fails here whether or not any other test
runs the offending line.
"""

from __future__ import annotations

import ast
import dataclasses
import importlib
from pathlib import Path

import pytest

import heelstrike

PACKAGE = Path(heelstrike.__file__).resolve().parent
PLOTS = sorted((PACKAGE / "plots").glob("*.py"))

#: The analysis names ``plots/`` may import: result types (drawn, never computed) ...
RESULT_TYPES = frozenset({
    "Basin", "BifurcationDiagram", "Continuation", "DesignResult", "Figure3bData", "GaitMap",
    "ImpactMap", "PaperFigureData", "WalkResult",
})
#: ... and plain constants (names of outcomes, of the impact-angle axis).
CONSTANTS = frozenset({"ANGLE", "OUTCOMES"})
#: The :mod:`heelstrike.robots` names ``plots/`` may import: result types only.
ROBOT_RESULT_TYPES = frozenset({"ReplayResult", "RobotStudy"})

#: Attribute calls that write data files; only :mod:`heelstrike.io` may make them.
DATA_WRITERS = frozenset({"to_csv", "to_netcdf", "savetxt"})
#: Attribute calls that write any file; ``plots/`` makes none (animations save through
#: matplotlib's ``Animation.save``, to the path they are given).
FILE_WRITERS = DATA_WRITERS | {"savefig", "write_text", "write_bytes", "to_zarr"}


def _module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = rel.parts[:-1] if rel.name == "__init__" else rel.parts
    return ".".join(parts)


def _imports(path: Path) -> list[tuple[str, list[str]]]:
    """``(module, names)`` of every import in the file (relative imports resolved; a plain
    ``import a.b`` gives ``("a.b", [])``), including imports inside functions and
    ``TYPE_CHECKING`` blocks."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = ""
    if path.is_relative_to(PACKAGE):
        name = _module_name(path)
        package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found: list[tuple[str, list[str]]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(a.name, []) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            module = node.module or ""
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                module = ".".join([*base, module] if module else base)
            found.append((module, [a.name for a in node.names]))
    return found


def _attribute_calls(path: Path) -> list[tuple[str, int]]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return [
        (node.func.attr, node.lineno)
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
    ]


def test_plots_modules_are_found() -> None:
    names = {p.stem for p in PLOTS}
    assert {"__init__", "gait", "paper", "models", "powered", "robots"} <= names


@pytest.mark.parametrize("path", PLOTS, ids=lambda p: p.name)
def test_plots_import_neither_dynamics_nor_analysis_functions(path: Path) -> None:
    for module, names in _imports(path):
        assert not module.startswith("heelstrike.dynamics"), (path.name, module)
        assert module != "matplotlib.pyplot" and "pyplot" not in names, (path.name, module)
        if module == "heelstrike.analysis" or module.startswith("heelstrike.analysis."):
            assert names, f"{path.name}: 'import {module}' gives access to its functions"
            bad = set(names) - RESULT_TYPES - CONSTANTS
            assert not bad, f"{path.name} imports {sorted(bad)} from {module}"
        if module == "heelstrike.robots" or module.startswith("heelstrike.robots."):
            assert names, f"{path.name}: 'import {module}' gives access to its functions"
            bad = set(names) - ROBOT_RESULT_TYPES
            assert not bad, f"{path.name} imports {sorted(bad)} from {module}"


@pytest.mark.parametrize(
    "path",
    sorted(p for p in PACKAGE.rglob("*.py") if "plots" not in p.relative_to(PACKAGE).parts),
    ids=lambda p: str(p.relative_to(PACKAGE)),
)
def test_only_plots_draw(path: Path) -> None:
    """Figures are drawn in ``plots/`` alone: no other module imports matplotlib
    (:mod:`heelstrike.outputs` saves the figures it is given)."""
    for module, _ in _imports(path):
        assert module.split(".")[0] != "matplotlib", (str(path.relative_to(PACKAGE)), module)


def test_the_allowed_analysis_names_are_results_and_constants() -> None:
    """The allow-list itself: frozen dataclasses of results, and constants that compute
    nothing (the check above means something only if these hold)."""
    import pkgutil

    import heelstrike.analysis as analysis

    owners = [importlib.import_module(f"heelstrike.analysis.{m.name}")
              for m in pkgutil.iter_modules(analysis.__path__) if not m.name.startswith("_")]

    def value_of(name: str) -> object:
        (module,) = [m for m in owners if name in m.__all__]  # public in one submodule
        return getattr(module, name)

    for name in RESULT_TYPES:
        value = value_of(name)
        assert isinstance(value, type) and dataclasses.is_dataclass(value), name
        assert value.__dataclass_params__.frozen, name  # type: ignore[attr-defined]
    for name in CONSTANTS:
        assert not callable(value_of(name)), name


@pytest.mark.parametrize("path", PLOTS, ids=lambda p: p.name)
def test_plots_write_no_files(path: Path) -> None:
    calls = [(attr, line) for attr, line in _attribute_calls(path) if attr in FILE_WRITERS]
    assert calls == [], f"{path.name} writes files: {calls}"
    tree = ast.parse(path.read_text(encoding="utf-8"))
    opens = [n.lineno for n in ast.walk(tree) if isinstance(n, ast.Call)
             and isinstance(n.func, ast.Name) and n.func.id == "open"]
    assert opens == [], f"{path.name} opens files at lines {opens}"


def test_only_io_writes_csv_and_netcdf() -> None:
    writers: dict[str, list[str]] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = str(path.relative_to(PACKAGE))
        hits = [f"{attr}:{line}" for attr, line in _attribute_calls(path)
                if attr in DATA_WRITERS]
        hits += [f"import csv:{m}" for m, _ in _imports(path) if m == "csv"]
        if hits:
            writers[rel] = hits
    assert set(writers) == {"io.py"}, writers
    assert {h.split(":")[0] for h in writers["io.py"]} == {"to_csv", "to_netcdf"}


def test_the_checks_catch_a_violation(tmp_path: Path) -> None:
    """The ast checks see imports inside functions and attribute calls anywhere."""
    bad = tmp_path / "bad.py"
    bad.write_text(
        "def f(walk):\n"
        "    from heelstrike.dynamics.hybrid import ground_reaction\n"
        "    from heelstrike.analysis.limit_cycle import find_limit_cycle, Continuation\n"
        "    walk.table.to_csv('x.csv')\n"
    )
    imports = _imports(bad)
    assert ("heelstrike.dynamics.hybrid", ["ground_reaction"]) in imports
    names = dict(imports)["heelstrike.analysis.limit_cycle"]
    assert set(names) - RESULT_TYPES - CONSTANTS == {"find_limit_cycle"}
    assert ("to_csv", 4) in _attribute_calls(bad)


def test_outputs_names_replace_the_old_plot_writers() -> None:
    """Every writer that left ``plots/`` is in :mod:`heelstrike.outputs`, and gone from
    ``plots/`` (one owner)."""
    outputs = importlib.import_module("heelstrike.outputs")
    moved = {
        # the bifurcation writers that computed the diagram themselves are gone (issue 9: the
        # CLI computes, outputs writes): write_bifurcation_files is the one writer
        "gait": ("write_basin", "write_bifurcation_files", "write_gait_map",
                 "write_model_walk_figures", "write_walk_figures"),
        "models": ("write_impact_map",),
        "paper": ("reproduce_paper",),
        "powered": ("write_cost_figures",),
    }
    for module, names in moved.items():
        plots_module = importlib.import_module(f"heelstrike.plots.{module}")
        for name in names:
            assert name in outputs.__all__ and hasattr(outputs, name), name
            assert not hasattr(plots_module, name), (module, name)


@pytest.mark.parametrize(
    ("command", "option", "function", "parameter"),
    [
        ("bifurcation", "transient", "gait_map.compass_bifurcation", "transient"),
        ("bifurcation", "transient", "gait_map.model_bifurcation", "transient"),
        ("bifurcation", "transient", "limit_cycle.bifurcation_diagram", "transient"),
        ("bifurcation", "record", "gait_map.compass_bifurcation", "record"),
        ("bifurcation", "record", "gait_map.model_bifurcation", "record"),
        ("bifurcation", "record", "limit_cycle.bifurcation_diagram", "record"),
        ("basin", "steps", "basin.basin_of_attraction", "steps"),
        ("basin", "steps", "basin.model_basin_of_attraction", "steps"),
        ("basin", "tol", "basin.basin_of_attraction", "tol"),
        ("basin", "tol", "basin.model_basin_of_attraction", "tol"),
    ],
)
def test_cli_defaults_are_the_analysis_defaults(
    command: str, option: str, function: str, parameter: str
) -> None:
    """The CLI reads an analysis default (and its help text) from the analysis, not a copy."""
    import argparse
    import inspect

    from heelstrike.cli import build_parser

    module, name = function.split(".")
    fn = getattr(importlib.import_module(f"heelstrike.analysis.{module}"), name)
    expected = inspect.signature(fn).parameters[parameter].default
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    action = next(a for a in sub.choices[command]._actions if a.dest == option)
    assert action.default == expected
    assert action.help is not None and f"default {expected:g}" in action.help
