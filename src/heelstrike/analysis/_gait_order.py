"""What "stable", "cheapest" and the order of gaits mean, defined once (issue 32).

Every command that finds several gaits (``gait``, ``powered``, ``study cost``, ``map``) reports
them in this order: the cheapest **stable** gait first, then the other stable ones, then the
unstable ones (marked as such); among ordinary steps first, a multi-swing gait (its swing foot
through the ground away from mid-stance, outside the scuffing convention) only after them.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["first_gait", "gait_order", "is_stable", "ordered_gaits", "spectral_radius",
           "stable_radius"]

_G = TypeVar("_G")


def spectral_radius(multipliers: ArrayLike) -> float:
    """Largest modulus of the Floquet multipliers (NaN for none).

    Parameters
    ----------
    multipliers : array_like of complex
        Floquet multipliers of a gait's step map.

    Returns
    -------
    float
    """
    m = np.abs(np.asarray(multipliers, dtype=complex))
    return float(np.max(m)) if m.size else float("nan")


def stable_radius(radius: Any) -> Any:
    """Whether a gait of this spectral radius is stable: ``radius < 1``, every Floquet
    multiplier strictly inside the unit circle (False for NaN: no gait). Elementwise for
    arrays (e.g. the ``spectral_radius`` of a map dataset)."""
    return radius < 1.0


def is_stable(multipliers: ArrayLike) -> bool:
    """Whether a gait with these Floquet multipliers is stable (:func:`stable_radius` of their
    :func:`spectral_radius`; False for none, or a non-finite one)."""
    return bool(stable_radius(spectral_radius(multipliers)))


def gait_order(gait: Any) -> tuple[bool, bool, float, float]:
    """Sort key of a gait: cheapest stable first.

    Parameters
    ----------
    gait : Gait
        Any gait with ``multipliers``, ``actuator_work`` (J per step; 0 for a passive gait)
        and ``multi_swing``; its ``stability_undecided`` (McGeer's wheel, ``R = l``: its gaits
        at one target form a neutral family, a multiplier of 1 to round-off; False if absent)
        leaves stability out of the key: the cheapest comes first.

    Returns
    -------
    tuple
        ``(multi_swing, not stable, actuator_work, spectral_radius)``: ordinary steps before
        multi-swing gaits, stable before unstable, then the least actuator work (the cheapest),
        then the most attracting (passive gaits all need no work).
    """
    rho = spectral_radius(gait.multipliers)
    unstable = False if getattr(gait, "stability_undecided", False) else not stable_radius(rho)
    return (bool(gait.multi_swing), unstable, float(gait.actuator_work),
            rho if np.isfinite(rho) else float("inf"))


def ordered_gaits(gaits: Iterable[_G]) -> list[_G]:
    """The gaits in the one reporting order (:func:`gait_order`): the first is the one a
    command reports, the cheapest stable gait where there is one.

    Parameters
    ----------
    gaits : iterable of Gait

    Returns
    -------
    list
    """
    return sorted(gaits, key=gait_order)


def first_gait(gaits: Sequence[_G]) -> _G:
    """The gait a command reports among ``gaits`` (non-empty): ``ordered_gaits(gaits)[0]``."""
    if not gaits:
        raise ValueError("no gaits to choose from")
    return min(gaits, key=gait_order)
