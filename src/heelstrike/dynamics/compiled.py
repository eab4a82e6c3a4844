"""Compiled passive walking of the circular-feet compass gait: one walker or whole ensembles.

This module re-implements, in numba-compiled code, exactly the hybrid model of
:func:`heelstrike.dynamics.hybrid.simulate` for the passive :class:`~heelstrike.models.CompassGait`
on a slope (no torque, no push-off, inert impact; :func:`simulate_compiled` runs those on the
kernel generated from the walker's description):

- **Single support.** The stance foot rolls (``q1 = c - R q3``, ``q2 = R``); the free coordinates
  ``theta = (q3, q4)`` obey ``J^T M J theta_dd = -J^T h`` with the constant null-space basis ``J``
  of :class:`~heelstrike.dynamics.single_support.SingleSupport`. The 2x2 reduced mass matrix and
  forcing are written in closed form from the same point Jacobians as
  :meth:`CompassGait.mass_matrix` / :meth:`CompassGait.bias_forces`: with ``s = l - R``,
  ``e(t) = (-sin t, cos t)`` and the reduced Jacobians (columns ``q3_dot``, ``q4_dot``)

  - hip ``j_H = [(-R - s cos q3, 0), (-s sin q3, 0)]``,
  - stance-leg centre of mass ``j_R = [(-R - (s - b) cos q3, 0), (-(s - b) sin q3, 0)]``,
  - swing-leg centre of mass ``j_L = j_H + b [(cos q34, cos q34), (sin q34, sin q34)]``,

  ``J^T M J = sum m_i j_i^T j_i + I [[2, 1], [1, 1]]`` and
  ``-J^T h = -sum m_i j_i^T (a_i - g)`` where ``a_i`` are the velocity-product accelerations
  (``a_H = -s e(q3) q3_dot^2``, ``a_R = -(s - b) e(q3) q3_dot^2``,
  ``a_L = a_H + b e(q34) q34_dot^2``) and ``g = g (-sin gamma, -cos gamma)``. The ground
  reaction is Newton's law for the whole walker, ``lambda = sum m_i (j_i theta_dd + a_i) - m g``.
- **Integrator.** Dormand-Prince 5(4) of :mod:`heelstrike.dynamics._dp5` (shared with the
  described walkers' kernel) with scipy's error norm (RMS of
  ``err / (atol + rtol max(|y|, |y_new|))``) and step-size control.
- **Events.** The two phases of a step and their terminal events are those of ``simulate``
  (mid-stance, falls, lost contact, heel strike ``2 q3 + q4`` rising through 0), detected by a
  sign change over an accepted step with the same direction rules as ``solve_ivp`` (a phase
  that starts with a normal force ``<= 0`` ends at once with lost contact). The event
  time is located by the Illinois method on the *exact* Runge-Kutta step of length ``tau`` from
  the step's start (each trial is a fresh DP5 step), to ``|d tau| < 1e-13 s``; the earliest
  event of a step ends the phase.
- **Impact and swap.** ``q_dot+ = P_a q_dot-`` with the full 4x4 ``M`` and the left foot's
  Jacobian ``A_L`` (Cholesky solves), ``T_c = 1/2 mu^T (A M^-1 A^T) mu``; the trailing foot must
  lift (``q2_dot+ > LIFT_TOLERANCE l (|q3_dot-| + |q4_dot-|)``, the rule of
  :mod:`heelstrike.models._contact` compiled); then ``q3 <- q3 + q4``, ``q4 <- -q4`` and the
  velocities alike.

A hip law, a push-off, a friction limit or dense samples are not this kernel's:
:func:`simulate_compiled` runs them on the kernel generated from the walker's description
(``compass.toml``, the same equations and coordinates;
:meth:`~heelstrike.models.base.PlanarWalker.as_described`).

The numba functions are in :mod:`heelstrike.dynamics._compass_kernels`. Serial calls run them
from an extension module compiled ahead of time from that same source (:data:`AOT_EXPORTS`,
:mod:`heelstrike.dynamics._aot`; identical results, and a process that loads it imports no
numba), ``prange``-parallel ensembles through numba's JIT.

Status codes are :attr:`WalkStatus.code <heelstrike.dynamics.hybrid.WalkStatus>` (module-level
constants below, compile-time constants for numba; :meth:`WalkStatus.from_code` converts back).
``tests/test_compiled.py`` checks everything against ``simulate``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin, tuple_dict
from heelstrike._typing import FloatArray, IntArray
from heelstrike.core._parallel import use_parallel
from heelstrike.dynamics._aot import AotExport, AotLibrary, load_library
from heelstrike.dynamics.hybrid import (
    ImpactRecord,
    WalkResult,
    WalkStatus,
    check_initial_state,
)
from heelstrike.models import _contact
from heelstrike.models.base import PlanarWalker
from heelstrike.models.compass import CompassGait

if TYPE_CHECKING:
    from heelstrike.dynamics.actuation import EnergyTracking, PushOff, SwingLegPD

__all__ = [
    "STATUS_NAMES",
    "CompiledStep",
    "EnsembleResult",
    "check_compiled_compass",
    "ensemble_walk",
    "simulate_compiled",
    "single_support_compiled",
    "step_map_compiled",
    "walker_parameters",
]

#: Status names indexed by the integer codes written by the kernels (``WalkStatus.code``).
STATUS_NAMES: tuple[str, ...] = WalkStatus.names_by_code()
# Kernel status codes: plain ints taken from the enum (numba freezes globals at compile time).
COMPLETED = WalkStatus.COMPLETED.code
FELL_FORWARD = WalkStatus.FELL_FORWARD.code
FELL_BACKWARD = WalkStatus.FELL_BACKWARD.code
TRAILING_FOOT_STAYS = WalkStatus.TRAILING_FOOT_STAYS.code
LOST_CONTACT = WalkStatus.LOST_CONTACT.code
NO_HEEL_STRIKE = WalkStatus.NO_HEEL_STRIKE.code
INTEGRATION_FAILED = WalkStatus.INTEGRATION_FAILED.code

#: Layout of a row of the parameter array: mH, m, l, b, R, I, g, slope.
PARAMETER_NAMES: tuple[str, ...] = (
    "hip_mass",
    "leg_mass",
    "leg_length",
    "leg_com_from_hip",
    "foot_radius",
    "leg_inertia",
    "gravity",
    "slope",
)


# Event kinds. Phase 1 (before mid-stance): MID, BACK1, NORMAL; phase 2: STRIKE, BACK2, FWD,
# NORMAL (the order of ``_step_events`` in hybrid.py).
_EV_MID = 0
_EV_BACK1 = 1
_EV_NORMAL = 2
_EV_STRIKE = 3
_EV_BACK2 = 4
_EV_FWD = 5
_EV_NONE = -1  # time limit reached
_EV_FAIL = -2  # integrator failure

# ---------------------------------------------------------------------------------------------
# The kernel's entry points
# ---------------------------------------------------------------------------------------------
_F2 = "f8[:,::1]"
#: The serial entry points compiled ahead of time, with their signatures (the functions are
#: :data:`heelstrike.dynamics._compass_kernels.SERIAL`).
AOT_EXPORTS: tuple[AotExport, ...] = (
    AotExport(
        name="ensemble",
        args=(_F2, _F2, "i8[::1]", "i8", "f8", "f8", "f8", "f8[::1]", "f8", "i8[::1]",
              "i8[::1]", "f8[::1]", _F2, _F2, _F2, _F2, "b1"),
        returns="void",
    ),
    AotExport(name="integrate_phase",
              args=("f8[::1]", "f8[::1]", "f8", "f8", "i8", "f8", "f8", "f8", _F2),
              returns="Tuple((i8, f8, f8))"),
    AotExport(name="impact", args=("f8[::1]", "f8[::1]", "f8[::1]"), returns="UniTuple(f8, 2)"),
    AotExport(name="phase_status", args=("i8",), returns="i8"),
    AotExport(name="integrate_plain", args=("f8[::1]", "f8[::1]", "f8", "f8", "f8", _F2),
              returns="i8"),
    AotExport(name="dynamics", args=("f8[::1]", "f8[::1]"), returns="UniTuple(f8, 4)"),
)


def _jit_serial() -> dict[str, Any]:
    from heelstrike.dynamics import _compass_kernels

    return _compass_kernels.SERIAL


_LIBRARY = AotLibrary(
    name="compass",
    exports=AOT_EXPORTS,
    functions=_jit_serial,
    source_modules=(
        "heelstrike.dynamics._compass_kernels", "heelstrike.dynamics.compiled",
        "heelstrike.dynamics.hybrid", "heelstrike.dynamics._dp5", "heelstrike.models._contact",
        "heelstrike.models.compass_fast", "heelstrike.core.fast",
    ),
)


class _JitSerial:
    """The serial entry points as numba dispatchers (the ahead-of-time tier off or failed)."""

    def __init__(self, functions: dict[str, Any]) -> None:
        self.__dict__.update(functions)


def _serial() -> Any:
    """The kernel's serial entry points (:data:`AOT_EXPORTS` by name): the ahead-of-time
    module, built on first use, or numba's JIT functions."""
    aot = load_library(_LIBRARY)
    return aot if aot is not None else _JitSerial(_jit_serial())


