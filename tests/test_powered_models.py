"""Powered gaits of described walkers (``powered --model``): push-off plus a declared posture law.

Physics checked on the torso walker's periodic level gait (``walkers/torso.toml``, its
``[control.torso]`` PD law):

- energy book over one period (post-impact to post-impact, level ground): only the posture
  torque works in single support (the hip is passive), the push-off impulse adds
  ``W_push = T(q_dot-) - T(q_dot- - dq)`` just before heel strike and the heel strike removes
  ``T_c``, so ``W_posture + W_push - T_c = Delta(T + V) = 0`` on the periodic gait. Each term is
  computed independently of the simulator's integrated work (from states and energies);
- the compiled fixed point is a fixed point of the scipy reference map, at the target speed;
- the compass walker described by ``compass.toml`` gives the compass path's gait.
"""

from __future__ import annotations

import json
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
    find_powered_gait,
)
from heelstrike.cli import main
from heelstrike.core.impact import kinetic_energy
from heelstrike.dynamics.actuation import PushOff, mechanical_energy, push_off_velocity_change
from heelstrike.dynamics.phased import PhasedWalker, PhasedWalkResult, TorsoPD, simulate_phased
from heelstrike.models.builder import load_walker
from heelstrike.models.compass import CompassGait
from heelstrike.models.description import ModelDescriptionError, parse_description

WALKERS = Path(heelstrike.__file__).parent / "walkers"

SPEED = 0.4  # m/s: inside the range of the torso walker's push-off gaits (a fold at 0.4902)


@pytest.fixture(scope="module")
def torso_gait() -> Gait:
    return find_model_powered_gait(load_walker("torso"), speed=SPEED)


# -- the [control] table ------------------------------------------------------------------------
def _data(name: str) -> dict[str, Any]:
    with open(WALKERS / f"{name}.toml", "rb") as fh:
        return tomllib.load(fh)


def test_torso_file_declares_its_posture_law() -> None:
    w = load_walker("torso")
    law = declared_posture_law(w)
    assert isinstance(law, TorsoPD)
    spec = w.description.control[0]
    assert (spec.joint, law.kp, law.kd, law.angle) == (
        "torso", float(spec.kp), float(spec.kd), float(spec.angle))
    assert declared_posture_law(load_walker("compass")) is None


def test_control_values_are_expressions_and_not_in_structure_key() -> None:
    data = _data("torso")
    base = parse_description(data)
    data["control"]["torso"] = {"joint": "torso", "kp": "60 * mT", "kd": 12.0, "angle": "pi/40"}
    desc = parse_description(data)
    assert desc.structure_key() == base.structure_key()
    law = declared_posture_law(PhasedWalker(desc, mT=4.0))
    assert law.kd == 12.0 and law.kp == pytest.approx(240.0)
    assert law.angle == pytest.approx(np.pi / 40)


@pytest.mark.parametrize(
    ("law", "message"),
    [
        ({"joint": "torso", "kp": 1.0}, "control.torso.kd: missing required field"),
        ({"joint": "torso", "kp": 1.0, "kd": 1.0, "gain": 2.0}, "control.torso.gain: unknown key"),
        ({"joint": "knee", "kp": 1.0, "kd": 1.0}, "control.torso.joint: 'knee' is not an actua"),
        ({"joint": "torso", "kp": "-mT", "kd": 1.0}, "control.torso.kp: must be >= 0"),
        ({"joint": "torso", "kp": "zz", "kd": 1.0}, "control.torso.kp: unknown parameter 'zz'"),
        ({"joint": "torso", "kp": True, "kd": 1.0}, "control.torso.kp: must be a number"),
    ],
)
def test_control_errors_name_the_field(law: dict[str, Any], message: str) -> None:
    data = _data("torso")
    data["control"] = {"torso": law}
    with pytest.raises(ModelDescriptionError, match="^" + message.replace("(", r"\(")):
        parse_description(data)


def test_control_law_needs_an_actuated_joint_on_the_root() -> None:
    data = _data("kneed")
    desc = parse_description(data)
    off_root = [lk for lk in desc.links if lk.joint is not None and lk.parent != desc.root.name]
    assert off_root  # a shank hangs on a thigh, not on the root
    for lk in off_root:
        assert lk.joint is not None
        data["control"] = {"knee": {"joint": lk.joint.name, "kp": 1.0, "kd": 1.0}}
        with pytest.raises(ModelDescriptionError, match=r"^control\.knee\.joint: "):
            parse_description(data)


