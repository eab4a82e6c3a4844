"""Impacts with several candidate contacts: which constraints stay active after the impact?

Walker-agnostic. Given ``M`` (n, n), pre-impact velocities ``q_dot-``, *bilateral* inert
constraints that certainly engage (rows ``A_b`` (k_b, n), e.g. the striking foot rolling without
slip, a knee lock) and *unilateral* candidate contacts ``i`` (a normal row ``n_i`` and optionally a
tangential row ``t_i``, e.g. the trailing foot), find the post-impact velocity with

- impulse-momentum balance ``M (q_dot+ - q_dot-) = A_b^T lambda_b + sum_i (n_i^T p_i + t_i^T s_i)``;
- ``A_b q_dot+ = 0`` (inert, perfectly plastic);
- for every candidate, the complementarity ``p_i >= 0``, ``n_i q_dot+ >= 0``,
  ``p_i (n_i q_dot+) = 0`` (no pulling, no penetration, no impulse on a separating contact).

Friction model
--------------
Each candidate contact ends the impact in one of three modes:

``"separate"``
    ``p_i = s_i = 0`` and ``n_i q_dot+ >= 0`` (the foot lifts or just grazes).
``"stick"``
    no slip (infinite friction): ``n_i q_dot+ = 0``, ``t_i q_dot+ = 0``, ``p_i >= 0``, ``s_i``
    free; the contact becomes an inert constraint like the bilateral ones.
``"slip"``
    frictionless sliding: ``n_i q_dot+ = 0``, ``p_i >= 0``, ``s_i = 0``.

Active sets are enumerated exactly (``3^m`` for ``m`` candidates; meant for few contacts).
The solver prefers, in order: no slipping contact, then the fewest active contacts (a contact is
kept only if separation would violate ``n_i q_dot+ >= 0``). A contact without tangential row is
frictionless and only ever ``"separate"`` or ``"slip"``. With only separate/slip modes the
problem is an LCP with a positive definite matrix (unique solution, always found); the no-slip
modes come first because walkers' feet are assumed not to slip, and ``"slip"`` is the fallback
when no stick/separate assignment is consistent (a Painlevé-type situation of infinite
friction).

Energy: the final active rows ``A`` (bilateral, stick: normal + tangential, slip: normal) define
the projectors of :func:`heelstrike.core.impact.impact`, so ``q_dot+ = P_a q_dot-`` and the
decomposition ``T = T_c + T_a``, energy lost ``T_c``, hold for the resolved impact.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.impact import ImpactInputError, ImpactResult, impact

__all__ = ["CandidateContact", "ContactMode", "MultiContactImpact", "resolve_impact"]

ContactMode = Literal["separate", "stick", "slip"]


@dataclass(frozen=True, kw_only=True)
class CandidateContact:
    """A unilateral contact that may or may not stay engaged through the impact.

    Attributes
    ----------
    normal : ndarray, shape (n,)
        Row mapping ``q_dot`` to the contact's normal (separating-positive) velocity (m/s).
    tangential : ndarray, shape (n,) or None
        Row mapping ``q_dot`` to its tangential velocity; None for a frictionless contact.
    name : str
        Label used in results.
    """

    normal: FloatArray
    tangential: FloatArray | None = None
    name: str = "contact"

    @classmethod
    def from_jacobian(cls, A: ArrayLike, name: str = "contact") -> CandidateContact:
        """From a walker's contact Jacobian with rows (tangential, normal), shape (2, n)."""
        A_ = np.asarray(A, dtype=float)
        if A_.ndim != 2 or A_.shape[0] != 2:
            raise ImpactInputError(f"contact Jacobian must have shape (2, n), got {A_.shape}")
        return cls(normal=A_[1].copy(), tangential=A_[0].copy(), name=name)


