"""One solve vocabulary (issue #32, item 6): :class:`SolveStatus` carries every solve outcome's
message and integer code, for the Newton engine, its wrappers and the compiled compass heel
strike's per-item status."""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike.analysis.gait_map import NewtonGait, newton_gait, newton_gaits
from heelstrike.analysis.limit_cycle import GaitNotFoundError
from heelstrike.analysis.newton import newton_solve
from heelstrike.core.impact import ImpactInputError
from heelstrike.models import compass_fast
from heelstrike.models.compass import CompassGait
from heelstrike.status import SolveStatus

SLOPE3 = np.deg2rad(3.0)
Z3 = np.array([-0.27102868, 1.09238359, -0.71500964])
#: A start from which the compass gait takes no step: it falls backward at once.
NO_STEP = np.array([-0.3, 0.2, 0.0])


def test_every_code_round_trips_and_every_member_has_its_message() -> None:
    assert sorted(s.code for s in SolveStatus) == list(range(len(SolveStatus)))
    for s in SolveStatus:
        assert SolveStatus.from_code(s.code) is s
        assert SolveStatus.from_code(np.uint8(s.code)) is s  # as a kernel writes it
        assert SolveStatus(s.value) is s and s == s.value
        assert SolveStatus.messages_by_code()[s.code] == s.message
    messages = [s.message for s in SolveStatus]
    assert all(isinstance(m, str) and m for m in messages)
    assert len(set(messages)) == len(messages)


@pytest.mark.parametrize("bad", [-1, len(SolveStatus), 255])
def test_unknown_code_is_refused(bad: int) -> None:
    with pytest.raises(ValueError, match="no solve status has code"):
        SolveStatus.from_code(bad)


def test_the_compiled_heel_strike_writes_member_codes() -> None:
    pairs = {"_OK": SolveStatus.CONVERGED, "_NOT_FINITE": SolveStatus.NOT_FINITE,
             "_BAD_MASS": SolveStatus.BAD_MASS, "_BAD_LENGTH": SolveStatus.BAD_LENGTH,
             "_BAD_COM": SolveStatus.BAD_COM, "_BAD_RADIUS": SolveStatus.BAD_RADIUS,
             "_BAD_INERTIA": SolveStatus.BAD_INERTIA,
             "_SINGULAR": SolveStatus.SINGULAR_MASS_MATRIX}
    for name, member in pairs.items():
        const = getattr(compass_fast, name)
        assert type(const) is int and const == member.code, name
    assert not hasattr(compass_fast, "_MESSAGES")
    # the pure-Python strike (what the kernel compiles) returns the member's code, and the
    # batch reports the member's message with the item's index
    assert compass_fast._strike(0.2, 1.5, 0.0, 0.0, 1.0, 0.0, 2.0, 0.5, 1.0, 0.5, 0.0,
                                0.0)[0] == SolveStatus.BAD_RADIUS.code
    radius = np.full(5, 0.2)
    radius[3] = 1.5
    with pytest.raises(ImpactInputError) as info:
        compass_fast.heel_strike_impact(0.2, foot_radius=radius)
    assert str(info.value).startswith(f"{SolveStatus.BAD_RADIUS.message} (flat batch index 3;")


def test_newton_engine_reports_members() -> None:
    # x^2 = 4 converges from 3; a residual that is NaN at the start is a failed step
    sol = newton_solve(lambda X: np.where(X > -5, X * X - 4.0, np.nan),
                       np.array([[3.0], [-6.0]]), tol=1e-12)
    assert sol.status == (SolveStatus.CONVERGED, SolveStatus.STEP_FAILED)
    assert all(isinstance(s, SolveStatus) for s in sol.status)
    assert sol.message(1).startswith(SolveStatus.STEP_FAILED.message)
    np.testing.assert_allclose(sol.x[0], [2.0], rtol=1e-10)


def test_newton_gaits_returns_a_gait_or_a_member_per_start() -> None:
    """The scipy map: the paper's start converges to the 3 deg gait (period and fixed point
    of the compiled map agree to the search tolerance); a start that falls backward is
    STEP_FAILED after one evaluation, a member (not a free-text string)."""
    out = newton_gaits(CompassGait(), SLOPE3, np.stack([Z3, NO_STEP]), backend="scipy")
    gait, failed = out
    assert isinstance(gait, NewtonGait)
    np.testing.assert_allclose(gait.z, Z3, atol=1e-6)
    assert gait.residual < 1e-10
    assert failed is SolveStatus.STEP_FAILED
    # the single-start wrapper raises with the engine's message (the iterate named)
    with pytest.raises(GaitNotFoundError, match=r"^the walker fails to take a step from the "
                       r"Newton iterate \(q3 = -0\.3 rad"):
        newton_gait(CompassGait(), SLOPE3, NO_STEP, backend="scipy")
