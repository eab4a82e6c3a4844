"""Default gains find the default target (issue 11 item 12, issue 9 speed list).

``heelstrike powered --radius R --speed 0.5 --actuation A`` with the default gains must find a
periodic level-ground gait for every built-in actuation at ``R = 0`` and ``R = 0.3`` m, with the
energy books of Font & Kövecses (2008), eqs. (14)-(15): ``W_act = T_c`` per step. The gaits are
checked independently of the search's own residual: one step simulated afresh from the reported
fixed point, with the actuation rebuilt from the reported parameter, must return to it.
A target beyond what a law reaches must fail quickly, saying how far the gaits go.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from heelstrike.analysis.powered import (
    PoweredGaitNotFoundError,
    actuation_family,
    find_powered_gait,
    powered_step,
)
from heelstrike.cli import main
from heelstrike.dynamics.actuation import (
    DEFAULT_ENERGY_GAIN,
    DEFAULT_MAX_TORQUE,
    DEFAULT_PD_KD,
    DEFAULT_PD_KP,
    EnergyTracking,
    SwingLegPD,
)
from heelstrike.models.compass import CompassGait

Capture = pytest.CaptureFixture[str]

SLOW = pytest.mark.slow
CASES = [
    pytest.param("pushoff", 0.0, id="pushoff-R0"),
    pytest.param("pushoff", 0.3, id="pushoff-R0.3"),
    pytest.param("hip-pd", 0.0, id="hip-pd-R0"),
    pytest.param("hip-pd", 0.3, id="hip-pd-R0.3"),
    pytest.param("hip-energy", 0.0, id="hip-energy-R0", marks=SLOW),
    pytest.param("hip-energy", 0.3, id="hip-energy-R0.3", marks=SLOW),
]


@pytest.mark.parametrize(("actuation", "radius"), CASES)
def test_default_command_finds_periodic_gait_at_default_speed(
    actuation: str, radius: float, capsys: Capture
) -> None:
    """The CLI in-process, default gains and default speed (0.5 m/s)."""
    argv = ["powered", "--radius", str(radius), "--actuation", actuation, "--json"]
    assert main(argv) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 1
    d = json.loads(out[0])
    # the requested target, met to 1e-6 m/s
    assert d["speed"] == pytest.approx(0.5, abs=1e-6)
    assert d["speed"] == pytest.approx(d["step_length"] / d["period"], rel=1e-12)
    # eqs. (14)-(15) on a periodic level gait: W_act = -W_col = T_c per step, to 1e-8 J
    assert d["collision_loss"] > 1e-3
    assert abs(d["actuator_work"] - d["collision_loss"]) < 1e-8
    assert abs(d["energy_change"]) < 1e-8
    if actuation == "pushoff":
        assert d["hip_work"] == pytest.approx(0.0, abs=1e-12)
    else:
        assert d["push_off_work"] == 0.0
    # stability is reported and consistent with the multipliers
    mods = np.asarray(d["multipliers"])
    assert mods.size == 3 and np.all(np.isfinite(mods))
    assert isinstance(d["stable"], bool) and d["stable"] == bool(mods[0] < 1.0)
    # independent check: one step from the reported fixed point with the actuation rebuilt
    # from the reported parameter returns to the fixed point
    walker = CompassGait(foot_radius=radius)
    torque, push = actuation_family(actuation).build(walker, d["parameter"])
    z = np.array(list(d["fixed_point"].values()))
    st = powered_step(walker, z, torque, push)
    assert st.ok
    np.testing.assert_allclose(st.z_next, z, atol=1e-8)
    assert st.record is not None
    assert st.record.step_length / st.record.step_duration == pytest.approx(0.5, abs=1e-6)


def test_library_defaults_are_the_documented_ones(capsys: Capture) -> None:
    """``actuation_family`` and the torque laws share one set of defaults (the CLI passes
    nothing unless asked, and its help states them), so the command and the library find the
    same gait."""
    with pytest.raises(SystemExit):
        main(["powered", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    for option, value in (("gain", DEFAULT_ENERGY_GAIN), ("kp", DEFAULT_PD_KP),
                          ("kd", DEFAULT_PD_KD), ("max-torque", DEFAULT_MAX_TORQUE)):
        assert f"--{option}" in help_text
        assert f"default {value:g})" in help_text.split(f"--{option} ")[-1].split("--")[0]
    w = CompassGait()
    torque, _ = actuation_family("hip-energy").build(w, 150.0)
    assert isinstance(torque, EnergyTracking)
    assert (torque.gain, torque.max_torque) == (DEFAULT_ENERGY_GAIN, DEFAULT_MAX_TORQUE)
    assert EnergyTracking(walker=w, energy=1.0).gain == DEFAULT_ENERGY_GAIN
    pd, _ = actuation_family("hip-pd").build(w, 0.2)
    assert isinstance(pd, SwingLegPD)
    assert (pd.kp, pd.kd, pd.max_torque) == (DEFAULT_PD_KP, DEFAULT_PD_KD, DEFAULT_MAX_TORQUE)
    assert SwingLegPD(amplitude=0.2).kp == DEFAULT_PD_KP
    # the PD must dominate the swing leg's own gravitational stiffness m g b (the reason for
    # the default; with 5 N m/rad the point-foot gaits stop near 0.42 m/s)
    assert DEFAULT_PD_KP > w.leg_mass * w.gravity * w.leg_com_from_hip


@SLOW
def test_gait_matches_between_library_and_cli_options(capsys: Capture) -> None:
    """Explicit options equal to the defaults give the same gait as no options."""
    base = ["powered", "--radius", "0", "--actuation", "hip-pd", "--json"]
    assert main(base) == 0
    a = json.loads(capsys.readouterr().out)
    assert main([*base, "--kp", str(DEFAULT_PD_KP), "--kd", str(DEFAULT_PD_KD),
                 "--max-torque", str(DEFAULT_MAX_TORQUE)]) == 0
    b = json.loads(capsys.readouterr().out)
    assert a["parameter"] == pytest.approx(b["parameter"], abs=1e-9)
    g = find_powered_gait(CompassGait(foot_radius=0.0), actuation="hip-pd", speed=0.5)
    assert g.actuation.parameter == pytest.approx(a["parameter"], abs=1e-7)


@pytest.mark.parametrize("option", ["--gain", "--max-torque"])
def test_bad_actuation_options_are_rejected(option: str, capsys: Capture) -> None:
    assert main(["powered", option, "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("heelstrike: error:") and option in err[0]


@SLOW
def test_target_beyond_the_laws_reach_fails_with_the_range_found() -> None:
    """With the former weak PD (5 N m/rad, below the swing leg's gravitational stiffness
    24.5 N m/rad) the point-foot gaits end near 0.42 m/s: the search says how far they go,
    within a bounded number of simulated steps, instead of running into the time limit."""
    weak = actuation_family("hip-pd", kp=5.0, kd=1.0, max_torque=20.0)
    with pytest.raises(PoweredGaitNotFoundError, match=r"span .* m/s") as info:
        find_powered_gait(CompassGait(foot_radius=0.0), actuation=weak, speed=0.5,
                          max_evaluations=400)
    msg = str(info.value)
    assert "time limit" not in msg and "budget" not in msg
    reached = float(msg.split(" and end near ")[1].split()[0])
    assert 0.35 < reached < 0.5
    # and the range is real: a gait just below the reported end exists
    g = find_powered_gait(CompassGait(foot_radius=0.0), actuation=weak, speed=reached - 0.01,
                          max_evaluations=400)
    assert g.speed == pytest.approx(reached - 0.01, abs=1e-6)