@dataclass(frozen=True, kw_only=True)
class MultiContactImpact(ResultDictMixin):
    """Outcome of :func:`resolve_impact`.

    Attributes
    ----------
    modes : tuple of str
        Mode of each candidate contact (``"separate"``, ``"stick"``, ``"slip"``).
    active : tuple of int
        Indices of candidates in contact after the impact (stick or slip).
    impact : ImpactResult
        The inert impact with the final active rows (projectors, energies, ``q_dot+``).
    active_rows : ndarray, shape (k, n)
        The final constraint rows: bilateral rows, then per active candidate its normal row and
        (if sticking) its tangential row.
    bilateral_impulse : ndarray, shape (k_b,)
        Impulses of the bilateral rows (N s).
    normal_impulse, tangential_impulse : ndarray, shape (m,)
        ``p_i``, ``s_i`` of each candidate (0 when separating) (N s).
    normal_velocity, tangential_velocity : ndarray, shape (m,)
        Post-impact ``n_i q_dot+`` and ``t_i q_dot+`` (m/s; nan for a missing tangential row).
    n_consistent : int
        Number of consistent assignments found among the no-slip ones (1 if unique; 0 means
        the slip fallback was needed).
    """

    modes: tuple[ContactMode, ...]
    active: tuple[int, ...]
    impact: ImpactResult
    active_rows: FloatArray
    bilateral_impulse: FloatArray
    normal_impulse: FloatArray
    tangential_impulse: FloatArray
    normal_velocity: FloatArray
    tangential_velocity: FloatArray
    n_consistent: int

    @property
    def velocity_post(self) -> FloatArray:
        """``q_dot+``, shape (n,)."""
        return self.impact.velocity_post

    @property
    def kinetic_energy(self) -> float:
        """``T`` before impact (J)."""
        return float(self.impact.kinetic_energy)

    @property
    def kinetic_energy_constrained(self) -> float:
        """``T_c`` (J): energy lost in the inert impact."""
        return float(self.impact.kinetic_energy_constrained)

    @property
    def kinetic_energy_admissible(self) -> float:
        """``T_a`` (J): energy kept."""
        return float(self.impact.kinetic_energy_admissible)


def _rows_for(
    A_b: FloatArray, contacts: Sequence[CandidateContact], modes: Sequence[ContactMode]
) -> tuple[FloatArray, list[tuple[int, int, int | None]]]:
    """Stack the active rows; return them and, per active contact, (i, normal row, tang row)."""
    rows = [r for r in A_b]
    where: list[tuple[int, int, int | None]] = []
    for i, (c, mode) in enumerate(zip(contacts, modes, strict=True)):
        if mode == "separate":
            continue
        rows.append(c.normal)
        r_n = len(rows) - 1
        r_t: int | None = None
        if mode == "stick":
            assert c.tangential is not None
            rows.append(c.tangential)
            r_t = len(rows) - 1
        where.append((i, r_n, r_t))
    return np.asarray(rows, dtype=float).reshape(len(rows), A_b.shape[1]), where


