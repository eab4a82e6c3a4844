"""Walker files as researchers write them (QA sweep 4): what a file may not declare is refused
when it is loaded, in one line naming the field, instead of crashing or being ignored later.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import pytest

import heelstrike
from heelstrike.cli import main
from heelstrike.dynamics.phased import PhasedWalker
from heelstrike.models.builder import load_walker
from heelstrike.models.description import ModelDescriptionError, parse_description

WALKERS = Path(heelstrike.__file__).parent / "walkers"


def _data(name: str) -> dict[str, Any]:
    with open(WALKERS / f"{name}.toml", "rb") as fh:
        return tomllib.load(fh)


def test_lockable_hip_is_refused_at_load() -> None:
    # a lockable hip left the Poincare section without the swing leg's rate: gait, walk,
    # basin and powered crashed with an IndexError
    data = _data("compass")
    swing = next(lk for lk in data["link"] if lk.get("joint", {}).get("name") == "hip")
    swing["joint"]["lockable"] = True
    desc = parse_description(data)
    with pytest.raises(ModelDescriptionError,
                       match=r"^link\[1\]\.joint\.lockable: the hip \('hip'\) cannot be lockable"):
        PhasedWalker(desc)
    # the kneed walker's lockable knees are still fine, and its hip is free
    kneed = load_walker("kneed")
    assert kneed.lockable_joints and kneed.hip_joint not in kneed.lockable_joints


def test_lockable_hip_file_fails_in_one_line(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    text = (WALKERS / "compass.toml").read_text().replace(
        'joint = { name = "hip", actuated = true',
        'joint = { name = "hip", actuated = true, lockable = true', 1)
    assert "lockable = true" in text
    path = tmp_path / "w.toml"
    path.write_text(text)
    assert main(["gait", "--model", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "cannot be lockable" in err[0] and "IndexError" not in err[0]


@pytest.mark.parametrize(("expr", "why"), [("l / (b - b)", "division by zero"),
                                           ("(l - b) ** -1", "negative power")])
def test_arithmetic_errors_name_the_field(expr: str, why: str) -> None:
    data = _data("compass")
    data["params"]["b"] = 1.0  # b = l: (l - b) = 0
    data["constraints"] = []
    data["link"][0]["com"] = expr
    with pytest.raises(ModelDescriptionError,
                       match=rf"^link\[0\]\.com: .* cannot be evaluated: .*{why}"):
        PhasedWalker(parse_description(data))


def test_posture_law_on_another_joint_is_refused_at_load() -> None:
    # it loaded, was ignored by impact and gait, and only powered refused it
    data = _data("compass")
    data["control"] = {"torso": {"joint": "hip", "kp": 10.0, "kd": 1.0}}
    with pytest.raises(ModelDescriptionError,
                       match=r"^control\.torso\.joint: one posture law, on a joint named "
                             r"'torso', is supported \(got 'hip'\)"):
        parse_description(data)
    data = _data("torso")  # the shipped torso law still loads
    assert [law.joint for law in parse_description(data).control] == ["torso"]


@pytest.mark.slow
def test_own_walker_file_finds_the_stable_gait_of_the_same_physics(tmp_path: Path) -> None:
    # compass.toml with other numbers (QA sweep 4, P1): its stable gait (stance angle -0.55 rad,
    # outside the search's old fixed seed box) was missed, so gait, map, basin and walk called
    # the walker unstable while the built-in compass gait with the same values is stable
    import numpy as np

    from heelstrike.analysis.limit_cycle import find_limit_cycle
    from heelstrike.analysis.model_gaits import find_model_gaits
    from heelstrike.models.compass import CompassGait

    text = (WALKERS / "compass.toml").read_text()
    for old, new in (("m = 5.0 ", "m = 8.0 "), ("b = 0.5 ", "b = 0.45 "),
                     ("R = 0.0 ", "R = 0.5 "), ("I = 0.0 ", "I = 0.3 ")):
        assert text.count(old) == 1
        text = text.replace(old, new)
    path = tmp_path / "heavy.toml"
    path.write_text(text)
    slope = float(np.deg2rad(3.0))
    ref = find_limit_cycle(CompassGait(leg_mass=8.0, leg_com_from_hip=0.45, foot_radius=0.5,
                                       leg_inertia=0.3), slope=slope)
    assert ref.stable
    gaits = find_model_gaits(load_walker(str(path)), slope=slope)
    assert gaits[0].stable
    np.testing.assert_allclose(gaits[0].fixed_point, ref.fixed_point, atol=1e-8)
    # the loss per step is the potential energy gravity releases (m_total g L sin(slope))
    g = gaits[0]
    assert g.collision_loss == pytest.approx(
        26.0 * 9.81 * g.step_length * np.sin(slope), rel=1e-7)


def test_bent_knee_is_free_in_an_impact_and_said(capsys: pytest.CaptureFixture[str]) -> None:
    # QA sweep 4: impact --state with the swing knee bent 0.3 rad locked it at the bent angle
    # (its post-impact rate was 6e-16): a joint away from its lock angle is not locked
    import numpy as np

    from heelstrike.analysis.model_gaits import model_heel_strike, symmetric_heel_strike_state
    from heelstrike.core.impact import impact

    kneed = load_walker("kneed")
    q, qd = symmetric_heel_strike_state(kneed, 0.26)
    knee = kneed.joint_index("swing_knee")
    stance_knee = kneed.joint_index("stance_knee")
    assert kneed.joints_at_lock(q) == kneed.lockable_joints  # the symmetric state: all locked
    q = q.copy()
    q[knee] = 0.3  # bent swing knee; the swing foot then sits elsewhere: put it on the ground
    q = PhasedWalker.from_built(kneed).touchdown_configuration(q)
    assert kneed.joints_at_lock(q) == (stance_knee,)
    hs = model_heel_strike(kneed, q, qd)
    assert abs(hs.q_dot_plus[knee]) > 1e-3 and abs(hs.q_dot_plus[stance_knee]) < 1e-12
    assert hs.T == pytest.approx(hs.T_c + hs.T_a, rel=1e-12)
    # the same impact from the algebra alone: striking foot and stance knee, trailing foot lifts
    assert hs.trailing_foot_lifts
    A = np.vstack((kneed.contact_jacobian(q, "left"), kneed.lock_jacobian((stance_knee,))))
    ref = impact(kneed.mass_matrix(q), A, qd)
    np.testing.assert_allclose(hs.q_dot_plus, ref.velocity_post, atol=1e-12)
    state = ",".join(f"{v:.17g}" for v in q)
    assert main(["impact", "--model", "kneed", f"--state={state}", "--json"]) == 0
    out = capsys.readouterr()
    assert "joint 'swing_knee' is at 0.3 rad, not at its lock angle 0 rad: it is free" in out.err


def test_stance_foot_must_roll_before_the_impact(capsys: pytest.CaptureFixture[str]) -> None:
    # QA sweep 4: a stance foot moving into the ground at 3 m/s was accepted (T_c = T)
    import numpy as np

    from heelstrike.analysis.heel_strike import NotAHeelStrikeError, check_stance_foot_rolls
    from heelstrike.analysis.model_gaits import symmetric_heel_strike_state

    kneed = load_walker("kneed")
    q, qd = symmetric_heel_strike_state(kneed, 0.26)
    check_stance_foot_rolls(kneed, q, qd)  # the rolling state passes
    for bad in ((0, 0.0), (1, -3.0)):  # x_dot = 0 (slides, R > 0), y_dot = -3 m/s
        v = qd.copy()
        v[bad[0]] = bad[1]
        with pytest.raises(NotAHeelStrikeError, match="stance foot's contact point moves"):
            check_stance_foot_rolls(kneed, q, v)
    state = ",".join(f"{x:.17g}" for x in q)
    vel = ",".join(f"{x:.17g}" for x in np.where(np.arange(qd.size) == 1, -3.0, qd))
    assert main(["impact", "--model", "kneed", f"--state={state}", f"--velocity={vel}"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "stance foot's contact point moves" in err[0]


@pytest.mark.parametrize("argv", [["impact", "--angle", "20deg", "--q3dot", "0"],
                                  ["impact", "--model", "kneed", "--angle", "20deg",
                                   "--q3dot", "0"]])
def test_impact_at_rest_is_refused(argv: list[str],
                                   capsys: pytest.CaptureFixture[str]) -> None:
    # QA sweep 4: --q3dot 0 printed an all-zero "heel strike" (exit 0) while --q3dot -1 was
    # refused: a striking foot at rest strikes nothing
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "does not move towards the ground" in err[0]


@pytest.mark.parametrize(("argv", "choices"), [([], "reproduce, impact, gait"),
                                               (["robot"], "list, info, state"),
                                               (["study"], "cost")])
def test_missing_subcommand_names_the_choices(argv: list[str], choices: str,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    # QA sweep 4: "the following arguments are required: robot_command"
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "needs a command: " + choices in err[0]
    assert "robot_command" not in err[0]


def test_a_parameter_given_twice_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    # QA sweep 4: --param R=0.3 --param R=0.2 silently took the last value
    assert main(["impact", "--model", "compass", "--param", "R=0.3", "--param", "R=0.2",
                 "--angle", "20deg"]) == 2
    assert "--param R is given twice" in capsys.readouterr().err


def test_default_gains_of_the_paper_scale_are_the_documented_ones() -> None:
    # QA sweep 4: compass.toml's scale (g from its potential) gave gain 2.999999999999999
    from heelstrike.dynamics.actuation import (
        DEFAULT_ENERGY_GAIN,
        DEFAULT_MAX_TORQUE,
        DEFAULT_PD_KD,
        DEFAULT_PD_KP,
        default_gains,
    )
    from heelstrike.models.compass import CompassGait

    want = {"gain": DEFAULT_ENERGY_GAIN, "kp": DEFAULT_PD_KP, "kd": DEFAULT_PD_KD,
            "max_torque": DEFAULT_MAX_TORQUE}
    for walker in (CompassGait(), load_walker("compass")):
        assert default_gains(walker.scale) == want
    heavy = default_gains(CompassGait(leg_mass=10.0).scale)  # 30 kg instead of 20 kg
    assert heavy["kp"] == pytest.approx(1.5 * DEFAULT_PD_KP, rel=1e-12)
