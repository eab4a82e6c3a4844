"""The default target of ``heelstrike powered`` is declared by the walker (issue 9).

"The CLI holds no defaults copied from the models": without ``--speed`` or ``--step-length``
the command seeks the speed the walker declares, :attr:`PlanarWalker.powered_speed`: a walker
file's ``[powered] speed`` (m/s) or the compass gait's own 0.5 m/s. The former fixed 0.5 m/s lay
outside the torso walker's push-off gaits (a fold at 0.4902 m/s) and the kneed walker's
(level gaits only at about 1.22-1.41 m/s), so ``powered --model torso`` and ``--model kneed``
failed by default.

Checked here:

- the ``[powered]`` table's validation (a finite number > 0, unknown keys refused, errors name
  the field) and that it is not part of the derivation (same generated model with or without);
- the default commands for the torso and kneed walkers succeed at the declared speed with a
  periodic gait, verified on the scipy reference map at ``rtol = 1e-12`` independently of the
  search, and the energy book of the period closes: push-off work (+ posture-law work) = the
  impacts' ``T_c``. Tolerance 1e-8 J: the search stops at a section residual below 1e-8
  (rad, rad/s) and the energy per step changes by O(1 J) per unit of those, while the books of
  the gaits found close to about 5e-10 J;
- the compass gait's default is unchanged: 0.5 m/s with and without ``--model compass``;
- the output says which target was used (``target_speed``, ``target_step_length``,
  ``target_source`` in the JSON; a ``target`` line in the text).
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import heelstrike
from heelstrike.analysis.gaits import Gait
from heelstrike.analysis.limit_cycle import PoincareMap
from heelstrike.analysis.powered import (
    declared_posture_law,
    find_model_powered_gait,
)
from heelstrike.cli import main
from heelstrike.core.impact import kinetic_energy
from heelstrike.dynamics.actuation import PushOff, push_off_velocity_change
from heelstrike.dynamics.phased import PhasedWalker, PhasedWalkResult, simulate_phased
from heelstrike.models.builder import BuiltWalker, load_walker, walker_description
from heelstrike.models.compass import CompassGait
from heelstrike.models.description import (
    ModelDescriptionError,
    PoweredSpec,
    parse_description,
    read_description,
)

Capture = pytest.CaptureFixture[str]
WALKERS = Path(heelstrike.__file__).parent / "walkers"
#: Energy-book tolerance (J); see the module docstring.
BOOK_TOL = 1e-8


def _data(name: str) -> dict[str, Any]:
    with open(WALKERS / f"{name}.toml", "rb") as fh:
        return tomllib.load(fh)


def _text_without_powered(name: str) -> str:
    text = (WALKERS / f"{name}.toml").read_text(encoding="utf-8")
    head, sep, _ = text.partition("\n[powered]")
    assert sep, f"{name}.toml has no [powered] table"
    return head + "\n"


def _json(argv: list[str], capsys: Capture) -> dict[str, Any]:
    assert main(argv) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1  # exactly one JSON object on stdout
    return dict(json.loads(out[0]))


# -- the [powered] table ------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["compass", "torso", "kneed"])
def test_shipped_files_declare_a_target_speed(name: str) -> None:
    raw = _data(name)["powered"]["speed"]
    desc = walker_description(name)
    assert desc.powered == PoweredSpec(speed=float(raw))
    assert math.isfinite(raw) and raw > 0
    assert load_walker(name).powered_speed == float(raw)


def test_compass_declares_the_paper_walkers_default() -> None:
    # the hand-written compass gait and its walker file declare the same 0.5 m/s
    assert CompassGait().powered_speed == 0.5
    assert load_walker("compass").powered_speed == CompassGait().powered_speed
    assert CompassGait(foot_radius=0.3).replace(hip_mass=8.0).powered_speed == 0.5


@pytest.mark.parametrize(
    ("powered", "needle"),
    [
        ({"speed": 0.0}, "powered.speed: must be finite and > 0 (m/s), got 0"),
        ({"speed": -0.4}, "powered.speed: must be finite and > 0 (m/s), got -0.4"),
        ({"speed": math.nan}, "powered.speed: must be finite and > 0 (m/s), got nan"),
        ({"speed": math.inf}, "powered.speed: must be finite and > 0 (m/s), got inf"),
        ({"speed": "0.5"}, "powered.speed: must be a number (m/s), not str"),
        ({"speed": "l / 2"}, "powered.speed: must be a number (m/s), not str"),
        ({"speed": True}, "powered.speed: must be a number (m/s), not bool"),
        ({"speed": [0.5]}, "powered.speed: must be a number (m/s), not list"),
        ({}, "powered.speed: missing required field"),
        ({"speed": 0.5, "step_length": 0.3}, "powered.step_length: unknown key"),
        (0.5, "powered: must be a table"),
    ],
)
def test_bad_powered_table_names_the_field(powered: Any, needle: str) -> None:
    data = _data("compass")
    data["powered"] = powered
    with pytest.raises(ModelDescriptionError) as info:
        parse_description(data)
    assert str(info.value).startswith(needle)


def test_bad_speed_in_a_file_is_refused(tmp_path: Path) -> None:
    # through TOML itself (its nan/inf literals), as `--model FILE` reads it
    for literal, needle in (("nan", "got nan"), ("-inf", "got -inf"), ("0", "got 0"),
                            ('"fast"', "not str")):
        path = tmp_path / "bad.toml"
        path.write_text(_text_without_powered("compass") + f"[powered]\nspeed = {literal}\n",
                        encoding="utf-8")
        with pytest.raises(ModelDescriptionError, match=r"^powered\.speed: ") as info:
            read_description(path)
        assert needle in str(info.value)


def test_powered_table_is_optional_and_not_part_of_the_derivation() -> None:
    data = _data("compass")
    with_table = parse_description(data)
    data.pop("powered")
    without = parse_description(data)
    assert without.powered is None and with_table.powered == PoweredSpec(speed=0.5)
    # the generated model (and its caches) do not depend on the declared target
    assert without.structure_key() == with_table.structure_key()
    assert BuiltWalker(without).powered_speed is None


def test_cli_without_declared_target_asks_for_one(tmp_path: Path, capsys: Capture) -> None:
    path = tmp_path / "mine.toml"
    path.write_text(_text_without_powered("compass"), encoding="utf-8")
    assert main(["powered", "--model", str(path), "--json"]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("heelstrike: error:")
    assert "declares no target speed" in lines[0] and "[powered]" in lines[0]
    assert "--speed" in lines[0] and "--step-length" in lines[0]


def test_help_states_the_default(capsys: Capture) -> None:
    with pytest.raises(SystemExit):
        main(["powered", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "default: the walker's declared target speed, 0.5 m/s for the compass gait" in text


# -- the compass gait: default unchanged --------------------------------------------------------
def test_compass_default_is_half_a_metre_per_second(capsys: Capture) -> None:
    d = _json(["powered", "--json"], capsys)
    assert d["target_source"] == "walker"
    assert d["target_speed"] == 0.5 and d["target_step_length"] is None
    assert abs(d["speed"] - 0.5) < 1e-6
    # the same gait as the explicit former default
    e = _json(["powered", "--speed", "0.5", "--json"], capsys)
    assert e["target_source"] == "--speed" and e["target_speed"] == 0.5
    assert e["parameter"] == d["parameter"] and e["fixed_point"] == d["fixed_point"]
    assert set(d["units"]) == set(d) - {"units"}
    assert d["units"]["target_speed"] == "m/s" and d["units"]["target_step_length"] == "m"


def test_model_compass_default_and_no_declaration_agree(tmp_path: Path,
                                                        capsys: Capture) -> None:
    # --model compass seeks its file's 0.5 m/s; the same file without [powered] given
    # --speed 0.5 finds the same gait (the table changes the target only, not the walker)
    d = _json(["powered", "--model", "compass", "--json"], capsys)
    assert d["target_source"] == "walker" and d["target_speed"] == 0.5
    assert abs(d["speed"] - 0.5) < 1e-6
    path = tmp_path / "mine.toml"
    path.write_text(_text_without_powered("compass"), encoding="utf-8")
    e = _json(["powered", "--model", str(path), "--speed", "0.5", "--json"], capsys)
    assert e["target_source"] == "--speed"
    assert abs(e["parameter"] - d["parameter"]) < 1e-10
    assert abs(e["collision_loss"] - d["collision_loss"]) < 1e-10


def test_step_length_target_is_reported(capsys: Capture) -> None:
    d = _json(["powered", "--model", "compass", "--step-length", "0.35", "--json"], capsys)
    assert d["target_source"] == "--step-length"
    assert d["target_step_length"] == 0.35 and d["target_speed"] is None
    assert abs(d["step_length"] - 0.35) < 1e-6


# -- torso and kneed: the default command succeeds ----------------------------------------------
def _reference_walk(walker: PhasedWalker, fixed_point: np.ndarray,
                    impulse: float) -> PhasedWalkResult:
    """One period on the scipy reference (rtol = atol = 1e-12) with the declared posture law."""
    walk = simulate_phased(walker, *walker.section_to_state(fixed_point), slope=0.0, steps=1,
                           torque=declared_posture_law(walker),
                           push_off=PushOff(impulse=impulse), rtol=1e-12, atol=1e-12)
    assert isinstance(walk, PhasedWalkResult) and walk.ok
    return walk


@pytest.fixture(scope="module", params=["torso", "kneed"])
def declared(request: pytest.FixtureRequest) -> tuple[str, float, Gait]:
    """The walker, its declared speed and the library's gait there (no time limit: a cold
    compile happens here, not inside the command's time limit)."""
    name = str(request.param)
    w = load_walker(name)
    speed = w.powered_speed
    assert speed is not None
    return name, speed, find_model_powered_gait(w, speed=speed)


