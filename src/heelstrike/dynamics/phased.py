"""Described walkers: their Poincare section and torque laws (their walk is the one loop).

A :class:`~heelstrike.models.builder.BuiltWalker` walks by
:func:`heelstrike.dynamics.hybrid.simulate`, the one hybrid loop for every walker, running the
schedule the walker declares (:meth:`~heelstrike.models.builder.BuiltWalker.step_schedule`:
knee swing, knee strike, locked swing, heel strike with the trailing foot decided by
complementarity); :func:`simulate_phased` is that same function, and :class:`PhasedImpact`,
:class:`PhasedWalkResult` and :func:`check_initial_state` are its results and its start check.

Poincare section
----------------
:class:`PhasedWalker` (a :class:`BuiltWalker` with section hooks) uses the state just after heel
strike (legs relabelled): lockable joints at their lock angles with zero rate, stance foot
rolling with its contact point at ``x = 0``, and the ``hip`` coordinate eliminated by the
relation that the trailing (now "left") foot touches the ground (clearance 0). The section
coordinates are the remaining joint angles and all unlocked rates; for ``compass.toml`` these
are exactly :class:`~heelstrike.models.CompassGait`'s ``(q3, q3_dot, q4_dot)``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._typing import FloatArray
from heelstrike.dynamics.hybrid import (
    ImpactKind,
    PhasedImpact,
    PhasedWalkResult,
    check_initial_state,
    simulate,
)
from heelstrike.models.builder import BuiltWalker, walker_description
from heelstrike.models.description import WalkerDescription

__all__ = [
    "ImpactKind",
    "PhasedImpact",
    "PhasedWalkResult",
    "PhasedWalker",
    "TorsoPD",
    "check_initial_state",
    "load_phased_walker",
    "simulate_phased",
]


# -- walker with a Poincare section ------------------------------------------------------------
class PhasedWalker(BuiltWalker):
    """A :class:`BuiltWalker` with a generic post-heel-strike Poincare section.

    See the module docstring for the section. Construct with :func:`load_phased_walker` or
    :meth:`from_built`.

    Parameters
    ----------
    description : WalkerDescription
    use_cache : bool
    **params : float
        Parameter values (scalars: the section is not batched).
    """

    @property
    def section_solved_coordinate(self) -> int:
        """The hip (:attr:`eliminated`), solved for zero swing-foot clearance on the section."""
        return self.eliminated

    def __init__(
        self, description: WalkerDescription, *, use_cache: bool = True, **params: ArrayLike
    ) -> None:
        super().__init__(description, use_cache=use_cache, **params)
        names = self.coordinate_names
        self.eliminated: int = names.index("hip") if "hip" in names else 3
        lock = set(self.lockable_joints)
        self._section_q = tuple(
            i for i in range(2, len(names)) if i not in lock and i != self.eliminated
        )
        self._section_v = tuple(i for i in range(2, len(names)) if i not in lock)

    @classmethod
    def from_built(cls, walker: BuiltWalker) -> PhasedWalker:
        """The same walker (description and parameter values) with section hooks.

        A described walker that already defines its Poincare section (the walker contract's
        ``description`` and ``has_poincare_section``: a phased walker) is returned as it is.
        """
        if walker.description is not None and walker.has_poincare_section:
            return cast(PhasedWalker, walker)
        values: dict[str, Any] = dict(walker.parameters)
        return cls(walker.description, **values)

    def replace(self, **params: ArrayLike) -> PhasedWalker:
        """A copy with some parameter values changed (no re-derivation)."""
        merged: dict[str, Any] = dict(self.parameters)
        merged.update(params)
        return PhasedWalker(self.description, **merged)

    @property
    def section_names(self) -> tuple[str, ...]:
        """Names of the section coordinates: angles (rad) then rates (rad/s)."""
        n = self.coordinate_names
        return tuple(n[i] for i in self._section_q) + tuple(f"{n[i]}_dot" for i in self._section_v)

    def touchdown_configuration(self, q: ArrayLike) -> FloatArray:
        """``q`` with the eliminated (hip) coordinate solved for zero swing-foot clearance, or
        for the walker file's declared heel-strike guard (``[events] heel_strike``: zero
        just after the strike too;
        :meth:`~heelstrike.models.builder.BuiltWalker.heel_strike_function`, which is minus
        the clearance otherwise).

        Newton's method from the symmetric guess ``hip = -2 q[2]`` (exact for straight
        symmetric legs), so the root found is the swing foot ahead, not the mid-stance one.

        Parameters
        ----------
        q : array_like, shape (n,)

        Returns
        -------
        ndarray, shape (n,)
        """
        q_ = np.array(q, dtype=float)
        j = self.eliminated
        q_[j] = -2.0 * q_[2]
        for _ in range(50):
            f = float(self.heel_strike_function(q_))
            h = 1e-7
            qp, qm = q_.copy(), q_.copy()
            qp[j] += h
            qm[j] -= h
            fp, fm = self.heel_strike_function(qp), self.heel_strike_function(qm)
            df = (float(fp) - float(fm)) / (2 * h)
            if df == 0.0:
                break
            step = f / df
            q_[j] -= step
            if abs(step) < 1e-15:
                break
        return q_

    def section_to_state(self, z: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Post-heel-strike ``(q, q_dot)``, each shape (n,), from section coordinates ``z``."""
        z_ = np.asarray(z, dtype=float)
        nq, nv = len(self._section_q), len(self._section_v)
        if z_.shape != (nq + nv,):
            raise ValueError(f"z must have shape ({nq + nv},): {self.section_names}")
        n = self.n_coordinates
        R = float(np.asarray(self.foot_radii[0]))
        q = np.zeros(n)
        q[1] = R
        for j, a in zip(self.lockable_joints, self.lock_angles, strict=True):
            q[j] = float(a)
        q[list(self._section_q)] = z_[:nq]
        q = self.touchdown_configuration(q)
        qd = np.zeros(n)
        qd[list(self._section_v)] = z_[nq:]
        qd[0] = -R * qd[2]
        return q, qd

    def state_to_section(self, q: ArrayLike, q_dot: ArrayLike) -> FloatArray:
        """Section coordinates of a post-heel-strike state, shape (d,)."""
        q_, qd = np.asarray(q, dtype=float), np.asarray(q_dot, dtype=float)
        return np.concatenate(
            (q_[..., list(self._section_q)], qd[..., list(self._section_v)]), axis=-1
        )


