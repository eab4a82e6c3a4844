"""Default settings of the analyses that the command line also offers, defined once.

The analysis functions' signatures and the CLI's options (with their help texts) read them
from here. The module imports nothing, so ``heelstrike --help`` stays cheap.
"""

from __future__ import annotations

__all__ = ["BASIN_STEPS", "BASIN_TOLERANCE", "BIFURCATION_RECORD", "BIFURCATION_TRANSIENT"]

#: Steps walked at each slope of a bifurcation diagram before recording (a discarded transient).
BIFURCATION_TRANSIENT = 50
#: Steps recorded at each slope of a bifurcation diagram (impact angle and duration of each).
BIFURCATION_RECORD = 16
#: Largest number of steps walked from each initial state of a basin of attraction.
BASIN_STEPS = 60
#: Convergence radius of a basin walk around the fixed point: the norm of the difference of the
#: section coordinates (rad and rad/s together).
BASIN_TOLERANCE = 1e-3
