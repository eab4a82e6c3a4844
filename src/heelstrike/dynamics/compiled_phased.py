"""Compiled (numba) phased simulation of any described walker: the ``"compiled"`` backend.

The same hybrid model as :func:`heelstrike.dynamics.phased.simulate_phased`, step for step:

- *knee swing* (walkers with lockable joints): stance knee locked, swing knee free; first until
  the swing knee has flexed past ``knee_flex_threshold``, then until it straightens to its lock
  angle (**knee strike**: an inert impact with ``A = [A_R; lock rows]``);
- *locked swing*: all lockable joints locked; first until the heel strike is *armed* (stance
  angle > 0, swing foot ahead and above the ground), then until the swing foot's clearance
  falls through zero;
- **heel strike**: bilateral rows ``[A_L; lock rows]``, the trailing foot a unilateral
  candidate whose mode (separate, stick, slip fallback) is decided by enumerating the active
  sets in the order of :func:`heelstrike.core.complementarity.resolve_impact`; the walk ends
  with ``trailing_foot_stays`` unless it separates with ``v_n > LIFT_TOLERANCE l sum |q_dot-|``
  (the rule of :mod:`heelstrike.models._contact`, compiled); then the legs are
  relabelled (``swap``) and the locks reset exactly.

A walker whose legs differ (a ``[swap]`` table, two
:attr:`~heelstrike.models.base.PlanarWalker.steps_per_period`) alternates with the walker
after its leg swap, as the scipy reference does: the kernel takes the parameter values, float
configuration and lock angles of both (:func:`stride_walkers`; they share the generated
functions) as the rows of 2-row arrays, and step ``k`` is taken with row ``k mod 2`` (the swap
itself with the striking step's row), in the single walk and in the ensembles, whose arrival
test is made after whole strides.

A walker file declaring its heel-strike guard (``[events] heel_strike``, e.g. McGeer's wheel
``wheel.toml``) runs it as the scipy reference does
(:meth:`heelstrike.models.builder.BuiltWalker.step_schedule`): the locked swing is armed when
the stance angle rises through zero (skipped if it is ``>= 0``), the strike is the declared
guard (generated into the same numba source as the equations:
:mod:`heelstrike.models._codegen_numba`'s ``heel_strike_guard``) rising through zero, and a
crossing with the swing foot off the ground (``|clearance| > CONTACT_TOLERANCE l``) arms it
anew. With ``trailing_foot = "lifts_or_grazes"`` the heel strike is the projector with rows
``[A_L; lock rows]`` only, and the walk goes on if the trailing foot lifts or grazes
(:func:`~heelstrike.models._contact.grazes`; modes ``"graze"``, ``"separate"`` or
``"penetrating"``); with ``"lifts"`` the trailing foot is the complementarity candidate above.

Each continuous stretch uses the terminal events of ``simulate_phased`` (``lost_contact``,
``fell_forward``, ``fell_backward`` and, with a friction coefficient, ``slipped``) with
``solve_ivp``'s crossing rules; a stretch that starts with the contact already lost (normal
force or friction margin ``<= 0``) ends at once with that status. The right-hand side is the
reduced single-support dynamics ``J^T M J theta_dd = J^T (B u - h)`` with ``M``, ``h``, the
contact Jacobians, the swap and the declared guard generated from the walker's sympy expressions
(:mod:`heelstrike.models._codegen_numba`). The integrator is the Dormand-Prince 5(4) scheme of
:mod:`heelstrike.dynamics._dp5`, shared with :mod:`heelstrike.dynamics.compiled` (scipy's error
norm and step control; an event's time is located by the Illinois method on the exact
Runge-Kutta step, to ``1e-13 s``), for any number of free coordinates.

Actuation (all evaluated in the kernel; see :func:`check_compiled_actuation`): passive, the
:class:`~heelstrike.dynamics.phased.TorsoPD` posture law, on a walker whose one actuated joint
is coordinate 3 (the compass gait's hip) the :class:`~heelstrike.dynamics.actuation.SwingLegPD`
set point and :class:`~heelstrike.dynamics.actuation.EnergyTracking` hip laws (``T + V`` from the
generated ``dynamics``), and the :class:`~heelstrike.dynamics.actuation.PushOff` impulse; other
torque laws and push-off models need the ``"scipy"`` backend.

The numba functions are in :mod:`heelstrike.dynamics._phased_kernels`. Through numba's JIT the
kernel takes the generated functions as first-class function arguments, so it is compiled (and
disk-cached by numba) once for every walker; serial calls of a shipped walker (and of any
walker, with ``HEELSTRIKE_AOT=all``) run an extension module compiled ahead of time from the
same source with that walker's functions bound (:data:`AOT_EXPORTS`,
:mod:`heelstrike.dynamics._aot`: identical results, no numba in the process). Samples are the
states after every accepted integrator step (not scipy's); impacts and statuses are the same as
the scipy reference's (``tests/test_backend_conformance.py``).
"""