def _parallel_ensemble() -> Any:
    """The ``prange``-parallel ensemble kernel (numba's JIT)."""
    from heelstrike.dynamics import _compass_kernels

    return _compass_kernels._ensemble_parallel


# ---------------------------------------------------------------------------------------------
# Python API
# ---------------------------------------------------------------------------------------------
def walker_parameters(walker: PlanarWalker, slope: ArrayLike = 0.0) -> FloatArray:
    """Parameter rows ``(mH, m, l, b, R, I, g, slope)`` broadcast over array-valued fields.

    Parameters
    ----------
    walker : PlanarWalker
        A walker simulated by this module's kernel (``walker.compiled_kernel == "compass"``:
        the :class:`~heelstrike.models.CompassGait`); any parameter may be an array (e.g. a
        grid of foot radii).
    slope : array_like
        Slope (rad), broadcast with the walker's parameters.

    Returns
    -------
    ndarray, shape (..., 8)
        SI units (kg, kg, m, m, m, kg m^2, m/s^2, rad).

    Raises
    ------
    TypeError
        If ``walker`` is not a walker or its compiled kernel is not the compass-gait one.
    """
    if not isinstance(walker, PlanarWalker) or walker.compiled_kernel != "compass":
        raise TypeError("the compiled path supports the CompassGait walker only")
    params = walker.parameters
    vals = [np.asarray(params[n], dtype=float) for n in PARAMETER_NAMES[:-1]]
    vals.append(np.asarray(slope, dtype=float))
    b = np.broadcast_arrays(*vals)
    return np.ascontiguousarray(np.stack(b, axis=-1))


