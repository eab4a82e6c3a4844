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

Parameter derivatives ``dP/dp`` come from the same chain on the state augmented with the
parameters (zero rate): ``step_jacobian(..., parameters=("foot_radius", "slope"))``, with the
step quantities' partial derivatives (period, step length, speed, collision loss, ``eta``)
in ``z`` and ``p``.

An actuated step is differentiated the same way. A smooth torque law
``u = tau(t, q, q_dot; a)`` enters ``F`` as ``B u`` (``B`` the walker's
:meth:`~heelstrike.models.base.PlanarWalker.actuation_matrix`), so its derivatives in
``(q, q_dot)`` enter ``D_x F`` and those in its parameters ``a`` (gains, amplitude, target
energy: :data:`ACTUATION_PARAMETERS`) the parameter columns; the built-in laws
(:mod:`heelstrike.dynamics.actuation`) are evaluated here without their cast to float,
saturation by the real part (outside the limit the torque is constant: no derivative). A
push-off impulse ``p`` just before the heel strike is part of the reset ``H``
(``q_dot -> q_dot + P_a M^-1 A_st^T p e(q3)``, then the impact), so ``DH`` carries its
state derivative and ``p`` is one more parameter (``"impulse"``).

The *naive* product (reset Jacobians times flow Jacobians, ``Xi`` replaced by ``D Delta`` and
``Pi_h`` by the identity) is returned too: it is wrong (it ignores that moving the initial
state moves the event times), and shows how much the saltation terms matter.
"""

from __future__ import annotations

import types
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
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
    "ACTUATION_PARAMETERS",
    "COMPLEX_STEP",
    "ExactJacobianUnavailable",
    "StepFailedError",
    "StepJacobian",
    "UnscheduledStepError",
    "actuation_differentiable",
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


class UnscheduledStepError(StepFailedError):
    """The step completes, but not through its schedule's phases (a phase skipped), or the
    variational equations fail: the step map is defined there, its exact Jacobian is not (a
    caller may fall back to differences of the map)."""


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
    parameters : tuple of str
        The parameters differentiated in (``step_jacobian(..., parameters=...)``), in the
        columns' order; empty by default.
    parameter_jacobian : ndarray, shape (d, k)
        ``dP/dp`` at fixed ``z`` (section units per parameter unit), exact.
    quantities : dict of str to float
        The step's ``period`` (s, the heel strike's time), ``step_length`` (m), ``speed``
        (m/s), ``collision_loss`` (``T_c`` of the heel strike, J) and ``eta`` (J/m).
    quantity_state_gradients : dict of str to ndarray, shape (d,)
        Their partial derivatives in ``z`` (exact).
    quantity_parameter_gradients : dict of str to ndarray, shape (k,)
        Their partial derivatives in ``p`` at fixed ``z`` (exact).
    """

    z: FloatArray
    z_next: FloatArray
    jacobian: FloatArray
    naive: FloatArray
    event_times: tuple[float, ...]
    events: tuple[str, ...]
    parameters: tuple[str, ...] = ()
    parameter_jacobian: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))
    quantities: dict[str, float] = field(default_factory=dict)
    quantity_state_gradients: dict[str, FloatArray] = field(default_factory=dict)
    quantity_parameter_gradients: dict[str, FloatArray] = field(default_factory=dict)


# -- complex-capable equations of a walker ---------------------------------------------------
def _twin(walker: PlanarWalker) -> Any:
    """The described walker whose generated equations are differentiated (None if none)."""
    if walker.generated_model is not None:
        return walker
    return walker.as_described()