from __future__ import annotations

import importlib.resources
import itertools
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray, IntArray
from heelstrike.core._parallel import use_parallel
from heelstrike.core.impact import ImpactInputError
from heelstrike.dynamics._aot import AotExport, AotLibrary, aot_mode, load_library
from heelstrike.dynamics.actuation import EnergyTracking, PushOff, SwingLegPD
from heelstrike.dynamics.compiled import STATUS_NAMES, EnsembleStatus
from heelstrike.dynamics.hybrid import ImpactRecord, WalkStatus, cut_off_profile
from heelstrike.dynamics.phased import (
    ImpactKind,
    PhasedImpact,
    PhasedWalker,
    PhasedWalkResult,
    TorsoPD,
    check_initial_state,
)
from heelstrike.models._codegen_numba import NumbaModel, build_numba, numba_source_key
from heelstrike.models.builder import BuiltWalker

__all__ = [
    "STATUS_NAMES",
    "PhasedEnsembleResult",
    "check_compiled_actuation",
    "ensemble_walk_phased",
    "numba_model",
    "section_states",
    "simulate_phased_compiled",
    "stride_walkers",
]

# Kernel status codes beyond the compass kernel's (plain ints: numba freezes globals).
SLIPPED = WalkStatus.SLIPPED.code
_NO_CONSISTENT_ASSIGNMENT = WalkStatus.NO_CONSISTENT_ASSIGNMENT.code
_NO_SWAP = WalkStatus.NO_LEG_SWAP.code

# event kinds
_EV_FLEXED, _EV_KNEE, _EV_ARMED, _EV_STRIKE = 0, 1, 2, 3
_EV_LOST, _EV_FWD, _EV_BACK, _EV_SLIP = 4, 5, 6, 7
_EV_NONE = -1  # time limit reached
_EV_FAIL = -2  # integrator failure

# float configuration: slope, stance foot radius, swing foot radius, knee flex threshold,
# friction coefficient (nan: none), the joint law's joint (-1: passive), its reference angle,
# kp, kd, push-off impulse (nan: none), leg length of the walker's scale (the lift rule's
# velocity scale), the joint law (_LAW_*), its torque limit (N m, inf: none), the energy gain
# and the target energy (J), the heel-strike guard (1.0: the walker's declared guard, 0.0: the
# swing foot's clearance) and the trailing-foot rule (1.0: lift or graze, 0.0: complementarity)
_C_SLOPE, _C_RST, _C_RSW, _C_THR, _C_MU, _C_TJ, _C_TANG, _C_KP, _C_KD, _C_PUSH, _C_LEG = range(11)
_C_LAW, _C_UMAX, _C_GAIN, _C_EREF, _C_GUARD, _C_TRAIL = range(11, 17)
# joint laws: TorsoPD (absolute angle q_2 + q_j), SwingLegPD (relative q_j), EnergyTracking
_LAW_POSTURE, _LAW_JOINT_PD, _LAW_ENERGY = 0, 1, 2
#: The torque laws the kernel evaluates (:func:`check_compiled_actuation`).
JointLaw = TorsoPD | SwingLegPD | EnergyTracking

# impact row layout: kind, step, time, T, T_c, T_a, v_trail, mode, rows, work, push-off work,
# then q, q_dot-, q_dot+ and the impulses (n each)
_I_HEAD = 11
_KIND_KNEE, _KIND_HEEL = 0.0, 1.0
_MODES = ("separate", "stick", "slip", "graze", "penetrating")
_MODE_SEPARATE, _MODE_GRAZE, _MODE_PENETRATING = 0, 3, 4

# ---------------------------------------------------------------------------------------------
# The kernel's entry points
# ---------------------------------------------------------------------------------------------
_F2 = "f8[:,::1]"
_WALK_ARGS = (_F2, _F2, "f8[::1]", "f8[::1]", "i8", "i8[::1]", "i8[::1]", _F2,
              "f8", "f8", "f8", "f8")
#: A walker's entry points compiled ahead of time (its generated functions bound; see
#: :func:`heelstrike.dynamics._phased_kernels.bound_functions`), with their signatures:
#: ``walk(P, CFG, q0, q_dot0, steps, stance_locks, swing_locks, LOCK_VALUES, max_duration,
#: rtol, atol, max_step) -> (status, samples, n_samples, impacts, n_impacts, step_starts, q,
#: q_dot)`` and ``ensemble(P, CFG, Q0, QD0, steps, stance_locks, swing_locks, LOCK_VALUES,
#: max_duration, rtol, atol, max_step, section_q, section_v, target, stop_tol, i0, i1, status,
#: taken, Q, QD)``. ``P``, ``CFG`` and ``LOCK_VALUES`` have one row per walker of a period
#: (:func:`stride_walkers`): step ``k`` is taken with row ``k mod s``.
AOT_EXPORTS: tuple[AotExport, ...] = (
    AotExport(name="walk", args=_WALK_ARGS,
              returns=f"Tuple((i8, {_F2}, i8, {_F2}, i8, {_F2}, f8[::1], f8[::1]))"),
    AotExport(name="ensemble",
              args=(*_WALK_ARGS[:2], _F2, _F2, *_WALK_ARGS[4:], "i8[::1]", "i8[::1]", "f8[::1]",
                    "f8", "i8", "i8", "i8[::1]", "i8[::1]", _F2, _F2),
              returns="void"),
)
_SOURCES = (
    "heelstrike.dynamics._phased_kernels", "heelstrike.dynamics.compiled_phased",
    "heelstrike.dynamics._compass_kernels", "heelstrike.dynamics.compiled",
    "heelstrike.dynamics.hybrid", "heelstrike.dynamics._dp5", "heelstrike.models._contact",
    "heelstrike.models._codegen_numba",
)


