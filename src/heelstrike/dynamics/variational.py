"""Exact step-map derivatives: variational equations through every event of a step.

The step map ``P`` takes the section coordinates ``z`` just after a heel strike to those just
after the next one. Its Jacobian is the chain

.. math::

    DP(z) = DH\\, \\Pi_h\\, \\Phi_{N}\\, \\Xi_{N-1}\\, \\Phi_{N-1} \\cdots \\Xi_1\\, \\Phi_1\\, X_0,

with ``X_0`` the derivative of the phase-one integrator state ``x = (theta, theta_dot)`` with
respect to ``z`` (:meth:`~heelstrike.models.base.PlanarWalker.section_to_state` and the
reduction to the free coordinates),
``Phi_k`` the fundamental matrix of the ``k``-th continuous phase, integrated with the state by
the variational equations ``Phi' = D_x F(t, x) Phi`` (``F`` the reduced single-support field of
:class:`~heelstrike.dynamics.single_support.SingleSupport`), ``Xi_k`` the saltation matrix of
the reset that ends phase ``k`` (a knee strike;
:func:`~heelstrike.core.saltation.saltation_matrix`), ``Pi_h`` the projection of the heel-strike
guard
(:func:`~heelstrike.core.saltation.section_projection`: the section is the heel-strike event
itself) and ``DH`` the Jacobian of the heel strike's reset ``H`` (push-off, the inert impact
``q_dot+ = P_a q_dot-`` with ``A = [A_L; lock rows]``, relabelling, section coordinates).

Every derivative is exact to round-off: ``D_x F``, the guards' gradients and the resets'
Jacobians are complex-step derivatives (``Im f(x + i h e_k) / h``, ``h = 1e-30``: no
subtraction) of the walker's generated sympy expressions (a described walker's own, or those
of the hand-written walker's description,
:meth:`~heelstrike.models.base.PlanarWalker.as_described`: the same equations in the same
coordinates). The guard of a knee strike is the
striking joint reaching its lock angle, that of the heel strike the swing foot's clearance
(the compass gait's ``2 q3 + q4`` is the same surface): only the guard's normal enters
``Xi`` and ``Pi``. The event times and the nominal trajectory are those of
:func:`~heelstrike.dynamics.hybrid.simulate` (the scipy reference).

The *naive* product (reset Jacobians times flow Jacobians, ``Xi`` replaced by ``D Delta`` and
``Pi_h`` by the identity) is returned too: it is wrong (it ignores that moving the initial
state moves the event times), and shows how much the saltation terms matter.
"""

from __future__ import annotations

import types
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.saltation import saltation_matrix, section_projection
from heelstrike.dynamics.hybrid import PushOff, simulate
from heelstrike.dynamics.single_support import SingleSupport, TorqueLaw
from heelstrike.models.base import PlanarWalker
from heelstrike.models.schedule import Phase

__all__ = [
    "COMPLEX_STEP",
    "ExactJacobianUnavailable",
    "StepFailedError",
    "StepJacobian",
    "step_jacobian",
]

#: Imaginary step of the complex-step derivatives (no cancellation: any tiny step is exact).
COMPLEX_STEP = 1e-30

#: A real or complex array (complex-step evaluations), shape as documented where used.
_ComplexArray = NDArray[Any]


class ExactJacobianUnavailable(ValueError):
    """The exact Jacobian cannot be formed for this walk (the message names the part: a walker
    without generated equations, a torque law or push-off that does not take complex states)."""


class StepFailedError(ValueError):
    """The step from the given section point does not complete (a fall, no heel strike...)."""


@dataclass(frozen=True, kw_only=True)
class StepJacobian(ResultDictMixin):
    """The exact Jacobian of one step of the step map.

    Attributes
    ----------
    z : ndarray, shape (d,)
        Section point (post-heel-strike coordinates,
        :attr:`~heelstrike.models.base.PlanarWalker.section_names`).
    z_next : ndarray, shape (d,)
        ``P(z)``: the section point after the step (scipy reference).
    jacobian : ndarray, shape (d, d)
        ``DP(z)`` with the saltation and section corrections (dimensionless, rad/(rad/s) ...
        by the units of the section coordinates).
    naive : ndarray, shape (d, d)
        The product of the reset and flow Jacobians without the event-time corrections
        (wrong; for comparison).
    event_times : tuple of float
        Time (s) of each reset of the step (knee strikes, then the heel strike).
    events : tuple of str
        Their kinds (``"knee_strike"``, ``"heel_strike"``).
    """

    z: FloatArray
    z_next: FloatArray
    jacobian: FloatArray
    naive: FloatArray
    event_times: tuple[float, ...]
    events: tuple[str, ...]


