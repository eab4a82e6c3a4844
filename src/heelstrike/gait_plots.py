"""Figures and animations of gaits: walking animation, bifurcation diagram.

Drawing only: the data come from :mod:`heelstrike.dynamics` and :mod:`heelstrike.analysis`.
Uses matplotlib's object API with the Agg canvas (no global pyplot state).
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter
from matplotlib.artist import Artist
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from numpy.typing import NDArray

from heelstrike.analysis.basin import OUTCOMES, Basin
from heelstrike.analysis.gait_map import GaitMap
from heelstrike.analysis.limit_cycle import (
    BifurcationDiagram,
    Continuation,
    bifurcation_diagram,
    continue_limit_cycle,
    find_limit_cycle,
)
from heelstrike.dynamics.hybrid import WalkResult
from heelstrike.models.compass import CompassGait

__all__ = [
    "animate_walk",
    "basin_figure",
    "bifurcation_figure",
    "gait_map_figure",
    "resample_walk",
    "write_basin",
    "write_bifurcation",
    "write_gait_map",
]

LEG_COLOURS = ("tab:blue", "tab:red")


def resample_walk(walk: WalkResult, fps: float) -> tuple[NDArray[np.float64], NDArray[np.int_]]:
    """Indices of ``walk`` samples nearest to a uniform frame clock at ``fps`` frames/s.

    Returns ``(times, indices)``.
    """
    if walk.t.size == 0:
        raise ValueError("the walk has no samples")
    times = np.arange(walk.t[0], walk.t[-1] + 0.5 / fps, 1.0 / fps)
    idx = np.clip(np.searchsorted(walk.t, times), 0, walk.t.size - 1)
    return times, idx


def _to_world(points: NDArray[np.float64], slope: float) -> NDArray[np.float64]:
    """Slope frame (ground along x, rising towards +x) to the world frame, shape (..., 2)."""
    c, s = np.cos(slope), np.sin(slope)
    x, y = points[..., 0], points[..., 1]
    return np.stack((c * x - s * y, s * x + c * y), axis=-1)


def _foot_arc(centre: NDArray[np.float64], leg_angle: float, radius: float) -> NDArray[np.float64]:
    """Polyline of a circular foot arc (+-60 deg about the leg's downward direction)."""
    if radius <= 0:
        return centre[None, :]
    phi = np.linspace(-np.pi / 3, np.pi / 3, 25) + leg_angle
    return centre + radius * np.stack((np.sin(phi), -np.cos(phi)), axis=-1)


def animate_walk(
    walker: CompassGait, walk: WalkResult, path: str | Path, *, fps: float = 30.0
) -> Path:
    """Animate a compass-gait walk to a GIF (or MP4 where ffmpeg exists).

    Draws the ground, both legs (each physical leg keeps its colour), both feet's arcs, the hip
    mass, and a step counter. The file type follows the suffix of ``path``.

    Returns
    -------
    Path
        The written file.
    """
    out = Path(path)
    suffix = out.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"animation file must end in .gif or .mp4, got {out.name!r}")
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise ValueError("writing .mp4 needs ffmpeg on the PATH; use a .gif file instead")
    times, idx = resample_walk(walk, fps)
    R = float(walker.foot_radius)
    pos = walker.positions(walk.q)
    slope = walk.slope
    hip = _to_world(pos.hip, slope)
    xmin, xmax = float(hip[:, 0].min()) - 1.0, float(hip[:, 0].max()) + 1.0

    fig = Figure(figsize=(7, 3.6), dpi=90)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    ax.set_xlim(xmin, xmax)
    ends = np.array([[xmin / np.cos(slope), 0.0], [xmax / np.cos(slope), 0.0]])
    y_ground = _to_world(ends, slope)
    ax.set_ylim(float(y_ground[:, 1].min()) - 0.2, float(hip[:, 1].max()) + 0.4)
    ax.plot(y_ground[:, 0], y_ground[:, 1], color="0.3", lw=2)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"compass gait, R = {R:g} m, slope = {np.rad2deg(slope):.2f} deg")
    legs = [ax.plot([], [], lw=3, color=c, solid_capstyle="round")[0] for c in LEG_COLOURS]
    feet = [ax.plot([], [], lw=2, color=c)[0] for c in LEG_COLOURS]
    (hip_dot,) = ax.plot([], [], "o", color="k", ms=10)
    label = ax.text(0.02, 0.92, "", transform=ax.transAxes)

    def draw(frame: int) -> list[Artist]:
        i = int(idx[frame])
        q = walk.q[i]
        stance = int(walk.stance_leg[i])
        centres = (pos.right_foot_centre[i], pos.left_foot_centre[i])
        angles = (q[2], q[2] + q[3])
        H = pos.hip[i]
        for role, (c, ang) in enumerate(zip(centres, angles, strict=True)):
            leg = stance if role == 0 else 1 - stance
            arc = _foot_arc(c, float(ang), R)
            line = _to_world(np.vstack((H, c)), slope)
            legs[leg].set_data(line[:, 0], line[:, 1])
            arc_w = _to_world(arc, slope)
            feet[leg].set_data(arc_w[:, 0], arc_w[:, 1])
        hw = _to_world(H, slope)
        hip_dot.set_data([hw[0]], [hw[1]])
        label.set_text(f"step {int(walk.step[i]) + 1}   t = {walk.t[i]:.2f} s")
        return [*legs, *feet, hip_dot, label]

    anim = FuncAnimation(fig, draw, frames=len(times), interval=1000.0 / fps, blit=False)
    writer = PillowWriter(fps=round(fps)) if suffix == ".gif" else FFMpegWriter(fps=round(fps))
    out.parent.mkdir(parents=True, exist_ok=True)
    anim.save(str(out), writer=writer)
    return out


