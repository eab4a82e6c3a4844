"""Periodic gaits of powered walkers on level ground, with their energy books.

On level ground a walker has no passive gait: the heel strike dissipates ``|W_col| = T_c``
per step (Font & Kövecses 2008, eq. 15) and the actuators must supply it. Applying the energy
theorem between two successive post-impact instants (eq. 14),

.. math:: \\Delta T + \\Delta U = W_{act} + W_{col}, \\qquad W_{col} = -T_c,

and on a periodic level gait ``Delta T = Delta U = 0`` so ``W_act = T_c``. The loss per metre
is ``eta = T_c / L_S`` (eq. 16) and the (mechanical) cost of transport
``W_act / (m_total g L_S)``.

A gait is found by Newton's method on the Poincare map (section just after heel strike,
``z = (q3, q3_dot, q4_dot)`` for the compass gait) *augmented* with the actuation parameter
``a`` (push-off impulse, target energy or swing amplitude) as an extra unknown and the target
(speed or step length) as an extra equation:

.. math:: P(z, a) - z = 0, \\qquad g(z, a) - g^* = 0.

The Jacobian is estimated by central differences. If Newton cannot reach the target directly
from the seed gait, the target is approached by natural-parameter continuation.

McGeer's wheel (``R = l``)
--------------------------
With ``R = l`` both foot arcs are centred on the hip: the two contact points coincide, the
heel strike constrains nothing that moves (``T_c = 0``) and the trailing foot's post-impact
normal velocity is exactly zero, so :func:`heelstrike.dynamics.hybrid.simulate` reports
``trailing_foot_stays``. Here that outcome is accepted *only* for a wheel (``R = l``) and only if
the trailing foot's normal velocity is zero to round-off (it grazes: the "other" contact is the
same point); the legs are then relabelled by hand and the gait is flagged
:attr:`PoweredGait.trailing_foot_grazes`. For ``R < l`` the outcome remains a failure.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike.dynamics.actuation import (
    EnergyTracking,
    PushOff,
    SwingLegPD,
    mechanical_energy,
)
from heelstrike.dynamics.hybrid import ImpactRecord, WalkResult, WalkStatus, simulate
from heelstrike.dynamics.single_support import TorqueLaw
from heelstrike.models.base import PlanarWalker

FloatArray = NDArray[np.float64]
Target = Literal["speed", "step_length"]

__all__ = [
    "ACTUATIONS",
    "ActuationFamily",
    "PoweredGait",
    "PoweredGaitNotFoundError",
    "actuation_family",
    "find_powered_gait",
    "powered_step",
]

#: Names of the built-in actuation models.
ACTUATIONS = ("pushoff", "hip-energy", "hip-pd")

#: Relative tolerance (of ``l`` times the angular speeds) under which a wheel's trailing foot
#: is considered to graze the ground (``q2_dot+ = 0`` exactly in exact arithmetic).
GRAZING_TOLERANCE = 1e-9


class PoweredGaitNotFoundError(RuntimeError):
    """No periodic powered gait was found for the requested target (the message says why)."""


@dataclass(frozen=True, kw_only=True)
class ActuationFamily:
    """A one-parameter family of actuations, ``a -> (torque law, push-off)``.

    Attributes
    ----------
    name : str
        ``"pushoff"``, ``"hip-energy"``, ``"hip-pd"`` or a user name.
    parameter_name, parameter_unit : str
        What the free parameter ``a`` is (e.g. ``"impulse"``, ``"N s"``).
    build : callable ``(walker, a) -> (torque, push_off)``
        The actuation for a parameter value; either may be None.
    seed : callable ``(walker) -> tuple of float``
        Parameter values, tried in order, that may let the walker walk (to find a first gait).
    lower : float
        Smallest admissible parameter value (e.g. 0 for an impulse magnitude).
    """

    name: str
    parameter_name: str
    parameter_unit: str
    build: Callable[[PlanarWalker, float], tuple[TorqueLaw | None, PushOff | None]]
    seed: Callable[[PlanarWalker], tuple[float, ...]]
    lower: float = -np.inf


_SEED_SECTIONS = (
    (-0.25, 1.1, -0.45),
    (-0.2, 0.9, -0.3),
    (-0.3, 1.2, -0.6),
    (-0.15, 0.8, -0.2),
    (-0.35, 1.4, -0.8),
)


def _scale(walker: PlanarWalker) -> tuple[float, float, float]:
    """``(m_total, g, l)`` of a compass-like walker."""
    m = float(np.asarray(walker.total_mass))
    g = float(np.asarray(getattr(walker, "gravity", 9.81)))
    l = float(np.asarray(getattr(walker, "leg_length", 1.0)))
    return m, g, l


def actuation_family(
    name: str,
    *,
    gain: float = 10.0,
    kp: float = 5.0,
    kd: float = 1.0,
    max_torque: float = 20.0,
) -> ActuationFamily:
    """One of the built-in actuation models.

    Parameters
    ----------
    name : {"pushoff", "hip-energy", "hip-pd"}
        ``pushoff``: :class:`~heelstrike.dynamics.actuation.PushOff`, parameter the impulse
        ``p`` (N s), passive hip. ``hip-energy``:
        :class:`~heelstrike.dynamics.actuation.EnergyTracking`, parameter the target energy
        ``E_ref`` (J, ``T + V`` with ``V`` zero at ground level). ``hip-pd``:
        :class:`~heelstrike.dynamics.actuation.SwingLegPD`, parameter the amplitude ``A`` (rad).
    gain : float
        Energy-tracking gain (hip-energy).
    kp, kd : float
        PD gains (hip-pd), N m/rad and N m s/rad.
    max_torque : float
        Hip torque limit (N m) of the hip laws.
    """
    if name == "pushoff":
        return ActuationFamily(
            name=name,
            parameter_name="impulse",
            parameter_unit="N s",
            build=lambda w, a: (None, PushOff(impulse=max(float(a), 0.0))),
            seed=lambda w: tuple(
                c * _scale(w)[0] * float(np.sqrt(_scale(w)[1] * _scale(w)[2]))
                for c in (0.05, 0.03, 0.08)
            ),
            lower=0.0,
        )
    if name == "hip-energy":

        def seed_energy(w: PlanarWalker) -> tuple[float, ...]:
            q, qd = w.section_to_state(np.asarray(_SEED_SECTIONS[0]))
            m, g, l = _scale(w)
            E = float(mechanical_energy(w, q, qd))
            return tuple(E + c * m * g * l for c in (0.005, 0.0025, 0.01, 0.001))

        return ActuationFamily(
            name=name,
            parameter_name="energy",
            parameter_unit="J",
            build=lambda w, a: (
                EnergyTracking(walker=w, energy=float(a), gain=gain, max_torque=max_torque),
                None,
            ),
            seed=seed_energy,
        )
    if name == "hip-pd":
        return ActuationFamily(
            name=name,
            parameter_name="amplitude",
            parameter_unit="rad",
            build=lambda w, a: (
                SwingLegPD(amplitude=float(a), kp=kp, kd=kd, max_torque=max_torque),
                None,
            ),
            seed=lambda w: (0.35, 0.3, 0.45, 0.25),
        )
    raise ValueError(f"unknown actuation {name!r}: choose from {', '.join(ACTUATIONS)}")


@dataclass(frozen=True, kw_only=True)
class PoweredStep:
    """One step of a powered walker from a section point (see :func:`powered_step`).

    Attributes
    ----------
    z_next : ndarray, shape (d,)
        Section coordinates after the step (NaN if the step failed).
    walk : WalkResult
        The simulated step.
    record : ImpactRecord or None
        Its heel strike.
    energy_start, energy_end : float
        Mechanical energy ``T + V`` (J) just after the previous impact and just after this one.
    trailing_foot_grazes : bool
        The wheel case (``R = l``): the trailing foot's normal velocity is zero to round-off.
    """

    z_next: FloatArray
    walk: WalkResult
    record: ImpactRecord | None
    energy_start: float
    energy_end: float
    trailing_foot_grazes: bool

    @property
    def ok(self) -> bool:
        return bool(np.all(np.isfinite(self.z_next)))


def _is_wheel(walker: PlanarWalker) -> bool:
    R = float(np.asarray(walker.foot_radii[0]))
    l = float(np.asarray(getattr(walker, "leg_length", np.inf)))
    return bool(np.isclose(R, l, rtol=1e-12, atol=0.0))


def powered_step(
    walker: PlanarWalker,
    z: ArrayLike,
    torque: TorqueLaw | None,
    push_off: PushOff | None,
    *,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step_duration: float = 4.0,
) -> PoweredStep:
    """Simulate one step on level ground from the post-impact section point ``z``.

    Handles McGeer's wheel (module docstring): a ``trailing_foot_stays`` outcome with a zero
    (to round-off) trailing-foot velocity is accepted only when ``R = l``.
    """
    z_ = np.asarray(z, dtype=float)
    q, qd = walker.section_to_state(z_)
    E0 = float(mechanical_energy(walker, q, qd))
    walk = simulate(
        walker, q, qd, slope=0.0, steps=1, torque=torque, push_off=push_off,
        rtol=rtol, atol=atol, max_step_duration=max_step_duration,
    )
    rec = walk.impacts[0] if walk.impacts else None
    grazes = False
    if walk.ok:
        qf, qdf = walk.final_q, walk.final_q_dot
    elif walk.status is WalkStatus.TRAILING_FOOT_STAYS and rec is not None and _is_wheel(walker):
        l = float(np.asarray(getattr(walker, "leg_length", 1.0)))
        scale = l * (abs(rec.q_dot_minus[2]) + abs(rec.q_dot_minus[3]))
        if abs(rec.trailing_normal_velocity) > GRAZING_TOLERANCE * scale:
            return PoweredStep(z_next=np.full(z_.shape, np.nan), walk=walk, record=rec,
                               energy_start=E0, energy_end=np.nan, trailing_foot_grazes=False)
        qf, qdf = walker.swap_legs(rec.q, rec.q_dot_plus)
        grazes = True
    else:
        return PoweredStep(z_next=np.full(z_.shape, np.nan), walk=walk, record=rec,
                           energy_start=E0, energy_end=np.nan, trailing_foot_grazes=False)
    return PoweredStep(
        z_next=np.asarray(walker.state_to_section(qf, qdf), dtype=float),
        walk=walk,
        record=rec,
        energy_start=E0,
        energy_end=float(mechanical_energy(walker, qf, qdf)),
        trailing_foot_grazes=grazes,
    )


@dataclass(frozen=True, kw_only=True)
class PoweredGait:
    """A period-one powered gait on level ground and its energy books (per step).

    Attributes
    ----------
    actuation : str
        Actuation model name.
    parameter_name, parameter_unit : str
        The actuation parameter found by Newton and its unit.
    parameter : float
        Its value (N s, J or rad).
    fixed_point : ndarray, shape (d,)
        Section coordinates just after heel strike (``section_names``).
    period : float
        Step duration (s).
    step_length : float
        Distance per step along the ground (m), ``L_S``.
    speed : float
        ``step_length / period`` (m/s).
    impact_angle : float
        ``q3`` at heel strike (rad).
    actuator_work : float
        ``W_act`` per step (J), push-off included.
    push_off_work : float
        Work of the push-off impulse alone (J).
    collision_loss : float
        ``|W_col| = T_c`` per step (J), eq. (15).
    energy_change : float
        Change of mechanical energy ``T + V`` over the step (J); 0 on a periodic gait.
    energy_balance_error : float
        ``W_act - T_c - energy_change`` (J): the integration error of the books.
    cost_of_transport : float
        ``W_act / (m_total g L_S)`` (dimensionless).
    eta : float
        ``T_c / L_S`` (J/m), eq. (16).
    multipliers : ndarray of complex, shape (d,)
        Floquet multipliers of the map at fixed actuation parameter, largest modulus first.
    stable : bool
        All multipliers inside the unit circle.
    residual : float
        Norm of the augmented Newton residual at convergence.
    iterations : int
        Newton iterations (summed over continuation steps).
    trailing_foot_lift_velocity : float
        Normal velocity of the trailing foot just after heel strike (m/s).
    trailing_foot_grazes : bool
        Wheel case ``R = l`` (module docstring).
    walk : WalkResult
        One simulated period.
    """

    actuation: str
    parameter_name: str
    parameter_unit: str
    parameter: float
    fixed_point: FloatArray
    section_names: tuple[str, ...]
    period: float
    step_length: float
    speed: float
    impact_angle: float
    actuator_work: float
    push_off_work: float
    collision_loss: float
    energy_change: float
    energy_balance_error: float
    cost_of_transport: float
    eta: float
    multipliers: NDArray[np.complex128]
    stable: bool
    residual: float
    iterations: int
    trailing_foot_lift_velocity: float
    trailing_foot_grazes: bool
    walk: WalkResult = field(repr=False)

    @property
    def hip_work(self) -> float:
        """Work of the hip torque during single support (J)."""
        return self.actuator_work - self.push_off_work

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (SI units)."""
        return {
            "actuation": self.actuation,
            "parameter_name": self.parameter_name,
            "parameter_unit": self.parameter_unit,
            "parameter": self.parameter,
            "period": self.period,
            "step_length": self.step_length,
            "speed": self.speed,
            "impact_angle": self.impact_angle,
            "actuator_work": self.actuator_work,
            "push_off_work": self.push_off_work,
            "hip_work": self.hip_work,
            "collision_loss": self.collision_loss,
            "energy_change": self.energy_change,
            "energy_balance_error": self.energy_balance_error,
            "cost_of_transport": self.cost_of_transport,
            "eta": self.eta,
            "stable": bool(self.stable),
            "multipliers": [float(abs(m)) for m in self.multipliers],
            "multipliers_complex": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "fixed_point": dict(zip(self.section_names, map(float, self.fixed_point), strict=True)),
            "residual": self.residual,
            "trailing_foot_lift_velocity": self.trailing_foot_lift_velocity,
            "trailing_foot_grazes": bool(self.trailing_foot_grazes),
        }


