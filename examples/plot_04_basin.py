"""
A basin of attraction
=====================

Which post-impact states lead to the passive gait? Every point of a grid on the
``(q3, q3_dot)`` slice through the fixed point (``q4_dot`` held at its fixed-point value) is
walked for up to 40 steps with the compiled ensemble integrator, and coloured by its fate:
converged to the gait, still walking, or how it fell (a start whose trailing foot would sink
into the ground is not walked: ``inadmissible_start``)
(:func:`heelstrike.analysis.basin.basin_of_attraction`). A 60 x 60 grid takes seconds; the
command line's ``heelstrike basin --grid 400x400`` draws the fine one.
"""

import numpy as np

from heelstrike.analysis.basin import basin_of_attraction
from heelstrike.models import CompassGait
from heelstrike.plots.gait import basin_figure

walker = CompassGait(foot_radius=0.0)
basin = basin_of_attraction(walker, np.deg2rad(3.0), grid=(60, 60), steps=40)
print({k: round(v, 3) for k, v in basin.fractions().items()})

fig = basin_figure(basin)
fig.savefig("basin.png")
