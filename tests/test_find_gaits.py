"""``find_gaits``: one gait finder, one result type, one order of gaits (issue 32, item 3).

Each gait returned is checked against the physics independently of the search that found it:
one step re-simulated from its fixed point on the scipy reference returns to it, and its
stability flag agrees with the spectral radius of a central-difference Jacobian of that map.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from heelstrike.analysis import Actuation, Gait, find_gaits
from heelstrike.analysis.limit_cycle import PoincareMap, find_limit_cycles
from heelstrike.analysis.powered import actuation_family, powered_step
from heelstrike.cli import main
from heelstrike.models.compass import CompassGait

#: The paper's slope (the ``gait`` command's default).
SLOPE = float(np.deg2rad(3.0))


def _passive_step(walker: CompassGait, slope: float, z: np.ndarray) -> np.ndarray:
    """One passive step on the scipy reference (tight tolerances) from section point ``z``."""
    return PoincareMap(walker=walker, slope=slope, rtol=1e-12, atol=1e-12, method="scipy")(z)


def _powered_step(walker: CompassGait, gait: Gait, z: np.ndarray) -> np.ndarray:
    """One step with the gait's actuation (its family at its amplitude) on the scipy reference."""
    assert gait.actuation is not None
    torque, push_off = actuation_family(gait.actuation.name).build(walker,
                                                                   gait.actuation.parameter)
    st = powered_step(walker, z, torque, push_off, rtol=1e-12, atol=1e-12)
    assert st.ok
    return np.asarray(st.z_next, dtype=float)


def _radius(step: object, z: np.ndarray, h: float = 1e-5) -> float:
    """Spectral radius of the central-difference Jacobian of ``step`` at ``z``."""
    f = step  # a callable z -> P(z)
    DP = np.column_stack([(f(z + h * e) - f(z - h * e)) / (2 * h)  # type: ignore[operator]
                          for e in np.eye(z.size)])
    return float(np.max(np.abs(np.linalg.eigvals(DP))))


@pytest.fixture(scope="module")
def compass_gaits() -> tuple[CompassGait, tuple[Gait, ...]]:
    w = CompassGait()
    return w, find_gaits(w, SLOPE, backend="compiled")


def test_passive_compass_is_find_limit_cycles(
        compass_gaits: tuple[CompassGait, tuple[Gait, ...]]) -> None:
    """(a) The compass at the paper's slope: the same gaits as find_limit_cycles to 1e-10."""
    w, gaits = compass_gaits
    ref = find_limit_cycles(w, slope=SLOPE, method="compiled")
    assert len(gaits) == len(ref) >= 1
    for g, r in zip(gaits, ref, strict=True):
        assert isinstance(g, Gait) and g.actuation is None
        np.testing.assert_allclose(g.fixed_point, r.fixed_point, rtol=0, atol=1e-10)
        assert g.period == pytest.approx(r.period, abs=1e-10)


def test_passive_gaits_are_fixed_points_in_the_one_order(
        compass_gaits: tuple[CompassGait, tuple[Gait, ...]]) -> None:
    """(c) Each passive gait is a fixed point of the scipy reference's step map, its stability
    that of the map's Jacobian there; (b) the first gait is stable if any is, and the books
    close (the slope's energy released = T_c)."""
    w, gaits = compass_gaits
    for g in gaits:
        z = np.asarray(g.fixed_point, dtype=float)
        assert np.linalg.norm(_passive_step(w, SLOPE, z) - z) < 1e-8
        rho = _radius(lambda x: _passive_step(w, SLOPE, x), z)
        assert rho == pytest.approx(g.spectral_radius, abs=1e-4)
        assert g.stable is (rho < 1.0)
        assert g.collision_loss == pytest.approx(g.potential_energy_released, rel=1e-7)
    if any(g.stable for g in gaits):
        assert gaits[0].stable
    assert [g.stable for g in gaits] == sorted((g.stable for g in gaits), reverse=True)