@dataclass(frozen=True, kw_only=True)
class _Problem:
    walker: PlanarWalker
    family: ActuationFamily
    target: Target
    rtol: float
    atol: float
    budget: int = 2000
    _count: list[int] = field(default_factory=lambda: [0], repr=False)

    def step(self, x: FloatArray) -> PoweredStep:
        self._count[0] += 1
        if self._count[0] > self.budget:
            raise PoweredGaitNotFoundError(
                f"gave up after {self.budget} simulated steps (evaluation budget)"
            )
        torque, push = self.family.build(self.walker, float(x[-1]))
        return powered_step(self.walker, x[:-1], torque, push, rtol=self.rtol, atol=self.atol)

    def measure(self, st: PoweredStep) -> float:
        assert st.record is not None
        if self.target == "step_length":
            return st.record.step_length
        return st.record.step_length / st.record.step_duration

    def residual(self, x: FloatArray, value: float) -> FloatArray:
        st = self.step(x)
        rec = st.record
        if not st.ok or rec is None or rec.step_length <= 1e-6 or rec.step_duration <= 0:
            return np.full(x.size, np.nan)
        return np.append(st.z_next - x[:-1], self.measure(st) - value)

    def jacobian(self, x: FloatArray, value: float, h: float) -> FloatArray:
        n = x.size
        J = np.empty((n, n))
        for i in range(n):
            dx = np.zeros(n)
            dx[i] = h * max(1.0, abs(x[i]))
            J[:, i] = (self.residual(x + dx, value) - self.residual(x - dx, value)) / (2 * dx[i])
        return J


