"""The one result type of every gait search: :class:`Gait`.

A gait is a fixed point ``P(z*) = z*`` of the step-to-step map on the post-impact section
(:class:`~heelstrike.analysis.limit_cycle.PoincareMap`), with its period, step length, speed,
Floquet multipliers and stability, the kinetic energy lost at its impacts (``T_c``, Font &
Kövecses 2008) and its energy books. Passive gaits of the compass and of described walkers
alike are :class:`Gait`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.dynamics.hybrid import WalkResult

if TYPE_CHECKING:
    from heelstrike.dynamics.phased import PhasedImpact

__all__ = ["ENERGY_BOOKS_RTOL", "Gait", "StepBook"]

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
    """

    step: int
    duration: float
    step_length: float
    collision_loss: float
    potential_energy_released: float
    actuator_work: float
    kinetic_energy_gained: float


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



@dataclass(frozen=True, kw_only=True)
class Gait(ResultDictMixin):
    """A periodic gait and its energetics: the one result type of every gait search.

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
        step and ``collision_loss`` are the stride's too, and ``impact_angle``, ``T`` and
        ``T_a`` those of its first heel strike).
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
        Kinetic energy lost at heel strike per step, ``T_c`` for an inert impact (J).
    kinetic_energy_pre, kinetic_energy_admissible : float
        ``T`` and ``T_a`` just before impact (J).
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
    impacts: tuple[PhasedImpact, ...] = ()
    energy_residual: float = float("nan")
    hanging_links: tuple[str, ...] = ()
    steps: tuple[StepBook, ...] = ()
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
        energy). Only passive gaits are checked by the search (a push-off's work is not in
        ``actuator_work``)."""
        supplied = self.potential_energy_released + self.actuator_work
        loss = self.collision_loss
        if not (np.isfinite(supplied) and np.isfinite(loss) and supplied > 0 and loss > 0):
            return False
        return abs(loss - supplied) <= ENERGY_BOOKS_RTOL * max(loss, supplied)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (SI units; angles in rad); with recorded impacts also
        ``energy_residual``, ``impacts`` (each impact's kind, ``T``, ``T_c``, ``T_a`` (J), time
        and step), ``steps_per_period`` and ``steps`` (each step's book)."""
        d = {
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
