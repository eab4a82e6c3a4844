"""Gradients of a periodic gait for design (:func:`heelstrike.analysis.design.design`), by the
implicit function theorem.

The implicit-function solve is :func:`heelstrike.analysis.sensitivity.gait_sensitivity`'s (one
machinery): a period-one gait is a fixed point ``z*(p) = P(z*(p), p)`` of the step map ``P`` of
a described walker; differentiating the periodicity condition gives

.. math::

    \\frac{dz^*}{dp} = (I - D_z P)^{-1} D_p P,

with ``D_z P``, ``D_p P`` and the partial derivatives of the step length, period and heel-strike
``T_c`` exact (:func:`heelstrike.dynamics.variational.step_jacobian` with ``parameters``:
variational equations with saltation matrices; central differences for a parameter the exact
machinery refuses, e.g. a lock angle, as ``gait_sensitivity`` does), and the derivative of the
spectral radius the modulus derivative of the largest multiplier
(:attr:`~heelstrike.analysis.sensitivity.GaitSensitivity.modulus_derivatives`).

What this module adds for design: the slope as a parameter, the collision loss summed over
every impact of the step (knee strikes included), the cost of transport and the trailing foot's
lift velocity. A field ``F(z, p)`` of the step from ``z`` has the total derivative
``dF/dp = D_z F dz*/dp + D_p F``; the partial derivatives ``gait_sensitivity`` does not give
(the knee strikes' share of the collision loss, the lift velocity, only when asked for) are
fourth-order central differences of one step (:data:`STENCIL_STEP`; a step, not a converged
gait, so no Newton tolerance enters). The walker's weight ``M g`` is a function of the
parameters only (central differences of it, no step). The derived fields follow by the chain
rule (``speed = L / T``, ``eta = T_c / L``, the mechanical cost of transport ``T_c / (M g L)``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.analysis.limit_cycle import PoincareMap
from heelstrike.dynamics.backends import simulator as backend_simulator
from heelstrike.dynamics.phased import PhasedWalker
from heelstrike.models.builder import BuiltWalker

__all__ = [
    "GRADIENT_FIELDS",
    "GRADIENT_UNITS",
    "STENCIL_STEP",
    "GaitGradients",
    "GradientError",
    "gait_gradients",
    "step_fields",
]

#: Relative step of the fourth-order stencil (``h = STENCIL_STEP * max(1, |x|)``): its
#: truncation error ``h^4`` and the integrator's round-off ``tol / h`` are both about 1e-8 or less.
STENCIL_STEP = 3e-4

#: The gait fields differentiated, in this order (``lift_velocity``: the trailing foot's normal
#: velocity just after the heel strike, m/s, positive when it lifts).
GRADIENT_FIELDS = ("step_length", "period", "speed", "collision_loss", "eta", "cost_of_transport",
                   "lift_velocity")

#: Their units (SI).
GRADIENT_UNITS = {"step_length": "m", "period": "s", "speed": "m/s", "collision_loss": "J",
                  "eta": "J/m", "cost_of_transport": "1", "spectral_radius": "1",
                  "lift_velocity": "m/s"}


class GradientError(ValueError):
    """A parameter is unknown or a step of the stencil fails (the message names it)."""


@dataclass(frozen=True, kw_only=True)
class GaitGradients(ResultDictMixin):
    """Derivatives of a periodic gait with respect to named parameters.

    Attributes
    ----------
    parameters : tuple of str
        The parameters ``p`` (walker parameters, or ``"slope"``).
    values : ndarray, shape (k,)
        Their values (SI; ``slope`` in rad).
    section_names : tuple of str
        Names of the section coordinates.
    fixed_point : ndarray, shape (d,)
        ``z*``.
    fixed_point_derivative : ndarray, shape (d, k)
        ``dz*/dp`` (section units per parameter unit).
    fields : dict of str to float
        The gait's :data:`GRADIENT_FIELDS` (and ``spectral_radius``), SI.
    derivatives : dict of str to ndarray, shape (k,)
        ``dF/dp`` for every field (units of the field per unit of the parameter).
    multipliers : ndarray of complex, shape (d,)
        Eigenvalues of the exact ``D_z P(z*)``, largest modulus first.
    """

    parameters: tuple[str, ...]
    values: FloatArray
    section_names: tuple[str, ...]
    fixed_point: FloatArray
    fixed_point_derivative: FloatArray
    fields: dict[str, float]
    derivatives: dict[str, FloatArray]
    multipliers: np.ndarray

    def table(self) -> list[dict[str, Any]]:
        """One row per (field, parameter): ``field``, ``parameter``, ``value`` and ``units``."""
        return [{"field": f, "parameter": p, "value": float(self.derivatives[f][j]),
                 "units": f"{GRADIENT_UNITS.get(f, '1')} per {_param_unit(p)}"}
                for f in self.derivatives for j, p in enumerate(self.parameters)]


def _param_unit(name: str) -> str:
    return "rad" if name == "slope" else "unit of " + name


def _setup(walker: BuiltWalker, values: Mapping[str, float], slope: float) -> PoincareMap:
    """The scipy step map of ``walker`` with ``values`` (``slope`` among them or not)."""
    params = {k: v for k, v in values.items() if k != "slope"}
    sl = float(values.get("slope", slope))
    w = PhasedWalker.from_built(walker)
    if params:
        w = w.replace(**params)
    return PoincareMap(walker=w, slope=sl, simulator=backend_simulator(w, "scipy"))


def step_fields(walker: BuiltWalker, z: ArrayLike, values: Mapping[str, float], *,
                slope: float) -> FloatArray:
    """One step from ``z``: ``(P(z), step_length, period, collision_loss, weight, lift)``.

    Parameters
    ----------
    walker : BuiltWalker
        The walker; ``values`` replace some of its parameters (``slope``: the ground's).
    z : array_like, shape (d,)
        Section point.
    values : mapping of str to float
        Parameter values.
    slope : float
        Ground slope (rad) unless ``values`` has ``slope``.

    Returns
    -------
    ndarray, shape (d + 5,)
        The next section point, the step length (m), the step's duration (s), the collision
        loss summed over its impacts (J), the walker's weight ``M g`` (N) and the trailing
        foot's normal velocity just after the heel strike (m/s; positive: it lifts).

    Raises
    ------
    GradientError
        If the step does not complete.
    """
    pmap = _setup(walker, values, slope)
    walk = pmap.walk(np.asarray(z, dtype=float), 1)
    if not walk.ok:
        raise GradientError(f"no step at {dict(values)} from z = {np.asarray(z)}: "
                               f"{walk.status.value}")
    w = pmap.walker
    z1 = np.asarray(w.state_to_section(walk.final_q, walk.final_q_dot), dtype=float)
    rec = walk.impacts[0]
    loss = float(sum(e.kinetic_energy_constrained for e in walk.events))  # type: ignore[attr-defined]
    weight = float(w.total_mass) * float(w.scale.gravity)
    lift = float(walk.events[-1].trailing_normal_velocity)  # type: ignore[attr-defined]
    return np.concatenate((z1, [rec.step_length, rec.step_duration, loss, weight, lift]))


def _derived(L: float, T: float, C: float, W: float, V: float
             ) -> tuple[FloatArray, FloatArray]:
    """:data:`GRADIENT_FIELDS` from ``(L, T, C, W, V)`` and their Jacobian, shape (7, 5)."""
    vals = np.array([L, T, L / T, C, C / L, C / (W * L), V])
    jac = np.array([
        [1, 0, 0, 0, 0],
        [0, 1, 0, 0, 0],
        [1 / T, -L / T**2, 0, 0, 0],
        [0, 0, 1, 0, 0],
        [-C / L**2, 0, 1 / L, 0, 0],
        [-C / (W * L**2), 0, 1 / (W * L), -C / (W**2 * L), 0],
        [0, 0, 0, 0, 1],
    ], dtype=float)
    return vals, jac


def _stencil(fun: Any, x: FloatArray, k: int) -> FloatArray:
    """Fourth-order central difference of ``fun`` along coordinate ``k`` of ``x``."""
    h = STENCIL_STEP * max(1.0, abs(float(x[k])))
    e = np.zeros_like(x)
    e[k] = h
    return np.asarray((-fun(x + 2 * e) + 8 * fun(x + e) - 8 * fun(x - e) + fun(x - 2 * e))
                      / (12 * h))


def _weight(walker: BuiltWalker, values: Mapping[str, float]) -> float:
    """``M g`` (N) of ``walker`` with ``values`` (``slope`` ignored)."""
    params = {k: v for k, v in values.items() if k != "slope"}
    w = walker.replace(**params) if params else walker
    return float(w.total_mass) * float(w.scale.gravity)


def gait_gradients(
    walker: BuiltWalker,
    fixed_point: ArrayLike,
    parameters: Sequence[str],
    *,
    slope: float,
    spectral_radius: bool = True,
    lift: bool = True,
) -> GaitGradients:
    """Derivatives of a converged passive gait with respect to ``parameters``.

    ``dz*/dp`` and the derivatives of the step length, period and heel-strike collision loss
    are :func:`~heelstrike.analysis.sensitivity.gait_sensitivity`'s (the implicit function
    theorem on the exact step-map Jacobians); the spectral radius's is its largest
    multiplier's modulus derivative. The collision loss of a step with knee strikes (their
    share), the walker's weight and the lift velocity are differentiated here (the chain rule
    on ``dz*/dp``), and the derived fields follow from :func:`_derived`.

    Parameters
    ----------
    walker : BuiltWalker
        A described walker at the gait's parameter values.
    fixed_point : array_like, shape (d,)
        The gait's fixed point ``z*`` (converged, e.g. ``Gait.fixed_point``).
    parameters : sequence of str
        Names of walker parameters, or ``"slope"``.
    slope : float
        Ground slope (rad).
    spectral_radius : bool
        Also differentiate the spectral radius (``2 k`` more exact Jacobians).
    lift : bool
        Also differentiate the trailing foot's lift velocity (``4 (d + k)`` more steps; NaN
        derivatives otherwise).

    Returns
    -------
    GaitGradients

    Raises
    ------
    GradientError
        For an unknown parameter name or a failed step.
    """
    from heelstrike.analysis.sensitivity import gait_sensitivity
    from heelstrike.dynamics.variational import StepFailedError

    names = tuple(parameters)
    known = set(walker.parameters)
    for name in names:
        if name != "slope" and name not in known:
            raise GradientError(f"unknown parameter {name!r}: the walker has "
                                f"{', '.join(sorted(known))} (and 'slope')")
    base = {n: float(slope) if n == "slope" else float(np.asarray(walker.parameters[n]))
            for n in names}
    z = np.asarray(fixed_point, dtype=float)
    d, k = z.size, len(names)
    p0 = np.array([base[n] for n in names])
    x0 = np.concatenate((z, p0))

    def G(x: FloatArray) -> FloatArray:
        return step_fields(walker, x[:d], dict(zip(names, map(float, x[d:]), strict=True)),
                           slope=slope)

    g0 = G(x0)  # (P(z), L, T, C, W, V): the values, and the loss over every impact
    pmap = _setup(walker, base, slope)
    try:
        sens = gait_sensitivity(pmap.walker, z, names, slope=pmap.slope, rtol=pmap.rtol,
                                atol=pmap.atol, multipliers=spectral_radius)
    except StepFailedError as exc:  # a step it differentiates does not complete
        raise GradientError(f"no gait sensitivity at {base}: {exc}") from None
    dz = sens.fixed_point  # (d, k)
    dbasic = np.full((5, k), np.nan)  # d/dp of L, T, C, W, V along the gait
    dbasic[0], dbasic[1] = sens.quantities["step_length"], sens.quantities["period"]
    if len(pmap.walker.step_schedule().phases) > 1:  # knee strikes lose energy too
        dC = np.array([_stencil(G, x0, j)[d + 2] for j in range(d + k)])
        dbasic[2] = dC[:d] @ dz + dC[d:]
    else:
        dbasic[2] = sens.quantities["collision_loss"]
    for j, name in enumerate(names):  # the weight depends on the parameters only
        if name == "slope":
            dbasic[3, j] = 0.0
            continue
        h = STENCIL_STEP * max(1.0, abs(p0[j]))
        dbasic[3, j] = (_weight(walker, {**base, name: p0[j] + h})
                        - _weight(walker, {**base, name: p0[j] - h})) / (2 * h)
    if lift:
        dV = np.array([_stencil(G, x0, j)[d + 4] for j in range(d + k)])
        dbasic[4] = dV[:d] @ dz + dV[d:]
    vals, jac = _derived(*g0[d:])
    dfields = jac @ np.nan_to_num(dbasic, nan=0.0)
    dfields[-1] = dbasic[4]  # the lift velocity: NaN where not asked for
    mult = np.asarray(sens.multipliers, dtype=complex)
    fields = dict(zip(GRADIENT_FIELDS, map(float, vals), strict=True))
    derivs = {f: dfields[i].copy() for i, f in enumerate(GRADIENT_FIELDS)}
    fields["spectral_radius"] = float(np.max(np.abs(mult)))
    if spectral_radius:
        derivs["spectral_radius"] = np.asarray(sens.modulus_derivatives[0], dtype=float)
    return GaitGradients(parameters=names, values=p0,
                         section_names=tuple(pmap.walker.section_names), fixed_point=z.copy(),
                         fixed_point_derivative=np.asarray(dz, dtype=float), fields=fields,
                         derivatives=derivs, multipliers=mult)
