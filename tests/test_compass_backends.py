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
- the hip laws (swing-leg PD, energy tracking) run in the generated kernel too: walks equal the
  reference, the energy book closes step by step (``E- = E+ + W_hip`` between impacts, ``T_c``
  at each), and the powered hip-law gaits are the same on both backends;
- the generated ``dynamics`` returns the walker's potential energy (the energy law's ``V``);
- the CLI defaults: ``walk``, ``powered``, ``study cost`` run compiled and say so (McGeer's
  wheel on the reference; ``--backend compiled`` there is a one-line error).
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
from heelstrike.dynamics.actuation import CustomTorque, EnergyTracking, PushOff, SwingLegPD
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
        assert dict(d.parameters) == {DESCRIBED_PARAMETERS[k]: float(v)
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
    with pytest.raises(ValueError, match="torque"):
        simulate(w, q, qd, backend="compiled",
                 torque=CustomTorque(function=lambda t, q, qd: -qd[..., 3]))
    with pytest.raises(ValueError, match="profile"):
        simulate(w, q, qd, backend="compiled",
                 torque=SwingLegPD(amplitude=0.2, profile=lambda t: min(t, 1.0)))
    other = CompassGait(foot_radius=0.3, hip_mass=12.0)  # another walker's energy
    with pytest.raises(ValueError, match="walker simulated"):
        simulate(w, q, qd, backend="compiled", torque=EnergyTracking(walker=other, energy=150.0))
    with pytest.raises(ValueError, match="slope"):  # V on another slope than the walk's
        simulate(w, q, qd, backend="compiled", slope=SLOPE,
                 torque=EnergyTracking(walker=w, energy=150.0))
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


# -- the hip laws in the generated kernel ---------------------------------------------------------
def _hip_laws(w: CompassGait, q: np.ndarray, qd: np.ndarray) -> dict[str, object]:
    E0 = float(w.mechanical_energy(q, qd))
    return {
        "pd": SwingLegPD(amplitude=0.2),
        "pd-saturated": SwingLegPD(amplitude=0.25, kp=200.0, max_torque=4.0),
        "energy": EnergyTracking(walker=w, energy=E0 + 0.3),
        "energy-saturated": EnergyTracking(walker=w, energy=E0 + 2.0, gain=20.0, max_torque=3.0),
    }


@pytest.mark.parametrize("law", ["pd", "pd-saturated", "energy", "energy-saturated"])
@pytest.mark.parametrize("radius", [0.0, 0.3])
def test_compiled_hip_laws_equal_the_reference(law: str, radius: float) -> None:
    w = CompassGait(foot_radius=radius)
    q, qd = w.section_to_state(np.array([-0.25, 1.1, -0.45]))
    torque = _hip_laws(w, q, qd)[law]
    # A saturating law has a kink in the right-hand side, where both integrators' error
    # estimates are poor: at rtol = atol = 1e-10 the backends differ by up to 2e-7 (impulses),
    # at 1e-12 by 6e-9 or less, i.e. the difference is integration error and shrinks with the
    # tolerance. The saturated cases are compared at 1e-12.
    tol = 1e-12 if law.endswith("saturated") else 1e-10
    ref = simulate(w, q, qd, backend="scipy", steps=3, torque=torque, rtol=tol, atol=tol)
    got = simulate(w, q, qd, backend="compiled", steps=3, torque=torque, rtol=tol, atol=tol)
    assert isinstance(got, PhasedWalkResult)
    assert ref.status == "completed" and ref.n_steps == 3
    _compare(got, ref)
    for ra, rb in zip(got.impacts, ref.impacts, strict=True):
        assert ra.actuator_work == pytest.approx(rb.actuator_work, rel=1e-8, abs=1e-8)
    if law.startswith("pd"):  # also on a slope
        kw = dict(steps=2, slope=SLOPE, torque=torque, rtol=tol, atol=tol)
        _compare(simulate(w, q, qd, backend="compiled", **kw),
                 simulate(w, q, qd, backend="scipy", **kw))


@pytest.mark.parametrize("law", ["pd-saturated", "energy-saturated"])
def test_compiled_hip_law_energy_book_closes(law: str) -> None:
    """Level ground: over each step ``E(before impact) = E(after the previous) + W_hip``, and
    each heel strike removes ``T_c`` (the kernel's work integral and its law, checked against
    the compass gait's own ``T + V``)."""
    w = CompassGait(foot_radius=0.3)
    q, qd = w.section_to_state(np.array([-0.25, 1.1, -0.45]))
    torque = _hip_laws(w, q, qd)[law]
    walk = simulate(w, q, qd, backend="compiled", steps=3, torque=torque, max_step=0.01)
    assert walk.status == "completed"
    E_after = float(w.mechanical_energy(q, qd))
    for rec in walk.impacts:
        before = float(w.mechanical_energy(rec.q, rec.q_dot_minus))
        assert abs(rec.actuator_work) > 0.1  # the law did work
        assert before == pytest.approx(E_after + rec.actuator_work, rel=1e-8)
        E_after = float(w.mechanical_energy(rec.q, rec.q_dot_plus))
        assert before - E_after == pytest.approx(rec.kinetic_energy_constrained, abs=1e-9)
    # the saturated law reached its limit: the torque along the samples is clipped
    u = np.array([float(np.asarray(torque(0.0, qq, vv)).ravel()[0])
                  for qq, vv in zip(walk.q, walk.q_dot, strict=True)])
    assert np.max(np.abs(u)) == pytest.approx(torque.max_torque)


def test_generated_dynamics_returns_the_potential_energy() -> None:
    """The energy law's ``V`` in the kernel: the generated ``dynamics`` returns the walker's
    potential energy (the numpy derivation's) for every shipped walker."""
    from heelstrike.dynamics.compiled_phased import numba_model
    from heelstrike.models.builder import load_walker

    rng = np.random.default_rng(3)
    for name in ("compass", "kneed", "torso"):
        w = load_walker(name)
        fns = numba_model(w)
        p = np.array([float(w.parameters[k]) for k in w.description.param_names])
        n = w.n_coordinates
        for _ in range(4):
            q, u = rng.uniform(-1, 1, n), rng.uniform(-2, 2, n)
            slope = float(rng.uniform(-0.1, 0.1))
            M, h = np.empty((n, n)), np.empty(n)
            V = fns.dynamics(q, u, p, slope, M, h)
            assert V == pytest.approx(float(w.potential_energy(q, slope)), rel=1e-12, abs=1e-12)
            np.testing.assert_allclose(M, w.mass_matrix(q), atol=1e-12)
    # and for the compass gait the description's V is the compass gait's (same zero)
    c = CompassGait(foot_radius=0.3, hip_mass=7.0)
    d = c.as_described()
    assert d is not None
    q = rng.uniform(-1, 1, 4)
    assert float(d.potential_energy(q, 0.05)) == pytest.approx(float(c.potential_energy(q, 0.05)),
                                                               rel=1e-12)


# -- analyses on both backends -------------------------------------------------------------------
@pytest.mark.parametrize("actuation", ["pushoff", "hip-energy", "hip-pd"])
@pytest.mark.parametrize("radius", [0.0, 0.3])
def test_powered_gait_is_the_same_on_both_backends(radius: float, actuation: str) -> None:
    w = CompassGait(foot_radius=radius)
    family = actuation_family(actuation)
    sim = family_simulator(w, family, None)
    assert sim is not None and sim.backend == "compiled"  # compiled by default
    got = find_powered_gait(w, actuation=family, speed=0.5, simulator=sim)
    ref = find_powered_gait(w, actuation=family, speed=0.5)
    np.testing.assert_allclose(got.fixed_point, ref.fixed_point, atol=1e-8)
    assert got.actuation.parameter == pytest.approx(ref.actuation.parameter, abs=1e-8)
    assert got.collision_loss == pytest.approx(ref.collision_loss, abs=1e-8)
    assert got.speed == pytest.approx(0.5, abs=1e-9)
    # eqs. 14-15 on the periodic level gait: the actuator supplies T_c
    assert got.actuator_work == pytest.approx(got.collision_loss, abs=1e-8)
    assert got.stable == ref.stable


def test_hip_laws_run_compiled_but_on_the_wheel() -> None:
    w, wheel = CompassGait(), CompassGait(foot_radius=1.0)
    for name in ("hip-energy", "hip-pd"):
        family = actuation_family(name)
        sim = family_simulator(w, family, None)
        assert sim is not None and sim.backend == "compiled"
        assert family_simulator(w, family, "scipy") is None  # the reference
        assert family_simulator(wheel, family, None) is None  # no generated kernel
        with pytest.raises(ValueError, match="McGeer's wheel"):
            family_simulator(wheel, family, "compiled")
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
    assert out.startswith("powered gait (hip-pd, compiled backend)")
    assert main(["powered", "--actuation", "hip-pd", "--backend", "scipy"]) == 0
    assert capsys.readouterr().out.startswith("powered gait (hip-pd, scipy backend)")
    assert main(["powered", "--radius", "1"]) == 0  # McGeer's wheel: the reference
    assert capsys.readouterr().out.startswith("powered gait (pushoff, scipy backend), R = 1 m")


def test_cli_study_cost_records_the_backend_of_each_row(tmp_path: Path) -> None:
    argv = ["study", "cost", "--radius", "0:0.3:2", "--step-length", "0.4:0.5:2",
            "--actuation", "pushoff", "--actuation", "hip-pd", "--out", str(tmp_path)]
    assert main(argv) == 0
    ds = xr.open_dataset(tmp_path / "cost_study.nc")
    assert ds["backend"].dims == ("actuation", "radius")
    assert ds["backend"].values.tolist() == [["compiled", "compiled"], ["compiled", "compiled"]]
    assert int(ds["found"].sel(actuation="pushoff").sum()) == 4
    # hip-pd with the default gains reaches 0.489 m on point feet (both backends), so 3 of 4
    assert int(ds["found"].sel(actuation="hip-pd").sum()) == 3
    for act in ("pushoff", "hip-pd"):
        work = ds["actuator_work"].sel(actuation=act).values
        found = np.isfinite(work)
        # the actuator supplies T_c (eqs. 14-15), to the study's search tolerance
        np.testing.assert_allclose(work[found],
                                   ds["collision_loss"].sel(actuation=act).values[found],
                                   rtol=1e-6)