def bifurcation_figure(
    diagram: BifurcationDiagram, continuation: Continuation | None = None, *, title: str = ""
) -> Figure:
    """Period-doubling diagram: steady impact angles and step periods against the slope.

    With a ``continuation`` the period-one branch is overlaid (solid where stable, dotted where
    unstable) and its period-doubling slopes marked.
    """
    fig = Figure(figsize=(7, 6), dpi=110)
    FigureCanvasAgg(fig)
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    slopes_deg = np.rad2deg(diagram.slopes)
    for ax, data, ylabel, scale in (
        (ax1, diagram.impact_angles, "impact angle q3 (deg)", 180 / np.pi),
        (ax2, diagram.periods, "step period (s)", 1.0),
    ):
        xs = np.repeat(slopes_deg, data.shape[1])
        ax.plot(xs, data.ravel() * scale, ".", ms=3, color="k", label="steady state (simulated)")
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
    if continuation is not None and continuation.cycles:
        v = np.rad2deg(continuation.values) if continuation.parameter == "slope" else None
        if v is not None:
            ang = np.rad2deg([c.impact_angle for c in continuation.cycles])
            per = np.asarray([c.period for c in continuation.cycles])
            stable = np.asarray([c.stable for c in continuation.cycles])
            for ax, y in ((ax1, ang), (ax2, per)):
                ax.plot(np.where(stable, v, np.nan), np.where(stable, y, np.nan), "-",
                        color="tab:blue", label="period-one gait, stable")
                ax.plot(np.where(~stable, v, np.nan), np.where(~stable, y, np.nan), ":",
                        color="tab:blue", label="period-one gait, unstable")
                for pd in np.rad2deg(continuation.period_doubling):
                    ax.axvline(pd, color="tab:red", ls="--", lw=1)
    ax1.legend(loc="upper left", fontsize=8)
    ax2.set_xlabel("slope (deg)")
    ax1.set_title(title or "compass gait: bifurcation diagram")
    fig.tight_layout()
    return fig