class _Libraries:
    """Each walker structure's ahead-of-time library, by the key of its generated code (a
    cache, an object: module-level dicts are data to the sweep identity)."""

    def __init__(self) -> None:
        self.by_key: dict[str, AotLibrary] = {}


_LIBRARIES = _Libraries()


def _library(walker: BuiltWalker) -> AotLibrary:
    desc = walker.description
    key = numba_source_key(desc)
    lib = _LIBRARIES.by_key.get(key)
    if lib is None:

        def functions() -> dict[str, Any]:
            from heelstrike.dynamics._phased_kernels import bound_functions

            return bound_functions(build_numba(desc))

        def size() -> float:
            from heelstrike.dynamics._aot import _source_lines

            generated = build_numba(desc)  # derived first (announced as a build of its own)
            lines = generated.path.read_text().count("\n") if generated.path else 400
            return float(_source_lines(_SOURCES) + lines)

        lib = _LIBRARIES.by_key[key] = AotLibrary(
            name=f"walker_{desc.name}" if desc.name.isidentifier() else "walker",
            exports=AOT_EXPORTS, functions=functions, source_modules=_SOURCES, key=key,
            kind="aot-walker", size=size,
            what=f"the {desc.name!r} walker's kernels, compiled ahead of time",
        )
    return lib


def _builds_ahead_of_time(walker: BuiltWalker) -> bool:
    """Whether a walker's missing ahead-of-time module is built on first use.

    Yes for the shipped walkers (``heelstrike/walkers``) and, with ``HEELSTRIKE_AOT=all``, for
    every walker. Otherwise (a walker file of your own) the JIT kernel runs it: compiled once
    for all walkers, a new structure costs seconds there, its own module about a minute; a
    module already built for the same structure (e.g. a copy of a shipped walker) is used.
    """
    if aot_mode() == "all":
        return True
    shipped = Path(str(importlib.resources.files("heelstrike") / "walkers")).resolve()
    try:
        return Path(walker.description.source).resolve().parent == shipped
    except (OSError, ValueError):
        return False


def _kernels(walker: BuiltWalker, *, serial: bool = True) -> Any:
    """A walker's ``walk`` and ``ensemble`` entry points (:data:`AOT_EXPORTS`).

    Serial calls run the walker's ahead-of-time module (built on first use for the walkers of
    :func:`_builds_ahead_of_time`); without it, and for calls from several threads at once
    (``serial=False``: the module holds the GIL), numba's JIT kernel with the generated
    functions passed in.
    """
    if serial:
        aot = load_library(_library(walker), build_missing=_builds_ahead_of_time(walker))
        if aot is not None:
            return aot
    from heelstrike.dynamics._phased_kernels import JitBound

    return JitBound(numba_model(walker))


# ---------------------------------------------------------------------------------------------
# Python API
# ---------------------------------------------------------------------------------------------
def numba_model(walker: BuiltWalker) -> NumbaModel:
    """The numba functions generated for a walker's structure (built and cached on demand)."""
    return build_numba(walker.description)


def _same_walker(law_walker: Any, walker: BuiltWalker) -> bool:
    """``law_walker`` (an energy law's) has ``walker``'s equations: it is ``walker``, or its
    description (:meth:`~heelstrike.models.base.PlanarWalker.as_described`) has the same
    structure and parameter values."""
    if law_walker is walker:
        return True
    described = law_walker if law_walker.description is not None else law_walker.as_described()
    if described is None:
        return False
    if described is walker:
        return True
    names = walker.description.param_names
    return bool(
        described.model.key == walker.model.key  # the same structure (its code's key)
        and all(np.array_equal(np.asarray(described.parameters[k], dtype=float),
                               np.asarray(walker.parameters[k], dtype=float)) for k in names)
    )


