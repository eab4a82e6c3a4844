"""Every figure draws its data inside its axes, clear of its legend, its labels and its caption.

QA findings (issue 35): Fig. 2's and Fig. 3a's R = 0 curve ran under the legend between 14 and
22 deg; the cost study's comparison figure drew lines diving off a log axis at McGeer's wheel
(work of round-off, 1e-13 J) and its y label ran under a five-line caption.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.transforms import Bbox

from heelstrike.analysis.paper import paper_figure_data
from heelstrike.plots import figure2, figure3a, figure3b
from heelstrike.plots.powered import NO_WORK_LABEL, cost_figure, paper_comparison_figure


def _data_points(ax: object) -> np.ndarray:
    """Display coordinates of every finite data point of the lines drawn in data units."""
    pts = []
    for line in ax.get_lines():  # type: ignore[attr-defined]
        if line.get_transform() != ax.transData:  # type: ignore[attr-defined]
            continue  # edge markers (axes coordinates) are placed, not data
        xy = np.column_stack([line.get_xdata(), line.get_ydata()]).astype(float)
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        if xy.size:
            pts.append(ax.transData.transform(xy))  # type: ignore[attr-defined]
    return np.concatenate(pts) if pts else np.empty((0, 2))


def assert_figure_is_readable(fig: Figure) -> None:
    """Data inside the axes; no legend over data; labels, titles and caption inside the
    figure and clear of each other."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    frame = fig.bbox
    texts: list[tuple[str, Bbox]] = []
    legends = [lg for lg in [*fig.legends, *(a.get_legend() for a in fig.axes)] if lg]
    for ax in fig.axes:
        if not ax.get_lines() and not ax.collections:
            continue
        box = ax.get_window_extent(renderer)
        pts = _data_points(ax)
        tol = 1.0  # px: a point on the frame is inside
        inside = ((pts[:, 0] >= box.x0 - tol) & (pts[:, 0] <= box.x1 + tol)
                  & (pts[:, 1] >= box.y0 - tol) & (pts[:, 1] <= box.y1 + tol))
        assert inside.all(), (ax.get_title(), pts[~inside][:5], box)
        for legend in legends:
            lb = legend.get_window_extent(renderer)
            covered = [(px, py) for px, py in pts if lb.contains(px, py)]
            assert not covered, (ax.get_title(), covered[:5])
        for label in (ax.xaxis.label, ax.yaxis.label, ax.title):
            if label.get_text():
                texts.append((label.get_text(), label.get_window_extent(renderer)))
    for t in fig.texts:
        if t.get_text():
            texts.append((t.get_text(), t.get_window_extent(renderer)))
    for text, bb in texts:
        assert frame.x0 - 1 <= bb.x0 and bb.x1 <= frame.x1 + 1, text
        assert frame.y0 - 1 <= bb.y0 and bb.y1 <= frame.y1 + 1, text
    for i, (ta, a) in enumerate(texts):
        for tb, b in texts[i + 1:]:
            assert not a.overlaps(b), (ta, tb)
    for legend in legends:  # a legend covers no title, label or caption either
        lb = legend.get_window_extent(renderer)
        for text, bb in texts:
            assert not lb.overlaps(bb), (text, "under the legend")


@pytest.fixture(scope="module")
def paper() -> object:
    return paper_figure_data()


def test_figure2_is_readable(paper: object) -> None:
    assert_figure_is_readable(figure2(paper.figure2))  # type: ignore[attr-defined]


def test_figure3a_is_readable(paper: object) -> None:
    assert_figure_is_readable(figure3a(paper.figure3a))  # type: ignore[attr-defined]


def test_figure3b_is_readable(paper: object) -> None:
    assert_figure_is_readable(figure3b(paper.figure3b))  # type: ignore[attr-defined]


def _study(work_at_wheel: float, stable_at_wheel: float) -> xr.Dataset:
    R = np.array([0.0, 0.5, 1.0])
    L = np.array([0.3])
    work = np.array([[[0.8], [0.3], [work_at_wheel]]])  # J/m, (actuation, radius, L)
    cot = work / (10.0 * 9.81)
    stable = np.array([[[1.0], [0.0], [stable_at_wheel]]])
    dims = ("actuation", "radius", "step_length")
    return xr.Dataset(
        {"cost_of_transport": (dims, cot, {"units": "1"}),
         "work_per_metre": (dims, work, {"units": "J/m"}),
         "stable": (dims, stable),
         "eta_paper": (("radius", "step_length"), np.array([[5.0], [1.5], [1e-32]]))},
        coords={"actuation": ["pushoff"], "radius": R,
                "step_length": ("step_length", L, {"units": "m"})},
        attrs={"target": "step_length", "work_floor_J": 1e-8},
    )


def test_cost_figures_are_readable() -> None:
    ds = _study(4e-13, np.nan)
    assert_figure_is_readable(cost_figure(ds))
    assert_figure_is_readable(paper_comparison_figure(ds))


def test_a_gait_needing_no_work_is_an_edge_marker_not_a_dive() -> None:
    fig = paper_comparison_figure(_study(4e-13, np.nan))
    ax = fig.axes[0]
    lo, hi = ax.get_ylim()
    assert lo > 1e-2 and hi < 1e2  # the axis spans the real values, not the round-off
    edge = [ln for ln in ax.get_lines() if ln.get_label() == f"pushoff: {NO_WORK_LABEL}"]
    assert len(edge) == 1 and edge[0].get_xdata().tolist() == [1.0]
    # undecided stability (NaN) is not drawn as unstable; the unstable gait at R = 0.5 is
    crosses = [ln for ln in ax.get_lines() if ln.get_marker() == "x"]
    assert np.concatenate([ln.get_xdata() for ln in crosses]).tolist() == [0.5]
    # a real (small) cost is drawn on the line
    fig = paper_comparison_figure(_study(2e-4, 1.0))
    line = next(ln for ln in fig.axes[0].get_lines() if ln.get_label() == "pushoff: W_act / L")
    assert np.asarray(line.get_ydata(), dtype=float)[2] == pytest.approx(2e-4)