def test_default_command_finds_the_declared_gait(declared: tuple[str, float, Gait],
                                                 capsys: Capture) -> None:
    name, speed, gait = declared
    d = _json(["powered", "--model", name, "--json"], capsys)
    assert d["model"] == name and d["actuation"] == "pushoff"
    assert d["target_source"] == "walker"
    assert d["target_speed"] == speed and d["target_step_length"] is None
    assert abs(d["speed"] - speed) < 1e-6
    assert d["speed"] == pytest.approx(d["step_length"] / d["period"], rel=1e-12)
    assert abs(d["parameter"] - gait.actuation.parameter) < 1e-8  # the library's gait at that speed
    assert d["parameter"] > 0.0  # the push-off does positive work
    # the energy book of the periodic level gait: push-off + posture work = sum of T_c
    assert d["collision_loss"] > 1e-3
    assert abs(d["push_off_work"] + d["torque_work"] - d["collision_loss"]) < BOOK_TOL
    assert abs(d["energy_change"]) < BOOK_TOL and abs(d["energy_balance_error"]) < BOOK_TOL
    mods = np.asarray(d["multipliers"])
    assert np.all(np.isfinite(mods)) and d["stable"] == bool(mods[0] < 1.0)


def test_default_text_output_names_the_target(declared: tuple[str, float, Gait],
                                              capsys: Capture) -> None:
    name, speed, _ = declared
    assert main(["powered", "--model", name]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert f"  target          speed {speed:g} m/s (the walker's declared target)" in lines
    assert main(["powered", "--model", name, "--speed", f"{speed:g}"]) == 0
    assert f"  target          speed {speed:g} m/s (--speed)" in capsys.readouterr().out


def test_declared_gait_is_periodic_on_the_reference_map(
        declared: tuple[str, float, Gait]) -> None:
    name, speed, gait = declared
    pw = PhasedWalker.from_built(load_walker(name))
    walk = _reference_walk(pw, gait.fixed_point, gait.actuation.parameter)
    z_next = pw.state_to_section(walk.final_q, walk.final_q_dot)
    assert np.max(np.abs(z_next - gait.fixed_point)) < 1e-8
    rec = walk.impacts[0]
    assert abs(rec.step_length / rec.step_duration - speed) < 1e-8
    # every impact's T_c in the period, from the reference walk's own events, is the reported
    # collision loss
    lost = sum(e.kinetic_energy_constrained for e in walk.events)
    assert lost > 0.0 and abs(lost - gait.collision_loss) < BOOK_TOL
    # the same multipliers on the reference map
    P = PoincareMap(walker=pw, simulator=simulate_phased, torque=declared_posture_law(pw),
                    push_off=PushOff(impulse=gait.actuation.parameter), rtol=1e-12, atol=1e-12)
    mult = np.sort(np.abs(np.linalg.eigvals(P.jacobian(gait.fixed_point, 1e-5))))[::-1]
    assert np.allclose(mult, np.abs(gait.multipliers), atol=1e-3)


def test_kneed_default_energy_book_from_states() -> None:
    # the kneed walker declares no posture law: the push-off work, computed from kinetic
    # energies just before heel strike, equals the knee strike's plus the heel strike's T_c
    w = load_walker("kneed")
    speed = w.powered_speed
    assert speed is not None
    gait = find_model_powered_gait(w, speed=speed)
    pw = PhasedWalker.from_built(w)
    assert declared_posture_law(pw) is None
    walk = _reference_walk(pw, gait.fixed_point, gait.actuation.parameter)
    rec = walk.impacts[0]
    dq, _ = push_off_velocity_change(pw, rec.q, gait.actuation.parameter, walk.events[-1].lock_rows)
    M = pw.mass_matrix(rec.q)
    w_push = float(kinetic_energy(M, rec.q_dot_minus) - kinetic_energy(M, rec.q_dot_minus - dq))
    kinds = [e.kind for e in walk.events]
    assert kinds == ["knee_strike", "heel_strike"]
    lost = sum(e.kinetic_energy_constrained for e in walk.events)
    assert w_push > 0.0 and abs(w_push - lost) < BOOK_TOL
    assert abs(gait.actuation.push_off_work - w_push) < BOOK_TOL


@pytest.mark.slow
def test_scipy_backend_agrees_on_the_default(declared: tuple[str, float, Gait],
                                             capsys: Capture) -> None:
    name, speed, gait = declared
    # the search's wall-clock guard (DEFAULT_TIME_LIMIT, 45 s) depends on the machine's load:
    # this test is about the backends' agreement, so it gives the scipy search room
    d = _json(["powered", "--model", name, "--backend", "scipy", "--time-limit", "600",
               "--json"], capsys)
    assert d["target_source"] == "walker" and d["target_speed"] == speed
    assert abs(d["parameter"] - gait.actuation.parameter) < 1e-8
    fp = np.array(list(d["fixed_point"].values()))
    assert np.max(np.abs(fp - gait.fixed_point)) < 1e-8
    assert abs(d["collision_loss"] - gait.collision_loss) < 1e-8