def check_compiled_actuation(walker: BuiltWalker, torque: Any, push_off: Any) -> None:
    """Raise ``ValueError`` unless the compiled backend supports this actuation.

    Supported: no push-off or a :class:`~heelstrike.dynamics.actuation.PushOff`, and

    - passive (``torque=None``);
    - a :class:`~heelstrike.dynamics.phased.TorsoPD` torque on a walker with a ``torso`` joint;
    - on a walker whose one actuated joint is the law's ``joint`` (its hip: coordinate 3 of
      the compass gait and of its description ``compass.toml``, 4 of ``kneed.toml``): a
      :class:`~heelstrike.dynamics.actuation.SwingLegPD` set point (no time profile), or
      :class:`~heelstrike.dynamics.actuation.EnergyTracking` whose walker has this walker's
      equations (the walker itself, or the compass gait it describes with the same parameter
      values; its slope must be the walk's).
    """
    if push_off is not None and type(push_off) is not PushOff:
        raise ValueError(
            "the compiled backend supports the PushOff impulse only; use backend='scipy'"
        )
    if torque is None or (type(torque) is TorsoPD and "torso" in walker.coordinate_names):
        return
    hip_laws = "TorsoPD, SwingLegPD and EnergyTracking"
    if type(torque) is TorsoPD:
        raise ValueError("TorsoPD acts across a joint named 'torso', and this walker has none")
    if type(torque) not in (SwingLegPD, EnergyTracking):
        raise ValueError(
            f"the compiled backend evaluates passive walking and the {hip_laws} torque laws "
            "only; use backend='scipy' for other torque laws"
        )
    if tuple(walker.actuated_joints) != (torque.joint,):
        raise ValueError(
            f"{type(torque).__name__} acts across coordinate {torque.joint}, and the walker's "
            f"one actuated joint must be that one; this walker's actuated joints are "
            f"{tuple(walker.actuated_joints)}"
        )
    if type(torque) is SwingLegPD and torque.profile is not None:
        raise ValueError(
            "the compiled backend evaluates SwingLegPD with a constant set point (profile=None); "
            "use backend='scipy' for a time profile"
        )
    if type(torque) is EnergyTracking and not all(
            _same_walker(torque.walker, w) for w in stride_walkers(walker)):
        raise ValueError(
            "EnergyTracking's walker must be the walker simulated at every step (its energy "
            "T + V is evaluated in the kernel from the equations of the walker taking the step; "
            "a walker whose legs differ alternates with the walker after its leg swap): use "
            "backend='scipy'"
        )


def _joint_law(walker: BuiltWalker, torque: JointLaw | None, slope: float) -> tuple[float, ...]:
    """``(law, joint, reference angle, kp, kd, torque limit, gain, target energy)`` of the
    kernel's configuration for a torque checked by :func:`check_compiled_actuation` (joint -1:
    passive)."""
    if torque is None:
        return (_LAW_POSTURE, -1.0, 0.0, 0.0, 0.0, math.inf, 0.0, 0.0)
    if isinstance(torque, SwingLegPD):
        return (_LAW_JOINT_PD, float(torque.joint), torque.reference(0.0), float(torque.kp),
                float(torque.kd), float(torque.max_torque), 0.0, 0.0)
    if isinstance(torque, EnergyTracking):
        if float(torque.slope) != float(slope):
            raise ValueError(
                f"the compiled backend evaluates EnergyTracking's potential energy on the "
                f"walk's slope ({slope} rad); the law's is {torque.slope} rad: use "
                "backend='scipy'"
            )
        hip = walker.hip_joint if torque.joint is None else torque.joint  # set by the law
        return (_LAW_ENERGY, float(hip), 0.0, 0.0, 0.0, float(torque.max_torque),
                float(torque.gain), float(torque.energy))
    joint = float(walker.joint_index("torso"))
    return (_LAW_POSTURE, joint, float(torque.angle), float(torque.kp), float(torque.kd),
            math.inf, 0.0, 0.0)


def stride_walkers(walker: BuiltWalker) -> tuple[BuiltWalker, ...]:
    """The walkers taking the steps of one period, in order: step ``k`` of a walk from
    ``walker`` is taken by member ``k mod s`` (``s`` =
    :attr:`~heelstrike.models.base.PlanarWalker.steps_per_period`).

    ``(walker,)`` when the leg swap is a symmetry; for a walker whose legs differ
    ``(walker, walker.after_swap())``, as :func:`~heelstrike.dynamics.hybrid.simulate`
    alternates them. Both have the walker's description (the same generated equations), so one
    kernel walks the stride with their parameter values alternating.

    Parameters
    ----------
    walker : BuiltWalker

    Returns
    -------
    tuple of BuiltWalker
        Length ``walker.steps_per_period``.

    Raises
    ------
    ValueError
        If a walker of the period has another description (another kernel).
    """
    out = [walker]
    while len(out) < int(walker.steps_per_period):
        nxt = out[-1].after_swap()
        if nxt.description is None or (nxt.description is not walker.description
                                       and nxt.description != walker.description):
            raise ValueError(
                f"walker {walker.description.name!r}: the walker after its leg swap has another "
                "description, so the compiled kernel cannot walk its stride")
        out.append(cast(BuiltWalker, nxt))
    return tuple(out)