@dataclass(frozen=True, kw_only=True)
class _Equations:
    """The walker's generated expressions, evaluated without casting to float (complex step).

    ``params`` is the generated functions' parameter vector; its entries may be complex
    arrays (a batch of complex steps). ``radii`` are the (stance, swing) foot radii and
    ``slope`` the ground slope at these parameter values.
    """

    fn: Callable[[str], Callable[..., Any]]
    params: tuple[Any, ...]
    radii: tuple[Any, Any]
    slope: Any

    @classmethod
    def of(cls, walker: PlanarWalker, slope: float) -> _Equations:
        twin = _twin(walker)
        model = None if twin is None else twin.generated_model
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

        radii = tuple(float(np.asarray(r)) for r in twin.foot_radii)
        return cls(fn=fn, params=tuple(twin._p), radii=(radii[0], radii[1]), slope=float(slope))

    def mass_matrix(self, q: _ComplexArray) -> _ComplexArray:
        return np.asarray(self.fn("mass_matrix")(q, self.params))

    def bias_forces(self, q: _ComplexArray, qd: _ComplexArray) -> _ComplexArray:
        return np.asarray(self.fn("bias_forces")(q, qd, self.params, self.slope))

    def contact_jacobian(self, q: _ComplexArray, foot: str) -> _ComplexArray:
        return np.asarray(self.fn(f"contact_jacobian_{foot}")(q, self.params))

    def stance_centre(self, q: _ComplexArray) -> _ComplexArray:
        """Stance foot's rolling-disc centre ``(x, y)`` (m), above its contact point."""
        return np.asarray(self.fn("foot_centre_stance")(q, self.params))

    def swing_centre(self, q: _ComplexArray) -> _ComplexArray:
        """Swing foot arc centre ``(x, y)`` (m), shape (..., 2)."""
        return np.asarray(self.fn("foot_centre_swing")(q, self.params))

    def swing_clearance(self, q: _ComplexArray) -> Any:
        return self.swing_centre(q)[..., 1] - self.radii[1]

    def swap_legs(self, q: _ComplexArray, qd: _ComplexArray) -> tuple[_ComplexArray, _ComplexArray]:
        q_new = np.asarray(self.fn("swap_coordinates")(q, self.params))
        S = np.asarray(self.fn("swap_jacobian")(q, self.params))
        return q_new, np.einsum("...ij,...j->...i", S, qd)


@dataclass(frozen=True, kw_only=True)
class _Parameters:
    """How the differentiated parameters enter the equations.

    ``index[i]`` is the position of parameter ``names[i]`` in the generated functions'
    parameter vector (None: the ground slope). The foot radii are the description's
    expressions evaluated at complex parameter values (for the feet whose radius
    ``radius_moves`` with the parameters; the others keep their value).
    """

    names: tuple[str, ...]
    index: tuple[int | None, ...]
    eq: _Equations
    values: dict[str, Any]
    twin_names: tuple[str, ...]
    feet: tuple[Any, Any]
    nominal: FloatArray
    radius_moves: tuple[bool, bool] = (True, True)

    @property
    def k(self) -> int:
        return len(self.names)

    def at(self, pv: _ComplexArray) -> _Equations:
        """The equations at parameter values ``pv`` (..., k) of :attr:`names`."""
        if self.k == 0:
            return self.eq
        from heelstrike.models.description import rolling_radius

        params = list(self.eq.params)
        slope: Any = self.eq.slope
        values = dict(self.values)
        for i, idx in enumerate(self.index):
            if idx is None:
                slope = pv[..., i]
            else:
                params[idx] = pv[..., i]
                values[self.twin_names[idx]] = pv[..., i]
        radii = tuple(rolling_radius(ft, values) if moves else r
                      for ft, moves, r in zip(self.feet, self.radius_moves, self.eq.radii,
                                              strict=True))
        return _Equations(fn=self.eq.fn, params=tuple(params), radii=(radii[0], radii[1]),
                          slope=slope)


def _parameter_entry(walker: PlanarWalker, name: str) -> tuple[int | None, PlanarWalker | None]:
    """Where walker parameter ``name`` enters the generated equations (``"slope"``: None) and
    the walker with it changed (for the checks of :func:`_section_input`).

    Raises
    ------
    ValueError
        If ``name`` is neither ``"slope"`` nor a parameter of the walker.
    ExactJacobianUnavailable
        If the parameter does not enter as one entry of the equations' parameter vector, or
        it moves a joint's lock angle (not differentiated here).
    """
    if name == "slope":
        return None, None
    known = walker.parameters
    if name not in known:
        raise ValueError(f"{name!r} is not a parameter of {type(walker).__name__} "
                         f"(its parameters: {', '.join(known)}, or 'slope')")
    twin = _twin(walker)
    if twin is None or twin.generated_model is None:
        raise ExactJacobianUnavailable(
            f"parameter {name!r}: {type(walker).__name__} has no generated equations")
    p = float(np.asarray(known[name]))
    delta = 0.25 * max(1.0, abs(p))  # any change the walker accepts shows where p enters
    other = None
    for step in (delta, 1e-3 * delta, -1e-3 * delta):
        try:
            other = walker.replace(**{name: p + step})
            break
        except ValueError:
            continue
    twin2 = None if other is None else _twin(other)
    if other is None or twin2 is None:
        raise ExactJacobianUnavailable(
            f"parameter {name!r}: no valid walker with it changed to check how it enters "
            "the equations; use central differences")
    diff = np.asarray(twin2._p, dtype=float) - np.asarray(twin._p, dtype=float)
    moved = np.flatnonzero(diff)
    change = float(np.asarray(other.parameters[name])) - p
    if moved.size != 1 or not np.isclose(diff[moved[0]], change, rtol=1e-12, atol=0.0):
        raise ExactJacobianUnavailable(
            f"parameter {name!r} does not enter {type(walker).__name__}'s generated equations "
            "as one of their parameters: no exact derivative; use central differences")
    if twin2.step_schedule().lock_angles != twin.step_schedule().lock_angles:
        raise ExactJacobianUnavailable(
            f"parameter {name!r} moves a joint's lock angle (the knee-strike guard and the "
            "locked configuration): not differentiated exactly; use central differences")
    return int(moved[0]), other