class EnsembleStatus:
    """What the ensemble results of both compiled kernels offer on their ``status`` codes."""

    status: IntArray

    @property
    def status_names(self) -> NDArray[np.str_]:
        """Status of every walker as a ``WalkStatus`` value string, shape (N,)."""
        return np.asarray(STATUS_NAMES)[self.status]

    @property
    def ok(self) -> NDArray[np.bool_]:
        """Walkers that completed every requested step (or stopped on arrival), shape (N,)."""
        return np.asarray(self.status == COMPLETED)


@dataclass(frozen=True, kw_only=True)
class EnsembleResult(EnsembleStatus, ResultDictMixin):
    """Outcome of :func:`ensemble_walk` for ``N`` walkers and up to ``S`` steps.

    Attributes
    ----------
    z : ndarray, shape (N, 3)
        Final section coordinates ``(q3, q3_dot, q4_dot)`` (rad, rad/s): just after the last heel
        strike for a completed walk; for a failed walk the state where it failed (``q3``,
        ``q3_dot``, ``q4_dot`` of the reduced state, pre-swap).
    state : ndarray, shape (N, 4)
        Final reduced state ``(q3, q4, q3_dot, q4_dot)`` (rad, rad/s).
    status : ndarray of int, shape (N,)
        Status codes, names in :data:`STATUS_NAMES` (``WalkStatus`` values).
    steps : ndarray of int, shape (N,)
        Heel strikes taken (``WalkResult.n_steps``): with status ``trailing_foot_stays`` the
        last one is counted although the legs were not swapped.
    time : ndarray, shape (N,)
        Simulated time at the end (s).
    impact_angle, step_time, collision_loss, step_length : ndarray, shape (N, S) or None
        Per step: ``q3`` at heel strike (rad), step duration (s), ``T_c`` (J) and step length
        along the ground (m); NaN after the walk ended. None unless recorded. A step whose
        impact left the trailing foot on the ground is recorded too (as in ``simulate``).
    """

    z: FloatArray
    state: FloatArray
    status: IntArray
    steps: IntArray
    time: FloatArray
    impact_angle: FloatArray | None
    step_time: FloatArray | None
    collision_loss: FloatArray | None
    step_length: FloatArray | None


