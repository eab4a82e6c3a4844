"""
A sweep on a Dask cluster
=========================

:func:`heelstrike.analysis.sweep.sweep` evaluates a vectorized function over the outer product
of named grids, chunk by chunk, and returns a labelled xarray Dataset. Here the heel-strike
energy split of the paper is swept over foot radius and impact angle on a
``dask.distributed`` :class:`~distributed.LocalCluster` (two single-threaded worker processes
on this machine; pass a scheduler address such as ``"tcp://host:8786"`` to use a real
cluster). Needs the ``scale`` extra
(``pip install '.[scale]'`` in a clone of heelstrike).
"""

import logging

import numpy as np
from distributed import LocalCluster

from heelstrike.analysis.heel_strike import heel_strike_study
from heelstrike.analysis.sweep import sweep
from heelstrike.models import CompassGait


def energy_split(foot_radius, impact_angle):
    """T_c and eta of the paper's heel strike (q3_dot = 1 rad/s, q4_dot = 0)."""
    s = heel_strike_study(CompassGait(foot_radius=foot_radius), impact_angle)
    return {"T_c": s.kinetic_energy_constrained, "eta": s.eta}


if __name__ == "__main__":
    logging.getLogger("distributed").setLevel(logging.ERROR)  # no cluster start/stop chatter
    grid = {"foot_radius": np.linspace(0.0, 1.0, 21), "impact_angle": np.deg2rad(
        np.linspace(1.0, 45.0, 45))}
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None, silence_logs=logging.CRITICAL) as cluster:
        ds = sweep(energy_split, grid, chunks={"foot_radius": 7}, scheduler=cluster,
                   progress=False, units={"T_c": "J", "eta": "J/m"})
    print(ds)

    # The result is labelled: select, reduce, plot.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(6.5, 4.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    mesh = ax.pcolormesh(np.rad2deg(ds["impact_angle"]), ds["foot_radius"], ds["eta"],
                         shading="nearest", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label="eta = T_c / L_S (J/m)")
    ax.set_xlabel("impact angle q3 (deg)")
    ax.set_ylabel("foot radius R (m)")
    ax.set_title("energy lost per metre, swept on a Dask LocalCluster", fontsize=10)
    fig.savefig("sweep_eta.png")
