"""Impact laws per contact: inert, Newton restitution and Coulomb friction, with the energy split.

Walker- and robot-agnostic: everything is expressed with a mass matrix ``M`` (n, n), pre-impact
generalized velocities ``q_dot-`` (n,) and, for every contact, a block of constraint rows
``J_i`` (k_i, n) of which some are *normal* rows (the first of them is the principal normal, the
one along which the contact may separate) and the rest *tangential* rows.

Contacts
--------
``bilateral=True`` (persistent, e.g. a stance sole that stays put)
    all rows inert: ``J_i q_dot+ = 0``, any impulse; reported as mode ``"stick"``.
``bilateral=False`` (striking, or a contact whose lift must be decided)
    unilateral with Newton restitution ``e_i`` on the normal rows and Coulomb friction ``mu_i``
    on the tangential rows, evaluated on the post-impact velocity ``u+ = J_i q_dot+``:

    - ``"separate"``: no impulse; the principal normal velocity satisfies
      ``u_n+ >= -e_i min(u_n-, 0)``;
    - ``"stick"``: ``u_N+ = -e_i u_N-`` on the normal rows (``min(u_n-, 0)`` for the principal
      one), ``u_T+ = 0``, impulse inside the cone ``|w_a lambda_a| <= mu_i lambda_n`` for
      every tangential row ``a``, ``lambda_n >= 0``;
    - ``"slip"``: same normal rows, some tangential row sliding, its impulse on the cone's
      edge and opposite to its post-impact velocity (maximum dissipation per row:
      ``w_a lambda_a = -mu_i lambda_n sign(u_a+)``).

    The friction cone is the **pyramid**, one Coulomb law per tangential row; ``w`` are the
    rows' weights (1 for forces; ``1 / rho`` for a twisting moment with torsional radius
    ``rho``). A contact's further normal rows (a flat sole held flat: the tilt moments) are
    held with any impulse while it is active, and free when it separates: all rows or none.

Solver (the choice stated): a **complementarity** formulation, *not* a convex QP relaxation (the
convex QP of Anitescu and of MuJoCo makes slipping contacts drift apart, ``u_n+ = mu ||u_T+||``;
here slipping contacts stay closed), solved **exactly** for every striking contact (points,
arcs, a sole's corners, a sole held flat) by one solver,
:func:`heelstrike.core.complementarity.solve_point_contacts`'s: bilateral rows are eliminated
(pseudo-inverse Schur complement of their Delassus block), every active set (per contact:
separate, or each tangential row sticking or sliding either way) is enumerated up to
:data:`~heelstrike.core.complementarity.ENUMERATION_BUDGET` (above it Lemke's method gives one
outcome) and each is one linear system with sign checks. The outcomes found are ``solutions``
(``unique``, ``exhaustive``, ``active_sets``); ``impulse_unique`` says whether the impulses are
determined too (not where contacts are redundant: two soles of one body), ``continuum`` whether
an active set admits a segment of outcomes (singular along a direction that moves ``q_dot+``),
``kkt_residual`` certifies the returned outcome in the full coordinates. Redundant rows (two heel
corners, a four-corner sole) give the unique ``q_dot+`` with the impulses of the smallest
consistent active set (Carathéodory) and the kept rows' least-norm impulses. A sole held flat
whose hold needs a pull while releasing it leaves it moving into the ground (an edge or corner
landing) has no consistent outcome: :func:`resolve_contact_impact` raises
:class:`~heelstrike.core.impact.ImpactInputError` rather than report a contact passing through
the ground: give such a sole as its corners. The energy split of a striking impact is the
nested one below with pseudo-inverses (:func:`energy_split` with ``redundant=True``): rows that
repeat earlier ones add nothing, so their energy goes to the contacts before them in the stated
order.

Energy split (every law)
------------------------
The rows *active* in the resolved impact (bilateral: all; stick: all; slip: the normal rows;
separate: none) define the projectors of :func:`heelstrike.core.impact.impact`, so that
``T = T_c + T_a`` with ``T_c = 1/2 (P_c q_dot-)^T M (P_c q_dot-)``. ``T_c`` is split into normal
and tangential parts by nested M-orthogonal projections: first onto the span of all active normal
rows (contact order), then adding the tangential rows; each contact's share is the energy its
row group adds to the preceding groups, so the shares are non-negative and add up exactly
(``sum T_c_normal + sum T_c_tangential = T_c``; the per-contact attribution depends on the
contact order when contacts couple through ``M``). The energy actually lost, ``T - T+``, equals
``T_c`` for the inert law and ``(1 - e^2) T_c`` for a single frictionless contact. With
``e > 0`` on a *sticking* contact whose normal and tangential rows couple through ``M``, Newton's
kinematic law gives ``T+ = T_a + e^2 T_w`` (``T_w`` the energy of the rebound velocity), which can
exceed ``T`` (Kane's paradox): a known limit of Newton restitution with friction, not a bug.

Direct path
-----------
When every contact is bilateral (persistent, inert: the paper's law) nothing has to be decided
and :func:`inert_contact_impact` solves the impact directly: one Cholesky factorization of ``M``
and one of the Delassus matrix ``W = A M^-1 A^T`` with the rows in the nesting order of the
energy split, so that ``T_c`` and its normal/tangential shares are sums of squares of one
triangular solve. It gives the numbers of :func:`resolve_contact_impact` to rounding and
accepts and rejects the same input (its rank test is the reference's SVD unless a cheap
certificate shows the rows far from rank deficient). :func:`inert_contact_impact_batch` is its
vectorised form over a batch (numpy's stacked solvers); :func:`inert_velocity` and
:func:`inert_velocity_batch` compute only ``q_dot+`` and the impulses.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.complementarity import (
    ENUMERATION_BUDGET,
    RestitutionLaw,
    _Layout,
    _pinv_psd,
    _solve_contacts,
)
from heelstrike.core.impact import ImpactInputError, impact

__all__ = [
    "ContactImpact",
    "ContactLaw",
    "ContactRows",
    "ImpactMode",
    "InertImpactBatch",
    "InertLayout",
    "check_inert_batch",
    "energy_split",
    "inert_contact_impact",
    "inert_contact_impact_batch",
    "inert_velocity",
    "inert_velocity_batch",
    "resolve_contact_impact",
]

ImpactMode = Literal["stick", "slip", "separate"]


@dataclass(frozen=True, kw_only=True)
class ContactLaw:
    """Impact law of one unilateral contact.

    Parameters
    ----------
    friction : float
        Coulomb coefficient ``mu >= 0`` (``inf``: no slip, the paper's inert contact).
    restitution : float
        Newton coefficient ``e`` in [0, 1] on the normal rows (0: the paper's inert contact).
    """

    friction: float = float("inf")
    restitution: float = 0.0

    def __post_init__(self) -> None:
        mu, e = float(self.friction), float(self.restitution)
        if not (mu >= 0.0) or np.isnan(mu):
            raise ImpactInputError(f"friction must be >= 0, got {self.friction!r}")
        if not (np.isfinite(e) and 0.0 <= e <= 1.0):
            raise ImpactInputError(f"restitution must lie in [0, 1], got {self.restitution!r}")
        object.__setattr__(self, "friction", mu)
        object.__setattr__(self, "restitution", e)


@dataclass(frozen=True, kw_only=True)
class ContactRows:
    """Constraint rows of one contact.

    Parameters
    ----------
    jacobian : array_like, shape (k, n)
        Rows mapping generalized velocities to contact velocities (m/s, rad/s).
    normal : sequence of int
        Indices (into the rows) of the normal rows; ``normal[0]`` is the principal normal, along
        which the contact pushes (``lambda >= 0``) and may separate.
    tangential : sequence of int
        Indices of the tangential rows (may be empty: frictionless by construction).
    tangential_weights : sequence of float, optional
        Positive weights ``w`` of the tangential rows in the friction norm (default all 1).
    bilateral : bool
        ``True``: persistent inert contact (all rows kept at zero velocity).
    law : ContactLaw
        Restitution and friction (ignored when ``bilateral``).
    name : str
        Label for reports.
    """

    jacobian: FloatArray
    normal: tuple[int, ...]
    tangential: tuple[int, ...] = ()
    tangential_weights: tuple[float, ...] | None = None
    bilateral: bool = False
    law: ContactLaw = field(default_factory=ContactLaw)
    name: str = ""

    def __post_init__(self) -> None:
        J = np.array(self.jacobian, dtype=float)
        if J.ndim != 2 or J.shape[0] < 1:
            raise ImpactInputError(f"contact {self.name!r}: jacobian must be (k, n), got {J.shape}")
        if not np.all(np.isfinite(J)):
            raise ImpactInputError(f"contact {self.name!r}: jacobian has non-finite entries")
        J.setflags(write=False)
        object.__setattr__(self, "jacobian", J)
        nrm, tan = tuple(int(i) for i in self.normal), tuple(int(i) for i in self.tangential)
        if not nrm:
            raise ImpactInputError(f"contact {self.name!r}: needs at least one normal row")
        idx = nrm + tan
        if sorted(idx) != list(range(J.shape[0])):
            raise ImpactInputError(
                f"contact {self.name!r}: normal {nrm} and tangential {tan} rows must partition "
                f"the {J.shape[0]} rows"
            )
        w = (1.0,) * len(tan) if self.tangential_weights is None else self.tangential_weights
        w = tuple(float(x) for x in w)
        if len(w) != len(tan) or not all(np.isfinite(x) and x > 0 for x in w):
            raise ImpactInputError(f"contact {self.name!r}: tangential_weights must be positive")
        object.__setattr__(self, "normal", nrm)
        object.__setattr__(self, "tangential", tan)
        object.__setattr__(self, "tangential_weights", w)

    @property
    def rows(self) -> int:
        """Number of constraint rows ``k``."""
        return int(self.jacobian.shape[0])


@dataclass(frozen=True, kw_only=True)
class ContactImpact(ResultDictMixin):
    """Resolved impact with per-contact laws.

    Attributes
    ----------
    velocity_pre, velocity_post : ndarray, shape (n,)
        ``q_dot-`` and ``q_dot+``.
    impulse : ndarray, shape (sum k_i,)
        Constraint impulses (N s, N m s) of all rows, contact after contact, each contact's rows
        in the order of its Jacobian.
    generalized_impulse : ndarray, shape (n,)
        ``M (q_dot+ - q_dot-) = sum_i J_i^T lambda_i``.
    modes : tuple of str
        ``"stick"``, ``"slip"`` or ``"separate"`` per contact (bilateral contacts: ``"stick"``).
    contact_velocity_pre, contact_velocity_post : tuple of ndarray
        ``J_i q_dot-`` and ``J_i q_dot+`` per contact.
    T, T_c, T_a, T_post, energy_lost : float
        Kinetic energy before, its constrained and admissible parts for the active rows, after,
        and ``T - T_post`` (J).
    T_c_normal, T_c_tangential : ndarray, shape (contacts,)
        Per-contact normal and tangential shares of ``T_c`` (J); they add up to ``T_c``.
    solutions : tuple of ndarray
        ``q_dot+`` (n,) of every distinct outcome the law admits, the returned one first (and
        the finite ends of any continuum), when the active sets were examined (a striking
        contact); empty when nothing was to decide (bilateral contacts only).
    exhaustive : bool
        Whether every active set was examined (``solutions`` is then complete).
    active_sets : int
        Number of active sets of the law (a bound on the number of outcomes; 0 if unknown).
    restitution_law : str
        ``"newton"`` or ``"energetic"``.
    impulse_unique : bool or None
        Whether the impulses are determined by the law (False: their split between redundant
        contacts is not, e.g. a body landing flat on two soles); None when not examined.
    continuum : bool
        Some active set admits a segment of outcomes ``q_dot+`` (then ``unique`` is False and
        ``solutions`` holds its finite ends).
    velocity_range : ndarray, shape (2, n), or None
        Componentwise smallest and largest ``q_dot+`` over the outcomes (``-inf``/``inf``
        where a continuum is unbounded); None when not examined.
    kkt_residual : float
        Largest relative violation of the law's conditions by the returned outcome, checked
        in the full coordinates (:class:`heelstrike.core.complementarity.
        PointContactSolution`); 0 when not examined.
    """

    velocity_pre: FloatArray
    velocity_post: FloatArray
    impulse: FloatArray
    generalized_impulse: FloatArray
    modes: tuple[ImpactMode, ...]
    contact_velocity_pre: tuple[FloatArray, ...]
    contact_velocity_post: tuple[FloatArray, ...]
    T: float
    T_c: float
    T_a: float
    T_post: float
    energy_lost: float
    T_c_normal: FloatArray
    T_c_tangential: FloatArray
    solutions: tuple[FloatArray, ...] = ()
    exhaustive: bool = False
    active_sets: int = 0
    restitution_law: str = "newton"
    impulse_unique: bool | None = None
    continuum: bool = False
    velocity_range: FloatArray | None = None
    kkt_residual: float = 0.0
    _stop_unique: bool | None = field(default=None, repr=False)

    @property
    def outcomes(self) -> int:
        """Number of distinct outcomes found (1 when the active sets were not examined)."""
        return max(len(self.solutions), 1)

    @property
    def unique(self) -> bool | None:
        """Whether ``q_dot+`` is determined by the law (one outcome, no continuum): None when
        the active sets were not all examined, unless the inelastic impact is certified to
        stop everything (normal impulses alone can stop the system: then ``q_dot+ = 0`` is the
        only outcome, True)."""
        if self.exhaustive:
            return len(self.solutions) == 1 and not self.continuum
        return self._stop_unique


def _check_M(M: ArrayLike) -> tuple[FloatArray, tuple[FloatArray, bool]]:
    M_ = np.asarray(M, dtype=float)
    if M_.ndim != 2 or M_.shape[0] != M_.shape[1]:
        raise ImpactInputError(f"M must be (n, n), got {M_.shape}")
    if not np.all(np.isfinite(M_)):
        raise ImpactInputError("M contains non-finite values")
    scale = float(np.max(np.abs(M_))) if M_.size else 1.0
    if np.max(np.abs(M_ - M_.T)) > 1e-10 * scale:
        raise ImpactInputError("M is not symmetric")
    try:
        cho = scipy.linalg.cho_factor(M_)
    except np.linalg.LinAlgError as exc:
        raise ImpactInputError("M is not positive definite") from exc
    return M_, cho


def energy_split(
    M: ArrayLike,
    q_dot: ArrayLike,
    groups: Sequence[ArrayLike],
    *,
    check: bool = True,
    redundant: bool = False,
) -> tuple[float, FloatArray]:
    """Nested M-orthogonal split of the constrained energy over ordered row groups.

    Parameters
    ----------
    M : array_like, shape (n, n)
        Mass matrix, symmetric positive definite.
    q_dot : array_like, shape (n,)
        Velocities (m/s, rad/s).
    groups : sequence of array_like, each shape (k_j, n)
        Row groups in the order of the nesting (``k_j`` may be 0).
    check : bool
        Verify the rank of the stacked rows by an SVD (default True).
    redundant : bool
        Accept rows of any rank (default False): the energy of the projection onto the span
        of the first ``j`` groups is then ``E_j = 1/2 b_j^T W_j^+ b_j`` (``b_j``, ``W_j`` the
        rows' velocities and Delassus block, ``+`` the pseudo-inverse) and group ``j``'s share
        ``E_j - E_{j-1} >= 0``. A group whose rows repeat earlier ones gets 0: the groups
        before it take the energy (the convention the order sets).

    Returns
    -------
    T_c : float
        Energy (J) of the M-orthogonal projection of ``q_dot`` onto the span of
        ``M^-1 A^T`` for all rows ``A`` of all groups.
    shares : ndarray, shape (len(groups),)
        Energy each group adds to the preceding ones (J, >= 0); ``shares.sum() == T_c``.

    Raises
    ------
    ImpactInputError
        If the stacked rows are rank deficient (unless ``redundant``).
    """
    M_, cho = _check_M(M)
    v = np.asarray(q_dot, dtype=float)
    n = M_.shape[0]
    mats = [np.asarray(g, dtype=float).reshape(-1, n) for g in groups]
    shares = np.zeros(len(mats))
    if not mats or sum(g.shape[0] for g in mats) == 0:
        return 0.0, shares
    A = np.vstack(mats)
    X = scipy.linalg.cho_solve(cho, A.T)
    W = A @ X
    W = 0.5 * (W + W.T)
    b = A @ v
    if redundant:
        prev, stop = 0.0, 0
        for j, g in enumerate(mats):
            stop += g.shape[0]
            if g.shape[0]:
                E = 0.5 * float(b[:stop] @ (_pinv_psd(W[:stop, :stop]) @ b[:stop]))
                shares[j] = max(E - prev, 0.0)
                prev = max(E, prev)
        return float(shares.sum()), shares
    try:
        L = np.linalg.cholesky(W)
    except np.linalg.LinAlgError as exc:
        raise ImpactInputError("contact rows are rank deficient (redundant contacts?)") from exc
    if check:
        sv = np.linalg.svd(A, compute_uv=False)
        if sv[-1] <= 1e-12 * max(A.shape) * sv[0]:
            raise ImpactInputError("contact rows are rank deficient (redundant contacts?)")
    # Prefix energies 1/2 b_S^T W_SS^-1 b_S = 1/2 |L_SS^-1 b_S|^2 (Cholesky is nested).
    y = scipy.linalg.solve_triangular(L, b, lower=True)
    start = 0
    for j, g in enumerate(mats):
        stop = start + g.shape[0]
        shares[j] = 0.5 * float(y[start:stop] @ y[start:stop])
        start = stop
    return float(shares.sum()), shares


def resolve_contact_impact(
    M: ArrayLike,
    q_dot: ArrayLike,
    contacts: Sequence[ContactRows],
    *,
    restitution_law: RestitutionLaw = "newton",
) -> ContactImpact:
    """Resolve an impact with per-contact inert/restitution/friction laws (module doc).

    Parameters
    ----------
    M : array_like, shape (n, n)
        Mass matrix at impact, symmetric positive definite.
    q_dot : array_like, shape (n,)
        Pre-impact velocities ``q_dot-``.
    contacts : sequence of ContactRows
        Bilateral (persistent) and unilateral (striking) contacts, in report order.
    restitution_law : {"newton", "energetic"}
        Newton's kinematic law (can gain energy with sticking friction: Kane's paradox) or
        the energetic two-phase law of :func:`heelstrike.core.complementarity.
        solve_point_contacts`, which cannot.

    Returns
    -------
    ContactImpact

    Raises
    ------
    ImpactInputError
        On malformed input, rank-deficient rows when every contact is bilateral, or a
        striking contact with several normal rows that has no consistent outcome (an edge or
        corner landing of a sole held flat).

    Notes
    -----
    With a striking contact the exact active-set solver decides (module doc: every active set
    of the pyramid-cone law up to :data:`~heelstrike.core.complementarity.ENUMERATION_BUDGET`,
    ``unique``, ``impulse_unique``, ``kkt_residual``); with bilateral contacts only, the
    impact is the inert projection of :func:`heelstrike.core.impact.impact` (full-rank rows).
    """
    M_, cho = _check_M(M)
    n = M_.shape[0]
    v = np.asarray(q_dot, dtype=float)
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ImpactInputError(f"q_dot must be finite with shape ({n},), got {v.shape}")
    if not contacts:
        raise ImpactInputError("no contacts given")
    for c in contacts:
        if c.jacobian.shape[1] != n:
            raise ImpactInputError(
                f"contact {c.name!r}: jacobian has {c.jacobian.shape[1]} columns, expected {n}"
            )
    if restitution_law not in ("newton", "energetic"):
        raise ImpactInputError(
            f"restitution law must be newton or energetic, got {restitution_law!r}")
    if any(not c.bilateral for c in contacts):
        return _resolve_active_set(M_, v, contacts, restitution_law)
    A_b = np.vstack([c.jacobian for c in contacts])
    if A_b.shape[0] > n:
        raise ImpactInputError(f"{A_b.shape[0]} contact rows exceed the {n} coordinates")
    sv = np.linalg.svd(A_b, compute_uv=False)
    if sv[-1] <= 1e-12 * max(A_b.shape) * sv[0]:
        raise ImpactInputError("contact rows are rank deficient (redundant contacts?)")
    X_b = scipy.linalg.cho_solve(cho, A_b.T)
    W_bb = A_b @ X_b
    cho_b = scipy.linalg.cho_factor(0.5 * (W_bb + W_bb.T))
    lam = -scipy.linalg.cho_solve(cho_b, A_b @ v)
    v_plus = v + X_b @ lam
    # Energy split over the rows: normal groups first, then tangential groups.
    normal_groups = [c.jacobian[list(c.normal)] for c in contacts]
    tangential_groups = [c.jacobian[list(c.tangential)] for c in contacts]
    _, shares = energy_split(M_, v, normal_groups + tangential_groups, check=False)
    m = len(contacts)
    split = impact(M_, np.vstack(normal_groups + tangential_groups), v, check=False)
    T, T_c = float(split.kinetic_energy), float(split.kinetic_energy_constrained)
    T_a = float(split.kinetic_energy_admissible)
    T_post = 0.5 * float(v_plus @ M_ @ v_plus)
    return ContactImpact(
        velocity_pre=v,
        velocity_post=v_plus,
        impulse=lam,
        generalized_impulse=A_b.T @ lam,
        modes=tuple("stick" for _ in contacts),
        contact_velocity_pre=tuple(c.jacobian @ v for c in contacts),
        contact_velocity_post=tuple(c.jacobian @ v_plus for c in contacts),
        T=T,
        T_c=T_c,
        T_a=T_a,
        T_post=T_post,
        energy_lost=T - T_post,
        T_c_normal=shares[:m],
        T_c_tangential=shares[m:],
    )


def _resolve_active_set(M: FloatArray, v: FloatArray, contacts: Sequence[ContactRows],
                        law: RestitutionLaw) -> ContactImpact:
    """:func:`resolve_contact_impact` by exact active sets (pyramid cones, any rank)."""
    n = M.shape[0]
    uni = [c for c in contacts if not c.bilateral]
    rows: list[FloatArray] = []
    principal: list[int] = []
    extra: list[tuple[int, ...]] = []
    tangential: list[tuple[int, ...]] = []
    where: list[int] = []  # first stacked row of each striking contact
    for c in uni:  # stacked in the contact's own row order, tangential rows scaled by 1/w
        start = len(rows)
        where.append(start)
        weight = dict(zip(c.tangential, c.tangential_weights or (), strict=True))
        rows += [c.jacobian[r] / weight.get(r, 1.0) for r in range(c.rows)]
        principal.append(start + c.normal[0])
        extra.append(tuple(start + r for r in c.normal[1:]))
        tangential.append(tuple(start + r for r in c.tangential))
    R = np.array(rows).reshape(-1, n)
    lay = _Layout(principal=tuple(principal), extra=tuple(extra), tangential=tuple(tangential))
    mu = np.array([c.law.friction if c.tangential else 0.0 for c in uni])
    e = np.array([c.law.restitution for c in uni])
    bil = [c.jacobian for c in contacts if c.bilateral]
    A_b = np.vstack(bil) if bil else np.zeros((0, n))
    try:
        sol = _solve_contacts(M, v, R, lay, A_b, mu, e, law, ENUMERATION_BUDGET)
    except ImpactInputError as exc:
        held = [c for c in uni if len(c.normal) > 1]
        if "no consistent active set" not in str(exc) or not held:
            raise
        c = held[0]
        v0 = v  # released (no impulse of its own), with the kept rows still holding
        if A_b.shape[0]:
            X = np.linalg.solve(M, A_b.T)
            v0 = v - X @ (_pinv_psd(A_b @ X) @ (A_b @ v))
        u_n = float(c.jacobian[c.normal[0]] @ v0)
        raise ImpactInputError(
            f"contact {c.name!r}: no consistent impact: holding its {len(c.normal)} normal "
            "rows (the sole flat on the ground) needs a pull, and releasing it leaves it "
            f"moving into the ground at {u_n:.4g} m/s; the sole lands on an edge or a corner, "
            "which this contact law does not model (give the sole as its corners)") from None
    modes: list[ImpactMode] = []
    lam_parts: list[FloatArray] = []
    normal_groups: list[FloatArray] = []
    tangential_groups: list[FloatArray] = []
    bpos, j = 0, 0
    for c in contacts:
        Jn, Jt = c.jacobian[list(c.normal)], c.jacobian[list(c.tangential)]
        if c.bilateral:
            lam_parts.append(sol.bilateral_impulse[bpos:bpos + c.rows])
            bpos += c.rows
            modes.append("stick")
        else:
            lam = sol.impulse[where[j]:where[j] + c.rows].copy()
            for r, w in zip(c.tangential, c.tangential_weights or (), strict=True):
                lam[r] /= w  # the scaled row's impulse is w lambda
            lam_parts.append(lam)
            modes.append(sol.modes[j])
            if sol.modes[j] == "separate":
                Jn = Jn[:0]
            Jt = Jt[[a for a, r in enumerate(c.tangential) if sol.stick[where[j] + r]]]
            j += 1
        normal_groups.append(Jn)
        tangential_groups.append(Jt)
    lam_all = np.concatenate(lam_parts)
    T_c, shares = energy_split(M, v, normal_groups + tangential_groups, redundant=True)
    v_plus = sol.velocity_post
    T = 0.5 * float(v @ M @ v)
    T_post = 0.5 * float(v_plus @ M @ v_plus)
    k = len(contacts)
    return ContactImpact(
        velocity_pre=v,
        velocity_post=v_plus,
        impulse=lam_all,
        generalized_impulse=np.vstack([c.jacobian for c in contacts]).T @ lam_all,
        modes=tuple(modes),
        contact_velocity_pre=tuple(c.jacobian @ v for c in contacts),
        contact_velocity_post=tuple(c.jacobian @ v_plus for c in contacts),
        T=T,
        T_c=T_c,
        T_a=T - T_c,
        T_post=T_post,
        energy_lost=T - T_post,
        T_c_normal=shares[:k],
        T_c_tangential=shares[k:],
        solutions=sol.solutions,
        exhaustive=sol.exhaustive,
        active_sets=sol.active_sets,
        restitution_law=law,
        impulse_unique=sol.impulse_unique,
        continuum=sol.continuum,
        velocity_range=sol.velocity_range,
        kkt_residual=sol.kkt_residual,
        _stop_unique=None if sol.exhaustive else sol.unique,
    )


# -- direct path: all contacts bilateral and inert ---------------------------------------------
#: The rank test of the direct path is skipped when a cheap lower bound on
#: ``(sigma_min / sigma_max)^2`` of the stacked rows exceeds this (the reference test rejects
#: ratios ``sigma_min / sigma_max <= 1e-12 max(k, n)``, about 1e-20 squared); otherwise the
#: reference's SVD test decides, so both paths accept and reject the same rows.
_RANK_CERTIFICATE = 1e-10


@dataclass(frozen=True, kw_only=True)
class InertLayout:
    """Row layout of contacts for the direct inert path and its nested energy split.

    Parameters
    ----------
    normal : sequence of sequence of int
        Per contact, indices (into that contact's rows) of its normal rows.
    tangential : sequence of sequence of int
        Per contact, indices of its tangential rows; with ``normal`` they partition the rows.

    Attributes
    ----------
    rows : tuple of int
        Rows ``k_i`` per contact; the stacked Jacobian has ``sum(rows)`` rows, contact after
        contact.
    slices : tuple of slice
        Each contact's rows within the stacked rows.
    order : ndarray of int, shape (k,)
        Stacked rows in the nesting order of the energy split: all normal rows (contact order),
        then all tangential rows (contact order).
    bounds : ndarray of int, shape (2 m + 1,)
        Boundaries of the ``2 m`` row groups within ``order`` (normal groups, then tangential).
    """

    normal: tuple[tuple[int, ...], ...]
    tangential: tuple[tuple[int, ...], ...]
    rows: tuple[int, ...] = field(init=False)
    slices: tuple[slice, ...] = field(init=False, repr=False, compare=False)
    order: NDArray[np.intp] = field(init=False, repr=False, compare=False)
    bounds: NDArray[np.intp] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        nrm = tuple(tuple(int(i) for i in g) for g in self.normal)
        tan = tuple(tuple(int(i) for i in g) for g in self.tangential)
        if len(nrm) != len(tan) or not nrm:
            raise ImpactInputError("give normal and tangential rows for every contact")
        rows, order_n, order_t, sizes = [], [], [], []
        start = 0
        for j, (n_j, t_j) in enumerate(zip(nrm, tan, strict=True)):
            k = len(n_j) + len(t_j)
            if not n_j or sorted(n_j + t_j) != list(range(k)):
                raise ImpactInputError(
                    f"contact {j}: normal {n_j} and tangential {t_j} rows must partition its "
                    "rows, with at least one normal row"
                )
            rows.append(k)
            order_n += [start + i for i in n_j]
            order_t += [start + i for i in t_j]
            start += k
        sizes = [len(g) for g in nrm] + [len(g) for g in tan]
        object.__setattr__(self, "normal", nrm)
        object.__setattr__(self, "tangential", tan)
        object.__setattr__(self, "rows", tuple(rows))
        ends = np.cumsum(rows)
        object.__setattr__(self, "slices", tuple(
            slice(int(e) - r, int(e)) for e, r in zip(ends, rows, strict=True)))
        order = np.array(order_n + order_t, dtype=np.intp)
        bounds = np.concatenate(([0], np.cumsum(sizes))).astype(np.intp)
        order.setflags(write=False)
        bounds.setflags(write=False)
        object.__setattr__(self, "order", order)
        object.__setattr__(self, "bounds", bounds)

    @classmethod
    def of(cls, contacts: Sequence[ContactRows]) -> InertLayout:
        """Layout of ``contacts`` (their normal and tangential rows)."""
        return cls(normal=tuple(c.normal for c in contacts),
                   tangential=tuple(c.tangential for c in contacts))

    @property
    def k(self) -> int:
        """Total number of rows."""
        return self.slices[-1].stop

    def group_energies(self, y: FloatArray) -> FloatArray:
        """``1/2 |y_g|^2`` for every row group ``g``: shape (..., 2 m) from ``y`` (..., k)."""
        pad = np.concatenate((y * y, np.zeros((*y.shape[:-1], 1))), axis=-1)
        out = 0.5 * np.add.reduceat(pad, self.bounds[:-1], axis=-1)
        # reduceat gives the element at the boundary for an empty group: those are zero.
        empty = self.bounds[1:] == self.bounds[:-1]
        if np.any(empty):
            out[..., empty] = 0.0
        return np.asarray(out)


def _certified_full_rank(A: FloatArray) -> bool:
    """Cheap sufficient test that ``A`` (k, n) passes the reference SVD rank test.

    ``(sigma_min / sigma_max)^2 >= 1 / (||L^-1||_F^2 ||A||_F^2)`` with ``A A^T = L L^T``.
    """
    G = A @ A.T
    L, info = scipy.linalg.lapack.dpotrf(G, lower=1, clean=1)
    if info != 0:
        return False
    Li, info = scipy.linalg.lapack.dtrtri(L, lower=1)
    if info != 0:
        return False
    denom = float(np.einsum("ij,ij->", Li, Li)) * float(np.trace(G))
    return bool(np.isfinite(denom) and denom * _RANK_CERTIFICATE < 1.0)


def _check_rank_reference(A: FloatArray) -> None:
    """The reference path's rank test (an SVD), run only when no certificate is at hand."""
    sv = np.linalg.svd(A, compute_uv=False)
    if sv[-1] <= 1e-12 * max(A.shape) * sv[0]:
        raise ImpactInputError("contact rows are rank deficient (redundant contacts?)")


def _inert_rows_check(M: FloatArray, v: FloatArray, A: FloatArray, layout: InertLayout) -> None:
    """Input checks of the direct path, with the reference path's messages."""
    n = M.shape[0]
    if A.ndim != 2 or A.shape[0] != layout.k:
        raise ImpactInputError(f"A must be ({layout.k}, n) for this layout, got {A.shape}")
    if A.shape[1] != n:
        raise ImpactInputError(f"contact jacobian has {A.shape[1]} columns, expected {n}")
    if not np.all(np.isfinite(A)):
        raise ImpactInputError("contact jacobian has non-finite entries")
    if v.shape != (n,) or not np.all(np.isfinite(v)):
        raise ImpactInputError(f"q_dot must be finite with shape ({n},), got {v.shape}")
    if A.shape[0] > n:
        raise ImpactInputError(f"{A.shape[0]} contact rows exceed the {n} coordinates")
    if not _certified_full_rank(A):
        _check_rank_reference(A)


def inert_velocity(M: ArrayLike, q_dot: ArrayLike, A: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``q_dot+`` and impulses of bilateral inert rows, nothing else (no checks, no energies).

    What ``pinocchio.impulseDynamics`` returns, by the algebra of :func:`inert_contact_impact`
    (LAPACK Cholesky of ``M`` and of ``W = A M^-1 A^T``).

    Parameters
    ----------
    M : array_like, shape (n, n)
        Mass matrix, symmetric positive definite.
    q_dot : array_like, shape (n,)
        Pre-impact velocities.
    A : array_like, shape (k, n)
        Constraint rows, full row rank.

    Returns
    -------
    q_dot_plus : ndarray, shape (n,)
    impulse : ndarray, shape (k,)
        In the row order of ``A``.

    Raises
    ------
    ImpactInputError
        If ``M`` is not positive definite or ``W`` is singular.
    """
    lapack = scipy.linalg.lapack
    A_ = np.asarray(A, dtype=float)
    v = np.asarray(q_dot, dtype=float)
    c, info = lapack.dpotrf(np.asarray(M, dtype=float), lower=1, clean=0)
    if info != 0:
        raise ImpactInputError("M is not positive definite")
    X, _ = lapack.dpotrs(c, A_.T, lower=1)
    W = A_ @ X
    Lw, info = lapack.dpotrf(0.5 * (W + W.T), lower=1, clean=1)
    if info != 0:
        raise ImpactInputError("contact rows are rank deficient (redundant contacts?)")
    lam, _ = lapack.dpotrs(Lw, (A_ @ v)[:, None], lower=1)
    lam = -lam[:, 0]
    return v + X @ lam, lam


def inert_contact_impact(
    M: ArrayLike,
    q_dot: ArrayLike,
    A: ArrayLike,
    layout: InertLayout,
    *,
    check: bool = True,
) -> ContactImpact:
    """Direct inert impact of bilateral contacts, with the nested energy split.

    The same numbers (to rounding) as :func:`resolve_contact_impact` with every contact
    bilateral, without its general machinery: one Cholesky factorization of ``M``, the
    Delassus matrix ``W = A M^-1 A^T`` with its rows in the nesting order of the energy split
    (:class:`InertLayout`), one Cholesky factorization of ``W``, and
    ``y = L_W^-1 A q_dot-``, ``lambda = -L_W^-T y``, ``q_dot+ = q_dot- + M^-1 A^T lambda``,
    ``T_c = 1/2 |y|^2`` (the nested shares are the squares of the segments of ``y``),
    ``T_a = T+ = 1/2 q_dot+^T M q_dot+``. It forms ``W`` (as ``pinocchio.impulseDynamics``
    does), so its relative accuracy is about ``cond(W)`` times the unit roundoff; for nearly
    redundant rows the reference path (QR, no ``W``) is the more accurate one.

    Parameters
    ----------
    M : array_like, shape (n, n)
        Mass matrix, symmetric positive definite (kg, kg m, kg m^2 entries).
    q_dot : array_like, shape (n,)
        Pre-impact velocities ``q_dot-`` (m/s, rad/s).
    A : array_like, shape (k, n)
        Rows of all contacts stacked in contact order (``k = layout.k``).
    layout : InertLayout
        Normal and tangential rows of every contact.
    check : bool
        Validate ``M`` (finite, symmetric), ``q_dot`` and the rank of ``A`` as
        :func:`resolve_contact_impact` does, with its messages (default True). Without checks a
        non-positive-definite ``M`` or a rank-deficient ``A`` still raises.

    Returns
    -------
    ContactImpact
        Every contact in mode ``"stick"`` (as the reference path reports).

    Raises
    ------
    ImpactInputError
        On malformed input, ``M`` not positive definite or rank-deficient rows.
    """
    M_ = np.asarray(M, dtype=float)
    v = np.asarray(q_dot, dtype=float)
    A_ = np.asarray(A, dtype=float)
    if check:
        if M_.ndim != 2 or M_.shape[0] != M_.shape[1]:
            raise ImpactInputError(f"M must be (n, n), got {M_.shape}")
        if not np.all(np.isfinite(M_)):
            raise ImpactInputError("M contains non-finite values")
        scale = float(np.abs(M_).max()) if M_.size else 1.0
        if np.abs(M_ - M_.T).max() > 1e-10 * scale:
            raise ImpactInputError("M is not symmetric")
    lapack = scipy.linalg.lapack
    c, info = lapack.dpotrf(M_, lower=1, clean=0)
    if info != 0:
        raise ImpactInputError("M is not positive definite")
    if check:
        _inert_rows_check(M_, v, A_, layout)
    Ap = A_[layout.order]
    X, _ = lapack.dpotrs(c, Ap.T, lower=1)  # M^-1 A^T, (n, k)
    W = Ap @ X
    W = 0.5 * (W + W.T)
    Lw, info = lapack.dpotrf(W, lower=1, clean=1)
    if info != 0:
        raise ImpactInputError("contact rows are rank deficient (redundant contacts?)")
    y2, _ = lapack.dtrtrs(Lw, (Ap @ v)[:, None], lower=1)
    lam2, _ = lapack.dtrtrs(Lw, y2, lower=1, trans=1)
    y, lam_p = y2[:, 0], -lam2[:, 0]
    v_plus = v + X @ lam_p
    lam = np.empty_like(lam_p)
    lam[layout.order] = lam_p
    shares = layout.group_energies(y)
    m = len(layout.rows)
    T = 0.5 * float(v @ (M_ @ v))
    T_post = 0.5 * float(v_plus @ (M_ @ v_plus))
    u_pre, u_post = A_ @ v, A_ @ v_plus
    return ContactImpact(
        velocity_pre=v,
        velocity_post=v_plus,
        impulse=lam,
        generalized_impulse=A_.T @ lam,
        modes=tuple("stick" for _ in range(m)),
        contact_velocity_pre=tuple(u_pre[sl] for sl in layout.slices),
        contact_velocity_post=tuple(u_post[sl] for sl in layout.slices),
        T=T,
        T_c=float(shares.sum()),
        T_a=T_post,
        T_post=T_post,
        energy_lost=T - T_post,
        T_c_normal=shares[:m],
        T_c_tangential=shares[m:],
    )


@dataclass(frozen=True, kw_only=True)
class InertImpactBatch(ResultDictMixin):
    """Direct inert impacts of bilateral contacts over a batch of configurations.

    Attributes
    ----------
    velocity_pre, velocity_post : ndarray, shape (..., n)
        ``q_dot-`` and ``q_dot+``.
    impulse : ndarray, shape (..., k)
        Constraint impulses of all rows in contact order (N s, N m s).
    T, T_c, T_a, T_post, energy_lost : ndarray, shape (...)
        As :class:`ContactImpact` (J); ``T_a = T_post`` and ``energy_lost = T_c`` (inert law).
    T_c_normal, T_c_tangential : ndarray, shape (..., m)
        Per-contact normal and tangential shares of ``T_c`` (J).
    """

    velocity_pre: FloatArray
    velocity_post: FloatArray
    impulse: FloatArray
    T: FloatArray
    T_c: FloatArray
    T_a: FloatArray
    T_post: FloatArray
    energy_lost: FloatArray
    T_c_normal: FloatArray
    T_c_tangential: FloatArray


def _solve_stack(a: FloatArray, b: FloatArray) -> FloatArray:
    return np.asarray(np.linalg.solve(a, b))


def inert_velocity_batch(
    Ms: ArrayLike, q_dots: ArrayLike, As: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``q_dot+`` and impulses of bilateral inert rows, batched (no checks, no energies).

    What ``pinocchio.impulseDynamics`` returns, with numpy's batched solvers:
    ``X = M^-1 A^T``, ``W = A X = L_W L_W^T``, ``y = L_W^-1 A q_dot-``,
    ``lambda = -L_W^-T y``, ``q_dot+ = q_dot- + X lambda``.

    Parameters
    ----------
    Ms : array_like, shape (B, n, n)
    q_dots : array_like, shape (B, n)
    As : array_like, shape (B, k, n)

    Returns
    -------
    q_dot_plus : ndarray, shape (B, n)
    impulse : ndarray, shape (B, k)
        In the row order of ``As``.
    y : ndarray, shape (B, k)
        ``L_W^-1 A q_dot-`` (``T_c = 1/2 |y|^2``; nested energies by segments).

    Raises
    ------
    ImpactInputError
        If ``M`` is singular or the rows are rank deficient.
    """
    M_ = np.asarray(Ms, dtype=float)
    v = np.asarray(q_dots, dtype=float)
    A_ = np.asarray(As, dtype=float)
    At = np.swapaxes(A_, -1, -2)
    try:
        X = _solve_stack(M_, At)
    except np.linalg.LinAlgError as exc:
        raise ImpactInputError("M is not positive definite") from exc
    W = A_ @ X
    W = 0.5 * (W + np.swapaxes(W, -1, -2))
    try:
        Lw = np.linalg.cholesky(W)
    except np.linalg.LinAlgError as exc:
        raise ImpactInputError("contact rows are rank deficient (redundant contacts?)") from exc
    b = (A_ @ v[..., None])
    y = _solve_stack(np.asarray(Lw, dtype=float), b)
    lam = -_solve_stack(np.asarray(np.swapaxes(Lw, -1, -2), dtype=float), y)
    v_plus = v + (X @ lam)[..., 0]
    return v_plus, lam[..., 0], y[..., 0]


def check_inert_batch(
    Ms: FloatArray, q_dots: FloatArray, As: FloatArray, *, symmetric: bool = False
) -> None:
    """Checks of the batched direct path: finite, symmetric and positive-definite ``M``,
    full-rank rows (the reference SVD test where a cheap certificate is not at hand).

    Parameters
    ----------
    Ms : ndarray, shape (B, n, n)
    q_dots : ndarray, shape (B, n)
    As : ndarray, shape (B, k, n)
    symmetric : bool
        ``M`` is symmetric by construction (skip that test).

    Raises
    ------
    ImpactInputError
        With the reference path's messages.
    """
    B, k, n = As.shape
    for name, arr in (("M", Ms), ("q_dot", q_dots), ("contact jacobian", As)):
        if not np.isfinite(arr).all():
            raise ImpactInputError(f"{name} contains non-finite values")
    if not symmetric:
        scale = np.abs(Ms).max(axis=(-2, -1), keepdims=True)
        if np.any(np.abs(Ms - np.swapaxes(Ms, -1, -2)) > 1e-10 * scale):
            raise ImpactInputError("M is not symmetric")
    try:
        np.linalg.cholesky(Ms)
    except np.linalg.LinAlgError as exc:
        raise ImpactInputError("M is not positive definite") from exc
    if k > n:
        raise ImpactInputError(f"{k} contact rows exceed the {n} coordinates")
    G = As @ np.swapaxes(As, -1, -2)
    try:
        Li = np.linalg.inv(np.linalg.cholesky(G))
        denom = np.einsum("bij,bij->b", Li, Li) * np.trace(G, axis1=-2, axis2=-1)
        unsure = ~(np.isfinite(denom) & (denom * _RANK_CERTIFICATE < 1.0))
    except np.linalg.LinAlgError:
        unsure = np.ones(B, dtype=bool)
    if np.any(unsure):
        sv = np.linalg.svd(As[unsure], compute_uv=False)
        if np.any(sv[:, -1] <= 1e-12 * max(k, n) * sv[:, 0]):
            raise ImpactInputError("contact rows are rank deficient (redundant contacts?)")


def inert_contact_impact_batch(
    Ms: ArrayLike,
    q_dots: ArrayLike,
    As: ArrayLike,
    layout: InertLayout,
    *,
    check: bool = True,
) -> InertImpactBatch:
    """:func:`inert_contact_impact` vectorised over a batch (numpy's stacked solvers).

    Parameters
    ----------
    Ms : array_like, shape (B, n, n)
        Mass matrices, symmetric positive definite.
    q_dots : array_like, shape (B, n)
        Pre-impact velocities (m/s, rad/s).
    As : array_like, shape (B, k, n)
        Rows of all contacts, stacked in contact order (``k = layout.k``).
    layout : InertLayout
    check : bool
        Validate finiteness, symmetry and definiteness of ``M`` and the rank of the rows
        (the reference test where no cheap certificate is at hand); default True.

    Returns
    -------
    InertImpactBatch

    Raises
    ------
    ImpactInputError
        On malformed input, ``M`` not positive definite or rank-deficient rows.
    """
    M_ = np.asarray(Ms, dtype=float)
    v = np.asarray(q_dots, dtype=float)
    A_ = np.asarray(As, dtype=float)
    if M_.ndim != 3 or A_.ndim != 3 or v.ndim != 2:
        raise ImpactInputError(
            f"need Ms (B, n, n), q_dots (B, n), As (B, k, n); got {M_.shape}, {v.shape}, "
            f"{A_.shape}"
        )
    B, n = v.shape
    if M_.shape != (B, n, n) or A_.shape != (B, layout.k, n):
        raise ImpactInputError(
            f"shapes disagree: Ms {M_.shape}, q_dots {v.shape}, As {A_.shape} (k={layout.k})"
        )
    if check:
        check_inert_batch(M_, v, A_)
    Ap = A_[:, layout.order]
    v_plus, lam_p, y = inert_velocity_batch(M_, v, Ap)
    lam = np.empty_like(lam_p)
    lam[:, layout.order] = lam_p
    shares = layout.group_energies(y)
    m = len(layout.rows)
    T = 0.5 * np.einsum("bi,bi->b", v, (M_ @ v[..., None])[..., 0])
    T_post = 0.5 * np.einsum("bi,bi->b", v_plus, (M_ @ v_plus[..., None])[..., 0])
    return InertImpactBatch(
        velocity_pre=v,
        velocity_post=v_plus,
        impulse=lam,
        T=T,
        T_c=shares.sum(axis=-1),
        T_a=T_post,
        T_post=T_post,
        energy_lost=T - T_post,
        T_c_normal=shares[:, :m],
        T_c_tangential=shares[:, m:],
    )
