"""The cheapest *stable* gait first, everywhere, and every gait found listed (issue 32).

- ``study cost`` at R = 0.15 m, L = 0.6 m reported an unstable gait (spectral radius 1.27,
  1.370 J per step) as the cheapest, while a stable gait needing 1.356 J exists 1 % away: the
  seed gait's continuation to the target landed on the unstable one and no search met the
  other. Both are found now (deflated Newton beside the gaits found) and the stable one is
  kept and reported first.
- ``powered`` for a walker with very light legs (m = 0.1 kg, mH = 10 kg) at 0.5 m/s reported
  one gait; an unstable one needing 21 % less work exists beside it.

The gaits are checked by their own physics: periodic under the walker's own simulation, the
multipliers of the step map measured here by central differences, perturbations decaying on
the stable gait, the energy books closing (``W_act = T_c`` per step on level ground).
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from heelstrike.analysis._gait_order import gait_order, is_stable, ordered_gaits
from heelstrike.analysis.gaits import Gait
from heelstrike.analysis.powered import (
    actuation_family,
    family_simulator,
    powered_gaits,
    powered_step,
    preferred_gait,
)
from heelstrike.cli import main
from heelstrike.models.compass import CompassGait

Capture = pytest.CaptureFixture[str]


def _step(walker: CompassGait, gait: Gait, z: np.ndarray) -> np.ndarray:
    """One step of the walker with the gait's push-off from section point ``z``."""
    family = actuation_family(gait.actuation.name)
    torque, push_off = family.build(walker, gait.actuation.parameter)
    sim = family_simulator(walker, family, "compiled")
    st = powered_step(walker, z, torque, push_off, rtol=1e-11, atol=1e-11, simulator=sim)
    assert st.ok
    return st.z_next


def _check_gait(walker: CompassGait, gait: Gait) -> float:
    """Assert the gait's physics; return the spectral radius measured here."""
    z = np.asarray(gait.fixed_point, dtype=float)
    assert np.linalg.norm(_step(walker, gait, z) - z) < 1e-8  # periodic
    assert gait.actuator_work == pytest.approx(gait.collision_loss, rel=1e-6)  # W_act = T_c
    assert abs(gait.energy_change) < 1e-6 * gait.actuator_work
    h = 1e-5
    DP = np.column_stack([(_step(walker, gait, z + h * e) - _step(walker, gait, z - h * e))
                          / (2 * h) for e in np.eye(z.size)])
    rho = float(np.max(np.abs(np.linalg.eigvals(DP))))
    assert rho == pytest.approx(float(np.max(np.abs(gait.multipliers))), abs=1e-3)
    assert gait.stable is (rho < 1.0)
    return rho


def _decays(walker: CompassGait, gait: Gait, steps: int = 120) -> bool:
    """Whether a 1e-3 perturbation of the fixed point dies out under the walker's own steps."""
    z0 = np.asarray(gait.fixed_point, dtype=float)
    z = z0 + 1e-3 * np.ones(z0.size) / np.sqrt(z0.size)
    for _ in range(steps):
        z = _step(walker, gait, z)
    return bool(np.linalg.norm(z - z0) < 1e-4)