def _parameters(walker: PlanarWalker, names: tuple[str, ...], slope: float
                ) -> tuple[_Parameters, list[PlanarWalker | None]]:
    eq = _Equations.of(walker, slope)
    entries = [_parameter_entry(walker, name) for name in names]
    twin = _twin(walker)
    desc = twin.description
    par = _Parameters(
        names=names, index=tuple(e[0] for e in entries), eq=eq,
        values=dict(twin._values), twin_names=tuple(desc.param_names),
        feet=(desc.feet[0], desc.feet[1]),
        nominal=np.array([float(slope) if e[0] is None else float(twin._p[e[0]])
                          for e in entries]),
    )
    # which foot radii move with the parameters: a complex step along each
    steps = par.nominal + 1j * COMPLEX_STEP * np.eye(par.k)
    moves = tuple(bool(np.any(np.imag(r) != 0.0)) for r in par.at(steps).radii)
    return replace(par, radius_moves=(moves[0], moves[1])), [e[1] for e in entries]


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


# -- actuation: torque laws and the push-off, complex-capable ---------------------------------
#: The parameters of the built-in actuation that :func:`step_jacobian` differentiates in, by the
#: class that has them (the push-off's impulse; the hip laws' gains and amplitudes).
ACTUATION_PARAMETERS: dict[str, tuple[str, ...]] = {
    "PushOff": ("impulse",),
    "SwingLegPD": ("amplitude", "kp", "kd"),
    "EnergyTracking": ("energy", "gain"),
}

#: A complex-capable torque law with its parameters: ``(t, q, q_dot, values) -> u``, shapes
#: (..., n), (..., n), a dict of name to (...) arrays, (..., n_u).
_LawTerm = Callable[[float, _ComplexArray, _ComplexArray, dict[str, Any]], _ComplexArray]


def _complex_energy(walker: PlanarWalker, q: _ComplexArray, qd: _ComplexArray,
                    slope: float) -> _ComplexArray:
    """``E = T + V`` of ``walker`` on ``slope``, complex-capable (the generated equations):
    the energy a tracking law reads (:data:`~heelstrike.dynamics.actuation.EnergyFunction`)."""
    eq = _Equations.of(walker, float(slope))
    M = eq.mass_matrix(q)
    return 0.5 * np.einsum("...i,...ij,...j->...", qd, M, qd) \
        + np.asarray(eq.fn("potential_energy")(q, eq.params, eq.slope))


def _law_term(law: Any) -> tuple[dict[str, float], _LawTerm]:
    """The torque law as a term ``(t, q, qd, values) -> u`` taking complex states, with the
    parameters that can be differentiated in (names of :data:`ACTUATION_PARAMETERS`, nominal
    values).

    The built-in laws (:class:`~heelstrike.dynamics.actuation.HipTorque`) are evaluated by
    their own :meth:`~heelstrike.dynamics.actuation.HipTorque.evaluate` (written once, for any
    array type), the energy of a tracking law by the generated equations; a user function
    (:class:`~heelstrike.dynamics.actuation.CustomTorque`, or any other law) is called row by
    row on a batch (a :class:`~heelstrike.dynamics.single_support.TorqueLaw` takes one state)
    and must take complex states itself.
    """
    from heelstrike.dynamics.actuation import HipTorque, call_by_rows

    if isinstance(law, HipTorque):
        def builtin(t: float, q: _ComplexArray, qd: _ComplexArray, v: dict[str, Any]
                    ) -> _ComplexArray:
            return np.asarray(law.evaluate(t, q, qd, v, energy=_complex_energy))

        return law.parameters, builtin

    def rows(t: float, q: _ComplexArray, qd: _ComplexArray, v: dict[str, Any]
             ) -> _ComplexArray:
        return np.asarray(call_by_rows(law, t, q, qd))

    return {}, rows