def write_bifurcation(
    walker: CompassGait,
    slope_start: float,
    slope_stop: float,
    count: int,
    out_dir: Path,
    *,
    transient: int = 50,
    record: int = 16,
    continuation_points: int = 12,
    progress: bool = False,
) -> list[Path]:
    """Compute and write the slope bifurcation diagram (PNG, PDF and CSV).

    Slopes in rad. Writes ``bifurcation.png``, ``bifurcation.pdf``, ``bifurcation.csv`` (one row
    per recorded step: slope, impact angle, period) and ``period_one_branch.csv`` (the continued
    period-one gait with its spectral radius and stability).
    """
    import pandas as pd

    slopes = np.linspace(slope_start, slope_stop, count)
    first = find_limit_cycle(walker, slope=float(slopes[0]), progress=progress)
    diagram = bifurcation_diagram(
        walker, slopes, guess=first.fixed_point, transient=transient, record=record,
        progress=progress,
    )
    branch = continue_limit_cycle(
        walker, "slope", np.linspace(slope_start, slope_stop, continuation_points),
        guess=first.fixed_point, progress=progress, rtol=1e-10, atol=1e-10,
    )
    out_dir.mkdir(parents=True, exist_ok=True)
    fig = bifurcation_figure(
        diagram, branch,
        title=f"compass gait, R = {float(walker.foot_radius):g} m: bifurcation diagram",
    )
    paths = [out_dir / "bifurcation.png", out_dir / "bifurcation.pdf"]
    for p in paths:
        fig.savefig(p)
    rows = pd.DataFrame(
        {
            "slope_deg": np.repeat(np.rad2deg(slopes), record),
            "impact_angle_rad": diagram.impact_angles.ravel(),
            "period_s": diagram.periods.ravel(),
        }
    )
    csv = out_dir / "bifurcation.csv"
    rows.to_csv(csv, index=False)
    bcsv = out_dir / "period_one_branch.csv"
    pd.DataFrame(
        {
            "slope_deg": np.rad2deg(branch.values),
            "impact_angle_rad": [c.impact_angle for c in branch.cycles],
            "period_s": [c.period for c in branch.cycles],
            "spectral_radius": [c.spectral_radius for c in branch.cycles],
            "stable": [c.stable for c in branch.cycles],
        }
    ).to_csv(bcsv, index=False)
    return [*paths, csv, bcsv]


# -- basin of attraction and stable-gait map ----------------------------------------------------
_COLOURS = (
    "#1a9850",  # converged
    "#91cf60",  # keeps walking
    "#d73027",  # fell forward
    "#4575b4",  # fell backward
    "#fdae61",  # trailing foot stays
    "#984ea3",  # lost contact
    "#bdbdbd",  # no heel strike
    "#000000",  # integration failed
)