@pytest.mark.slow
def test_study_cost_keeps_the_stable_gait_at_r015_l06(tmp_path: Path, capsys: Capture) -> None:
    import xarray as xr

    walker = CompassGait(foot_radius=0.15)
    gaits = powered_gaits(0.15, step_length=0.6)
    assert len(gaits) >= 2
    first, *others = gaits
    assert first.stable and first.actuator_work == pytest.approx(1.356, abs=1e-3)
    assert _check_gait(walker, first) < 1.0 and _decays(walker, first)
    unstable = [g for g in others if not g.stable]
    assert unstable and min(g.actuator_work for g in unstable) == pytest.approx(1.370, abs=1e-3)
    for g in unstable:
        assert _check_gait(walker, g) > 1.0
    assert preferred_gait(gaits) is first
    for g in gaits:
        assert g.step_length == pytest.approx(0.6, abs=1e-8)
    # the study keeps it, as do powered's text and JSON
    assert main(["study", "cost", "--radius", "0.15:0.15:1", "--step-length", "0.6:0.6:1",
                 "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    with xr.open_dataset(tmp_path / "cost_study.nc") as ds:
        assert float(ds["actuator_work"].item()) == pytest.approx(first.actuator_work, rel=1e-6)
        assert float(ds["spectral_radius"].item()) < 1.0 and int(ds["stable"].item()) == 1
        assert int(ds["gaits_found"].item()) == len(gaits)
        assert "stable" in ds.attrs["branch_note"]
        # every gait found is listed, in the one order, the unstable ones marked
        listed = ds["gait_actuator_work"].values.ravel()
        n = int(np.isfinite(listed).sum())
        assert n == len(gaits)
        np.testing.assert_allclose(listed[:n], [g.actuator_work for g in gaits], rtol=1e-6)
        assert ds["gait_stable"].values.ravel()[:n].tolist() == [float(g.stable) for g in gaits]
        assert np.all(ds["gait_spectral_radius"].values.ravel()[1:n] > 1.0)
    assert main(["powered", "--radius", "0.15", "--step-length", "0.6", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["stable"] and d["actuator_work"] == pytest.approx(first.actuator_work, rel=1e-6)
    assert d["gaits_found"] == len(gaits) == 1 + len(d["other_gaits"])
    assert [o["stable"] for o in d["other_gaits"]] == [g.stable for g in others]


@pytest.mark.slow
def test_powered_finds_both_gaits_of_a_walker_with_light_legs(capsys: Capture) -> None:
    walker = CompassGait(leg_mass=0.1)  # mH = 10 kg
    gaits = powered_gaits(0.0, speed=0.5, walker=walker)
    assert len(gaits) == 2
    stable, cheap = gaits
    for g in gaits:
        assert g.speed == pytest.approx(0.5, abs=1e-8)
    # the cheaper one is unstable: the stable one stays first, the cheaper one is listed
    assert cheap.actuator_work == pytest.approx(0.79 * stable.actuator_work, rel=0.01)
    assert _check_gait(walker, stable) < 1.0 and _decays(walker, stable)
    assert _check_gait(walker, cheap) > 1.0
    assert main(["powered", "--leg-mass", "0.1", "--speed", "0.5", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["gaits_found"] == 2 and d["stable"]
    assert d["actuator_work"] == pytest.approx(stable.actuator_work, rel=1e-6)
    (other,) = d["other_gaits"]
    assert other["stable"] is False and other["spectral_radius"] > 1.0
    assert other["actuator_work"] == pytest.approx(cheap.actuator_work, rel=1e-6)
    assert main(["powered", "--leg-mass", "0.1", "--speed", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "2 distinct gaits meet this target" in out and "stable no" in out


def _fake(work: float, rho: float, multi: bool = False, undecided: bool = False
          ) -> SimpleNamespace:
    return SimpleNamespace(actuator_work=work, multipliers=np.array([rho, 0.1]),
                           multi_swing=multi, stability_undecided=undecided,
                           name=f"{work}/{rho}/{multi}")


def test_the_one_order_of_gaits() -> None:
    gaits = [_fake(1.0, 1.3), _fake(2.0, 0.5), _fake(1.5, 0.9), _fake(0.5, 0.99, True),
             _fake(0.8, 2.0)]
    names = [g.name for g in ordered_gaits(gaits)]
    # cheapest stable, other stable, unstable by work, a multi-swing gait last
    assert names == ["1.5/0.9/False", "2.0/0.5/False", "0.8/2.0/False", "1.0/1.3/False",
                     "0.5/0.99/True"]
    # passive gaits need no work: the most attracting stable gait first
    passive = [_fake(0.0, 0.8), _fake(0.0, 0.3), _fake(0.0, 1.1)]
    assert [g.multipliers[0] for g in ordered_gaits(passive)] == [0.3, 0.8, 1.1]
    assert is_stable([0.999]) and not is_stable([1.0]) and not is_stable([np.nan])
    assert gait_order(_fake(1.0, 1.0))[1] is True  # |m| = 1 is not stable
    # McGeer's wheel: stability undecided (a neutral family), the cheapest first
    wheel = [_fake(0.2, 0.999, undecided=True), _fake(0.0, 1.0 + 1e-9, undecided=True)]
    assert [g.actuator_work for g in ordered_gaits(wheel)] == [0.0, 0.2]
    decided = [_fake(0.2, 0.999), _fake(0.0, 1.0 + 1e-9)]
    assert [g.actuator_work for g in ordered_gaits(decided)] == [0.2, 0.0]


def test_gait_and_map_rank_passive_gaits_by_the_same_order() -> None:
    from heelstrike.analysis.limit_cycle import _preference

    for g in (_fake(0.0, 0.8), _fake(0.0, 1.1, True)):
        g.spectral_radius = float(np.max(np.abs(g.multipliers)))
        g.stable = is_stable(g.multipliers)
        assert _preference(g) == gait_order(g)