# -- the torso walker's powered gait --------------------------------------------------------------
def test_torso_energy_book_closes(torso_gait: Gait) -> None:
    g = torso_gait
    pw = PhasedWalker.from_built(load_walker("torso"))
    law = declared_posture_law(pw)
    walk = simulate_phased(pw, *pw.section_to_state(g.fixed_point), steps=1, torque=law,
                           push_off=PushOff(impulse=g.actuation.parameter), rtol=1e-12, atol=1e-12)
    assert isinstance(walk, PhasedWalkResult) and walk.ok
    rec = walk.impacts[0]
    q0, qd0 = pw.section_to_state(g.fixed_point)
    E_start = float(mechanical_energy(pw, q0, qd0))
    dq, _ = push_off_velocity_change(pw, rec.q, g.actuation.parameter)
    qd_before_push = rec.q_dot_minus - dq
    M = pw.mass_matrix(rec.q)
    # single support: only the posture torque works (hip passive)
    W_posture = float(mechanical_energy(pw, rec.q, qd_before_push)) - E_start
    W_push = float(kinetic_energy(M, rec.q_dot_minus) - kinetic_energy(M, qd_before_push))
    T_c = sum(e.kinetic_energy_constrained for e in walk.events)
    # inert heel strike: the kinetic energy lost is T_c
    assert float(kinetic_energy(M, rec.q_dot_minus) - kinetic_energy(M, rec.q_dot_plus)) == \
        pytest.approx(T_c, abs=1e-10)
    # the simulator's integrated books agree with the energies
    assert abs(rec.push_off_work - W_push) < 1e-10
    assert abs((rec.actuator_work - rec.push_off_work) - W_posture) < 1e-8
    # periodic level gait: total actuator work = collision losses
    assert abs(W_posture + W_push - T_c) < 1e-8
    # ... and the reported (compiled) books say the same
    assert abs(g.actuation.torque_work - W_posture) < 1e-8
    assert abs(g.actuation.push_off_work - W_push) < 1e-8
    assert abs(g.collision_loss - T_c) < 1e-8
    assert abs(g.energy_balance_error) < 1e-8
    assert g.actuation.torque_joint == "torso" and g.actuation.hip_work == 0.0
    # the law does work, so the book is not the push-off's alone
    assert g.actuation.torque_work != 0.0


def test_torso_compiled_fixed_point_is_scipy_fixed_point(torso_gait: Gait) -> None:
    g = torso_gait
    pw = PhasedWalker.from_built(load_walker("torso"))
    P = PoincareMap(walker=pw, simulator=simulate_phased, torque=declared_posture_law(pw),
                    push_off=PushOff(impulse=g.actuation.parameter), rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(P(g.fixed_point) - g.fixed_point)) < 1e-8
    rec = P.walk(g.fixed_point).impacts[0]
    assert abs(rec.step_length / rec.step_duration - SPEED) < 1e-6
    assert abs(g.speed - SPEED) < 1e-6
    # stability as reported: multipliers of the scipy map's Jacobian
    mult = np.sort(np.abs(np.linalg.eigvals(P.jacobian(g.fixed_point, 1e-5))))[::-1]
    assert np.allclose(mult[:3], np.abs(g.multipliers[:3]), atol=1e-3)
    assert g.stable == bool(np.all(mult < 1.0))


@pytest.mark.slow
def test_torso_scipy_backend_agrees(torso_gait: Gait) -> None:
    ref = find_model_powered_gait(load_walker("torso"), speed=SPEED, backend="scipy",
                                  guess=np.append(torso_gait.fixed_point,
                                                  torso_gait.actuation.parameter))
    assert abs(ref.actuation.parameter - torso_gait.actuation.parameter) < 1e-6
    assert np.max(np.abs(ref.fixed_point - torso_gait.fixed_point)) < 1e-7
    assert abs(ref.collision_loss - torso_gait.collision_loss) < 1e-8


@pytest.mark.slow
def test_model_compass_matches_compass_path() -> None:
    ref = find_powered_gait(CompassGait(), actuation="pushoff", speed=0.5)
    got = find_model_powered_gait(load_walker("compass"), speed=0.5)
    assert abs(got.speed - ref.speed) < 1e-6
    assert abs(got.actuation.parameter - ref.actuation.parameter) < 1e-6
    assert abs(got.collision_loss - ref.collision_loss) < 1e-6
    assert np.max(np.abs(got.fixed_point - ref.fixed_point)) < 1e-6
    assert got.actuation.torque_work == 0.0