def ensemble_walk(
    walker: CompassGait,
    z0: ArrayLike,
    slope: ArrayLike = 0.0,
    *,
    steps: int = 1,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step_duration: float = 5.0,
    record: bool = True,
    stop_near: tuple[ArrayLike, float] | None = None,
    parallel: bool | None = None,
    initial_state: ArrayLike | None = None,
) -> EnsembleResult:
    """Walk a whole ensemble of passive compass gaits for ``steps`` steps in one compiled call.

    Walker ``i`` has the parameters of row ``i`` of ``walker_parameters(walker, slope)``
    broadcast with the initial states, so ``walker`` fields and ``slope`` may be arrays of
    length ``N`` (or scalars).

    Parameters
    ----------
    walker : CompassGait
        Walker(s); fields broadcast with ``slope`` and ``z0``'s leading axis.
    z0 : array_like, shape (N, 3) or (3,)
        Post-impact section coordinates ``(q3, q3_dot, q4_dot)`` (rad, rad/s), ``q4 = -2 q3``.
    slope : array_like, shape (N,) or ()
        Slope (rad).
    steps : int
        Number of heel strikes to take.
    rtol, atol : float
        Integrator tolerances (DP5, scipy's error norm).
    max_step_duration : float
        Time bound of one step (s); exceeding it is ``no_heel_strike``.
    record : bool
        Record the per-step impact angles, durations, ``T_c`` and step lengths.
    stop_near : (array_like of shape (3,), float), optional
        ``(z_target, tol)``: stop a walker (status completed) as soon as its post-impact state is
        within ``tol`` of ``z_target`` (Euclidean norm in section coordinates).
    parallel : bool, optional
        Run walkers on all cores with ``numba.prange``; default: parallel on the main thread,
        serial on other threads (e.g. Dask workers).
    initial_state : array_like, shape (N, 4), optional
        Full reduced states ``(q3, q4, q3_dot, q4_dot)`` to start from instead of ``z0`` (which is
        then ignored); e.g. to continue a walk.

    Returns
    -------
    EnsembleResult
    """
    if steps < 1:
        raise ValueError("steps must be >= 1")
    if initial_state is not None:
        Y0 = np.atleast_2d(np.asarray(initial_state, dtype=float))
        if Y0.shape[-1] != 4:
            raise ValueError(f"initial_state must have shape (N, 4), got {Y0.shape}")
    else:
        z = np.atleast_2d(np.asarray(z0, dtype=float))
        if z.shape[-1] != 3 or z.ndim != 2:
            raise ValueError(f"z0 must have shape (N, 3) or (3,), got {np.shape(z0)}")
        Y0 = np.stack((z[:, 0], -2.0 * z[:, 0], z[:, 1], z[:, 2]), axis=-1)
    P = walker_parameters(walker, slope)
    if P.ndim > 2:
        raise ValueError("walker parameters and slope must be scalars or 1-D arrays")
    n = max(Y0.shape[0], P.shape[0] if P.ndim == 2 else 1)
    P = np.broadcast_to(P, (n, 8)).copy(order="C")  # C order, as the kernel's signature says
    Y = np.broadcast_to(Y0, (n, 4)).copy(order="C")
    if not (np.all(np.isfinite(P)) and np.all(np.isfinite(Y))):
        raise ValueError("initial states and parameters must be finite")
    target = np.zeros(3)
    stop_tol = 0.0
    if stop_near is not None:
        target = np.asarray(stop_near[0], dtype=float).reshape(3).copy()
        stop_tol = float(stop_near[1])
    status = np.zeros(n, dtype=np.int64)
    taken = np.zeros(n, dtype=np.int64)
    elapsed = np.zeros(n)
    shape = (n, steps) if record else (1, steps)
    angle = np.full(shape, np.nan)
    time = np.full(shape, np.nan)
    tc = np.full(shape, np.nan)
    length = np.full(shape, np.nan)
    args: tuple[Any, ...] = (
        steps, float(rtol), float(atol), float(max_step_duration), target, stop_tol,
        status, taken, elapsed, angle, time, tc, length, bool(record),
    )
    if use_parallel(parallel) and n > 1:
        # a fixed shuffle balances the static prange split (falls are much cheaper than walks)
        order = np.random.default_rng(0).permutation(n).astype(np.int64)
        _parallel_ensemble()(P, Y, order, *args)
    else:
        _serial().ensemble(P, Y, np.arange(n, dtype=np.int64), *args)
    zf = np.stack((Y[:, 0], Y[:, 2], Y[:, 3]), axis=-1)
    return EnsembleResult(
        z=zf,
        state=Y,
        status=status,
        steps=taken,
        time=elapsed,
        impact_angle=angle if record else None,
        step_time=time if record else None,
        collision_loss=tc if record else None,
        step_length=length if record else None,
    )


