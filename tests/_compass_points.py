"""Test reference: the compass gait's point Jacobians written out by hand (not used by the package).

The package assembles the compass mass matrix and forces from ``CompassGait._jacobian_columns``;
the tests build them again from these full ``(..., 2, 4)`` Jacobians (``M = sum m J^T J``) as an
independent derivation.
"""

from __future__ import annotations

import numpy as np

from heelstrike.models.compass import CompassGait


def point_jacobians(walker: CompassGait, q: np.ndarray) -> tuple[np.ndarray, ...]:
    """Jacobians (..., 2, 4) of the hip, right-leg and left-leg centres of mass at ``q``."""
    l, b, R = (np.asarray(getattr(walker, k), dtype=float)
               for k in ("leg_length", "leg_com_from_hip", "foot_radius"))
    s = l - R
    q3, q34 = q[..., 2], q[..., 2] + q[..., 3]

    def de(theta: np.ndarray) -> np.ndarray:  # d/dtheta of a leg's unit vector (-sin, cos)
        return np.stack((-np.cos(theta), -np.sin(theta)), axis=-1)

    de3, de34 = de(q3), de(q34)
    shape = np.broadcast_shapes(q3.shape, s.shape)
    eye = np.broadcast_to(np.eye(2), (*shape, 2, 2))
    zero = np.zeros((*shape, 2))

    def jac(col3: np.ndarray, col4: np.ndarray) -> np.ndarray:
        cols = np.broadcast_arrays(col3, col4, zero)
        return np.concatenate((eye, cols[0][..., None], cols[1][..., None]), axis=-1)

    J_H = jac(s[..., None] * de3, zero)
    J_R = jac((s - b)[..., None] * de3, zero)
    J_L = jac(s[..., None] * de3 - b[..., None] * de34, -b[..., None] * de34)
    return J_H, J_R, J_L
