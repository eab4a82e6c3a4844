"""
A powered gait's energy books
=============================

On level ground nothing pays for the heel strike but the actuators. Here a push-off impulse
just before heel strike (Kuo 2002) drives a periodic gait at 0.5 m/s
(:func:`heelstrike.analysis.powered.find_powered_gait`); over one step the actuator work equals
the energy the collision destroys, ``W_act = T_c`` (paper eqs. 14-15).
"""

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from heelstrike.analysis.powered import find_powered_gait
from heelstrike.models import CompassGait

walker = CompassGait(foot_radius=0.3)
gait = find_powered_gait(walker, actuation="pushoff", speed=0.5)
print(f"push-off impulse {gait.actuation.parameter:.4f} {gait.actuation.parameter_unit}, "
      f"step length {gait.step_length:.3f} m, period {gait.period:.3f} s, stable: {gait.stable}")
print(f"W_act = {gait.actuator_work:.5f} J, T_c = {gait.collision_loss:.5f} J, "
      f"books balance to {gait.energy_balance_error:.1e} J")
print(f"cost of transport {gait.cost_of_transport:.4f}, eta = {gait.eta:.4f} J/m")

# %%
# The books as bars, and the energy along the step.
walk = gait.walk
T = walker.kinetic_energy(walk.q, walk.q_dot)
U = walker.potential_energy(walk.q, 0.0)

fig = Figure(figsize=(9, 3.6), layout="constrained")
FigureCanvasAgg(fig)
ax1, ax2 = fig.subplots(1, 2, width_ratios=[1, 2])
names = ["push-off\n$W_{act}$", "collision\n$T_c$"]
values = [gait.actuation.push_off_work, gait.collision_loss]
ax1.bar(names, values, color=["tab:green", "tab:red"], width=0.6)
ax1.set_ylabel("energy per step (J)")
ax1.set_title("energy books of one step", fontsize=10)
ax2.plot(walk.t, T, ".-", label="kinetic $T$")
ax2.plot(walk.t, U - U[0], ".-", label="potential $U - U(0)$")
ax2.plot(walk.t, T + U - U[0], "k", lw=2, label="total")
ax2.set_xlabel("time (s)")
ax2.set_ylabel("energy (J)")
ax2.legend(fontsize=8)
ax2.set_title("single support (level ground: the total is constant)", fontsize=10)
fig.savefig("powered_books.png")
assert np.isclose(gait.actuator_work, gait.collision_loss, rtol=1e-6)
