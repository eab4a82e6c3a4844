"""The powered search starts from seeds scaled to the walker, and its hints fit the actuation.

- The seed section points were chosen for ``g = 9.81 m/s^2`` and ``l = 1 m``; their rates are
  scaled by the walker's ``sqrt(g / l)``. On the Moon-like ``g = 3.7`` the unscaled seeds made
  the walker leave the ground at once and ``heelstrike powered --gravity 3.7`` found no gait
  at any speed (while ``--model compass --gravity 3.7``, seeded by its passive gaits, did).
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
    assert abs(g.push_off_work - g.collision_loss) < 1e-8
    m_total = float(w.total_mass)
    assert g.cost_of_transport == pytest.approx(
        g.actuator_work / (m_total * gravity * g.step_length), rel=1e-12)


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