def _newton(
    prob: _Problem, x0: FloatArray, value: float, tol: float, max_iter: int, h: float
) -> tuple[FloatArray, float, int]:
    x = x0.copy()
    for it in range(1, max_iter + 1):
        F = prob.residual(x, value)
        if not np.all(np.isfinite(F)):
            raise PoweredGaitNotFoundError("the walker fails to take a step from a Newton iterate")
        res = float(np.linalg.norm(F))
        if res < tol:
            return x, res, it
        J = prob.jacobian(x, value, h)
        if not np.all(np.isfinite(J)):
            raise PoweredGaitNotFoundError("a step failed while estimating the Jacobian")
        try:
            dx = np.linalg.solve(J, -F)
        except np.linalg.LinAlgError as exc:
            raise PoweredGaitNotFoundError("singular Newton system") from exc
        lam = 1.0
        while lam > 1e-3:
            x_try = x + lam * dx
            x_try[-1] = max(x_try[-1], prob.family.lower)
            F_try = prob.residual(x_try, value)
            if np.all(np.isfinite(F_try)) and np.linalg.norm(F_try) < (1 - 0.25 * lam) * res:
                break
            lam *= 0.5
        else:
            if res < 10.0 * tol:  # at the integrator's noise floor: accept, report residual
                return x, res, it
            raise PoweredGaitNotFoundError(f"Newton stalled (residual {res:.2e})")
        x = x_try
    raise PoweredGaitNotFoundError(f"Newton did not converge in {max_iter} iterations")


