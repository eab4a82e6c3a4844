"""The Python API refuses arguments that hung, crashed deep in numpy or gave an answer for
something that does not happen (QA sweep 12 of the API), naming the argument.

- ``simulate``: a NaN slope hung the compiled backend, ``atol=0`` hung scipy's first step,
  ``rtol=-1`` was taken, a slope of 3 (meant as degrees) walked 172 deg, ``friction=-1``
  "slipped", fractional or string step counts, array slopes and batches of walkers failed
  deep inside;
- ``find_limit_cycle`` and ``basin_of_attraction`` refuse a batch of walkers and array slopes,
  the basin a fractional grid;
- ``heel_strike_study`` refused nothing: a striking foot moving away from the ground (e.g.
  ``q3_dot < 0``) got a loss that never happens, and angles outside ``0 <= q3 < pi/2`` (the
  hip below the ground at 2 rad) an answer; a NaN angle was blamed on ``M``.
"""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike.analysis.basin import basin_of_attraction
from heelstrike.analysis.heel_strike import NotAHeelStrikeError, heel_strike_study
from heelstrike.analysis.limit_cycle import find_limit_cycle
from heelstrike.core.impact import ImpactInputError
from heelstrike.dynamics import simulate
from heelstrike.models.compass import CompassGait

WALKER = CompassGait(foot_radius=0.3)
SLOPE = float(np.deg2rad(3.0))
GAIT = [-0.38628396, 1.41932714, -0.96794436]  # the 3 deg gait's section point
BATCH = CompassGait(foot_radius=np.array([0.1, 0.3]))


@pytest.mark.parametrize("backend", ["scipy", "compiled"])
@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"slope": np.nan}, r"slope must be finite \(rad\), got nan"),
        ({"slope": np.array([SLOPE, SLOPE])}, r"slope must be one number \(rad\)"),
        ({"slope": [SLOPE]}, r"slope must be one number \(rad\)"),
        ({"slope": "0.05"}, r"slope must be one number \(rad\)"),
        ({"slope": 3.0}, r"slope 3 rad is 171\.887 deg, no incline to walk on \(slopes are in "
                         r"radians"),
        ({"atol": 0.0}, r"atol must be a finite tolerance > 0, got 0"),
        ({"rtol": 0.0, "atol": 0.0}, r"rtol must be a finite tolerance > 0, got 0"),
        ({"rtol": -1.0}, r"rtol must be a finite tolerance > 0, got -1"),
        ({"rtol": np.inf}, r"rtol must be a finite tolerance > 0, got inf"),
        ({"friction": -1.0}, r"friction must be a coefficient >= 0"),
        ({"friction": np.nan}, r"friction must be a coefficient >= 0"),
        ({"steps": 2.5}, r"steps must be >= 1 \(a whole number\), got 2\.5"),
        ({"steps": "3"}, r"steps must be >= 1 \(a whole number\), got '3'"),
        ({"steps": True}, r"steps must be >= 1 \(a whole number\), got True"),
    ],
)
def test_simulate_names_the_argument_it_refuses(backend, kwargs, message) -> None:
    q, qd = WALKER.section_to_state(GAIT)
    args = {"slope": SLOPE, "steps": 1, **kwargs}
    with pytest.raises(ValueError, match=f"^{message}"):
        simulate(WALKER, q, qd, backend=backend, **args)


@pytest.mark.parametrize("backend", ["scipy", "compiled"])
def test_simulate_takes_numpy_scalars_and_refuses_a_batch_of_walkers(backend) -> None:
    q, qd = WALKER.section_to_state(GAIT)
    walk = simulate(WALKER, q, qd, backend=backend, slope=np.float64(SLOPE), steps=np.int64(2),
                    friction=np.float64(np.inf), rtol=np.float32(1e-9), atol=1e-9)
    assert walk.ok and walk.n_steps == 2
    with pytest.raises(ValueError, match=r"^one walker is walked at a time, and this one has "
                       r"array parameters \(a batch of shape \(2,\)\)"):
        simulate(BATCH, q, qd, backend=backend, slope=SLOPE)


@pytest.mark.parametrize("method", ["scipy", "compiled"])
def test_gait_searches_refuse_batches_and_array_slopes(method) -> None:
    with pytest.raises(ValueError, match=r"^one walker is walked at a time"):
        find_limit_cycle(BATCH, slope=SLOPE, method=method)
    for slope in (np.array([0.05, 0.06]), [0.05]):
        with pytest.raises(ValueError, match=r"^slope must be one number \(rad\)"):
            find_limit_cycle(WALKER, slope=slope, method=method)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^rtol must be a finite tolerance > 0"):
        find_limit_cycle(WALKER, slope=SLOPE, method=method, rtol=0.0)


def test_basin_refuses_batches_and_fractional_grids() -> None:
    with pytest.raises(ValueError, match=r"^one walker is walked at a time"):
        basin_of_attraction(BATCH, SLOPE, grid=(3, 3), fixed_point=GAIT)
    with pytest.raises(ValueError, match=r"^grid must be two whole numbers, got \(3\.5, 4\)"):
        basin_of_attraction(WALKER, SLOPE, grid=(3.5, 4), fixed_point=GAIT)


@pytest.mark.parametrize("backend", ["scipy", "compiled"])
def test_heel_strike_study_refuses_what_is_no_heel_strike(backend) -> None:
    q3 = np.deg2rad(20.0)
    # the stance leg rotating backwards lifts the leading foot: its normal velocity is
    # > 0, computed here from the contact Jacobian independently of the study
    from heelstrike.models.compass import heel_strike_state

    q_pre, qd_pre = heel_strike_state(WALKER, q3, q3_dot=-1.0)
    vn = float((WALKER.contact_jacobian(q_pre, "left") @ qd_pre)[1])
    assert vn > 0.1
    with pytest.raises(NotAHeelStrikeError, match=r"moves away from the ground before the impact "
                       r"at 1 of 1 state\(s\) \(e\.g\. q3 = 0\.349066 rad, q3_dot = -1"):
        heel_strike_study(WALKER, q3, q3_dot=-1.0, backend=backend)
    # in a batch: named with the count, nothing computed
    with pytest.raises(NotAHeelStrikeError, match="at 1 of 2 state"):
        heel_strike_study(WALKER, q3, q3_dot=np.array([1.0, -1.0]), backend=backend)
    for angle, message in ((-0.3, r"got -0\.3 rad \(-17\.1887 deg\)"),
                           (2.0, r"got 2 rad \(114\.592 deg\)"),
                           (np.pi / 2, r"got 1\.5708 rad")):
        with pytest.raises(ImpactInputError, match=r"^impact_angle must satisfy 0 <= q3 < pi/2 "
                           f"rad .*{message}"):
            heel_strike_study(WALKER, angle, backend=backend)
    for bad in (np.nan, np.inf, None):
        with pytest.raises(ImpactInputError, match=r"^impact_angle must be finite \(rad\)"):
            heel_strike_study(WALKER, bad, backend=backend)  # type: ignore[arg-type]
    with pytest.raises(ImpactInputError, match=r"^q4_dot must be finite \(rad/s\)"):
        heel_strike_study(WALKER, q3, q4_dot=np.nan, backend=backend)
    # the paper's grid (q3 = 0 included, every radius up to the wheel) is all heel strikes
    grid = heel_strike_study(CompassGait(foot_radius=np.linspace(0.0, 1.0, 5)[:, None]),
                             np.linspace(0.0, 1.5, 31)[None, :], backend=backend)
    assert np.isfinite(grid.kinetic_energy_constrained).all()
