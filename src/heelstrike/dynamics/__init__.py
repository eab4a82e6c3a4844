"""Single support, events and hybrid simulation.

:func:`~heelstrike.dynamics.backends.simulate` is the one simulation entry point: every walker
on every backend it declares (:mod:`heelstrike.dynamics.backends`; ``backend="scipy"`` by
default, the numbers of :func:`heelstrike.dynamics.hybrid.simulate` for hand-written walkers).
"""

from heelstrike.dynamics.backends import BACKENDS, kernel_kind, simulate
from heelstrike.dynamics.events import Event
from heelstrike.dynamics.hybrid import (
    GroundReaction,
    ImpactRecord,
    WalkResult,
    WalkStatus,
    ground_reaction,
    heel_strike,
)
from heelstrike.dynamics.single_support import SingleSupport, TorqueLaw

__all__ = [
    "BACKENDS",
    "Event",
    "GroundReaction",
    "ImpactRecord",
    "SingleSupport",
    "TorqueLaw",
    "WalkResult",
    "WalkStatus",
    "ground_reaction",
    "heel_strike",
    "kernel_kind",
    "simulate",
]
