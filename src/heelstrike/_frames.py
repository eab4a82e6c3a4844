"""Frames of reference shared by the tables (:mod:`heelstrike.analysis.walk_tables`) and the
drawings (:mod:`heelstrike.plots`): the slope frame of the models and the world frame."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["slope_to_world"]


def slope_to_world(points: NDArray[np.float64], slope: float) -> NDArray[np.float64]:
    """Points of the slope frame in the world frame.

    Parameters
    ----------
    points : ndarray, shape (..., 2)
        Positions (m) in the slope frame (x along the ground, rising towards +x; y normal to it).
    slope : float
        Ground slope (rad).

    Returns
    -------
    ndarray, shape (..., 2)
        The same points (m) in the world frame (x horizontal, y up).
    """
    c, s = np.cos(slope), np.sin(slope)
    x, y = points[..., 0], points[..., 1]
    return np.stack((c * x - s * y, s * x + c * y), axis=-1)
