"""heelstrike: impulsive dynamics and energetics of walking machines.

Layers (imports point one way): :mod:`heelstrike.cli` -> :mod:`heelstrike.analysis` ->
:mod:`heelstrike.dynamics` -> :mod:`heelstrike.models` -> :mod:`heelstrike.core`.
"""

from importlib.metadata import PackageNotFoundError, version

from heelstrike.core import ImpactResult, impact
from heelstrike.dynamics import WalkResult, WalkStatus, simulate
from heelstrike.models import CompassGait, heel_strike_state

try:
    __version__ = version("heelstrike")
except PackageNotFoundError:  # pragma: no cover
    __version__ = "0.0.0"

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