def _locks(walker: BuiltWalker) -> tuple[tuple[int, ...], tuple[int, ...], FloatArray]:
    """``(stance locks, swing locks, LOCK_VALUES)``: the lock angle of every coordinate (rad,
    0 if none), one row per walker of :func:`stride_walkers` (shape (s, n))."""
    stance_locks, swing_locks = walker.stance_and_swing_locks()
    stride = stride_walkers(walker)
    lockv = np.zeros((len(stride), walker.n_coordinates))
    for r, w in enumerate(stride):
        if w.stance_and_swing_locks() != (stance_locks, swing_locks):
            raise ValueError(f"walker {walker.description.name!r}: the walker after its leg "
                             "swap locks other joints")
        for j, a in zip(w.lockable_joints, w.lock_angles, strict=True):
            lockv[r, j] = float(a)
    return stance_locks, swing_locks, lockv


def _configuration(
    walker: BuiltWalker, slope: float, torque: JointLaw | None, push_off: PushOff | None,
    friction: float | None, knee_flex_threshold: float,
) -> tuple[FloatArray, FloatArray]:
    """The kernel's parameter values ``P`` and float configurations ``CFG`` (``_C_*``), one
    row per walker of :func:`stride_walkers`, shapes (s, n_p) and (s, n_cfg)."""
    rows = [_one_configuration(w, slope, torque, push_off, friction, knee_flex_threshold)
            for w in stride_walkers(walker)]
    return (np.ascontiguousarray(np.stack([p for p, _ in rows])),
            np.ascontiguousarray(np.stack([c for _, c in rows])))


def _one_configuration(
    walker: BuiltWalker, slope: float, torque: JointLaw | None, push_off: PushOff | None,
    friction: float | None, knee_flex_threshold: float,
) -> tuple[FloatArray, FloatArray]:
    """One walker's parameter values ``p`` and float configuration ``cfg`` (``_C_*``)."""
    walker.check_heel_strike_detectable()  # a clearance guard must see the strike
    events = walker.description.events
    declared = events is not None
    grazing = declared and events.trailing_foot == "lifts_or_grazes"  # type: ignore[union-attr]
    values = [np.asarray(walker.parameters[k], dtype=float) for k in walker.description.param_names]
    if any(v.ndim != 0 for v in values):
        raise ValueError("the compiled backend needs scalar parameter values (one walker)")
    law, tj, tang, kp, kd, umax, gain, eref = _joint_law(walker, torque, slope)
    cfg = np.array(
        [slope, float(np.asarray(walker.foot_radii[0])), float(np.asarray(walker.foot_radii[1])),
         knee_flex_threshold, math.nan if friction is None else float(friction), tj, tang, kp,
         kd, math.nan if push_off is None else float(push_off.impulse),
         float(walker.scale.leg_length), law, umax, gain, eref, float(declared),
         float(grazing)],
        dtype=float,
    )
    return np.array([float(v) for v in values]), cfg


def simulate_phased_compiled(
    walker: BuiltWalker,
    q0: ArrayLike,
    q_dot0: ArrayLike,
    *,
    slope: float = 0.0,
    steps: int = 1,
    torque: JointLaw | None = None,
    push_off: PushOff | None = None,
    friction: float | None = None,
    max_step_duration: float = 5.0,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step: float = np.inf,
    knee_flex_threshold: float = 1e-6,
) -> PhasedWalkResult:
    """Compiled :func:`~heelstrike.dynamics.phased.simulate_phased` (same arguments and result).

    Parameters
    ----------
    walker : BuiltWalker
        Any described walker (scalar parameters). A walker whose legs differ alternates with
        the walker after its leg swap (:func:`stride_walkers`), as the scipy reference does:
        step ``k`` is taken with the parameter values of member ``k mod 2``.
    q0, q_dot0 : array_like, shape (n,)
        State just after a heel strike (stance foot rolling, lockable joints locked).
    slope : float
        Ground slope (rad).
    steps : int
        Number of heel strikes to simulate.
    torque : TorsoPD, SwingLegPD or EnergyTracking, optional
        Joint law evaluated in the kernel (:func:`check_compiled_actuation`); None: passive.
    push_off : PushOff, optional
        Push-off impulse just before each heel strike (evaluated in the kernel).
    friction : float, optional
        Coulomb coefficient of the stance foot (``slipped`` event).
    max_step_duration : float
        Time bound of one step (s).
    rtol, atol, max_step : float
        Integrator (DP5) settings.
    knee_flex_threshold : float
        The swing knee must flex past this angle (rad) before its strike is looked for.

    Returns
    -------
    PhasedWalkResult
        Samples are the states after every accepted integrator step. A walk in which a
        profile foot leaves its ``phi_range`` ends in ``off_profile`` at the first sample or
        heel strike out of range (:func:`~heelstrike.dynamics.hybrid.cut_off_profile`).

    Raises
    ------
    ValueError
        On an invalid initial state, or actuation this backend does not support.
    NotImplementedError
        If a step ends in a heel strike and the walker declares no mirrors (no leg swap).
    """
    q, qd = check_initial_state(walker, q0, q_dot0, steps)
    check_compiled_actuation(walker, torque, push_off)
    stance_locks, swing_locks, lockv = _locks(walker)
    p, cfg = _configuration(walker, slope, torque, push_off, friction, knee_flex_threshold)
    status, S, ns, Imp, ni, starts, qf, qdf = _kernels(walker).walk(
        p, cfg, q, qd, int(steps),
        np.asarray(stance_locks, dtype=np.int64), np.asarray(swing_locks, dtype=np.int64),
        lockv, float(max_step_duration), float(rtol), float(atol), float(max_step),
    )
    if status == _NO_CONSISTENT_ASSIGNMENT:
        raise ImpactInputError(WalkStatus.NO_CONSISTENT_ASSIGNMENT.message)
    if status == _NO_SWAP:
        raise NotImplementedError(
            f"walker {walker.description.name!r}: {WalkStatus.NO_LEG_SWAP.message}"
        )
    walk = _result(walker, int(status), S[:ns], Imp[:ni], starts, qf, qdf, float(slope),
                   stance_locks + swing_locks)
    return cut_off_profile(walker, walk)  # the kernel has no off_profile guards