def actuation_differentiable(torque: Any, push_off: Any) -> bool:
    """Whether :func:`step_jacobian` differentiates this actuation by its own derivation.

    True for no actuation, a :class:`~heelstrike.dynamics.actuation.PushOff` impulse and the
    built-in torque laws (:class:`~heelstrike.dynamics.actuation.SwingLegPD`,
    :class:`~heelstrike.dynamics.actuation.EnergyTracking`,
    :class:`~heelstrike.dynamics.phased.TorsoPD` and sums of them), which are evaluated
    complex-capable; False for any other law (a user function may still take complex states,
    which :func:`step_jacobian` finds out when it tries).

    Parameters
    ----------
    torque : TorqueLaw or None
    push_off : PushOff or None

    Returns
    -------
    bool
    """
    from heelstrike.dynamics.actuation import EnergyTracking, SwingLegPD, TorqueSum
    from heelstrike.dynamics.actuation import PushOff as PushOffImpulse
    from heelstrike.dynamics.phased import TorsoPD

    def law_ok(law: Any) -> bool:
        if isinstance(law, TorqueSum):
            return all(law_ok(part) for part in law.laws)
        return law is None or isinstance(law, (SwingLegPD, EnergyTracking, TorsoPD))

    return law_ok(torque) and (push_off is None or isinstance(push_off, PushOffImpulse))


@dataclass(frozen=True, kw_only=True)
class _Actuation:
    """The walk's torque law and push-off impulse, with the actuation parameters
    differentiated in (``names``, nominal values ``nominal``): the last ``k`` entries of the
    augmented state (zero rate, as the walker's parameters)."""

    names: tuple[str, ...]
    nominal: FloatArray
    values: dict[str, float]
    term: _LawTerm | None
    impulse: float | None

    @property
    def k(self) -> int:
        return len(self.names)

    @classmethod
    def of(cls, torque: Any, push_off: Any, names: tuple[str, ...],
           walker: PlanarWalker | None = None) -> _Actuation:
        """The actuation of a walk, its parameters ``names`` located.

        Raises
        ------
        ValueError
            For a name that is no parameter of this walk's actuation (nor of ``walker``,
            which the message names).
        """
        values: dict[str, float] = {}
        term = None
        if torque is not None:
            values, term = _law_term(torque)
        impulse = None if push_off is None else float(push_off.impulse)
        if impulse is not None:
            values = {**values, "impulse": impulse}
        for name in names:
            if name not in values:
                theirs = f"; its actuation's: {', '.join(values)}" if values else ""
                whose = "the walker" if walker is None else type(walker).__name__
                mine = "" if walker is None else f"its parameters: {', '.join(walker.parameters)}, "
                raise ValueError(f"{name!r} is not a parameter of {whose} ({mine}or 'slope'"
                                 f"{theirs})")
        return cls(names=names, nominal=np.array([values[n] for n in names], dtype=float),
                   values=values, term=term, impulse=impulse)

    def at(self, a: _ComplexArray) -> dict[str, Any]:
        """The actuation's parameter values with ``names`` set to ``a`` (..., k)."""
        out: dict[str, Any] = dict(self.values)
        for i, name in enumerate(self.names):
            out[name] = a[..., i]
        return out

    def torque(self, t: float, q: _ComplexArray, qd: _ComplexArray, a: _ComplexArray
               ) -> _ComplexArray | None:
        """``u`` (..., n_u) at parameter values ``a`` (..., k); None without a torque law."""
        if self.term is None:
            return None
        return np.asarray(self.term(t, q, qd, self.at(a)))