def basin_figure(basin: Basin) -> Any:
    """Image of the basin: outcome per initial state, the fixed point marked.

    Returns a :class:`matplotlib.figure.Figure` (Agg canvas attached).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    ds = basin.dataset
    q3, q3d = ds["q3"].values, ds["q3_dot"].values
    fig = Figure(figsize=(7.5, 5.5), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    cmap = ListedColormap(list(_COLOURS))
    norm = BoundaryNorm(np.arange(len(OUTCOMES) + 1) - 0.5, cmap.N)
    dx = (q3[-1] - q3[0]) / max(len(q3) - 1, 1) / 2
    dy = (q3d[-1] - q3d[0]) / max(len(q3d) - 1, 1) / 2
    ax.imshow(
        ds["outcome"].values.T, origin="lower", cmap=cmap, norm=norm, aspect="auto",
        interpolation="nearest",
        extent=(q3[0] - dx, q3[-1] + dx, q3d[0] - dy, q3d[-1] + dy),
    )
    z = basin.fixed_point
    ax.plot(z[0], z[1], marker="*", ms=14, mfc="white", mec="black", ls="none",
            label="fixed point")
    fr = basin.fractions()
    handles = [
        Patch(color=c, label=f"{name.replace('_', ' ')} ({100 * fr[name]:.1f} %)")
        for c, name in zip(_COLOURS, OUTCOMES, strict=True)
        if fr[name] > 0
    ]
    handles.append(ax.get_lines()[0])  # type: ignore[arg-type]
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.9)
    ax.set_xlabel(r"post-impact stance angle $q_3$ (rad)")
    ax.set_ylabel(r"post-impact stance velocity $\dot q_3$ (rad/s)")
    ax.set_title(
        f"basin of attraction, R = {ds.attrs['foot_radius']:g} m, slope = "
        f"{np.degrees(ds.attrs['slope']):g} deg, $\\dot q_4$ = {ds.attrs['q4_dot']:.4f} rad/s\n"
        f"{100 * basin.converging_fraction:.2f} % of the grid converges within "
        f"{ds.attrs['max_steps']} steps",
        fontsize=10,
    )
    return fig


def write_basin(basin: Basin, out_dir: str | Path, stem: str = "basin") -> tuple[Path, Path]:
    """Write the figure (PNG) and the dataset (netCDF) into ``out_dir``; returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    png = out / f"{stem}.png"
    nc = out / f"{stem}.nc"
    basin_figure(basin).savefig(png, dpi=130)
    basin.dataset.to_netcdf(nc)
    return png, nc


def gait_map_figure(gmap: GaitMap) -> Any:
    """Spectral radius over (slope, radius), the stable region outlined, period doubling marked.

    Returns a :class:`matplotlib.figure.Figure` (Agg canvas attached).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.colors import TwoSlopeNorm
    from matplotlib.figure import Figure

    ds = gmap.dataset
    R = ds["foot_radius"].values
    S = np.degrees(ds["slope"].values)
    rho = ds["spectral_radius"].values
    fig = Figure(figsize=(7.5, 5.2), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.set_facecolor("#d9d9d9")  # no period-one gait found
    finite = rho[np.isfinite(rho)]
    vmax = max(2.0, float(finite.max()) if finite.size else 2.0)
    norm = TwoSlopeNorm(vmin=0.0, vcenter=1.0, vmax=vmax)
    mesh: Any
    if S.size > 1 and R.size > 1:
        mesh = ax.pcolormesh(S, R, rho, cmap="RdYlGn_r", norm=norm, shading="nearest")
        if np.nanmin(rho) < 1.0 < np.nanmax(rho):
            ax.contour(S, R, np.where(np.isfinite(rho), rho, 10.0), levels=[1.0],
                       colors="black", linewidths=1.2)
    else:
        mesh = ax.scatter(np.broadcast_to(S, rho.shape), np.broadcast_to(R[:, None], rho.shape),
                          c=rho, cmap="RdYlGn_r", norm=norm, s=60)
    fig.colorbar(mesh, ax=ax, label="spectral radius of the step map (stable < 1)")
    pd = np.degrees(ds["period_doubling_slope"].values)
    ok = np.isfinite(pd)
    if np.any(ok):
        ax.plot(pd[ok], R[ok], "o--", color="navy", mfc="white", label="period doubling")
        ax.legend(loc="upper left", fontsize=9)
    ax.set_xlabel("slope (deg)")
    ax.set_ylabel("foot radius R (m)")
    ax.set_title("passive period-one gaits of the circular-feet compass gait\n"
                 "(black line: spectral radius 1; grey: no gait found)", fontsize=10)
    return fig


def write_gait_map(gmap: GaitMap, out_dir: str | Path, stem: str = "gait_map") -> tuple[Path, Path]:
    """Write the figure (PNG) and the dataset (netCDF) into ``out_dir``; returns the paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    png, nc = out / f"{stem}.png", out / f"{stem}.nc"
    gait_map_figure(gmap).savefig(png, dpi=130)
    ds = gmap.dataset.copy()
    ds["stable"] = ds["stable"].astype(np.int8)
    ds.to_netcdf(nc)
    return png, nc
