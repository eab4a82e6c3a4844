"""One gait finder and one result type: :func:`find_gaits` and :class:`Gait`.

A gait is a fixed point ``P(z*) = z*`` of the step-to-step map on the post-impact section
(:class:`~heelstrike.analysis.limit_cycle.PoincareMap`), with its period, step length, speed,
Floquet multipliers and stability, the kinetic energy lost at its impacts (``T_c``, Font &
Kövecses 2008) and its energy books. A powered gait is a fixed point with one more unknown,
the actuation amplitude, and one more equation, the target speed or step length; its
:class:`Actuation` record says how it is driven. Passive and powered gaits of the compass
and of described walkers alike are :class:`Gait`, listed in the one order of gaits
(:func:`~heelstrike.analysis._gait_order.ordered_gaits`: the cheapest stable gait first).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.dynamics.hybrid import WalkResult
from heelstrike.status import CodedStatus, check_codes

if TYPE_CHECKING:
    from heelstrike.analysis.model_gaits import GaitLocks
    from heelstrike.dynamics.phased import PhasedImpact
    from heelstrike.models.base import PlanarWalker

__all__ = [
    "ENERGY_BOOKS_RTOL",
    "TARGETS",
    "Actuation",
    "Gait",
    "GaitNote",
    "StepBook",
    "find_gaits",
]

#: Relative tolerance of a passive gait's energy books: the collision loss per step must equal
#: the potential energy released per step to within this fraction of the larger. The books of
#: the compass gait close to about 1e-7 at 1e-6 rad and to 0.6 % at 1e-9 rad; on slopes so small
#: that the step's energies reach the round-off of the potential energy (about 1e-14 of
#: ``m g l``), Newton still converges on "gaits" whose books disagree many times over (40x at
#: 1e-300 rad): those are no gaits, and are not returned.
ENERGY_BOOKS_RTOL = 0.05


@dataclass(frozen=True, kw_only=True)
class StepBook(ResultDictMixin):
    """The energy book of one step of a gait's period (Font & Kövecses 2008, eqs. 14-15).

    Attributes
    ----------
    step : int
        Step index in the period (0-based; 0 and 1 for the stride of a walker whose legs
        differ, leg A then leg B in stance).
    duration : float
        Step duration (s).
    step_length : float
        Distance walked along the ground (m).
    collision_loss : float
        Sum of ``T_c`` over the step's impacts (knee strikes and its heel strike) (J).
    potential_energy_released : float
        Potential energy released from the step's start to its heel strike (J).
    actuator_work : float
        Actuator work in the step, push-off included (J).
    kinetic_energy_gained : float
        ``actuator_work + potential_energy_released - collision_loss`` (J): the kinetic
        energy the step hands on to the next (just after its heel strike minus just after the
        previous one); zero on each step of a symmetric walker's gait, opposite on the two
        steps of a stride.
    kinetic_energy_pre, kinetic_energy_admissible : float
        ``T`` and ``T_a`` (J) just before each of the step's impacts, summed over them as
        ``collision_loss`` sums ``T_c`` (eq. 10 impact by impact: ``T = T_c + T_a``), so
        ``kinetic_energy_pre = collision_loss + kinetic_energy_admissible``.
    impact_angle : float
        Stance-leg angle at the step's heel strike (rad).
    """

    step: int
    duration: float
    step_length: float
    collision_loss: float
    potential_energy_released: float
    actuator_work: float
    kinetic_energy_gained: float
    kinetic_energy_pre: float = 0.0
    kinetic_energy_admissible: float = 0.0
    impact_angle: float = 0.0


class _WalkField:
    """Data descriptor of :attr:`Gait.walk`: holds a :class:`WalkResult`, or a
    zero-argument callable that simulates it, called on first access (then kept).

    A gait characterised on the compiled backend needs no trajectory; its ``walk`` (the scipy
    reference's samples of one period) is simulated only if asked for.
    """

    def __set_name__(self, owner: type, name: str) -> None:
        self._slot = f"_{name}_value"

    def __get__(self, obj: object | None, objtype: type | None = None) -> WalkResult:
        if obj is None:
            raise AttributeError("walk is set per instance")
        value = obj.__dict__[self._slot]
        if not isinstance(value, WalkResult):
            value = value()
            obj.__dict__[self._slot] = value
        return cast(WalkResult, value)

    def __set__(self, obj: object, value: WalkResult | Callable[[], WalkResult]) -> None:
        if isinstance(value, _WalkField):  # the dataclass default: the argument was left out
            raise TypeError(f"{type(obj).__name__}() needs the keyword argument 'walk'")
        obj.__dict__[self._slot] = value


class _LocksField:
    """Data descriptor of :attr:`Gait.locks`: holds a
    :class:`~heelstrike.analysis.model_gaits.GaitLocks` or None, or a zero-argument callable
    that computes it, called on first access (then kept).

    The lock torques need one dense walk of the step: a search returning several gaits
    walks again only the steps whose locks are asked for.
    """

    def __set_name__(self, owner: type, name: str) -> None:
        self._slot = f"_{name}_value"

    def __get__(self, obj: object | None, objtype: type | None = None) -> GaitLocks | None:
        if obj is None:
            raise AttributeError("locks is set per instance")
        value = obj.__dict__[self._slot]
        if callable(value):
            value = value()
            obj.__dict__[self._slot] = value
        return cast("GaitLocks | None", value)

    def __set__(
        self, obj: object, value: GaitLocks | Callable[[], GaitLocks | None] | None
    ) -> None:
        obj.__dict__[self._slot] = None if isinstance(value, _LocksField) else value


class GaitNote(CodedStatus):
    """What a report of a gait must say besides its numbers: the notes of
    :attr:`~heelstrike.analysis.gaits.Gait.notes`, decided where the gait is found
    (:func:`~heelstrike.analysis.gaits.find_gaits`), not by the reports. Each member is its
    string name with a stable integer ``code`` and a ``message`` (reports may word it at more
    length); the search's notes (``NO_STABLE_GAIT``: the first gait in the one order of
    gaits of a search without ``guess`` is unstable, so that, stable gaits coming first, none
    found is stable, or, McGeer's wheel's gaits ordered by work alone, the cheapest is not;
    ``REFERENCE_FOLLOWED``) are given to every gait it returns, the others to the
    gaits whose fields decide them (``BOOKS_OPEN``: a powered gait's
    :func:`~heelstrike.analysis.powered.books_gap` above ``BOOKS_NOTE`` of
    :mod:`heelstrike.analysis.powered`)."""

    HANGING_LINKS = (
        "hanging_links", 0,
        "a link described upright hangs in this gait (its centre of mass below its joint): a "
        "gait of the hanging link, not of the upright one",
    )
    MULTI_SWING = (
        "multi_swing", 1,
        "the swing leg crosses the stance leg more than once a step: its foot passes through "
        "the ground away from mid-stance, outside the scuffing convention",
    )
    NO_STABLE_GAIT = (
        "no_stable_gait", 2,
        "the search met no stable gait (it is local: one may still exist)",
    )
    REFERENCE_FOLLOWED = (
        "reference_followed", 3,
        "the search also followed the walker file's own parameters' stable gait at the "
        "reference slope, if it has one, to these parameters and slope",
    )
    BOOKS_OPEN = (
        "books_open", 4,
        "the energy books close only to more than BOOKS_NOTE of the work (books_gap): the "
        "gait is resolved no better than that",
    )
    STABILITY_UNDECIDED = (
        "stability_undecided", 5,
        "McGeer's wheel (R = l): the gaits at one target form a neutral family, their "
        "stability undecided",
    )
    TRAILING_FOOT_GRAZES = (
        "trailing_foot_grazes", 6,
        "R = l (McGeer's wheel): the trailing foot's lift velocity is exactly 0; both contacts "
        "are the same point, so the step was accepted",
    )


check_codes(GaitNote)


@dataclass(frozen=True, kw_only=True)
class Actuation(ResultDictMixin):
    """How a powered gait is driven: the actuation family, the amplitude Newton found (the
    one more unknown of a powered fixed point, solved with one more equation: a target speed
    or step length) and the work it does per step.

    Attributes
    ----------
    name : str
        Actuation family (:func:`~heelstrike.analysis.powered.actuation_family`).
    parameter_name, parameter_unit : str
        The actuation parameter found by Newton and its unit.
    parameter : float
        Its value (N s, J, N m or rad: ``parameter_unit``).
    push_off_work : float
        Work of the push-off impulse alone per step (J).
    torque_work : float
        Work of the torque law during single support per step (J), across ``torque_joint``
        (the gait's ``actuator_work`` minus ``push_off_work``).
    torque_joint : str
        The joint the torque law acts across (``"hip"``, or a posture law's joint).
    gains : dict of str to float
        The torque law's gains as used (:func:`~heelstrike.analysis.powered.law_gains`;
        empty for the push-off alone): what reproduces the gait.
    model : str or None
        The described walker's name (None: the compass gait).
    """

    name: str
    parameter_name: str
    parameter_unit: str
    parameter: float
    push_off_work: float
    torque_work: float
    torque_joint: str = "hip"
    gains: dict[str, float] = field(default_factory=dict)
    model: str | None = None

    @property
    def hip_work(self) -> float:
        """Work of the hip torque during single support (J); 0 if the torque acts elsewhere."""
        return self.torque_work if self.torque_joint == "hip" else 0.0


@dataclass(frozen=True, kw_only=True)
class Gait(ResultDictMixin):
    """A periodic gait and its energetics: the one result type of every gait search, passive
    (``actuation`` None) or powered.

    Attributes
    ----------
    fixed_point : ndarray, shape (d,)
        Section coordinates just after heel strike (names in ``section_names``).
    q, q_dot : ndarray, shape (n,)
        Full post-impact state (stance contact at x = 0).
    period : float
        Step duration (s): the duration of the period of
        :attr:`~heelstrike.models.base.PlanarWalker.steps_per_period` steps (the stride, two
        steps, for a walker whose legs differ; then ``step_length``, the energies of the
        step, ``collision_loss`` and the kinetic energies ``T``, ``T_a`` (sums over the
        impacts) are the stride's too, and ``impact_angle`` that of its first heel strike).
    step_length : float
        Distance walked along the ground per step (m).
    speed : float
        Mean walking speed along the ground, ``step_length / period`` (m/s).
    impact_angle : float
        Stance-leg angle ``q3`` at heel strike (rad).
    multipliers : ndarray of complex, shape (d,)
        Floquet multipliers, largest modulus first.
    stable : bool
        All multipliers inside the unit circle.
    collision_loss : float
        Kinetic energy lost at heel strike per step, ``T_c`` for an inert impact (J); for a
        gait with recorded ``impacts`` (a described walker) the sum over the period's impacts.
    kinetic_energy_pre, kinetic_energy_admissible : float
        ``T`` and ``T_a`` just before impact (J); with recorded ``impacts``, their sums over
        the period's impacts, as ``collision_loss`` (so ``T = T_c + T_a`` holds for them).
    eta : float
        Collision loss per distance, ``collision_loss / step_length`` (J/m), paper eq. (16).
    potential_energy_released : float
        Potential energy released per step (J); balances the losses on a passive gait.
    actuator_work : float
        Actuator work per step (J).
    residual : float
        ``|P(z*) - z*|`` at convergence.
    iterations : int
        Newton iterations used.
    slope : float
        Ground slope (rad).
    leg_crossings : int or None
        Times the swing leg crosses the stance leg in the step
        (:func:`~heelstrike.analysis.limit_cycle.leg_crossings`): 1 for an ordinary step;
        more for a multi-swing gait, whose swing foot goes through the ground away from
        mid-stance (:attr:`multi_swing`). None if not counted.
    impacts : tuple of PhasedImpact
        Every impact of one period (knee strikes, then the heel strike, step by step) of a
        gait whose walk records them (a described walker's); empty otherwise. With impacts,
        ``collision_loss`` is the sum of ``T_c`` over them, ``actuator_work`` and
        ``potential_energy_released`` the period's totals.
    energy_residual : float
        ``actuator_work + potential_energy_released - collision_loss`` (J); ~0 on a gait
        (NaN where the impacts are not recorded).
    hanging_links : tuple of str
        The links described upright that the gait carries hanging, at its post-impact
        configuration (:func:`~heelstrike.analysis.model_gaits.hanging_links`): a gait of the
        hanging link, not of the upright one. Empty for walkers without such links.
    steps : tuple of StepBook
        The energy book of each step of the period (empty where the impacts are not
        recorded).
    energy_change : float
        Change of mechanical energy ``T + V`` over the period (J); 0 on a periodic gait on level
        ground (NaN where not computed: the passive searches).
    energy_balance_error : float
        ``actuator_work - collision_loss - energy_change`` (J): the integration error of the
        books of a powered gait (NaN where not computed).
    cost_of_transport : float
        ``actuator_work / (m_total g step_length)`` (dimensionless; NaN where not computed).
    trailing_foot_lift_velocity : float
        Normal velocity of the trailing foot just after heel strike (m/s; NaN where not
        computed).
    trailing_foot_grazes : bool
        The trailing foot leaves the ground tangentially at heel strike (McGeer's wheel,
        ``R = l``).
    stability_undecided : bool
        Whether the gait's stability is undecided: McGeer's wheel (``R = l``), whose gaits at
        one target form a neutral family (a multiplier of 1 to round-off). The one order of
        gaits (:func:`~heelstrike.analysis._gait_order.gait_order`) then leaves stability out
        of its key, and reports say "undecided".
    actuation : Actuation or None
        How a powered gait is driven (None for a passive gait).
    notes : tuple of GaitNote
        What a report of the gait must say (:class:`GaitNote`, in code order), decided by
        :func:`find_gaits` from the gait's fields and its search (empty for a gait found
        otherwise, e.g. by :func:`~heelstrike.analysis.model_gaits.find_model_gaits` alone).
    locks : GaitLocks or None
        The torques the walker's locks exert over one step of the gait
        (:func:`~heelstrike.analysis.model_gaits.gait_locks`: ranges, and which locks must
        pull as well as push); None for a walker without locked joints, and where not
        computed (the compass gait's and powered searches). The constructor also takes a
        zero-argument callable returning it, called on first access (one dense walk of the
        step: :func:`~heelstrike.analysis.model_gaits.find_model_gaits` sets one per gait).
    newton_jacobian : str
        The Jacobian of Newton's iterations (``jacobian`` of
        :func:`~heelstrike.analysis.limit_cycle.find_limit_cycle`): ``"exact"`` (variational
        equations at every iterate), ``"central"`` (differences of the map), ``"mixed"`` (exact
        where it could be formed, differences elsewhere).
    walk : WalkResult
        One simulated period from the fixed point (the map's simulator; for a gait
        characterised on the compiled backend the scipy reference, simulated on first access).
        The constructor also takes a zero-argument callable returning it.
    """

    fixed_point: FloatArray
    section_names: tuple[str, ...]
    q: FloatArray
    q_dot: FloatArray
    period: float
    step_length: float
    speed: float
    impact_angle: float
    multipliers: NDArray[np.complex128]
    stable: bool
    collision_loss: float
    kinetic_energy_pre: float
    kinetic_energy_admissible: float
    eta: float
    potential_energy_released: float
    actuator_work: float
    residual: float
    iterations: int
    slope: float
    leg_crossings: int | None = None
    newton_jacobian: str = "central"
    impacts: tuple[PhasedImpact, ...] = ()
    energy_residual: float = float("nan")
    hanging_links: tuple[str, ...] = ()
    steps: tuple[StepBook, ...] = ()
    energy_change: float = float("nan")
    energy_balance_error: float = float("nan")
    cost_of_transport: float = float("nan")
    trailing_foot_lift_velocity: float = float("nan")
    trailing_foot_grazes: bool = False
    stability_undecided: bool = False
    actuation: Actuation | None = None
    notes: tuple[GaitNote, ...] = ()
    locks: _LocksField = field(default=_LocksField(), repr=False, compare=False)
    walk: _WalkField = field(default=_WalkField(), repr=False, compare=False)

    @property
    def multi_swing(self) -> bool:
        """Whether the swing leg crosses the stance leg more than once in the step (its foot
        then goes through the ground away from mid-stance, outside the scuffing convention:
        QA sweep 13, a 1.93 s "gait" at R = 0.3 m, 18 mm under the ground after mid-stance)."""
        return self.leg_crossings is not None and self.leg_crossings > 1

    @property
    def spectral_radius(self) -> float:
        """Largest multiplier modulus."""
        return float(np.max(np.abs(self.multipliers)))

    @property
    def energy_books_close(self) -> bool:
        """Whether the step's energy books close: the collision loss equals the potential
        energy released plus the actuator work, both positive, to within
        :data:`ENERGY_BOOKS_RTOL` of the larger (a periodic step neither gains nor loses
        energy). Only passive gaits are checked by the search; a powered gait's books are
        :attr:`energy_balance_error` (its ``actuator_work`` includes the push-off's)."""
        supplied = self.potential_energy_released + self.actuator_work
        loss = self.collision_loss
        if not (np.isfinite(supplied) and np.isfinite(loss) and supplied > 0 and loss > 0):
            return False
        return abs(loss - supplied) <= ENERGY_BOOKS_RTOL * max(loss, supplied)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (SI units; angles in rad); with recorded impacts also
        ``energy_residual``, ``impacts`` (each impact's kind, ``T``, ``T_c``, ``T_a`` (J), time
        and step), ``steps_per_period`` and ``steps`` (each step's book). A powered gait's
        summary has its actuation record's fields flattened into it (``actuation`` the
        family's name, ``parameter``, ``push_off_work``, ``torque_work``, ``gains``...)."""
        if self.actuation is not None:
            return self._powered_dict(self.actuation)
        d: dict[str, Any] = {
            "period": self.period,
            "step_length": self.step_length,
            "speed": self.speed,
            "impact_angle": self.impact_angle,
            "multipliers": [float(abs(m)) for m in self.multipliers],
            "multipliers_complex": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "stable": bool(self.stable),
            "collision_loss": self.collision_loss,
            "eta": self.eta,
            "potential_energy_released": self.potential_energy_released,
            "actuator_work": self.actuator_work,
            "kinetic_energy_pre": self.kinetic_energy_pre,
            "kinetic_energy_admissible": self.kinetic_energy_admissible,
            "fixed_point": dict(zip(self.section_names, map(float, self.fixed_point), strict=True)),
            "slope": self.slope,
            "residual": self.residual,
            "leg_crossings": self.leg_crossings,
        }
        if self.impacts:
            # every energy at the top level is the period's (sums over its impacts, knee
            # strikes included), so T = T_c + T_a holds here as impact by impact
            d["per"] = "stride" if len(self.steps) > 1 else "step"
            d["kinetic_energy_constrained"] = self.collision_loss
            d["energy_residual"] = self.energy_residual
            d["impacts"] = [
                {
                    "kind": e.kind,
                    "T": e.kinetic_energy,
                    "T_c": e.kinetic_energy_constrained,
                    "T_a": e.kinetic_energy_admissible,
                    "time": e.time,
                    "step": e.step,
                }
                for e in self.impacts
            ]
            d["steps_per_period"] = len(self.steps)
            d["steps"] = [b.to_dict() for b in self.steps]
        return d

    def _powered_dict(self, a: Actuation) -> dict[str, Any]:
        """:meth:`to_dict` of a powered gait: the actuation record flattened in."""
        return {
            "actuation": a.name,
            "parameter_name": a.parameter_name,
            "parameter_unit": a.parameter_unit,
            "parameter": a.parameter,
            "period": self.period,
            "step_length": self.step_length,
            "speed": self.speed,
            "impact_angle": self.impact_angle,
            "actuator_work": self.actuator_work,
            "push_off_work": a.push_off_work,
            "hip_work": a.hip_work,
            "torque_joint": a.torque_joint,
            "torque_work": a.torque_work,
            "model": a.model,
            "gains": dict(a.gains),
            "collision_loss": self.collision_loss,
            "energy_change": self.energy_change,
            "energy_balance_error": self.energy_balance_error,
            "cost_of_transport": self.cost_of_transport,
            "eta": self.eta,
            "stable": bool(self.stable),
            "stability_undecided": bool(self.stability_undecided),
            "multipliers": [float(abs(m)) for m in self.multipliers],
            "multipliers_complex": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "fixed_point": dict(zip(self.section_names, map(float, self.fixed_point), strict=True)),
            "residual": self.residual,
            "trailing_foot_lift_velocity": self.trailing_foot_lift_velocity,
            "trailing_foot_grazes": bool(self.trailing_foot_grazes),
            "leg_crossings": self.leg_crossings,
        }


#: The targets of a powered gait search (:func:`find_gaits`): the one more equation of the
#: augmented fixed point, and its unit.
TARGETS = {"speed": "m/s", "step_length": "m"}


def find_gaits(
    walker: PlanarWalker,
    slope: float = 0.0,
    *,
    control: str | None = None,
    target: Mapping[str, float] | None = None,
    backend: str | None = None,
    guess: ArrayLike | None = None,
    actuation_options: Mapping[str, float] | None = None,
    **options: Any,
) -> tuple[Gait, ...]:
    """Every distinct gait found, in the one order of gaits: the cheapest stable gait first.

    A gait is a fixed point ``P(z*) = z*`` of the step-to-step map on the post-impact section.
    A passive gait (``control`` None) is found on a downhill ``slope``; a powered gait is a
    fixed point with one more unknown, the amplitude ``a`` of the actuation family
    ``control``, and one more equation, the ``target``: ``P(z*, a) = z*`` with
    ``v(z*, a) = v_target`` (speed) or ``L(z*, a) = L_target`` (step length), on level ground.

    Parameters
    ----------
    walker : PlanarWalker
        The compass gait (:class:`~heelstrike.models.CompassGait`) or a described walker
        (:class:`~heelstrike.models.builder.BuiltWalker`, a walker file).
    slope : float
        Ground slope (rad), positive downhill; > 0 for a passive gait, 0 for a powered one.
    control : str or None
        None: passive gaits (:func:`~heelstrike.analysis.limit_cycle.find_limit_cycles` for
        the compass gait, :func:`~heelstrike.analysis.model_gaits.find_model_gaits` for a
        described walker). Else an actuation family of
        :data:`~heelstrike.analysis.powered.ACTUATIONS` (``"pushoff"``, ``"hip-energy"``,
        ``"hip-pd"``): the powered gaits that meet ``target``
        (:func:`~heelstrike.analysis.powered.powered_gaits`).
    target : mapping, optional
        With ``control``: exactly one of ``{"speed": v}`` (m/s) or ``{"step_length": L}`` (m),
        finite and > 0.
    backend : {"compiled", "scipy"} or None
        Step simulator; None: compiled where the walker runs on it, else the scipy reference
        (powered: as :func:`~heelstrike.analysis.powered.powered_gaits` chooses).
    guess : array_like, optional
        Passive only: section coordinates to start Newton from (the one gait it converges
        to is returned).
    actuation_options : mapping, optional
        With ``control``: the torque law's gains (:func:`~heelstrike.analysis.powered.law_gains`
        names).
    **options
        Passed to the search (``tol``, ``rtol``, ``atol``, ``progress``, ``time_limit``,
        ``every_start``...).

    Returns
    -------
    tuple of Gait
        Distinct gaits in :func:`~heelstrike.analysis._gait_order.ordered_gaits` order: ordinary
        steps before multi-swing gaits, stable before unstable (``stable`` marks each; a gait
        whose ``stability_undecided``, McGeer's wheel, is ordered by work alone), then the least
        actuator work, then the most attracting. Powered gaits carry their
        :class:`Actuation`; passive ones have ``actuation`` None. Each carries its
        :attr:`~Gait.notes` (:class:`GaitNote`), and a described walker's passive gait its
        lazy :attr:`~Gait.locks`.

    Raises
    ------
    ValueError
        Unknown ``control``, a bad ``target`` (missing, not one of ``speed`` and
        ``step_length``, not finite and > 0), a ``target`` or ``guess`` where it does not
        apply, a powered search on a slope, or an unknown backend.
    GaitNotFoundError, PoweredGaitNotFoundError
        No gait found (:class:`~heelstrike.analysis.limit_cycle.GaitNotFoundError`,
        :class:`~heelstrike.analysis.powered.PoweredGaitNotFoundError`).
    """
    from heelstrike.analysis._gait_order import ordered_gaits
    from heelstrike.models.builder import BuiltWalker

    described = walker.description is not None  # built from a walker file (the contract)
    if control is None:
        if target is not None:
            raise ValueError(f"target {dict(target)!r} is for a powered gait: give control "
                             "(an actuation family), or no target for passive gaits")
        if actuation_options:
            raise ValueError("actuation_options are for a powered gait: give control")
        method = backend or ("compiled" if walker.supports("compiled") else "scipy")
        if described:
            from heelstrike.analysis.model_gaits import find_model_gaits

            found: Sequence[Gait] = find_model_gaits(
                cast(BuiltWalker, walker), slope=slope, guess=guess, backend=method, **options)
        else:
            from heelstrike.analysis.limit_cycle import find_limit_cycle, find_limit_cycles

            found = (find_limit_cycles(walker, slope=slope, method=method, **options)
                     if guess is None else
                     (find_limit_cycle(walker, slope=slope, guess=guess, method=method,
                                       **options),))
        ordered = ordered_gaits(found)
        search: set[GaitNote] = set()
        if guess is None and ordered and not ordered[0].stable:
            search.add(GaitNote.NO_STABLE_GAIT)
            if described and options.get("from_reference", True):
                from heelstrike.analysis.model_gaits import follows_reference

                if follows_reference(cast(BuiltWalker, walker), slope):
                    search.add(GaitNote.REFERENCE_FOLLOWED)
        return tuple(_noted(g, search) for g in ordered)
    from heelstrike.analysis.powered import ACTUATIONS, design_radius, powered_gaits

    if control not in ACTUATIONS:
        raise ValueError(f"control {control!r} is not an actuation family (one of "
                         f"{', '.join(ACTUATIONS)}; None for passive gaits)")
    if guess is not None:
        raise ValueError("guess starts a passive gait's Newton; a powered search seeds itself")
    if slope != 0.0:
        raise ValueError(f"powered gaits are found on level ground (slope 0), got slope "
                         f"{slope:g} rad")
    goal = _target(target)
    radius = design_radius(walker)
    gaits = powered_gaits(
        radius, speed=goal.get("speed"), step_length=goal.get("step_length"),
        actuation=control, walker=None if described else cast(Any, walker),
        model=walker if described else None, backend=backend,
        actuation_options=dict(actuation_options) if actuation_options else None, **options)
    from heelstrike.analysis.powered import BOOKS_NOTE, books_gap

    ordered = ordered_gaits(gaits)
    # McGeer's wheel: its gaits' stability is undecided, not "none stable"
    search = ({GaitNote.NO_STABLE_GAIT} if ordered and not ordered[0].stable
              and not ordered[0].stability_undecided else set())
    return tuple(_noted(g, search | ({GaitNote.BOOKS_OPEN} if books_gap(g) > BOOKS_NOTE
                                     else set()))
                 for g in ordered)


def _noted(gait: Gait, search: set[GaitNote]) -> Gait:
    """``gait`` with its :attr:`~Gait.notes`: those its own fields decide (hanging links, a
    multi-swing step, undecided stability, a grazing trailing foot) and those of its search
    (``search``), in code order. Its lazy ``walk`` and ``locks`` stay lazy (a
    :func:`dataclasses.replace` would compute them)."""
    own = {
        GaitNote.HANGING_LINKS: bool(gait.hanging_links),
        GaitNote.MULTI_SWING: gait.multi_swing,
        GaitNote.STABILITY_UNDECIDED: gait.stability_undecided,
        GaitNote.TRAILING_FOOT_GRAZES: gait.trailing_foot_grazes,
    }
    notes = tuple(n for n in GaitNote if own.get(n, False) or n in search)
    kw = {f.name: getattr(gait, f.name) for f in fields(gait)
          if f.name not in ("walk", "locks", "notes")}
    return Gait(**kw, notes=notes, walk=gait.__dict__["_walk_value"],
                locks=gait.__dict__["_locks_value"])


def _target(target: Mapping[str, float] | None) -> dict[str, float]:
    """The powered search's ``target`` checked: one key of :data:`TARGETS`, finite and > 0."""
    if target is None:
        raise ValueError("a powered gait needs a target: {'speed': v} (m/s) or "
                         "{'step_length': L} (m)")
    keys = list(target)
    if len(keys) != 1 or keys[0] not in TARGETS:
        raise ValueError(f"target {dict(target)!r} must have exactly one of the keys "
                         f"{', '.join(TARGETS)}")
    (key,) = keys
    value = float(target[key])
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"target {key} must be finite and > 0 ({TARGETS[key]}), got {value:g}")
    return {key: value}