def _seed(prob: _Problem) -> FloatArray:
    """A first gait (section point and parameter) by iterating the map at seed parameters.

    Stable gaits attract: the first candidate that converges is returned; otherwise the most
    nearly periodic state met (Newton then handles unstable gaits).
    """
    coarse = _Problem(walker=prob.walker, family=prob.family, target=prob.target,
                      rtol=1e-7, atol=1e-7, budget=prob.budget, _count=prob._count)
    best: tuple[float, FloatArray] | None = None
    for a in prob.family.seed(prob.walker):
        for z0 in _SEED_SECTIONS[:3]:
            z = np.asarray(z0, dtype=float)
            for _ in range(40):
                st = coarse.step(np.append(z, a))
                if not st.ok:
                    break
                err = float(np.linalg.norm(st.z_next - z))
                z = st.z_next
                if best is None or err < best[0]:
                    best = (err, np.append(z, a))
                if err < 1e-6:
                    return np.append(z, a)
            if best is not None and best[0] < 1e-3:
                return best[1]
    if best is None:
        raise PoweredGaitNotFoundError(
            f"the walker cannot take a step with any seed {prob.family.name} actuation"
        )
    return best[1]


def find_powered_gait(
    walker: PlanarWalker,
    *,
    actuation: str | ActuationFamily = "pushoff",
    speed: float | None = None,
    step_length: float | None = None,
    guess: ArrayLike | None = None,
    tol: float = 1e-9,
    max_iter: int = 20,
    fd_step: float = 1e-6,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_continuation: int = 24,
    max_evaluations: int = 1500,
    fallback: bool = True,
) -> PoweredGait:
    """Find a period-one level-ground gait with a given speed or step length.

    Parameters
    ----------
    walker : PlanarWalker
        A compass-like walker with a Poincare section (``section_to_state``).
    actuation : str or ActuationFamily
        ``"pushoff"``, ``"hip-energy"``, ``"hip-pd"`` (see :func:`actuation_family`) or a
        custom family.
    speed : float, optional
        Target mean speed (m/s). Exactly one of ``speed`` and ``step_length`` must be given.
    step_length : float, optional
        Target step length ``L_S`` (m).
    guess : array_like, shape (d + 1,), optional
        Section point and actuation parameter to start Newton from (e.g. a neighbouring gait's
        ``(*fixed_point, parameter)``); automatic if None.
    tol : float
        Tolerance on the augmented residual (section coordinates and target, SI units).
    max_iter : int
        Newton iterations per continuation step.
    fd_step : float
        Relative central-difference step of the Jacobians.
    rtol, atol : float
        Integrator tolerances.
    max_continuation : int
        Largest number of continuation steps from the seed gait to the target.
    max_evaluations : int
        Budget of simulated steps (bounds the run time when no gait exists).
    fallback : bool
        If Newton from ``guess`` fails, search from the seed gait (default) or give up.

    Returns
    -------
    PoweredGait

    Raises
    ------
    PoweredGaitNotFoundError
        If no gait reaching the target is found.
    ValueError
        For an invalid target.
    """
    if (speed is None) == (step_length is None):
        raise ValueError("give exactly one of speed and step_length")
    target: Target = "speed" if speed is not None else "step_length"
    value = float(speed if speed is not None else step_length)  # type: ignore[arg-type]
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"the target {target} must be > 0, got {value}")
    if target == "step_length" and hasattr(walker, "leg_length"):
        l, R = float(np.asarray(walker.leg_length)), float(np.asarray(walker.foot_radii[0]))
        longest = 2.0 * (l - R) + np.pi * R  # L_S at q3 = 90 deg
        if value >= longest:
            raise PoweredGaitNotFoundError(
                f"step length {value:g} m is not below the geometric limit {longest:.3g} m"
            )
    family = actuation if isinstance(actuation, ActuationFamily) else actuation_family(actuation)
    prob = _Problem(walker=walker, family=family, target=target, rtol=rtol, atol=atol,
                    budget=max_evaluations)
    total_it = 0
    if guess is not None:
        x0 = np.asarray(guess, dtype=float)
        try:
            x, res, it = _newton(prob, x0, value, tol, max_iter, fd_step)
            return _characterise(prob, x, res, it, fd_step)
        except PoweredGaitNotFoundError:
            if not fallback:
                raise
    x = _seed(prob)
    st = prob.step(x)
    if not st.ok:
        raise PoweredGaitNotFoundError("the seed gait fails")
    current = prob.measure(st)
    # converge the seed onto its own target value first, then continue to the requested one
    x, res, it = _newton(prob, x, current, tol, max_iter, fd_step)
    total_it += it
    frac, dfrac = 0.0, 1.0
    steps = 0
    x_prev: FloatArray | None = None
    frac_prev = 0.0
    while frac < 1.0:
        steps += 1
        if steps > max_continuation:
            raise PoweredGaitNotFoundError(
                f"continuation from {target} {current:.4g} towards {value:.4g} took too many "
                "steps (the target is probably outside the reachable range)"
            )
        f_try = min(1.0, frac + dfrac)
        v_try = current + f_try * (value - current)
        x_pred = x.copy()
        if x_prev is not None and frac > frac_prev:
            x_pred = x + (x - x_prev) * (f_try - frac) / (frac - frac_prev)
        try:
            x_new, res, it = _newton(prob, x_pred, v_try, tol, max_iter, fd_step)
        except PoweredGaitNotFoundError as exc:
            dfrac *= 0.5
            if dfrac < 1e-3:
                raise PoweredGaitNotFoundError(
                    f"no gait with {target} {value:g} (continuation from {current:.4g} stopped "
                    f"at {current + frac * (value - current):.4g}: {exc})"
                ) from exc
            continue
        total_it += it
        x_prev, frac_prev = x, frac
        x, frac = x_new, f_try
        dfrac = min(2.0 * dfrac, 1.0)
    return _characterise(prob, x, res, total_it, fd_step)