class CompiledStep(NamedTuple):
    """One step of the compiled Poincare map (:func:`step_map_compiled`).

    Attributes
    ----------
    z : ndarray, shape (3,)
        Post-impact section coordinates after the leg swap (rad, rad/s); NaN if the step failed.
    step_time : float
        Duration of the step (s); NaN if it failed.
    impact_angle : float
        ``q3`` at heel strike (rad).
    collision_loss : float
        ``T_c`` at heel strike (J).
    step_length : float
        Distance along the ground between the stance and the striking contact points (m).
    status : WalkStatus
        How the step ended.
    """

    z: FloatArray
    step_time: float
    impact_angle: float
    collision_loss: float
    step_length: float
    status: WalkStatus

    def to_dict(self) -> dict[str, Any]:
        """Every field as plain Python (:func:`~heelstrike._results.tuple_dict`)."""
        return tuple_dict(self)


def step_map_compiled(
    walker: CompassGait,
    z: ArrayLike,
    slope: float,
    *,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step_duration: float = 5.0,
) -> CompiledStep:
    """The compiled step-to-step (Poincare) map of the passive walker.

    Parameters
    ----------
    walker : CompassGait
        Scalar-parameter walker.
    z : array_like, shape (3,)
        Post-impact section coordinates ``(q3, q3_dot, q4_dot)`` (rad, rad/s).
    slope : float
        Slope (rad).
    rtol, atol : float
        Integrator tolerances.
    max_step_duration : float
        Time bound of the step (s).

    Returns
    -------
    CompiledStep
    """
    res = ensemble_walk(
        walker, np.asarray(z, dtype=float).reshape(1, 3), slope, steps=1, rtol=rtol,
        atol=atol, max_step_duration=max_step_duration, parallel=False,
    )
    assert res.impact_angle is not None and res.step_time is not None
    assert res.collision_loss is not None and res.step_length is not None
    status = WalkStatus.from_code(int(res.status[0]))
    ok = status is WalkStatus.COMPLETED
    return CompiledStep(
        z=res.z[0] if ok else np.full(3, np.nan),
        step_time=float(res.step_time[0, 0]) if ok else math.nan,
        impact_angle=float(res.impact_angle[0, 0]),
        collision_loss=float(res.collision_loss[0, 0]),
        step_length=float(res.step_length[0, 0]),
        status=status,
    )


