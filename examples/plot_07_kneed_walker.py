"""
Your own walker in TOML: a kneed walker
=======================================

Walkers are described in TOML files: links, joints, feet and point masses, with named
parameters. ``heelstrike`` derives the equations of motion with sympy, and finds gaits with the
same tools as for the compass gait. Here the shipped ``kneed`` description (McGeer-style knees
that lock) is copied to a file, its foot radius changed, and its passive gait found
(:func:`heelstrike.models.builder.load_walker`,
:func:`heelstrike.analysis.model_gaits.find_model_gait`). Every impact of the step, knee strike
and heel strike, is an inert impact with its own ``T_c``.
"""

import importlib.resources
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.models.builder import load_walker

text = (importlib.resources.files("heelstrike") / "walkers" / "kneed.toml").read_text()
Path("my_kneed.toml").write_text(text)  # your own copy: edit links, masses, feet...
print(text[:600])

walker = load_walker("my_kneed.toml", R=0.1)
gait = find_model_gait(walker, slope=0.0504)
print(f"period {gait.cycle.period:.4f} s, step length {gait.cycle.step_length:.4f} m, "
      f"stable: {gait.cycle.stable}")
for imp in gait.impacts:
    print(f"{imp.kind:12s} T_c = {imp.kinetic_energy_constrained:.6f} J")
print(f"losses {gait.collision_loss:.6f} J = potential energy released "
      f"{gait.potential_energy_released:.6f} J")

# %%
# The link angles over one step: the swing knee flexes, then locks at the knee strike.
walk = gait.cycle.walk
angles = walker.link_angles(walk.q)
fig = Figure(figsize=(7, 4), layout="constrained")
FigureCanvasAgg(fig)
ax = fig.add_subplot()
for name, a in angles.items():
    ax.plot(walk.t, np.rad2deg(a), label=name.replace("_", " "))
for imp in gait.impacts:
    ax.axvline(imp.time, color="0.5", ls="--", lw=0.8)
    ax.text(imp.time, ax.get_ylim()[1], f" {imp.kind}", fontsize=8, va="top", rotation=90)
ax.set_xlabel("time (s)")
ax.set_ylabel("link angle from the vertical (deg)")
ax.legend(fontsize=8)
ax.set_title("kneed walker: one step of its passive gait", fontsize=10)
fig.savefig("kneed.png")
