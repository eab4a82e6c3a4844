"""
A passive gait and its stability
================================

Find the period-one gait of the circular-feet compass gait walking down a 3 degree slope with
Newton's method on the Poincare map (:func:`heelstrike.analysis.limit_cycle.find_limit_cycle`,
the compiled step map for speed), read its Floquet multipliers, and look at the walk: a
stick-figure strobe of one step, the phase portrait, the joint angles and ground reaction over a
step, and the mechanical energy, constant between impacts and dropping by ``T_c`` at every heel
strike. :mod:`heelstrike.analysis.walk_tables` turns the walk into tables and
:mod:`heelstrike.plots.gait` draws them (``heelstrike walk --out DIR`` writes the same figures
with their data as CSV, through :func:`heelstrike.outputs.write_walk_figures`).
"""

import numpy as np

from heelstrike.analysis.limit_cycle import PoincareMap, find_limit_cycle
from heelstrike.analysis.walk_tables import (
    phase_portrait_table,
    step_table,
    strobe_table,
    walk_energy_table,
    walk_impact_table,
)
from heelstrike.models import CompassGait
from heelstrike.plots.gait import (
    energy_figure,
    phase_portrait_figure,
    step_figure,
    strobe_figure,
)

walker = CompassGait(foot_radius=0.3)
slope = np.deg2rad(3.0)
cycle = find_limit_cycle(walker, slope=slope, method="compiled")
print(f"period {cycle.period:.4f} s, step length {cycle.step_length:.4f} m, "
      f"speed {cycle.speed:.3f} m/s")
print("|Floquet multipliers|:", np.abs(cycle.multipliers).round(3), "stable:", cycle.stable)
print(f"T_c per step {cycle.collision_loss:.4f} J = potential energy released "
      f"{cycle.potential_energy_released:.4f} J")

# %%
# Walk four steps from the fixed point and draw one step, strobed.
walk = PoincareMap(walker=walker, slope=slope, rtol=1e-10, atol=1e-10, max_step=0.02).walk(
    cycle.fixed_point, 4
)
fig = strobe_figure(strobe_table(walker, walk), foot_radius=0.3, slope=slope)
fig.savefig("strobe.png")

# %%
# The phase portrait: every step traces the same loop.
fig = phase_portrait_figure(phase_portrait_table(walk))
fig.savefig("phase_portrait.png")

# %%
# Joint angles and the ground's force on the stance foot over the first step: the normal force
# stays positive (the foot does not leave the ground) and the friction the step needs is the
# ratio of the tangential to the normal force.
fig = step_figure(step_table(walker, walk))
fig.savefig("step.png")

# %%
# Energy books: the total is constant in single support and drops by ``T_c`` at heel strike.
impacts = walk_impact_table(walker, walk)
print(impacts[["step", "drop_J", "T_c_J"]])
fig = energy_figure(walk_energy_table(walker, walk), impacts)
fig.savefig("energy.png")
