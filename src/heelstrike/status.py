"""How a solve ended: the one status vocabulary of every solver.

:class:`SolveStatus` is to solves what :class:`~heelstrike.dynamics.hybrid.WalkStatus` is to
walks (and basins): every member is its string name, carries a ``message`` for users and a
stable integer ``code``. The Newton engine (:func:`~heelstrike.analysis.newton.newton_solve`)
and its wrappers report members per start; the compiled, batched heel strike of the compass gait
(:func:`~heelstrike.models.compass_fast.heel_strike_impact`) writes member codes per item.

This module imports nothing of the package: every layer may use it.
"""

from __future__ import annotations

import re
from enum import StrEnum
from functools import cache
from typing import Any, Self

__all__ = ["CodedStatus", "SolveStatus", "check_codes"]


class CodedStatus(StrEnum):
    """A status vocabulary: members are their string names with a stable integer ``code``
    (what compiled kernels write) and a ``message`` for users. Subclasses (:class:`SolveStatus`,
    :class:`~heelstrike.dynamics.hybrid.WalkStatus`) only list their members as
    ``NAME = value, code, message``, with codes 0, 1, ... without gaps or repeats
    (:func:`check_codes`)."""

    code: int
    message: str

    # ``Status("converged")`` looks a member up by value (the defaults only let type checkers
    # accept that call).
    def __new__(cls, value: str, code: int = -1, message: str = "") -> Self:
        obj = str.__new__(cls, value)
        obj._value_ = value
        obj.code = code
        obj.message = message
        return obj

    @classmethod
    def from_code(cls, code: int) -> Self:
        """The member with integer code ``code`` (as written by a compiled kernel).

        Raises
        ------
        ValueError
            If no member has that code.
        """
        members = _members(cls)
        try:
            k = int(code)
        except (TypeError, ValueError):
            k = -1
        if 0 <= k < len(members) and members[k].code == k:  # codes are the definition order
            return members[k]
        what = re.sub(r"(?<!^)(?=[A-Z])", " ", cls.__name__).lower()  # "walk status"
        raise ValueError(f"no {what} has code {code!r}")

    @classmethod
    def names_by_code(cls) -> tuple[str, ...]:
        """Member names indexed by code: ``names_by_code()[s.code] == s.value``."""
        return tuple(s.value for s in cls)

    @classmethod
    def messages_by_code(cls) -> dict[int, str]:
        """``{code: message}`` of every member."""
        return {s.code: s.message for s in cls}


@cache
def _members(status: type[CodedStatus]) -> tuple[Any, ...]:
    """The members of a vocabulary in definition (= code) order, listed once."""
    return tuple(status)


def check_codes(status: type[CodedStatus]) -> None:
    """Refuse a vocabulary whose codes are not its definition order 0, 1, ... (checked once,
    where it is defined: :meth:`CodedStatus.from_code` relies on it)."""
    if [s.code for s in status] != list(range(len(status))):  # pragma: no cover
        raise RuntimeError(f"{status.__name__} codes must be 0, 1, ... in definition order")


class SolveStatus(CodedStatus):
    """How a solve ended (a Newton start, or one item of a compiled impact batch).

    Each member is its string name (``status == "converged"`` holds), carries a
    human-readable ``message`` and a stable integer ``code`` (what compiled kernels write;
    :meth:`from_code` converts back). Codes never change meaning; new statuses get new codes.

    Codes 1-7 are the input checks and the factorisation of the compiled compass heel strike
    (:func:`~heelstrike.models.compass_fast.heel_strike_impact`); codes 8-14 end a Newton start
    (:func:`~heelstrike.analysis.newton.newton_solve`). ``CONVERGED`` (0) is success for both.
    """

    CONVERGED = "converged", 0, "converged"
    NOT_FINITE = "not_finite", 1, "an input contains non-finite values (nan or inf)"
    BAD_MASS = "bad_mass", 2, "hip_mass and leg_mass must be > 0 (kg)"
    BAD_LENGTH = "bad_length", 3, "leg_length must be > 0 (m)"
    BAD_COM = "bad_com", 4, "leg_com_from_hip must satisfy 0 < b < leg_length (m)"
    BAD_RADIUS = "bad_radius", 5, "foot_radius must satisfy 0 <= R <= leg_length (m)"
    BAD_INERTIA = "bad_inertia", 6, "leg_inertia must be >= 0 (kg m^2)"
    SINGULAR_MASS_MATRIX = "singular_mass_matrix", 7, "reduced mass matrix is singular"
    STEP_FAILED = (
        "step_failed", 8, "the walker fails to take a step from the Newton iterate",
    )
    JACOBIAN_FAILED = "jacobian_failed", 9, "a step failed while estimating the Jacobian"
    SINGULAR = (
        "singular", 10, "singular Newton system (for a fixed point: a multiplier equals 1)",
    )
    STALLED = "stalled", 11, "Newton stalled (the line search found no better point)"
    SLOW = "slow", 12, "Newton converges too slowly"
    MAX_ITERATIONS = "max_iterations", 13, "Newton did not converge in the allowed iterations"
    TIME_LIMIT = "time_limit", 14, "time limit reached"


check_codes(SolveStatus)