def load_phased_walker(
    name_or_path: str | os.PathLike[str], **params: ArrayLike
) -> PhasedWalker:
    """:func:`~heelstrike.models.builder.load_walker` returning a :class:`PhasedWalker`."""
    return PhasedWalker(walker_description(name_or_path), **params)  # type: ignore[arg-type]


# -- torque law for the torso walker ------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class TorsoPD:
    """Hold a torso up by a PD torque across its joint (reaction on the stance leg).

    .. math:: u_{torso} = -k_p (\\theta_{torso} - \\theta_{ref}) - k_d \\dot\\theta_{torso},
              \\qquad \\theta_{torso} = q_2 + q_{torso},

    with ``theta_torso`` the torso's absolute angle from the ground normal (rad, positive leaning
    towards ``-x``, the walking direction). Other actuated joints (the hip) get zero torque.

    Parameters
    ----------
    walker : BuiltWalker
        Must have an actuated joint named ``torso`` (its coordinate is relative to the stance
        leg, whose absolute angle is ``q[2]``).
    angle : float
        ``theta_ref`` (rad); a forward lean (> 0) feeds energy in through the stance leg.
    kp : float
        Stiffness (N m / rad).
    kd : float
        Damping (N m s / rad).
    """

    walker: BuiltWalker
    angle: float = 0.0
    kp: float = 300.0
    kd: float = 30.0

    def __call__(self, t: float, q: FloatArray, q_dot: FloatArray) -> FloatArray:
        j = self.walker.joint_index("torso")
        col = self.walker.actuated_joints.index(j)
        # complex states pass through (complex-step derivatives, :mod:`.variational`)
        q_, qd = np.asarray(q), np.asarray(q_dot)
        theta = q_[..., 2] + q_[..., j]
        omega = qd[..., 2] + qd[..., j]
        u = np.zeros((*q_.shape[:-1], len(self.walker.actuated_joints)),
                     dtype=np.result_type(theta, omega, float))
        u[..., col] = -self.kp * (theta - self.angle) - self.kd * omega
        return u


#: The one hybrid loop runs described walkers too (their declared step schedule).
simulate_phased = simulate
