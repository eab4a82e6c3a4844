"""heelstrike: impulsive dynamics and energetics of walking machines.

Layers (imports point one way): :mod:`heelstrike.cli` -> :mod:`heelstrike.analysis` ->
:mod:`heelstrike.dynamics` -> :mod:`heelstrike.models` -> :mod:`heelstrike.core`.

The simulation names (:func:`simulate`, :class:`WalkResult`, :class:`WalkStatus`) are imported
on first use, so that ``import heelstrike`` (and ``heelstrike --help``) does not load
``scipy.integrate``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from heelstrike._version import __version__
from heelstrike.core import ImpactResult, impact
from heelstrike.models import CompassGait, heel_strike_state

if TYPE_CHECKING:
    from heelstrike.dynamics import WalkResult, WalkStatus, simulate


_LAZY = {"WalkResult", "WalkStatus", "simulate"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import heelstrike.dynamics

        return getattr(heelstrike.dynamics, name)
    raise AttributeError(f"module 'heelstrike' has no attribute {name!r}")


__all__ = [
    "CompassGait",
    "ImpactResult",
    "WalkResult",
    "WalkStatus",
    "__version__",
    "heel_strike_state",
    "impact",
    "simulate",
]
