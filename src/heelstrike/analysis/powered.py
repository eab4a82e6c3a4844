"""Periodic gaits of powered walkers on level ground, with their energy books.

On level ground a walker has no passive gait: the heel strike dissipates ``|W_col| = T_c``
per step (Font & Kövecses 2008, eq. 15) and the actuators must supply it. Applying the energy
theorem between two successive post-impact instants (eq. 14),

.. math:: \\Delta T + \\Delta U = W_{act} + W_{col}, \\qquad W_{col} = -T_c,

and on a periodic level gait ``Delta T = Delta U = 0`` so ``W_act = T_c``. The loss per metre
is ``eta = T_c / L_S`` (eq. 16) and the (mechanical) cost of transport
``W_act / (m_total g L_S)``, with ``W_act`` the *net* actuator work (a law's negative work, e.g.
a torso law braking, counts against its positive work; on a periodic level gait it is ``T_c``).

A gait is found by Newton's method on the Poincare map (section just after heel strike,
``z = (q3, q3_dot, q4_dot)`` for the compass gait) *augmented* with the actuation parameter
``a`` (push-off impulse, target energy or swing amplitude) as an extra unknown and the target
(speed or step length) as an extra equation:

.. math:: P(z, a) - z = 0, \\qquad g(z, a) - g^* = 0.

The search has two stages (:func:`find_powered_gait`). It first works on the map integrated
at :data:`SEARCH_TOLERANCE` (3-5x cheaper per step): seed gaits from a few map iterations at
the family's seed parameters, Newton with forward-difference Jacobians kept up to date by
Broyden's formula, and natural-parameter continuation in the target from the seed gait's own
speed or step length (tangent predictor; a step that Newton does not solve quickly is halved,
and where the halvings stall, at a fold of the family, the search stops and reports the range
its gaits spanned, with the end verified by solves to :data:`FAMILY_END_RESIDUAL`, since past
a fold the residual's nonzero minimum can pass the path's looser bar; :func:`_family_end`).
It then polishes the gait on the accurate map by chord iterations with the
search's Jacobian (about one step per three digits) and measures the multipliers there by
central differences.

Walkers without a level-ground seed gait
-----------------------------------------
A kneed walker's passive gaits exist only on slopes steeper than about 2 deg, and the push-off
seeds converge to nothing on level ground. Given its passive gaits (``passive_gait``), the
search then reaches level ground by a homotopy (:func:`_slope_homotopy`): from the passive gait
on a slope, a continuation in the slope lowers it to 0 with the target held and the push-off
free, raising the target where that continuation folds; the level gait it ends at starts the
continuation in the target as a seed gait would. The compass gait's push-off search has the
same fallback (:func:`passive_gait_finder`, which ``heelstrike powered`` and the cost study
pass): with a light hip (``mH = 4 kg``) it has no seed gait on level ground either.

McGeer's wheel (``R = l``)
--------------------------
With ``R = l`` both foot arcs are centred on the hip: the two contact points coincide, the
heel strike loses only the swing leg's rotation relative to the stance leg (``T_c = 0`` when
that is at rest at the strike, :data:`WHEEL_FAMILY`) and the trailing foot's post-impact
normal velocity is exactly zero, so :func:`heelstrike.dynamics.hybrid.simulate` reports
``trailing_foot_stays``. Here that outcome is accepted *only* for a wheel (``R = l``) and only if
the trailing foot's normal velocity is zero to round-off (it grazes: the "other" contact is the
same point); the legs are then relabelled by hand and the gait is flagged
:attr:`Gait.trailing_foot_grazes`. For ``R < l`` the outcome remains a failure.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, TypeVar

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike._units import UNITS
from heelstrike.analysis._gait_order import first_gait, is_stable, ordered_gaits
from heelstrike.analysis.gaits import Actuation, Gait
from heelstrike.analysis.heel_strike import loss_per_metre
from heelstrike.analysis.limit_cycle import leg_crossings
from heelstrike.analysis.newton import floquet_multipliers
from heelstrike.core.impact import kinetic_energy
from heelstrike.dynamics._aot import compile_seconds
from heelstrike.dynamics.actuation import (
    EnergyTracking,
    PushOff,
    SwingLegPD,
    default_gains,
    mechanical_energy,
)
from heelstrike.dynamics.hybrid import ImpactRecord, WalkResult, WalkStatus, simulate
from heelstrike.dynamics.single_support import TorqueLaw
from heelstrike.models._contact import grazes as foot_grazes
from heelstrike.models._contact import lift_velocity_scale
from heelstrike.models.base import PlanarWalker
from heelstrike.models.compass import CompassGait

Target = Literal["speed", "step_length"]
_T = TypeVar("_T")

__all__ = [
    "ACTUATIONS",
    "WHEEL_FAMILY",
    "ActuationFamily",
    "PoweredGaitNotFoundError",
    "SearchLimitError",
    "actuation_family",
    "books_gap",
    "check_model_actuation",
    "declared_posture_law",
    "energy_book_tables",
    "family_simulator",
    "find_model_powered_gait",
    "find_powered_gait",
    "impact_angle_for_step_length",
    "law_gains",
    "max_walking_speed",
    "passive_gait_finder",
    "powered_gaits",
    "powered_step",
    "preferred_gait",
]

#: Names of the built-in actuation models.
ACTUATIONS = ("pushoff", "hip-energy", "hip-pd")

class PoweredGaitNotFoundError(RuntimeError):
    """No periodic powered gait was found for the requested target (the message says why)."""


class SearchLimitError(PoweredGaitNotFoundError):
    """The search hit its time limit or its budget of simulated steps."""


#: Bound (s) on the wall-clock time of ``heelstrike powered`` (:func:`find_powered_gait`).
DEFAULT_TIME_LIMIT = 45.0


def max_walking_speed(walker: PlanarWalker) -> float:
    """Upper bound (m/s) of the mean speed of a walker rolling on feet of radius ``R < l``.

    At mid-stance the hip, at height ``l`` above the contact point, moves on a curve of radius
    ``l^2 / (l - R)`` (a point at ``l - R`` from the centre of a rolling arc of radius ``R``);
    keeping the stance foot on the ground needs a centripetal acceleration ``<= g``:
    ``v <= l sqrt(g / (l - R))`` (Froude number ``v^2 / (g l) <= l / (l - R)``; ``sqrt(g l)``
    for point feet). ``inf`` for McGeer's wheel (``R = l``). ``l`` and ``g`` are the walker's
    :attr:`~heelstrike.models.base.PlanarWalker.scale`, ``R`` its stance foot radius.
    """
    _, g, l = _scale(walker)
    R = float(np.asarray(walker.foot_radii[0]))
    if not (np.isfinite(l) and np.isfinite(g) and l > R):
        return float("inf")
    return float(l * np.sqrt(g / (l - R)))


@dataclass(frozen=True, kw_only=True)
class ActuationFamily:
    """A one-parameter family of actuations, ``a -> (torque law, push-off)``.

    Attributes
    ----------
    name : str
        ``"pushoff"``, ``"hip-energy"``, ``"hip-pd"`` or a user name.
    parameter_name, parameter_unit : str
        What the free parameter ``a`` is (e.g. ``"impulse"``, ``"N s"``).
    parameter_meaning : str
        One phrase saying what the parameter means physically (for reports).
    build : callable ``(walker, a) -> (torque, push_off)``
        The actuation for a parameter value; either may be None.
    seed : callable ``(walker) -> tuple of float``
        Parameter values, tried in order, that may let the walker walk (to find a first gait).
    lower : float
        Smallest admissible parameter value (e.g. 0 for an impulse magnitude).
    torque_joint : str
        The joint the family's torque law acts across (``"hip"``; ``"torso"`` for a described
        walker's posture law): labels the torque's work in the energy books.
    """

    name: str
    parameter_name: str
    parameter_unit: str
    build: Callable[[PlanarWalker, float], tuple[TorqueLaw | None, PushOff | None]]
    seed: Callable[[PlanarWalker], tuple[float, ...]]
    lower: float = -np.inf
    torque_joint: str = "hip"
    parameter_meaning: str = ""


def family_simulator(
    walker: PlanarWalker, family: ActuationFamily, backend: str | None
) -> Callable[..., WalkResult] | None:
    """The step simulator of :func:`find_powered_gait` for an actuation family on a backend.

    Parameters
    ----------
    walker : PlanarWalker
    family : ActuationFamily
    backend : {"compiled", "scipy"} or None
        ``"compiled"``: :func:`heelstrike.dynamics.simulate` on the compiled backend, checked
        for the family's laws (built at its first seed value). ``"scipy"``: None, i.e.
        :func:`~heelstrike.dynamics.hybrid.simulate` (the reference). None: compiled if its
        kernels walk this walker with the family's laws (push-off, the compass hip laws, a
        declared posture law; not McGeer's wheel), else the reference.

    Returns
    -------
    callable or None
        For the ``simulator`` argument of :func:`find_powered_gait`.

    Raises
    ------
    ValueError
        ``backend="compiled"`` for laws its kernels do not evaluate, or an unknown backend.
    """
    from heelstrike.dynamics.backends import simulator

    if backend == "scipy":
        return None
    if backend not in (None, "compiled"):
        raise ValueError(f"backend must be 'compiled' or 'scipy', got {backend!r}")
    torque, push_off = family.build(walker, family.seed(walker)[0])
    try:
        return simulator(walker, "compiled", torque=torque, push_off=push_off)
    except ValueError:
        if backend is None:
            return None
        raise


_SEED_SECTIONS = (
    (-0.25, 1.1, -0.45),
    (-0.2, 0.9, -0.3),
    (-0.3, 1.2, -0.6),
    (-0.15, 0.8, -0.2),
    (-0.35, 1.4, -0.8),
)


def _other_gains(family: ActuationFamily, before: str, after: str) -> str:
    """``"other gains"`` (between ``before`` and ``after``) for a family with a torque law
    whose gains could change its gaits (the hip laws, a declared posture law); "" for the
    push-off alone, which has none."""
    has_law = family.name != "pushoff" or family.torque_joint != "hip"
    return f"{before}other gains{after}" if has_law else ""


def _scaled_seed_sections(walker: PlanarWalker) -> tuple[tuple[float, ...], ...]:
    """:data:`_SEED_SECTIONS` (chosen for ``g = 9.81 m/s^2``, ``l = 1 m``) on this walker's
    Poincare section (:meth:`~heelstrike.models.base.PlanarWalker.section_point`: further
    links upright): angles as they are, rates scaled by the walker's ``sqrt(g / l)`` (its
    inverse time scale), so a walker on the Moon or with long legs starts near its own gaits;
    unchanged for the reference walker (a factor of exactly 1)."""
    _, g, l = _scale(walker)
    k = float(np.sqrt((g / l) / 9.81))
    return tuple(tuple(float(v) for v in walker.section_point(q, k * qd3, k * qd4))
                 for q, qd3, qd4 in _SEED_SECTIONS)


def _scale(walker: PlanarWalker) -> tuple[float, float, float]:
    """``(m_total, g, l)`` of any walker: its :attr:`~heelstrike.models.base.PlanarWalker.scale`."""
    s = walker.scale
    return float(s.total_mass), float(s.gravity), float(s.leg_length)


def _gains(walker: PlanarWalker, **given: float | None) -> dict[str, float]:
    """The gains named in ``given``: the value given, else the walker's default
    (:func:`~heelstrike.dynamics.actuation.default_gains`)."""
    defaults = default_gains(walker.scale)
    return {k: defaults[k] if v is None else float(v) for k, v in given.items()}


def actuation_family(
    name: str,
    *,
    gain: float | None = None,
    kp: float | None = None,
    kd: float | None = None,
    max_torque: float | None = None,
) -> ActuationFamily:
    """One of the built-in actuation models.

    The defaults of the gains are those of :mod:`heelstrike.dynamics.actuation` (their physical
    reasons are given there) for the paper's walker, and the same dimensionless gains for
    another (:func:`~heelstrike.dynamics.actuation.default_gains`: torques scaled by its
    ``m g l``, times by its ``sqrt(l / g)``); with them ``find_powered_gait(walker,
    actuation=name, speed=0.5)`` succeeds for the paper's walker with ``R = 0`` and
    ``R = 0.3`` m. The hip laws act across the walker's
    :attr:`~heelstrike.models.base.PlanarWalker.hip_joint`.

    Parameters
    ----------
    name : {"pushoff", "hip-energy", "hip-pd"}
        ``pushoff``: :class:`~heelstrike.dynamics.actuation.PushOff`, parameter the impulse
        ``p`` (N s), passive hip. ``hip-energy``:
        :class:`~heelstrike.dynamics.actuation.EnergyTracking`, parameter the target energy
        ``E_ref`` (J, ``T + V`` with ``V`` zero at ground level). ``hip-pd``:
        :class:`~heelstrike.dynamics.actuation.SwingLegPD`, parameter the amplitude ``A`` (rad).
    gain : float, optional
        Energy-tracking gain (hip-energy), s/rad.
    kp, kd : float, optional
        PD gains (hip-pd), N m/rad and N m s/rad.
    max_torque : float, optional
        Hip torque limit (N m) of the hip laws.

    Notes
    -----
    Seeds (parameter values whose attractor or near-periodic motion starts the search):
    push-off impulses of 0.03-0.08 ``m_total sqrt(g l)``; target energies a little above the
    energy of the first seed section, its rates scaled by the walker's ``sqrt(g / l)``
    (0.1-1 % of ``m_total g l``: the law must inject a collision loss of that order per
    step); PD amplitudes of 0.1-0.25 rad, the half inter-leg
    angle at heel strike of slow to moderate steps (with the default stiffness the set point,
    not gravity, places the swing foot). The search then continues in the target from
    whichever seed gait it finds first.
    """
    if name == "pushoff":
        return ActuationFamily(
            name=name,
            parameter_name="impulse",
            parameter_unit="N s",
            parameter_meaning="push-off impulse of the trailing foot just before heel strike",
            build=lambda w, a: (None, PushOff(impulse=max(float(a), 0.0))),
            seed=lambda w: tuple(
                c * _scale(w)[0] * float(np.sqrt(_scale(w)[1] * _scale(w)[2]))
                for c in (0.05, 0.03, 0.08)
            ),
            lower=0.0,
        )
    if name == "hip-energy":

        def energy_law(w: PlanarWalker, energy: float) -> EnergyTracking:
            g = _gains(w, gain=gain, max_torque=max_torque)
            return EnergyTracking(walker=w, energy=energy, gain=g["gain"],
                                  max_torque=g["max_torque"])

        def seed_energy(w: PlanarWalker) -> tuple[float, ...]:
            q, qd = w.section_to_state(np.asarray(_scaled_seed_sections(w)[0]))
            m, g, l = _scale(w)
            E = float(mechanical_energy(w, q, qd))
            return tuple(E + c * m * g * l for c in (0.005, 0.0025, 0.01, 0.001))

        return ActuationFamily(
            name=name,
            parameter_name="energy",
            parameter_unit="J",
            parameter_meaning="the hip law's target energy E_ref = T + V, V = 0 at the ground",
            build=lambda w, a: (energy_law(w, float(a)), None),
            seed=seed_energy,
        )
    if name == "hip-pd":

        def pd_law(w: PlanarWalker, amplitude: float) -> SwingLegPD:
            g = _gains(w, kp=kp, kd=kd, max_torque=max_torque)
            return SwingLegPD(amplitude=amplitude, kp=g["kp"], kd=g["kd"],
                              max_torque=g["max_torque"], joint=w.hip_joint)

        return ActuationFamily(
            name=name,
            parameter_name="amplitude",
            parameter_unit="rad",
            parameter_meaning="the hip set point's half-angle A, target hip angle -2 A",
            build=lambda w, a: (pd_law(w, float(a)), None),
            seed=lambda w: (0.15, 0.2, 0.1, 0.25),  # rad
        )
    raise ValueError(f"unknown actuation {name!r}: choose from {', '.join(ACTUATIONS)}")


@dataclass(frozen=True, kw_only=True)
class PoweredStep(ResultDictMixin):
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


def powered_step(
    walker: PlanarWalker,
    z: ArrayLike,
    torque: TorqueLaw | None,
    push_off: PushOff | None,
    *,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    max_step_duration: float = 4.0,
    simulator: Callable[..., WalkResult] | None = None,
    slope: float = 0.0,
) -> PoweredStep:
    """Simulate one step on level ground (or on ``slope``, rad) from the post-impact section
    point ``z``.

    Handles McGeer's wheel (module docstring): a ``trailing_foot_stays`` outcome with a zero
    (to round-off) trailing-foot velocity is accepted only when ``R = l``. ``simulator`` is a
    step simulator with :func:`~heelstrike.dynamics.hybrid.simulate`'s signature (None: that
    function), e.g. :func:`~heelstrike.dynamics.phased.simulate_phased` for described walkers.

    Raises
    ------
    ValueError
        For a walker whose legs differ
        (:attr:`~heelstrike.models.base.PlanarWalker.steps_per_period` 2): its powered gait
        would be a stride of two differently actuated steps, which this step map does not
        model.
    """
    if walker.steps_per_period != 1:
        raise ValueError(
            "powered gaits of a walker whose legs differ (steps_per_period 2) are not "
            "supported: the powered map is one step of one walker; its passive gaits on a "
            "slope are (heelstrike gait --model FILE)")
    z_ = np.asarray(z, dtype=float)
    q, qd = walker.section_to_state(z_)
    E0 = float(mechanical_energy(walker, q, qd))
    walk = (simulate if simulator is None else simulator)(
        walker, q, qd, slope=slope, steps=1, torque=torque, push_off=push_off,
        rtol=rtol, atol=atol, max_step_duration=max_step_duration,
    )
    rec = walk.impacts[0] if walk.impacts else None
    grazes = False
    if walk.ok:
        qf, qdf = walk.final_q, walk.final_q_dot
    elif walk.status is WalkStatus.TRAILING_FOOT_STAYS and rec is not None and walker.is_wheel:
        scale = lift_velocity_scale(_scale(walker)[2], np.asarray(rec.q_dot_minus[2:], float))
        if not foot_grazes(rec.trailing_normal_velocity, scale):
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


#: Integrator tolerance (``rtol = atol``) of the search stage: the seed, Newton from the seed and
#: the continuation to the target run on this cheaper map (a step costs 3-5x less than at
#: ``1e-10``); its fixed points are within ~1e-7 of the accurate ones, which the final
#: polishing at the requested tolerance then removes (see :func:`find_powered_gait`).
SEARCH_TOLERANCE = 1e-7

#: Residual at which the search stage hands over to the polishing stage: ~100x the coarse
#: map's integration noise, so that Newton is not asked for digits the coarse map lacks (the
#: polishing gains ~3 digits per accurate step, see :func:`_polish`).
SEARCH_RESIDUAL = 1e-5

#: Residual of the intermediate gaits of the search (the first gait, continuation points):
#: they only start the next Newton solve, whose basin is far wider than this.
PATH_RESIDUAL = 1e-4

#: Newton iterations per continuation step: a step that needs more is halved instead (cheaper
#: than damped iterations far from the solution).
CONTINUATION_ITERATIONS = 6

#: Smallest line-search step of a continuation step's Newton solve: a step that needs heavier
#: damping is halved in the target instead.
CONTINUATION_MIN_STEP = 0.125

#: Largest residual ratio of an accepted Newton iteration in a continuation step: from a
#: tangent prediction Newton converges fast; slow progress means a fold or a too long step.
CONTINUATION_MIN_RATE = 0.5

#: Relative resolution (of the target) at which a stalled continuation stops and reports where
#: the family of gaits ends: near a fold (a largest or smallest speed the actuation reaches)
#: every halving costs failed Newton solves, so the end is located to 0.5 % and not better.
CONTINUATION_RESOLUTION = 5e-3

#: Relative finite-difference step of the search-stage Jacobians: ``sqrt`` of the coarse map's
#: noise, which balances truncation (``~h``) against noise (``~1e-7 / h``).
SEARCH_FD_STEP = 3e-4

#: Map iterations per seed candidate (see :func:`_seeds`).
SEED_STEPS = 12

#: Relative offset (of each unknown, times ``max(1, |x_i|)``) of the starts of the deflated
#: search for another gait near the gaits found (:func:`_deflated_gaits`): from 1 % offsets
#: the other gaits of issue 32 were reached (a stable 1.356 J gait beside an unstable 1.370 J
#: one at R = 0.15 m, L = 0.6 m; an unstable gait 21 % cheaper beside the stable one of a
#: walker with legs of 0.1 kg at 0.5 m/s), from 3 % offsets only one of them, from 10 % none.
DEFLATION_OFFSET = 0.01

#: Newton iterations of each deflated start (:func:`_deflated_gaits`): the starts that reached
#: the gaits of issue 32 converged in 8; a start that does not converge costs ``2 n + 1``
#: steps an iteration (most of the search's added cost: the default compass ``study cost``
#: took 23 s with the deflated search, 13 s without, on a shared 2-core machine).
DEFLATION_ITERATIONS = 10

#: Slopes (rad) of the passive gaits the slope homotopy starts from, tried in order (about 2.9,
#: 4.0 and 2.0 deg; see :func:`_slope_homotopy`): a kneed walker's passive gaits exist only on
#: slopes steeper than about 2 deg.
HOMOTOPY_SLOPES = (0.05, 0.07, 0.035)

#: Relative raise of the target (speed or step length) where the homotopy's continuation in the
#: slope folds.
HOMOTOPY_RAISE = 0.1

#: Largest number of raises of the target during the homotopy.
HOMOTOPY_RAISES = 10

#: Slope (rad) by which the homotopy backs off from a fold of its continuation in the slope
#: before it raises the target (at the fold itself the augmented Jacobian is singular).
HOMOTOPY_BACKOFF = 0.005

#: Slope step (rad) below which a stalled continuation in the slope stops: where the fold is
#: located to.
HOMOTOPY_SLOPE_RESOLUTION = 2e-4

#: Relative resolution (of the target) to which a failed search locates where its family of
#: gaits ends (:func:`_family_end`).
FAMILY_END_RESOLUTION = 1e-3

#: Residual (on the search map) a gait must reach to count as verified in :func:`_family_end`:
#: 10x the search map's integration noise. Past a fold the minimum of ``|F|`` grows from zero
#: in proportion to the distance, so a looser bar would verify points past the fold.
FAMILY_END_RESIDUAL = 1e-6

#: Doublings of the distance (from :data:`CONTINUATION_RESOLUTION` / 2 of the target) at which
#: :func:`_family_end` looks for a verified gait on either side of a failed target.
FAMILY_END_DOUBLINGS = 6

#: A largest multiplier within this of ``+1`` at the end of a family marks a fold (saddle-node:
#: the family turns back there, and the minimum of ``|F|`` past it is not zero), together with
#: :data:`FOLD_TANGENT_TOLERANCE`.
FOLD_MULTIPLIER_TOLERANCE = 0.05

#: At a fold in the target the family's tangent ``t`` (the null vector of ``[DP - I, dP/da]``)
#: is orthogonal to the target's gradient ``g``: ``abs(g @ t) / norm(g)`` below this (at the
#: verified end, within :data:`FAMILY_END_RESOLUTION` of the fold) marks one. The torso
#: walker's fold gives 0.014; the push-off gaits' slow end (0.094, a multiplier near 1 but no
#: fold: QA sweep 5) and R = 0.9's fast end (0.52, the impact angle reaching 90 deg) are no
#: folds.
FOLD_TANGENT_TOLERANCE = 0.04

#: Largest relative disagreement of a gait's energy books, ``max(|ΔE|, |W - T_c - ΔE|)`` over
#: ``max(|W|, |T_c|)`` (``ΔE``: change of ``T + V`` over the step, zero for a period-one gait on
#: level ground), before :func:`_books_refined` converges the gait again at tolerances scaled
#: down in proportion. Gaits of ordinary size meet it at the default tolerances; very slow ones
#: do not: at R = 0.9 m and 0.02 m/s (W = 4.7e-9 J against T = 4e-3 J, a largest multiplier of
#: 0.999997) the absolute tolerances (residual 1e-9, integration 1e-10) left ``ΔE`` at 0.6 % of
#: W and the two backends 1.8e-3 apart in W (QA sweep 5).
BOOKS_RTOL = 1e-6

#: A report notes a gait whose books (:func:`books_gap`) still disagree by more than this.
BOOKS_NOTE = 1e-4

#: Smallest size (J) :func:`books_gap` measures a gap against: the integrator's round-off of
#: a walker's energy (a gait needing no work has books of 1e-13 J, all round-off).
BOOKS_FLOOR = 1e-8

#: What a powered gait of McGeer's wheel (``R = l``) is, said by ``powered`` and recorded as
#: the cost study's failure at ``R = l`` (QA sweep 12: ``powered --radius 1`` reported one
#: gait's 0.0068 J per step as the wheel's cost, and "stable, barely").
WHEEL_FAMILY = (
    "R = l is McGeer's wheel: its gaits at one target form a neutral family (a Floquet "
    "multiplier of 1: their stability is undecided), which includes gaits that lose nothing "
    "(T_c = 0 when the swing leg is at rest relative to the stance leg at the strike: no "
    "actuation needed); the gait shown is the one needing the least work")

#: Smallest factor by which :func:`_books_refined` scales the tolerances down, and the smallest
#: integration tolerance it asks for (round-off bounds what a tighter one could give).
BOOKS_MIN_FACTOR, BOOKS_MIN_TOLERANCE = 1e-5, 1e-13


@dataclass(frozen=True, kw_only=True)
class _Problem:
    walker: PlanarWalker
    family: ActuationFamily
    target: Target
    rtol: float
    atol: float
    budget: int = 2000
    _count: list[int] = field(default_factory=lambda: [0], repr=False)
    deadline: float = float("inf")
    time_limit: float = float("inf")
    compiled_before: float = 0.0
    bar: Any = None
    simulator: Callable[..., WalkResult] | None = None
    seed_sections: tuple[tuple[float, ...], ...] = _SEED_SECTIONS
    slope: float = 0.0
    passive_gait: Callable[[float], ArrayLike] | None = None

    def at_tolerance(self, tol: float) -> _Problem:
        """The same problem integrated at ``rtol = atol = tol``, sharing budget and clock."""
        return self.replace(rtol=tol, atol=tol)

    def replace(self, **changes: Any) -> _Problem:
        """The same problem with some fields changed, sharing budget and clock."""
        return dataclasses.replace(self, **changes)  # _count: the same list, shared

    def step(self, x: FloatArray) -> PoweredStep:
        self._count[0] += 1
        if self.bar is not None:
            self.bar.update(1)
        if self._count[0] > self.budget:
            raise SearchLimitError(
                f"gave up after {self.budget} simulated steps (evaluation budget)"
            )
        compiling = compile_seconds() - self.compiled_before  # first-run kernel builds
        if time.monotonic() - compiling > self.deadline:
            spent = f", not counting {compiling:.0f} s compiling kernels" if compiling >= 1 else ""
            raise SearchLimitError(
                f"gave up after {self.time_limit:g} s (time limit{spent}; "
                f"{self._count[0] - 1} simulated steps)"
            )
        torque, push = self.family.build(self.walker, float(x[-1]))
        return powered_step(self.walker, x[:-1], torque, push, rtol=self.rtol, atol=self.atol,
                            simulator=self.simulator, slope=self.slope)

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

    def jacobian(
        self, x: FloatArray, value: float, h: float, F0: FloatArray | None = None
    ) -> FloatArray:
        """Finite-difference Jacobian of :meth:`residual`: central, or forward from ``F0``."""
        n = x.size
        J = np.empty((n, n))
        for i in range(n):
            dx = np.zeros(n)
            dx[i] = h * max(1.0, abs(x[i]))
            if F0 is None:
                J[:, i] = (self.residual(x + dx, value) - self.residual(x - dx, value)) / (
                    2 * dx[i])
            else:
                J[:, i] = (self.residual(x + dx, value) - F0) / dx[i]
        return J


def _newton(
    prob: _Problem, x0: FloatArray, value: float, tol: float, max_iter: int, h: float,
    *, forward: bool = False, accept: float | None = None, min_step: float = 1e-3,
    min_rate: float = 1.0,
) -> tuple[FloatArray, float, int, FloatArray]:
    """Damped Newton on the augmented map (the one engine,
    :func:`~heelstrike.analysis.newton.newton_solve`); returns ``(x, residual, iterations,
    jacobian)``.

    ``forward``: forward-difference Jacobians updated by Broyden's rank-one formula between
    recomputations (about ``1 + n/k`` steps per iteration instead of ``2n + 1``; used by the
    search stage). If the line search fails the Jacobian is recomputed once before giving up.
    A stall with the residual below ``accept`` (default ``10 tol``, the integrator's noise
    floor) returns the iterate.
    ``min_step`` is the smallest line-search step (a fraction of the Newton step); an accepted
    step must also reduce the residual at least ``1 / min_rate``-fold (else: stalled). The
    actuation parameter (the last unknown) is kept at or above the family's lower bound.
    """
    from heelstrike.analysis.newton import newton_solve

    lower = prob.family.lower

    def residual(X: FloatArray) -> FloatArray:
        return np.stack([prob.residual(x, value) for x in X])

    def project(X: FloatArray) -> FloatArray:
        Y = X.copy()
        Y[:, -1] = np.maximum(Y[:, -1], lower)
        return Y

    sol = newton_solve(
        residual, x0, tol=tol, max_iter=max_iter, fd_step=h,
        jacobian="broyden" if forward else "central", jacobian_at_root=False,
        line_search="decrease", min_step=min_step, accept=accept, min_rate=min_rate,
        project=project,
    )
    if not sol.converged[0]:
        fam = prob.family
        labels = (*prob.walker.section_labels, (fam.parameter_name, fam.parameter_unit))
        raise PoweredGaitNotFoundError(sol.message(0, labels))
    return sol.x[0], float(sol.residual_norm[0]), int(sol.iterations[0]), sol.jacobian[0]


def _polish(
    prob: _Problem, x0: FloatArray, value: float, tol: float, J0: FloatArray, max_iter: int,
    h: float,
) -> tuple[FloatArray, float, int]:
    """Converge a search-stage gait on the accurate map: chord iterations, then Newton.

    The search-stage Jacobian ``J0`` is close to the accurate one, so the chord iteration
    ``x <- x - J^-1 F(x)`` (:func:`~heelstrike.analysis.newton.newton_solve` with
    ``jacobian="chord"``) gains digits at one simulated step per iteration. If it contracts by
    less than 5x per step, ``J`` is replaced once by a forward-difference Jacobian of the
    accurate map (``n`` steps, relative step ``sqrt(rtol)``, which balances truncation and
    integration noise); if that fails too, damped Newton with central differences takes over.
    """
    from heelstrike.analysis.newton import newton_solve
    from heelstrike.status import SolveStatus

    def residual(X: FloatArray) -> FloatArray:
        return np.stack([prob.residual(x, value) for x in X])

    sol = newton_solve(
        residual, x0, tol=tol, max_iter=max_iter, fd_step=max(h, float(np.sqrt(prob.rtol))),
        jacobian="chord", jacobian0=J0[None], contraction=0.2, jacobian_at_root=False,
    )
    if sol.status[0] is SolveStatus.STEP_FAILED and sol.iterations[0] == 1:
        raise PoweredGaitNotFoundError("the walker fails to take a step from the search's gait")
    if sol.converged[0]:
        return sol.x[0], float(sol.residual_norm[0]), int(sol.iterations[0])
    x, res, it, _ = _newton(prob, sol.x[0], value, tol, max_iter, h)
    return x, res, it


def _seeds(prob: _Problem) -> Iterator[FloatArray]:
    """First gaits (section point and parameter) to start Newton from, best first.

    For each seed parameter and seed section the map is iterated a few steps: a stable gait
    attracts, and even an unstable one's neighbourhood is approached while transients decay.
    A candidate is yielded once successive section points agree to ``1e-4`` (well inside
    Newton's basin) or after :data:`SEED_STEPS` steps; the candidate is the most nearly
    periodic section point met, also when the walker falls later (it then passed near an
    unstable gait, which Newton finds); a walker that falls at its first step gives none.
    Iterating longer
    (the earlier 40 steps per candidate) bought little: the cost is in the steps, and Newton
    converges from ~1e-2 as well as from ~1e-4.
    """
    for a in prob.family.seed(prob.walker):
        for z0 in prob.seed_sections[:3]:
            z = np.asarray(z0, dtype=float)
            best: tuple[float, FloatArray] | None = None
            for _ in range(SEED_STEPS):
                st = prob.step(np.append(z, a))
                if not st.ok:
                    break
                err = float(np.linalg.norm(st.z_next - z))
                z = st.z_next
                if best is None or err < best[0]:
                    best = (err, np.append(z, a))
                if err < 1e-4:
                    break
            if best is not None:
                yield best[1]


def _constant(value: _T) -> Callable[[float], _T]:
    """The function of ``lam`` that returns ``value``."""
    return lambda _lam: value


def _continue_scalar(
    problem_at: Callable[[float], _Problem], value_at: Callable[[float], float], x: FloatArray,
    J: FloatArray, start: float, end: float, *, first_step: float, max_step: float,
    resolution: float, tol: float, h: float,
) -> tuple[list[tuple[float, FloatArray, FloatArray]], int, Exception | None]:
    """Natural-parameter continuation of a gait in a scalar ``lam`` from ``start`` to ``end``.

    The problem and the target value are functions of ``lam`` (the slope of the ground, rad,
    or the target itself). Secant predictor from the last two gaits, Newton as in the
    target continuation of :func:`_find` (a fresh forward-difference Jacobian, Broyden
    updates; the last gait's Broyden Jacobian made Newton stall near folds); a step Newton
    does not solve quickly is halved, and below ``resolution`` the continuation stops (a fold
    of the family, or a step the walker cannot take). The steps are the one continuation's
    (``heelstrike.analysis._continuation.follow``): the first ``first_step``, each accepted one
    doubling the next up to ``max_step``.

    Returns
    -------
    path : list of (float, ndarray, ndarray)
        The gaits reached, in order, from the start ``(start, x, J)``: ``(lam, x, J)`` with
        ``x`` (shape (d + 1,), section point and parameter) and its Jacobian (shape
        (d + 1, d + 1)); the last one's ``lam`` is ``end`` exactly if the continuation got
        there.
    iterations : int
        Newton iterations.
    error : Exception or None
        Why the last failed step failed (None if none failed).
    """
    from heelstrike.analysis._continuation import Point, follow

    lower = problem_at(start).family.lower
    state: dict[str, Any] = {"its": 0, "error": None}

    class _StepFailed(Exception):
        """A sub-step Newton did not solve (a :class:`SearchLimitError` propagates)."""

    def correct(lam: float, x_pred: FloatArray, _: int) -> tuple[Any, FloatArray, int, float]:
        try:
            x_new, _res, it, J_new = _newton(
                problem_at(lam), x_pred, value_at(lam), tol, CONTINUATION_ITERATIONS, h,
                forward=True, accept=10.0 * tol, min_step=CONTINUATION_MIN_STEP,
                min_rate=CONTINUATION_MIN_RATE)
        except SearchLimitError:
            raise
        except PoweredGaitNotFoundError as exc:
            state["error"] = exc
            raise _StepFailed from exc
        state["its"] += it
        return J_new, x_new, it, float("nan")

    def bound(x_pred: FloatArray) -> FloatArray:
        out = x_pred.copy()
        out[-1] = max(out[-1], lower)
        return out

    # every accepted step doubles the next (fast_iter=None), no jump test: the augmented
    # problem's unknowns mix section coordinates and the parameter
    _, points = follow(correct, Point(value=start, z=x, mnr=float("nan"), gait=J), [end],
                       max_step, h_min=resolution, first_step=first_step, fast_iter=None,
                       slow_iter=None, max_jump=float("inf"), bound=bound,
                       failures=(_StepFailed,), reach_tol=0.0)
    return [(p.value, p.z, p.gait) for p in points], int(state["its"]), state["error"]


def _slope_homotopy(
    search: _Problem, target: Target, unit: str, tol: float, h: float, no_seed: str,
) -> tuple[tuple[FloatArray, float, int, FloatArray], str]:
    """A first level-ground gait from a passive gait on a slope (no seed gait on level ground).

    Walkers whose passive gaits exist only on slopes steeper than some angle (a kneed walker's
    end at a fold near 2 deg) have no seed gait on level ground for :func:`_find` to start
    from. A homotopy connects the two: from the passive gait (zero push-off) found by
    ``search.passive_gait`` on one of :data:`HOMOTOPY_SLOPES`, a natural-parameter
    continuation in the slope (:func:`_continue_scalar`) lowers the slope to 0 with the
    target (speed or step length) held at the passive gait's value and the push-off impulse
    free: the push-off takes over the energy input that the slope supplied. Where that
    continuation folds (a lowest slope at this target), the target is raised by
    :data:`HOMOTOPY_RAISE` at the fold's slope (a continuation in the target) and the slope
    continuation resumes, at most :data:`HOMOTOPY_RAISES` times.

    Returns
    -------
    first : tuple
        ``(x, value, iterations, J)``: the level-ground gait, its target value, Newton
        iterations and Jacobian, for :func:`_find`'s continuation to the requested target.
    via : str
        How it was reached (appended to the search's failure messages).

    Raises
    ------
    PoweredGaitNotFoundError
        No passive gait on any of the slopes, or no homotopy reached level ground; the
        message lists, per slope, where the homotopy stopped (slope in deg, target).
    """
    from heelstrike.analysis.limit_cycle import GaitNotFoundError

    assert search.passive_gait is not None
    name, pname = search.family.name, search.family.parameter_name
    tried: list[str] = []
    for s0 in HOMOTOPY_SLOPES:
        deg0 = float(np.rad2deg(s0))
        state = f"looking for the passive gait on a {deg0:.3g} deg slope"
        try:
            try:
                z0 = np.asarray(search.passive_gait(s0), dtype=float)
            except SearchLimitError:
                raise
            except (GaitNotFoundError, PoweredGaitNotFoundError) as exc:
                tried.append(f"no passive gait on a {deg0:.3g} deg slope ({exc})")
                continue
            start = search.replace(slope=s0)
            x = np.append(z0, max(0.0, search.family.lower))
            st = start.step(x)
            if not st.ok:
                tried.append(f"the passive gait on a {deg0:.3g} deg slope does not step")
                continue
            v0 = v = start.measure(st)
            try:
                x, _, its, J = _newton(start, x, v, tol, 20, h, forward=True, accept=10.0 * tol)
            except PoweredGaitNotFoundError as exc:
                if isinstance(exc, SearchLimitError):
                    raise
                tried.append(f"the passive gait on a {deg0:.3g} deg slope is not a gait of the "
                             f"augmented map ({exc})")
                continue
            s, raises = s0, 0
            while True:
                state = (f"lowering the slope from {deg0:.3g} deg (had reached "
                         f"{np.rad2deg(s):.3g} deg, {target} {v:.4g} {unit})")
                path, it, err = _continue_scalar(
                    lambda lam: search.replace(slope=lam), _constant(v), x, J, s, 0.0,
                    first_step=s0 / 8.0, max_step=s0 / 4.0,
                    resolution=HOMOTOPY_SLOPE_RESOLUTION, tol=tol, h=h)
                its += it
                s_fold, x, J = path[-1]
                if s_fold == 0.0:
                    raised = (f", the {target} raised from {v0:.4g} to {v:.4g} {unit} at "
                              f"{raises} fold(s) of the slope continuation" if raises else "")
                    via = (f" [no seed gait on level ground; these gaits were reached by a "
                           f"homotopy from the passive gait on a {deg0:.3g} deg slope "
                           f"({target} {v0:.4g} {unit}), the slope lowered to 0 while the "
                           f"push-off {pname} took over{raised}]")
                    return (x, v, its, J), via
                at = f"{np.rad2deg(s_fold):.3g} deg"
                lowest = (f"from the passive gait on a {deg0:.3g} deg slope ({target} "
                          f"{v0:.4g} {unit}) the slope was lowered only to {at} (at {target} "
                          f"{v:.4g} {unit}, {pname} {x[-1]:.4g} {search.family.parameter_unit}"
                          f"; {err})")
                if raises == HOMOTOPY_RAISES:
                    tried.append(f"{lowest} after {raises} raises of the {target}")
                    break
                # back off from the fold (where the Jacobian is singular) before raising
                above = [p for p in path if p[0] >= s_fold + HOMOTOPY_BACKOFF]
                s, x, J = above[-1] if above else path[0]
                state = (f"raising the {target} from {v:.4g} {unit} at {np.rad2deg(s):.3g} "
                         f"deg, above the fold near {at} of the homotopy from {deg0:.3g} deg")
                path, it, err2 = _continue_scalar(
                    _constant(search.replace(slope=s)), lambda lam: lam, x, J, v,
                    v * (1.0 + HOMOTOPY_RAISE), first_step=HOMOTOPY_RAISE * v,
                    max_step=HOMOTOPY_RAISE * v, resolution=CONTINUATION_RESOLUTION * v,
                    tol=tol, h=h)
                its += it
                v_new, x, J = path[-1]
                if v_new == v:
                    tried.append(f"{lowest}, and the {target} could not be raised at "
                                 f"{np.rad2deg(s):.3g} deg ({err2})")
                    break
                v, raises = v_new, raises + 1
        except SearchLimitError as exc:
            raise SearchLimitError(
                f"{exc} while {state}, on the homotopy to level ground (no {name} seed gait on "
                f"level ground: {no_seed}); the target was never approached"
            ) from exc
    raise PoweredGaitNotFoundError(
        f"no periodic {name} gait found on level ground: {no_seed}; and no homotopy from a "
        f"passive gait on a slope reached level ground: {'; '.join(tried)}"
    )


def _family_end(
    search: _Problem, accurate: _Problem, x: FloatArray, value: float, tol: float, h: float,
    max_iter: int, fd_step: float,
) -> tuple[float, FloatArray, complex, float] | None:
    """Where the family of gaits near a failed target ``value`` ends, verified.

    A continuation step or the final solve is accepted at a residual of up to
    ``10 *`` :data:`PATH_RESIDUAL`, which past a fold (where no gait exists) is met by the
    minimum of ``|F|`` itself: the ends the search reports could then lie beyond the gaits
    that exist. Here only solves to ``tol`` on the search map count (no stall accepted above
    it). From ``x`` (the search's point at ``value``, shape (d + 1,)) a verified gait is
    looked for at ``value -+ delta``, ``delta`` doubling from ``CONTINUATION_RESOLUTION / 2``
    of the target (:data:`FAMILY_END_DOUBLINGS` times), then the border between verified
    targets and ``value`` is bisected to :data:`FAMILY_END_RESOLUTION` of the target.

    Parameters
    ----------
    search, accurate : _Problem
        The search-stage problem (solves) and the accurate one (multipliers).
    x : ndarray, shape (d + 1,)
        Section point and parameter the search failed from.
    value : float
        The target that failed (m/s or m).
    tol : float
        Residual of a verified gait (:data:`FAMILY_END_RESIDUAL`).
    h, fd_step : float
        Relative finite-difference steps of the search's Jacobians and of ``DP``.
    max_iter : int
        Newton iterations per solve.

    Returns
    -------
    (end, x_end, multiplier, turning) or None
        The verified target nearest the failure (m/s or m), its gait (shape (d + 1,)), the
        largest multiplier (by modulus) of its ``DP`` (central differences on the
        ``accurate`` map, relative step ``max(fd_step, sqrt(rtol))``; NaN if a step failed)
        and ``abs(g @ t) / norm(g)`` (:data:`FOLD_TANGENT_TOLERANCE`; NaN if a step failed);
        None if ``value`` itself solves to ``tol`` (the failure is not the family's end) or
        no verified gait was found.

    Raises
    ------
    SearchLimitError
        When the budget or the clock runs out.
    """

    def solve(x0: FloatArray, v: float) -> FloatArray | None:
        try:
            return _newton(search, x0, v, tol, max_iter, h, forward=True, accept=tol,
                           min_step=CONTINUATION_MIN_STEP)[0]
        except SearchLimitError:
            raise
        except PoweredGaitNotFoundError:
            return None

    if solve(x, value) is not None:
        return None
    delta = 0.5 * CONTINUATION_RESOLUTION * abs(value)
    ok: tuple[float, FloatArray] | None = None
    for _ in range(FAMILY_END_DOUBLINGS + 1):
        for v in (value - delta, value + delta):
            xv = solve(x, v) if v > 0 else None
            if xv is not None:
                ok = (v, xv)
                break
        if ok is not None:
            break
        delta *= 2.0
    if ok is None:
        return None
    lo, x_lo = ok
    hi = value
    while abs(hi - lo) > FAMILY_END_RESOLUTION * abs(value):
        mid = 0.5 * (lo + hi)
        x_mid = solve(x_lo, mid)
        if x_mid is None:
            hi = mid
        else:
            lo, x_lo = mid, x_mid
    # one central-difference Jacobian of the augmented residual on the accurate map (near a
    # fold the search map's forward differences at ``h`` are off by more than the distance of
    # a multiplier from 1): its section block is ``DP - I`` (the steps of
    # :func:`_section_jacobian`), its rows give the family's tangent and the target's gradient
    J = accurate.jacobian(x_lo, lo, max(fd_step, float(np.sqrt(accurate.rtol))))
    if not np.all(np.isfinite(J)):
        return lo, x_lo, complex(np.nan), float("nan")
    mult = np.linalg.eigvals(J[:-1, :-1] + np.eye(x_lo.size - 1))
    turning = float("nan")
    if np.linalg.norm(J[-1]) > 0:
        tangent = np.linalg.svd(J[:-1])[2][-1]
        turning = abs(float(J[-1] @ tangent)) / float(np.linalg.norm(J[-1]))
    return lo, x_lo, complex(mult[np.argmax(np.abs(mult))]), turning


def _end_message(
    prob: _Problem, target: Target, value: float, unit: str, path: tuple[float, float],
    end: tuple[float, FloatArray, complex, float], exc: Exception, note: str = "",
) -> str:
    """The error of a search whose family of gaits ends (:func:`_family_end`) short of
    ``value``: a fold (a multiplier at ``+1``) or an end for another reason. ``path``: the
    targets the continuation started and stopped at; only its part on this side of the
    verified end is reported as gaits found. ``note`` (what is known of the path's start, the
    seed) is appended when that start is reported, i.e. when the family ends below the target
    side's other end (``side`` "below")."""
    v_end, x_end, m, turning = end
    fam = prob.family
    if value > v_end:
        lo, hi, side = min(*path, v_end), v_end, "above"
        note = ""  # the span reported ends at the verified end, not at the seed
    else:
        lo, hi, side = v_end, max(*path, v_end), "below"
    found = (f"span {lo:.4g} to {hi:.4g} {unit} and end near {v_end:.4g} {unit}"
             if hi - lo > FAMILY_END_RESOLUTION * abs(value) else
             f"end near {v_end:.4g} {unit}")
    at = f"{fam.parameter_name} {x_end[-1]:.4g} {fam.parameter_unit}"
    if abs(m - 1.0) < FOLD_MULTIPLIER_TOLERANCE and turning < FOLD_TANGENT_TOLERANCE:
        return (
            f"no gait with {target} {value:g} {unit}: the {fam.name} gaits found {found} "
            f"({at}), at a fold: a Floquet multiplier reaches +1 there (largest |m| = "
            f"{abs(m):.3f} at that gait) and the family turns back, so none of its gaits has a "
            f"{target} {side} about {v_end:.4g} {unit} (past the fold Newton stalls at the "
            f"residual's nonzero minimum: {exc}){note}"
            f"{_other_gains(fam, '; ', ' may reach further')}"
        )
    largest = f"; largest multiplier |m| = {abs(m):.3f}" if np.isfinite(abs(m)) else ""
    # the last gait's impact angle: the legs near horizontal (R near l, fast) or a shuffle
    angle = f"; impact angle {np.degrees(abs(float(x_end[0]))):.3g} deg"
    return (
        f"no gait with {target} {value:g} {unit}: the {fam.name} gaits found {found} "
        f"({at}{largest}{angle}); Newton finds none {side} it ({exc}), but the family does "
        f"not turn back there (no fold), so gaits {side} it may exist that this search does "
        f"not reach{note}"
        f"{_other_gains(fam, '; ', ' may reach further')}"
    )


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
    max_continuation: int = 200,
    max_evaluations: int = 1500,
    fallback: bool = True,
    time_limit: float | None = None,
    progress: bool = False,
    simulator: Callable[..., WalkResult] | None = None,
    seed_sections: tuple[tuple[float, ...], ...] | None = None,
    passive_gait: Callable[[float], ArrayLike] | None = None,
    other_than: Sequence[ArrayLike] | None = None,
) -> Gait:
    """Find a period-one level-ground gait with a given speed or step length.

    Several gaits can meet one target. This returns the one its search reaches: the seed gait
    continued to the target (or Newton from ``guess``), which need not be the stable or the
    cheapest one, and can differ between backends where the search's path does.
    :func:`powered_gaits` (every gait the search and a few fresh starts meet) with
    :func:`preferred_gait` (the stable one needing the least work) is what ``heelstrike
    powered`` reports. At ``R = 0.99 l`` and 0.5 m/s this function returns a gait needing
    1.05 J per step, ``heelstrike powered`` a stable one needing 2.8e-5 J (QA sweep 6).

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
        Newton iterations of a solve (continuation steps use at most
        :data:`CONTINUATION_ITERATIONS`).
    fd_step : float
        Relative central-difference step of the accurate map's Jacobians (multipliers, final
        Newton); the search stage uses at least :data:`SEARCH_FD_STEP`.
    rtol, atol : float
        Integrator tolerances of the final gait (the search runs at :data:`SEARCH_TOLERANCE`
        when that is looser, see the module docstring).
    max_continuation : int
        Largest number of continuation steps (tried, including halved ones) from the seed gait
        to the target. The default 200 is rarely the bound: a fold stops the continuation
        first (steps halved below :data:`CONTINUATION_RESOLUTION`), and ``max_evaluations``
        and ``time_limit`` bound its cost. (It was 24, which stopped the torso walker's
        continuation from its seed gait near 0.49 m/s at 0.359 m/s although its gaits reach
        0.15 m/s: 60 steps, 0.4 s.)
    max_evaluations : int
        Budget of simulated steps (bounds the run time when no gait exists).
    fallback : bool
        If Newton from ``guess`` fails, search from the seed gait (default) or give up.
    time_limit : float or None
        Bound on the wall-clock time (s), not counting the time spent compiling kernels on a
        first run (:func:`heelstrike.dynamics._aot.compile_seconds`); None (default): only
        ``max_evaluations`` bounds the search, so that results do not depend on the machine's
        load (the CLI uses :data:`DEFAULT_TIME_LIMIT`).
    progress : bool
        Count simulated steps in a progress bar on stderr (shown after 2 s).
    simulator : callable, optional
        Step simulator with :func:`~heelstrike.dynamics.hybrid.simulate`'s signature (None:
        that function); :func:`find_model_powered_gait` passes the phased ones.
    seed_sections : tuple of tuple of float, optional
        Section points the seed search starts from (None: the compass gait's
        ``(q3, q3_dot, q4_dot)`` seeds).
    passive_gait : callable, optional
        ``passive_gait(slope)``: section point of a passive gait (zero push-off, the family's
        torque law at zero parameter) on a slope (rad); raises ``GaitNotFoundError`` (or
        ``PoweredGaitNotFoundError``) if there is none. When no seed gait is found on level
        ground, the search starts a homotopy in the slope from such a gait on one of
        :data:`HOMOTOPY_SLOPES` (see :func:`_slope_homotopy`). None (default): no homotopy.
    other_than : sequence of array_like, optional
        Gaits already found at this target, each ``(*fixed_point, parameter)``: the search
        looks for another one near them instead (:func:`_deflated_gaits`: deflated Newton
        from small offsets of each, the known gaits divided out of the residual; no seed
        search, no continuation) and raises :class:`PoweredGaitNotFoundError` if it finds
        none. :func:`powered_gaits` and the cost study use it to list every gait.

    Returns
    -------
    Gait

    Raises
    ------
    PoweredGaitNotFoundError
        If no gait reaching the target is found; at once for a target outside the reachable
        range (a speed at or above :func:`max_walking_speed`, a step length at or above the
        geometric limit); after the continuation stalls at the end of the actuation's family of
        gaits, with the range of speeds (or step lengths) its gaits spanned;
        :class:`SearchLimitError` when the time limit or the budget is hit.
    ValueError
        For an invalid target.
    """
    if (speed is None) == (step_length is None):
        raise ValueError("give exactly one of speed and step_length")
    target: Target = "speed" if speed is not None else "step_length"
    value = float(speed if speed is not None else step_length)  # type: ignore[arg-type]
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"the target {target} must be > 0, got {value}")
    if target == "step_length":
        from heelstrike.analysis.heel_strike import symmetric_step_length

        l, R = _scale(walker)[2], float(np.asarray(walker.foot_radii[0]))
        longest = float(symmetric_step_length(np.pi / 2, l, R))  # L_S at q3 = 90 deg
        if value >= longest:
            raise PoweredGaitNotFoundError(
                f"no gait with step_length {value:g} m: it is not below the geometric limit "
                f"{longest:.3g} m"
            )
    if target == "speed":
        vmax = max_walking_speed(walker)
        if value >= vmax:
            raise PoweredGaitNotFoundError(
                f"no gait with speed {value:g} m/s: it is outside the reachable range "
                f"0 < speed < {vmax:.3g} m/s "
                "of this walker: faster, the hip's centripetal acceleration at mid-stance would "
                "exceed g and the stance foot would leave the ground (v <= l sqrt(g / (l - R)); "
                "an upper bound: the gaits of an actuation usually end below it)"
            )
    family = actuation if isinstance(actuation, ActuationFamily) else actuation_family(actuation)
    limit = float("inf") if time_limit is None else float(time_limit)
    bar: Any = None
    if progress:
        from heelstrike._progress import progress_bar

        bar = progress_bar(desc=f"{family.name} gait search", unit=" steps")
    prob = _Problem(walker=walker, family=family, target=target, rtol=rtol, atol=atol,
                    budget=max_evaluations, deadline=time.monotonic() + limit, time_limit=limit,
                    compiled_before=compile_seconds(),
                    bar=bar, simulator=simulator,
                    seed_sections=(_scaled_seed_sections(walker) if seed_sections is None
                                   else seed_sections),
                    passive_gait=passive_gait)
    try:
        if other_than is not None:
            return _find_other(prob, value, [np.asarray(x, dtype=float) for x in other_than],
                               tol, max_iter, fd_step)
        return _find(prob, target, value, guess, tol, max_iter, fd_step, max_continuation,
                     fallback)
    finally:
        if bar is not None:
            bar.close()


def _find(
    prob: _Problem, target: Target, value: float, guess: ArrayLike | None, tol: float,
    max_iter: int, fd_step: float, max_continuation: int, fallback: bool,
) -> Gait:
    """The search of :func:`find_powered_gait`.

    Two stages. The *search* runs on the map integrated at :data:`SEARCH_TOLERANCE`: Newton
    from ``guess`` or, failing that, from a seed gait (:func:`_seeds`), then natural-parameter
    continuation in the target value (tangent predictor from the last Jacobian, Broyden
    updates). The *polish* converges the result on the accurate map (:func:`_polish`, mostly
    one simulated step per iteration) and :func:`_characterise` measures it there.
    """
    search = prob if prob.rtol >= SEARCH_TOLERANCE else prob.at_tolerance(SEARCH_TOLERANCE)
    s_tol = max(tol, SEARCH_RESIDUAL)
    p_tol = max(tol, PATH_RESIDUAL)
    s_h = max(fd_step, SEARCH_FD_STEP)
    accept = 10.0 * s_tol

    def finish(x: FloatArray, J: FloatArray, its: int) -> Gait:
        x, res, it = _polish(prob, x, value, tol, J, max_iter, fd_step)
        gait = _characterise(prob, x, res, its + it, fd_step)
        return _books_refined(prob, gait, x, value, tol, J, max_iter, fd_step)

    seed_note = [""]  # what the failure messages say about a seed that is not quite a gait

    def end_of_family(
        x: FloatArray, at: float, exc: Exception, path: tuple[float, float]
    ) -> PoweredGaitNotFoundError | None:
        """The error saying where the gaits end (:func:`_family_end`) when the search fails
        at ``at`` from ``x``; None if that cannot be verified (budget or clock included)."""
        try:
            end = _family_end(search, prob, x, at, min(s_tol, FAMILY_END_RESIDUAL), s_h,
                              max_iter, fd_step)
        except SearchLimitError:
            return None
        if end is None:
            return None
        return PoweredGaitNotFoundError(
            _end_message(prob, target, value, unit, path, end, exc, seed_note[0]))

    if guess is not None:
        x0 = np.asarray(guess, dtype=float)
        try:
            x, _, it, J = _newton(search, x0, value, s_tol, max_iter, s_h, forward=True,
                                  accept=accept)
            return finish(x, J, it)
        except SearchLimitError:
            raise
        except PoweredGaitNotFoundError:
            if not fallback:
                raise
    # a first gait: Newton (at the seed's own target value) from each seed candidate in turn
    first: tuple[FloatArray, float, int, FloatArray] | None = None
    last_error: Exception | None = None
    try:
        for cand in _seeds(search):
            st = search.step(cand)
            if not st.ok:
                continue
            current = search.measure(st)
            try:
                x, res, it, J = _newton(search, cand, current, p_tol, max_iter, s_h,
                                        forward=True, accept=10.0 * p_tol)
            except SearchLimitError:
                raise
            except PoweredGaitNotFoundError as exc:
                last_error = exc
                continue
            first = (x, current, it, J)
            if res > p_tol:  # a Newton stall accepted: near a fold, or just past one
                seed_note[0] = (
                    f"; the seed gait at {target} {current:.4g} "
                    f"{'m/s' if target == 'speed' else 'm'} is periodic only to a residual of "
                    f"{res:.1e} (it may lie just past a fold, where no gait has its {target})")
            break
    except SearchLimitError as exc:
        raise SearchLimitError(
            f"{exc} while still looking for a first {prob.family.name} gait to continue from "
            f"(iterating the map from {len(prob.family.seed(prob.walker))} seed "
            f"{prob.family.parameter_name} values); the target was never approached"
        ) from exc
    unit = "m/s" if target == "speed" else "m"
    via = ""  # how the first gait was reached, when not from a level-ground seed
    if first is None:
        why = f" (last: {last_error})" if last_error is not None else ""
        no_seed = (f"Newton converged from none of the {len(prob.family.seed(prob.walker))} "
                   f"seed {prob.family.parameter_name} values on level ground{why}")
        if prob.passive_gait is None:
            raise PoweredGaitNotFoundError(
                f"no periodic {prob.family.name} gait found: Newton converged from none of the "
                f"{len(prob.family.seed(prob.walker))} seed {prob.family.parameter_name} values "
                f"({_other_gains(prob.family, '', ' or ')}a starting guess (the library's guess=) "
                f"may find one){why}"
            )
        first, via = _slope_homotopy(search, target, unit, p_tol, s_h, no_seed)
    x, current, total_it, J = first
    frac, dfrac = 0.0, 1.0
    steps = 0
    while frac < 1.0:
        steps += 1
        reached = current + frac * (value - current)
        if steps > max_continuation:
            raise PoweredGaitNotFoundError(
                f"continuation from {target} {current:.4g} towards {value:.4g} {unit} stopped "
                f"after {max_continuation} steps at {reached:.4g} {unit}, still advancing (no "
                f"fold found on the way; the target may be reachable with more steps)"
                f"{seed_note[0]}{via}"
            )
        f_try = min(1.0, frac + dfrac)
        v_try = current + f_try * (value - current)
        x_pred = x.copy()
        if np.all(np.isfinite(J)):
            # tangent predictor: F(x, v) = (P(z, a) - z, g(z, a) - v), so dx/dv = J^-1 e_last
            try:
                e = np.zeros(x.size)
                e[-1] = 1.0
                x_pred = x + np.linalg.solve(J, e) * (v_try - reached)
            except np.linalg.LinAlgError:
                x_pred = x.copy()
            x_pred[-1] = max(x_pred[-1], prob.family.lower)
        try:
            last = f_try >= 1.0
            x_new, _, it, J_new = _newton(
                search, x_pred, v_try, s_tol if last else p_tol,
                min(max_iter, CONTINUATION_ITERATIONS), s_h,
                forward=True, accept=accept if last else 10.0 * p_tol,
                min_step=CONTINUATION_MIN_STEP, min_rate=CONTINUATION_MIN_RATE)
        except SearchLimitError as exc:
            raise SearchLimitError(
                f"{exc}: continuation from {target} {current:.4g} towards {value:.4g} {unit} "
                f"had reached {reached:.4g} {unit}{via}"
            ) from exc
        except PoweredGaitNotFoundError as exc:
            dfrac = 0.5 * (f_try - frac)  # half the increment that failed
            if dfrac * abs(value - current) < CONTINUATION_RESOLUTION * max(abs(value), 1e-3):
                # where two families of gaits meet (the push-off gaits near 0.91 m/s, a
                # multiplier pair on the unit circle) Newton converges, but slower than a
                # continuation step allows; one
                # solve with the full iterations decides whether the path goes on
                rescued = _rescue(search, x_pred, v_try, s_tol if last else p_tol, max_iter,
                                  s_h)
                if rescued is not None:
                    x_new, it, J_new = rescued
                    total_it += it
                    dfrac = f_try - frac  # the next step: the one that passed
                    x, frac, J = x_new, f_try, J_new
                    continue
                if not via:  # where the gaits really end (the path may lie past a fold)
                    ended = end_of_family(x, v_try, exc, (current, reached))
                    if ended is not None:
                        raise ended from exc
                lo, hi = min(current, reached), max(current, reached)
                found = (f"span only {lo:.6g} {unit} (the seed gait; continuation could not "
                         f"move it towards {value:g} {unit}: {exc})"
                         if hi - lo < 1e-4 * max(abs(hi), 1e-3) else
                         f"span {lo:.4g} to {hi:.4g} {unit} and end near {reached:.4g} {unit} "
                         f"(continuation from {current:.4g} stopped there: {exc}; the end "
                         f"of the path searched, not a verified end of the family)")
                raise PoweredGaitNotFoundError(
                    f"no gait with {target} {value:g} {unit}: the {prob.family.name} gaits "
                    f"found {found}{seed_note[0]}"
                    f"{via or _other_gains(prob.family, '; ', ' may reach further')}"
                ) from exc
            continue
        total_it += it
        x, frac, J = x_new, f_try, J_new
        dfrac = min(2.0 * dfrac, 1.0)
    try:
        return finish(x, J, total_it)
    except SearchLimitError:
        raise
    except PoweredGaitNotFoundError as exc:
        # the search accepted a residual (its bar, or a stall under 10x it) that the polish
        # cannot reduce: just past a fold the residual's nonzero minimum is that small
        ended = end_of_family(x, value, exc, (current, value)) if not via else None
        if ended is None:
            raise
        raise ended from exc


def _find_other(
    prob: _Problem, value: float, known: list[FloatArray], tol: float, max_iter: int,
    fd_step: float,
) -> Gait:
    """The ``other_than`` search of :func:`find_powered_gait`: a gait at the target ``value``
    other than the ``known`` ones (each shape (d + 1,)), by :func:`_deflated_gaits` on the
    search map, then polished and measured on the accurate map as :func:`_find` does."""
    search = prob if prob.rtol >= SEARCH_TOLERANCE else prob.at_tolerance(SEARCH_TOLERANCE)
    s_tol, s_h = max(tol, SEARCH_RESIDUAL), max(fd_step, SEARCH_FD_STEP)
    for x in _deflated_gaits(search, known, value, s_tol, s_h):
        try:  # the undeflated Jacobian, for the polish
            x, _, its, J = _newton(search, x, value, s_tol, max_iter, s_h, forward=True,
                                   accept=10.0 * s_tol)
            if min(float(np.linalg.norm(x - k)) for k in known) <= 1e-6:
                continue
            x, res, it = _polish(prob, x, value, tol, J, max_iter, fd_step)
        except SearchLimitError:
            raise
        except PoweredGaitNotFoundError:
            continue
        gait = _characterise(prob, x, res, its + it, fd_step)
        return _books_refined(prob, gait, x, value, tol, J, max_iter, fd_step)
    raise PoweredGaitNotFoundError(
        f"no other {prob.family.name} gait found near the {len(known)} known one(s) (deflated "
        f"Newton from offsets of {DEFLATION_OFFSET:g} of each)")


def _deflated_gaits(
    prob: _Problem, known: list[FloatArray], value: float, tol: float, h: float,
) -> list[FloatArray]:
    """Other roots of the augmented residual ``F`` near the ``known`` ones, by deflation.

    Newton (central differences, :data:`DEFLATION_ITERATIONS` iterations) solves
    ``G(x) = F(x) prod_k (1 / |x - x_k|^2 + 1)`` (Farrell, Birkisson and Funke, SIAM J. Sci.
    Comput. 37, 2015): the known roots ``x_k`` are divided out, so Newton cannot return to
    them, and ``|F| <= |G|`` elsewhere, so a root of ``G`` is one of ``F``. It starts from
    every known root offset by ``+-`` :data:`DEFLATION_OFFSET` along each unknown (times
    ``max(1, |x_i|)``), all starts in one batch. Near an unstable gait a stable one can lie
    1 % away (and the converse): the attractor seeds and the continuation of :func:`_find`
    meet only one of them (issue 32).

    Returns
    -------
    list of ndarray, shape (d + 1,)
        The roots found (``|F| <= tol``), distinct, nearest to their start first.
    """
    from heelstrike.analysis.newton import newton_solve

    K = np.asarray(known, dtype=float)
    lower = prob.family.lower

    def deflated(X: FloatArray) -> FloatArray:
        F = np.stack([prob.residual(x, value) for x in X])
        d2 = np.sum((X[:, None, :] - K[None, :, :]) ** 2, axis=2)
        with np.errstate(divide="ignore"):
            factor = np.prod(1.0 / d2 + 1.0, axis=1)
        return F * factor[:, None]

    def project(X: FloatArray) -> FloatArray:
        Y = X.copy()
        Y[:, -1] = np.maximum(Y[:, -1], lower)
        return Y

    n = K.shape[1]
    offsets = np.concatenate([np.eye(n), -np.eye(n)]) * DEFLATION_OFFSET
    starts = np.concatenate([k + offsets * np.maximum(1.0, np.abs(k)) for k in K])
    sol = newton_solve(deflated, project(starts), tol=tol, max_iter=DEFLATION_ITERATIONS,
                       fd_step=h, jacobian="central", jacobian_at_root=False,
                       line_search="finite", min_step=1e-2, project=project)
    found: list[FloatArray] = []
    for i in np.argsort(np.linalg.norm(sol.x - starts, axis=1)):
        x = sol.x[i]
        if sol.converged[i] and all(np.linalg.norm(x - y) > 1e-6 for y in found):
            found.append(x)
    return found


def _rescue(
    prob: _Problem, x0: FloatArray, value: float, tol: float, max_iter: int, h: float,
) -> tuple[FloatArray, int, FloatArray] | None:
    """One damped Newton solve with ``max_iter`` iterations (no rate bar) for a continuation
    step that its short solves failed at the resolution: ``(x, iterations, jacobian)``, or None
    if that fails too (a :class:`SearchLimitError` propagates)."""
    try:
        x, _res, it, J = _newton(prob, x0, value, tol, max_iter, h, forward=True,
                                 accept=10.0 * tol)
    except SearchLimitError:
        raise
    except PoweredGaitNotFoundError:
        return None
    return x, it, J


def _augmented(gait: Gait) -> FloatArray:
    """The powered ``gait``'s unknowns of the augmented map: its fixed point and actuation
    parameter, shape (d + 1,)."""
    if gait.actuation is None:
        raise ValueError("a passive gait has no actuation parameter")
    return np.append(gait.fixed_point, gait.actuation.parameter)


def books_gap(gait: Gait) -> float:
    """How far a powered gait's energy books are from closing, relative to their size.

    Parameters
    ----------
    gait : Gait

    Returns
    -------
    float
        ``max(|ΔE|, |W - T_c - ΔE|) / max(|W|, |T_c|, BOOKS_FLOOR)``: ``ΔE`` the change of
        ``T + V`` over the step (zero for a period-one gait on level ground), ``W`` the actuator
        work, ``T_c`` the collision loss; books smaller than :data:`BOOKS_FLOOR` (McGeer's
        wheel's gaits that need no work) are measured against it.
    """
    gap = max(abs(gait.energy_change), abs(gait.energy_balance_error))
    return gap / max(abs(gait.actuator_work), abs(gait.collision_loss), BOOKS_FLOOR)


def _books_refined(
    prob: _Problem, gait: Gait, x: FloatArray, value: float, tol: float, J: FloatArray,
    max_iter: int, fd_step: float,
) -> Gait:
    """``gait`` converged again at tighter tolerances if its books disagree by more than
    :data:`BOOKS_RTOL` (:func:`books_gap`), else ``gait``.

    The Newton tolerance and the integration tolerances are scaled down by the factor
    ``BOOKS_RTOL / gap`` (at least :data:`BOOKS_MIN_FACTOR`; integration at least
    :data:`BOOKS_MIN_TOLERANCE`), so that slow gaits, whose velocities and energies are small
    against the absolute tolerances, are resolved relative to their own size. The refined gait
    is kept if its books are closer; a refinement that fails (the walker falls, the budget or
    the clock runs out) keeps ``gait``.
    """
    gap = books_gap(gait)
    if not gap > BOOKS_RTOL:
        return gait
    factor = max(BOOKS_RTOL / gap, BOOKS_MIN_FACTOR)
    fine = prob.at_tolerance(max(min(prob.rtol, prob.atol) * factor, BOOKS_MIN_TOLERANCE))
    try:
        x2, res2, it2 = _polish(fine, x, value, tol * factor, J, max_iter, fd_step)
        refined = _characterise(fine, x2, res2, gait.iterations + it2, fd_step)
    except PoweredGaitNotFoundError:  # SearchLimitError included
        return gait
    return refined if books_gap(refined) < gap else gait


def _section_jacobian(prob: _Problem, x: FloatArray, fd_step: float,
                      jacobian: Literal["exact", "central"] = "exact"
                      ) -> tuple[FloatArray, str]:
    """``(DP, kind)``: ``DP``, shape (d, d), the step map's Jacobian in the section point at
    ``x`` (shape (d + 1,), the parameter held), and how it was formed.

    ``jacobian="exact"`` (default): exact (``kind = "exact"``) where
    :func:`~heelstrike.dynamics.variational.step_jacobian` applies (a walker with generated
    equations and one step per period, a push-off impulse and the built-in torque laws:
    :func:`~heelstrike.dynamics.variational.actuation_differentiable`): variational equations
    with the torque law's derivatives and the push-off in the heel strike's reset, on the
    scipy reference at the problem's tolerances (the same map as the compiled backend's, to
    its integration tolerance). Elsewhere, and for ``"central"``: central differences
    (``kind = "central"``, ``2 d`` steps) with the relative step ``max(fd_step, sqrt(rtol))``
    (it balances truncation ``~h^2`` and integration noise ``~rtol / h``)."""
    d = x.size - 1
    if jacobian == "exact":
        from heelstrike.core.saltation import GrazingEventError
        from heelstrike.dynamics.variational import (
            ExactJacobianUnavailable,
            StepFailedError,
            actuation_differentiable,
            step_jacobian,
        )

        torque, push = prob.family.build(prob.walker, float(x[-1]))
        walker = prob.walker
        if (actuation_differentiable(torque, push) and walker.steps_per_period == 1
                and not walker.is_batched):
            try:
                sj = step_jacobian(walker, x[:-1], slope=prob.slope, torque=torque,
                                   push_off=push, rtol=prob.rtol, atol=prob.atol)
            except (ExactJacobianUnavailable, GrazingEventError, StepFailedError):
                pass  # central differences below (a wheel's grazing trailing foot...)
            else:
                return np.asarray(sj.jacobian), "exact"
    h = max(fd_step, float(np.sqrt(prob.rtol)))
    DP = np.empty((d, d))
    for i in range(d):
        dz = np.zeros(d + 1)
        dz[i] = h * max(1.0, abs(x[i]))
        DP[:, i] = (prob.step(x + dz).z_next - prob.step(x - dz).z_next) / (2.0 * dz[i])
    return DP, "central"


def _characterise(
    prob: _Problem, x: FloatArray, residual: float, iterations: int, fd_step: float
) -> Gait:
    """The gait at ``x`` on the accurate map: books, and multipliers of ``DP``.

    ``DP`` exact where :func:`_section_jacobian` can form it (variational equations through
    the torque law and the push-off), else by central differences (``2 d`` steps), step
    ``max(fd_step, sqrt(rtol))`` times ``max(1, |x_i|)``: truncation ``~h^2``, integration
    noise ``~rtol / h``, multipliers to about 1e-6. (Forward differences from the gait's own
    step, ``d`` steps fewer, erred by up to 5e-3 on slow gaits, whose section coordinates are
    small against the step, and called stable gaits unstable: QA sweep 5.)
    """
    from heelstrike.dynamics.phased import PhasedWalkResult

    walker = prob.walker
    st = prob.step(x)
    rec = st.record
    assert rec is not None and st.ok
    z = x[:-1]
    DP, _ = _section_jacobian(prob, x, fd_step)
    mult = floquet_multipliers(DP)
    m, g, _ = _scale(walker)
    L = rec.step_length
    dE = st.energy_end - st.energy_start
    # every impact of the step (a described walker's knee strikes too), else the heel strike
    events = st.walk.events if isinstance(st.walk, PhasedWalkResult) else ()
    loss = (float(sum(e.kinetic_energy_constrained for e in events)) if events
            else rec.energy_lost)
    desc = walker.description
    law, _ = prob.family.build(walker, float(x[-1]))
    q, q_dot = walker.section_to_state(np.asarray(z, dtype=float))
    work = float(rec.actuator_work)
    return Gait(
        fixed_point=np.asarray(z, dtype=float),
        section_names=tuple(walker.section_names),
        q=np.asarray(q, dtype=float),
        q_dot=np.asarray(q_dot, dtype=float),
        period=rec.step_duration,
        step_length=L,
        speed=L / rec.step_duration,
        impact_angle=rec.impact_angle,
        multipliers=mult,
        stable=is_stable(mult),
        collision_loss=loss,
        kinetic_energy_pre=float(rec.kinetic_energy),
        kinetic_energy_admissible=float(rec.kinetic_energy_admissible),
        eta=float(loss_per_metre(loss, L)),
        potential_energy_released=float(rec.potential_energy_released),
        actuator_work=work,
        residual=residual,
        iterations=iterations,
        slope=float(prob.slope),
        leg_crossings=leg_crossings(walker, st.walk),
        impacts=tuple(events),
        energy_residual=work + float(rec.potential_energy_released) - loss,
        energy_change=dE,
        energy_balance_error=work - loss - dE,
        cost_of_transport=work / (m * g * L),
        trailing_foot_lift_velocity=rec.trailing_normal_velocity,
        trailing_foot_grazes=st.trailing_foot_grazes,
        stability_undecided=bool(walker.is_wheel),
        actuation=Actuation(
            name=prob.family.name,
            parameter_name=prob.family.parameter_name,
            parameter_unit=prob.family.parameter_unit,
            parameter=float(x[-1]),
            push_off_work=float(rec.push_off_work),
            torque_work=work - float(rec.push_off_work),
            torque_joint=prob.family.torque_joint,
            gains=law_gains(law),
            model=None if desc is None else str(desc.name),
        ),
        walk=st.walk,
    )


#: Units of the gains :func:`law_gains` reports (those of the ``--json`` units map).
GAIN_UNITS: dict[str, str | None] = {
    k: UNITS[k] for k in ("gain", "kp", "kd", "angle", "max_torque")}


def law_gains(torque: Any) -> dict[str, float]:
    """The gains of a torque law, by the names of :func:`actuation_family` and the walker
    file's ``[control]`` tables (:data:`GAIN_UNITS`): those the law has and that are finite
    (no ``max_torque`` for an unsaturated law); empty for None.

    Parameters
    ----------
    torque : torque law or None
        E.g. :class:`~heelstrike.dynamics.actuation.SwingLegPD` (``kp``, ``kd``,
        ``max_torque``), :class:`~heelstrike.dynamics.actuation.EnergyTracking` (``gain``,
        ``max_torque``), :class:`~heelstrike.dynamics.phased.TorsoPD` (``kp``, ``kd``, ``angle``).

    Returns
    -------
    dict
        Name -> value (SI units, :data:`GAIN_UNITS`).
    """
    if torque is None:
        return {}
    out = {}
    for name in GAIN_UNITS:
        value = getattr(torque, name, None)
        if isinstance(value, (int, float, np.floating)) and np.isfinite(value):
            out[name] = float(value)
    return out


# -- described walkers (TOML models) ------------------------------------------------------------
def declared_posture_law(walker: Any) -> Any:
    """The posture law a described walker's file declares (``[control.<name>]``), or None.

    Parameters
    ----------
    walker : BuiltWalker
        A described walker; its parameter values evaluate the law's expressions.

    Returns
    -------
    TorsoPD or None
        :class:`~heelstrike.dynamics.phased.TorsoPD` with ``kp`` (N m/rad), ``kd``
        (N m s/rad) and ``angle`` (rad) from the file.

    Raises
    ------
    ValueError
        If the file declares more than one law, or a law on a joint other than ``torso`` (the
        only one :class:`~heelstrike.dynamics.phased.TorsoPD` and the compiled kernel drive).
    """
    from heelstrike.dynamics.phased import TorsoPD
    from heelstrike.models.description import evaluate_expression

    laws = walker.description.control
    if not laws:
        return None
    if len(laws) > 1 or laws[0].joint != "torso":
        raise ValueError(
            f"model {walker.description.name!r} declares posture laws on "
            f"{[law.joint for law in laws]}: only one law, on a joint named 'torso', is supported"
        )
    law = laws[0]
    vals = walker.parameters

    def ev(v: Any, key: str) -> float:
        return float(np.asarray(evaluate_expression(v, vals, path=f"control.{law.name}.{key}")))

    return TorsoPD(walker=walker, kp=ev(law.kp, "kp"), kd=ev(law.kd, "kd"),
                   angle=ev(law.angle, "angle"))


#: Newton tolerance of the passive gait a described walker's slope homotopy starts from (it only
#: starts a continuation on the search's map).
PASSIVE_TOLERANCE = 1e-7


def passive_gait_finder(
    walker: PlanarWalker, family: ActuationFamily, simulator: Callable[..., WalkResult] | None,
) -> Callable[[float], FloatArray] | None:
    """The ``passive_gait`` of :func:`find_powered_gait` (its slope homotopy) for a walker
    without a description of its own (the compass gait).

    The homotopy starts where the family's parameter at its lower bound leaves the walker
    passive: the push-off alone (zero impulse, no torque law). A hip law acts at every
    parameter value, so for the hip laws there is none.

    Parameters
    ----------
    walker : PlanarWalker
    family : ActuationFamily
    simulator : callable or None
        The search's step simulator (:func:`family_simulator`): its passive gaits are found
        on the compiled compass map when it is compiled, else on the scipy reference.

    Returns
    -------
    callable or None
        ``slope -> section point`` of the walker's passive gait on that slope (rad)
        (:func:`~heelstrike.analysis.limit_cycle.find_limit_cycle`, to
        :data:`PASSIVE_TOLERANCE`), or None.
    """
    torque, _ = family.build(walker, max(0.0, family.lower))
    if family.name != "pushoff" or torque is not None:
        return None
    method = "compiled" if simulator is not None and walker.compiled_kernel == "compass" \
        else "scipy"

    def passive_gait(slope: float) -> FloatArray:
        from heelstrike.analysis.limit_cycle import find_limit_cycle

        gait = find_limit_cycle(walker, slope=slope, method=method, tol=PASSIVE_TOLERANCE)
        return np.asarray(gait.fixed_point, dtype=float)

    return passive_gait


def find_model_powered_gait(
    walker: Any,
    *,
    actuation: str = "pushoff",
    speed: float | None = None,
    step_length: float | None = None,
    backend: str = "compiled",
    posture: bool = True,
    actuation_options: Mapping[str, float] | None = None,
    **options: Any,
) -> Gait:
    """Level-ground powered gait of a described walker: push-off plus its posture law, or a
    hip law.

    The same two-stage search as :func:`find_powered_gait` (Newton on the walker's section
    (:class:`~heelstrike.dynamics.phased.PhasedWalker`) augmented with the push-off impulse
    ``p`` (N s), target speed or step length) on the phased step simulator. The posture law
    the walker file declares (``[control.torso]``, :func:`declared_posture_law`) acts during
    single support; its work and the push-off's are the actuator work. Over one period
    (post-impact to post-impact) the energy theorem on level ground gives

    .. math:: W_{push} + W_{posture} = \\sum T_c,

    since ``T + V`` returns to its value (:attr:`Gait.energy_balance_error` is the
    integration error of that book; ``sum T_c`` counts the knee strikes too).

    Walkers without a level-ground seed gait (the kneed walker: its passive gaits end at a
    fold near a 2 deg slope) are reached by a homotopy in the slope from their passive gait
    on one of :data:`HOMOTOPY_SLOPES` (:func:`~heelstrike.analysis.model_gaits.find_model_gait`
    with the posture law): the slope is lowered to 0 while the push-off takes over the
    energy input, the target raised where that continuation folds, and the level-ground gait
    so found is continued to the target (:func:`_slope_homotopy`). The kneed walker's gaits
    reached this way span about 1.22-1.41 m/s (a fold at the slow end, a step the walker
    cannot take at the fast end): a slower target fails with a message saying what was tried.

    The hip laws of :func:`actuation_family` (``"hip-energy"``, ``"hip-pd"``) act across the
    walker's hip (:attr:`~heelstrike.models.base.PlanarWalker.hip_joint`) and need a walker
    whose one actuator is its hip (``compass.toml``, ``kneed.toml``; not ``torso.toml``,
    which also drives its torso). They act at every parameter value, so the search has no
    passive start and no slope homotopy: it starts from the law's seeds on level ground.

    Parameters
    ----------
    walker : BuiltWalker
        Any described walker (scalar parameters).
    actuation : {"pushoff", "hip-energy", "hip-pd"}
        Push-off (with the declared posture law) or a hip law of :func:`actuation_family`.
    speed, step_length : float, optional
        Target (m/s or m); exactly one.
    backend : {"compiled", "scipy"}
        Backend of :func:`heelstrike.dynamics.simulate`: the generated numba kernel (default)
        or the scipy reference.
    posture : bool
        Apply the declared posture law (default); False: push-off only.
    actuation_options : mapping, optional
        The hip law's gains (``gain``, ``kp``, ``kd``, ``max_torque`` of
        :func:`actuation_family`); refused with the push-off.
    **options
        Passed to :func:`find_powered_gait` (``tol``, ``rtol``, ``time_limit``, ``guess``...;
        ``passive_gait=None`` turns the slope homotopy off).

    Returns
    -------
    Gait
        ``torque_joint`` names the law's joint: the posture law's, ``"hip"`` for a hip law or
        without a law (zero work).

    Raises
    ------
    ValueError
        Unknown backend or actuation, a hip law on a walker with other actuators, or gains
        with the push-off.
    PoweredGaitNotFoundError
    """
    from heelstrike.dynamics.backends import simulator as backend_simulator
    from heelstrike.dynamics.phased import PhasedWalker

    w = PhasedWalker.from_built(walker)
    if actuation != "pushoff":
        return _find_model_hip_law_gait(w, actuation, dict(actuation_options or {}), speed=speed,
                                        step_length=step_length, backend=backend, **options)
    if actuation_options:
        raise ValueError(f"actuation options {', '.join(sorted(actuation_options))} set the "
                         "hip laws, not the push-off (a posture law's gains are declared in "
                         "the walker file)")
    law = declared_posture_law(w) if posture else None
    # the one entry point, checked for this walker and actuation (ValueError if unsupported)
    simulator = backend_simulator(w, backend, torque=law, push_off=PushOff(impulse=0.0))
    base = actuation_family("pushoff")
    family = ActuationFamily(
        name="pushoff",
        parameter_name=base.parameter_name,
        parameter_unit=base.parameter_unit,
        parameter_meaning=base.parameter_meaning,
        build=lambda _w, a: (law, PushOff(impulse=max(float(a), 0.0))),
        seed=base.seed,
        lower=base.lower,
        torque_joint="hip" if law is None else "torso",
    )

    def passive_gait(slope: float) -> FloatArray:
        from heelstrike.analysis.model_gaits import find_model_gait

        gait = find_model_gait(walker, slope=slope, torque=law, backend=backend,
                               tol=PASSIVE_TOLERANCE, rtol=SEARCH_TOLERANCE * 0.1,
                               atol=SEARCH_TOLERANCE * 0.1)
        return np.asarray(gait.fixed_point, dtype=float)

    options.setdefault("passive_gait", passive_gait)
    return find_powered_gait(w, actuation=family, speed=speed, step_length=step_length,
                             simulator=simulator,
                             **options)


def check_model_actuation(walker: Any, actuation: str) -> None:
    """Raise ``ValueError`` (one line) unless a described walker takes this actuation.

    The push-off (with the posture law the walker file declares) suits every walker; a hip law
    of :func:`actuation_family` needs a walker whose one actuated joint is its
    :attr:`~heelstrike.models.base.PlanarWalker.hip_joint` (the law is its only torque).

    Parameters
    ----------
    walker : BuiltWalker or PhasedWalker
    actuation : str
        One of :data:`ACTUATIONS`.
    """
    if actuation not in ACTUATIONS:
        raise ValueError(f"unknown actuation {actuation!r}: choose from {', '.join(ACTUATIONS)}")
    if actuation == "pushoff" or tuple(walker.actuated_joints) == (walker.hip_joint,):
        return
    actuated = ", ".join(walker.coordinate_names[j] for j in walker.actuated_joints)
    raise ValueError(
        f"the hip law {actuation} needs a walker whose one actuated joint is its hip (the "
        f"law is its only torque); model {walker.description.name!r} actuates "
        f"{actuated or 'no joint'}"
    )


def _find_model_hip_law_gait(
    walker: Any, actuation: str, actuation_options: dict[str, float], *,
    speed: float | None, step_length: float | None, backend: str, **options: Any,
) -> Gait:
    """:func:`find_model_powered_gait` with a hip law (``walker`` a
    :class:`~heelstrike.dynamics.phased.PhasedWalker`)."""
    from heelstrike.dynamics.backends import simulator as backend_simulator

    check_model_actuation(walker, actuation)
    family = actuation_family(actuation, **actuation_options)
    torque, push_off = family.build(walker, family.seed(walker)[0])
    # the one entry point, checked for this walker and law (ValueError if unsupported)
    simulator = backend_simulator(walker, backend, torque=torque, push_off=push_off)
    options.setdefault("passive_gait", None)
    return find_powered_gait(walker, actuation=family, speed=speed, step_length=step_length,
                             simulator=simulator, **options)


def energy_book_tables(walker: PlanarWalker, gait: Gait) -> tuple[Any, Any]:
    """The energy of one period of a powered gait, for
    :func:`heelstrike.plots.gait.energy_figure`.

    Parameters
    ----------
    walker : PlanarWalker
        The walker the gait was found for.
    gait : Gait

    Returns
    -------
    energy : pandas.DataFrame
        ``t_s`` (s), ``step`` (0: the period is one step), ``event``, ``kinetic_J``,
        ``potential_J``, ``total_J`` (J) at every sample of the period (``event`` empty; the
        last is just before the push-off), then two rows at the heel-strike time: just after
        the push-off (``event`` ``"push_off"``: the total jumps by its work, none for a hip
        law) and just after the heel strike (``"heel_strike"``: the total drops by ``T_c``,
        back to its start value on the periodic gait). Between them the torque law's work
        changes the total. The sample just after an impact within the step (a knee strike)
        has that impact's kind as ``event``.
    impacts : pandas.DataFrame
        One row per impact of the step (a knee strike, then the heel strike), the columns of
        :func:`~heelstrike.analysis.walk_tables.walk_impact_table`: ``step``, ``kind``
        (``"knee_strike"``, ``"heel_strike"``), ``time_s``, ``impact_angle_rad`` (``q[2]``),
        ``total_before_J`` (the heel strike's after the push-off), ``total_after_J``,
        ``drop_J`` and ``T_c_J`` (J, that impact's own).
    """
    import pandas as pd

    from heelstrike.dynamics.phased import PhasedWalkResult

    walk = gait.walk
    rec = walk.impacts[0]
    q_all = np.vstack((walk.q, rec.q, walk.final_q))
    qd_all = np.vstack((walk.q_dot, rec.q_dot_minus, walk.final_q_dot))
    T = np.asarray([float(kinetic_energy(walker.mass_matrix(q), qd))
                    for q, qd in zip(q_all, qd_all, strict=True)])
    U = np.asarray([float(np.asarray(walker.potential_energy(q, 0.0))) for q in q_all])
    t = np.concatenate((walk.t, [rec.time, rec.time]))
    event = [""] * walk.t.size + ["push_off", "heel_strike"]
    E = T + U
    rows = []
    # impacts within the step (a kneed walker's knee strike): the walk samples both sides of
    # each at its time; the later sample is just after it (QA sweep 6: it was unlabelled, and
    # its loss counted in the heel strike's)
    events = walk.events if isinstance(walk, PhasedWalkResult) else ()
    for e in events[:-1]:
        at = np.flatnonzero(np.isclose(walk.t, e.time, rtol=0.0, atol=1e-12))
        if at.size < 2:
            continue
        event[int(at[-1])] = str(e.kind)
        rows.append({"step": 0, "kind": str(e.kind), "time_s": e.time,
                     "impact_angle_rad": float(e.q[2]), "total_before_J": float(E[at[0]]),
                     "total_after_J": float(E[at[-1]]),
                     "drop_J": float(E[at[0]] - E[at[-1]]),
                     "T_c_J": float(e.kinetic_energy_constrained)})
    energy = pd.DataFrame({"t_s": t, "step": np.zeros(t.size, dtype=int), "event": event,
                           "kinetic_J": T, "potential_J": U, "total_J": E})
    before, after = float(E[-2]), float(E[-1])
    heel = (float(events[-1].kinetic_energy_constrained) if events
            else gait.collision_loss)
    rows.append({
        "step": 0, "kind": "heel_strike", "time_s": rec.time,
        "impact_angle_rad": rec.impact_angle, "total_before_J": before,
        "total_after_J": after, "drop_J": before - after, "T_c_J": heel,
    })
    return energy, pd.DataFrame(rows)


# -- every gait at one design point (what `powered` reports and `study cost` keeps) -----------
def impact_angle_for_step_length(walker: PlanarWalker, step_length: float) -> float:
    """``q3`` (rad) of the symmetric heel strike with step length ``step_length`` (m): the
    inverse of :func:`~heelstrike.analysis.heel_strike.symmetric_step_length` (increasing on
    [0, pi/2]) with the walker's leg length (:attr:`~PlanarWalker.scale`) and stance foot
    radius; NaN if even ``q3 = pi/2`` steps shorter."""
    from heelstrike.analysis.heel_strike import symmetric_step_length

    l, R = float(walker.scale.leg_length), float(np.asarray(walker.foot_radii[0]))
    if not 0.0 <= R <= l:  # a described walker's foot radius beyond its leg length
        return float("nan")

    def f(q3: float) -> float:
        return float(symmetric_step_length(q3, l, R)) - step_length

    if f(np.pi / 2) < 0:
        return float("nan")
    from scipy.optimize import brentq  # only for step-length targets: keep `powered` light

    return float(brentq(f, 0.0, np.pi / 2, xtol=1e-14))


#: Extra Newton starts ``(q3_dot, q4_dot)`` (rad/s) of the fresh search, with ``q3`` from the
#: target step length and the family's smallest seed parameter. They reach the cheap push-off
#: branch near McGeer's wheel that the attractor seeds of ``find_powered_gait`` miss.
_FRESH_STARTS = ((0.6, -0.3), (0.9, -0.3))


def _solver(
    base: CompassGait, model: Any | None, actuation: str, actuation_options: dict[str, float],
    backend: str | None,
) -> Callable[..., Gait]:
    """``solve(radius, **options)``: the powered gait of the compass gait ``base`` (or of the
    described ``model``) with foot radius ``radius`` (m), by
    :func:`~heelstrike.analysis.powered.find_powered_gait` (or
    :func:`~heelstrike.analysis.powered.find_model_powered_gait`) on ``backend``."""
    family = actuation_family(actuation, **actuation_options)

    def solve(radius: float, **opts: Any) -> Gait:
        if model is None:
            w = base.replace(foot_radius=radius)
            sim = family_simulator(w, family, backend)
            opts.setdefault("passive_gait", passive_gait_finder(w, family, sim))
            return find_powered_gait(w, actuation=family, simulator=sim, **opts)
        return find_model_powered_gait(
            _at_radius(model, radius), actuation=actuation,
            backend=backend or ("compiled" if model.supports("compiled") else "scipy"),
            actuation_options=None if actuation == "pushoff" else dict(actuation_options),
            **opts)

    return solve


def powered_gaits(
    radius: float,
    *,
    speed: float | None = None,
    step_length: float | None = None,
    actuation: str = "pushoff",
    walker: CompassGait | None = None,
    model: Any | None = None,
    backend: str | None = None,
    actuation_options: dict[str, float] | None = None,
    **kwargs: Any,
) -> list[Gait]:
    """Every distinct powered gait the cost study meets at one design point, cheapest first.

    The study's fresh search at a grid point without neighbours: the seed search of
    :func:`~heelstrike.analysis.powered.find_powered_gait` (or
    :func:`~heelstrike.analysis.powered.find_model_powered_gait` for ``model``) and Newton
    from the fresh starts (``_FRESH_STARTS``), which reach branches the seed search misses
    (near McGeer's wheel a push-off gait needing 1/4000 of the work of the one the seeds find).
    Near the wheel (``R`` above :data:`NEAR_WHEEL` ``l``) the push-off gaits (of the compass
    gait, or of a model with a foot radius parameter ``R``) are also continued in the radius
    from ``NEAR_WHEEL l``, as a study's grid would reach them
    (:func:`_gaits_from_farther_radius`): the fresh starts alone miss the cheap branch at
    ``R = 0.99 l``. When none of these meets the target, the gaits at :data:`ANCHOR_FACTORS`
    times the target are continued to it (:func:`_gaits_from_anchor_targets`); the study does
    not do this (its grid's neighbours are its anchors; on the kneed walker's default grid the
    anchors found nothing more, for twice the time). Then other gaits near those are looked
    for by deflation (:func:`_other_gaits`), as the study does: a stable gait can lie 1 % away
    from an unstable one that the seeds reach (issue 32). Several gaits can meet one target;
    they are listed in the one order of gaits
    (:func:`~heelstrike.analysis._gait_order.gait_order`), the first being the one the study
    keeps there: the cheapest stable ordinary step (legs crossing once), else the cheapest
    unstable one. Each gait is polished to ``tol`` (default 1e-9).

    Parameters
    ----------
    radius : float
        Foot radius ``R`` (m); for a ``model`` without a parameter ``R``, its foot radius
        (the walker is studied as given).
    speed, step_length : float, optional
        Target (m/s or m); exactly one.
    actuation : str
        One of :data:`~heelstrike.analysis.powered.ACTUATIONS`.
    walker : CompassGait, optional
        The compass gait's other parameters (paper defaults); or ``model``, a described walker
        with a foot radius parameter ``R``.
    backend : {"compiled", "scipy"} or None
        As in :func:`~heelstrike.analysis.cost_study.cost_study`.
    actuation_options : dict, optional
        The hip laws' gains.
    **kwargs
        Passed to the searches (``tol``, ``progress``, ``time_limit``...).

    Returns
    -------
    list of Gait
        Distinct gaits (fixed point and parameter differing by more than 1e-4): ordinary steps
        first, stable before unstable, each group by actuator work (a multi-swing gait last).

    Raises
    ------
    PoweredGaitNotFoundError
        The seed search's failure, when no search met the target.
    """
    if (speed is None) == (step_length is None):
        raise ValueError("give exactly one of speed and step_length")
    base = CompassGait() if walker is None else walker
    opts = dict(actuation_options or {})
    solve = _solver(base, model, actuation, opts, backend)
    family = actuation_family(actuation, **opts)
    gaits, err = _fresh_gaits(solve, float(radius), _seed_walker(base, model, float(radius)),
                              family, speed, step_length, kwargs)
    if family.name == "pushoff" and (model is None or "R" in model.parameters):
        gaits += _gaits_from_farther_radius(solve, base, model, family, float(radius), speed,
                                            step_length, kwargs)
    if not gaits:
        gaits = _gaits_from_anchor_targets(solve, float(radius), speed, step_length, kwargs)
    if not gaits:
        assert err is not None
        raise err
    gaits += _other_gaits(solve, float(radius), _seed_walker(base, model, float(radius)),
                          gaits, speed, step_length, kwargs)
    tol = float(kwargs.get("tol", 1e-9))
    polished: list[Gait] = []
    for g in gaits:
        if g.residual > tol:  # a fresh start's looser tolerance
            try:
                g = solve(float(radius), guess=_augmented(g),
                          speed=speed, step_length=step_length, fallback=False, **kwargs)
            except (PoweredGaitNotFoundError, ValueError):
                continue
        if all(not _same_gait(g, h) for h in polished):
            polished.append(g)
    if not polished:
        assert err is not None
        raise err
    return ordered_gaits(polished)  # McGeer's wheel: each gait's stability_undecided


#: Foot radius (fraction of the leg length) above which :func:`powered_gaits` also continues the
#: compass gait's push-off gaits from this radius: near McGeer's wheel (``R = l``) a cheap
#: branch coexists with a costly one that the seeds find (at ``R = 0.97 l``, 0.5 m/s: 0.00025 J
#: against 1.01 J per step).
NEAR_WHEEL = 0.9

#: Largest radius step (fraction of the leg length) of that continuation, the cost study's
#: default ``radius_step`` for ``l = 1 m``.
NEAR_WHEEL_STEP = 0.05


def _gaits_from_farther_radius(
    solve: Callable[..., Gait], base: CompassGait, model: Any | None,
    family: ActuationFamily, r: float, speed: float | None, length: float | None,
    kwargs: dict[str, Any],
) -> list[Gait]:
    """Gaits at radius ``r`` (m) continued in the radius from ``NEAR_WHEEL l``, when ``r`` is
    above it (else none): the fresh search there, then Newton along radii at most
    ``NEAR_WHEEL_STEP l`` apart."""
    leg = float((base if model is None else model).scale.leg_length)
    r0 = NEAR_WHEEL * leg
    if r <= r0:
        return []
    start, _ = _fresh_gaits(solve, r0, _seed_walker(base, model, r0), family, speed, length,
                            kwargs)
    n_sub = max(1, int(np.ceil((r - r0) / (NEAR_WHEEL_STEP * leg) - 1e-9)))
    found: list[Gait] = []
    for g in start:
        x = _augmented(g)
        try:
            for r_sub in np.linspace(r0, r, n_sub + 1)[1:]:
                g = solve(float(r_sub), guess=x, speed=speed, step_length=length,
                          fallback=False, **kwargs)
                x = _augmented(g)
        except (PoweredGaitNotFoundError, ValueError):
            continue
        found.append(g)
    return found


#: Targets (factors of the asked one) that :func:`powered_gaits` searches from when the search
#: at the target itself met no gait, each gait then continued to the target in
#: :data:`ANCHOR_STEPS` geometric steps. Natural-parameter continuation from the seed gait
#: stops at a fold of its family; from beyond the target it comes in on another branch (QA
#: sweep 6, R = 0 push-off: no gait at 0.9 m/s from the seed gait at 0.51 m/s, a stable one
#: from 0.675 m/s). Only then: where an unstable gait was met they could also find a stable
#: one (at 0.073 m/s one needing 1/59 of the work), but a failing anchor search costs seconds
#: on the scipy reference (8 s more for the R = 0 hip-energy gait at 0.5 m/s).
ANCHOR_FACTORS = (1.35, 0.75)

#: Geometric continuation steps from an anchor target to the asked one (see
#: :data:`ANCHOR_FACTORS`).
ANCHOR_STEPS = 4


def _gaits_from_anchor_targets(
    solve: Callable[..., Gait], r: float, speed: float | None, length: float | None,
    kwargs: dict[str, Any],
) -> list[Gait]:
    """Gaits at the target continued from the seed search at :data:`ANCHOR_FACTORS` times it
    (radius ``r``, m); none where a search or a continuation fails. A time limit in
    ``kwargs`` bounds all of them together."""
    target = "speed" if speed is not None else "step_length"
    value = float(speed if speed is not None else length)  # type: ignore[arg-type]
    limit = kwargs.get("time_limit")
    deadline = time.monotonic() + float(limit) if limit is not None else float("inf")
    found: list[Gait] = []
    for factor in ANCHOR_FACTORS:
        left = deadline - time.monotonic()
        if left <= 0:
            break
        opts = kwargs | ({"time_limit": left} if limit is not None else {})
        try:
            g = solve(r, **{target: value * factor}, **opts)
            for v in np.geomspace(value * factor, value, ANCHOR_STEPS + 1)[1:]:
                g = solve(r, guess=_augmented(g), fallback=False,
                          **{target: float(v)}, **opts)
        except (PoweredGaitNotFoundError, ValueError):
            continue
        found.append(g)
    return found


def preferred_gait(gaits: Sequence[Gait]) -> Gait:
    """The gait ``heelstrike powered`` and ``study cost`` report among several meeting one
    target: the first in the one order of gaits
    (:func:`~heelstrike.analysis._gait_order.gait_order`), the stable one needing the least
    actuator work, else (none stable) the one needing the least work; among ordinary steps
    first, a multi-swing gait (:attr:`Gait.multi_swing`, its swing foot through the
    ground away from mid-stance) only where no other meets the target.

    A stable gait is one the walker walks with this actuation alone (as ``gait`` prefers the
    most attracting stable passive gait); the unstable ones are listed after it, marked.

    Parameters
    ----------
    gaits : sequence of Gait
        Non-empty, e.g. :func:`powered_gaits`. Gaits whose stability is undecided
        (:attr:`~heelstrike.analysis.gaits.Gait.stability_undecided`: McGeer's wheel,
        :data:`WHEEL_FAMILY`) are ordered by work alone: the one needing the least first.
    """
    return first_gait(gaits)


def _same_gait(a: Gait, b: Gait, tol: float = 1e-4) -> bool:
    """Whether two gaits are one (fixed point and parameter within ``tol``: the study's fresh
    starts converge to 1e-7 only, and met one gait 1.1e-6 from its polished self, which was
    counted twice at 1e-6; the distinct gaits of issue 32 lie 1e-2 apart)."""
    xa, xb = _augmented(a), _augmented(b)
    return float(np.linalg.norm(xa - xb)) <= tol


def _seed_walker(base: CompassGait, model: Any | None, r: float) -> Any:
    """The walker at radius ``r`` whose section the fresh starts are laid out on."""
    if model is None:
        return base.replace(foot_radius=r)
    from heelstrike.dynamics.phased import PhasedWalker

    return PhasedWalker.from_built(_at_radius(model, r))


def design_radius(walker: PlanarWalker) -> float:
    """The foot radius (m) that names a walker's design point in :func:`powered_gaits` and
    the cost study: its parameter ``R`` if it has one (a walker file's arc radius, or a
    profile's circle term), else its stance foot's radius (the compass gait's
    ``foot_radius``).

    A profile foot's rolling radius at ``phi = 0`` (``foot_radii``) is not its ``R``:
    :func:`powered_gaits` writes the radius back into ``R``, so passing the rolling radius
    would search another walker.

    Raises
    ------
    ValueError
        For a batch of walkers (one design point at a time).
    """
    if walker.is_batched:
        raise ValueError("powered gaits are searched for one walker at a time, not a batch "
                         f"(parameter shape {walker.parameter_shape})")
    params = walker.parameters
    if walker.description is not None and "R" in params:
        return float(np.asarray(params["R"], dtype=float))
    return float(np.asarray(walker.foot_radii[0], dtype=float))


def _at_radius(model: Any, r: float) -> Any:
    """The described walker with foot radius parameter ``R = r`` (m); a walker file without
    ``R`` (:func:`powered_gaits` of a walker as given) is returned unchanged."""
    return model.replace(R=r) if "R" in model.parameters else model


def _fresh_start(w: Any, q3: float, w3: float, w4: float, p0: float) -> FloatArray:
    """Newton start on ``w``'s section: stance angle ``-q3``, rates ``(w3, w4)``
    (:meth:`~heelstrike.models.base.PlanarWalker.section_point`: further links upright), then
    the parameter ``p0``."""
    return np.append(w.section_point(-q3, w3, w4), p0)


def _fresh_gaits(
    solve: Any, r: float, w: Any, family: Any, speed: float | None, length: float | None,
    kwargs: dict[str, Any],
) -> tuple[list[Gait], Exception | None]:
    """Gaits found without continuation at radius ``r``: the seed search of ``solve`` (the
    compass or described walker's ``find_*powered_gait``) and Newton from
    :data:`_FRESH_STARTS`. Returns the gaits and the seed search's failure (or None)."""
    gaits: list[Gait] = []
    err: Exception | None = None
    try:
        gaits.append(solve(r, speed=speed, step_length=length, **kwargs))
    except (PoweredGaitNotFoundError, ValueError) as exc:
        err = exc
    if length is not None:
        q3 = impact_angle_for_step_length(w, length)  # NaN: no symmetric step that long
    else:
        q3 = 0.2
    if not np.isfinite(q3):
        return gaits, err
    p0 = float(min(family.seed(w)))
    if family.name == "pushoff" and w.is_wheel:  # its passive gaits (WHEEL_FAMILY), polished
        for z in _wheel_passive_gaits(w, speed, length):
            try:
                gaits.append(solve(r, speed=speed, step_length=length, guess=np.append(z, 0.0),
                                   fallback=False, **kwargs))
            except (PoweredGaitNotFoundError, ValueError):
                pass
    # near the wheel the map is flat and Newton stalls at ~1e-8 (integrator noise floor)
    opts = {"max_iter": 12, "max_evaluations": 200, "tol": 1e-7} | kwargs
    for w3, w4 in _FRESH_STARTS:
        try:
            gaits.append(solve(r, speed=speed, step_length=length,
                               guess=_fresh_start(w, q3, w3, w4, p0), fallback=False, **opts))
        except (PoweredGaitNotFoundError, ValueError):
            pass
    return gaits, err


def _wheel_passive_gaits(
    wheel: PlanarWalker, speed: float | None, length: float | None
) -> list[FloatArray]:
    """Section points of McGeer's wheel's passive level-ground gait meeting the target: the
    unactuated step map's fixed point with that speed (m/s) or step length (m), by least
    squares from a few stance rates (the family is neutral, so Newton's square system is
    singular there); the first that meets it to 1e-9, or none (QA sweep 12: ``powered --radius
    1`` kept a gait needing 0.0068 J per step)."""
    from scipy.optimize import least_squares

    target = float(length if length is not None else speed)  # type: ignore[arg-type]

    def residual(z: FloatArray) -> FloatArray:
        st = powered_step(wheel, z, None, None, rtol=1e-12, atol=1e-12)
        if not st.ok:
            return np.full(4, 10.0)
        rec = st.record
        if rec is None:  # pragma: no cover - an ok step has its heel strike
            return np.full(4, 10.0)
        got = rec.step_length if length is not None else rec.step_length / rec.step_duration
        return np.append(st.z_next - z, got - target)

    q3 = 0.5 * (length if length is not None else 0.4) / float(wheel.scale.leg_length)
    for rate in (0.4, 0.7, 1.0, 1.5, 2.5):
        sol = least_squares(residual, [-q3, rate, 0.0], xtol=1e-14, ftol=1e-14, gtol=1e-14)
        if float(np.max(np.abs(residual(sol.x)))) < 1e-9:
            return [np.asarray(sol.x, dtype=float)]
    return []


#: Rounds of :func:`_other_gaits`: each looks for one more gait beside all those found.
OTHER_GAIT_ROUNDS = 3


def _other_gaits(
    solve: Callable[..., Gait], r: float, w: Any, gaits: Sequence[Gait],
    speed: float | None, length: float | None, kwargs: dict[str, Any],
) -> list[Gait]:
    """Gaits at radius ``r`` (m) beside the ``gaits`` found, by the deflated search of
    :func:`find_powered_gait` (``other_than``), one more per round while one is found (at most
    :data:`OTHER_GAIT_ROUNDS`); none for McGeer's wheel ``w`` (its gaits at one target form a
    neutral family, :data:`WHEEL_FAMILY`)."""
    if w.is_wheel or not gaits:
        return []
    known = [_augmented(g) for g in gaits]
    found: list[Gait] = []
    for _ in range(OTHER_GAIT_ROUNDS):
        try:
            g = solve(r, speed=speed, step_length=length, other_than=known, **kwargs)
        except (PoweredGaitNotFoundError, ValueError):
            break
        found.append(g)
        known.append(_augmented(g))
    return found


def _count_distinct(gaits: Sequence[Gait]) -> int:
    """Number of distinct gaits (:func:`_same_gait`)."""
    kept: list[Gait] = []
    for g in gaits:
        if all(not _same_gait(g, k) for k in kept):
            kept.append(g)
    return len(kept)
