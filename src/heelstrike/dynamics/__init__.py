"""Single support, events and hybrid simulation."""

from heelstrike.dynamics.events import Event
from heelstrike.dynamics.hybrid import (
    GroundReaction,
    ImpactRecord,
    WalkResult,
    WalkStatus,
    ground_reaction,
    heel_strike,
    simulate,
)
from heelstrike.dynamics.single_support import SingleSupport, TorqueLaw

__all__ = [
    "Event",
    "GroundReaction",
    "ImpactRecord",
    "SingleSupport",
    "TorqueLaw",
    "WalkResult",
    "WalkStatus",
    "ground_reaction",
    "heel_strike",
    "simulate",
]
