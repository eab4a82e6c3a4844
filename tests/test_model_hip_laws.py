"""The hip laws (hip-energy, hip-pd) on described walkers whose one actuator is the hip.

- ``compass.toml`` is the compass gait: its hip-law gaits equal the compass gait's.
- ``kneed.toml`` drives its hip (coordinate 4, not the compass gait's 3): its gaits are the
  same on the compiled and the scipy backends, and the actuator work equals the collision loss
  of the heel and knee strikes (eqs. 14-15).
- The default gains are dimensionless (:func:`~heelstrike.dynamics.actuation.default_gains`):
  a walker of twice the mass, or on a quarter of the gravity, walks the same gait (masses and
  energies doubled, or times doubled) with its defaults, which the equations of motion require
  of gains scaled by ``m g l`` and ``sqrt(l / g)``.
- ``torso.toml`` actuates its torso too: the hip laws are refused in one line.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.powered import (
    actuation_family,
    check_model_actuation,
    family_simulator,
    find_model_powered_gait,
    find_powered_gait,
)
from heelstrike.cli import main
from heelstrike.dynamics.actuation import (
    DEFAULT_ENERGY_GAIN,
    DEFAULT_MAX_TORQUE,
    DEFAULT_PD_KD,
    DEFAULT_PD_KP,
    EnergyTracking,
    SwingLegPD,
    default_gains,
)
from heelstrike.dynamics.phased import PhasedWalker
from heelstrike.models.builder import load_walker
from heelstrike.models.compass import CompassGait

HIP_LAWS = ("hip-pd", "hip-energy")


@pytest.mark.parametrize("actuation", HIP_LAWS)
@pytest.mark.parametrize("radius", [0.0, 0.3])
def test_compass_file_hip_law_gaits_equal_the_compass_gaits(actuation: str,
                                                            radius: float) -> None:
    ref_walker = CompassGait(foot_radius=radius)
    family = actuation_family(actuation)
    ref = find_powered_gait(ref_walker, actuation=family, speed=0.5,
                            simulator=family_simulator(ref_walker, family, "compiled"))
    g = find_model_powered_gait(load_walker("compass", R=radius), actuation=actuation,
                                speed=0.5)
    # compass.toml's section (stance_leg, stance_leg_dot, hip_dot) is (q3, q3_dot, q4_dot)
    np.testing.assert_allclose(g.fixed_point, ref.fixed_point, rtol=0, atol=1e-8)
    assert g.actuation.parameter == pytest.approx(ref.actuation.parameter, rel=1e-8, abs=1e-8)
    assert g.collision_loss == pytest.approx(ref.collision_loss, rel=1e-8, abs=1e-10)
    assert g.actuator_work == pytest.approx(g.collision_loss, abs=1e-8)  # eqs. 14-15
    assert g.actuation.push_off_work == 0.0 and g.actuation.torque_joint == "hip"


@pytest.fixture(scope="module")
def kneed() -> PhasedWalker:
    return PhasedWalker.from_built(load_walker("kneed"))


def test_kneed_hip_laws_act_across_its_hip(kneed: PhasedWalker) -> None:
    assert kneed.hip_joint == kneed.coordinate_names.index("hip") == 4
    assert CompassGait().hip_joint == 3
    pd, _ = actuation_family("hip-pd").build(kneed, 0.2)
    energy, _ = actuation_family("hip-energy").build(kneed, 12.0)
    assert isinstance(pd, SwingLegPD) and isinstance(energy, EnergyTracking)
    assert pd.joint == energy.joint == 4
    # the law reads the hip, not coordinate 3 (the stance knee)
    q = np.zeros(kneed.n_coordinates)
    qd = np.zeros(kneed.n_coordinates)
    q[3], q[4] = 0.3, -0.1
    u = float(pd(0.0, q, qd)[0])
    assert u == pytest.approx(pd.kp * (-0.4 + 0.1))
    qd[4] = 2.0
    E = float(kneed.mechanical_energy(q, qd))
    assert float(energy(0.0, q, qd)[0]) == pytest.approx(
        float(np.clip(-energy.gain * (E - 12.0) * 2.0, -energy.max_torque, energy.max_torque)))
    with pytest.raises(ValueError, match="joint must be a coordinate index >= 2 and < 6"):
        EnergyTracking(walker=kneed, energy=1.0, joint=6)
    with pytest.raises(ValueError, match="joint must be a coordinate index"):
        SwingLegPD(amplitude=0.1, joint=1)


@pytest.mark.slow
@pytest.mark.parametrize("actuation", HIP_LAWS)
def test_kneed_hip_law_gait_same_on_both_backends(actuation: str) -> None:
    walker = load_walker("kneed")
    compiled = find_model_powered_gait(walker, actuation=actuation, speed=0.5)
    scipy = find_model_powered_gait(walker, actuation=actuation, speed=0.5, backend="scipy")
    for g in (compiled, scipy):
        assert g.speed == pytest.approx(0.5, abs=1e-8) and g.residual < 1e-8
        # level ground, periodic: the hip's work is the loss of every strike (heel and knees)
        assert g.actuation.torque_work == pytest.approx(g.collision_loss, abs=1e-8)
        assert g.actuation.push_off_work == 0.0 and g.actuation.hip_work == g.actuation.torque_work
        assert g.collision_loss > 0
    np.testing.assert_allclose(compiled.fixed_point, scipy.fixed_point, rtol=0, atol=1e-8)
    assert compiled.actuation.parameter == pytest.approx(scipy.actuation.parameter, rel=1e-8,
                                                         abs=1e-8)
    assert compiled.collision_loss == pytest.approx(scipy.collision_loss, rel=1e-8)


def test_default_gains_are_the_documented_ones_for_the_paper_walker() -> None:
    assert default_gains(CompassGait().scale) == {
        "gain": DEFAULT_ENERGY_GAIN, "kp": DEFAULT_PD_KP, "kd": DEFAULT_PD_KD,
        "max_torque": DEFAULT_MAX_TORQUE}
    heavy = default_gains(CompassGait(hip_mass=20.0, leg_mass=10.0).scale)
    moon = default_gains(CompassGait(gravity=9.81 / 4).scale)
    assert heavy == pytest.approx({"gain": 3.0, "kp": 100.0, "kd": 10.0, "max_torque": 100.0})
    assert moon == pytest.approx({"gain": 6.0, "kp": 12.5, "kd": 2.5, "max_torque": 12.5})


@pytest.mark.slow
@pytest.mark.parametrize("actuation", HIP_LAWS)
def test_scaled_walkers_walk_the_same_gait_with_their_default_gains(actuation: str) -> None:
    """Similarity: twice the masses (energies x 2) and a quarter of the gravity (times x 2,
    energies / 4) leave the gait's shape unchanged when the gains scale with the walker."""

    def gait(w: CompassGait, speed: float) -> object:
        family = actuation_family(actuation)
        return find_powered_gait(w, actuation=family, speed=speed,
                                 simulator=family_simulator(w, family, "compiled"))

    ref = gait(CompassGait(), 0.5)
    heavy = gait(CompassGait(hip_mass=20.0, leg_mass=10.0), 0.5)
    moon = gait(CompassGait(gravity=9.81 / 4), 0.25)
    energy = 1.0 if actuation == "hip-pd" else None  # the parameter's scale, below
    np.testing.assert_allclose(heavy.fixed_point, ref.fixed_point, atol=1e-7)
    np.testing.assert_allclose(moon.fixed_point, np.asarray(ref.fixed_point) * [1, 0.5, 0.5],
                               atol=1e-7)
    assert heavy.collision_loss == pytest.approx(2 * ref.collision_loss, rel=1e-7)
    assert moon.collision_loss == pytest.approx(ref.collision_loss / 4, rel=1e-7)
    assert heavy.period == pytest.approx(ref.period, rel=1e-7)
    assert moon.period == pytest.approx(2 * ref.period, rel=1e-7)
    if energy is None:  # the target energy (J) scales with m g l
        assert heavy.actuation.parameter == pytest.approx(2 * ref.actuation.parameter, rel=1e-7)
        assert moon.actuation.parameter == pytest.approx(ref.actuation.parameter / 4, rel=1e-7)
    else:  # the amplitude (rad) is dimensionless
        assert heavy.actuation.parameter == pytest.approx(ref.actuation.parameter, rel=1e-7)
        assert moon.actuation.parameter == pytest.approx(ref.actuation.parameter, rel=1e-7)