def _characterise(
    prob: _Problem, x: FloatArray, residual: float, iterations: int, fd_step: float
) -> PoweredGait:
    walker = prob.walker
    st = prob.step(x)
    rec = st.record
    assert rec is not None and st.ok
    z = x[:-1]
    d = z.size
    DP = np.empty((d, d))
    for i in range(d):
        dz = np.zeros(d + 1)
        dz[i] = fd_step * max(1.0, abs(z[i]))
        plus, minus = prob.step(x + dz), prob.step(x - dz)
        DP[:, i] = (plus.z_next - minus.z_next) / (2 * dz[i])
    mult = np.linalg.eigvals(DP).astype(complex) if np.all(np.isfinite(DP)) else np.full(d, np.nan)
    mult = mult[np.argsort(-np.abs(mult), kind="stable")]
    m, g, _ = _scale(walker)
    L = rec.step_length
    dE = st.energy_end - st.energy_start
    return PoweredGait(
        actuation=prob.family.name,
        parameter_name=prob.family.parameter_name,
        parameter_unit=prob.family.parameter_unit,
        parameter=float(x[-1]),
        fixed_point=np.asarray(z, dtype=float),
        section_names=tuple(walker.section_names),
        period=rec.step_duration,
        step_length=L,
        speed=L / rec.step_duration,
        impact_angle=rec.impact_angle,
        actuator_work=rec.actuator_work,
        push_off_work=rec.push_off_work,
        collision_loss=rec.energy_lost,
        energy_change=dE,
        energy_balance_error=rec.actuator_work - rec.energy_lost - dE,
        cost_of_transport=rec.actuator_work / (m * g * L),
        eta=rec.energy_lost / L,
        multipliers=mult,
        stable=bool(np.all(np.abs(mult) < 1.0)),
        residual=residual,
        iterations=iterations,
        trailing_foot_lift_velocity=rec.trailing_normal_velocity,
        trailing_foot_grazes=st.trailing_foot_grazes,
        walk=st.walk,
    )
