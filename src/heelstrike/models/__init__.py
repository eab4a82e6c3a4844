"""Walker models."""

from heelstrike.models.base import PlanarWalker, gravity_vector
from heelstrike.models.compass import CompassGait, CompassPositions, heel_strike_state

__all__ = ["CompassGait", "CompassPositions", "PlanarWalker", "gravity_vector", "heel_strike_state"]