def test_torso_walker_refuses_the_hip_laws() -> None:
    torso = load_walker("torso")
    check_model_actuation(torso, "pushoff")
    check_model_actuation(load_walker("kneed"), "hip-pd")
    for actuation in HIP_LAWS:
        with pytest.raises(ValueError, match="model 'torso' actuates hip, torso"):
            check_model_actuation(torso, actuation)
        with pytest.raises(ValueError, match="model 'torso' actuates hip, torso"):
            find_model_powered_gait(torso, actuation=actuation, speed=0.5)
    with pytest.raises(ValueError, match="set the hip laws, not the push-off"):
        find_model_powered_gait(torso, speed=0.5, actuation_options={"kp": 5.0})


@pytest.mark.slow
def test_cli_powered_model_kneed_hip_pd(capsys: pytest.CaptureFixture[str],
                                        tmp_path: Path) -> None:
    assert main(["powered", "--model", "kneed", "--actuation", "hip-pd", "--speed", "0.5",
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["model"] == "kneed" and d["backend"] == "compiled"
    assert d["speed"] == pytest.approx(0.5, abs=1e-8)
    assert d["hip_work"] == pytest.approx(d["collision_loss"], abs=1e-8)
    lib = find_model_powered_gait(load_walker("kneed"), actuation="hip-pd", speed=0.5)
    assert d["parameter"] == pytest.approx(lib.actuation.parameter, abs=1e-9)
    # explicit gains reach the law: a softer hip takes a longer step at the same speed
    assert main(["powered", "--model", "kneed", "--actuation", "hip-pd", "--speed", "0.5",
                 "--kp", "3", "--json"]) == 0
    soft = json.loads(capsys.readouterr().out)
    assert soft["step_length"] > d["step_length"] + 0.01
    assert soft["hip_work"] == pytest.approx(soft["collision_loss"], abs=1e-8)
    # the declared target (the push-off gaits' 1.3 m/s) lies beyond the hip-pd gaits: a
    # one-line failure saying where they end
    assert main(["powered", "--model", "kneed", "--actuation", "hip-pd"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "the hip-pd gaits found span" in err[0]


@pytest.mark.slow
def test_cli_study_cost_model_kneed_hip_laws(tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    import xarray as xr

    # the kneed walker's hip-law gaits reach 0.5 m/s from about R = 0.08 m up (with point-like
    # feet, R = 0.05 m, the hip-pd gaits end at 0.456 m/s)
    assert main(["study", "cost", "--model", "kneed", "--actuation", "hip-pd",
                 "--actuation", "hip-energy", "--radius", "0.1:0.2:2", "--speed",
                 "0.48:0.52:2", "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    with xr.open_dataset(tmp_path / "cost_study.nc") as ds:
        assert int(ds["found"].sum()) == ds["found"].size == 8
        assert set(np.asarray(ds["backend"]).ravel().tolist()) == {"compiled"}
        assert float(np.max(ds["push_off_work"].values)) == 0.0  # the hip alone drives it
        # the hip supplies the heel and knee strikes' loss (eqs. 14-15)
        np.testing.assert_allclose(ds["torque_work"].values, ds["collision_loss"].values,
                                   rtol=1e-6)
        speed = (ds["step_length"] / ds["period"]).transpose(*ds["found"].dims).values
        target = np.broadcast_to(ds["speed"].values, speed.shape)
        assert np.max(np.abs(speed - target)) < 1e-6
