"""Units of the keys of the CLI's ``--json`` objects (the ``units`` map every object carries).

Values follow UDUNITS spelling where it is plain (``"J"``, ``"J/m"``, ``"rad/s"``, ``"N s"``);
``"1"`` marks a dimensionless number (fractions, counts, multipliers, cost of transport) and
``None`` (JSON ``null``) a value that is not a quantity (flags, names, file paths, a residual
norm over mixed units). A key whose value is

- a list of quantities with one unit has that unit; a configuration or velocity vector
  (``q``, ``q_dot``, ``qdot_minus``, ``qdot_plus``: ``(x, y, angles...)``) and ``impulse`` have a
  list with one unit per entry;
- an object (``fixed_point``, ``fractions``) has an object of units for its keys;
- a list of objects (``impacts``, ``gaits``, ``other_gaits``, ``walks``, ``branch``) has the
  object of units of its entries' keys (``{}`` when it is empty).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["json_units"]

#: Units of scalar (or uniform-list) keys.
UNITS: dict[str, str | None] = {
    # energies (J), losses per metre (J/m)
    "T": "J", "T_c": "J", "T_a": "J", "T_plus": "J", "energy_lost": "J",
    "collision_loss": "J", "potential_energy_released": "J", "actuator_work": "J",
    "push_off_work": "J", "hip_work": "J", "torque_work": "J", "kinetic_energy_pre": "J",
    "kinetic_energy_admissible": "J", "kinetic_energy_constrained": "J", "energy_change": "J",
    "energy_balance_error": "J", "energy_residual": "J",
    "eta": "J/m", "work_per_metre": "J/m",
    # geometry, time, speed
    "step_length": "m", "radius": "m", "foot_radius": "m",
    "impact_angle": "rad", "slope": "rad", "period_doubling_slope": "rad",
    "period_doubling_slopes": "rad",
    "period": "s", "time": "s", "elapsed": "s",
    "speed": "m/s", "trailing_normal_velocity": "m/s", "trailing_foot_lift_velocity": "m/s",
    "target_speed": "m/s", "target_step_length": "m",
    # dimensionless numbers and counts
    "restitution": "1", "multipliers": "1", "multipliers_complex": "1",
    "cost_of_transport": "1", "spectral_radius": "1", "converging_fraction": "1",
    "stable_fraction": "1", "gait_found_fraction": "1", "grid": "1", "steps": "1",
    "gaits_found": "1", "period_steps": "1", "leg_crossings": "1",
    "iterations": "1",
    # torque-law gains (heelstrike.analysis.powered.GAIN_UNITS)
    "gain": "s/rad", "kp": "N m/rad", "kd": "N m s/rad", "max_torque": "N m", "angle": "rad",
    # not quantities
    "trailing_foot_lifts": None, "trailing_foot_held": None, "degenerate_wheel": None,
    "stable": None, "stability_undecided": None,
    "trailing_foot_grazes": None, "model": None, "torque_joint": None, "coordinates": None,
    "actuation": None, "target_source": None, "backend": None,
    "parameter_name": None, "parameter_unit": None, "kind": None, "figure": None,
    "data": None, "residual": None, "status": None, "message": None, "gait_found": None,
    "gait_stable": None, "note": None, "branch_data": None, "branch_stopped": None,
    "hanging_links": None, "settling": None, "per": None,
    # robots (heelstrike.cli.robot writes its own units maps with these)
    "loss_beyond_T_c": "J", "normal_impulse": "N s", "admissible": None, "frame": None,
    "joint": None, "unit": None,
    # a joint outside its limits: rad (m for a prismatic joint, its "unit" says which)
    "position": "rad", "lower": "rad", "upper": "rad",
}

#: Keys whose value is a list of objects: the object of units of their entries' keys, ``{}``
#: when the list is empty.
_OBJECT_LISTS = {"impacts", "gaits", "other_gaits", "walks", "branch"}

_POSITION = {"q"}
_VELOCITY = {"q_dot", "qdot_minus", "qdot_plus"}


def _vector(n: int, base: str, rest: str) -> list[str]:
    """``(x, y, angles...)``: the first two entries translational, the others rotational."""
    return [base if i < 2 else rest for i in range(n)]


def _impulse(obj: Mapping[str, Any], n: int) -> list[str]:
    """Ground impulses (N s) of the striking foot, joint-lock impulses (N m s), and the
    trailing foot's (N s) when it stays on the ground."""
    if "coordinates" not in obj:  # the compass gait: the striking foot's (x, y) only
        return ["N s"] * n
    trailing = 1 if obj.get("trailing_foot_held", False) else 0  # its normal impulse
    locks = n - 2 - trailing
    if locks < 0:  # not the layout of model_heel_strike: forces only
        return ["N s"] * n
    return ["N s"] * 2 + ["N m s"] * locks + ["N s"] * trailing


def _section(names: Mapping[str, Any]) -> dict[str, str]:
    return {k: ("rad/s" if k.endswith("_dot") else "rad") for k in names}


def json_units(obj: Mapping[str, Any]) -> dict[str, Any]:
    """The ``units`` map of a ``--json`` object: one entry per key whose units are known.

    Parameters
    ----------
    obj : mapping
        The JSON object (before ``units`` is added).

    Returns
    -------
    dict
        Key -> unit string, ``None``, list of units or nested map (see the module docstring).
    """
    units: dict[str, Any] = {}
    for key, value in obj.items():
        if key == "units":
            continue
        if key in _POSITION and isinstance(value, list):
            units[key] = _vector(len(value), "m", "rad")
        elif key in _VELOCITY and isinstance(value, list):
            units[key] = _vector(len(value), "m/s", "rad/s")
        elif key == "impulse" and isinstance(value, list):
            units[key] = _impulse(obj, len(value))
        elif key == "fixed_point" and isinstance(value, Mapping):
            units[key] = _section(value)
        elif key == "fractions" and isinstance(value, Mapping):
            units[key] = dict.fromkeys(value, "1")
        elif key == "lock_torque_range" and isinstance(value, Mapping):  # joint -> (min, max)
            units[key] = dict.fromkeys(value, "N m")
        elif key == "parameter" and isinstance(obj.get("parameter_unit"), str):
            units[key] = obj["parameter_unit"]
        elif key == "parameter_values":  # a swept walker parameter: its unit, if known
            units[key] = obj.get("parameter_unit")
        elif key in _OBJECT_LISTS and isinstance(value, list) and not value:
            units[key] = {}
        elif isinstance(value, list) and value and all(isinstance(v, Mapping) for v in value):
            merged: dict[str, Any] = {}
            for item in value:
                merged.update(json_units(item))
            units[key] = merged
        elif isinstance(value, Mapping):
            units[key] = json_units(value)
        elif key in UNITS:
            units[key] = UNITS[key]
    return units
