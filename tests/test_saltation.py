"""The saltation matrix against closed forms: a bouncing ball and a linear hybrid system.

The naive product of the reset's and the flow's Jacobians is shown to be wrong on both.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from heelstrike.core.saltation import GrazingEventError, saltation_matrix, section_projection


def test_bouncing_ball_closed_form() -> None:
    # x'' = -g, guard x = 0 (falling), reset v+ = -e v-. From (x0, v0) the ball lands at
    # t_e = (v0 + sqrt(v0^2 + 2 g x0)) / g with speed v_e = -sqrt(v0^2 + 2 g x0); tau after the
    # bounce it is at (x, v) = (-e v_e tau - g tau^2 / 2, -e v_e - g tau) for a FIXED total time
    # T = t_e + tau. Differentiate that closed form by hand and compare with Xi Phi.
    g, e, x0, v0, T = 9.81, 0.6, 1.3, 0.4, 1.0
    root = np.sqrt(v0**2 + 2 * g * x0)
    t_e = (v0 + root) / g
    tau = T - t_e
    assert tau > 0
    ve = -root
    # d t_e / d(x0, v0), d v_e / d(x0, v0)
    dte = np.array([1.0 / root, (1.0 + v0 / root) / g])
    dve = -np.array([g / root, v0 / root])
    dtau = -dte
    dx = -e * dve * tau - e * ve * dtau - g * tau * dtau
    dv = -e * dve - g * dtau
    exact = np.vstack([dx, dv])
    # the same from the saltation matrix
    phi_before = np.array([[1.0, t_e], [0.0, 1.0]])  # flow Jacobian of x'' = -g over t_e
    phi_after = np.array([[1.0, tau], [0.0, 1.0]])
    D = np.diag([1.0, -e])
    xi = saltation_matrix(D, [ve, -g], [-e * ve, -g], [1.0, 0.0])
    np.testing.assert_allclose(phi_after @ xi @ phi_before, exact, rtol=1e-13, atol=1e-13)
    naive = phi_after @ D @ phi_before
    assert np.max(np.abs(naive - exact)) > 0.1  # the naive product is wrong


def _linear_step_map(A: np.ndarray, c: np.ndarray, d: float, R: np.ndarray, r: np.ndarray,
                     x0: np.ndarray) -> tuple[np.ndarray, float]:
    """x' = A x until c . x = d (first crossing, found to round-off), then x+ = R x + r."""
    ts = np.linspace(0.0, 5.0, 50001)
    vals = np.array([c @ expm(A * t) @ x0 for t in ts[:: 100]]) - d
    k = int(np.argmax(np.sign(vals[1:]) != np.sign(vals[:-1])))
    lo, hi = ts[::100][k], ts[::100][k + 1]
    for _ in range(200):  # bisection to round-off: the event located exactly
        mid = 0.5 * (lo + hi)
        if np.sign(c @ expm(A * mid) @ x0 - d) == np.sign(vals[k]):
            lo = mid
        else:
            hi = mid
    t_e = 0.5 * (lo + hi)
    return R @ (expm(A * t_e) @ x0) + r, t_e


def test_linear_hybrid_system_against_its_exact_event_time_derivative() -> None:
    A = np.array([[0.0, 1.0], [-4.0, -0.3]])  # a damped oscillator
    c, d = np.array([1.0, 0.0]), -0.5
    R, r = np.array([[1.0, 0.0], [0.2, -0.7]]), np.array([0.0, 0.1])
    x0 = np.array([1.0, 0.0])
    xp, t_e = _linear_step_map(A, c, d, R, r, x0)
    xm = expm(A * t_e) @ x0
    # the exact Jacobian of the map to the post-event state, with the event time's
    # derivative from the implicit function theorem on c . exp(A t) x0 = d
    Phi = expm(A * t_e)
    dt = -(c @ Phi) / (c @ A @ xm)
    exact = R @ (Phi + np.outer(A @ xm, dt))
    # saltation: the post-event state at time t_e (+0) as the flow of xp backwards by 0
    xi = saltation_matrix(R, A @ xm, A @ xp, c)
    # Xi Phi is the Jacobian to a fixed time just after the event; the map stops AT the
    # event, whose time moves by dt: x+(t_e) = x(t*) - f+ (t* - t_e)
    fixed_time = xi @ Phi
    np.testing.assert_allclose(fixed_time + np.outer(A @ xp, dt), exact, rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(R @ Phi - exact)) > 1e-2  # the naive product is wrong


def test_section_projection_removes_the_flow_direction() -> None:
    rng = np.random.default_rng(1)
    f = rng.normal(size=(5, 4))
    s = rng.normal(size=(5, 4))
    P = section_projection(f, s)
    np.testing.assert_allclose(np.einsum("...ij,...j->...i", P, f), 0.0, atol=1e-12)
    np.testing.assert_allclose(np.einsum("...i,...ij->...j", s, P), 0.0, atol=1e-12)
    np.testing.assert_allclose(P @ P, P, atol=1e-12)  # a projector


def test_grazing_events_are_refused() -> None:
    with pytest.raises(GrazingEventError, match="tangentially"):
        saltation_matrix(np.eye(2), [0.0, 1.0], [0.0, 1.0], [1.0, 0.0])
    with pytest.raises(GrazingEventError):
        section_projection([1.0, 0.0], [0.0, 1.0])
