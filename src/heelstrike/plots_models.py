"""Figures of the heel-strike study for any described walker (see
:func:`heelstrike.analysis.model_gaits.impact_map`): ``T_c``, ``T_a`` and ``eta`` over two swept
quantities, with the boundary of admissible impacts (trailing foot lifts) drawn dashed."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from heelstrike.analysis.model_gaits import ANGLE, ImpactMap

__all__ = ["write_impact_map"]


def _label(name: str) -> str:
    return "impact angle (deg)" if name == ANGLE else name


def _axis(m: ImpactMap, name: str, values: np.ndarray) -> np.ndarray:
    return np.degrees(values) if name == ANGLE else values


def write_impact_map(m: ImpactMap, out_dir: str | Path) -> list[Path]:
    """Write ``impact_map.png`` (three panels) and ``impact_map.csv`` (one row per point).

    Parameters
    ----------
    m : ImpactMap
    out_dir : str or Path
        Created if needed.

    Returns
    -------
    list of Path
        The files written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    csv_path = out / "impact_map.csv"
    with csv_path.open("w", newline="", encoding="utf-8") as fh:
        wr = csv.writer(fh)
        wr.writerow([m.x_name, m.y_name, "T_J", "T_c_J", "T_a_J", "eta_J_per_m",
                     "step_length_m", "trailing_normal_velocity_m_per_s", "trailing_foot_lifts"])
        for i, yy in enumerate(m.y):
            for j, xx in enumerate(m.x):
                wr.writerow([repr(float(xx)), repr(float(yy)), repr(float(m.T[i, j])),
                             repr(float(m.T_c[i, j])), repr(float(m.T_a[i, j])),
                             repr(float(m.eta[i, j])), repr(float(m.step_length[i, j])),
                             repr(float(m.trailing_normal_velocity[i, j])), int(m.lifts[i, j])])
    X, Y = np.meshgrid(_axis(m, m.x_name, m.x), _axis(m, m.y_name, m.y))
    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2), constrained_layout=True)
    for ax, (title, Z) in zip(
        axes, (("$T_c$ (J)", m.T_c), ("$T_a$ (J)", m.T_a), (r"$\eta$ (J/m)", m.eta)),
        strict=True,
    ):
        if m.x.size > 1 and m.y.size > 1:
            pc = ax.pcolormesh(X, Y, np.ma.masked_invalid(Z), shading="auto", cmap="viridis")
            fig.colorbar(pc, ax=ax)
            v = m.trailing_normal_velocity
            if np.any(np.isfinite(v)) and np.nanmin(v) < 0 < np.nanmax(v):
                ax.contour(X, Y, v, levels=[0.0], colors="w", linestyles="--")
        else:
            ax.plot(X.ravel() if m.x.size > 1 else Y.ravel(), Z.ravel(), "o-")
        ax.set_title(title)
        ax.set_xlabel(_label(m.x_name))
        ax.set_ylabel(_label(m.y_name))
    fig.suptitle(f"heel strike of '{m.walker_name}' (dashed: trailing foot lift boundary)")
    png = out / "impact_map.png"
    fig.savefig(png, dpi=120)
    plt.close(fig)
    return [png, csv_path]
