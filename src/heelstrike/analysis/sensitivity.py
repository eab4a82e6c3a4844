"""Parameter sensitivities of a periodic gait by the implicit function theorem.

A period-one gait is a fixed point of the step map, ``P(z*(p), p) = z*(p)``. Differentiating
the periodicity condition in a walker parameter ``p`` gives

.. math:: \\frac{dz^*}{dp} = (I - D_z P)^{-1} \\frac{\\partial P}{\\partial p},

with ``D_z P`` the exact step-map Jacobian
(:meth:`~heelstrike.analysis.limit_cycle.PoincareMap.exact_jacobian`) and ``dP/dp`` exact too,
by default: :func:`~heelstrike.dynamics.variational.step_jacobian` with ``parameters`` (the
variational equations on the state augmented with the parameters; one integration for every
parameter). A quantity ``Q(z, p)`` of one step (period, step length, speed, collision loss
``T_c``, ``eta``) then has ``dQ/dp = D_z Q dz*/dp + dQ/dp``, its partial derivatives exact from
the same integration. ``method="central"`` takes ``dP/dp`` and the partials of ``Q`` by central
differences of the step map instead (two step maps per parameter and per section coordinate;
no Newton solve), the check of the exact ones; so does the exact method for a parameter that
cannot be differentiated exactly (one the walker's equations do not take as one of their
parameters, or one that moves a lock angle: see
:func:`~heelstrike.dynamics.variational.step_jacobian`), for that parameter's column only.
A powered gait (``torque``, ``push_off``) is differentiated the same way, in its walker's
parameters and in its actuation's (the push-off impulse, a hip law's gains and amplitude:
:data:`~heelstrike.dynamics.variational.ACTUATION_PARAMETERS`), exactly: the torque law's
derivatives enter the variational equations and the impulse the heel strike's reset.
The Floquet multipliers ``lambda_i`` (eigenvalues of ``D_z P`` with right and left eigenvectors
``v_i``, ``w_i``) move by ``d lambda_i = w_i^H (d D_z P) v_i / (w_i^H v_i)``, with
``d D_z P / dp`` central differences of the exact Jacobian along the gait,
``(z* +- h dz*/dp, p +- h)``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields, is_dataclass, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.analysis.limit_cycle import PoincareMap
from heelstrike.dynamics.actuation import PushOff
from heelstrike.dynamics.single_support import TorqueLaw
from heelstrike.models.base import PlanarWalker

__all__ = ["GAIT_QUANTITY_UNITS", "GaitSensitivity", "gait_sensitivity"]

#: The step quantities whose sensitivities :func:`gait_sensitivity` gives, with their units.
GAIT_QUANTITY_UNITS: dict[str, str] = {
    "period": "s", "step_length": "m", "speed": "m/s", "collision_loss": "J", "eta": "J/m",
}


@dataclass(frozen=True, kw_only=True)
class GaitSensitivity(ResultDictMixin):
    """Derivatives of a periodic gait with respect to walker parameters.

    Attributes
    ----------
    parameters : tuple of str
        The walker parameters ``p`` (names of
        :attr:`~heelstrike.models.base.PlanarWalker.parameters`, or ``"slope"``), in the
        columns' order.
    section_names : tuple of str
        The section coordinates, in the rows' order of ``fixed_point``.
    fixed_point : ndarray, shape (d, k)
        ``dz*/dp`` (section units per parameter unit).
    quantities : dict of str to ndarray, shape (k,)
        ``dQ/dp`` of every quantity of :data:`GAIT_QUANTITY_UNITS` (its unit per parameter
        unit).
    values : dict of str to float
        The quantities at the gait.
    multipliers : ndarray of complex, shape (d,)
        The Floquet multipliers at the gait, largest modulus first
        (:func:`~heelstrike.analysis.newton.floquet_multipliers` of the exact Jacobian).
    multiplier_derivatives : ndarray of complex, shape (d, k)
        ``d lambda_i / dp`` (per parameter unit), rows in the order of ``multipliers``; NaN
        if not asked for (``gait_sensitivity(..., multipliers=False)``).
    exact : tuple of bool
        Per parameter: True if its partial derivatives are exact, False if central
        differences (``method="central"``, or a parameter with no exact derivative).
    """

    parameters: tuple[str, ...]
    section_names: tuple[str, ...]
    fixed_point: FloatArray
    quantities: dict[str, FloatArray]
    values: dict[str, float]
    multipliers: NDArray[np.complex128]
    multiplier_derivatives: NDArray[np.complex128]
    exact: tuple[bool, ...] = ()

    @property
    def modulus_derivatives(self) -> FloatArray:
        """``d |lambda_i| / dp = Re(conj(lambda_i) d lambda_i) / |lambda_i|``, shape (d, k)."""
        lam = self.multipliers[:, None]
        return np.asarray(np.real(np.conj(lam) * self.multiplier_derivatives) / np.abs(lam))


def _quantities(pmap: PoincareMap, z: FloatArray) -> FloatArray:
    """``(period, step_length, speed, collision_loss, eta)`` of the step from ``z``, shape (5,)."""
    walk = pmap.walk(z, 1)
    if not walk.ok:
        raise ValueError(f"no step from z = {np.round(z, 6)} ({walk.status.value})")
    rec = walk.impacts[0]
    T, L, loss = rec.step_duration, rec.step_length, rec.energy_lost
    return np.array([T, L, L / T, loss, loss / L])


def _changed_law(law: Any, name: str, value: float) -> Any:
    """Torque law or push-off ``law`` with its parameter ``name`` set to ``value`` (in every
    law of a :class:`~heelstrike.dynamics.actuation.TorqueSum` that has it)."""
    from heelstrike.dynamics.actuation import TorqueSum

    if isinstance(law, TorqueSum):
        return replace(law, laws=tuple(_changed_law(part, name, value) for part in law.laws))
    if is_dataclass(law) and name in {f.name for f in fields(law)}:
        return replace(law, **{name: value})  # type: ignore[type-var]
    return law


def _changed_map(pmap: PoincareMap, name: str, value: float) -> PoincareMap:
    """``pmap`` with parameter ``name`` (a walker parameter, ``"slope"``, or a parameter of
    its actuation: the push-off's ``"impulse"``, a torque law's gain or amplitude) set to
    ``value``."""
    if name == "slope":
        return replace(pmap, slope=value)
    if name in pmap.walker.parameters:
        return replace(pmap, walker=pmap.walker.replace(**{name: value}))
    if name == "impulse" and pmap.push_off is not None:
        return replace(pmap, push_off=_changed_law(pmap.push_off, "impulse", value))
    return replace(pmap, torque=_changed_law(pmap.torque, name, value))


def _stencil(pmap: PoincareMap, name: str, p: float, h: float
             ) -> list[tuple[float, float, PoincareMap]]:
    """``(offset, weight, map)`` of a second-order difference in ``name`` at ``p``, step ``h``
    (the derivative is ``sum(weight * f(map at p + offset h)) / h``): central, or one-sided
    where ``p - h`` is outside the walker's admissible values (``R = 0``: a foot radius < 0
    is no walker)."""
    try:
        minus = _changed_map(pmap, name, p - h)
    except ValueError:
        return [(0.0, -1.5, pmap), (1.0, 2.0, _changed_map(pmap, name, p + h)),
                (2.0, -0.5, _changed_map(pmap, name, p + 2.0 * h))]
    return [(-1.0, -0.5, minus), (1.0, 0.5, _changed_map(pmap, name, p + h))]


def gait_sensitivity(
    walker: PlanarWalker,
    fixed_point: Any,
    parameters: Sequence[str],
    *,
    slope: float,
    torque: TorqueLaw | None = None,
    push_off: PushOff | None = None,
    method: Literal["exact", "central"] = "exact",
    rel_step: float = 1e-5,
    rtol: float = 1e-12,
    atol: float = 1e-12,
    multipliers: bool = True,
) -> GaitSensitivity:
    """Sensitivities of a gait, passive or powered, to walker and actuation parameters
    (implicit function theorem).

    Parameters
    ----------
    walker : PlanarWalker
        A walker whose exact step Jacobian exists (see
        :func:`~heelstrike.dynamics.variational.step_jacobian`).
    fixed_point : array_like, shape (d,)
        The gait's fixed point ``z*`` (e.g. the ``fixed_point`` of a
        :class:`~heelstrike.analysis.gaits.Gait`), converged at about ``rtol``.
    parameters : sequence of str
        Names in :attr:`~heelstrike.models.base.PlanarWalker.parameters` (SI units),
        ``"slope"`` (rad), or parameters of the actuation
        (:data:`~heelstrike.dynamics.variational.ACTUATION_PARAMETERS`: the push-off's
        ``"impulse"``, N s; a hip PD law's ``"amplitude"``, ``"kp"``, ``"kd"``; an
        energy-tracking law's ``"energy"``, ``"gain"``). A walker parameter's name takes
        precedence. The torque law is held fixed when a walker parameter changes (an
        energy-tracking law keeps its own walker's energy).
    slope : float
        Ground slope (rad).
    torque : TorqueLaw, optional
        The gait's torque law (:mod:`heelstrike.dynamics.actuation`).
    push_off : PushOff, optional
        The gait's push-off impulse before heel strike.
    method : {"exact", "central"}
        ``"exact"`` (default): ``dP/dp`` and the quantities' partial derivatives in ``z`` and
        ``p`` by the variational equations
        (:func:`~heelstrike.dynamics.variational.step_jacobian` with ``parameters``), falling
        back to central differences for a parameter with no exact derivative (see
        ``GaitSensitivity.exact``). ``"central"``: central differences of the step map
        for all of them. Either way the multipliers' derivatives (second derivatives of the
        step map) are central differences of the exact Jacobian along the gait.
    rel_step : float
        Relative central-difference step, ``h = rel_step max(1, |p|)`` (and
        ``max(1, |z_i|)`` in ``z``).
    rtol, atol : float
        Integrator tolerances.
    multipliers : bool
        Also differentiate the Floquet multipliers (``2 k`` exact Jacobians); False: their
        derivatives are NaN.

    Returns
    -------
    GaitSensitivity

    Raises
    ------
    ValueError
        For a name that is not a parameter of the walker (nor ``"slope"``, nor one of the
        actuation's), an unknown ``method``, or a step that fails.
    """
    from heelstrike.dynamics.variational import (
        ExactJacobianUnavailable,
        _Actuation,
        _parameter_entry,
        step_jacobian,
    )

    names = tuple(parameters)
    known = walker.parameters
    acting = _Actuation.of(torque, push_off, ()).values  # the actuation's parameters
    for name in names:
        if name not in known and name != "slope" and name not in acting:
            theirs = f"; its actuation's: {', '.join(acting)}" if acting else ""
            raise ValueError(f"{name!r} is not a parameter of {type(walker).__name__} "
                             f"(its parameters: {', '.join(known)}, or 'slope'{theirs})")
    if method not in ("exact", "central"):
        raise ValueError(f"method must be 'exact' or 'central', not {method!r}")
    z = np.asarray(fixed_point, dtype=float)
    d = z.size
    pmap = PoincareMap(walker=walker, slope=slope, torque=torque, push_off=push_off,
                       rtol=rtol, atol=atol)
    exact_names: list[str] = []
    if method == "exact":
        for name in names:
            if name not in known and name != "slope":  # the actuation's: exact
                exact_names.append(name)
                continue
            try:
                _parameter_entry(walker, name)
            except ExactJacobianUnavailable:
                continue
            exact_names.append(name)
    sj = step_jacobian(walker, z, slope=slope, torque=torque, push_off=push_off,
                       parameters=exact_names, rtol=rtol, atol=atol)
    DP = sj.jacobian
    lam, V = np.linalg.eig(DP)
    order = np.argsort(-np.abs(lam), kind="stable")
    lam, V = lam[order], V[:, order]
    W = np.linalg.inv(V).conj().T  # left eigenvectors: W^H V = I
    keys = tuple(GAIT_QUANTITY_UNITS)
    dlam = np.empty((d, len(names)), dtype=complex)
    dz_all = np.empty((d, len(names)))
    dQ = np.empty((5, len(names)))
    if method == "exact":
        DQz = np.stack([sj.quantity_state_gradients[q] for q in keys])
        values = np.array([sj.quantities[q] for q in keys])
    else:  # D_z Q by central differences of one step
        hz = rel_step * np.maximum(1.0, np.abs(z))
        DQz = np.stack([(_quantities(pmap, z + hz[i] * e) - _quantities(pmap, z - hz[i] * e))
                        / (2.0 * hz[i]) for i, e in enumerate(np.eye(d))], axis=-1)
        values = _quantities(pmap, z)
    for k, name in enumerate(names):
        p = (float(slope) if name == "slope" else float(np.asarray(known[name]))
             if name in known else acting[name])
        h = rel_step * max(1.0, abs(p))
        stencil = _stencil(pmap, name, p, h)
        if name in exact_names:
            i = exact_names.index(name)
            dPdp = sj.parameter_jacobian[:, i]
            dQdp = np.array([sj.quantity_parameter_gradients[q][i] for q in keys])
        else:
            dPdp = np.sum([w * m(z) for _, w, m in stencil], axis=0) / h
            dQdp = np.sum([w * _quantities(m, z) for _, w, m in stencil], axis=0) / h
        dz_all[:, k] = np.linalg.solve(np.eye(d) - DP, dPdp)
        dQ[:, k] = DQz @ dz_all[:, k] + dQdp
        if not multipliers:
            dlam[:, k] = np.nan
            continue
        dDP = np.sum([w * m.exact_jacobian(z + s * h * dz_all[:, k]).jacobian
                      for s, w, m in stencil], axis=0) / h
        dlam[:, k] = np.einsum("ji,jk,ki->i", W.conj(), dDP, V)
    return GaitSensitivity(
        parameters=names, section_names=tuple(walker.section_names), fixed_point=dz_all,
        quantities={key: dQ[i].copy() for i, key in enumerate(keys)},
        values={key: float(values[i]) for i, key in enumerate(keys)},
        multipliers=np.asarray(lam, dtype=complex), multiplier_derivatives=dlam,
        exact=tuple(name in exact_names for name in names),
    )