def test_powered_gaits_two_at_one_target_stable_first(capsys: pytest.CaptureFixture[str]
                                                      ) -> None:
    """A powered gait is a fixed point with one more unknown (the push-off impulse) and one
    more equation (the speed): light legs (mH = 10 kg, m = 0.1 kg) at 0.5 m/s have two, the
    cheaper unstable (issue 32). (b) The stable one comes first, the unstable one is listed
    after it, marked; (c) each returns to its fixed point after one scipy step with its own
    impulse, at the target speed, and its flag agrees with the map's Jacobian."""
    walker = CompassGait(leg_mass=0.1)
    gaits = find_gaits(walker, 0.0, control="pushoff", target={"speed": 0.5})
    assert len(gaits) == 2
    for g in gaits:
        assert isinstance(g.actuation, Actuation) and g.actuation.name == "pushoff"
        z = np.asarray(g.fixed_point, dtype=float)
        assert np.linalg.norm(_powered_step(walker, g, z) - z) < 1e-8
        assert g.speed == pytest.approx(0.5, abs=1e-8)
        # level ground: the push-off pays for the heel strike's loss (W_act = T_c)
        assert g.actuator_work == pytest.approx(g.collision_loss, rel=1e-6)
        assert g.actuation.push_off_work == pytest.approx(g.actuator_work, rel=1e-12)
        rho = _radius(lambda x, g=g: _powered_step(walker, g, x), z)
        assert g.stable is (rho < 1.0)
    first, other = gaits
    assert first.stable and not other.stable
    assert other.actuator_work < first.actuator_work  # the cheaper one is unstable
    # the CLI reports the same order: the stable one, the other listed and marked
    assert main(["powered", "--leg-mass", "0.1", "--speed", "0.5", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["stable"] and d["actuator_work"] == pytest.approx(first.actuator_work, rel=1e-6)
    assert [o["stable"] for o in d["other_gaits"]] == [False]
    assert first.actuation is not None
    assert d["parameter"] == pytest.approx(first.actuation.parameter, abs=1e-8)


def test_the_gait_dict_flattens_the_actuation() -> None:
    """A powered gait's summary has its actuation's fields under today's ``powered --json``
    keys; a passive gait's has none of them."""
    act = Actuation(name="pushoff", parameter_name="impulse", parameter_unit="N s",
                    parameter=0.25, push_off_work=0.75, torque_work=0.25, torque_joint="hip",
                    gains={"gain": 2.0}, model=None)
    base = dict(fixed_point=np.array([-0.2, 1.0, -0.1]), section_names=("q3", "q3_dot", "q4_dot"),
                q=np.zeros(4), q_dot=np.zeros(4), period=1.0, step_length=0.5, speed=0.5,
                impact_angle=0.2, multipliers=np.array([0.5 + 0j]), stable=True,
                collision_loss=1.0, kinetic_energy_pre=2.0, kinetic_energy_admissible=1.0,
                eta=2.0, potential_energy_released=0.0, actuator_work=1.0, residual=0.0,
                iterations=1, slope=0.0, walk=lambda: None)
    powered = Gait(**base, actuation=act, energy_change=0.0, energy_balance_error=0.0,
                   cost_of_transport=0.1)  # type: ignore[arg-type]
    d = powered.to_dict()
    assert (d["actuation"], d["parameter"], d["push_off_work"]) == ("pushoff", 0.25, 0.75)
    assert d["torque_work"] == 0.25 and d["hip_work"] == 0.25 and d["gains"] == {"gain": 2.0}
    passive = Gait(**base).to_dict()  # type: ignore[arg-type]
    assert not {"actuation", "parameter", "push_off_work", "gains"} & set(passive)
    assert Actuation(**{**act.__dict__, "torque_joint": "torso"}).hip_work == 0.0


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"control": "jetpack", "target": {"speed": 0.5}}, "not an actuation family"),
    ({"control": "pushoff"}, "needs a target"),
    ({"control": "pushoff", "target": {"speed": 0.5, "step_length": 0.5}}, "exactly one"),
    ({"control": "pushoff", "target": {"cadence": 1.0}}, "exactly one"),
    ({"control": "pushoff", "target": {"speed": -0.5}}, "finite and > 0"),
    ({"control": "pushoff", "target": {"step_length": float("nan")}}, "finite and > 0"),
    ({"target": {"speed": 0.5}}, "is for a powered gait"),
    ({"control": "pushoff", "target": {"speed": 0.5}, "guess": [0.1, 0.2, 0.3]}, "guess"),
])
def test_bad_requests_are_refused(kwargs: dict[str, object], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        find_gaits(CompassGait(), 0.0, **kwargs)  # type: ignore[arg-type]


def test_a_powered_search_is_on_level_ground() -> None:
    with pytest.raises(ValueError, match="level ground"):
        find_gaits(CompassGait(), SLOPE, control="pushoff", target={"speed": 0.5})


def test_a_powered_search_keeps_a_profile_foot_walker_as_given() -> None:
    """Review finding: for a profile foot the search's design radius was the rolling radius
    at ``phi = 0`` (``R + 4 k2`` here), which the search writes back into ``R``: it searched
    a walker with another foot (0.38 m for R = 0.3 m, 23 % less work). The design radius is
    the walker's own ``R``, so the walker searched is the one given."""
    from pathlib import Path

    from heelstrike.analysis.powered import _at_radius, design_radius
    from heelstrike.models.builder import load_walker

    path = Path(__file__).parents[1] / "examples" / "walkers" / "compass_foot6.toml"
    w = load_walker(str(path)).replace(k2=0.02)
    # the rolling radius at phi = 0 is R + k2 (1 + 3 cos 0) = 0.38 m: not the foot's R
    assert float(w.foot_radii[0]) == pytest.approx(0.38, abs=1e-12)
    assert design_radius(w) == 0.3
    searched = _at_radius(w, design_radius(w))
    assert dict(searched.parameters) == dict(w.parameters)
    # the compass gait's design radius is its foot radius
    assert design_radius(CompassGait(foot_radius=0.25)) == 0.25


def test_a_powered_search_of_a_batch_is_refused_clearly() -> None:
    """Review finding: a batch of walkers raised numpy's 'only 0-dimensional arrays' from
    deep inside; the passive search refuses it by name, and so does the powered one."""
    with pytest.raises(ValueError, match="one walker at a time"):
        find_gaits(CompassGait(foot_radius=np.array([0.2, 0.3])), control="pushoff",
                   target={"speed": 0.5})


def test_a_powered_search_of_a_stride_walker_names_the_reason() -> None:
    """Review finding: a walker whose legs differ was sent to the compiled backend, which it
    does not support, and the error named the backend instead of the reason (its powered
    map would be a stride). The search runs on a backend the walker supports."""
    from pathlib import Path

    from heelstrike.models.builder import load_walker

    w = load_walker(str(Path(__file__).parents[1] / "examples" / "walkers" / "amputee.toml"))
    with pytest.raises(ValueError, match="legs differ") as err:
        find_gaits(w, control="pushoff", target={"speed": 0.5})
    assert "backend" not in str(err.value)


def test_the_wheels_powered_gaits_are_reported_undecided(
        capsys: pytest.CaptureFixture[str]) -> None:
    """Review finding: McGeer's wheel's report said the stability is undecided, then called
    the gait "stable no, barely", the others "stable yes" (|m| 0.9999999965) and noted that
    no stable gait was met. Each gait's ``stability_undecided`` is what the report and the
    JSON say, and a neutral multiplier (|m| = 1 to round-off) is why."""
    assert main(["powered", "--radius", "1", "--speed", "0.5", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["stability_undecided"] is True
    assert d["other_gaits"] and all(o["stability_undecided"] for o in d["other_gaits"])
    for m in [d["multipliers"][0]] + [o["spectral_radius"] for o in d["other_gaits"]]:
        assert abs(m - 1.0) < 1e-6  # the neutral family's multiplier
    assert main(["powered", "--radius", "1", "--speed", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "stable          undecided" in out
    assert "stable yes" not in out and "stable no" not in out
    assert "met no stable gait" not in out
