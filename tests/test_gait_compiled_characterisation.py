"""The compiled gait search characterises its gaits on the compiled backend (issue 9).

``find_limit_cycles(..., method="compiled")`` no longer re-simulates every gait with the scipy
reference: period, step length, energies and Floquet multipliers come from the compiled map and
the compiled pre-impact state. They must equal the scipy reference's characterisation of the
same gait to 1e-8; the trajectory (``Gait.walk``) is the scipy reference's, simulated on
first access. A described walker's gait (compiled step simulator throughout) must equal the
scipy reference's from the automatic guess too.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from heelstrike.analysis.gaits import Gait
from heelstrike.analysis.limit_cycle import find_limit_cycle, find_limit_cycles
from heelstrike.models import CompassGait

TOL = 1e-8
SLOPE = float(np.radians(3.0))
#: Characterisation values compared with the scipy reference (SI units, rad).
VALUES = (
    "period", "step_length", "speed", "impact_angle", "collision_loss", "kinetic_energy_pre",
    "kinetic_energy_admissible", "eta", "potential_energy_released", "actuator_work",
)
KNEED_SLOPE = 0.0504


@pytest.fixture(scope="module")
def compiled_gaits() -> tuple[Gait, ...]:
    return find_limit_cycles(CompassGait(foot_radius=0.3), slope=SLOPE, method="compiled")


def test_compiled_search_characterisation_equals_scipy_reference(
    compiled_gaits: tuple[Gait, ...],
) -> None:
    walker = CompassGait(foot_radius=0.3)
    assert len(compiled_gaits) >= 2  # the stable gait and the unstable long-step gait
    for got in compiled_gaits:
        ref = find_limit_cycle(walker, slope=SLOPE, guess=got.fixed_point, method="scipy")
        np.testing.assert_allclose(got.fixed_point, ref.fixed_point, rtol=0, atol=TOL)
        for name in VALUES:
            assert getattr(got, name) == pytest.approx(getattr(ref, name), rel=0, abs=TOL), name
        np.testing.assert_allclose(np.sort_complex(got.multipliers),
                                   np.sort_complex(ref.multipliers), rtol=0, atol=TOL)
        assert got.stable == ref.stable
        # the passive energy balance holds on the compiled characterisation too
        assert got.potential_energy_released == pytest.approx(got.collision_loss, abs=TOL)
        assert got.kinetic_energy_pre == pytest.approx(
            got.collision_loss + got.kinetic_energy_admissible, abs=TOL)


def test_compiled_guess_path_characterisation_equals_search(
    compiled_gaits: tuple[Gait, ...],
) -> None:
    """``find_limit_cycle(guess=...)`` on the compiled map characterises on the compiled
    backend too, and agrees with the search's gait."""
    best = compiled_gaits[0]
    again = find_limit_cycle(CompassGait(foot_radius=0.3), slope=SLOPE, method="compiled",
                             guess=best.fixed_point)
    for name in VALUES:
        assert getattr(again, name) == pytest.approx(getattr(best, name), rel=0, abs=TOL), name
    np.testing.assert_allclose(again.multipliers, best.multipliers, rtol=0, atol=TOL)


def test_walk_of_a_compiled_gait_is_the_scipy_period_on_demand(
    compiled_gaits: tuple[Gait, ...],
) -> None:
    c = compiled_gaits[0]
    assert "_walk_value" in vars(c) and not hasattr(vars(c)["_walk_value"], "impacts")
    walk = c.walk  # simulated now, with the scipy reference
    assert walk is c.walk  # and kept
    assert walk.ok and walk.n_steps == 1
    rec = walk.impacts[0]
    assert rec.step_duration == pytest.approx(c.period, abs=TOL)
    assert rec.energy_lost == pytest.approx(c.collision_loss, abs=TOL)
    assert rec.step_length == pytest.approx(c.step_length, abs=TOL)
    # one scipy period from the compiled fixed point comes back to it
    z1 = CompassGait(foot_radius=0.3).state_to_section(walk.final_q, walk.final_q_dot)
    np.testing.assert_allclose(z1, c.fixed_point, rtol=0, atol=TOL)
    with pytest.raises(dataclasses.FrozenInstanceError):
        c.walk = walk  # type: ignore[misc]


def test_limit_cycle_needs_a_walk(compiled_gaits: tuple[Gait, ...]) -> None:
    c = compiled_gaits[0]
    fields = {f.name: getattr(c, f.name) for f in dataclasses.fields(c) if f.name != "walk"}
    with pytest.raises(TypeError, match="walk"):
        Gait(**fields)
    given = Gait(**fields, walk=c.walk)
    assert given.walk is c.walk


@pytest.mark.slow  # the scipy reference's automatic search of the kneed walker (~10 s)
def test_kneed_automatic_gait_same_on_both_backends() -> None:
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.models import load_walker

    w = load_walker("kneed")
    got = find_model_gait(w, slope=KNEED_SLOPE, backend="compiled")
    ref = find_model_gait(w, slope=KNEED_SLOPE, backend="scipy")
    np.testing.assert_allclose(got.fixed_point, ref.fixed_point, rtol=0, atol=TOL)
    for name in ("period", "step_length", "collision_loss", "potential_energy_released"):
        assert getattr(got, name) == pytest.approx(getattr(ref, name), abs=TOL)
    assert got.collision_loss == pytest.approx(ref.collision_loss, abs=TOL)
    np.testing.assert_allclose([e.kinetic_energy_constrained for e in got.impacts],
                               [e.kinetic_energy_constrained for e in ref.impacts], atol=TOL)