def _result(
    walker: BuiltWalker, status: int, S: FloatArray, Imp: FloatArray, starts: FloatArray,
    qf: FloatArray, qdf: FloatArray, slope: float, all_locks: tuple[int, ...],
) -> PhasedWalkResult:
    n = walker.n_coordinates
    A_lock = walker.lock_jacobian(all_locks) if all_locks else np.zeros((0, n))
    events: list[PhasedImpact] = []
    records: list[ImpactRecord] = []
    first = walker
    stride = stride_walkers(first)
    for row in Imp:
        kind: ImpactKind = "knee_strike" if row[0] == _KIND_KNEE else "heel_strike"
        k = int(row[1])
        walker = stride[k % len(stride)]  # the walker taking step k
        t = float(row[2])
        nrows = int(row[8])
        q = row[_I_HEAD : _I_HEAD + n].copy()
        qdm = row[_I_HEAD + n : _I_HEAD + 2 * n].copy()
        qdp = row[_I_HEAD + 2 * n : _I_HEAD + 3 * n].copy()
        lam = row[_I_HEAD + 3 * n : _I_HEAD + 3 * n + nrows].copy()
        mode = _MODES[int(row[7])]
        if kind == "knee_strike":
            rows = np.vstack((walker.contact_jacobian(q, "right"), A_lock))
        else:
            A_R = walker.contact_jacobian(q, "right")
            extra = {"stick": A_R[::-1], "slip": A_R[1:]}.get(mode, A_R[:0])
            rows = np.vstack((walker.contact_jacobian(q, "left"), A_lock, extra))
        T, T_c, T_a = float(row[3]), float(row[4]), float(row[5])
        v_trail = float(row[6])
        events.append(
            PhasedImpact(
                kind=kind, step=k, time=t, q=q, q_dot_minus=qdm, q_dot_plus=qdp, rows=rows,
                kinetic_energy=T, kinetic_energy_constrained=T_c, kinetic_energy_admissible=T_a,
                energy_lost=T_c, impulse=lam, lock_rows=A_lock.copy(),
                lock_velocity_post=A_lock @ qdp, trailing_normal_velocity=v_trail,
                trailing_mode=mode,
            )
        )
        if kind == "heel_strike":
            t0, w0 = float(starts[k, 0]), float(starts[k, 1])
            q_start = starts[k, 2:]
            records.append(
                ImpactRecord.of_step(
                    walker, slope, step=k, step_start=(t0, q_start), time=t, q=q,
                    q_dot_minus=qdm, q_dot_plus=qdp, kinetic_energy=T,
                    kinetic_energy_constrained=T_c, kinetic_energy_admissible=T_a,
                    impulse=lam[:2].copy(), trailing_normal_velocity=v_trail,
                    actuator_work=float(row[9]) - w0, push_off_work=float(row[10]),
                )
            )
    st = WalkStatus.from_code(status)
    q_all = np.ascontiguousarray(S[:, 5 : 5 + n])
    qd_all = np.ascontiguousarray(S[:, 5 + n : 5 + 2 * n])
    # each sample's energy is that of the walker taking its step (as hybrid.simulate)
    energy = np.empty(S.shape[0])
    of_step = S[:, 2].astype(np.int_) % len(stride)
    for r, w in enumerate(stride):
        at = of_step == r
        energy[at] = np.asarray(w.mechanical_energy(q_all[at], qd_all[at], slope))
    return PhasedWalkResult(
        status=st,
        message=st.message,
        t=S[:, 0].copy(),
        q=q_all,
        q_dot=qd_all,
        stance_leg=S[:, 3].astype(np.int_),
        step=S[:, 2].astype(np.int_),
        actuator_work=S[:, 1].copy(),
        impacts=tuple(records),
        final_q=np.asarray(qf),
        final_q_dot=np.asarray(qdf),
        slope=slope,
        events=tuple(events),
        phase=np.where(S[:, 4] == 0, "knee_swing", "locked_swing"),
        mechanical_energy=energy,
    )



