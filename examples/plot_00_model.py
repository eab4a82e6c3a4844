"""
The model: the compass gait with circular feet
==============================================

The walker of the paper (its Fig. 1): two straight legs of length ``l`` and mass ``m`` (centre
of mass ``b`` below the hip, ``a = l - b`` above the foot's lowest point), a hip point mass
``mH`` and circular feet of radius ``R``. The generalized coordinates are the position
``(q1, q2)`` of the right foot's arc centre ``P_R``, the right leg's absolute angle ``q3``
(from the vertical, counter-clockwise positive) and the angle ``q4`` of the left leg relative
to the right one.
"""

import numpy as np

from heelstrike.models import CompassGait
from heelstrike.plots.gait import model_diagram

walker = CompassGait(foot_radius=0.3)  # the paper's l = 1 m, a = b = 0.5 m, mH = 2 m = 10 kg
fig = model_diagram(walker)
fig.savefig("model.png")

# %%
# The mass matrix ``M(q)`` of eq. (1) and the swing foot's contact Jacobian ``A_L`` at the drawn
# configuration (``q3 = 0.32 rad``, ``q4 = -0.72 rad``; eq. (5) is its value at heel strike,
# ``q4 = -2 q3``):
q = np.array([0.9, 0.3, 0.32, -0.72])
print("M(q) =\n", walker.mass_matrix(q).round(3))
print("A_L(q) =\n", walker.contact_jacobian(q, "left").round(3))