# -- complex-capable equations of a walker ---------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class _Equations:
    """The walker's generated expressions, evaluated without casting to float (complex step)."""

    fn: Callable[[str], Callable[..., Any]]
    params: tuple[Any, ...]
    swing_radius: float

    @classmethod
    def of(cls, walker: PlanarWalker) -> _Equations:
        twin = walker if getattr(walker, "model", None) is not None else walker.as_described()
        model = getattr(twin, "model", None)
        if twin is None or model is None:
            raise ExactJacobianUnavailable(
                f"{type(walker).__name__} has no generated equations (no walker description) "
                "to differentiate: use central differences")
        # the generated functions allocate their outputs with the injected ``zeros`` (float):
        # the same code with complex outputs
        namespace = dict(model.namespace)
        namespace["zeros"] = lambda shape: np.zeros(shape, dtype=complex)
        cache: dict[str, Callable[..., Any]] = {}

        def fn(name: str) -> Callable[..., Any]:
            if name not in cache:
                code = model.fn(name).__code__
                cache[name] = types.FunctionType(code, namespace, name)
            return cache[name]

        return cls(fn=fn, params=tuple(twin._p),  # type: ignore[attr-defined]
                   swing_radius=float(np.asarray(twin.foot_radii[1])))

    def mass_matrix(self, q: _ComplexArray) -> _ComplexArray:
        return np.asarray(self.fn("mass_matrix")(q, self.params))

    def bias_forces(self, q: _ComplexArray, qd: _ComplexArray, slope: float) -> _ComplexArray:
        return np.asarray(self.fn("bias_forces")(q, qd, self.params, slope))

    def contact_jacobian(self, q: _ComplexArray, foot: str) -> _ComplexArray:
        return np.asarray(self.fn(f"contact_jacobian_{foot}")(q, self.params))

    def swing_clearance(self, q: _ComplexArray) -> Any:
        return np.asarray(self.fn("foot_centre_swing")(q, self.params))[..., 1] \
            - self.swing_radius

    def swap_legs(self, q: _ComplexArray, qd: _ComplexArray) -> tuple[_ComplexArray, _ComplexArray]:
        q_new = np.asarray(self.fn("swap_coordinates")(q, self.params))
        S = np.asarray(self.fn("swap_jacobian")(q, self.params))
        return q_new, S @ qd


def _complex_jacobian(fun: Callable[[_ComplexArray], _ComplexArray], x: FloatArray,
                      what: str) -> FloatArray:
    """``D fun(x)`` (m, n) by the complex step; ``fun`` must be analytic and take complex input."""
    x = np.asarray(x, dtype=float)
    cols = []
    with warnings.catch_warnings():
        warnings.simplefilter("error", np.exceptions.ComplexWarning)
        for k in range(x.size):
            xc = x.astype(complex)
            xc[k] += 1j * COMPLEX_STEP
            try:
                y = np.asarray(fun(xc))
            except (TypeError, np.exceptions.ComplexWarning) as exc:
                raise ExactJacobianUnavailable(
                    f"the {what} does not take complex states ({exc}): no complex-step "
                    "derivative; use central differences") from None
            cols.append(np.imag(y).reshape(-1) / COMPLEX_STEP)
    return np.stack(cols, axis=-1)


def _inert_impact(M: _ComplexArray, A: _ComplexArray, qd: _ComplexArray,
                  restitution: float = 0.0) -> _ComplexArray:
    """``q_dot+ = q_dot- - (1 + e) M^-1 A^T (A M^-1 A^T)^-1 A q_dot-`` (paper eq. 13 for
    ``e = 0``), complex-capable."""
    MiAt = np.linalg.solve(M, A.T)
    lam = np.linalg.solve(A @ MiAt, A @ qd)
    return np.asarray(qd - (1.0 + restitution) * (MiAt @ lam))


