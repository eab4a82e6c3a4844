"""
Designing a foot for the paper's walker
=======================================

The paper's compass walker (``mH = 10 kg``, ``m = 5 kg``, ``l = 1 m``, ``b = 0.5 m``) with a
convex foot profile ``h(phi) = R (1 - cos phi) + d sin phi + k2 (1 - cos 2 phi) + ...``
(``examples/walkers/compass_foot6.toml``, six coefficients; :doc:`/design`). On a passive gait
the collision loss per metre is ``M g sin(slope)`` whatever the foot, so the foot is designed
for the gait's kinematics: the fastest passive gait on a 0.05 rad slope, over the base radius
``R`` and the ``1 - cos 2 phi`` coefficient ``k2`` (``k2 > 0`` flattens the sole under the leg
and rounds its ends: the radius of curvature is ``R + k2 (1 + 3 cos 2 phi)``), with SLSQP and
the implicit-function-theorem gradients of
:func:`heelstrike.analysis.design_gradients.gait_gradients`. The command line does the same
(with all six coefficients if asked)::

    heelstrike design --model examples/walkers/compass_foot6.toml --slope 0.05 \
        --vary R=0.2:0.4 --vary k2=-0.01:0.01 --cost=-speed --out DIR

Both parameters end on their upper bounds: a larger base radius and a sole flatter under the
leg walk faster (and, here, more stably).
"""

from pathlib import Path

import numpy as np

from heelstrike.analysis.design import design
from heelstrike.models.builder import load_walker
from heelstrike.plots.design import cost_history_figure, foot_figure

# the walker file next to this script (sphinx-gallery runs it from its own folder)
here = Path(__file__).resolve().parent if "__file__" in globals() else Path.cwd()
foot6 = next(p for p in (here / "walkers" / "compass_foot6.toml",
                         here / "examples" / "walkers" / "compass_foot6.toml") if p.is_file())
walker = load_walker(foot6)
res = design(walker, vary={"R": (0.2, 0.4), "k2": (-0.01, 0.01)}, cost="-speed", slope=0.05,
             max_iter=8)
print(f"{res.status.value}: {res.message}")
for name, a, b in zip(res.parameters, res.start.values, res.final.values, strict=True):
    print(f"{name}: {a:.5g} -> {b:.5g}")
print(f"speed {res.start.fields['speed']:.4f} -> {res.final.fields['speed']:.4f} m/s, "
      f"spectral radius {res.start.fields['spectral_radius']:.3f} -> "
      f"{res.final.fields['spectral_radius']:.3f}; on a bound: {res.active_bounds}")
print("eta (J/m), the same for every design:",
      np.round([it.fields["eta"] for it in res.history], 9))

# %%
# The cost (minus the speed) at each iterate, and the sole before and after.
fig = cost_history_figure(res)
fig.savefig("design_cost.png")

# %%
fig = foot_figure(res)
fig.savefig("design_foot.png")