@dataclass(frozen=True, kw_only=True)
class PhasedEnsembleResult(EnsembleStatus, ResultDictMixin):
    """Outcome of :func:`ensemble_walk_phased` for ``N`` walkers (initial states).

    Attributes
    ----------
    status : ndarray of int, shape (N,)
        Status codes, names in :data:`STATUS_NAMES` (the ``WalkStatus`` values, as returned by
        :func:`~heelstrike.dynamics.phased.simulate_phased`).
    steps : ndarray of int, shape (N,)
        Heel strikes taken (``PhasedWalkResult.n_steps``; a heel strike that left the trailing
        foot on the ground counts).
    q, q_dot : ndarray, shape (N, n)
        Final state (m, rad, m/s, rad/s): just after the last heel strike and leg swap for a
        completed walk; where the walk ended otherwise (``final_q`` / ``final_q_dot`` of
        ``simulate_phased``).
    z : ndarray, shape (N, d)
        Section coordinates of the final state (``PhasedWalker.section_names``; rad, rad/s).
    section_names : tuple of str
        Names of the ``d`` section coordinates.
    """

    status: IntArray
    steps: IntArray
    q: FloatArray
    q_dot: FloatArray
    z: FloatArray
    section_names: tuple[str, ...]


def section_states(walker: BuiltWalker, z: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Post-heel-strike states of many section points (``PhasedWalker.section_to_state``).

    The touchdown configuration (a Newton solve) is computed once per distinct angle part of
    ``z``, so a grid with few distinct angles is cheap.

    Parameters
    ----------
    walker : BuiltWalker
    z : array_like, shape (N, d) or (d,)
        Section coordinates (rad, rad/s).

    Returns
    -------
    q, q_dot : ndarray, shape (N, n)
    """
    w = PhasedWalker.from_built(walker)
    Z = np.atleast_2d(np.asarray(z, dtype=float))
    d = len(w.section_names)
    if Z.ndim != 2 or Z.shape[1] != d:
        raise ValueError(f"z must have shape (N, {d}) or ({d},): {w.section_names}")
    nq = d - len(w._section_v)
    angles, inverse = np.unique(Z[:, :nq], axis=0, return_inverse=True)
    q_by_angle = np.array([w.section_to_state(np.concatenate((a, np.zeros(d - nq))))[0]
                           for a in angles])
    Q = q_by_angle[np.asarray(inverse).ravel()]
    QD = np.zeros_like(Q)
    QD[:, list(w._section_v)] = Z[:, nq:]
    R = float(np.asarray(w.foot_radii[0]))
    QD[:, 0] = -R * QD[:, 2]
    return Q, QD


def ensemble_walk_phased(
    walker: BuiltWalker,
    z0: ArrayLike | None = None,
    *,
    states: tuple[ArrayLike, ArrayLike] | None = None,
    slope: float = 0.0,
    steps: int = 1,
    torque: JointLaw | None = None,
    push_off: PushOff | None = None,
    friction: float | None = None,
    max_step_duration: float = 5.0,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step: float = np.inf,
    knee_flex_threshold: float = 1e-6,
    stop_near: tuple[ArrayLike, float] | None = None,
    parallel: bool | None = None,
) -> PhasedEnsembleResult:
    """Walk ``N`` initial states of one described walker for ``steps`` steps, compiled.

    Every walker is :func:`simulate_phased_compiled` (the same kernel, step by step from the
    previous post-impact state, so a walk can stop on arrival), all in one compiled call per
    thread; no samples or impact records are kept.

    Parameters
    ----------
    walker : BuiltWalker
        Any described walker with scalar parameters (a walker whose legs differ alternates
        with the walker after its leg swap, as :func:`simulate_phased_compiled`).
    z0 : array_like, shape (N, d) or (d,), optional
        Post-heel-strike section points (``PhasedWalker.section_names``; rad, rad/s).
    states : (array_like, array_like), optional
        ``(q0, q_dot0)``, each shape (N, n): full post-impact states instead of ``z0`` (stance
        foot on the ground and rolling, lockable joints locked with zero rate).
    slope : float
        Ground slope (rad).
    steps : int
        Largest number of heel strikes per walker.
    torque, push_off, friction, max_step_duration, rtol, atol, max_step, knee_flex_threshold
        As :func:`simulate_phased_compiled`.
    stop_near : (array_like of shape (d,), float), optional
        ``(z_target, tol)``: a walker stops (status completed) as soon as its post-impact
        section point is within ``tol`` of ``z_target`` (Euclidean norm), tested after whole
        periods (:attr:`~heelstrike.models.base.PlanarWalker.steps_per_period` steps: a stride
        walker's section after an odd step is the other walker's).
    parallel : bool, optional
        Split the walkers over ``os.cpu_count()`` threads (the kernel releases the GIL);
        default: parallel on the main thread, serial on other threads (e.g. Dask workers).

    Returns
    -------
    PhasedEnsembleResult

    Raises
    ------
    ValueError
        Neither or both of ``z0`` and ``states``, bad shapes, invalid initial states, or
        actuation the compiled backend does not support.
    ImpactInputError
        If a heel strike has no consistent contact assignment (as ``simulate_phased``).
    NotImplementedError
        If the walker declares no mirrors (no leg swap).
    """
    if steps < 1:
        raise ValueError("steps must be >= 1")
    if (z0 is None) == (states is None):
        raise ValueError("give exactly one of z0 (section points) and states=(q0, q_dot0)")
    check_compiled_actuation(walker, torque, push_off)
    w = PhasedWalker.from_built(walker)
    n = w.n_coordinates
    stance_locks, swing_locks, lockv = _locks(w)
    if states is not None:
        Q = np.array(np.atleast_2d(np.asarray(states[0], dtype=float)))
        QD = np.array(np.atleast_2d(np.asarray(states[1], dtype=float)))
        if Q.ndim != 2 or Q.shape[1] != n or QD.shape != Q.shape:
            raise ValueError(f"states must be two arrays of shape (N, {n})")
        _check_post_impact(w, Q, QD)
    else:
        Q, QD = section_states(w, z0)  # type: ignore[arg-type]
    if not (np.all(np.isfinite(Q)) and np.all(np.isfinite(QD))):
        raise ValueError("initial states must be finite")
    p, cfg = _configuration(w, slope, torque, push_off, friction, knee_flex_threshold)
    d = len(w.section_names)
    target = np.zeros(d)
    stop_tol = 0.0
    if stop_near is not None:
        target = np.asarray(stop_near[0], dtype=float).reshape(d).copy()
        stop_tol = float(stop_near[1])
    N = Q.shape[0]
    status = np.zeros(N, dtype=np.int64)
    taken = np.zeros(N, dtype=np.int64)
    Qf = np.zeros((N, n))
    QDf = np.zeros((N, n))
    Q = np.ascontiguousarray(Q)
    QD = np.ascontiguousarray(QD)
    common: tuple[Any, ...] = (
        p, cfg, Q, QD, int(steps),
        np.asarray(stance_locks, dtype=np.int64), np.asarray(swing_locks, dtype=np.int64),
        lockv, float(max_step_duration), float(rtol), float(atol), float(max_step),
        np.asarray(w._section_q, dtype=np.int64), np.asarray(w._section_v, dtype=np.int64),
        target, stop_tol,
    )
    outs = (status, taken, Qf, QDf)
    n_threads = min(os.cpu_count() or 1, N)
    if n_threads > 1 and use_parallel(parallel):
        kernels = _kernels(w, serial=False)
        # interleaved blocks balance falls (cheap) against long walks
        order = np.random.default_rng(0).permutation(N)
        Qs, QDs = np.ascontiguousarray(Q[order]), np.ascontiguousarray(QD[order])
        sub: list[Any] = [np.empty_like(a) for a in outs]
        bounds = np.linspace(0, N, n_threads + 1).astype(np.int64)

        def block(lo: int, hi: int) -> None:
            kernels.ensemble(*common[:2], Qs, QDs, *common[4:], lo, hi, *sub)

        from concurrent.futures import ThreadPoolExecutor  # only for threaded ensembles

        with ThreadPoolExecutor(n_threads) as pool:
            futures = [pool.submit(block, int(lo), int(hi))
                       for lo, hi in itertools.pairwise(bounds)]
            for f in futures:
                f.result()
        for a, b in zip(outs, sub, strict=True):
            a[order] = b
    else:
        _kernels(w).ensemble(*common, 0, N, *outs)
    if np.any(status == _NO_SWAP):
        raise NotImplementedError(
            f"walker {w.description.name!r}: {WalkStatus.NO_LEG_SWAP.message}"
        )
    if np.any(status == _NO_CONSISTENT_ASSIGNMENT):
        i = int(np.flatnonzero(status == _NO_CONSISTENT_ASSIGNMENT)[0])
        raise ImpactInputError(f"walker {i}: {WalkStatus.NO_CONSISTENT_ASSIGNMENT.message}")
    return PhasedEnsembleResult(
        status=status, steps=taken, q=Qf, q_dot=QDf, z=w.state_to_section(Qf, QDf),
        section_names=w.section_names,
    )


def _check_post_impact(walker: BuiltWalker, Q: FloatArray, QD: FloatArray) -> None:
    """Raise ``ValueError`` unless every row is a valid start (:func:`check_initial_state`)."""
    for i in range(Q.shape[0]):
        try:
            check_initial_state(walker, Q[i], QD[i], 1)
        except ValueError as exc:
            raise ValueError(f"state {i}: {exc}") from None