# -- one phase ---------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class _PhaseField:
    """The reduced single-support field ``F(t, x)`` of one phase, complex-capable."""

    support: SingleSupport
    eq: _Equations
    slope: float
    torque: Any
    q_ref: FloatArray

    @property
    def free(self) -> list[int]:
        return list(self.support.free_coordinates)

    def basis(self) -> FloatArray:
        """``J`` (n, m): ``q_dot = J theta_dot`` (rolling stance foot, locked joints held)."""
        free = self.free
        J = np.zeros((self.q_ref.size, len(free)))
        J[free, range(len(free))] = 1.0
        J[0, 0] = -self.radius()
        return J

    def radius(self) -> float:
        return float(np.asarray(self.support.walker.foot_radii[0]))

    def unpack(self, x: _ComplexArray) -> tuple[_ComplexArray, _ComplexArray]:
        """Full ``(q, q_dot)``, shapes (..., n), of integrator states ``x`` (..., 2 m)."""
        free = self.free
        m, R = len(free), self.radius()
        q = np.broadcast_to(self.q_ref, (*x.shape[:-1], self.q_ref.size)).astype(
            np.result_type(x, float))
        q[..., free] = x[..., :m]
        q[..., 0] = self.q_ref[0] + R * self.q_ref[2] - R * x[..., 0]
        q[..., 1] = R
        qd = x[..., m: 2 * m] @ self.basis().T
        return q, qd

    def pack(self, q: _ComplexArray, qd: _ComplexArray) -> _ComplexArray:
        free = self.free
        return np.concatenate((q[..., free], qd[..., free]), axis=-1)

    def __call__(self, t: float, x: _ComplexArray) -> _ComplexArray:
        """``F(t, x) = (theta_dot, (J^T M J)^-1 J^T (B u - h))``, shape (..., 2 m)."""
        m = len(self.free)
        q, qd = self.unpack(x)
        f = -self.eq.bias_forces(q, qd, self.slope)
        if self.torque is not None:
            B = np.asarray(self.support.walker.actuation_matrix(), dtype=float)
            if x.ndim == 1:
                u = np.asarray(self.torque(t, q, qd))
            else:  # a law takes one state (TorqueLaw): row by row
                u = np.stack([np.asarray(self.torque(t, a, b)) for a, b in zip(q, qd,
                                                                                  strict=True)])
            f = f + u @ B.T
        J = self.basis()
        Mr = np.einsum("ia,...ij,jb->...ab", J, self.eq.mass_matrix(q), J)
        acc = np.linalg.solve(Mr, (f @ J)[..., None])[..., 0]
        return np.concatenate((x[..., m: 2 * m], acc), axis=-1)

    def linearise(self, t: float, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``F(t, x)`` (2 m,) and ``D_x F(t, x)`` (2 m, 2 m) from one batched call: complex
        steps along every axis (the real part of each is ``F(t, x)`` to ``O(h^2)``, exact)."""
        X = x + 1j * COMPLEX_STEP * np.eye(x.size)
        with warnings.catch_warnings():
            warnings.simplefilter("error", np.exceptions.ComplexWarning)
            try:
                FX = self(t, X)
            except (TypeError, np.exceptions.ComplexWarning) as exc:
                raise ExactJacobianUnavailable(
                    f"the torque law does not take complex states ({exc}): no complex-step "
                    "derivative; use central differences") from None
        return np.asarray(np.real(FX[0])), np.asarray(np.imag(FX).T / COMPLEX_STEP)

    def flow(self, x0: FloatArray, t0: float, t1: float, rtol: float, atol: float,
             max_step: float) -> tuple[FloatArray, FloatArray]:
        """``x(t1)`` and ``Phi = dx(t1)/dx(t0)`` (DOP853 on state and variational equations)."""
        from scipy.integrate import solve_ivp

        n = x0.size

        def rhs(t: float, y: FloatArray) -> FloatArray:
            x = y[:n]
            Phi = y[n:].reshape(n, n)
            fx, D = self.linearise(t, x)
            return np.concatenate((fx, (D @ Phi).reshape(-1)))

        y0 = np.concatenate((x0, np.eye(n).reshape(-1)))
        if t1 <= t0:
            return x0.copy(), np.eye(n)
        sol = solve_ivp(rhs, (t0, t1), y0, method="DOP853", rtol=rtol, atol=atol,
                        max_step=max_step)
        if sol.status < 0:
            raise StepFailedError(f"the variational equations failed: {sol.message}")
        y1 = sol.y[:, -1]
        return y1[:n], y1[n:].reshape(n, n)


def _section_input(walker: PlanarWalker, z: FloatArray, eq: _Equations
                   ) -> tuple[FloatArray, FloatArray]:
    """``(dq/dz, dq_dot/dz)``, shapes (n, d): the derivative of the walker's
    :meth:`~heelstrike.models.base.PlanarWalker.section_to_state`.

    A section that eliminates a coordinate by the trailing foot's touchdown
    (:class:`~heelstrike.dynamics.phased.PhasedWalker`: ``clearance(q) = 0`` solved for
    ``q[eliminated]``) gets its row by the implicit function theorem; the rest of the map must
    be affine in ``z`` (the compass gait's ``q4 = -2 q3``; checked with two steps): its columns
    are exact differences.
    """
    d = z.size
    q0, qd0 = walker.section_to_state(z)
    j = getattr(walker, "eliminated", None)
    cols = []
    for step in (1.0, 0.5):
        dq = np.empty((q0.size, d))
        dqd = np.empty((q0.size, d))
        for k in range(d):
            e = np.zeros(d)
            e[k] = step
            qp, qdp = walker.section_to_state(z + e)
            dq[:, k] = (qp - q0) / step
            dqd[:, k] = (qdp - qd0) / step
        if j is not None:
            dq[j] = 0.0
        cols.append(np.concatenate((dq, dqd)))
    if not np.allclose(cols[0], cols[1], rtol=1e-12, atol=1e-12):
        raise ExactJacobianUnavailable(
            f"the Poincare section of {type(walker).__name__} is not affine in z (nor solved "
            "for a touchdown coordinate): its derivative is not known exactly")
    if j is not None:
        grad = _complex_jacobian(lambda qc: np.atleast_1d(eq.swing_clearance(qc)), q0,
                                 "swing foot clearance")[0]
        dq[j] = 0.0
        dq[j] = -(grad @ dq) / grad[j]
        dq[0] = 0.0  # the stance contact stays at x = 0 (section_to_state's q1)
    return dq, dqd


# -- the step ----------------------------------------------------------------------------------
def step_jacobian(
    walker: PlanarWalker,
    z: ArrayLike,
    *,
    slope: float,
    torque: TorqueLaw | Callable[[float, FloatArray, FloatArray], FloatArray] | None = None,
    push_off: PushOff | None = None,
    rtol: float = 1e-11,
    atol: float = 1e-11,
    max_step_duration: float = 5.0,
    max_step: float = np.inf,
) -> StepJacobian:
    """Exact Jacobian ``DP(z)`` of the step map by variational equations and saltation matrices.

    Parameters
    ----------
    walker : PlanarWalker
        A walker with a Poincare section and generated equations (a described walker, or a
        hand-written one with :meth:`~heelstrike.models.base.PlanarWalker.as_described`).
    z : array_like, shape (d,)
        Section point (units of :attr:`~heelstrike.models.base.PlanarWalker.section_names`).
    slope : float
        Ground slope (rad).
    torque : TorqueLaw, optional
        Actuator law (time since the step's start, ``q``, ``q_dot``); it must take complex
        states (e.g. :class:`~heelstrike.dynamics.phased.TorsoPD`).
    push_off : PushOff, optional
        A :class:`~heelstrike.dynamics.actuation.PushOff` impulse before the heel strike.
    rtol, atol : float
        Tolerances of the nominal step and of the variational equations (DOP853).
    max_step_duration, max_step : float
        As :func:`~heelstrike.dynamics.hybrid.simulate` (s).

    Returns
    -------
    StepJacobian

    Raises
    ------
    StepFailedError
        If the step does not complete.
    ExactJacobianUnavailable
        If a part of the step cannot be differentiated exactly (see the class).
    heelstrike.core.saltation.GrazingEventError
        If an event is grazing.
    """
    from heelstrike.dynamics.actuation import PushOff as PushOffImpulse
    from heelstrike.dynamics.actuation import _leg_direction

    z_ = np.asarray(z, dtype=float)
    if push_off is not None and not isinstance(push_off, PushOffImpulse):
        raise ExactJacobianUnavailable(
            f"push-off {type(push_off).__name__} is not a PushOff impulse: its reset has no "
            "exact derivative here; use central differences")
    impulse = None if push_off is None else float(push_off.impulse)
    eq = _Equations.of(walker)
    q0, qd0 = walker.section_to_state(z_)
    walk = simulate(walker, q0, qd0, slope=slope, steps=1, torque=torque, push_off=push_off,
                    rtol=rtol, atol=atol, max_step_duration=max_step_duration,
                    max_step=max_step)
    if not walk.ok:
        raise StepFailedError(f"no step from z = {np.round(z_, 6)}: {walk.status.value}")
    schedule = walker.step_schedule()
    phases: tuple[Phase, ...] = schedule.phases
    events = walk.events
    if len(events) != len(phases):
        raise StepFailedError(
            f"the step had {len(events)} resets for {len(phases)} phases (a phase skipped)")
    lock_angle = dict(schedule.lock_angles)
    n = walker.n_coordinates
    A_lock = np.eye(n)[list(schedule.locks)]
    S = np.stack([walker.state_to_section(*np.split(e, 2)) for e in np.eye(2 * n)], axis=-1)
    S = S - walker.state_to_section(np.zeros(n), np.zeros(n))[:, None]

    dq, dqd = _section_input(walker, z_, eq)
    fields = [
        _PhaseField(support=SingleSupport(walker=walker, slope=slope, torque=None,
                                          locked=ph.locked),
                    eq=eq, slope=float(slope), torque=torque, q_ref=np.zeros(n))
        for ph in phases
    ]
    first = fields[0]
    free = list(first.support.free_coordinates)
    X = np.concatenate((dq[free], dqd[free]))  # dx0/dz
    exact, naive = X, X
    t0, q_ref, x0 = 0.0, q0.copy(), np.concatenate((q0[free], qd0[free]))
    for i, (phase, ev) in enumerate(zip(phases, events, strict=True)):
        fld = _PhaseField(support=fields[i].support, eq=eq, slope=float(slope), torque=torque,
                          q_ref=q_ref)
        x_minus, Phi = fld.flow(x0, t0, float(ev.time), rtol, atol, max_step)
        exact, naive = Phi @ exact, Phi @ naive
        t_e = float(ev.time)
        f_minus = np.real(fld(t_e, x_minus.astype(complex)))
        if phase.reset == "knee_strike":
            nxt = _PhaseField(support=fields[i + 1].support, eq=eq, slope=float(slope),
                              torque=torque, q_ref=q_ref)
            q_strike = np.real(fld.unpack(x_minus)[0])
            striking = min(phase.strike_joints, key=lambda j: abs(q_strike[j] - lock_angle[j]))
            for j in phase.strike_joints:
                q_strike[j] = lock_angle[j]  # as the simulation resets them

            def knee(xc: _ComplexArray, fld: _PhaseField = fld, nxt: _PhaseField = nxt,
                     phase: Phase = phase) -> _ComplexArray:
                q, qd = fld.unpack(xc)
                for j in phase.strike_joints:
                    q[j] = lock_angle[j]
                A = np.vstack((eq.contact_jacobian(q, "stance"), A_lock))
                return nxt.pack(q, _inert_impact(eq.mass_matrix(q), A, qd))

            def guard(xc: _ComplexArray, fld: _PhaseField = fld, j: int = striking) -> Any:
                return np.atleast_1d(fld.unpack(xc)[0][j])

            D = _complex_jacobian(knee, x_minus, "knee strike")
            grad = _complex_jacobian(guard, x_minus, "knee-strike guard")[0]
            x_plus = np.real(knee(x_minus.astype(complex)))
            q_ref = q_strike  # the locked joints and the rolling offset of the next phase
            nxt = _PhaseField(support=nxt.support, eq=eq, slope=float(slope), torque=torque,
                              q_ref=q_ref)
            f_plus = np.real(nxt(t_e, x_plus.astype(complex)))
            exact = saltation_matrix(D, f_minus, f_plus, grad) @ exact
            naive = D @ naive
            t0, x0 = t_e, x_plus
            continue

        # -- the heel strike: push-off, impact, relabelling, section coordinates ---------------
        def heel(xc: _ComplexArray, fld: _PhaseField = fld) -> _ComplexArray:
            q, qd = fld.unpack(xc)
            if impulse is not None:
                f = eq.contact_jacobian(q, "stance").T @ (impulse * _leg_direction(q[2]))
                dv = np.linalg.solve(eq.mass_matrix(q), f)
                if A_lock.shape[0]:
                    dv = _inert_impact(eq.mass_matrix(q), A_lock.astype(complex), dv)
                qd = qd + dv
            A = np.vstack((eq.contact_jacobian(q, "swing"), A_lock))
            qd = _inert_impact(eq.mass_matrix(q), A, qd)
            q, qd = eq.swap_legs(q, qd)
            for j, a in schedule.lock_angles:
                q[j] = a
                qd[j] = 0.0
            return np.asarray(S @ np.concatenate((q, qd)))

        def strike_guard(xc: _ComplexArray, fld: _PhaseField = fld) -> Any:
            return np.atleast_1d(-eq.swing_clearance(fld.unpack(xc)[0]))

        DH = _complex_jacobian(heel, x_minus, "heel strike")
        grad = _complex_jacobian(strike_guard, x_minus, "heel-strike guard")[0]
        exact = DH @ section_projection(f_minus, grad) @ exact
        naive = DH @ naive
    z_next = np.asarray(walker.state_to_section(walk.final_q, walk.final_q_dot), dtype=float)
    return StepJacobian(z=z_.copy(), z_next=z_next, jacobian=np.asarray(exact),
                        naive=np.asarray(naive),
                        event_times=tuple(float(e.time) for e in events),
                        events=tuple(str(e.kind) for e in events))
