"""Studies built on the walker models: heel strikes, gaits, their stability and their cost.

The public analysis API, importable from here (``from heelstrike.analysis import
find_limit_cycle``); each name is loaded from its submodule on first use, so
``import heelstrike.analysis`` stays cheap (no scipy, numba or matplotlib).

Main entry points:

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
- :func:`~heelstrike.analysis.newton.newton_solve`: the one Newton engine every gait search
  runs (batched starts, per-start :class:`~heelstrike.analysis.newton.NewtonStatus`).
- :func:`~heelstrike.analysis.walk_tables.walk_energy_table` and the other tables of
  :mod:`~heelstrike.analysis.walk_tables`: a simulated walk as DataFrames (what the walk's
  figures draw).

``gait_map``, ``sweep`` and ``cost_study`` name both a submodule and its main function; here
they stay the submodules (``from heelstrike.analysis import sweep`` gives the module, as it
always has): call ``heelstrike.analysis.sweep.sweep`` and so on.
"""

from __future__ import annotations

import importlib
from typing import Any

#: Public names of each submodule (its ``__all__``, less the name of the submodule itself).
_PUBLIC: dict[str, tuple[str, ...]] = {
    "basin": (
        "BYTES_PER_POINT", "OUTCOMES", "Basin", "available_memory", "basin_memory_estimate",
        "basin_of_attraction", "default_ranges", "model_basin_of_attraction", "model_slice_axes",
    ),
    "cost_study": (
        "BRANCH_NOTE", "GAIT_VARIABLES", "STUDY_BYTES_PER_POINT", "cheapest_gaits",
        "check_study_memory", "paper_eta",
    ),
    "design": (
        "DESIGN_FIELDS", "DESIGN_TOL", "DesignError", "DesignIterate", "DesignResult",
        "DesignStatus", "foot_outline",
    ),
    "gait_map": (
        "GaitMap", "NewtonGait", "compass_bifurcation", "model_bifurcation", "model_gait_map",
        "newton_gait", "newton_gaits",
    ),
    "heel_strike": (
        "CONTACT_TOLERANCE", "LIFT_TOLERANCE", "HeelStrikeStudy", "NotAHeelStrikeError",
        "check_heel_strike_state", "check_stance_foot_rolls",
        "check_striking_foot_approaches", "heel_strike_study", "loss_per_metre",
        "step_length", "symmetric_step_length", "trailing_foot_lifts",
    ),
    "limit_cycle": (
        "ENERGY_BOOKS_RTOL",
        "BifurcationDiagram", "Continuation", "GaitNotFoundError", "LimitCycle", "PoincareMap",
        "bifurcation_diagram", "continue_limit_cycle", "find_limit_cycle", "find_limit_cycles",
        "leg_crossings", "refine_period_doubling",
    ),
    "model_gaits": (
        "ANGLE", "IMPACT_MAP_BYTES_PER_POINT", "IMPACT_MAP_SECONDS_PER_POINT", "ImpactMap",
        "LOCK_TORQUE_SAMPLES", "TWO_SIDED_FLOOR",
        "check_impact_map_memory",
        "ModelGait", "ModelHeelStrike", "REFERENCE_SLOPE", "find_model_gait",
        "find_model_gaits", "hanging_links", "impact_map", "lock_torque_ranges",
        "model_heel_strike",
        "symmetric_heel_strike_state", "two_sided_locks", "upright_links",
    ),
    "newton": ("NewtonSolution", "NewtonStatus", "SearchTimeLimitWarning", "floquet_multipliers",
               "newton_solve"),
    "paper": (
        "FIGURE_RADII", "MAX_IMPACT_ANGLE", "Figure3bData", "PaperFigureData", "figure2_data",
        "figure3a_data", "figure3b_data", "heel_strike_table", "impact_angle_grid",
        "paper_figure_data",
    ),
    "powered": (
        "ACTUATIONS", "WHEEL_FAMILY", "ActuationFamily", "PoweredGait", "PoweredGaitNotFoundError",
        "SearchLimitError", "actuation_family", "books_gap", "check_model_actuation",
        "declared_posture_law",
        "energy_book_tables", "family_simulator",
        "find_model_powered_gait", "find_powered_gait", "impact_angle_for_step_length",
        "law_gains", "max_walking_speed", "powered_gaits",
        "passive_gait_finder", "powered_step", "preferred_gait",
    ),
    "design_gradients": (
        "GRADIENT_FIELDS", "GRADIENT_UNITS", "STENCIL_STEP", "GaitGradients", "GradientError",
        "step_fields", "gait_gradients",
    ),
    "sensitivity": ("GAIT_QUANTITY_UNITS", "GaitSensitivity", "gait_sensitivity"),
    "sweep": (
        "KNOWN_UNITS", "SweepError", "SweepFunction", "SweepStoreLockedError",
        "SweepStoreMismatchError", "SweepStoreRepairWarning", "sweep_progress",
    ),
    "walk_tables": (
        "WalkResult", "model_phase_portrait_table", "model_strobe_table", "model_walk_frames",
        "phase_portrait_table", "resample_walk", "step_table", "strobe_table",
        "walk_energy_table", "walk_frames", "walk_impact_table",
    ),
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
