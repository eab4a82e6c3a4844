"""Walker models."""

from heelstrike.models.base import PlanarWalker, gravity_vector
from heelstrike.models.builder import BuiltWalker, load_walker
from heelstrike.models.compass import CompassGait, CompassPositions, heel_strike_state
from heelstrike.models.description import ModelDescriptionError

__all__ = [
    "BuiltWalker",
    "CompassGait",
    "CompassPositions",
    "ModelDescriptionError",
    "PlanarWalker",
    "gravity_vector",
    "heel_strike_state",
    "load_walker",
]
