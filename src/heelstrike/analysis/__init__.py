"""Studies built on the walker models: heel strikes, gaits, their stability and their cost.

The public analysis API, importable from here (``from heelstrike.analysis import
find_limit_cycle``); each name is loaded from its submodule on first use, so
``import heelstrike.analysis`` stays cheap (no scipy, numba or matplotlib).

Main entry points:

- :func:`~heelstrike.analysis.gaits.find_gaits`: every gait of a walker, passive on a slope or
  powered by an actuation family at a target speed or step length, as one result type
  (:class:`~heelstrike.analysis.gaits.Gait`), the cheapest stable gait first;
- :func:`~heelstrike.analysis.heel_strike.heel_strike_study`: energy split ``T_c`` / ``T_a``
  at heel strike over impact angles and foot radii;
- :func:`~heelstrike.analysis.limit_cycle.find_limit_cycle`,
  :func:`~heelstrike.analysis.limit_cycle.find_limit_cycles`: passive limit cycles on a slope
  and their Floquet multipliers;
- :func:`~heelstrike.analysis.limit_cycle.continue_limit_cycle`,
  :func:`~heelstrike.analysis.limit_cycle.bifurcation_diagram`: continuation in a parameter,
  period doubling;
- :func:`~heelstrike.analysis.basin.basin_of_attraction`,
  :func:`~heelstrike.analysis.gait_map.gait_map`: basins of attraction and gait maps;
- :func:`~heelstrike.analysis.powered.find_powered_gait`,
  :func:`~heelstrike.analysis.cost_study.cost_study`: powered gaits and the cost of transport;
- :func:`~heelstrike.analysis.model_gaits.find_model_gaits`,
  :func:`~heelstrike.analysis.model_gaits.find_model_gait`,
  :func:`~heelstrike.analysis.model_gaits.impact_map`: gaits and impact maps of described
  walkers;
- :func:`~heelstrike.analysis.sweep.sweep`: parameter sweeps with a resumable store;
- :func:`~heelstrike.analysis.sensitivity.gait_sensitivity` and
  :func:`~heelstrike.analysis.design.design`: a gait's parameter sensitivities (exact step
  Jacobians through the impacts) and gradient-based design;
- :func:`~heelstrike.analysis.newton.newton_solve`: the one Newton engine every gait search
  runs (batched starts, per-start :class:`~heelstrike.status.SolveStatus`);
- :func:`~heelstrike.analysis.walk_tables.walk_energy_table` and the other tables of
  :mod:`~heelstrike.analysis.walk_tables`: a simulated walk as DataFrames (what the walk's
  figures draw).

Only these entry points, their result types and errors are importable from here (at most 40
names); tuning constants and helpers are imported from their submodules
(``from heelstrike.analysis.basin import OUTCOMES``).

``gait_map``, ``sweep``, ``cost_study`` and ``design`` name both a submodule and its main
function; here they stay the submodules (``from heelstrike.analysis import sweep`` gives the
module, as it always has): call ``heelstrike.analysis.sweep.sweep``,
``heelstrike.analysis.design.design`` and so on.
"""

from __future__ import annotations

import importlib
from typing import Any

#: The package-level API: each submodule's main entry points, result types and errors (at most
#: 40 names, no tuning constants). Every other public name (constants, helpers) is imported from
#: its submodule: ``from heelstrike.analysis.basin import OUTCOMES``.
_PUBLIC: dict[str, tuple[str, ...]] = {
    "basin": ("Basin", "basin_of_attraction", "model_basin_of_attraction"),
    "cost_study": ("cheapest_gaits",),
    "design": ("DesignResult",),  # the function is heelstrike.analysis.design.design
    "gaits": ("Actuation", "Gait", "find_gaits"),
    "gait_map": ("GaitMap", "compass_bifurcation", "model_bifurcation", "model_gait_map"),
    "heel_strike": ("HeelStrikeStudy", "heel_strike_study"),
    "limit_cycle": (
        "BifurcationDiagram", "Continuation", "GaitNotFoundError", "PoincareMap",
        "bifurcation_diagram", "continue_limit_cycle", "find_limit_cycle",
    ),
    "model_gaits": (
        "ImpactMap", "ModelHeelStrike", "impact_map", "model_heel_strike",
    ),
    "newton": ("NewtonSolution", "newton_solve"),
    "paper": ("PaperFigureData", "paper_figure_data"),
    "powered": (
        "PoweredGaitNotFoundError", "find_model_powered_gait",
        "find_powered_gait", "max_walking_speed",
    ),
    "sensitivity": ("GaitSensitivity", "gait_sensitivity"),
    "walk_tables": ("WalkResult", "walk_energy_table"),
}
_SUBMODULE = {name: module for module, names in _PUBLIC.items() for name in names}

__all__ = sorted(_SUBMODULE)


def __getattr__(name: str) -> Any:
    module = _SUBMODULE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
