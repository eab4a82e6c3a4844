"""Derivatives through an event: the saltation matrix and the Poincare-section projection.

A hybrid system flows by ``x' = f-(x)`` until a guard ``g(x)`` falls (or rises) through zero at
the event time ``t_e``, jumps by a reset ``x+ = Delta(x-)`` and flows on by ``x' = f+(x)``. The
Jacobian of the state a fixed time after the event with respect to the state a fixed time before
it is **not** ``D Delta`` times the flow's Jacobian: moving the initial state moves the event
time, and the two flows differ there. The first-order correction gives the saltation matrix

.. math::

    \\Xi = D\\Delta + \\frac{\\left(f^+ - D\\Delta\\, f^-\\right) \\nabla g^T}{\\nabla g^T f^-},

all evaluated at the event (``f-`` and ``\\nabla g`` at ``x-``, ``f+`` at ``x+``), so that
``delta x(t_e + 0) = Xi delta x(t_e - 0)``. A map from one section to the next (a step map
whose section is an event surface ``s(x) = 0``) then removes the variation along the flow with

.. math::

    \\Pi = I - \\frac{f\\, \\nabla s^T}{\\nabla s^T f},

``f`` and ``\\nabla s`` at the point on the section. Both are pure algebra: they know no walker
and broadcast over leading axes (a batch of events at once). The guard's normal speed
``\\nabla g^T f^-`` must not vanish (a grazing event has no derivative): such an event is
refused with :class:`GrazingEventError`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._typing import FloatArray

__all__ = ["GrazingEventError", "saltation_matrix", "section_projection"]

#: Smallest relative normal speed ``|grad g . f| / (|grad g| |f|)`` of a transversal event.
GRAZING_TOLERANCE = 1e-12


class GrazingEventError(ValueError):
    """The flow meets the guard (or the section) tangentially: no derivative exists there."""


def _transversal_speed(gradient: FloatArray, field: FloatArray, what: str) -> FloatArray:
    speed = np.einsum("...i,...i->...", gradient, field)
    scale = np.linalg.norm(gradient, axis=-1) * np.linalg.norm(field, axis=-1)
    if np.any(~(np.abs(speed) > GRAZING_TOLERANCE * scale)):
        raise GrazingEventError(
            f"the flow meets the {what} tangentially (grad . f = 0 to round-off): the event "
            "time has no derivative there")
    return np.asarray(speed)


def saltation_matrix(reset_jacobian: ArrayLike, field_before: ArrayLike,
                     field_after: ArrayLike, guard_gradient: ArrayLike) -> FloatArray:
    """Saltation matrix ``Xi`` of an event (the Jacobian of the reset corrected by the
    event-time sensitivity).

    Parameters
    ----------
    reset_jacobian : array_like, shape (..., m, n)
        ``D Delta``: Jacobian of the reset ``x+ = Delta(x-)`` at the pre-event state.
    field_before : array_like, shape (..., n)
        ``f-(x-)``: the vector field that brings the state to the guard.
    field_after : array_like, shape (..., m)
        ``f+(x+)``: the vector field that carries the state on after the reset.
    guard_gradient : array_like, shape (..., n)
        ``grad g(x-)``: gradient of the guard function whose zero is the event.

    Returns
    -------
    numpy.ndarray, shape (..., m, n)
        ``Xi = D Delta + (f+ - D Delta f-) grad g^T / (grad g^T f-)``.

    Raises
    ------
    GrazingEventError
        Where the flow meets the guard tangentially.
    """
    D = np.asarray(reset_jacobian, dtype=float)
    fm = np.asarray(field_before, dtype=float)
    fp = np.asarray(field_after, dtype=float)
    grad = np.asarray(guard_gradient, dtype=float)
    speed = _transversal_speed(grad, fm, "guard")
    jump = fp - np.einsum("...ij,...j->...i", D, fm)
    return np.asarray(D + jump[..., :, None] * grad[..., None, :] / speed[..., None, None])


def section_projection(field: ArrayLike, section_gradient: ArrayLike) -> FloatArray:
    """Projection ``Pi`` that turns a flow Jacobian into the Jacobian of a map onto a section.

    Parameters
    ----------
    field : array_like, shape (..., n)
        ``f(x)`` at the point where the flow meets the section ``s(x) = 0``.
    section_gradient : array_like, shape (..., n)
        ``grad s(x)`` there.

    Returns
    -------
    numpy.ndarray, shape (..., n, n)
        ``Pi = I - f grad s^T / (grad s^T f)``: ``Pi f = 0`` and ``grad s^T Pi = 0``.

    Raises
    ------
    GrazingEventError
        Where the flow is tangent to the section.
    """
    f = np.asarray(field, dtype=float)
    grad = np.asarray(section_gradient, dtype=float)
    speed = _transversal_speed(grad, f, "section")
    n = f.shape[-1]
    return np.asarray(np.eye(n) - f[..., :, None] * grad[..., None, :] / speed[..., None, None])
