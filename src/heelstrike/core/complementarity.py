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

The second solver here, :func:`solve_point_contacts`, is the exact law of striking contacts
with Coulomb friction (a pyramid cone), Newton or energetic restitution, rows of any rank, and
every outcome reported (issue #34): whether ``q_dot+`` and the impulses are unique, decided by
the enumeration of the active sets and the null directions of each set's Delassus system,
and a KKT certificate of the returned outcome. :mod:`heelstrike.core.contact_laws` (every
striking contact: points, arcs, a sole's corners, a sole held flat) and the robots use it.

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
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.impact import ImpactInputError, ImpactResult, impact

__all__ = [
    "ENUMERATION_BUDGET",
    "PAINLEVE_FRICTION",
    "UNIQUENESS_TOLERANCE",
    "CandidateContact",
    "ContactMode",
    "MultiContactImpact",
    "PointContactSolution",
    "RestitutionLaw",
    "resolve_impact",
    "solve_point_contacts",
]

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


# -- unilateral contacts: exact active sets, pyramid friction, two restitution laws ------------
RestitutionLaw = Literal["newton", "energetic"]

#: Active sets :func:`solve_point_contacts` enumerates at most; above it one solution is found by
#: Lemke's pivoting method and the enumeration bound is reported instead of the outcome count.
ENUMERATION_BUDGET = 20_000

_SEP = -9  # code of a separating contact in an active set
_FREE_T = 2  # code of a frictionless contact's tangential row (impulse zero, velocity free)

#: Friction coefficient an unbounded cone takes where no stick/separate outcome exists and the
#: exact large-friction limit has more active sets than the enumeration budget (Lemke's method
#: then gives one outcome of the law with this finite coefficient).
PAINLEVE_FRICTION = 1e4

#: Relative size (of the largest impulse) below which an interval of impulses or of velocities
#: along a null direction of an active set counts as a single point (round-off).
UNIQUENESS_TOLERANCE = 1e-8


@dataclass(frozen=True, kw_only=True)
class PointContactSolution(ResultDictMixin):
    """Outcome of :func:`solve_point_contacts`.

    Attributes
    ----------
    velocity_post : ndarray, shape (n,)
        ``q_dot+`` of the returned outcome (m/s, rad/s).
    impulse : ndarray, shape (m, 3)
        Per contact ``(lambda_n, lambda_t1, lambda_t2)`` (N s): normal, then tangential rows.
    bilateral_impulse : ndarray, shape (k_b,)
        Least-norm impulses of the bilateral rows (N s).
    modes : tuple of str
        ``"stick"``, ``"slip"`` (some tangential row slides, or a frictionless contact pressed)
        or ``"separate"`` per contact; for the energetic law, those of the compression phase.
    stick_rows : ndarray of bool, shape (m, 2)
        Tangential rows held at zero velocity (active in ``T_c``).
    solutions : tuple of ndarray
        ``q_dot+`` of every distinct outcome found, the returned one first; where an active
        set admits a continuum of outcomes, its finite ends are included.
    exhaustive : bool
        Whether every active set was examined (then ``solutions`` holds all outcomes).
    active_sets : int
        Number of active sets of the law (the bound on the number of outcomes).
    restitution_law : str
        ``"newton"`` or ``"energetic"``.
    compression_velocity : ndarray, shape (n,)
        ``q_dot`` at the end of compression (the ``e = 0`` outcome; equal to ``velocity_post``
        for Newton's law with ``e = 0``).
    unique : bool or None
        Whether ``q_dot+`` is determined by the law: one distinct outcome and no active set
        with a continuum of them (:attr:`continuum`); None when the enumeration was not
        exhaustive, except for an inelastic impact (``e = 0``) that normal impulses alone can
        stop (``-M q_dot- = N^T y + A_b^T y_b``, ``y >= 0``, a verified LP certificate): then
        ``q_dot+ = 0`` is the only outcome (every outcome has ``q_dot+^T M q_dot+ <= q_dot+^T
        M q_dot- <= 0``), True.
    impulse_unique : bool or None
        Whether the contact impulses are determined too (False: the split of the impulse
        between redundant contacts is not, e.g. a rigid body landing on two soles); None when
        the enumeration was not exhaustive, except False where the stop certificate exhibits
        a second impulse (two soles' corners landing flat).
    continuum : bool
        Some consistent active set admits a segment of outcomes (its Delassus system is
        singular along a direction that moves ``q_dot+``, a Painlevé-type case).
    velocity_range : ndarray, shape (2, n)
        Componentwise smallest and largest ``q_dot+`` over the outcomes found and the
        continua (``-inf``/``inf`` where a continuum is unbounded).
    kkt_residual : float
        Certificate of the returned outcome, checked in the full coordinates (no Delassus
        matrix): the largest violation, relative to the impulse and velocity scales, of the
        momentum balance ``M (q_dot+ - q_dot-) = R^T lambda + A_b^T lambda_b``,
        ``A_b q_dot+ = 0``, ``lambda_n >= 0``, ``u_n+ >= tau``, ``lambda_n (u_n+ - tau) = 0``,
        the cone ``|lambda_t| <= mu lambda_n``, ``lambda_t u_t+ <= 0`` with ``lambda_t`` on the
        cone's edge where ``u_t+ != 0`` (compression phase for the energetic law).
    """

    velocity_post: FloatArray
    impulse: FloatArray
    bilateral_impulse: FloatArray
    modes: tuple[ContactMode, ...]
    stick_rows: NDArray[np.bool_]
    solutions: tuple[FloatArray, ...]
    exhaustive: bool
    active_sets: int
    restitution_law: RestitutionLaw
    compression_velocity: FloatArray
    unique: bool | None
    impulse_unique: bool | None
    continuum: bool
    velocity_range: FloatArray
    kkt_residual: float


@dataclass(frozen=True)
class _Reduced:
    """The problem after eliminating the bilateral rows (pseudo-inverse Schur complement)."""

    YR: FloatArray  # Y R^T, Y = M^-1 - X_b W_bb^+ X_b^T (M^-1 on ker A_b), (n, k)
    X_R: FloatArray  # M^-1 R^T, (n, k)
    X_b: FloatArray  # M^-1 A_b^T, (n, k_b)
    Wb_pinv: FloatArray  # W_bb^+, (k_b, k_b)
    A_b: FloatArray
    R: FloatArray  # stacked contact rows (k, n)
    G: FloatArray  # R Y R^T, (k, k)


@dataclass(frozen=True)
class _Layout:
    """Rows of each unilateral contact within the stacked rows ``R`` (k, n).

    ``principal[i]``: the normal row along which contact ``i`` pushes and may separate;
    ``extra[i]``: further normal rows held (any impulse) while it is active (a sole held
    flat); ``tangential[i]``: its friction rows, scaled so that the cone is
    ``|lambda_t| <= mu lambda_n`` per row.
    """

    principal: tuple[int, ...]
    extra: tuple[tuple[int, ...], ...]
    tangential: tuple[tuple[int, ...], ...]

    def normal_rows(self, i: int) -> tuple[int, ...]:
        return (self.principal[i], *self.extra[i])


def _pinv_psd(W: FloatArray) -> FloatArray:
    """Moore-Penrose inverse of a symmetric PSD matrix (eigenvalues below 1e-12 of the top: 0)."""
    if W.size == 0:
        return np.zeros_like(W)
    w, Q = np.linalg.eigh(0.5 * (W + W.T))
    keep = w > 1e-12 * max(float(w.max()), 1e-300)
    return np.asarray((Q[:, keep] / w[keep]) @ Q[:, keep].T)


def _reduce(M: FloatArray, A_b: FloatArray, R: FloatArray) -> _Reduced:
    import scipy.linalg  # here: a walk's heel strike imports no scipy.linalg (issue 9.6)

    kb = A_b.shape[0]
    try:
        cho = scipy.linalg.cho_factor(M)
    except np.linalg.LinAlgError as exc:
        raise ImpactInputError("M is not positive definite") from exc
    X = scipy.linalg.cho_solve(cho, np.vstack((A_b, R)).T)  # M^-1 [A_b^T, R^T]
    X_b, X_R = X[:, :kb], X[:, kb:]
    if kb:
        W_bb = A_b @ X_b
        Wp = _pinv_psd(0.5 * (W_bb + W_bb.T))
        YR = X_R - X_b @ (Wp @ (A_b @ X_R))
    else:
        Wp, YR = np.zeros((0, 0)), X_R
    G = R @ YR
    return _Reduced(YR=YR, X_R=X_R, X_b=X_b, Wb_pinv=Wp, A_b=A_b, R=R, G=0.5 * (G + G.T))


_Modes = Sequence[tuple[int, ...] | int]


def _options(mu: float, k_t: int, limit: bool = False) -> list[tuple[int, ...] | int]:
    """Active sets of one contact: separate, or active with each tangential row sticking (0)
    or sliding with ``u_t >= 0`` (+1, ``lambda_t = -mu lambda_n``) or ``u_t <= 0`` (-1).
    ``limit``: an unbounded cone in its large-friction limit (the rows may slide)."""
    if k_t == 0 or mu == 0.0:
        return [_SEP, (_FREE_T,) * k_t]  # frictionless: tangential impulses zero
    if np.isinf(mu) and not limit:
        return [_SEP, (0,) * k_t]
    return [_SEP, *itertools.product((0, 1, -1), repeat=k_t)]


@dataclass
class _SetSolution:
    """One consistent active set: row impulses ``f`` (k,), and what its null directions allow."""

    f: FloatArray
    fb: FloatArray  # f with each contact's bound variable at its principal row (see _try_set)
    key: tuple[int, int]  # (sliding rows, active contacts): the order of preference
    impulse_free: bool  # impulses can move along a null direction without moving q_dot+
    ends: list[FloatArray]  # row impulses at the finite ends of a continuum of q_dot+
    unbounded: list[FloatArray]  # generalized-velocity directions of unbounded continua


def _in_limit(limit: bool, md: tuple[int, ...]) -> bool:
    """Whether an active contact of an unbounded cone is in its large-friction limit: it may
    be (``limit``) and some row slides (sticking, it is the ordinary unbounded cone)."""
    return limit and any(a in (1, -1) for a in md)


def _constraints(
    lay: _Layout, modes: _Modes, mu: FloatArray, limit: NDArray[np.bool_],
) -> list[tuple[str, int, int, float]]:
    """The inequalities of an active set: ``(kind, row, sign, mu)`` with kinds ``"n"``
    (``lambda >= 0``), ``"c"`` (``mu lambda_n + sign lambda_t >= 0``), ``"s"`` (``sign u >=
    0``), ``"g"`` (``u - tau >= 0``)."""
    out: list[tuple[str, int, int, float]] = []
    for i, md in enumerate(modes):
        p = lay.principal[i]
        if md == _SEP:
            out.append(("g", p, 1, 0.0))
            continue
        assert isinstance(md, tuple)
        out.append(("n", p, 1, 0.0))
        lim = _in_limit(bool(limit[i]), md)
        for a, r in enumerate(lay.tangential[i]):
            if md[a] == 0 and (np.isfinite(mu[i]) or lim):
                c = 1.0 if lim else float(mu[i])  # the limit's bound is nu = mu lambda_n
                out += [("c", r, 1, c), ("c", r, -1, c)]
            elif md[a] in (1, -1):
                out.append(("s", r, md[a], 0.0))
    return out


def _values(cons: list[tuple[str, int, int, float]], lay: _Layout, f: FloatArray,
            fb: FloatArray, u: FloatArray, tau: FloatArray) -> FloatArray:
    """Each inequality's value (>= 0 when it holds) at impulses ``f`` (bound variables ``fb``)
    and velocities ``u``; ``tau`` is 0 for the directions (differences)."""
    principal = {r: p for p, ts in zip(lay.principal, lay.tangential, strict=True) for r in ts}
    vals = np.empty(len(cons))
    for j, (kind, r, s, m_) in enumerate(cons):
        if kind == "n":
            vals[j] = fb[r]
        elif kind == "c":
            vals[j] = m_ * fb[principal[r]] + s * f[r]
        elif kind == "s":
            vals[j] = s * u[r]
        else:
            vals[j] = u[r] - tau[r]
    return vals


def _interval(g: FloatArray, h: FloatArray, gtol: FloatArray) -> tuple[float, float]:
    """The ``t`` with ``g + t h >= 0`` for all inequalities (``g`` within ``-gtol`` counts as
    tight), ``(lo, hi)``; empty when ``lo > hi``."""
    lo, hi = -np.inf, np.inf
    g = np.maximum(g, 0.0)
    for gj, hj, tj in zip(g, h, gtol, strict=True):
        if hj > tj * 1e-3 + 1e-300 or hj < -(tj * 1e-3 + 1e-300):
            t = -gj / hj
            if hj > 0:
                lo = max(lo, t)
            else:
                hi = min(hi, t)
    return lo, hi


def _try_set(
    red: _Reduced, u0: FloatArray, tau: FloatArray, mu: FloatArray, lay: _Layout,
    modes: _Modes, vtol: float, limit: NDArray[np.bool_],
) -> _SetSolution | None:
    """The active set ``modes`` if it is consistent, else None.

    Unknowns: ``lambda_n`` of active contacts, the impulses of their extra normal rows and of
    their sticking tangential rows; generalized directions ``B`` (a sliding row adds ``-s mu``
    times its row to the normal one), constrained rows ``C`` (normal rows with targets
    ``tau``, sticking rows with target 0): ``K x = C Y B^T x = tau - C v0``. Sets whose bounded
    impulses (normal, and tangential ones of a finite cone) have directions ``Y B^T``
    dependent modulo those of the free ones (extra normal rows, sticking rows of an unbounded
    cone) are skipped: by Caratheodory's theorem such an outcome is also that of a smaller set
    (move along the dependence until an impulse reaches a bound). Redundant free impulses take
    their least-norm values.

    A sliding contact of an unbounded cone in the large-friction limit (``limit``) takes ``nu =
    mu lambda_n`` as its bound variable: its direction is the sliding rows' ``-s`` alone
    (``lambda_n = nu / mu -> 0``), its sticking rows are bounded by ``|lambda_t| <= nu``,
    ``nu >= 0``; sticking entirely, it is the ordinary unbounded cone.

    Null directions ``z`` of ``K`` (the Delassus matrix restricted to the set) are examined
    one by one: along ``z`` the inequalities allow an interval of ``t`` (exact linear
    bounds); where it is more than a point, the impulses (``Y B^T z = 0``) or ``q_dot+``
    (otherwise: a continuum, whose finite ends are returned) are not unique.
    """
    k = u0.shape[0]
    cols_B: list[FloatArray] = []
    rows_C: list[int] = []
    target: list[float] = []
    free: list[bool] = []  # impulses free of any bound
    bound_col: dict[int, int] = {}  # principal row -> column of a limit contact's nu
    for i, md in enumerate(modes):
        if md == _SEP:
            continue
        assert isinstance(md, tuple)
        lim = _in_limit(bool(limit[i]), md)
        b = np.zeros(k)
        b[lay.principal[i]] = 0.0 if lim else 1.0
        for a, r in enumerate(lay.tangential[i]):
            if md[a] in (1, -1):
                b[r] = -md[a] * (1.0 if lim else mu[i])
        if lim:
            bound_col[lay.principal[i]] = len(cols_B)
        cols_B.append(b)
        rows_C.append(lay.principal[i])
        target.append(float(tau[lay.principal[i]]))
        free.append(False)
        for r in lay.extra[i]:
            e = np.zeros(k)
            e[r] = 1.0
            cols_B.append(e)
            rows_C.append(r)
            target.append(float(tau[r]))
            free.append(True)
        for a, r in enumerate(lay.tangential[i]):
            if md[a] == 0:
                e = np.zeros(k)
                e[r] = 1.0
                cols_B.append(e)
                rows_C.append(r)
                target.append(0.0)
                free.append(bool(np.isinf(mu[i])) and not lim)
    G = red.G
    SB = np.zeros((0, k))
    Vt = np.zeros((0, 0))
    r_K = 0
    if cols_B:
        SB = np.array(cols_B)
        GB = G @ SB.T  # (k, p)
        K = GB[rows_C]
        rhs = np.array(target) - u0[rows_C]
        # least-norm solution by the SVD: free impulses redundant (the same q_dot+), or a
        # sliding set's K singular (then the null directions are examined below)
        U, sv, Vt = np.linalg.svd(K)
        big = max(float(sv[0]) if sv.size else 0.0, float(np.max(np.abs(GB))))  # K's scale
        r_K = int(np.sum(sv > 1e-10 * max(big, 1e-300)))
        x = Vt[:r_K].T @ ((U[:, :r_K].T @ rhs) / sv[:r_K])
        if not np.all(np.isfinite(x)) or np.max(np.abs(K @ x - rhs), initial=0.0) > vtol:
            return None
        f = SB.T @ x
    else:
        f = np.zeros(k)

    def bounds(f: FloatArray, x: FloatArray) -> FloatArray:
        fb = f.copy()
        for p, j in bound_col.items():
            fb[p] = x[j]
        return fb

    fb = bounds(f, x) if cols_B else f
    u = u0 + G @ f
    fscale = max(float(np.max(np.abs(f), initial=0.0)), float(np.max(np.abs(fb), initial=0.0)))
    ftol = 1e-9 * fscale + 1e-300
    cons = _constraints(lay, modes, mu, limit)
    vals = _values(cons, lay, f, fb, u, tau)
    tols = np.array([vtol if c[0] in ("s", "g") else ftol for c in cons])
    if np.any(vals < -tols):
        return None
    if cols_B:  # (tested last: the cheaper tests above reject most sets)
        H = SB @ GB
        F = np.flatnonzero(free)
        if _rank_psd(H) - _rank_psd(H[np.ix_(F, F)]) < len(free) - F.size:
            return None  # bounded impulses dependent modulo the free ones: a smaller set
    n_slip = sum(1 for md in modes if isinstance(md, tuple) for a in md if a in (1, -1))
    n_act = sum(1 for md in modes if md != _SEP)
    out = _SetSolution(f=f, fb=fb, key=(n_slip, n_act), impulse_free=False, ends=[],
                       unbounded=[])
    if not cols_B:
        return out
    # null directions of K: impulses (and maybe q_dot+) not fixed by the set's equations
    null = Vt[r_K:]
    if not null.shape[0]:
        return out
    D = red.YR @ SB.T  # (n, p): the velocity change of each unknown
    dscale = float(np.max(np.abs(D), initial=0.0)) + 1e-300
    for z in null:
        df = SB.T @ z
        dv = D @ z
        du = G @ df
        h = _values(cons, lay, df, bounds(df, z), du, np.zeros_like(tau))
        lo, hi = _interval(vals, h, tols)
        if not hi - lo > UNIQUENESS_TOLERANCE * max(fscale, 1e-300):
            continue
        if np.max(np.abs(dv)) <= 1e-10 * dscale:
            out.impulse_free = True
            continue
        for t in (lo, hi):
            if np.isfinite(t):
                out.ends.append(f + t * df)
            else:
                out.unbounded.append(np.sign(t) * dv)
    return out


def _rank_psd(H: FloatArray) -> int:
    """Numerical rank of a symmetric PSD matrix (eigenvalues above 1e-10 of the largest)."""
    if H.size == 0:
        return 0
    ev = np.linalg.eigvalsh(0.5 * (H + H.T))
    return int(np.sum(ev > 1e-10 * max(float(ev[-1]), 1e-300)))


def _lemke(Q: FloatArray, q: FloatArray, max_pivots: int = 10_000) -> FloatArray | None:
    """Lemke's complementary pivoting with the lexicographic ratio test (degeneracy-safe).

    Finds ``z >= 0`` with ``w = Q z + q >= 0`` and ``z^T w = 0``; None on ray termination.
    """
    N = q.shape[0]
    if np.all(q >= 0.0):
        return np.zeros(N)
    T = np.hstack((np.eye(N), -Q, -np.ones((N, 1)), q[:, None]))
    basis = list(range(N))
    # the first pivot by the same lexicographic rule: among the rows tied at the smallest
    # q_i, the lexicographically smallest (q_i, e_i) is the last one (a flat landing on
    # several corners ties them all; taking the first could end on a ray)
    tied = np.flatnonzero(q <= q.min() + 1e-12 * max(abs(float(q.min())), 1.0))
    entering, r = 2 * N, int(tied[-1])
    for _ in range(max_pivots):
        T[r] /= T[r, entering]
        for i in range(N):
            if i != r and T[i, entering] != 0.0:
                T[i] -= T[i, entering] * T[r]
        leaving, basis[r] = basis[r], entering
        if leaving == 2 * N:
            z = np.zeros(N)
            for i, b in enumerate(basis):
                if N <= b < 2 * N:
                    z[b - N] = T[i, -1]
            return z
        entering = leaving + N if leaving < N else leaving - N
        col = T[:, entering]
        cand = np.flatnonzero(col > 1e-12 * max(float(np.abs(col).max()), 1e-300))
        if cand.size == 0:
            return None
        for j in [2 * N + 1, *range(N)]:
            vals = T[cand, j] / col[cand]
            cand = cand[vals <= vals.min() + 1e-12 * max(abs(float(vals.min())), 1.0)]
            if cand.size == 1:
                break
        r = int(cand[0])
    return None


def _lemke_contacts(
    red: _Reduced, u0: FloatArray, tau: FloatArray, mu: FloatArray, lay: _Layout,
) -> FloatArray | None:
    """One outcome by Lemke's method on the pyramid-cone LCP (Stewart-Trinkle form).

    Per contact with finite ``mu > 0``: ``lambda_n``, ``beta_a+-`` per tangential row
    (tangential impulse ``beta+ - beta-``) and ``gamma_a`` (sliding speeds), with
    ``lambda_n _|_ u_n - tau``, ``beta+- _|_ +-u_t + gamma``, ``gamma _|_ mu lambda_n - beta+ -
    beta-``; frictionless contacts have ``lambda_n`` only. The matrix is copositive-plus, so
    the method ends with a solution. Contacts with extra normal rows are not an LCP (None).
    """
    k = u0.shape[0]
    if any(lay.extra):
        return None
    L: list[FloatArray] = []  # rows mapping u (k) to the velocity part of each w
    kinds: list[tuple[str, int, int]] = []
    for i, p in enumerate(lay.principal):
        e = np.zeros(k)
        e[p] = 1.0
        L.append(e)
        kinds.append(("n", i, p))
        if mu[i] > 0.0 and lay.tangential[i]:
            if np.isinf(mu[i]):
                return None
            for r in lay.tangential[i]:
                for s in (1.0, -1.0):
                    e = np.zeros(k)
                    e[r] = s
                    L.append(e)
                    kinds.append(("b", i, r))
            for r in lay.tangential[i]:
                L.append(np.zeros(k))
                kinds.append(("g", i, r))
    Lr = np.array(L)
    Q = Lr @ red.G @ Lr.T
    q = Lr @ u0
    idx_n = {i: j for j, (t, i, _) in enumerate(kinds) if t == "n"}
    for j, (t, i, r) in enumerate(kinds):
        if t == "n":
            q[j] -= tau[r]
        elif t == "b":
            g = next(jj for jj, kk in enumerate(kinds) if kk == ("g", i, r))
            Q[j, g] += 1.0
        else:
            Q[j, idx_n[i]] += mu[i]
            for jj, kk in enumerate(kinds):
                if kk == ("b", i, r):
                    Q[j, jj] -= 1.0
    z = _lemke(Q, q)
    if z is None:
        return None
    return np.asarray(Lr.T @ z)


def _modes_of(f: FloatArray, u: FloatArray, mu: FloatArray, lay: _Layout, ftol: float,
              vtol: float) -> tuple[list[ContactMode], NDArray[np.bool_]]:
    """Modes and sticking rows (k,) of an outcome: a contact with a normal impulse is active;
    its tangential rows stick where their velocity is zero (to ``vtol``), slide elsewhere."""
    modes: list[ContactMode] = []
    stick = np.zeros(f.shape[0], dtype=bool)
    for i, p in enumerate(lay.principal):
        ts = list(lay.tangential[i])
        if f[p] <= ftol:
            modes.append("separate")
        elif not ts or mu[i] == 0.0:
            modes.append("slip" if ts else "stick")
        else:
            stick[ts] = np.abs(u[ts]) <= vtol
            modes.append("stick" if stick[ts].all() else "slip")
    return modes, stick


def _inert_phase(
    red: _Reduced, u0: FloatArray, tau: FloatArray, mu: FloatArray, lay: _Layout,
    budget: int, vscale: float,
) -> tuple[list[_SetSolution], bool, int]:
    """Consistent active sets (exhaustive) or one outcome (Lemke), the flag and the bound.

    An unbounded cone whose stick/separate sets are all inconsistent (sticking would need a
    pull, separating would pass through: Painleve-type) takes the exact large-friction limit
    of the law: the contact slides with a vanishing normal impulse (``lambda_n = nu / mu ->
    0``) and a finite friction impulse (:func:`_try_set`). Where that limit has more active
    sets than ``budget``, Lemke's method gives one outcome with the large finite coefficient
    :data:`PAINLEVE_FRICTION`.
    """
    none = np.zeros(mu.shape[0], dtype=bool)
    found = _enumerate(red, u0, tau, mu, lay, budget, vscale, none)
    if found[0] or not np.any(np.isinf(mu)):
        return found
    found = _enumerate(red, u0, tau, mu, lay, budget, vscale, np.isinf(mu), lemke=False)
    if found[0] or found[1]:
        return found
    big = np.where(np.isinf(mu), PAINLEVE_FRICTION, mu)
    f = _lemke_contacts(red, u0, tau, big, lay)
    sets = [] if f is None else [_SetSolution(f, f, (0, 0), False, [], [])]
    return sets, False, found[2]


def _enumerate(
    red: _Reduced, u0: FloatArray, tau: FloatArray, mu: FloatArray, lay: _Layout,
    budget: int, vscale: float, limit: NDArray[np.bool_], lemke: bool = True,
) -> tuple[list[_SetSolution], bool, int]:
    opts = [_options(float(mu[i]), len(lay.tangential[i]), bool(limit[i]))
            for i in range(mu.shape[0])]
    count = int(np.prod([len(o) for o in opts]))
    scale = max(float(np.max(np.abs(u0), initial=0.0)),
                float(np.max(np.abs(tau), initial=0.0)), vscale, 1e-300)
    vtol = 1e-9 * scale
    if count <= budget:
        found: list[_SetSolution] = []
        for modes in itertools.product(*opts):
            sol = _try_set(red, u0, tau, mu, lay, modes, vtol, limit)
            if sol is not None:
                found.append(sol)
        found.sort(key=lambda s: s.key)
        return found, True, count
    if not lemke:
        return [], False, count
    f = _lemke_contacts(red, u0, tau, mu, lay)
    if f is None:
        raise ImpactInputError(
            f"{count} active sets exceed the enumeration budget ({budget}) and Lemke's method "
            "found no solution (an unbounded friction cone or a contact with several normal "
            "rows needs enumeration: give fewer contacts, a finite friction, or a sole as its "
            "corners)")
    return [_SetSolution(f, f, (0, 0), False, [], [])], False, count


_UNDECIDED = 9  # a contact's or a tangential row's mode not yet chosen in the mode tree
_ACTIVE = 1  # a contact pressed (its tangential rows' modes chosen further down the tree)


def _distinct(vs: list[FloatArray], scale: float) -> list[FloatArray]:
    out: list[FloatArray] = []
    for v in vs:
        if all(np.max(np.abs(v - w)) > 1e-8 * scale for w in out):
            out.append(v)
    return out


@dataclass(frozen=True)
class _Outcome:
    """What :func:`_solve_contacts` returns, in the stacked rows' order."""

    velocity_post: FloatArray
    impulse: FloatArray  # (k,) row impulses (scaled tangential rows)
    bilateral_impulse: FloatArray
    modes: tuple[ContactMode, ...]
    stick: NDArray[np.bool_]  # (k,)
    solutions: tuple[FloatArray, ...]
    exhaustive: bool
    active_sets: int
    compression_velocity: FloatArray
    unique: bool | None
    impulse_unique: bool | None
    continuum: bool
    velocity_range: FloatArray
    kkt_residual: float


def _kkt_residual(M: FloatArray, v: FloatArray, vc: FloatArray, R: FloatArray,
                  A_b: FloatArray, f: FloatArray, lam_b: FloatArray, tau: FloatArray,
                  mu: FloatArray, lay: _Layout) -> float:
    """Largest relative violation of the law by ``(vc, f, lam_b)`` in the full coordinates."""
    fs = max(float(np.max(np.abs(f), initial=0.0)), float(np.max(np.abs(lam_b), initial=0.0)),
             1e-300)
    u = R @ vc
    vs = max(float(np.max(np.abs(R @ v), initial=0.0)), float(np.max(np.abs(u), initial=0.0)),
             float(np.max(np.abs(tau), initial=0.0)), 1e-300)
    gen = R.T @ f + (A_b.T @ lam_b if A_b.shape[0] else 0.0)
    dp = M @ (vc - v)
    res = [float(np.max(np.abs(dp - gen))) / max(float(np.max(np.abs(dp))),
                                                   float(np.max(np.abs(gen))), 1e-300)]
    if A_b.shape[0]:
        res.append(float(np.max(np.abs(A_b @ vc))) / vs)
    for i, p in enumerate(lay.principal):
        ln = f[p]
        res += [max(-ln, 0.0) / fs, max(tau[p] - u[p], 0.0) / vs,
                abs(ln) * abs(u[p] - tau[p]) / (fs * vs)]
        if ln > 1e-9 * fs:
            res += [abs(u[r] - tau[r]) / vs for r in lay.extra[i]]
        for r in lay.tangential[i]:
            m_ = float(mu[i]) if np.isfinite(mu[i]) else np.inf
            res.append(max(abs(f[r]) - m_ * ln, 0.0) / fs if np.isfinite(m_) else 0.0)
            res.append(max(f[r] * u[r], 0.0) / (fs * vs))  # friction never does positive work
            if abs(u[r]) > 1e-9 * vs and np.isfinite(m_):  # sliding: on the cone's edge
                res.append(abs(f[r] + np.sign(u[r]) * m_ * ln) / fs)
    return float(max(res))


def _full_stop(
    M: FloatArray, v: FloatArray, R: FloatArray, lay: _Layout, A_b: FloatArray,
    v_plus: FloatArray, f: FloatArray, scale: float,
) -> tuple[bool | None, bool | None]:
    """``(unique, impulse_unique)`` of an inelastic impact not enumerated, where certified.

    Every outcome of the law with ``e = 0`` has ``lambda . u+ <= 0`` (normal complementarity,
    extra normal rows and bilateral rows held at zero velocity, friction never doing positive
    work), so ``q_dot+^T M q_dot+ <= q_dot+^T M q_dot-``. If normal impulses alone can stop
    the system, ``-M q_dot- = N^T y + A_b^T y_b`` with ``y >= 0`` on the principal normal rows
    ``N`` (Farkas), then ``q_dot+^T M q_dot- = -y . N q_dot+ <= 0`` for every outcome (its
    ``N q_dot+ >= 0``, ``A_b q_dot+ = 0``): ``q_dot+ = 0`` is the only outcome. ``y`` is found
    by :func:`scipy.optimize.linprog` (a feasibility LP) and the certificate is verified here
    (residual and signs). ``(y, 0)`` is itself an outcome's impulse: where the LP's smallest and
    largest ``y_0`` differ, or differ from the returned impulses ``f``, two impulses are
    exhibited and ``impulse_unique`` is False. (None, None) where not certified.
    """
    from scipy.optimize import linprog

    if np.max(np.abs(v_plus), initial=0.0) > 1e-9 * scale:
        return None, None
    P = list(lay.principal)
    A = np.hstack((R[P].T, A_b.T))  # (n, m + k_b)
    rhs = -M @ v
    s = float(np.max(np.abs(rhs), initial=0.0))
    if s == 0.0:
        return None, None
    m, kb = len(P), A_b.shape[0]
    bounds = [(0.0, None)] * m + [(None, None)] * kb
    ys: list[FloatArray] = []
    for sign in (1.0, -1.0):
        c = np.zeros(m + kb)
        c[0] = sign
        res = linprog(c, A_eq=A / s, b_eq=rhs / s, bounds=bounds, method="highs")
        if res.status != 0:
            return None, None
        y = np.asarray(res.x, dtype=float)
        ysc = max(float(np.max(np.abs(y))), 1e-300)
        if (np.max(np.abs(A @ y - rhs)) > 1e-9 * s
                or np.min(y[:m], initial=0.0) < -1e-12 * ysc):
            return None, None
        ys.append(y)
    fscale = max(float(np.max(np.abs(f), initial=0.0)), 1e-300)
    tol = 1e-6 * fscale  # far above the LP's round-off: two distinct impulses
    stop = np.zeros_like(f)
    for y in ys:
        stop[P] = y[:m]
        if np.max(np.abs(stop - f)) > tol:
            return True, False
    return True, None


def _solve_contacts(
    M: FloatArray, v: FloatArray, R: FloatArray, lay: _Layout, A_b: FloatArray,
    mu: FloatArray, e: FloatArray, law: RestitutionLaw, budget: int,
) -> _Outcome:
    """The exact active-set law of unilateral contacts ``lay`` (rows ``R``) beside the
    bilateral rows ``A_b``: see :func:`solve_point_contacts` (whose contacts are points)."""
    n = M.shape[0]
    m = len(lay.principal)
    if law not in ("newton", "energetic"):
        raise ImpactInputError(f"restitution law must be newton or energetic, got {law!r}")
    red = _reduce(M, A_b, R)

    def free(x: FloatArray) -> FloatArray:  # x projected on ker A_b in the M metric
        if not A_b.shape[0]:
            return x.copy()
        return np.asarray(x - red.X_b @ (red.Wb_pinv @ (A_b @ x)))

    def post(x0: FloatArray, f: FloatArray) -> FloatArray:
        return np.asarray(x0 + red.YR @ f)

    v0 = free(v)
    u_pre = R @ v
    tau = np.zeros(R.shape[0])
    normal_e = np.zeros(R.shape[0])  # e of every normal row
    for i in range(m):
        p = lay.principal[i]
        normal_e[list(lay.normal_rows(i))] = e[i]
        if law == "newton":
            tau[p] = -e[i] * min(float(u_pre[p]), 0.0)
            for r in lay.extra[i]:
                tau[r] = -e[i] * u_pre[r]
    vscale = float(np.max(np.abs(u_pre), initial=0.0))
    sets, exhaustive, count = _inert_phase(red, R @ v0, tau, mu, lay, budget, vscale)
    if not sets:
        raise ImpactInputError("no consistent active set (please report this impact)")
    scale = max(float(np.sqrt(v @ M @ v / max(np.trace(M) / n, 1e-300))), 1e-300)
    T = 0.5 * float(v @ M @ v)

    def finish(f: FloatArray) -> tuple[FloatArray, FloatArray]:
        vc = post(v0, f)
        if law == "newton" or not np.any(e > 0.0):
            return vc, f
        fr = normal_e * f
        fr[[r for i in range(m) for r in lay.tangential[i]]] = 0.0
        d = red.YR @ fr
        d_norm2 = float(d @ M @ d)
        absorbed = max(T - 0.5 * float(vc @ M @ vc), 0.0)
        emax2 = float(np.max(e)) ** 2
        s = 1.0 if d_norm2 <= 2.0 * absorbed * emax2 else float(
            np.sqrt(2.0 * absorbed * emax2 / d_norm2))
        x = vc + s * d
        f3 = _inert_phase(red, R @ x, np.zeros_like(tau), mu, lay, budget, vscale)[0][0].f
        return post(x, f3), f + s * fr + f3

    finals = [finish(s.f) for s in sets]
    ends = [finish(fe)[0] for s in sets for fe in s.ends]
    sols = _distinct([vp for vp, _ in finals] + ends, scale)
    continuum = any(s.ends or s.unbounded for s in sets)
    v_plus, f_tot = finals[0]
    allv = np.array(sols)
    lo, hi = allv.min(axis=0), allv.max(axis=0)
    for s in sets:
        for dv in s.unbounded:
            big = np.abs(dv) > 1e-10 * max(float(np.max(np.abs(dv))), 1e-300)
            lo = np.where(big & (dv < 0), -np.inf, lo)
            hi = np.where(big & (dv > 0), np.inf, hi)
    unique = impulse_unique = None
    if exhaustive:
        unique = len(sols) == 1 and not continuum
        fscale = max(float(np.max(np.abs(sets[0].f), initial=0.0)), 1e-300)
        impulse_unique = not continuum and not any(s.impulse_free for s in sets) and all(
            np.max(np.abs(s.f - sets[0].f), initial=0.0) <= UNIQUENESS_TOLERANCE * fscale
            for s in sets)
    elif not np.any(e > 0.0):
        unique, impulse_unique = _full_stop(M, v, R, lay, A_b, v_plus, f_tot, scale)
    vc0 = post(v0, sets[0].f)
    u_c = R @ vc0
    ftol = 1e-9 * float(np.max(np.abs(sets[0].fb), initial=0.0)) + 1e-300
    vtol = 1e-9 * max(vscale, 1e-300)
    modes, stick = _modes_of(sets[0].fb, u_c, mu, lay, ftol, vtol)

    def bilateral(vp: FloatArray, f: FloatArray) -> FloatArray:
        if not A_b.shape[0]:
            return np.zeros(0)
        return np.asarray(-red.Wb_pinv @ (A_b @ (v + red.X_R @ f)))

    lam_b = bilateral(v_plus, f_tot)
    kkt = _kkt_residual(M, v, vc0, R, A_b, sets[0].f, bilateral(vc0, sets[0].f), tau, mu, lay)
    return _Outcome(
        velocity_post=v_plus, impulse=f_tot, bilateral_impulse=lam_b, modes=tuple(modes),
        stick=stick, solutions=tuple(sols), exhaustive=exhaustive, active_sets=count,
        compression_velocity=vc0, unique=unique, impulse_unique=impulse_unique,
        continuum=continuum, velocity_range=np.array([lo, hi]), kkt_residual=kkt)


def solve_point_contacts(
    M: ArrayLike,
    q_dot: ArrayLike,
    rows: ArrayLike,
    *,
    tangential: ArrayLike | None = None,
    bilateral: ArrayLike | None = None,
    friction: ArrayLike = np.inf,
    restitution: ArrayLike = 0.0,
    law: RestitutionLaw = "newton",
    budget: int = ENUMERATION_BUDGET,
) -> PointContactSolution:
    """Impact with unilateral point contacts (corners of a sole, points, arcs) and bilateral rows.

    Every contact ``i`` has one normal row ``n_i`` and up to two tangential rows ``t_i1,
    t_i2``; the friction cone is the **pyramid** ``|lambda_ta| <= mu_i lambda_n`` (each
    tangential row its own Coulomb law, maximum dissipation per row), so that the active sets
    are finite and enumerated exactly. Rank-deficient rows (two corners of one heel, a
    four-corner sole, a contact repeating a bilateral row) are allowed: ``q_dot+`` is unique
    where the law is (the kinetic-metric projection for ``e = 0``), impulses are not, and the
    returned ones are those of the smallest active set (Caratheodory), bilateral ones least
    norm (``W_bb^+``).

    Uniqueness is decided by the enumeration (when exhaustive): ``unique`` (``q_dot+``) is
    False when two consistent active sets give different ``q_dot+`` or when one admits a
    continuum (its Delassus system ``K`` singular along a direction that moves ``q_dot+`` and
    that the inequalities allow: exact linear bounds); ``impulse_unique`` is False when two
    sets give different impulses or a null direction of ``K`` moves impulses only (the split
    between redundant contacts). The returned outcome is certified by ``kkt_residual``.

    Laws (``u = J q_dot``, ``tau_i`` the normal target):

    - ``"newton"``: ``lambda_n >= 0 _|_ u_n+ - tau_i >= 0`` with ``tau_i = -e_i min(u_n-, 0)``;
      it can gain energy with sticking friction (Kane's paradox).
    - ``"energetic"``: a compression phase (the same law with ``e = 0``: ``q_dot_c``,
      normal impulses ``p_c``), then a rebound impulse ``s M_b^-1 N^T (e * p_c)`` with
      ``s = min(1, sqrt(2 (T - T_c)) / ||M_b^-1 N^T p_c||_M)`` (at most ``e^2`` of the
      energy absorbed in compression is returned; ``M_b^-1`` is ``M^-1`` on the bilateral
      rows' null space), then the ``e = 0`` law once more from that velocity (no corner ends
      moving into the ground, friction acts). ``T+ <= T_c_end + e^2 (T - T_c_end) <= T``.

    Parameters
    ----------
    M : array_like, shape (n, n)
        Mass matrix, SPD.
    q_dot : array_like, shape (n,)
        ``q_dot-`` (m/s, rad/s).
    rows : array_like, shape (m, n)
        Normal rows (separating-positive).
    tangential : array_like, shape (m, 2, n), optional
        Tangential rows; None: frictionless contacts.
    bilateral : array_like, shape (k_b, n), optional
        Persistent inert rows (any rank).
    friction, restitution : array_like, shape (m,) or scalar
        ``mu_i >= 0`` (inf: no slip) and ``e_i`` in [0, 1].
    law : {"newton", "energetic"}
    budget : int
        Largest number of active sets enumerated (``prod_i`` of 10 with finite friction, 2
        otherwise); above it Lemke's method gives one outcome (``exhaustive=False``).

    Returns
    -------
    PointContactSolution
    """
    M_ = np.asarray(M, dtype=float)
    v = np.asarray(q_dot, dtype=float)
    n = M_.shape[0]
    N_ = np.asarray(rows, dtype=float).reshape(-1, n)
    m = N_.shape[0]
    T_ = (np.zeros((m, 2, n)) if tangential is None
          else np.asarray(tangential, dtype=float).reshape(m, 2, n))
    A_b = np.zeros((0, n)) if bilateral is None else np.asarray(bilateral, float).reshape(-1, n)
    mu = np.broadcast_to(np.asarray(friction, dtype=float), (m,)).copy()
    e = np.broadcast_to(np.asarray(restitution, dtype=float), (m,)).copy()
    R = np.empty((3 * m, n))
    R[0::3], R[1::3], R[2::3] = N_, T_[:, 0], T_[:, 1]
    has_t = tangential is not None
    lay = _Layout(principal=tuple(3 * i for i in range(m)), extra=((),) * m,
                  tangential=tuple((3 * i + 1, 3 * i + 2) if has_t else () for i in range(m)))
    out = _solve_contacts(M_, v, R, lay, A_b, mu, e, law, budget)
    return PointContactSolution(
        velocity_post=out.velocity_post,
        impulse=out.impulse.reshape(m, 3),
        bilateral_impulse=out.bilateral_impulse,
        modes=out.modes,
        stick_rows=out.stick.reshape(m, 3)[:, 1:],
        solutions=out.solutions,
        exhaustive=out.exhaustive,
        active_sets=out.active_sets,
        restitution_law=law,
        compression_velocity=out.compression_velocity,
        unique=out.unique,
        impulse_unique=out.impulse_unique,
        continuum=out.continuum,
        velocity_range=out.velocity_range,
        kkt_residual=out.kkt_residual,
    )