def single_support_compiled(
    walker: CompassGait,
    state: ArrayLike,
    slope: float,
    duration: float,
    *,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_samples: int = 100_000,
) -> FloatArray:
    """Integrate single support (no events) with the compiled DP5 and return every step.

    Parameters
    ----------
    walker : CompassGait
        Scalar-parameter walker.
    state : array_like, shape (4,)
        Initial ``(q3, q4, q3_dot, q4_dot)`` (rad, rad/s).
    slope : float
        Slope (rad).
    duration : float
        Time to integrate (s).
    rtol, atol : float
        Tolerances.
    max_samples : int
        Largest number of integrator steps stored.

    Returns
    -------
    ndarray, shape (K, 4)
        The state after every accepted step (the last at ``duration`` unless truncated).
    """
    p = walker_parameters(walker, slope)
    y = np.asarray(state, dtype=float).reshape(4).copy()
    out = np.empty((max_samples, 4))
    n = _serial().integrate_plain(p, y, float(duration), float(rtol), float(atol), out)
    return out[:n].copy()


def _on_generated_kernel(torque: Any, push_off: Any, friction: float | None,
                         max_step: float) -> bool:
    """A compiled compass walk runs on the kernel generated from the walker's description
    (not the passive compass kernel): a hip law, a push-off, a friction limit or dense
    samples (finite ``max_step``)."""
    return (torque is not None or push_off is not None or friction is not None
            or bool(np.isfinite(max_step)))


def check_compiled_compass(
    torque: Any = None, push_off: Any = None, friction: float | None = None,
    restitution: float = 0.0, *, walker: PlanarWalker | None = None,
    max_step: float = np.inf,
) -> None:
    """Raise ``ValueError`` unless the compiled backend runs this compass-gait actuation.

    The compass kernel walks the *passive* compass gait with an inert heel strike; a hip law
    (:class:`~heelstrike.dynamics.actuation.SwingLegPD` with a constant set point,
    :class:`~heelstrike.dynamics.actuation.EnergyTracking` of this walker's energy), a
    :class:`~heelstrike.dynamics.actuation.PushOff` impulse, a friction limit (``slipped``) or
    dense samples (finite ``max_step``) run on the kernel generated from the walker's
    description (:meth:`~heelstrike.models.base.PlanarWalker.as_described`, see
    :func:`simulate_compiled`), which ``walker`` (if given) must have. ``restitution = 0``.
    """
    from heelstrike.dynamics.actuation import EnergyTracking, PushOff, SwingLegPD

    unsupported = [
        name
        for name, given in (
            ("torque other than SwingLegPD or EnergyTracking",
             torque is not None and type(torque) not in (SwingLegPD, EnergyTracking)),
            ("push_off other than PushOff", push_off is not None and type(push_off) is not PushOff),
            ("restitution", float(restitution) != 0.0),
        )
        if given
    ]
    if unsupported:
        raise ValueError(
            "the compiled backend walks the compass gait passive, with the SwingLegPD or "
            "EnergyTracking hip law or with a PushOff impulse, with an inert impact "
            f"({', '.join(unsupported)} given); use backend='scipy'"
        )
    if _on_generated_kernel(torque, push_off, friction, max_step) and walker is not None:
        described = walker.as_described()
        if described is None:
            raise ValueError(
                "the compiled backend runs a hip law, a push-off, a friction limit or dense "
                "samples of the compass gait on the kernel generated from its description, "
                "and this walker has none (McGeer's wheel R = l, or a batch of walkers); use "
                "backend='scipy'"
            )
        from heelstrike.dynamics.compiled_phased import check_compiled_actuation

        check_compiled_actuation(described, torque, push_off)  # type: ignore[arg-type]


