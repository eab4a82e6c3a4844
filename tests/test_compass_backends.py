"""The compass gait on the compiled backend for every command (issue 9, item 4).

The hand-written compass kernel walks the passive gait; a push-off, a friction limit and dense
samples run on the kernel generated from ``compass.toml``
(:meth:`~heelstrike.models.compass.CompassGait.as_described`), and the compass ``basin`` and
``map`` run on the scipy reference too. Checked here:

- the described compass has the compass gait's equations (``M``, ``h``, contact Jacobians) to
  round-off for random parameters and states;
- every compiled walk equals the scipy reference (impact times, states, ``T_c``, impulses,
  step lengths, statuses) to 1e-8, as the backend-conformance test asks;
- energy is conserved between impacts on the compiled dense samples, and the push-off work
  equals the kinetic-energy jump it causes;
- the powered search finds the same gait on both backends, and its energy book closes
  (actuator work = ``T_c``, eqs. 14-15);
- the map and the basin give the same gaits and outcomes on both backends;
- the CLI defaults: ``walk``, ``powered``, ``study cost`` run compiled and say so; the hip laws
  run on the reference (and ``--backend compiled`` with one is a one-line error).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from heelstrike.analysis.limit_cycle import PoincareMap, find_limit_cycle
from heelstrike.analysis.powered import actuation_family, family_simulator, find_powered_gait
from heelstrike.cli import main
from heelstrike.dynamics import simulate
from heelstrike.dynamics.actuation import EnergyTracking, PushOff
from heelstrike.dynamics.backends import simulator
from heelstrike.dynamics.hybrid import PhasedWalkResult
from heelstrike.models.compass import DESCRIBED_PARAMETERS, CompassGait

SLOPE = np.deg2rad(3.0)


@pytest.fixture(scope="module")
def gait_03() -> np.ndarray:
    """The passive gait of R = 0.3 m on 3 deg (compiled map)."""
    return np.asarray(find_limit_cycle(CompassGait(foot_radius=0.3), slope=SLOPE,
                                       method="compiled").fixed_point)


def _compare(a: object, b: object, tol: float = 1e-8) -> None:
    """Two walks agree: status, number of steps and every impact record to ``tol`` (relative
    and absolute, the backend-conformance rule)."""
    assert a.status == b.status and a.n_steps == b.n_steps  # type: ignore[attr-defined]
    for ra, rb in zip(a.impacts, b.impacts, strict=True):  # type: ignore[attr-defined]
        for name in ("time", "q", "q_dot_minus", "q_dot_plus", "kinetic_energy_constrained",
                     "impulse", "step_length"):
            np.testing.assert_allclose(getattr(ra, name), getattr(rb, name), rtol=tol,
                                       atol=tol, err_msg=f"step {rb.step}: {name}")
    np.testing.assert_allclose(a.final_q, b.final_q, rtol=tol,  # type: ignore[attr-defined]
                               atol=tol)


# -- the description is the same walker ----------------------------------------------------------
def test_described_compass_has_the_same_equations() -> None:
    rng = np.random.default_rng(7)
    for _ in range(5):
        l = rng.uniform(0.6, 1.4)
        w = CompassGait(hip_mass=rng.uniform(1, 20), leg_mass=rng.uniform(1, 10),
                        leg_length=l, leg_com_from_hip=rng.uniform(0.1, 0.9) * l,
                        foot_radius=rng.uniform(0, 1) * l, leg_inertia=rng.uniform(0, 0.3),
                        gravity=rng.uniform(1, 20))
        d = w.as_described()
        assert d is not None
        assert dict(d.params) == {DESCRIBED_PARAMETERS[k]: float(v)
                                  for k, v in w.parameters.items()}
        for _ in range(4):
            q = rng.uniform(-1, 1, 4)
            qd = rng.uniform(-2, 2, 4)
            np.testing.assert_allclose(d.mass_matrix(q), w.mass_matrix(q), atol=1e-12)
            np.testing.assert_allclose(d.bias_forces(q, qd, 0.05), w.bias_forces(q, qd, 0.05),
                                       atol=1e-11)
            for foot in ("right", "left"):
                np.testing.assert_allclose(d.contact_jacobian(q, foot),
                                           w.contact_jacobian(q, foot), atol=1e-12)


def test_the_description_is_built_once_per_parameter_values() -> None:
    # a walk on the generated kernel must not rebuild the description (1-2 ms) every step
    a, b = CompassGait(foot_radius=0.3), CompassGait(foot_radius=0.3)
    assert a.as_described() is b.as_described()
    assert a.as_described() is not CompassGait(foot_radius=0.31).as_described()


def test_a_batch_of_walkers_has_no_single_description() -> None:
    assert CompassGait(foot_radius=np.array([0.0, 0.2])).as_described() is None


def test_mcgeers_wheel_runs_on_the_reference_only() -> None:
    """At R = l both foot arcs are one circle about the hip: the description's heel-strike
    guard (the swing foot's clearance) is round-off, and the described compass struck at
    0.39 s, legs nearly upright, where the compass gait's guard 2 q3 + q4 = 0 strikes at
    0.757 s. Now the described walkers refuse to walk it, and the compass gait walks it on
    the reference."""
    from heelstrike.dynamics.phased import load_phased_walker

    wheel = CompassGait(foot_radius=1.0)
    assert wheel.as_described() is None
    z = np.array([-0.2, 0.62092676, -0.29293942])
    for name in ("compass", "torso"):  # the described walkers refuse to walk it, on both
        w = load_phased_walker(name, R=1.0)
        q, qd = w.section_to_state(w.section_point(*z))
        for backend in ("scipy", "compiled"):
            with pytest.raises(ValueError, match="one circle in every posture"):
                simulate(w, q, qd, backend=backend)
        w.replace(R=0.999).check_heel_strike_detectable()  # just inside: fine
        # the algebra is still defined there: the described M equals the compass gait's
        if name == "compass":
            np.testing.assert_allclose(w.mass_matrix(q), wheel.mass_matrix(q), atol=1e-12)
    q, qd = wheel.section_to_state(z)
    with pytest.raises(ValueError, match="McGeer's wheel"):
        simulate(wheel, q, qd, backend="compiled", push_off=PushOff(impulse=1.8))
    ref = simulate(wheel, q, qd, backend="scipy", push_off=PushOff(impulse=1.8))
    assert ref.impacts[0].time == pytest.approx(0.75686, abs=1e-4)
    assert family_simulator(wheel, actuation_family("pushoff"), None) is None  # reference
    # just inside, the description is the compass gait again
    near = CompassGait(foot_radius=0.999)
    q, qd = near.section_to_state(z)
    _compare(simulate(near, q, qd, backend="compiled", max_step=0.02),
             simulate(near, q, qd, backend="scipy", max_step=0.02))


# -- simulate(..., backend="compiled") -----------------------------------------------------------
@pytest.mark.parametrize("options", [
    {"push_off": PushOff(impulse=1.0), "slope": 0.0},
    {"push_off": PushOff(impulse=2.5), "slope": SLOPE},
    {"max_step": 0.01, "slope": SLOPE},
    {"friction": 0.6, "slope": SLOPE},
    {"friction": 0.2, "slope": SLOPE},  # needs more: slips at once
], ids=["pushoff-level", "pushoff-slope", "dense", "friction", "slips"])
def test_compiled_compass_walks_equal_the_reference(options: dict, gait_03: np.ndarray) -> None:
    w = CompassGait(foot_radius=0.3)
    q, qd = w.section_to_state(gait_03)
    ref = simulate(w, q, qd, backend="scipy", steps=4, **options)
    got = simulate(w, q, qd, backend="compiled", steps=4, **options)
    assert isinstance(got, PhasedWalkResult)
    _compare(got, ref)
    if "friction" in options and options["friction"] < 0.3:
        assert got.status == "slipped"
    else:
        assert got.status == "completed" and got.n_steps == 4


def test_passive_compiled_walk_keeps_the_compass_kernel(gait_03: np.ndarray) -> None:
    w = CompassGait(foot_radius=0.3)
    q, qd = w.section_to_state(gait_03)
    walk = simulate(w, q, qd, backend="compiled", slope=SLOPE, steps=2)
    assert not isinstance(walk, PhasedWalkResult)  # the hand-written kernel's result
    _compare(walk, simulate(w, q, qd, backend="scipy", slope=SLOPE, steps=2))


def test_dense_compiled_samples_conserve_energy(gait_03: np.ndarray) -> None:
    w = CompassGait(foot_radius=0.3)
    q, qd = w.section_to_state(gait_03)
    walk = simulate(w, q, qd, backend="compiled", slope=SLOPE, steps=2, max_step=0.01,
                    rtol=1e-10, atol=1e-10)
    assert walk.t.size > 100
    E = np.asarray(w.mechanical_energy(walk.q, walk.q_dot, SLOPE))
    for n in range(2):
        E_step = E[walk.step == n]
        assert E_step.size > 50
        assert np.ptp(E_step) < 1e-7 * abs(E_step[0])
    # and each heel strike removes T_c: E after = E before - T_c
    for rec in walk.impacts:
        before = float(w.mechanical_energy(rec.q, rec.q_dot_minus, SLOPE))
        after = float(w.mechanical_energy(rec.q, rec.q_dot_plus, SLOPE))
        assert before - after == pytest.approx(rec.kinetic_energy_constrained, abs=1e-9)


def test_compiled_compass_refuses_what_no_kernel_runs(gait_03: np.ndarray) -> None:
    w = CompassGait(foot_radius=0.3)
    q, qd = w.section_to_state(gait_03)
    law = EnergyTracking(walker=w, energy=150.0)
    with pytest.raises(ValueError, match="torque"):
        simulate(w, q, qd, backend="compiled", torque=law)
    with pytest.raises(ValueError, match="restitution"):
        simulate(w, q, qd, backend="compiled", restitution=0.5)
    with pytest.raises(ValueError, match="push_off other than PushOff"):
        simulate(w, q, qd, backend="compiled", push_off=lambda *a: (a[2], 0.0))


def test_poincare_map_batches_the_pushed_compass_on_the_generated_kernel(
    gait_03: np.ndarray,
) -> None:
    w = CompassGait(foot_radius=0.3)
    push = PushOff(impulse=1.0)
    fast = PoincareMap(walker=w, push_off=push, rtol=1e-10, atol=1e-10,
                       simulator=simulator(w, "compiled", push_off=push))
    ref = PoincareMap(walker=w, push_off=push, rtol=1e-10, atol=1e-10)
    Z = gait_03 + np.array([[0.0, 0.0, 0.0], [0.01, -0.02, 0.03], [-0.3, 0.3, 0.0]])
    got = fast.many(Z)
    want = np.stack([ref(z) for z in Z])
    np.testing.assert_allclose(got, want, atol=1e-8)
    assert np.all(np.isnan(got[2]))  # a failed step is NaN on both


# -- analyses on both backends -------------------------------------------------------------------
@pytest.mark.parametrize("radius", [0.0, 0.3])
def test_powered_gait_is_the_same_on_both_backends(radius: float) -> None:
    w = CompassGait(foot_radius=radius)
    family = actuation_family("pushoff")
    sim = family_simulator(w, family, None)
    assert sim is not None and sim.backend == "compiled"  # push-off: compiled by default
    got = find_powered_gait(w, actuation=family, speed=0.5, simulator=sim)
    ref = find_powered_gait(w, actuation=family, speed=0.5)
    np.testing.assert_allclose(got.fixed_point, ref.fixed_point, atol=1e-8)
    assert got.parameter == pytest.approx(ref.parameter, abs=1e-8)
    assert got.collision_loss == pytest.approx(ref.collision_loss, abs=1e-8)
    assert got.speed == pytest.approx(0.5, abs=1e-9)
    # eqs. 14-15 on the periodic level gait: the push-off supplies T_c
    assert got.actuator_work == pytest.approx(got.collision_loss, abs=1e-8)
    assert got.stable == ref.stable


def test_hip_laws_run_on_the_reference_only() -> None:
    w = CompassGait()
    for name in ("hip-energy", "hip-pd"):
        family = actuation_family(name)
        assert family_simulator(w, family, None) is None  # the reference
        with pytest.raises(ValueError, match="torque"):
            family_simulator(w, family, "compiled")
    assert family_simulator(w, actuation_family("pushoff"), "scipy") is None
    with pytest.raises(ValueError, match="backend"):
        family_simulator(w, actuation_family("pushoff"), "euler")


def test_compass_map_is_the_same_on_both_backends() -> None:
    from heelstrike.analysis.gait_map import gait_map

    radii, slopes = np.array([0.0, 0.3]), np.deg2rad([2.5, 3.5])
    a = gait_map(CompassGait(), radii, slopes).dataset
    b = gait_map(CompassGait(), radii, slopes, backend="scipy").dataset
    assert a.attrs["backend"] == "compiled" and b.attrs["backend"] == "scipy"
    assert bool(a["gait_found"].all()) and bool(b["gait_found"].all())
    for k in ("fixed_point", "period", "step_length", "collision_loss", "impact_angle"):
        np.testing.assert_allclose(a[k].values, b[k].values, atol=1e-8)
    np.testing.assert_allclose(a["spectral_radius"].values, b["spectral_radius"].values,
                               atol=1e-6)
    assert (a["stable"].values == b["stable"].values).all()


def test_compass_basin_is_the_same_on_both_backends() -> None:
    from heelstrike.analysis.basin import basin_of_attraction

    kw = dict(grid=(6, 5), ranges=((-0.4, -0.1), (0.6, 1.6)), steps=25)
    a = basin_of_attraction(CompassGait(), SLOPE, **kw)
    b = basin_of_attraction(CompassGait(), SLOPE, backend="scipy", **kw)
    assert a.dataset.attrs["backend"] == "compiled" and b.dataset.attrs["backend"] == "scipy"
    np.testing.assert_allclose(a.fixed_point, b.fixed_point, atol=1e-8)
    assert (a.dataset["outcome"].values == b.dataset["outcome"].values).all()
    assert (a.dataset["steps"].values == b.dataset["steps"].values).all()
    assert 0 < a.converging_fraction < 1  # the window holds converging and failing starts


# -- the CLI defaults ----------------------------------------------------------------------------
def test_cli_walk_runs_compiled_by_default(tmp_path: Path,
                                           capsys: pytest.CaptureFixture[str]) -> None:
    for backend in ("compiled", "scipy"):
        argv = ["walk", "--steps", "2", "--fps", "10", "--out", str(tmp_path / backend)]
        assert main(argv if backend == "compiled" else [*argv, "--backend", "scipy"]) == 0
    assert "2 steps, status: completed" in capsys.readouterr().out
    got = pd.read_csv(tmp_path / "compiled" / "impacts.csv")
    ref = pd.read_csv(tmp_path / "scipy" / "impacts.csv")
    np.testing.assert_allclose(got["T_c_J"], ref["T_c_J"], atol=1e-7)
    np.testing.assert_allclose(got["time_s"], ref["time_s"], atol=1e-7)
    np.testing.assert_allclose(got["drop_J"], got["T_c_J"], atol=1e-7)  # each drop is its T_c
    # the step figure's data is the compass gait's (drawn for both backends)
    step = pd.read_csv(tmp_path / "compiled" / "step.csv")
    assert step["t_s"].iloc[0] == 0.0 and step["normal_N"].min() > 0


def test_cli_powered_says_which_backend_ran(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["powered", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["backend"] == "compiled" and d["units"]["backend"] is None
    assert d["actuator_work"] == pytest.approx(d["collision_loss"], abs=1e-8)
    assert main(["powered", "--actuation", "hip-pd"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("powered gait (hip-pd, scipy backend)")
    assert main(["powered", "--radius", "1"]) == 0  # McGeer's wheel: the reference
    assert capsys.readouterr().out.startswith("powered gait (pushoff, scipy backend), R = 1 m")


def test_cli_study_cost_records_the_backend_of_each_row(tmp_path: Path) -> None:
    argv = ["study", "cost", "--radius", "0:0.3:2", "--step-length", "0.4:0.5:2",
            "--actuation", "pushoff", "--actuation", "hip-pd", "--out", str(tmp_path)]
    assert main(argv) == 0
    ds = xr.open_dataset(tmp_path / "cost_study.nc")
    assert ds["backend"].dims == ("actuation", "radius")
    assert ds["backend"].values.tolist() == [["compiled", "compiled"], ["scipy", "scipy"]]
    assert int(ds["found"].sel(actuation="pushoff").sum()) == 4
    work = ds["actuator_work"].sel(actuation="pushoff").values
    # the push-off supplies T_c (eqs. 14-15), to the study's search tolerance
    np.testing.assert_allclose(work, ds["collision_loss"].sel(actuation="pushoff").values,
                               rtol=1e-6)
