"""Figures and animations of gaits: walking animation, bifurcation diagram, basins, gait maps
and the walk seen (strobe, phase portrait, one step, energy).

Drawing only: results in, :class:`~matplotlib.figure.Figure` out. The data come from
:mod:`heelstrike.analysis` (the walk's tables from :mod:`heelstrike.analysis.walk_tables`);
:mod:`heelstrike.outputs` writes figures and data to files. The animations are the one
exception: they render their frames to the file they are given. Uses matplotlib's object API
with the Agg canvas (no global pyplot state).
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.artist import Artist
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import NDArray

from heelstrike._frames import slope_to_world as _to_world
from heelstrike._typing import BoolArray, FloatArray
from heelstrike.analysis.basin import OUTCOMES, Basin
from heelstrike.analysis.gait_map import GaitMap
from heelstrike.analysis.limit_cycle import BifurcationDiagram, Continuation
from heelstrike.models.compass import CompassGait
from heelstrike.plots import _new_figure

__all__ = [
    "LEG_COLOURS",
    "animate_model_walk",
    "animate_walk",
    "basin_figure",
    "bifurcation_figure",
    "energy_figure",
    "gait_map_figure",
    "model_diagram",
    "model_strobe_figure",
    "phase_portrait_figure",
    "step_figure",
    "strobe_figure",
]

LEG_COLOURS = ("tab:blue", "tab:red")


def _walk_scene(
    xmin: float, xmax: float, ytop: float, slope: float, margins: tuple[float, float], title: str
) -> tuple[Figure, Any]:
    """Axes of an animation: equal aspect, the slope drawn from ``xmin`` to ``xmax`` (m), room
    ``margins`` (m) below the ground and above ``ytop``."""
    fig = _new_figure(7, 3.6, dpi=90, layout=None)
    fig.subplots_adjust(bottom=0.16, top=0.9)  # room for the x label and the title
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    ax.set_xlim(xmin, xmax)
    ends = np.array([[xmin / np.cos(slope), 0.0], [xmax / np.cos(slope), 0.0]])
    y_ground = _to_world(ends, slope)
    ax.set_ylim(float(y_ground[:, 1].min()) - margins[0], ytop + margins[1])
    ax.plot(y_ground[:, 0], y_ground[:, 1], color="0.3", lw=2)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(title)
    return fig, ax


def _foot_arc(centre: NDArray[np.float64], leg_angle: float, radius: float) -> NDArray[np.float64]:
    """Polyline of a circular foot arc (+-60 deg about the leg's downward direction)."""
    if radius <= 0:
        return centre[None, :]
    phi = np.linspace(-np.pi / 3, np.pi / 3, 25) + leg_angle
    return centre + radius * np.stack((np.sin(phi), -np.cos(phi)), axis=-1)


def _animation_file(path: str | Path) -> Path:
    """``path`` as a Path, checked: a ``.gif``, or an ``.mp4`` with ffmpeg on the PATH."""
    out = Path(path)
    suffix = out.suffix.lower()
    if suffix not in (".gif", ".mp4"):
        raise ValueError(f"animation file must end in .gif or .mp4, got {out.name!r}")
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise ValueError("writing .mp4 needs ffmpeg on the PATH (not found); install ffmpeg "
                         "or use a .gif file instead")
    return out


def _frames_rgb(fig: Figure, draw: Any, frames: int) -> Iterator[NDArray[np.uint8]]:
    """The ``frames`` frames of ``draw`` as RGB arrays (height, width, 3), rendered by blitting.

    The figure is drawn once with Agg without the artists ``draw`` returns (marked animated):
    that background (ground, axes, ticks, labels, title) is copied, and every frame restores
    it and draws only the moving artists over it, then hands over the canvas's pixels (a full
    draw per frame, as matplotlib's animation writers do, costs several times more).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    for a in draw(0):
        a.set_animated(True)
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    for k in range(frames):
        moving = draw(k)
        canvas.restore_region(background)
        for a in moving:
            fig.draw_artist(a)
        yield np.asarray(canvas.buffer_rgba())[..., :3].copy()


def _write_gif(images: Iterator[NDArray[np.uint8]], fps: float, out: Path) -> None:
    """Encode RGB frames into a looping GIF with Pillow: every frame on the first frame's
    palette (the scene's few colours; no dithering, so unchanged pixels stay unchanged)."""
    from PIL import Image

    palette: Any = None
    pictures: list[Any] = []
    for rgb in images:
        im = Image.fromarray(rgb, mode="RGB")
        if palette is None:
            palette = im.quantize(colors=255, method=Image.Quantize.MEDIANCUT,
                                  dither=Image.Dither.NONE)
        # every frame (the first too) mapped the same way: equal pixels stay equal
        pictures.append(im.quantize(palette=palette, dither=Image.Dither.NONE))
    if not pictures:
        raise ValueError("an animation needs at least one frame")
    # optimize=False: the palette is already minimal; Pillow's palette pass per frame would
    # cost about as much as rendering the frame (the file is 3 % larger)
    pictures[0].save(out, save_all=True, append_images=pictures[1:],
                     duration=round(1000.0 / fps), loop=0, optimize=False)


def _write_mp4(images: Iterator[NDArray[np.uint8]], fps: float, out: Path) -> None:
    """Encode RGB frames into an H.264 MP4 with ffmpeg (raw frames piped to its stdin).

    Raises
    ------
    ValueError
        ffmpeg is not on the PATH, or failed (its last message quoted).
    """
    import subprocess

    exe = shutil.which("ffmpeg")
    if exe is None:
        raise ValueError("writing .mp4 needs ffmpeg on the PATH (not found); install ffmpeg "
                         "or use a .gif file instead")
    proc: subprocess.Popen[bytes] | None = None
    try:
        for rgb in images:
            if proc is None:
                h, w = rgb.shape[:2]
                proc = subprocess.Popen(
                    [exe, "-v", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24",
                     "-s", f"{w}x{h}", "-r", f"{fps:g}", "-i", "-",
                     "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264",
                     "-pix_fmt", "yuv420p", str(out)],
                    stdin=subprocess.PIPE, stderr=subprocess.PIPE)
            assert proc.stdin is not None
            proc.stdin.write(np.ascontiguousarray(rgb).tobytes())
    finally:
        if proc is not None:
            assert proc.stdin is not None
            proc.stdin.close()
            err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
            if proc.wait() != 0:
                last = err.strip().splitlines()[-1:] or ["no message"]
                raise ValueError(f"ffmpeg could not write {out.name}: {last[0]}")


def _save_animation(
    fig: Figure, draw: Any, frames: int, fps: float, out: Path, progress: bool = False
) -> Path:
    """Render ``frames`` frames of ``draw`` at ``fps`` (frames per second of the file) into
    ``out`` (GIF by Pillow, MP4 by ffmpeg, after the suffix); returns ``out``.

    Frames are blitted on an Agg canvas and handed straight to the encoder
    (:func:`_frames_rgb`). With ``progress``, a progress bar on stderr counts the rendered
    frames, then says the file is being encoded (shown once rendering takes more than 2 s).
    """
    from heelstrike._progress import progress_bar
    from heelstrike.io import atomic_path

    write = _write_gif if out.suffix.lower() == ".gif" else _write_mp4
    images = _frames_rgb(fig, draw, frames)
    with progress_bar(total=frames, desc=f"heelstrike: rendering {out.name}", unit="frame",
                      enabled=progress) as bar:

        def counted() -> Iterator[NDArray[np.uint8]]:
            for k, rgb in enumerate(images):
                yield rgb
                bar.update(1)
                if k + 1 == frames:  # the encoder finishes the file after the last frame
                    bar.set_description(f"heelstrike: encoding {out.name}")

        with atomic_path(out) as part:  # written whole or not at all (issue 36)
            write(counted(), fps, part)
    return out


def animate_walk(
    frames: Any, path: str | Path, *, foot_radius: float, slope: float, title: str = "",
    fps: float = 30.0, progress: bool = False,
) -> Path:
    """Animate a compass-gait walk to a GIF (or MP4 where ffmpeg exists).

    Draws the ground, both legs (each physical leg keeps its colour), both feet's arcs, the hip
    mass, and a step counter. The file type follows the suffix of ``path``. With ``progress``,
    a progress bar on stderr counts the frames rendered (shown after 2 s).

    Parameters
    ----------
    frames : pandas.DataFrame
        From :func:`~heelstrike.analysis.walk_tables.walk_frames`, one row per frame.
    path : path
        Output file, ``.gif`` or ``.mp4``.
    foot_radius : float
        Radius of the feet (m).
    slope : float
        Ground slope (rad).
    title : str
        Figure title.
    fps : float
        Frames per second of the file (the rate ``frames`` was sampled at).
    progress : bool
        Count the frames rendered in a progress bar on stderr (shown after 2 s).

    Returns
    -------
    Path
        The written file.
    """
    out = _animation_file(path)
    R = float(foot_radius)
    hip_x, hip_y = frames["hip_x_m"].to_numpy(), frames["hip_y_m"].to_numpy()
    fig, ax = _walk_scene(float(hip_x.min()) - 1.0, float(hip_x.max()) + 1.0,
                          float(hip_y.max()), slope, (0.2, 0.4), title)
    legs = [ax.plot([], [], lw=3, color=c, solid_capstyle="round")[0] for c in LEG_COLOURS]
    feet = [ax.plot([], [], lw=2, color=c)[0] for c in LEG_COLOURS]
    (hip_dot,) = ax.plot([], [], "o", color="k", ms=10)
    label = ax.text(0.02, 0.92, "", transform=ax.transAxes)
    rows = frames.to_dict("records")

    def draw(frame: int) -> list[Artist]:
        row = rows[frame]
        stance = int(row["stance_leg"])
        H = np.array([row["hip_x_m"], row["hip_y_m"]])
        for role, side in enumerate(("stance", "swing")):
            leg = stance if role == 0 else 1 - stance
            c = np.array([row[f"{side}_foot_x_m"], row[f"{side}_foot_y_m"]])
            legs[leg].set_data([H[0], c[0]], [H[1], c[1]])
            arc = c + _to_world(_foot_arc(np.zeros(2), float(row[f"{side}_rad"]), R), slope)
            feet[leg].set_data(arc[:, 0], arc[:, 1])
        hip_dot.set_data([H[0]], [H[1]])
        label.set_text(f"step {int(row['step']) + 1}   t = {row['t_s']:.2f} s")
        return [*legs, *feet, hip_dot, label]

    return _save_animation(fig, draw, len(rows), fps, out, progress)


def _branch_piece(
    x: FloatArray, y: FloatArray, stable: NDArray[np.bool_], want: bool, crossings: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The points of a continued branch where ``stable == want``, as one polyline with NaN
    gaps; where stability changes between two points the line runs on to the change (the
    crossing slope between them, else the midpoint) along the straight segment joining them,
    so the stable and unstable pieces meet there."""
    xs: list[float] = []
    ys: list[float] = []
    for i in range(len(x)):
        if stable[i] == want:
            xs.append(float(x[i]))
            ys.append(float(y[i]))
        if i + 1 < len(x) and stable[i] != stable[i + 1]:
            lo, hi = sorted((float(x[i]), float(x[i + 1])))
            inside = [c for c in crossings if lo <= c <= hi]
            xc = float(inside[0]) if inside else 0.5 * (lo + hi)
            t = (xc - x[i]) / (x[i + 1] - x[i]) if x[i + 1] != x[i] else 0.5
            yc = float(y[i] + t * (y[i + 1] - y[i]))
            xs.append(xc)
            ys.append(yc)
            if stable[i] == want:  # the piece ends here
                xs.append(np.nan)
                ys.append(np.nan)
    return np.asarray(xs), np.asarray(ys)


def _shade_without_steady_state(ax: Any, slopes_deg: FloatArray, angles: FloatArray,
                                label: bool, branch_deg: FloatArray | None = None,
                                walked: BoolArray | None = None) -> None:
    """Grey bands over the slopes where a walk was simulated (``walked``, default every slope)
    and no recorded step exists (it fell within the transient), so that a blank stretch is not
    read as missing data. Bands stay within the slope range, and stop where the period-one
    branch (``branch_deg``, deg) starts or ends, so that they do not cover the branch drawn
    there."""
    empty = ~np.any(np.isfinite(np.asarray(angles, dtype=float)), axis=1)
    if walked is not None:
        empty &= np.asarray(walked, dtype=bool)
    if not np.any(empty) or slopes_deg.size < 2:
        return
    half = 0.5 * float(np.min(np.diff(slopes_deg)))
    first = True
    for k in np.flatnonzero(empty):
        lo = max(slopes_deg[k] - half, float(slopes_deg[0]))
        hi = min(slopes_deg[k] + half, float(slopes_deg[-1]))
        if branch_deg is not None and branch_deg.size:
            b0, b1 = float(np.min(branch_deg)), float(np.max(branch_deg))
            if slopes_deg[k] < b0 < hi:
                hi = b0
            if lo < b1 < slopes_deg[k]:
                lo = b1
        ax.axvspan(lo, hi, color="0.85", lw=0,
                   label="no steady state (the simulated walk fell)" if label and first
                   else None)
        first = False


def bifurcation_figure(
    diagram: BifurcationDiagram, continuation: Continuation | None = None, *, title: str = ""
) -> Figure:
    """Period-doubling diagram: steady impact angles and step periods against the slope.

    With a ``continuation`` the period-one branch is overlaid (solid where stable, dotted where
    unstable) and its period-doubling slopes marked.
    """
    fig = _new_figure(7, 6, dpi=110, layout=None)
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    slopes_deg = np.rad2deg(diagram.slopes)
    # a walk is drawn as a steady state where it settled into a period; one still converging
    # to the stable period-one gait, or without a period found (chaos, or a transient that
    # may yet fall: QA sweep 13), is drawn apart
    settling = (diagram.settling(continuation) if continuation is not None
                else np.zeros(slopes_deg.size, dtype=bool))
    periodic = diagram.period_steps() > 0
    if len(diagram.statuses) != slopes_deg.size:  # a diagram built by hand: all as recorded
        periodic = np.ones(slopes_deg.size, dtype=bool)
    for ax, data, ylabel, scale in (
        (ax1, diagram.impact_angles, "impact angle q3 (deg)", 180 / np.pi),
        (ax2, diagram.periods, "step period (s)", 1.0),
    ):
        marks: tuple[tuple[NDArray[np.bool_], dict[str, Any], str], ...] = (
            (periodic, dict(marker=".", ms=3, color="k"), "steady state (simulated)"),
            (settling, dict(marker="o", ms=3, mfc="none", color="0.55"),
             "still settling (the stable gait not yet reached)"),
            (~periodic & ~settling, dict(marker="x", ms=3, color="0.3"),
             "no period found (chaotic, or still settling)"),
        )
        for rows, mark, label in marks:
            if not np.any(rows):
                continue
            sub = data[rows]
            xs = np.repeat(slopes_deg[rows], sub.shape[1])
            ax.plot(xs, sub.ravel() * scale, ls="none", label=label, **mark)
        ax.set_ylabel(ylabel)
        ax.grid(alpha=0.3)
        branch_deg = (np.rad2deg(continuation.values)
                      if continuation is not None and continuation.cycles
                      and continuation.parameter == "slope" else None)
        # slopes below the first gait are not walked (status ""): nothing fell there
        walked = (np.asarray([s != "" for s in diagram.statuses])
                  if len(diagram.statuses) == slopes_deg.size else None)
        _shade_without_steady_state(ax, slopes_deg, diagram.impact_angles, ax is ax1,
                                    branch_deg, walked)
    if continuation is not None and continuation.cycles:
        v = np.rad2deg(continuation.values) if continuation.parameter == "slope" else None
        if v is not None:
            ang = np.rad2deg([c.impact_angle for c in continuation.cycles])
            per = np.asarray([c.period for c in continuation.cycles])
            stable = np.asarray([c.stable for c in continuation.cycles])
            pds = np.rad2deg(continuation.period_doubling)
            for ax, y in ((ax1, ang), (ax2, per)):
                for want, style, label in ((True, "-", "stable"), (False, ":", "unstable")):
                    xs, ys = _branch_piece(v, y, stable, want, pds)
                    ax.plot(xs, ys, style, color="tab:blue", label=f"period-one gait, {label}")
                for k, pd in enumerate(np.rad2deg(continuation.period_doubling)):
                    ax.axvline(pd, color="tab:red", ls="--", lw=1,
                               label=f"period doubling, {pd:.3f} deg" if k == 0 else None)
    ax1.legend(loc="upper left", fontsize=8)
    ax2.set_xlabel("slope (deg)")
    ax1.set_title(title or "compass gait: bifurcation diagram")
    fig.tight_layout()
    return fig


# -- basin of attraction and stable-gait map ----------------------------------------------------
#: Colour of each basin outcome, by name (:data:`~heelstrike.analysis.basin.OUTCOMES`; the
#: dataset holds their walk-status codes).
_COLOURS = {
    "converged": "#1a9850",
    "keeps_walking": "#91cf60",
    "fell_forward": "#d73027",
    "fell_backward": "#4575b4",
    "trailing_foot_stays": "#fdae61",
    "lost_contact": "#984ea3",
    "no_heel_strike": "#bdbdbd",
    "integration_failed": "#000000",
    "slipped": "#8c510a",
    "no_consistent_assignment": "#f781bf",
    "no_leg_swap": "#636363",
    "off_profile": "#35978f",
    "inadmissible_start": "#ffffbf",
}

#: Legend text of the basin outcomes whose name alone does not say it (the others: the name).
_LABELS = {"inadmissible_start": "inadmissible start: trailing foot sinks"}


def basin_figure(basin: Basin) -> Figure:
    """Image of the basin: outcome per initial state, the fixed point marked.

    The title says so when the gait is unstable (the dataset's ``gait_stable`` attribute is 0,
    with ``gait_spectral_radius``): nothing converges to it.

    Returns a :class:`matplotlib.figure.Figure` (Agg canvas attached).
    """
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    ds = basin.dataset
    xname, yname = ds["outcome"].dims
    q3, q3d = ds[xname].values, ds[yname].values
    fig = _new_figure(7.5, 5.5)
    ax = fig.add_subplot()
    # the dataset holds walk-status codes: colour each outcome's code (a code no basin gives,
    # such as 0 = completed, is never drawn)
    n_codes = max(s.code for s in OUTCOMES) + 1
    colours = ["#ffffff"] * n_codes
    for s in OUTCOMES:
        colours[s.code] = _COLOURS[s]
    cmap = ListedColormap(colours)
    norm = BoundaryNorm(np.arange(n_codes + 1) - 0.5, cmap.N)
    # half a cell; a one-point axis gets a cell of 1 % of its value (or 0.01) to be visible
    dx = (q3[-1] - q3[0]) / max(len(q3) - 1, 1) / 2 or 0.01 * max(abs(float(q3[0])), 1.0)
    dy = (q3d[-1] - q3d[0]) / max(len(q3d) - 1, 1) / 2 or 0.01 * max(abs(float(q3d[0])), 1.0)
    ax.imshow(
        ds["outcome"].values.T, origin="lower", cmap=cmap, norm=norm, aspect="auto",
        interpolation="nearest",
        extent=(q3[0] - dx, q3[-1] + dx, q3d[0] - dy, q3d[-1] + dy),
    )
    z = basin.fixed_point
    ax.plot(z[basin.axes[0]], z[basin.axes[1]], marker="*", ms=14, mfc="white", mec="black",
            ls="none", label="fixed point")
    fr = basin.fractions()
    handles = [
        Patch(color=_COLOURS[name],
              label=f"{_LABELS.get(name, name.replace('_', ' '))} ({100 * fr[name]:.1f} %)")
        for name in OUTCOMES
        if fr[name] > 0
    ]
    handles.append(ax.get_lines()[0])  # type: ignore[arg-type]
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.9)
    for name, set_label in ((xname, ax.set_xlabel), (yname, ax.set_ylabel)):
        a = ds[name].attrs
        set_label(a.get("label", f"{a.get('long_name', name)} ({a.get('units', '')})"))
    if "model" in ds.attrs:  # a described walker: name it and the coordinates held fixed
        head = (f"basin of attraction of '{ds.attrs['model']}', slope = "
                f"{np.degrees(ds.attrs['slope']):g} deg\nheld at the fixed point: "
                f"{ds.attrs['held']}")
    else:
        head = (f"basin of attraction, R = {ds.attrs['foot_radius']:g} m, slope = "
                f"{np.degrees(ds.attrs['slope']):g} deg, $\\dot q_4$ = "
                f"{ds.attrs['q4_dot']:.4f} rad/s")
    tail = ""
    if int(ds.attrs.get("gait_stable", 1)) == 0:  # recorded where the fixed point was found
        tail = (f"\nthe period-one gait is unstable (largest |multiplier| "
                f"{float(ds.attrs['gait_spectral_radius']):.4g}): no start converges to it")
    ax.set_title(
        f"{head}\n{100 * basin.converging_fraction:.2f} % of the grid converges within "
        f"{ds.attrs['max_steps']} steps{tail}",
        fontsize=10,
    )
    return fig


def gait_map_figure(gmap: GaitMap) -> Figure:
    """Spectral radius over (slope, radius), the stable region outlined, period doubling marked.

    Returns a :class:`matplotlib.figure.Figure` (Agg canvas attached).
    """
    from matplotlib.colors import TwoSlopeNorm

    ds = gmap.dataset
    pname = ds["spectral_radius"].dims[0]  # foot_radius, or a described walker's parameter
    R = ds[pname].values
    S = np.degrees(ds["slope"].values)
    rho = ds["spectral_radius"].values
    fig = _new_figure(7.5, 5.2)
    ax = fig.add_subplot()
    ax.set_facecolor("#d9d9d9")  # no period-one gait found
    finite = rho[np.isfinite(rho)]
    vmax = max(2.0, float(finite.max()) if finite.size else 2.0)
    norm = TwoSlopeNorm(vmin=0.0, vcenter=1.0, vmax=vmax)
    mesh: Any
    drawn = False  # a stability boundary (spectral radius 1) drawn
    if S.size > 1 and R.size > 1:
        mesh = ax.pcolormesh(S, R, rho, cmap="RdYlGn_r", norm=norm, shading="nearest")
        # the axes span the computed grid only: the cells' outer halves would show slopes
        # and radii (a negative foot radius at R = 0) that were never computed
        ax.set_xlim(float(S.min()), float(S.max()))
        ax.set_ylim(float(R.min()), float(R.max()))
        if np.nanmin(rho) < 1.0 < np.nanmax(rho):
            # NaN cells (no gait) masked: a stand-in value drew a false "spectral radius 1"
            # line along every edge of the grey region (QA sweep 13)
            contour = ax.contour(S, R, np.ma.masked_invalid(rho), levels=[1.0],
                                 colors="black", linewidths=1.2)
            drawn = any(len(seg) for seg in contour.allsegs[0])
    else:
        # one row or column of the grid: points, coloured by their values (flat arrays: a 2-D
        # ``c`` left the points uncoloured)
        xs = np.broadcast_to(S, rho.shape).ravel()
        ys = np.broadcast_to(R[:, None], rho.shape).ravel()
        ax.set_facecolor("white")  # the background is no grid cell here
        gap = ~np.isfinite(rho.ravel())
        ax.scatter(xs[gap], ys[gap], color="#d9d9d9", edgecolors="0.5", s=60)  # no gait
        mesh = ax.scatter(xs[~gap], ys[~gap], c=rho.ravel()[~gap], cmap="RdYlGn_r", norm=norm,
                          s=60)
    fig.colorbar(mesh, ax=ax, label="spectral radius of the step map (stable < 1)")
    pd = np.degrees(ds["period_doubling_slope"].values)
    ok = np.isfinite(pd)
    if np.any(ok):
        ax.plot(pd[ok], R[ok], "o--", color="navy", mfc="white", label="period doubling",
                clip_on=False)  # markers on the first or last radius stay whole
        ax.legend(loc="upper left", fontsize=9)
    ax.set_xlabel("slope (deg)")
    ax.set_ylabel(ds[pname].attrs.get("label", "foot radius R (m)"))
    who = (f"'{ds.attrs['model']}'" if "model" in ds.attrs
           else "the circular-feet compass gait")
    legend = "black line: spectral radius 1; grey: no gait found" if drawn else (
        "grey: no gait found")
    ax.set_title(f"passive period-one gaits of {who}\n({legend})", fontsize=10)
    return fig


# -- the walk, seen: strobe, phase portrait, step kinematics and ground reaction, energy --------
# Each figure draws a table of heelstrike.analysis.walk_tables (pandas DataFrame, SI units).
def strobe_figure(
    strobe: Any, *, foot_radius: float, slope: float = 0.0, title: str = ""
) -> Figure:
    """Stick-figure strobe of one step: the walker at every row of a strobe table.

    Parameters
    ----------
    strobe : pandas.DataFrame
        From :func:`~heelstrike.analysis.walk_tables.strobe_table`.
    foot_radius : float
        Foot arc radius ``R`` (m), to draw the feet.
    slope : float
        Ground slope (rad), to draw the ground.
    title : str
        Figure title (a default names the step).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = _new_figure(8.0, 3.6, dpi=110)
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    n = len(strobe)
    alphas = np.linspace(0.25, 1.0, n)
    for i, row in enumerate(strobe.itertuples(index=False)):
        stance = int(row.stance_leg)
        hip = np.array([row.hip_x_m, row.hip_y_m])
        for centre, ang, leg in (
            ((row.stance_foot_x_m, row.stance_foot_y_m), row.stance_rad, stance),
            ((row.swing_foot_x_m, row.swing_foot_y_m), row.swing_rad, 1 - stance),
        ):
            c = np.asarray(centre, dtype=float)
            ax.plot([hip[0], c[0]], [hip[1], c[1]], color=LEG_COLOURS[leg], lw=2,
                    alpha=float(alphas[i]), solid_capstyle="round")
            arc = _foot_arc(np.zeros(2), float(ang) + slope, foot_radius) + c
            ax.plot(arc[:, 0], arc[:, 1], color=LEG_COLOURS[leg], lw=1.5, alpha=float(alphas[i]))
        ax.plot(hip[0], hip[1], "o", color="k", ms=6, alpha=float(alphas[i]))
    ax.plot(strobe["hip_x_m"], strobe["hip_y_m"], ":", color="0.4", lw=1, label="hip path")
    xs = np.concatenate([strobe[k].to_numpy() for k in ("hip_x_m", "swing_foot_x_m",
                                                          "stance_foot_x_m")])
    _finish_strobe(ax, (float(xs.min()) - foot_radius - 0.1, float(xs.max()) + foot_radius + 0.1),
                   slope, n, float(strobe["t_s"].iloc[-1]), title)
    return fig


def _finish_strobe(ax: Axes, xlim: tuple[float, float], slope: float, frames: int,
                   duration: float, title: str) -> None:
    """The ground over ``xlim`` (m) on ``slope`` (rad), the axes' labels, legend and title
    (a default names the ``frames`` over the step's ``duration``, s) of a strobe figure."""
    x0, x1 = xlim
    ground = _to_world(np.array([[x0 / np.cos(slope), 0.0], [x1 / np.cos(slope), 0.0]]), slope)
    ax.plot(ground[:, 0], ground[:, 1], color="0.3", lw=2, label="ground")
    ax.set_xlim(x0, x1)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(title or f"one step, {frames} frames over {duration:.3f} s (darkest: heel "
                 "strike); blue and red: the two legs", fontsize=10)


def model_strobe_figure(strobe: Any, *, slope: float = 0.0, title: str = "") -> Figure:
    """Stick-figure strobe of one step of a described walker, drawn with its own links.

    Parameters
    ----------
    strobe : pandas.DataFrame
        From :func:`~heelstrike.analysis.walk_tables.model_strobe_table`.
    slope : float
        Ground slope (rad), to draw the ground.
    title : str
        Figure title (a default names the step).

    Returns
    -------
    matplotlib.figure.Figure
        Every frame fainter the earlier it is: links as segments (blue and red: the two legs;
        grey: links of neither leg), feet as arcs, point masses as black dots, their paths
        dotted.
    """
    fig = _new_figure(8.0, 3.6, dpi=110)
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    n = int(strobe["frame"].max()) + 1
    alphas = np.linspace(0.25, 1.0, n)
    for r in strobe.itertuples(index=False):
        alpha = float(alphas[int(r.frame)])
        colour = LEG_COLOURS[int(r.leg)] if int(r.leg) in (0, 1) else "0.3"
        if r.element == "link":
            ax.plot([r.x0_m, r.x1_m], [r.y0_m, r.y1_m], color=colour, lw=2, alpha=alpha,
                    solid_capstyle="round")
        elif r.element == "foot" and r.radius_m > 0:
            mid = np.arctan2(r.y1_m - r.y0_m, r.x1_m - r.x0_m)  # the arc's middle, on the leg
            phi = mid + np.linspace(-np.pi / 3, np.pi / 3, 25)
            ax.plot(r.x0_m + r.radius_m * np.cos(phi), r.y0_m + r.radius_m * np.sin(phi),
                    color=colour, lw=1.5, alpha=alpha)
        elif r.element == "mass":
            ax.plot(r.x0_m, r.y0_m, "o", color="k", ms=6, alpha=alpha)
    for name, d in strobe[strobe["element"] == "mass"].groupby("name", sort=False):
        ax.plot(d["x0_m"], d["y0_m"], ":", color="0.4", lw=1, label=f"{name} path")
    xs = strobe[["x0_m", "x1_m"]].to_numpy()
    pad = float(strobe["radius_m"].max()) + 0.1
    _finish_strobe(ax, (float(xs.min()) - pad, float(xs.max()) + pad), slope, n,
                   float(strobe["t_s"].max()), title)
    return fig


def phase_portrait_figure(
    portrait: Any, *, title: str = "", labels: tuple[str, str] | None = None
) -> Figure:
    """Phase portrait of a walk: ``q3`` against ``q3_dot`` (and the swing leg's), per step.

    Parameters
    ----------
    portrait : pandas.DataFrame
        From :func:`~heelstrike.analysis.walk_tables.phase_portrait_table`.
    title : str
        Figure title.
    labels : (str, str), optional
        Legend labels of the stance and swing curves (default: the compass gait's).

    Returns
    -------
    matplotlib.figure.Figure
        Solid: the stance leg ``(q3, q3_dot)``; dashed: the swing leg's absolute angle and
        rate; grey dotted lines join the states just before and just after each heel strike
        (the impact and the leg relabelling). On a limit cycle every step traces the same loop.
    """
    fig = _new_figure(6.4, 5.0, dpi=110)
    ax = fig.add_subplot()
    steps = np.unique(portrait["step"].to_numpy())
    stance_label, swing_label = labels or (
        "stance leg ($q_3$, $\\dot q_3$)", "swing leg ($q_3 + q_4$, $\\dot q_3 + \\dot q_4$)")
    for k in steps:
        d = portrait[portrait["step"] == k]
        first = k == steps[0]
        ax.plot(d["q3_rad"], d["q3_dot_rad_s"], "-", color="tab:blue", lw=1.5,
                label=stance_label if first else None)
        ax.plot(d["swing_rad"], d["swing_dot_rad_s"], "--", color="tab:red", lw=1.5,
                label=swing_label if first else None)
        nxt = portrait[portrait["step"] == k + 1]
        if len(nxt):
            a, b = d.iloc[-1], nxt.iloc[0]
            ax.plot([a["q3_rad"], b["q3_rad"]], [a["q3_dot_rad_s"], b["q3_dot_rad_s"]], ":",
                    color="0.5", lw=1,
                    label="heel strike + leg relabelling" if first else None)
            ax.plot([a["swing_rad"], b["swing_rad"]],
                    [a["swing_dot_rad_s"], b["swing_dot_rad_s"]], ":", color="0.5", lw=1)
    d0 = portrait[portrait["step"] == steps[0]].iloc[0]
    ax.plot(d0["q3_rad"], d0["q3_dot_rad_s"], "*", ms=12, mfc="white", mec="k", ls="none",
            label="start (post-impact)")
    ax.axhline(0.0, color="0.8", lw=0.8)
    ax.axvline(0.0, color="0.8", lw=0.8)
    ax.set_xlabel("leg angle from the slope's normal (rad)")
    ax.set_ylabel("leg angular velocity (rad/s)")
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title or f"phase portrait, {steps.size} steps", fontsize=10)
    return fig


#: Colours of the joint angles after the stance and swing legs in :func:`step_figure`.
_JOINT_COLOURS = ("tab:green", "tab:purple", "tab:brown", "tab:olive", "tab:cyan", "tab:pink")


def step_figure(step: Any, *, title: str = "", labels: Mapping[str, str] | None = None
                ) -> Figure:
    """Joint angles and the ground reaction over one step (three panels).

    Parameters
    ----------
    step : pandas.DataFrame
        From :func:`~heelstrike.analysis.walk_tables.step_table`.
    title : str
        Figure title.
    labels : mapping of str to str, optional
        Legend label of an angle column (e.g. ``{"q3_rad": "stance leg $q_3$"}``); by default
        the coordinate's name.

    Returns
    -------
    matplotlib.figure.Figure
        Top: the stance link's angle (the first ``*_rad`` column), the swing leg's absolute
        angle (``swing_rad``, dashed) and the other joint angles (deg); middle: normal and
        tangential ground force on the stance foot (N); bottom: the friction coefficient the
        step needs.
    """
    names = dict(labels or {})
    angles = [c for c in step.columns if c.endswith("_rad") and c != "swing_rad"]
    fig = _new_figure(7.0, 7.0, dpi=110)
    ax1, ax2, ax3 = fig.subplots(3, 1, sharex=True)
    t = step["t_s"]
    stance = angles[0]
    ax1.plot(t, np.rad2deg(step[stance]), color="tab:blue",
             label=names.get(stance, f"{stance[:-4]} (stance link)"))
    ax1.plot(t, np.rad2deg(step["swing_rad"]), color="tab:red", ls="--",
             label=names.get("swing_rad", "swing leg (absolute)"))
    for k, col in enumerate(angles[1:]):
        ax1.plot(t, np.rad2deg(step[col]), color=_JOINT_COLOURS[k % len(_JOINT_COLOURS)],
                 label=names.get(col, f"{col[:-4]} (joint, relative)"))
    ax1.set_ylabel("angle (deg)")
    ax1.legend(loc="best", fontsize=8)
    ax2.plot(t, step["normal_N"], color="k", label="normal")
    ax2.plot(t, step["tangential_N"], color="tab:purple", ls="--", label="tangential")
    ax2.axhline(0.0, color="0.8", lw=0.8)
    ax2.set_ylabel("ground force on stance foot (N)")
    ax2.legend(loc="best", fontsize=8)
    ax3.plot(t, step["required_friction"], color="tab:orange")
    ax3.set_ylabel("required friction |F_t|/F_n (-)")
    ax3.set_xlabel("time since the step began (s)")
    for ax in (ax1, ax2, ax3):
        ax.grid(alpha=0.3)
    ax1.set_title(title or "one step: joint angles and ground reaction", fontsize=10)
    return fig


def energy_figure(energy: Any, impacts: Any, *, title: str = "") -> Figure:
    """Kinetic, potential and total energy over a walk, the impacts' drops marked.

    Parameters
    ----------
    energy : pandas.DataFrame
        From :func:`~heelstrike.analysis.walk_tables.walk_energy_table`.
    impacts : pandas.DataFrame
        From :func:`~heelstrike.analysis.walk_tables.walk_impact_table`: one row per impact;
        a row whose ``kind`` is ``"knee_strike"`` is a knee strike, any other row a heel
        strike.
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        Potential and total energy are drawn relative to the initial potential energy ``U(0)``.
        Between impacts the total is constant; at each heel strike (grey dashed lines, orange
        arrows) and each knee strike (purple dotted lines and arrows) it drops by the impact's
        ``T_c``.
    """
    fig = _new_figure(7.5, 4.6, dpi=110)
    ax = fig.add_subplot()
    U0 = float(energy["potential_J"].iloc[0])
    t = energy["t_s"]
    ax.plot(t, energy["kinetic_J"], color="tab:red", label="kinetic $T$")
    ax.plot(t, energy["potential_J"] - U0, color="tab:blue", label="potential $U - U(0)$")
    ax.plot(t, energy["total_J"] - U0, color="k", lw=2, label="total $T + U - U(0)$")
    # (line colour, line style, drop colour, label) of each kind of impact
    styles = {"heel_strike": ("0.5", "--", "tab:orange", "heel strike"),
              "knee_strike": ("tab:purple", ":", "tab:purple", "knee strike")}
    labelled: set[str] = set()
    knees = False
    for r in impacts.itertuples(index=False):
        kind = "knee_strike" if r.kind == "knee_strike" else "heel_strike"
        knees |= kind == "knee_strike"
        line, ls, drop, label = styles[kind]
        ax.axvline(r.time_s, color=line, ls=ls, lw=0.8 if kind == "heel_strike" else 1.0,
                   label=None if kind in labelled else label)
        labelled.add(kind)
        ax.annotate(
            "", xy=(r.time_s, r.total_after_J - U0), xytext=(r.time_s, r.total_before_J - U0),
            arrowprops={"arrowstyle": "->", "color": drop, "lw": 1.5},
        )
        # above the total's level (a label below it was struck through by the total's line);
        # a knee strike's to the left of its line (the heel strike's, just after it, takes the
        # right); a heel strike's near the end (it ran past the axes) left of the arrow's tip
        late = kind == "heel_strike" and r.time_s > 0.85 * float(t.iloc[-1])
        left = kind == "knee_strike" or late
        ax.annotate(f"$T_c$ = {r.T_c_J:.3g} J",
                    (r.time_s, (r.total_after_J if late else r.total_before_J) - U0),
                    xytext=(-3 if left else 3, -3 if late else 3), textcoords="offset points",
                    fontsize=7, va="top" if late else "bottom", ha="right" if left else "left",
                    color=drop)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("energy (J)")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title or "energy over the walk: constant between impacts, "
                 f"dropping by $T_c$ at {'every heel and knee strike' if knees else 'heel strike'}",
                 fontsize=10)
    return fig


def model_diagram(
    walker: CompassGait | None = None, *, q3: float = 0.32, q4: float = -0.72
) -> Figure:
    """Fig. 1-style diagram of the circular-feet compass gait with its coordinates labelled.

    Draws the walker at ``q3`` (right leg from the vertical, counter-clockwise positive, rad)
    and ``q4`` (left leg relative to the right, rad), the right foot on the ground, and labels
    the generalized coordinates ``q1 .. q4`` (``(q1, q2)``: the right foot's arc centre
    ``P_R``), the lengths ``l``, ``a``, ``b``, ``R`` and the masses ``mH`` and ``m``.

    Parameters
    ----------
    walker : CompassGait, optional
        Scalar-parameter walker (default: the paper's, with ``R = 0.3 m``).
    q3, q4 : float
        Configuration drawn (rad).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.patches import Arc, Circle

    w = walker if walker is not None else CompassGait(foot_radius=0.3)
    l, b, R = float(w.leg_length), float(w.leg_com_from_hip), float(w.foot_radius)
    a = l - b
    q = np.array([0.9, R, q3, q4])
    pos = w.positions(q)
    H, PR, PL = pos.hip, pos.right_foot_centre, pos.left_foot_centre
    th_r, th_l = q3, q3 + q4
    up_r = np.array([-np.sin(th_r), np.cos(th_r)])  # foot centre towards hip
    up_l = np.array([-np.sin(th_l), np.cos(th_l)])
    tip_r, tip_l = PR - R * up_r, PL - R * up_l  # the legs' ends (feet's lowest points on axis)

    fig = _new_figure(7.5, 6.2, dpi=110)
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    ax.axhline(0.0, color="0.3", lw=2)
    ax.fill_between([-0.25, 2.1], -0.08, 0.0, color="0.85")
    # legs and feet
    for P, tip, th, colour, name in ((PR, tip_r, th_r, LEG_COLOURS[0], "R"),
                                     (PL, tip_l, th_l, LEG_COLOURS[1], "L")):
        ax.plot([H[0], tip[0]], [H[1], tip[1]], color=colour, lw=3, solid_capstyle="round")
        arc = _foot_arc(P, th, R)
        ax.plot(arc[:, 0], arc[:, 1], color=colour, lw=2.5)
        ax.plot(*P, "o", ms=4, color=colour)
        ax.annotate(f"$P_{name}$", (P[0], P[1]), xytext=(8, -2), textcoords="offset points",
                    fontsize=11, color=colour)
    # masses
    ax.add_patch(Circle(tuple(H), 0.045, color="k", zorder=5))
    ax.annotate("$m_H$", (H[0], H[1]), xytext=(10, 8), textcoords="offset points", fontsize=12)
    for com, colour in ((pos.right_leg_com, LEG_COLOURS[0]), (pos.left_leg_com, LEG_COLOURS[1])):
        ax.add_patch(Circle(tuple(com), 0.03, color=colour, zorder=5))
        ax.annotate("$m$", (com[0], com[1]), xytext=(-18, 0), textcoords="offset points",
                    fontsize=12, color=colour)

    def dim(p0: NDArray[np.float64], p1: NDArray[np.float64], label: str,
            offset: NDArray[np.float64], colour: str = "0.2") -> None:
        o0, o1 = p0 + offset, p1 + offset
        ax.annotate("", xy=tuple(o1), xytext=tuple(o0),
                    arrowprops={"arrowstyle": "<->", "color": colour, "lw": 1})
        for p, o in ((p0, o0), (p1, o1)):
            ax.plot([p[0], o[0]], [p[1], o[1]], color=colour, lw=0.5, ls=":")
        mid = 0.5 * (o0 + o1)
        ax.annotate(label, tuple(mid), xytext=tuple(8 * offset / np.linalg.norm(offset)),
                    textcoords="offset points", fontsize=12, color=colour,
                    ha="center", va="center")

    # lengths along the left leg: l = hip to foot end, b = hip to COM, a = COM to foot end
    n_l = np.array([np.cos(th_l), np.sin(th_l)])  # normal to the left leg, pointing away
    dim(H, tip_l, "$l$", -0.28 * n_l)
    dim(H, pos.left_leg_com, "$b$", -0.14 * n_l)
    dim(pos.left_leg_com, tip_l, "$a$", -0.14 * n_l)
    # foot radius on the left foot
    rim = PL + R * np.array([np.sin(th_l + 0.9), -np.cos(th_l + 0.9)])
    ax.annotate("", xy=tuple(rim), xytext=tuple(PL),
                arrowprops={"arrowstyle": "->", "color": "k", "lw": 1})
    ax.annotate("$R$", tuple(0.5 * (PL + rim)), xytext=(6, -10), textcoords="offset points",
                fontsize=12)
    # q1, q2: position of P_R from the origin O
    O = np.array([0.0, 0.0])
    ax.plot(*O, "ko", ms=4)
    ax.annotate("$O$", (0.0, 0.0), xytext=(-12, -14), textcoords="offset points", fontsize=11)
    ax.annotate("", xy=(1.45, 0.0), xytext=(0.0, 0.0),
                arrowprops={"arrowstyle": "->", "color": "0.4", "lw": 1})
    ax.annotate("$x$", (1.45, 0.0), xytext=(2, -14), textcoords="offset points", fontsize=10)
    ax.annotate("", xy=(0.0, 1.3), xytext=(0.0, 0.0),
                arrowprops={"arrowstyle": "->", "color": "0.4", "lw": 1})
    ax.annotate("$y$", (0.0, 1.3), xytext=(-12, -4), textcoords="offset points", fontsize=10)
    ax.annotate("", xy=(PR[0], -0.16), xytext=(0.0, -0.16),
                arrowprops={"arrowstyle": "<->", "color": "tab:green", "lw": 1})
    ax.annotate("$q_1$", (0.5 * PR[0], -0.16), xytext=(0, -12), textcoords="offset points",
                fontsize=12, color="tab:green", ha="center")
    ax.plot([PR[0], PR[0]], [PR[1], -0.18], color="tab:green", lw=0.5, ls=":")
    ax.annotate("", xy=(PR[0] + 0.12, PR[1]), xytext=(PR[0] + 0.12, 0.0),
                arrowprops={"arrowstyle": "<->", "color": "tab:green", "lw": 1})
    ax.annotate("$q_2$", (PR[0] + 0.12, 0.5 * PR[1]), xytext=(10, 0),
                textcoords="offset points", fontsize=12, color="tab:green", va="center")
    # q3: right leg from the vertical at P_R
    ax.plot([PR[0], PR[0]], [PR[1], PR[1] + 0.55], color="tab:green", lw=0.8, ls="--")
    ax.add_patch(Arc(tuple(PR), 0.44, 0.44, theta1=90.0, theta2=90.0 + np.rad2deg(th_r),
                     color="tab:green", lw=1.2))
    mid3 = PR + 0.22 * np.array([-np.sin(0.5 * th_r), np.cos(0.5 * th_r)])
    ax.annotate("$q_3$", tuple(mid3), xytext=(2, 6), textcoords="offset points", fontsize=12,
                color="tab:green", ha="center", va="bottom")
    # q4: left leg relative to the right leg, at the hip
    d_r = np.rad2deg(np.arctan2(-up_r[1], -up_r[0]))  # downward along the right leg
    d_l = np.rad2deg(np.arctan2(-up_l[1], -up_l[0]))
    ax.add_patch(Arc(tuple(H), 0.3, 0.3, theta1=min(d_r, d_l), theta2=max(d_r, d_l),
                     color="tab:green", lw=1.2))
    mid4 = np.deg2rad(0.5 * (d_r + d_l))
    ax.annotate("$q_4$", tuple(H + 0.15 * np.array([np.cos(mid4), np.sin(mid4)])),
                xytext=(0, -4), textcoords="offset points",
                fontsize=12, color="tab:green", ha="center", va="top")
    ax.set_xlim(-0.3, 2.1)
    ax.set_ylim(-0.35, 1.35)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(
        "compass gait with circular feet (paper Fig. 1): $q = (q_1, q_2, q_3, q_4)$,\n"
        f"$l$ = {l:g} m, $a$ = {a:g} m, $b$ = {b:g} m, $R$ = {R:g} m, "
        f"$m_H$ = {float(w.hip_mass):g} kg, $m$ = {float(w.leg_mass):g} kg",
        fontsize=10,
    )
    return fig


# -- walks of described walkers (TOML models) ----------------------------------------------------
def animate_model_walk(frames: Any, path: str | Path, *, slope: float, title: str = "",
                       fps: float = 30.0, progress: bool = False) -> Path:
    """Animate a described walker's walk to a GIF (or MP4 where ffmpeg exists).

    Draws the ground, every link as a segment (stance-side links blue, the others red, by the
    walker's current labelling), both feet's arcs and the point masses.

    Parameters
    ----------
    frames : pandas.DataFrame
        From :func:`~heelstrike.analysis.walk_tables.model_walk_frames`: rows of links, feet
        and point masses per frame.
    path, slope, title, fps, progress
        As :func:`animate_walk`.

    Returns
    -------
    Path
        The written file.
    """
    out = _animation_file(path)
    xs = frames[["x0_m", "x1_m"]].to_numpy()
    ys = frames[["y0_m", "y1_m"]].to_numpy()
    fig, ax = _walk_scene(float(xs.min()) - 0.3, float(xs.max()) + 0.3, float(ys.max()), slope,
                          (0.1, 0.2), title)
    by_frame = [f for _, f in frames.groupby("frame", sort=True)]
    first = by_frame[0]
    link_names = list(first.loc[first["element"] == "link", "name"])
    links = [ax.plot([], [], lw=3, solid_capstyle="round",
                     color=LEG_COLOURS[0] if name.startswith("stance") else LEG_COLOURS[1])[0]
             for name in link_names]
    feet = [ax.plot([], [], lw=2, color=c)[0] for c in LEG_COLOURS]
    (dots,) = ax.plot([], [], "o", color="k", ms=8)
    label = ax.text(0.02, 0.92, "", transform=ax.transAxes)
    arc = np.linspace(-0.8, 0.8, 25) - 0.5 * np.pi  # about straight down in the slope frame
    arc_unit = _to_world(np.column_stack((np.cos(arc), np.sin(arc))), slope)

    def draw(frame: int) -> list[Artist]:
        f = by_frame[frame]
        kind = f["element"].to_numpy()
        x0, y0 = f["x0_m"].to_numpy(), f["y0_m"].to_numpy()
        x1, y1 = f["x1_m"].to_numpy(), f["y1_m"].to_numpy()
        for line, k in zip(links, np.flatnonzero(kind == "link"), strict=True):
            line.set_data([x0[k], x1[k]], [y0[k], y1[k]])
        for line, k in zip(feet, np.flatnonzero(kind == "foot"), strict=True):
            r = float(f["radius_m"].iloc[k])
            line.set_data(x0[k] + r * arc_unit[:, 0], y0[k] + r * arc_unit[:, 1])
        m = kind == "mass"
        dots.set_data(x0[m], y0[m])
        label.set_text(f"step {int(f['step'].iloc[0]) + 1}   t = {f['t_s'].iloc[0]:.2f} s")
        return [*links, *feet, dots, label]

    return _save_animation(fig, draw, len(by_frame), fps, out, progress)