def simulate_compiled(
    walker: PlanarWalker,
    q0: ArrayLike,
    q_dot0: ArrayLike,
    *,
    slope: float = 0.0,
    steps: int = 1,
    torque: SwingLegPD | EnergyTracking | None = None,
    push_off: PushOff | None = None,
    friction: float | None = None,
    restitution: float = 0.0,
    max_step_duration: float = 5.0,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step: float = np.inf,
) -> WalkResult:
    """Compiled :func:`~heelstrike.dynamics.hybrid.simulate` of one compass gait.

    The passive walk without ``max_step`` runs this module's kernel, phase by phase (the
    integrator, events, impact and swap of :func:`ensemble_walk`, so impacts equal
    :func:`step_map_compiled`'s); the impact records are completed from the walker contract
    (impulse, trailing-foot velocity, energies,
    :meth:`~heelstrike.models.base.PlanarWalker.step_length`). A hip law, a push-off, a
    friction limit or dense samples (finite ``max_step``) run on the kernel generated from the
    walker's description instead
    (:meth:`~heelstrike.models.base.PlanarWalker.as_described`, the same equations and
    coordinates;
    :func:`~heelstrike.dynamics.compiled_phased.simulate_phased_compiled`).

    Parameters
    ----------
    walker : PlanarWalker
        A scalar-parameter walker with ``compiled_kernel == "compass"``.
    q0, q_dot0 : array_like, shape (4,)
        Initial state, stance foot on the ground (``q2 = R``) and rolling.
    slope : float
        Ground slope (rad).
    steps : int
        Number of heel strikes to simulate.
    torque : SwingLegPD or EnergyTracking, optional
        Hip law, evaluated in the generated kernel (:func:`check_compiled_compass`); None:
        passive hip.
    push_off : PushOff, optional
        Push-off impulse just before each heel strike (generated kernel).
    friction : float, optional
        Coulomb coefficient of the stance foot (generated kernel).
    restitution : float
        Must be 0 (the inert impact).
    max_step_duration : float
        Time bound of one step (s).
    rtol, atol : float
        Integrator (DP5) tolerances.
    max_step : float
        Largest integrator step (s); finite asks for dense samples (generated kernel).

    Returns
    -------
    WalkResult
        The compass kernel's samples are the phase boundaries only: the start of every step,
        mid-stance and the state just before heel strike. The generated kernel's
        (:class:`~heelstrike.dynamics.hybrid.PhasedWalkResult`) are its integrator's steps.

    Raises
    ------
    ValueError
        On an invalid initial state, batched parameters or unsupported actuation.
    """
    check_compiled_compass(torque, push_off, friction, restitution, walker=walker,
                           max_step=max_step)
    if _on_generated_kernel(torque, push_off, friction, max_step):
        from heelstrike.dynamics.compiled_phased import simulate_phased_compiled

        return simulate_phased_compiled(
            walker.as_described(),  # type: ignore[arg-type]  # checked above: not None
            q0, q_dot0, slope=slope, steps=steps, torque=torque, push_off=push_off,
            friction=friction,
            max_step_duration=max_step_duration, rtol=rtol, atol=atol, max_step=max_step,
        )
    p = walker_parameters(walker, slope)
    if p.shape != (8,):
        raise ValueError("the compiled compass kernel walks one walker (scalar parameters)")
    q, qd = check_initial_state(walker, q0, q_dot0, steps)
    R = float(p[4])
    leg_length = float(walker.scale.leg_length)
    kernel = _serial()
    k = np.empty((7, 4))
    qp = np.empty(4)
    y = np.array([q[2], q[3], qd[2], qd[3]])
    t, h = 0.0, 0.0
    ts: list[float] = []
    qs: list[FloatArray] = []
    qds: list[FloatArray] = []
    legs: list[int] = []
    step_ids: list[int] = []
    impacts: list[ImpactRecord] = []
    stance = 0
    status = WalkStatus.COMPLETED

    def full(x_start: float, q3_start: float) -> tuple[FloatArray, FloatArray]:
        """Floating-base state of the reduced ``y`` (stance foot rolled from the start)."""
        qq = np.array([x_start - R * (y[0] - q3_start), R, y[0], y[1]])
        return qq, np.array([-R * y[2], 0.0, y[2], y[3]])

    def sample(tt: float, qq: FloatArray, vv: FloatArray, step: int) -> None:
        ts.append(tt)
        qs.append(qq)
        qds.append(vv)
        legs.append(stance)
        step_ids.append(step)

    for n in range(steps):
        t_step, q_start, q3_start = t, q.copy(), float(y[0])
        sample(t, q, qd, n)
        t_limit = t_step + max_step_duration
        ev = _EV_MID
        if y[0] < 0.0:
            ev, t, h = kernel.integrate_phase(p, y, t, t_limit, 1, h, rtol, atol, k)
            q, qd = full(q_start[0], q3_start)
            sample(t, q, qd, n)
        if ev == _EV_MID:
            ev, t, h = kernel.integrate_phase(p, y, t, t_limit, 2, h, rtol, atol, k)
            q, qd = full(q_start[0], q3_start)
            sample(t, q, qd, n)
        if ev != _EV_STRIKE:
            status = WalkStatus.from_code(kernel.phase_status(ev))
            break
        T, Tc = kernel.impact(p, y, qp)
        qd_plus = qp.copy()
        M = walker.mass_matrix(q)
        A_L = walker.contact_jacobian(q, "left")
        impulse = np.asarray(np.linalg.solve(A_L @ A_L.T, A_L @ (M @ (qd_plus - qd))), np.float64)
        v_trailing = float((walker.contact_jacobian(q, "right") @ qd_plus)[1])
        impacts.append(
            ImpactRecord.of_step(
                walker, slope, step=n, step_start=(t_step, q_start), time=t, q=q,
                q_dot_minus=qd, q_dot_plus=qd_plus, kinetic_energy=float(T),
                kinetic_energy_constrained=float(Tc), kinetic_energy_admissible=float(T - Tc),
                impulse=impulse, trailing_normal_velocity=v_trailing,
            )
        )
        if not _contact.lifts(v_trailing, _contact.lift_velocity_scale(leg_length, qd[2:])):
            status = WalkStatus.TRAILING_FOOT_STAYS
            qd = qd_plus
            break
        q, qd = (np.asarray(a, dtype=float) for a in walker.swap_legs(q, qd_plus))
        y[:] = q[2], q[3], qd[2], qd[3]
        stance = 1 - stance
    return WalkResult(
        status=status,
        message=status.message,
        t=np.asarray(ts),
        q=np.asarray(qs),
        q_dot=np.asarray(qds),
        stance_leg=np.asarray(legs, dtype=np.int_),
        step=np.asarray(step_ids, dtype=np.int_),
        actuator_work=np.zeros(len(ts)),
        impacts=tuple(impacts),
        final_q=np.asarray(q),
        final_q_dot=np.asarray(qd),
        slope=float(slope),
    )
