"""
Your own walker in TOML: a kneed walker
=======================================

Walkers are described in TOML files: links, joints, feet and point masses, with named
parameters. ``heelstrike`` derives the equations of motion with sympy, and finds gaits with the
same tools as for the compass gait. Here the shipped ``kneed`` description (McGeer-style knees
that lock) is copied to a file, the foot radius in the copy's ``[params]`` changed from the
shipped 0.1 m to 0.2 m, and the passive gaits of both walkers found on the same slope
(:func:`heelstrike.models.builder.load_walker`,
:func:`heelstrike.analysis.model_gaits.find_model_gait`). Every impact of the step, knee strike
and heel strike, is an inert impact with its own ``T_c``. What it shows: on the same 2.9 deg
slope the walker with the larger feet takes longer steps (0.586 m against 0.524 m) and walks
faster (1.05 m/s against 0.93 m/s); each step releases more potential energy, and its impacts
lose exactly that much (about 0.46 J against 0.41 J).
"""

import importlib.resources
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.models.builder import load_walker

shipped = (importlib.resources.files("heelstrike") / "walkers" / "kneed.toml").read_text()
line = "R = 0.1      # foot radius (m)"
assert line in shipped  # the shipped file's default foot radius
text = shipped.replace(line, "R = 0.2      # foot radius (m)")  # your own copy: larger feet
Path("my_kneed.toml").write_text(text)  # edit links, masses, feet... as you like
print(text[text.index("[params]"):text.index("[[link]]")])

slope = 0.0504  # rad (2.9 deg)
gaits = {}
for label, path in (("shipped, R = 0.1 m", "kneed"), ("my_kneed.toml, R = 0.2 m",
                                                       "my_kneed.toml")):
    walker = load_walker(path)
    gait = find_model_gait(walker, slope=slope)
    gaits[label] = (walker, gait)
    print(f"{label}: period {gait.period:.4f} s, step length "
          f"{gait.step_length:.4f} m, speed {gait.speed:.3f} m/s, "
          f"stable: {gait.stable}")
    for imp in gait.impacts:
        print(f"  {imp.kind:12s} T_c = {imp.kinetic_energy_constrained:.6f} J")
    print(f"  losses {gait.collision_loss:.6f} J = potential energy released "
          f"{gait.potential_energy_released:.6f} J")

# %%
# The link angles over one step of the walker with the larger feet: the swing knee flexes, then
# locks at the knee strike.
walker, gait = gaits["my_kneed.toml, R = 0.2 m"]
walk = gait.walk
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
ax.set_title("kneed walker with 0.2 m feet: one step of its passive gait", fontsize=10)
fig.savefig("kneed.png")
