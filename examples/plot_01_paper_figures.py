"""
The paper's Figs. 2 and 3
=========================

Kinetic energy at heel strike split into the part the collision destroys (``T_c``) and the part
it keeps (``T_a``) over the impact angle ``q3`` for five foot radii (Fig. 2), the energy lost
per metre walked ``eta = T_c / L_S`` (Fig. 3a), and ``eta`` over ``(q3, R)`` with the region
where the trailing foot does not lift left white (Fig. 3b). The data come from
:mod:`heelstrike.analysis.paper` as pandas DataFrames; :mod:`heelstrike.plots.paper` draws them.
"""

from heelstrike.analysis.paper import paper_figure_data
from heelstrike.plots.paper import figure2, figure3a, figure3b

data = paper_figure_data()  # the paper's walker: mH = 2 m = 10 kg, a = b = 0.5 m, l = 1 m
print(data.figure2.head())

fig2 = figure2(data.figure2)
fig2.savefig("fig2.png")

# %%
# Fig. 3a: ``eta`` (J/m) against ``q3``. Shorter steps lose less per metre.
fig3a = figure3a(data.figure3a)
fig3a.savefig("fig3a.png")

# %%
# Fig. 3b: ``eta`` over ``(q3, R)``; above ``R`` of about 0.4 m the trailing foot lifts for every
# impact angle up to 45 degrees.
fig3b = figure3b(data.figure3b)
fig3b.savefig("fig3b.png")
