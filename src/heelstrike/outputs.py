"""Output files: results in, figures and data files out.

This module computes nothing: it takes the results of :mod:`heelstrike.analysis`, draws them
with :mod:`heelstrike.plots` and writes the data with :mod:`heelstrike.io` (CSV and netCDF).
The few writers that are given a walker rather than a result (:func:`write_walk_figures`,
:func:`write_model_walk_figures`, :func:`reproduce_paper`) get their results from
:mod:`heelstrike.analysis` first.

Every function creates its output directory and returns the paths it wrote, in a fixed order.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from heelstrike.io import save_figure, write_csv, write_netcdf

if TYPE_CHECKING:
    import pandas as pd
    import xarray as xr

    from heelstrike._typing import FloatArray
    from heelstrike.analysis.basin import Basin
    from heelstrike.analysis.gait_map import GaitMap
    from heelstrike.analysis.gaits import Gait
    from heelstrike.analysis.limit_cycle import BifurcationDiagram, Continuation
    from heelstrike.analysis.model_gaits import ImpactMap
    from heelstrike.analysis.paper import PaperFigureData
    from heelstrike.dynamics.hybrid import WalkResult
    from heelstrike.models.compass import CompassGait

__all__ = [
    "bifurcation_gap_note",
    "bifurcation_title",
    "reproduce_paper",
    "write_basin",
    "write_bifurcation_files",
    "write_cost_figures",
    "write_cost_study",
    "write_figure_data",
    "write_gait_map",
    "write_impact_map",
    "write_model_walk_figures",
    "write_powered_energy",
    "write_walk_figures",
]

def _directory(out_dir: str | Path) -> Path:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return out


# -- the paper's figures -------------------------------------------------------------------------
def write_figure_data(data: PaperFigureData, out_dir: str | Path) -> list[Path]:
    """Write ``fig2.csv``, ``fig3a.csv`` and ``fig3b.csv`` into ``out_dir`` (created).

    Parameters
    ----------
    data : PaperFigureData
        From :func:`heelstrike.analysis.paper.paper_figure_data`.
    out_dir : str or Path
        Output directory.

    Returns
    -------
    list of Path
        The files written, in figure order. Columns carry their units: ``R_m`` (m), ``q3_deg``
        (deg), ``q3_rad`` (rad), ``T_J``, ``T_c_J``, ``T_a_J``, ``energy_lost_J`` (J),
        ``eta_J_per_m`` (J/m), ``step_length_m`` (m), ``q2_dot_plus_m_per_s`` (m/s) and the
        flags ``trailing_foot_lifts`` (the impact is admissible) and ``degenerate_wheel``
        (McGeer's wheel, drawn as in the paper; ``fig3b.csv`` also has ``shown``: drawn).
    """
    out = _directory(out_dir)
    fig2_cols = ["R_m", "q3_deg", "q3_rad", "T_J", "T_c_J", "T_a_J", "q2_dot_plus_m_per_s",
                 "trailing_foot_lifts", "degenerate_wheel"]
    fig3a_cols = ["R_m", "q3_deg", "q3_rad", "eta_J_per_m", "energy_lost_J", "step_length_m",
                  "q2_dot_plus_m_per_s", "trailing_foot_lifts", "degenerate_wheel"]
    frames = {
        "fig2.csv": data.figure2[fig2_cols],
        "fig3a.csv": data.figure3a[fig3a_cols],
        "fig3b.csv": data.figure3b.to_frame(),
    }
    return [write_csv(frame, out / name) for name, frame in frames.items()]


def reproduce_paper(
    out_dir: str | Path,
    walker: CompassGait | None = None,
    formats: tuple[str, ...] = ("png", "pdf"),
) -> list[Path]:
    """Write the paper's Figs. 2, 3a and 3b as images plus one CSV of data per figure.

    The data come from :func:`heelstrike.analysis.paper.paper_figure_data`, the drawings from
    :mod:`heelstrike.plots.paper`.

    Parameters
    ----------
    out_dir : str or Path
        Output directory (created if needed).
    walker : CompassGait, optional
        Walker (default: the paper's, ``mH = 2 m = 10 kg``, ``a = b = 0.5 m``, ``l = 1 m``).
    formats : tuple of str
        Image formats understood by matplotlib.

    Returns
    -------
    list of Path
        ``fig2.png, fig2.pdf, fig2.csv, fig3a.png, ...`` in that order.
    """
    from heelstrike.analysis.paper import paper_figure_data
    from heelstrike.plots.paper import figure2, figure3a, figure3b

    out = _directory(out_dir)
    data = paper_figure_data(walker)
    csvs = dict(zip(("fig2", "fig3a", "fig3b"), write_figure_data(data, out), strict=True))
    figures = {
        "fig2": figure2(data.figure2),
        "fig3a": figure3a(data.figure3a),
        "fig3b": figure3b(data.figure3b),
    }
    paths: list[Path] = []
    for name, fig in figures.items():
        for ext in formats:
            path = out / f"{name}.{ext}"
            save_figure(fig, path, dpi=150, metadata=_metadata(ext))
            paths.append(path)
        paths.append(csvs[name])
    return paths


def _metadata(ext: str) -> dict[str, str | None]:
    """Reproducible files: no creation date in PDFs."""
    if ext == "pdf":
        return {"CreationDate": None, "Creator": "heelstrike"}
    return {"Software": "heelstrike"} if ext == "png" else {}


# -- bifurcation diagrams ------------------------------------------------------------------------
def bifurcation_title(walker: Any) -> str:
    """The bifurcation figure's title: ``"compass gait, R = 0.3 m: bifurcation diagram"`` for
    the compass gait, ``"<model name>: bifurcation diagram"`` for a described walker."""
    desc = walker.description
    if desc is not None:
        return f"{desc.name}: bifurcation diagram"
    return f"compass gait, R = {float(walker.foot_radius):g} m: bifurcation diagram"


def bifurcation_gap_note(start_deg: float, onset_deg: float, stable: bool) -> str:
    """The note of a bifurcation range that starts below the walker's first gait.

    ``start_deg``: the range's first slope; ``onset_deg``: the period-one branch's first slope
    (where the first gait was found; a stable one is preferred); ``stable``: that gait's
    stability. Used by the figure's title and by ``heelstrike bifurcation``'s output.
    """
    kind = "stable gait" if stable else "gait"
    return f"no {kind} found from {start_deg:.4g} to {onset_deg:.4g} deg"


def write_bifurcation_files(
    diagram: BifurcationDiagram, branch: Continuation, out_dir: str | Path, title: str
) -> list[Path]:
    """Write a bifurcation diagram and its period-one branch into ``out_dir``.

    Parameters
    ----------
    diagram : BifurcationDiagram
        Slopes (rad), shape (K,); impact angles (rad) and periods (s), shape (K, record).
    branch : Continuation
        The period-one gait continued in the slope.
    out_dir : str or Path
        Output directory.
    title : str
        Title of the figure.

    Returns
    -------
    list of Path
        ``bifurcation.png`` and ``.pdf`` (:func:`heelstrike.plots.gait.bifurcation_figure`),
        ``bifurcation.csv`` (one row per recorded step: ``slope_deg``, ``impact_angle_rad``,
        ``period_s``, and ``status``, how that slope's walk ended: ``completed``, or e.g.
        ``fell_backward`` on rows whose step was not taken, which are NaN; empty where the
        slope was not walked, below the first gait) and ``period_one_branch.csv``
        (``slope_deg``, ``impact_angle_rad``, ``period_s``, ``spectral_radius``, ``stable``).
        If the branch starts above the diagram's first slope (no gait below it), that part of
        the range is shaded on the figure and noted in its title.
    """
    from heelstrike.plots.gait import bifurcation_figure

    out = _directory(out_dir)
    # a range that starts below the walker's first gait (the branch starts later): that part is
    # shaded, nothing is drawn there, and the title says so
    gap = (np.rad2deg([diagram.slopes[0], branch.values[0]]) if branch.values.size
           and branch.values[0] > diagram.slopes[0] else None)
    if gap is not None:
        title += f"\n{bifurcation_gap_note(gap[0], gap[1], branch.cycles[0].stable)} (shaded)"
    fig = bifurcation_figure(diagram, branch, title=title)
    if gap is not None:
        for ax in fig.axes:
            ax.axvspan(gap[0], gap[1], color="0.85", lw=0, zorder=0)
    paths = [out / "bifurcation.png", out / "bifurcation.pdf"]
    for p in paths:
        save_figure(fig, p, metadata=_metadata(p.suffix[1:]))  # no creation date
    record = diagram.impact_angles.shape[1]

    def degrees(slopes: FloatArray) -> list[str]:
        # 12 significant digits, written as text: the slopes come from degrees, and
        # rad2deg(deg2rad(2)) is 2.0000000000000004, while even a rounded 4.2 reads
        # 4.2000000000000002 in the 17 digits of every other float column
        return [format(float(v), ".12g") for v in np.rad2deg(slopes)]

    csv = write_csv(
        {
            "slope_deg": np.repeat(degrees(diagram.slopes), record),
            "impact_angle_rad": diagram.impact_angles.ravel(),
            "period_s": diagram.periods.ravel(),
            "status": np.repeat(np.asarray(diagram.statuses or ("",) * diagram.slopes.size,
                                           dtype=object), record),
        },
        out / "bifurcation.csv",
    )
    bcsv = write_csv(
        {
            "slope_deg": degrees(branch.values),
            "impact_angle_rad": [c.impact_angle for c in branch.cycles],
            "period_s": [c.period for c in branch.cycles],
            "spectral_radius": [c.spectral_radius for c in branch.cycles],
            "stable": [c.stable for c in branch.cycles],
        },
        out / "period_one_branch.csv",
    )
    return [*paths, csv, bcsv]


# -- basins and gait maps ------------------------------------------------------------------------
def write_basin(basin: Basin, out_dir: str | Path, stem: str = "basin") -> tuple[Path, Path]:
    """Write the basin's figure (``<stem>.png``) and dataset (``<stem>.nc``) into ``out_dir``.

    Returns
    -------
    (Path, Path)
        The PNG (:func:`heelstrike.plots.gait.basin_figure`) and the netCDF file
        (:func:`heelstrike.io.write_netcdf` of ``basin.dataset``).
    """
    from heelstrike.plots.gait import basin_figure

    return _figure_and_dataset(basin_figure(basin), basin.dataset, out_dir, stem)


def write_gait_map(gmap: GaitMap, out_dir: str | Path, stem: str = "gait_map") -> tuple[Path, Path]:
    """Write the gait map's figure (``<stem>.png``) and dataset (``<stem>.nc``) into ``out_dir``.

    Returns
    -------
    (Path, Path)
        The PNG (:func:`heelstrike.plots.gait.gait_map_figure`) and the netCDF file (the
        dataset, with ``stable`` stored as ``int8``).
    """
    from heelstrike.plots.gait import gait_map_figure

    ds = gmap.dataset.copy()
    ds["stable"] = ds["stable"].astype(np.int8)
    return _figure_and_dataset(gait_map_figure(gmap), ds, out_dir, stem)


def _figure_and_dataset(
    fig: Any, ds: xr.Dataset, out_dir: str | Path, stem: str
) -> tuple[Path, Path]:
    """Write ``<stem>.png`` (130 dpi) and ``<stem>.nc`` into ``out_dir``."""
    out = _directory(out_dir)
    png = out / f"{stem}.png"
    save_figure(fig, png, dpi=130, metadata=_metadata("png"))
    return png, write_netcdf(ds, out / f"{stem}.nc")


# -- the walk, seen ------------------------------------------------------------------------------
def _write_figures_and_tables(
    out: Path, figures: Mapping[str, tuple[Any, pd.DataFrame]], impacts: pd.DataFrame
) -> list[Path]:
    paths: list[Path] = []
    for stem, (fig, table) in figures.items():
        png = out / f"{stem}.png"
        save_figure(fig, png, metadata=_metadata("png"))
        paths += [png, write_csv(table, out / f"{stem}.csv")]
    paths.append(write_csv(impacts, out / "impacts.csv"))
    return paths


def write_walk_figures(walker: CompassGait, walk: WalkResult, out_dir: str | Path) -> list[Path]:
    """Write a compass-gait walk's figures (PNG) and their data (CSV) into ``out_dir``.

    Files: ``strobe.png/.csv`` (stick figures over the first step), ``phase_portrait.png/.csv``,
    ``step.png/.csv`` (joint angles and ground reaction over the first step),
    ``energy.png/.csv`` (energy over the walk) and ``impacts.csv`` (the energy drop at every
    impact, in time order: the compass gait's are heel strikes). The tables (and their columns)
    are those of :mod:`heelstrike.analysis.walk_tables`.

    Returns
    -------
    list of Path
        The written files.
    """
    from heelstrike.analysis.walk_tables import (
        phase_portrait_table,
        step_table,
        strobe_table,
        walk_energy_table,
        walk_impact_table,
    )
    from heelstrike.plots.gait import (
        energy_figure,
        phase_portrait_figure,
        step_figure,
        strobe_figure,
    )

    out = _directory(out_dir)
    R = float(walker.foot_radius)
    what = f"R = {R:g} m, slope = {np.rad2deg(walk.slope):.2f} deg"
    strobe = strobe_table(walker, walk, 0)
    portrait = phase_portrait_table(walk)
    step = step_table(walker, walk, 0)
    energy = walk_energy_table(walker, walk)
    impacts = walk_impact_table(walker, walk)
    figures = {
        "strobe": (strobe_figure(strobe, foot_radius=R, slope=walk.slope,
                                 title=f"compass gait, {what}: one step, strobed"), strobe),
        "phase_portrait": (phase_portrait_figure(
            portrait, title=f"compass gait, {what}: phase portrait"), portrait),
        "step": (step_figure(step, title=f"compass gait, {what}: one step",
                             labels={"q3_rad": "stance leg $q_3$", "q4_rad": "hip angle $q_4$",
                                     "swing_rad": "swing leg $q_3 + q_4$"}), step),
        "energy": (energy_figure(energy, impacts, title=f"compass gait, {what}: energy"),
                   energy),
    }
    return _write_figures_and_tables(out, figures, impacts)


def write_model_walk_figures(walker: Any, walk: WalkResult, out_dir: str | Path) -> list[Path]:
    """Write a described walker's walk figures (PNG) and data (CSV) into ``out_dir``.

    Files: ``strobe.png/.csv`` (stick figures of the walker's own links over the first step,
    :func:`~heelstrike.analysis.walk_tables.model_strobe_table`), ``phase_portrait.png/.csv``
    (:func:`~heelstrike.analysis.walk_tables.model_phase_portrait_table`), ``step.png/.csv``
    (the walker's angles and the stance foot's ground reaction over the first step, its locked
    joints held: :func:`~heelstrike.analysis.walk_tables.step_table`), ``energy.png/.csv``
    (:func:`~heelstrike.analysis.walk_tables.walk_energy_table`: every impact, knee strikes
    included, drops the total; the figure marks heel and knee strikes apart) and
    ``impacts.csv`` (:func:`~heelstrike.analysis.walk_tables.walk_impact_table`: every impact
    in time order, knee strikes included, its ``kind`` in a column).

    Returns
    -------
    list of Path
        The written files.
    """
    from heelstrike.analysis.walk_tables import (
        model_phase_portrait_table,
        model_strobe_table,
        step_table,
        walk_energy_table,
        walk_impact_table,
    )
    from heelstrike.plots.gait import (
        energy_figure,
        model_strobe_figure,
        phase_portrait_figure,
        step_figure,
    )

    out = _directory(out_dir)
    what = f"{walker.description.name}, slope = {np.rad2deg(walk.slope):.2f} deg"
    strobe = model_strobe_table(walker, walk, 0)
    portrait = model_phase_portrait_table(walker, walk)
    step = step_table(walker, walk, 0)
    energy = walk_energy_table(walker, walk)
    impacts = walk_impact_table(walker, walk)
    swing = walker.description.links[walker.joint_index("hip") - 2].name
    figures = {
        "strobe": (model_strobe_figure(strobe, slope=walk.slope,
                                       title=f"{what}: one step, strobed"), strobe),
        "phase_portrait": (phase_portrait_figure(
            portrait, title=f"{what}: phase portrait",
            labels=(f"stance ({walker.coordinate_names[2]})", f"swing ({swing}, absolute)")),
            portrait),
        "step": (step_figure(step, title=f"{what}: one step",
                             labels={"swing_rad": f"swing leg ({swing}, absolute)"}), step),
        "energy": (energy_figure(energy, impacts, title=f"{what}: energy"), energy),
    }
    return _write_figures_and_tables(out, figures, impacts)


# -- described walkers' impact maps --------------------------------------------------------------
def write_impact_map(
    m: ImpactMap, out_dir: str | Path, *, units: Mapping[str, str] | None = None
) -> list[Path]:
    """Write ``impact_map.png`` (three panels) and ``impact_map.csv`` (one row per point).

    Parameters
    ----------
    m : ImpactMap
    out_dir : str or Path
        Created if needed.
    units : mapping of str to str, optional
        Units of the swept parameters for the axis labels (see
        :func:`heelstrike.models.description.parameter_units`).

    Returns
    -------
    list of Path
        The PNG (:func:`heelstrike.plots.models.impact_map_figure`) and the CSV: the two swept
        values (x varying fastest; columns named with their unit, e.g. ``R_m`` and
        ``angle_rad``, when ``units`` knows it), ``T_J``, ``T_c_J``, ``T_a_J`` (J),
        ``eta_J_per_m`` (J/m), ``step_length_m`` (m), ``trailing_normal_velocity_m_per_s`` (m/s) and
        ``trailing_foot_lifts`` (0 or 1) and ``trailing_foot_held`` (0 or 1: the ground holds
        the trailing foot, and the energies include that contact's loss).
    """
    from heelstrike.analysis.model_gaits import ANGLE
    from heelstrike.plots.models import impact_map_figure

    out = _directory(out_dir)
    X, Y = np.meshgrid(np.asarray(m.x, dtype=float), np.asarray(m.y, dtype=float))
    known = {**(units or {}), ANGLE: "rad"}

    def column(name: str) -> str:
        """``R`` -> ``R_m``, ``angle`` -> ``angle_rad``, ``Is`` -> ``Is_kg_m2``; bare if the
        unit is not known."""
        unit = known.get(name)
        if not unit or unit == "1":
            return name
        return f"{name}_{unit.replace('/', '_per_').replace('^', '').replace(' ', '_')}"

    csv_path = write_csv(
        {
            column(m.x_name): X.ravel(),
            column(m.y_name): Y.ravel(),
            "T_J": np.asarray(m.T, dtype=float).ravel(),
            "T_c_J": np.asarray(m.T_c, dtype=float).ravel(),
            "T_a_J": np.asarray(m.T_a, dtype=float).ravel(),
            "eta_J_per_m": np.asarray(m.eta, dtype=float).ravel(),
            "step_length_m": np.asarray(m.step_length, dtype=float).ravel(),
            "trailing_normal_velocity_m_per_s":
                np.asarray(m.trailing_normal_velocity, dtype=float).ravel(),
            # 1/0, not True/False: the file is all numbers (np.loadtxt reads it whole)
            "trailing_foot_lifts": np.asarray(m.lifts, dtype=bool).ravel().astype(int),
            "trailing_foot_held": np.asarray(m.held, dtype=bool).ravel().astype(int),
        },
        out / "impact_map.csv",
    )
    png = out / "impact_map.png"
    save_figure(impact_map_figure(m, units), png, dpi=120, metadata=_metadata("png"))
    return [png, csv_path]


# -- powered gaits and the cost study ------------------------------------------------------------
def write_powered_energy(
    gait: Gait, energy: pd.DataFrame, impacts: pd.DataFrame, out_dir: str | Path
) -> tuple[Path, Path]:
    """Write the energy of one period of a powered gait: ``powered_energy.png`` and ``.csv``.

    Parameters
    ----------
    gait : Gait
        A powered gait (its ``actuation`` set): its speed, works and ``T_c`` title the figure.
    energy, impacts : pandas.DataFrame
        From :func:`heelstrike.analysis.powered.energy_book_tables` (energies in J, times in s).
    out_dir : str or Path
        Output directory.

    Returns
    -------
    (Path, Path)
        The figure (:func:`heelstrike.plots.gait.energy_figure`) and the ``energy`` table.
    """
    from heelstrike.plots.gait import energy_figure

    out = _directory(out_dir)
    act = gait.actuation
    if act is None:
        raise ValueError("write_powered_energy draws a powered gait (its actuation is None)")
    name = act.model or "compass gait"
    # each impact's own loss (a kneed walker's knee strike, then the heel strike)
    losses = ", ".join(f"{str(r.kind).replace('_', ' ')} loses $T_c$ = {float(r.T_c_J):.4f} J"
                       for r in impacts.itertuples(index=False))
    fig = energy_figure(energy, impacts, title=(
        f"{name}, powered gait at {gait.speed:.3g} m/s: {act.torque_joint} torque "
        f"{act.torque_work:+.4f} J over the step,\npush-off {act.push_off_work:+.4f} J "
        f"(jump at heel strike){',' if len(impacts) < 2 else chr(10)} {losses}"))
    png = out / "powered_energy.png"
    save_figure(fig, png, metadata=_metadata("png"))
    return png, write_csv(energy, out / "powered_energy.csv")


def write_cost_study(ds: xr.Dataset, path: str | Path) -> Path:
    """Write the cost study (:func:`heelstrike.analysis.cost_study.cost_study`) to netCDF at
    ``path`` (its directory made if needed) and return the path."""
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    return write_netcdf(ds, p)


def write_cost_figures(ds: xr.Dataset, out: str | Path) -> list[Path]:
    """Write the cost study's figures (PNG) into ``out``; return their paths.

    ``cost_of_transport.png``, ``eta.png`` and ``actuator_work.png``
    (:func:`heelstrike.plots.powered.cost_figure`, each only if the variable has a finite
    value), then ``paper_vs_gait.png`` (:func:`heelstrike.plots.powered.paper_comparison_figure`)
    for a study over step length that holds the paper's impact-only ``eta_paper``.
    """
    from heelstrike.plots.powered import cost_figure, paper_comparison_figure

    d = _directory(out)
    paths = []
    for var in ("cost_of_transport", "eta", "actuator_work"):
        if np.any(np.isfinite(ds[var].values)):
            p = d / f"{var}.png"
            save_figure(cost_figure(ds, var), p, dpi=120, metadata=_metadata(p.suffix[1:]))
            paths.append(p)
    if str(ds.attrs.get("target", "step_length")) == "step_length" and "eta_paper" in ds:
        p = d / "paper_vs_gait.png"
        save_figure(paper_comparison_figure(ds), p, dpi=120,
                    metadata=_metadata(p.suffix[1:]))
        paths.append(p)
    return paths
