"""
A bifurcation diagram: period doubling with the slope
=====================================================

The point-foot compass gait (``R = 0``) walks a stable period-one gait on gentle slopes; near
4.4 degrees its gait doubles its period (long and short steps alternate), and further on it
becomes chaotic. Here each slope is walked for a transient from the previous slope's last
state, then the next impact angles and step durations are recorded, with the compiled walker
(:func:`heelstrike.dynamics.compiled.ensemble_walk`); the period-one branch is continued by
Newton's method to mark where it loses stability
(:func:`heelstrike.analysis.limit_cycle.continue_limit_cycle`). A small grid keeps this quick;
``heelstrike bifurcation --slope 0.5deg:6deg --out bif`` draws a finer one.
"""

import numpy as np

from heelstrike.analysis.limit_cycle import (
    BifurcationDiagram,
    continue_limit_cycle,
    find_limit_cycle,
)
from heelstrike.dynamics.compiled import ensemble_walk
from heelstrike.models import CompassGait
from heelstrike.plots.gait import bifurcation_figure

walker = CompassGait(foot_radius=0.0)
slopes = np.deg2rad(np.linspace(3.0, 5.3, 47))
transient, record = 60, 16
z = find_limit_cycle(walker, slope=float(slopes[0]), method="compiled").fixed_point
angles = np.full((slopes.size, record), np.nan)
periods = np.full((slopes.size, record), np.nan)
for i, slope in enumerate(slopes):
    res = ensemble_walk(walker, z, float(slope), steps=transient + record)
    angles[i] = res.impact_angle[0, transient:]
    periods[i] = res.step_time[0, transient:]
    if res.ok[0]:
        z = res.z[0]
diagram = BifurcationDiagram(slopes=slopes, impact_angles=angles, periods=periods)

branch = continue_limit_cycle(walker, "slope", np.deg2rad(np.linspace(3.0, 5.3, 12)),
                              method="compiled")
print("period doubling at", np.rad2deg(branch.period_doubling).round(2), "deg")

fig = bifurcation_figure(diagram, branch, title="compass gait, R = 0: bifurcation diagram")
fig.savefig("bifurcation.png")
