"""
The cost-of-transport map
=========================

How much work per metre and per newton of weight does a push-off walker need, for a range of
foot radii and step lengths? :func:`heelstrike.analysis.cost_study.cost_study` finds a powered
gait at every grid point (by continuation), and returns an xarray Dataset with the cost of
transport, ``eta`` and the actuator work; :func:`heelstrike.plots.powered.cost_figure` draws
it. Two foot radii and two step lengths here (integrator tolerances 1e-8, the radius grid
jumped in one continuation step) keep it to seconds; ``heelstrike study cost`` runs bigger
ones.
"""

import numpy as np

from heelstrike.analysis.cost_study import cost_study
from heelstrike.plots.powered import cost_figure, paper_comparison_figure

radii = np.array([0.0, 0.5])  # m
step_lengths = np.array([0.3, 0.5])  # m
ds = cost_study(radii, step_lengths, actuations=["pushoff"], radius_step=0.5, rtol=1e-8,
                atol=1e-8)
print(ds["cost_of_transport"].sel(actuation="pushoff").round(4).values)

fig = cost_figure(ds, "cost_of_transport")
fig.savefig("cost_of_transport.png")

# %%
# The paper's impact-only ``eta`` (pre-impact velocities imposed) against the work per metre
# the periodic gait actually needs.
fig = paper_comparison_figure(ds)
fig.savefig("paper_vs_gait.png")
