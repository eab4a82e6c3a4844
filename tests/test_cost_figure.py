"""The cost study's figure marks unstable gaits (a QA finding: they looked like any other)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from heelstrike.plots.powered import cost_figure, paper_comparison_figure


def _study(stable: np.ndarray) -> xr.Dataset:
    shape = stable.shape
    cot = np.linspace(0.01, 0.05, stable.size).reshape(shape)
    cot[0, 0, 2] = np.nan  # a grid point without a gait (R = 0, L = 0.5)
    dims = ("actuation", "radius", "step_length")
    return xr.Dataset(
        {"cost_of_transport": (dims, cot, {"units": "1"}),
         "stable": (dims, np.where(np.isfinite(cot), stable, np.nan))},
        coords={"actuation": ["pushoff"], "radius": [0.0, 0.3],
                "step_length": ("step_length", [0.3, 0.4, 0.5], {"units": "m"})},
        attrs={"target": "step_length"},
    )


def test_unstable_gaits_are_marked_and_only_they() -> None:
    stable = np.array([[[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]]])
    fig = cost_figure(_study(stable))
    ax = fig.axes[0]
    marked = [ln for ln in ax.get_lines() if ln.get_marker() == "x"]
    xs = np.concatenate([ln.get_xdata() for ln in marked])
    ys = np.concatenate([ln.get_ydata() for ln in marked])
    # (R = 0, L = 0.4) and (R = 0.3, L = 0.3) are unstable; (R = 0, L = 0.5) has no gait
    assert sorted(zip(xs.tolist(), ys.tolist(), strict=True)) == sorted(
        [(0.4, float(np.linspace(0.01, 0.05, 6)[1])), (0.3, float(np.linspace(0.01, 0.05, 6)[3]))])
    assert "unstable gait" in [t.get_text() for t in ax.get_legend().get_texts()]
    assert "red x: unstable" in fig.texts[0].get_text()


def test_grid_points_without_a_gait_are_marked_and_only_they() -> None:
    # a QA finding: a point without a gait was a silent gap in its line
    stable = np.array([[[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]]])
    ds = _study(stable)
    fig = cost_figure(ds)
    ax = fig.axes[0]
    missing = [ln for ln in ax.get_lines() if ln.get_marker() == "v"]
    assert len(missing) == 1 and missing[0].get_xdata().tolist() == [0.5]  # R = 0, L = 0.5
    assert "R = 0 m: no gait found" in [t.get_text() for t in ax.get_legend().get_texts()]
    assert "no gait found" in fig.texts[0].get_text()
    # the paper comparison marks the same point (against R, in the L = 0.5 m panel)
    ds["work_per_metre"] = ds["cost_of_transport"] * 100.0
    ds["eta_paper"] = (("radius", "step_length"), np.ones((2, 3)))
    fig = paper_comparison_figure(ds)
    marks = [[ln.get_xdata().tolist() for ln in a.get_lines() if ln.get_marker() == "v"]
             for a in fig.axes]
    assert marks == [[], [], [[0.0]]]


def test_paper_comparison_draws_the_wheels_zero_loss_as_a_marker() -> None:
    # QA sweep 4: at R = l the paper's eta is round-off (1e-32 J/m); on the log axis it
    # stretched the figure over 30 decades and squeezed every real value into the top band
    stable = np.ones((1, 2, 3))
    ds = _study(stable)
    ds["work_per_metre"] = ds["cost_of_transport"] * 100.0
    ds["eta_paper"] = (("radius", "step_length"), np.array([[2.0, 2.5, 3.0], [1e-32, 0, 2e-32]]))
    fig = paper_comparison_figure(ds)
    for ax in fig.axes:
        lo, hi = ax.get_ylim()
        assert lo > 1e-3 and hi < 1e2  # the axis spans the data, not the round-off
        wheel = [ln for ln in ax.get_lines() if ln.get_marker() == "D" and ln.get_color() == "k"]
        assert len(wheel) == 1 and wheel[0].get_xdata().tolist() == [0.3]
        # QA sweep 9: not the open triangle that means "no gait found" on the same edge
        assert not [ln for ln in ax.get_lines() if ln.get_marker() == "v" and ln.get_color() == "k"]


def test_cost_figure_axis_says_per_step() -> None:
    # QA sweep 4: "actuator work (J)" did not say it is per step: the variable's long name is
    stable = np.ones((1, 2, 3))
    ds = _study(stable)
    ds["actuator_work"] = (ds["cost_of_transport"].dims, ds["cost_of_transport"].values,
                           {"units": "J", "long_name": "actuator work per step"})
    fig = cost_figure(ds, "actuator_work")
    assert fig.axes[0].get_ylabel() == "actuator work per step (J)"


def test_cost_figure_labels_fit_and_legend_leaves_the_data() -> None:
    # QA sweep 6 (F8): eta.png's y label ran off the figure ("ollision loss per metre..."),
    # the legend covered data points, and values over five decades lay on the axis
    stable = np.ones((1, 2, 3))
    ds = _study(stable)
    ds["eta"] = ds["cost_of_transport"].copy()
    ds["eta"].attrs = {"units": "J/m", "long_name": "collision loss per metre T_c / L_S (eq. 16)"}
    ds["eta"][0, 1] = [1e-5, 2e-5, 4e-5]  # a near-wheel row, decades below the other
    fig = cost_figure(ds, "eta")
    fig.canvas.draw()
    ax = fig.axes[0]
    frame = fig.bbox
    label = ax.yaxis.label.get_window_extent()
    assert frame.x0 <= label.x0 and label.x1 <= frame.x1
    assert frame.y0 <= label.y0 and label.y1 <= frame.y1
    assert ax.get_yscale() == "log"
    legend = ax.get_legend().get_window_extent()
    for line in ax.get_lines():
        xy = np.column_stack([line.get_xdata(), line.get_ydata()]).astype(float)
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if xy.size and line.get_transform() == ax.transData:
            for px, py in ax.transData.transform(xy):
                assert not legend.contains(px, py), (line.get_label(), px, py)
    # values within two decades keep a linear axis
    assert cost_figure(_study(stable)).axes[0].get_yscale() == "linear"


def test_cost_legend_lists_what_is_drawn_radii_first() -> None:
    # QA sweep 7 (P3): "unstable gait" was in the legend with no unstable gait drawn, and the
    # markers' entries sat between the radii's lines
    ds = _study(np.ones((1, 2, 3)))
    labels = [t.get_text() for t in cost_figure(ds).axes[0].get_legend().get_texts()]
    assert "unstable gait" not in labels
    assert labels == ["R = 0 m", "R = 0.3 m", "R = 0 m: no gait found"]
    stable = np.array([[[1.0, 1.0, 0.0], [1.0, 0.0, 1.0]]])
    labels = [t.get_text() for t in cost_figure(_study(stable)).axes[0].get_legend().get_texts()]
    assert labels == ["R = 0 m", "R = 0.3 m", "unstable gait", "R = 0 m: no gait found"]


def test_a_gait_of_undecided_stability_is_neither_stable_nor_unstable() -> None:
    # issue 35: at McGeer's wheel (R = l) the study's flags alternated 1, 0, 1, 0 and the
    # comparison figure marked the wheel "unstable" where its note says stability is undecided
    from types import SimpleNamespace

    from heelstrike.analysis.cost_study import _row

    def gait(undecided: bool) -> SimpleNamespace:
        act = SimpleNamespace(push_off_work=1e-13, torque_work=0.0, parameter=0.0, gains={})
        return SimpleNamespace(
            cost_of_transport=0.0, eta=0.0, actuator_work=1e-13, collision_loss=1e-13,
            step_length=0.5, period=0.6, speed=0.8, impact_angle=0.25, actuation=act,
            multipliers=np.array([1.0 + 1e-9, 0.3]), stable=False, energy_balance_error=0.0,
            leg_crossings=1, stability_undecided=undecided)

    assert _row(gait(False))["stable"] == 0.0  # type: ignore[arg-type]
    assert np.isnan(_row(gait(True))["stable"])  # type: ignore[arg-type]
    ds = _study(np.ones((1, 2, 3)))
    ds["stable"][0, 1] = [np.nan, np.nan, np.nan]  # the wheel's row: undecided
    crosses = [ln for ln in cost_figure(ds).axes[0].get_lines() if ln.get_marker() == "x"]
    assert all(len(ln.get_xdata()) == 0 for ln in crosses)