def resolve_impact(
    M: ArrayLike,
    q_dot: ArrayLike,
    bilateral: ArrayLike | None,
    contacts: Sequence[CandidateContact],
    *,
    tol: float = 1e-10,
) -> MultiContactImpact:
    """Inert impact with bilateral constraints and unilateral candidate contacts.

    Parameters
    ----------
    M : array_like, shape (n, n)
        Mass matrix at the impact configuration (SPD).
    q_dot : array_like, shape (n,)
        Pre-impact velocities ``q_dot-``.
    bilateral : array_like, shape (k_b, n), or None
        Rows of the constraints that certainly engage (e.g. the leading foot's ``A_L``, a knee
        lock). May be None or empty.
    contacts : sequence of CandidateContact
        Unilateral candidates (e.g. the trailing foot, ``CandidateContact.from_jacobian(A_R)``).
    tol : float
        Relative tolerance of the sign conditions (scaled by the size of the impulses and
        velocities involved).

    Returns
    -------
    MultiContactImpact

    Raises
    ------
    ImpactInputError
        On bad shapes, or if no assignment is consistent (only possible with rank-deficient
        constraint sets).

    Notes
    -----
    Not batched: enumeration is per impact. See the module docstring for the friction model.
    """
    M_ = np.asarray(M, dtype=float)
    qd = np.asarray(q_dot, dtype=float)
    if M_.ndim != 2 or M_.shape[0] != M_.shape[1] or qd.shape != (M_.shape[0],):
        raise ImpactInputError(
            f"resolve_impact is not batched: need M (n, n), q_dot (n,), got {M_.shape}, {qd.shape}"
        )
    n = M_.shape[0]
    A_b = (
        np.zeros((0, n)) if bilateral is None else np.asarray(bilateral, dtype=float).reshape(-1, n)
    )
    for c in contacts:
        if c.normal.shape != (n,) or (c.tangential is not None and c.tangential.shape != (n,)):
            raise ImpactInputError(f"contact {c.name!r}: rows must have shape ({n},)")
    m = len(contacts)
    v_scale = float(np.sqrt(qd @ M_ @ qd / max(np.trace(M_) / n, 1e-300))) + 1e-300

    def options(c: CandidateContact, allow_slip: bool) -> tuple[ContactMode, ...]:
        if c.tangential is None:
            return ("separate", "slip")
        return ("separate", "stick", "slip") if allow_slip else ("separate", "stick")

    def n_active(modes: tuple[ContactMode, ...]) -> int:
        return sum(md != "separate" for md in modes)

    def try_modes(
        modes: tuple[ContactMode, ...],
    ) -> tuple[ImpactResult, FloatArray, list[tuple[int, int, int | None]]] | None:
        A, where = _rows_for(A_b, contacts, modes)
        if A.shape[0] == 0:
            res = _free(M_, qd)
        elif A.shape[0] > n or np.linalg.matrix_rank(A) < A.shape[0]:
            return None
        else:
            res = impact(M_, A, qd)
        lam = res.constraint_impulse
        v = res.velocity_post
        lam_scale = float(np.max(np.abs(lam), initial=0.0)) + 1e-300
        for _, r_n, _ in where:
            if lam[r_n] < -tol * max(lam_scale, 1.0):
                return None
        for i, c in enumerate(contacts):
            if modes[i] == "separate" and c.normal @ v < -tol * max(v_scale, 1.0):
                return None
        return res, A, where

    found: list[
        tuple[
            tuple[ContactMode, ...],
            tuple[ImpactResult, FloatArray, list[tuple[int, int, int | None]]],
        ]
    ] = []
    n_consistent = 0
    for allow_slip in (False, True):
        assignments = sorted(
            itertools.product(*(options(c, allow_slip) for c in contacts)),
            key=lambda md: (sum(x == "slip" for x in md), n_active(md)),
        )
        for modes in assignments:
            if allow_slip and "slip" not in modes:
                continue  # already tried without slip
            out = try_modes(modes)
            if out is not None:
                found.append((modes, out))
                if not allow_slip:
                    n_consistent += 1
        if found:
            break
    if not found:
        raise ImpactInputError("no consistent contact assignment (rank-deficient constraints?)")
    modes, (res, A, where) = found[0]
    lam = res.constraint_impulse
    v = res.velocity_post
    p = np.zeros(m)
    s = np.zeros(m)
    for i, r_n, r_t in where:
        p[i] = max(lam[r_n], 0.0)  # clip round-off below zero (checked within tol above)
        if r_t is not None:
            s[i] = lam[r_t]
    vn = np.array([c.normal @ v for c in contacts])
    vt = np.array([np.nan if c.tangential is None else c.tangential @ v for c in contacts])
    return MultiContactImpact(
        modes=modes,
        active=tuple(i for i, md in enumerate(modes) if md != "separate"),
        impact=res,
        active_rows=A,
        bilateral_impulse=np.asarray(lam[: A_b.shape[0]]),
        normal_impulse=p,
        tangential_impulse=s,
        normal_velocity=vn,
        tangential_velocity=vt,
        n_consistent=n_consistent,
    )


def _free(M: FloatArray, qd: FloatArray) -> ImpactResult:
    """The trivial 'impact' with no active constraint: nothing changes, nothing is lost."""
    n = M.shape[0]
    T = 0.5 * float(qd @ M @ qd)
    zero = np.zeros(n)
    return ImpactResult(
        constrained_projector=np.zeros((n, n)),
        admissible_projector=np.eye(n),
        velocity_pre=qd.copy(),
        velocity_constrained=zero,
        velocity_admissible=qd.copy(),
        velocity_post=qd.copy(),
        constraint_impulse=np.zeros(0),
        generalized_impulse=zero.copy(),
        kinetic_energy=np.asarray(T),
        kinetic_energy_constrained=np.asarray(0.0),
        kinetic_energy_admissible=np.asarray(T),
        kinetic_energy_post=np.asarray(T),
        energy_lost=np.asarray(0.0),
        restitution=0.0,
    )