# -- one phase ---------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class _PhaseField:
    """The reduced single-support field of one phase on the augmented state, complex-capable.

    The augmented state is ``y = (theta, theta_dot, c, p, a)``, shape
    (..., 2 m + 1 + k + k_a): the integrator state, the stance angle ``c`` at the step's start
    (the rolling stance foot's arc centre is at ``x = R (c - theta)``), the differentiated
    walker parameters ``p`` and actuation parameters ``a``; ``c``, ``p`` and ``a`` have zero
    rate, so the variational equations carry their columns (``dP/dp``).
    """

    support: SingleSupport
    par: _Parameters
    act: _Actuation
    q_ref: FloatArray

    @property
    def free(self) -> list[int]:
        return list(self.support.free_coordinates)

    @property
    def m(self) -> int:
        return len(self.free)

    def unpack(self, y: _ComplexArray) -> tuple[_ComplexArray, _ComplexArray, _Equations]:
        """Full ``(q, q_dot)``, shapes (..., n), and the equations at ``y``'s parameters."""
        free, m = self.free, self.m
        eq = self.par.at(y[..., 2 * m + 1: 2 * m + 1 + self.par.k])
        R = eq.radii[0]
        dtype = np.result_type(y, float)
        q = np.broadcast_to(self.q_ref, (*y.shape[:-1], self.q_ref.size)).astype(dtype)
        q[..., free] = y[..., :m]
        q[..., 0] = R * (y[..., 2 * m] - y[..., 0])
        q[..., 1] = R
        qd = np.zeros_like(q)
        qd[..., free] = y[..., m: 2 * m]
        qd[..., 0] = -R * y[..., m]
        return q, qd, eq

    def basis(self, eq: _Equations, batch: tuple[int, ...]) -> _ComplexArray:
        """``J`` (..., n, m): ``q_dot = J theta_dot`` (rolling stance foot, locked joints
        held)."""
        free = self.free
        J = np.zeros((*batch, self.q_ref.size, len(free)), dtype=np.result_type(eq.radii[0],
                                                                                 float))
        J[..., free, range(len(free))] = 1.0
        J[..., 0, 0] = -np.asarray(eq.radii[0])
        return J

    def pack(self, q: _ComplexArray, qd: _ComplexArray, rest: _ComplexArray) -> _ComplexArray:
        free = self.free
        return np.concatenate((q[..., free], qd[..., free], rest), axis=-1)

    def __call__(self, t: float, y: _ComplexArray) -> _ComplexArray:
        """``F(t, y) = (theta_dot, (J^T M J)^-1 J^T (B u - h), 0, 0, 0)``, shape (..., N),
        ``u = tau(t, q, q_dot; a)`` the torque law."""
        m = self.m
        q, qd, eq = self.unpack(y)
        f = -eq.bias_forces(q, qd)
        u = self.act.torque(t, q, qd, y[..., 2 * m + 1 + self.par.k:])
        if u is not None:
            B = np.asarray(self.support.walker.actuation_matrix(), dtype=float)
            f = f + u @ B.T
        J = self.basis(eq, y.shape[:-1])
        Mr = np.einsum("...ia,...ij,...jb->...ab", J, eq.mass_matrix(q), J)
        acc = np.linalg.solve(Mr, np.einsum("...i,...ia->...a", f, J)[..., None])[..., 0]
        return np.concatenate((y[..., m: 2 * m], acc, np.zeros_like(y[..., 2 * m:])), axis=-1)

    def linearise(self, t: float, y: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``F(t, y)`` (N,) and ``D_y F(t, y)`` (N, N) from one batched call: complex
        steps along every axis (the real part of each is ``F(t, y)`` to ``O(h^2)``, exact)."""
        Y = y + 1j * COMPLEX_STEP * np.eye(y.size)
        with warnings.catch_warnings():
            warnings.simplefilter("error", np.exceptions.ComplexWarning)
            try:
                FY = self(t, Y)
            except (TypeError, np.exceptions.ComplexWarning) as exc:
                raise ExactJacobianUnavailable(
                    f"the torque law does not take complex states ({exc}): no complex-step "
                    "derivative; use central differences") from None
        return np.asarray(np.real(FY[0])), np.asarray(np.imag(FY).T / COMPLEX_STEP)

    def flow(self, y0: FloatArray, t0: float, t1: float, rtol: float, atol: float,
             max_step: float) -> tuple[FloatArray, FloatArray]:
        """``y(t1)`` and ``Phi = dy(t1)/dy(t0)`` (DOP853 on state and variational equations)."""
        from scipy.integrate import solve_ivp

        n = y0.size

        def rhs(t: float, w: FloatArray) -> FloatArray:
            x = w[:n]
            Phi = w[n:].reshape(n, n)
            fx, D = self.linearise(t, x)
            return np.concatenate((fx, (D @ Phi).reshape(-1)))

        w0 = np.concatenate((y0, np.eye(n).reshape(-1)))
        if t1 <= t0:
            return y0.copy(), np.eye(n)
        sol = solve_ivp(rhs, (t0, t1), w0, method="DOP853", rtol=rtol, atol=atol,
                        max_step=max_step)
        if sol.status < 0:
            raise UnscheduledStepError(f"the variational equations failed: {sol.message}")
        w1 = sol.y[:, -1]
        return w1[:n], w1[n:].reshape(n, n)


def _section_input(walker: PlanarWalker, z: FloatArray, par: _Parameters,
                   changed: list[PlanarWalker | None]) -> tuple[FloatArray, FloatArray,
                                                                 FloatArray]:
    """``(dq/dz, dq_dot/dz, dq/dp)``, shapes (n, d), (n, d), (n, k): the derivative of the
    walker's :meth:`~heelstrike.models.base.PlanarWalker.section_to_state` (``dq_dot/dp``
    vanishes on the coordinates integrated; the rows of ``x``, ``y`` and the rolling rate
    are rebuilt from the foot radius by :class:`_PhaseField`).

    A section that eliminates a coordinate by the trailing foot's touchdown
    (:class:`~heelstrike.dynamics.phased.PhasedWalker`: ``clearance(q, p) = 0`` solved for
    ``q[eliminated]``) gets its row by the implicit function theorem, in ``z`` and ``p``; the
    rest of the map must be affine in ``z`` (the compass gait's ``q4 = -2 q3``; checked with
    two steps): its columns are exact differences, and independent of ``p`` (checked with
    the changed walkers ``changed``).
    """
    d = z.size
    q0, qd0 = walker.section_to_state(z)
    j = walker.section_solved_coordinate
    keep = [i for i in range(2, q0.size) if i != j]
    for name, other in zip(par.names, changed, strict=True):
        if other is None:
            continue
        q1, qd1 = other.section_to_state(z)
        if not (np.array_equal(q1[keep], q0[keep]) and np.array_equal(qd1[2:], qd0[2:])):
            raise ExactJacobianUnavailable(
                f"parameter {name!r} moves the Poincare section's state (other than a "
                "touchdown coordinate): its derivative is not known exactly")
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
    dqp = np.zeros((q0.size, par.k))
    if j is not None:
        def clearance(w: _ComplexArray) -> Any:
            eq = par.at(w[q0.size:])
            q = w[:q0.size].copy()
            q[1] = eq.radii[0]  # the stance foot's arc centre height, as section_to_state's
            return np.atleast_1d(eq.swing_clearance(q))

        grad = _complex_jacobian(clearance, np.concatenate((q0, par.nominal)),
                                 "swing foot clearance")[0]
        gq, gp = grad[:q0.size], grad[q0.size:]
        dq[j] = 0.0
        dq[j] = -(gq @ dq) / gq[j]
        dq[0] = 0.0  # the stance contact stays at x = 0 (section_to_state's q1)
        dqp[j] = -gp / gq[j]
    return dq, dqd, dqp


# -- the step ----------------------------------------------------------------------------------
def step_jacobian(
    walker: PlanarWalker,
    z: ArrayLike,
    *,
    slope: float,
    torque: TorqueLaw | Callable[[float, FloatArray, FloatArray], FloatArray] | None = None,
    push_off: PushOff | None = None,
    parameters: Sequence[str] = (),
    rtol: float = 1e-11,
    atol: float = 1e-11,
    max_step_duration: float = 5.0,
    max_step: float = np.inf,
) -> StepJacobian:
    """Exact Jacobian ``DP(z)`` of the step map by variational equations and saltation matrices.

    With ``parameters``, also ``dP/dp`` and the step quantities' partial derivatives, exact:
    the state is augmented with the parameters ``p`` (zero rate), so that the same chain
    (variational equations, saltation matrices, section projection, reset Jacobian, section
    input) carries ``k`` more columns. Every ``p``-dependence is complex-step differentiated:
    the generated functions' parameter vector, the foot radii (the description's expressions),
    the slope (in the bias forces), the touchdown configuration of the section. The period's
    sensitivity is the event time's, ``dt = -grad g . dy / (grad g . f)``; the step length and
    the collision loss ``T_c`` (kinetic energy before minus after the inert impact:
    ``T_c`` of the split ``T = T_c + T_a``) are differentiated at the projected heel-strike
    state. Actuation parameters (``"impulse"`` of the push-off, a torque law's gains and
    amplitude) are augmented states too: they enter the torque law in the variational
    equations and the push-off in the heel strike's reset.

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
        Actuator law (time since the step's start, ``q``, ``q_dot``). The built-in laws
        (:class:`~heelstrike.dynamics.actuation.SwingLegPD`,
        :class:`~heelstrike.dynamics.actuation.EnergyTracking`, their sums,
        :class:`~heelstrike.dynamics.actuation.CustomTorque` of a complex-capable function,
        :class:`~heelstrike.dynamics.phased.TorsoPD`) are differentiated here; any other
        law must take complex states.
    push_off : PushOff, optional
        A :class:`~heelstrike.dynamics.actuation.PushOff` impulse before the heel strike.
    parameters : sequence of str
        Names in :attr:`~heelstrike.models.base.PlanarWalker.parameters` (SI units),
        ``"slope"`` (rad), or parameters of the actuation (:data:`ACTUATION_PARAMETERS`:
        ``"impulse"``, N s, with a push-off; ``"amplitude"`` rad, ``"kp"`` N m/rad, ``"kd"``
        N m s/rad of a :class:`~heelstrike.dynamics.actuation.SwingLegPD`; ``"energy"`` J,
        ``"gain"`` s/rad of an :class:`~heelstrike.dynamics.actuation.EnergyTracking`; a
        name two laws of a sum share is not differentiable), to differentiate in (default
        none), columns in this order. A walker parameter's name takes precedence.
    rtol, atol : float
        Tolerances of the nominal step and of the variational equations (DOP853).
    max_step_duration, max_step : float
        As :func:`~heelstrike.dynamics.hybrid.simulate` (s).

    Returns
    -------
    StepJacobian

    Raises
    ------
    ValueError
        For a name that is neither a parameter of the walker, ``"slope"``, nor one of the
        actuation's, or a name given twice.
    StepFailedError
        If the step does not complete (:class:`UnscheduledStepError`, a subclass: it
        completes, but with a phase of its schedule skipped, or the variational equations
        fail).
    ExactJacobianUnavailable
        If a part of the step cannot be differentiated exactly (see the class), or a
        parameter: one that does not enter the generated equations as one entry of their
        parameter vector (e.g. a hand-written walker's parameter its description computes
        from others), one that moves a joint's lock angle, or one that moves the section's
        state other than through the touchdown coordinate. The message names it.
    heelstrike.core.saltation.GrazingEventError
        If an event is grazing.
    """
    from heelstrike.dynamics.actuation import PushOff as PushOffImpulse
    from heelstrike.dynamics.actuation import _leg_direction

    z_ = np.asarray(z, dtype=float)
    names = tuple(parameters)
    if push_off is not None and not isinstance(push_off, PushOffImpulse):
        raise ExactJacobianUnavailable(
            f"push-off {type(push_off).__name__} is not a PushOff impulse: its reset has no "
            "exact derivative here; use central differences")
    if len(set(names)) != len(names):
        raise ValueError(f"parameters {names} name one twice")
    known = walker.parameters
    walker_names = tuple(n for n in names if n == "slope" or n in known)
    act = _Actuation.of(torque, push_off, tuple(n for n in names if n not in walker_names),
                        walker)
    par, changed = _parameters(walker, walker_names, float(slope))
    kw = par.k
    k = kw + act.k
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
        raise UnscheduledStepError(
            f"the step had {len(events)} resets for {len(phases)} phases (a phase skipped)")
    lock_angle = dict(schedule.lock_angles)
    n = walker.n_coordinates
    d = z_.size
    A_lock = np.eye(n)[list(schedule.locks)]
    S = np.stack([walker.state_to_section(*np.split(e, 2)) for e in np.eye(2 * n)], axis=-1)
    S = S - walker.state_to_section(np.zeros(n), np.zeros(n))[:, None]

    dq, dqd, dqp = _section_input(walker, z_, par, changed)
    supports = [SingleSupport(walker=walker, slope=slope, torque=None, locked=ph.locked)
                for ph in phases]
    free = list(supports[0].free_coordinates)
    m = len(free)
    # dy0/d(z, p): the integrator state, the start's stance angle c = q0[2], the parameters
    X = np.zeros((2 * m + 1 + k, d + k))
    X[:m, :d], X[:m, d: d + kw] = dq[free], dqp[free]
    X[m: 2 * m, :d] = dqd[free]
    X[2 * m, :d] = dq[2]
    X[2 * m + 1:, d:] = np.eye(k)
    exact, naive = X, X
    t0 = 0.0
    q_ref = q0.copy()
    y0 = np.concatenate((q0[free], qd0[free], [q0[2]], par.nominal, act.nominal))
    for i, (phase, ev) in enumerate(zip(phases, events, strict=True)):
        fld = _PhaseField(support=supports[i], par=par, act=act, q_ref=q_ref)
        y_minus, Phi = fld.flow(y0, t0, float(ev.time), rtol, atol, max_step)
        exact, naive = Phi @ exact, Phi @ naive
        t_e = float(ev.time)
        f_minus = np.real(fld(t_e, y_minus.astype(complex)))
        if phase.reset == "knee_strike":
            q_strike = np.real(fld.unpack(y_minus)[0])
            striking = min(phase.strike_joints, key=lambda j: abs(q_strike[j] - lock_angle[j]))
            for j in phase.strike_joints:
                q_strike[j] = lock_angle[j]  # as the simulation resets them
            nxt = _PhaseField(support=supports[i + 1], par=par, act=act,
                              q_ref=q_strike)
            m_now = fld.m

            def knee(yc: _ComplexArray, fld: _PhaseField = fld, nxt: _PhaseField = nxt,
                     phase: Phase = phase, m_now: int = m_now) -> _ComplexArray:
                q, qd, eq = fld.unpack(yc)
                for j in phase.strike_joints:
                    q[j] = lock_angle[j]
                A = np.vstack((eq.contact_jacobian(q, "stance"), A_lock))
                return nxt.pack(q, _inert_impact(eq.mass_matrix(q), A, qd), yc[2 * m_now:])

            def guard(yc: _ComplexArray, fld: _PhaseField = fld, j: int = striking) -> Any:
                return np.atleast_1d(fld.unpack(yc)[0][j])

            D = _complex_jacobian(knee, y_minus, "knee strike")
            grad = _complex_jacobian(guard, y_minus, "knee-strike guard")[0]
            y_plus = np.real(knee(y_minus.astype(complex)))
            q_ref = q_strike  # the locked joints of the next phase
            f_plus = np.real(nxt(t_e, y_plus.astype(complex)))
            exact = saltation_matrix(D, f_minus, f_plus, grad) @ exact
            naive = D @ naive
            t0, y0 = t_e, y_plus
            continue

        # -- the heel strike: push-off, impact, relabelling, section coordinates ---------------
        def impact(yc: _ComplexArray, fld: _PhaseField = fld
                   ) -> tuple[_ComplexArray, _ComplexArray, _ComplexArray, _Equations]:
            """``(q, q_dot-, q_dot+, equations)`` of the heel strike (after push-off)."""
            q, qd, eq = fld.unpack(yc)
            M = eq.mass_matrix(q)
            if act.impulse is not None:
                impulse = act.at(yc[2 * fld.m + 1 + kw:])["impulse"]
                f = eq.contact_jacobian(q, "stance").T @ (impulse * _leg_direction(q[2]))
                dv = np.linalg.solve(M, f)
                if A_lock.shape[0]:
                    dv = _inert_impact(M, A_lock.astype(complex), dv)
                qd = qd + dv
            A = np.vstack((eq.contact_jacobian(q, "swing"), A_lock))
            return q, qd, _inert_impact(M, A, qd), eq

        def heel(yc: _ComplexArray) -> _ComplexArray:
            q, _, qd, eq = impact(yc)
            q, qd = eq.swap_legs(q, qd)
            for j, a in schedule.lock_angles:
                q[j] = a
                qd[j] = 0.0
            return np.asarray(S @ np.concatenate((q, qd)))

        def measures(yc: _ComplexArray, fld: _PhaseField = fld) -> _ComplexArray:
            """``(step length, T_c)``: ``x`` of the stance contact at the start minus the
            striking foot's (:meth:`~heelstrike.models.base.PlanarWalker.step_length`; the
            start's contact is below the rolling disc's centre ``x = 0`` for an arc foot, not
            for a profile foot: it moves with the start angle ``c`` and the profile); kinetic
            energy before minus after the inert impact."""
            q, qd_minus, qd_plus, eq = impact(yc)
            M = eq.mass_matrix(q)
            loss = 0.5 * (qd_minus @ M @ qd_minus - qd_plus @ M @ qd_plus)
            q_start = q.copy()
            q_start[0], q_start[2] = 0.0, yc[2 * fld.m]
            x_start = eq.stance_centre(q_start)[0]
            return np.array([x_start - eq.swing_centre(q)[0], loss])

        def strike_guard(yc: _ComplexArray, fld: _PhaseField = fld) -> Any:
            q, _, eq = fld.unpack(yc)
            return np.atleast_1d(-eq.swing_clearance(q))

        DH = _complex_jacobian(heel, y_minus, "heel strike")
        grad = _complex_jacobian(strike_guard, y_minus, "heel-strike guard")[0]
        Pi = section_projection(f_minus, grad)
        dT = -(grad @ exact) / (grad @ f_minus)  # the event time's sensitivity, (d + k,)
        dLC = _complex_jacobian(measures, y_minus, "step length and collision loss") \
            @ Pi @ exact
        L, loss = np.real(measures(y_minus.astype(complex)))
        exact = DH @ Pi @ exact
        naive = DH @ naive[:, :d]
    z_next = np.asarray(walker.state_to_section(walk.final_q, walk.final_q_dot), dtype=float)
    period = float(events[-1].time)
    values = {"period": period, "step_length": float(L), "speed": float(L) / period,
              "collision_loss": float(loss), "eta": float(loss) / float(L)}
    grads = {
        "period": dT,
        "step_length": dLC[0],
        "speed": dLC[0] / period - float(L) * dT / period**2,
        "collision_loss": dLC[1],
        "eta": dLC[1] / float(L) - float(loss) * dLC[0] / float(L) ** 2,
    }
    order = (*walker_names, *act.names)  # the augmented state's; the columns in ``names``'
    cols = [d + order.index(name) for name in names]
    return StepJacobian(z=z_.copy(), z_next=z_next, jacobian=np.asarray(exact[:, :d]),
                        naive=np.asarray(naive),
                        event_times=tuple(float(e.time) for e in events),
                        events=tuple(str(e.kind) for e in events),
                        parameters=names, parameter_jacobian=np.asarray(exact[:, cols]),
                        quantities=values,
                        quantity_state_gradients={q: np.asarray(g[:d]) for q, g in grads.items()},
                        quantity_parameter_gradients={q: np.asarray(g[cols])
                                                      for q, g in grads.items()})