def test_gait_needs_the_declared_law(torso_gait: Gait) -> None:
    # the same start and impulse without the posture law is not periodic: the law was used
    pw = PhasedWalker.from_built(load_walker("torso"))
    walk = simulate_phased(pw, *pw.section_to_state(torso_gait.fixed_point), steps=1,
                           push_off=PushOff(impulse=torso_gait.actuation.parameter))
    assert not walk.ok or np.max(np.abs(
        pw.state_to_section(walk.final_q, walk.final_q_dot) - torso_gait.fixed_point)) > 1e-3


# -- CLI -----------------------------------------------------------------------------------------
def test_cli_powered_model_torso_json(capsys: pytest.CaptureFixture[str],
                                      torso_gait: Gait) -> None:
    assert main(["powered", "--model", "torso", "--speed", str(SPEED), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["model"] == "torso" and d["hip_work"] == 0.0  # the torque acts on the torso
    assert abs(d["actuator_work"] - d["push_off_work"] - torso_gait.actuation.torque_work) < 1e-8
    assert set(d["units"]) == set(d) - {"units"}  # every key has its unit
    assert abs(d["speed"] - SPEED) < 1e-6
    assert abs(d["parameter"] - torso_gait.actuation.parameter) < 1e-8
    assert abs(d["actuator_work"] - d["collision_loss"]) < 1e-8
    assert tuple(d["fixed_point"]) == PhasedWalker.from_built(load_walker("torso")).section_names


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["powered", "--model", "torso", "--actuation", "hip-energy"],
         "the hip law hip-energy needs a walker whose one actuated joint is its hip"),
        (["powered", "--model", "torso", "--kp", "5"], "--kp not used by --actuation pushoff"),
        (["powered", "--actuation", "hip-energy", "--radius", "1", "--backend", "compiled"],
         "--backend compiled: the compiled backend runs a hip law"),
        (["powered", "--model", "torso", "--radius", "0.1", "--param", "R=0.1"],
         "--radius and --param R=... both set 'R'"),
        (["powered", "--model", "torso", "--param", "zz=1"], "zz"),
        (["study", "cost", "--model", "torso", "--actuation", "hip-pd"],
         "the hip law hip-pd needs a walker whose one actuated joint is its hip"),
        (["study", "cost", "--actuation", "pushoff", "--actuation", "hip-pd", "--radius",
          "0:1:2", "--backend", "compiled"], "(McGeer's wheel R = l, or a batch of walkers); "
         "use --backend scipy (the default there)"),
    ],
)
def test_cli_refusals_are_one_line(argv: list[str], needle: str,
                                   capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = [ln for ln in captured.err.splitlines() if ln.startswith("heelstrike: error:")]
    assert len(lines) == 1 and needle in lines[0]


def test_cli_powered_out_writes_the_energy_books(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str],
                                                  torso_gait: Gait) -> None:
    import pandas as pd

    assert main(["powered", "--model", "torso", "--speed", str(SPEED), "--out", str(tmp_path),
                 "--json"]) == 0
    captured = capsys.readouterr()
    json.loads(captured.out)  # one JSON object on stdout; the paths went to stderr
    assert str(tmp_path / "powered_energy.png") in captured.err
    assert (tmp_path / "powered_energy.png").stat().st_size > 0
    e = pd.read_csv(tmp_path / "powered_energy.csv")
    total = e["total_J"].to_numpy()
    g = torso_gait
    # the sampled single support gains the posture law's work, the push-off its own, and the
    # heel strike takes T_c, back to the start value
    assert abs(total[-3] - total[0] - g.actuation.torque_work) < 1e-8
    assert abs(total[-2] - total[-3] - g.actuation.push_off_work) < 1e-8
    assert abs(total[-2] - total[-1] - g.collision_loss) < 1e-8
    assert abs(total[-1] - total[0]) < 1e-8
    # the three rows at the heel-strike time say which is which
    assert e["event"].fillna("").tolist()[-3:] == ["", "push_off", "heel_strike"]
    assert set(e["event"].fillna("").iloc[:-2]) == {""}
