"""The powered search starts from seeds scaled to the walker, and its hints fit the actuation.

- The seed section points were chosen for ``g = 9.81 m/s^2`` and ``l = 1 m``; their rates are
  scaled by the walker's ``sqrt(g / l)``. On the Moon-like ``g = 3.7`` the unscaled seeds made
  the walker leave the ground at once and ``heelstrike powered --gravity 3.7`` found no gait
  at any speed (while ``--model compass --gravity 3.7``, seeded by its passive gaits, did).
- The hip-energy seed energies are those of the scaled seed section too: computed from the
  unscaled one, the target energies on ``g = 3.7`` were far above the walker's gaits and
  ``powered --actuation hip-energy --gravity 3.7 --speed 0.3`` (Froude-equivalent to 0.5 m/s
  on Earth) found none, on both backends.
- A compass gait with a light hip (``mH = 4 kg``) has no push-off seed gait on level ground:
  ``powered --hip-mass 4`` found no gait at 0.3-0.5 m/s, while ``powered --model compass
  --param mH=4`` (the same walker, with a slope homotopy from its passive gait) did. The
  compass search now has that homotopy too (:func:`passive_gait_finder`), and both commands
  give the same gait.
- A failure message suggests "other gains" only for actuations with gains (the hip laws, a
  posture law), not for the push-off alone.
"""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike.analysis.powered import PoweredGaitNotFoundError, find_powered_gait
from heelstrike.models.compass import CompassGait


@pytest.mark.parametrize("gravity", [3.7, 24.8])
def test_gait_found_at_other_gravity(gravity: float) -> None:
    w = CompassGait(gravity=gravity)
    g = find_powered_gait(w, speed=0.5)
    assert abs(g.speed - 0.5) < 1e-8 and g.residual < 1e-8
    # periodic level gait: the push-off work is the collision loss, and the cost of transport
    # uses this walker's gravity
    assert abs(g.actuation.push_off_work - g.collision_loss) < 1e-8
    m_total = float(w.total_mass)
    assert g.cost_of_transport == pytest.approx(
        g.actuator_work / (m_total * gravity * g.step_length), rel=1e-12)


def test_hip_energy_gait_found_on_the_moon() -> None:
    from heelstrike.analysis.powered import actuation_family, family_simulator

    w = CompassGait(gravity=3.7)
    family = actuation_family("hip-energy")
    sim = family_simulator(w, family, None)
    g = find_powered_gait(w, actuation=family, speed=0.3, simulator=sim)
    assert abs(g.speed - 0.3) < 1e-8 and g.residual < 1e-8
    assert g.actuator_work == pytest.approx(g.collision_loss, abs=1e-8)  # eqs. 14-15
    # the seeds of the reference walker are unchanged (scale factor 1)
    ref = CompassGait()
    q, qd = ref.section_to_state(np.asarray((-0.25, 1.1, -0.45)))
    E = float(ref.mechanical_energy(q, qd))
    assert family.seed(ref)[0] == pytest.approx(E + 0.005 * float(ref.total_mass) * 9.81,
                                                rel=1e-12)


def test_light_hip_compass_reaches_level_ground_by_the_slope_homotopy() -> None:
    from heelstrike.analysis.powered import (
        actuation_family,
        family_simulator,
        find_model_powered_gait,
        passive_gait_finder,
    )
    from heelstrike.models.builder import load_walker

    w = CompassGait(hip_mass=4.0)
    family = actuation_family("pushoff")
    sim = family_simulator(w, family, None)
    with pytest.raises(PoweredGaitNotFoundError, match="none of the 3 seed impulse"):
        find_powered_gait(w, actuation=family, speed=0.5, simulator=sim)  # no homotopy
    g = find_powered_gait(w, actuation=family, speed=0.5, simulator=sim,
                          passive_gait=passive_gait_finder(w, family, sim))
    ref = find_model_powered_gait(load_walker("compass", mH=4.0), speed=0.5)
    np.testing.assert_allclose(g.fixed_point, ref.fixed_point, atol=1e-8)
    assert g.actuation.parameter == pytest.approx(ref.actuation.parameter, abs=1e-8)
    assert g.actuator_work == pytest.approx(g.collision_loss, abs=1e-8)  # eqs. 14-15
    # the hip laws act at every parameter value: no passive start for them
    for name in ("hip-energy", "hip-pd"):
        fam = actuation_family(name)
        assert passive_gait_finder(w, fam, family_simulator(w, fam, None)) is None


def test_cli_powered_light_hip_finds_the_gait(capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from heelstrike.cli import main

    assert main(["powered", "--hip-mass", "4", "--speed", "0.5", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["speed"] == pytest.approx(0.5, abs=1e-8)
    assert d["actuator_work"] == pytest.approx(d["collision_loss"], abs=1e-8)


def test_reference_walker_seeds_are_unchanged() -> None:
    from heelstrike.analysis.powered import _SEED_SECTIONS, _scaled_seed_sections

    assert _scaled_seed_sections(CompassGait()) == _SEED_SECTIONS
    slow = _scaled_seed_sections(CompassGait(gravity=9.81 / 4))
    assert np.allclose(np.asarray(slow)[:, 1:], 0.5 * np.asarray(_SEED_SECTIONS)[:, 1:])


@pytest.mark.parametrize(("actuation", "gains"), [("pushoff", False), ("hip-pd", True)])
def test_failure_hint_fits_the_actuation(actuation: str, gains: bool) -> None:
    falling = ((0.0, 0.0, 0.0),)  # a standing walker: no seed step, so no first gait
    with pytest.raises(PoweredGaitNotFoundError) as info:
        find_powered_gait(CompassGait(), actuation=actuation, speed=0.5,
                          seed_sections=falling, fallback=False)
    msg = str(info.value)
    assert "no periodic" in msg and "starting guess" in msg
    assert ("other gains" in msg) == gains
