"""The cost study's figure marks unstable gaits (a QA finding: they looked like any other)."""

from __future__ import annotations

import numpy as np
import xarray as xr

from heelstrike.plots.powered import cost_figure


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
