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

The second solver here, :func:`solve_point_contacts`, is the exact law of striking point
contacts with Coulomb friction (a pyramid cone), Newton or energetic restitution, rows of any
rank, and every outcome reported (issue #34); :mod:`heelstrike.core.contact_laws` and the
robots' sole polygons use it.

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


# -- unilateral point contacts: exact active sets, pyramid friction, two restitution laws ------
RestitutionLaw = Literal["newton", "energetic"]

#: Active sets :func:`solve_point_contacts` enumerates at most; above it one solution is found by
#: Lemke's pivoting method and the enumeration bound is reported instead of the outcome count.
ENUMERATION_BUDGET = 20_000

_SEP = -9  # code of a separating contact in an active set

#: Friction coefficient an unbounded cone takes where no stick/separate outcome exists.
PAINLEVE_FRICTION = 1e4


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
        ``q_dot+`` of every distinct outcome found, the returned one first.
    exhaustive : bool
        Whether every active set was examined (then ``solutions`` holds all outcomes).
    active_sets : int
        Number of active sets of the law (the bound on the number of outcomes).
    restitution_law : str
        ``"newton"`` or ``"energetic"``.
    compression_velocity : ndarray, shape (n,)
        ``q_dot`` at the end of compression (the ``e = 0`` outcome; equal to ``velocity_post``
        for Newton's law with ``e = 0``).
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

    @property
    def unique(self) -> bool | None:
        """True/False when the enumeration was exhaustive, None when it was not done."""
        return len(self.solutions) == 1 if self.exhaustive else None


@dataclass(frozen=True)
class _Reduced:
    """The problem after eliminating the bilateral rows (pseudo-inverse Schur complement)."""

    Y: FloatArray  # M^-1 restricted to ker A_b: M^-1 - X_b W_bb^+ X_b^T, (n, n)
    X_b: FloatArray  # M^-1 A_b^T, (n, k_b)
    Wb_pinv: FloatArray  # W_bb^+, (k_b, k_b)
    A_b: FloatArray
    R: FloatArray  # stacked point rows (3 m, n): normal, t1, t2 per contact
    G: FloatArray  # R Y R^T, (3 m, 3 m)


def _pinv_psd(W: FloatArray) -> FloatArray:
    """Moore-Penrose inverse of a symmetric PSD matrix (eigenvalues below 1e-12 of the top: 0)."""
    if W.size == 0:
        return np.zeros_like(W)
    w, Q = np.linalg.eigh(0.5 * (W + W.T))
    keep = w > 1e-12 * max(float(w.max()), 1e-300)
    return np.asarray((Q[:, keep] / w[keep]) @ Q[:, keep].T)


def _reduce(M: FloatArray, A_b: FloatArray, R: FloatArray) -> _Reduced:
    import scipy.linalg  # here: a walk's heel strike imports no scipy.linalg (issue 9.6)

    n = M.shape[0]
    try:
        cho = scipy.linalg.cho_factor(M)
    except np.linalg.LinAlgError as exc:
        raise ImpactInputError("M is not positive definite") from exc
    Minv = scipy.linalg.cho_solve(cho, np.eye(n))
    Minv = 0.5 * (Minv + Minv.T)
    X_b = Minv @ A_b.T
    Wp = _pinv_psd(A_b @ X_b) if A_b.shape[0] else np.zeros((0, 0))
    Y = Minv - X_b @ Wp @ X_b.T
    Y = 0.5 * (Y + Y.T)
    G = R @ Y @ R.T
    return _Reduced(Y=Y, X_b=X_b, Wb_pinv=Wp, A_b=A_b, R=R, G=0.5 * (G + G.T))


def _options(mu: float, has_t: bool) -> list[tuple[int, int] | int]:
    """Active sets of one contact: separate, or active with each tangential row sticking (0)
    or sliding with ``u_t >= 0`` (+1, ``lambda_t = -mu lambda_n``) or ``u_t <= 0`` (-1)."""
    if not has_t or mu == 0.0:
        return [_SEP, (2, 2)]  # (2, 2): frictionless, tangential impulse zero
    if np.isinf(mu):
        return [_SEP, (0, 0)]
    return [_SEP] + [(a, b) for a in (0, 1, -1) for b in (0, 1, -1)]


def _try_set(
    red: _Reduced, u0: FloatArray, tau: FloatArray, mu: FloatArray,
    modes: Sequence[tuple[int, int] | int], vtol: float,
) -> FloatArray | None:
    """Row impulses ``f`` (3 m,) of one active set if it is consistent, else None.

    Unknowns: ``lambda_n`` of active contacts and ``lambda_t`` of sticking rows; generalized
    directions ``B`` (a sliding row adds ``-s mu`` times its row to the normal one), constrained
    rows ``C`` (normal with target ``tau``, sticking rows with target 0): ``C Y B^T x = tau -
    C v0``. Sets whose bounded impulses (normal, and tangential ones of a finite cone) have
    directions ``Y B^T`` dependent modulo those of the free ones (sticking rows of an
    unbounded cone) are skipped: by Caratheodory's theorem such an outcome is also that of a
    smaller set (move along the dependence until an impulse reaches a bound). Redundant free
    impulses take their least-norm values.
    """
    m3 = u0.shape[0]
    cols_B: list[FloatArray] = []
    rows_C: list[int] = []
    target: list[float] = []
    free: list[bool] = []  # sticking rows of an unbounded cone: impulse free of any bound
    for i, md in enumerate(modes):
        if md == _SEP:
            continue
        assert isinstance(md, tuple)
        b = np.zeros(m3)
        b[3 * i] = 1.0
        for a in (0, 1):
            if md[a] in (1, -1):
                b[3 * i + 1 + a] = -md[a] * mu[i]
        cols_B.append(b)
        rows_C.append(3 * i)
        target.append(float(tau[i]))
        free.append(False)
        for a in (0, 1):
            if md[a] == 0:
                e = np.zeros(m3)
                e[3 * i + 1 + a] = 1.0
                cols_B.append(e)
                rows_C.append(3 * i + 1 + a)
                target.append(0.0)
                free.append(bool(np.isinf(mu[i])))
    G = red.G
    if cols_B:
        SB = np.array(cols_B)
        GB = G @ SB.T  # (3m, p)
        H = SB @ GB
        F = np.flatnonzero(free)
        rank = _rank_psd(H)
        if rank - _rank_psd(H[np.ix_(F, F)]) < len(free) - F.size:
            return None  # bounded impulses dependent modulo the free ones: a smaller set
        K = GB[rows_C]
        rhs = np.array(target) - u0[rows_C]
        try:
            if rank < len(free):
                raise np.linalg.LinAlgError
            x = np.linalg.solve(K, rhs)
        except np.linalg.LinAlgError:  # free impulses redundant (least norm: same q_dot+),
            x = np.linalg.lstsq(K, rhs, rcond=1e-12)[0]  # or a sliding set's K singular
        if not np.all(np.isfinite(x)) or np.max(np.abs(K @ x - rhs), initial=0.0) > vtol:
            return None
        f = SB.T @ x
    else:
        f = np.zeros(m3)
    u = u0 + G @ f
    ftol = 1e-9 * float(np.max(np.abs(f), initial=0.0)) + 1e-300
    for i, md in enumerate(modes):
        if md == _SEP:
            if u[3 * i] < tau[i] - vtol:
                return None
            continue
        assert isinstance(md, tuple)
        lam_n = f[3 * i]
        if lam_n < -ftol:
            return None
        for a in (0, 1):
            s, lam_t, u_t = md[a], f[3 * i + 1 + a], u[3 * i + 1 + a]
            if s == 0 and np.isfinite(mu[i]) and abs(lam_t) > mu[i] * lam_n + ftol:
                return None
            if s in (1, -1) and s * u_t < -vtol:
                return None
    return f


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
    entering, r = 2 * N, int(np.argmin(q))
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


def _lemke_point_contacts(
    red: _Reduced, u0: FloatArray, tau: FloatArray, mu: FloatArray,
) -> FloatArray | None:
    """One outcome by Lemke's method on the pyramid-cone LCP (Stewart-Trinkle form).

    Per contact with finite ``mu > 0``: ``lambda_n``, ``beta_1+-``, ``beta_2+-`` (tangential
    impulse ``beta+ - beta-``) and ``gamma_1, gamma_2`` (sliding speeds), with
    ``lambda_n _|_ u_n - tau``, ``beta+- _|_ +-u_t + gamma``, ``gamma _|_ mu lambda_n - beta+ -
    beta-``; frictionless contacts have ``lambda_n`` only. The matrix is copositive-plus, so
    the method ends with a solution.
    """
    m = tau.shape[0]
    L: list[FloatArray] = []  # rows mapping u (3m) to the velocity part of each w
    kinds: list[tuple[str, int, int]] = []
    m3 = 3 * m
    for i in range(m):
        e = np.zeros(m3)
        e[3 * i] = 1.0
        L.append(e)
        kinds.append(("n", i, 0))
        if mu[i] > 0.0:
            if np.isinf(mu[i]):
                return None
            for a in (1, 2):
                for s in (1.0, -1.0):
                    e = np.zeros(m3)
                    e[3 * i + a] = s
                    L.append(e)
                    kinds.append(("b", i, a))
            for a in (1, 2):
                L.append(np.zeros(m3))
                kinds.append(("g", i, a))
    Lr = np.array(L)
    Q = Lr @ red.G @ Lr.T
    q = Lr @ u0
    idx_n = {i: k for k, (t, i, _) in enumerate(kinds) if t == "n"}
    for k, (t, i, a) in enumerate(kinds):
        if t == "n":
            q[k] -= tau[i]
        elif t == "b":
            g = next(j for j, kk in enumerate(kinds) if kk == ("g", i, a))
            Q[k, g] += 1.0
        else:
            Q[k, idx_n[i]] += mu[i]
            for j, kk in enumerate(kinds):
                if kk == ("b", i, a):
                    Q[k, j] -= 1.0
    z = _lemke(Q, q)
    if z is None:
        return None
    return np.asarray(Lr.T @ z)


def _modes_of(f: FloatArray, u: FloatArray, mu: FloatArray, has_t: NDArray[np.bool_],
              ftol: float, vtol: float) -> tuple[list[ContactMode], NDArray[np.bool_]]:
    """Modes and sticking rows of an outcome: a contact with a normal impulse is active; its
    tangential rows stick where their velocity is zero (to ``vtol``) and slide elsewhere."""
    modes: list[ContactMode] = []
    stick = np.zeros((mu.shape[0], 2), dtype=bool)
    for i in range(mu.shape[0]):
        if f[3 * i] <= ftol:
            modes.append("separate")
        elif not has_t[i] or mu[i] == 0.0:
            modes.append("slip" if has_t[i] else "stick")
        else:
            stick[i] = np.abs(u[3 * i + 1:3 * i + 3]) <= vtol
            modes.append("stick" if stick[i].all() else "slip")
    return modes, stick


def _inert_phase(
    red: _Reduced, u0: FloatArray, tau: FloatArray, mu: FloatArray, has_t: NDArray[np.bool_],
    budget: int, vscale: float,
) -> tuple[list[FloatArray], bool, int]:
    """Row impulses of every outcome (exhaustive) or of one (Lemke), the flag and the bound.

    An unbounded cone whose stick/separate sets are all inconsistent (sticking would need a
    pull, separating would pass through: Painleve-type) takes a large finite coefficient,
    :data:`PAINLEVE_FRICTION` (the contact slides with a normal impulse of order ``1 / mu``
    and a finite friction impulse: the large-``mu`` limit to about ``1e-4`` relative), as the
    Gauss-Seidel path takes its large-``mu`` limit.
    """
    found = _enumerate(red, u0, tau, mu, has_t, budget, vscale)
    if found[0] or not np.any(np.isinf(mu)):
        return found
    big = np.where(np.isinf(mu), PAINLEVE_FRICTION, mu)
    found = _enumerate(red, u0, tau, big, has_t, budget, vscale)
    if found[0]:
        return found
    f = _lemke_point_contacts(red, u0, tau, big)  # a large mu strains the enumeration's tests
    return ([] if f is None else [f]), False, found[2]


def _enumerate(
    red: _Reduced, u0: FloatArray, tau: FloatArray, mu: FloatArray, has_t: NDArray[np.bool_],
    budget: int, vscale: float,
) -> tuple[list[FloatArray], bool, int]:
    opts = [_options(float(mu[i]), bool(has_t[i])) for i in range(mu.shape[0])]
    count = int(np.prod([len(o) for o in opts]))
    scale = max(float(np.max(np.abs(u0), initial=0.0)),
                float(np.max(np.abs(tau), initial=0.0)), vscale, 1e-300)
    vtol = 1e-9 * scale
    if count <= budget:
        found: list[tuple[tuple[int, int], FloatArray]] = []
        for modes in itertools.product(*opts):
            f = _try_set(red, u0, tau, mu, modes, vtol)
            if f is not None:
                n_slip = sum(1 for md in modes if isinstance(md, tuple)
                             for a in md if a in (1, -1))
                n_act = sum(1 for md in modes if md != _SEP)
                found.append(((n_slip, n_act), f))
        found.sort(key=lambda t: t[0])
        return [f for _, f in found], True, count
    f = _lemke_point_contacts(red, u0, tau, mu)
    if f is None:
        raise ImpactInputError(
            f"{count} active sets exceed the enumeration budget ({budget}) and Lemke's method "
            "found no solution (an unbounded friction cone needs enumeration: give fewer "
            "contacts or a finite friction)")
    return [f], False, count


def _distinct(vs: list[FloatArray], scale: float) -> list[FloatArray]:
    out: list[FloatArray] = []
    for v in vs:
        if all(np.max(np.abs(v - w)) > 1e-8 * scale for w in out):
            out.append(v)
    return out


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
    has_t = np.full(m, tangential is not None)
    T_ = (np.zeros((m, 2, n)) if tangential is None
          else np.asarray(tangential, dtype=float).reshape(m, 2, n))
    A_b = np.zeros((0, n)) if bilateral is None else np.asarray(bilateral, float).reshape(-1, n)
    mu = np.broadcast_to(np.asarray(friction, dtype=float), (m,)).copy()
    e = np.broadcast_to(np.asarray(restitution, dtype=float), (m,)).copy()
    if law not in ("newton", "energetic"):
        raise ImpactInputError(f"restitution law must be newton or energetic, got {law!r}")
    R = np.empty((3 * m, n))
    R[0::3], R[1::3], R[2::3] = N_, T_[:, 0], T_[:, 1]
    red = _reduce(M_, A_b, R)

    def free(x: FloatArray) -> FloatArray:  # x projected on ker A_b in the M metric
        if not A_b.shape[0]:
            return x.copy()
        return np.asarray(x - red.X_b @ (red.Wb_pinv @ (A_b @ x)))

    def post(x0: FloatArray, f: FloatArray) -> FloatArray:
        return np.asarray(x0 + red.Y @ (R.T @ f))

    v0 = free(v)
    u_pre = N_ @ v
    tau_newton = -e * np.minimum(u_pre, 0.0)
    tau = tau_newton if law == "newton" else np.zeros(m)
    vscale = float(np.max(np.abs(R @ v), initial=0.0))
    fs, exhaustive, count = _inert_phase(red, R @ v0, tau, mu, has_t, budget, vscale)
    if not fs:
        raise ImpactInputError("no consistent active set (please report this impact)")
    scale = max(float(np.sqrt(v @ M_ @ v / max(np.trace(M_) / n, 1e-300))), 1e-300)
    T = 0.5 * float(v @ M_ @ v)
    finals: list[tuple[FloatArray, FloatArray]] = []
    for f in fs:
        vc = post(v0, f)
        if law == "newton" or not np.any(e > 0.0):
            finals.append((vc, f))
            continue
        fr = np.zeros(3 * m)
        fr[0::3] = e * f[0::3]
        d = red.Y @ (R.T @ fr)
        d_norm2 = float(d @ M_ @ d)
        absorbed = max(T - 0.5 * float(vc @ M_ @ vc), 0.0)
        s = 1.0 if d_norm2 <= 2.0 * absorbed * float(np.max(e)) ** 2 else float(
            np.sqrt(2.0 * absorbed * float(np.max(e)) ** 2 / d_norm2))
        x = vc + s * d
        f3 = _inert_phase(red, R @ x, np.zeros(m), mu, has_t, budget, vscale)[0][0]
        finals.append((post(x, f3), f + s * fr + f3))
    sols = _distinct([vp for vp, _ in finals], scale)
    v_plus, f_tot = finals[0]
    vc0 = post(v0, fs[0])
    u_c = R @ vc0
    ftol = 1e-9 * float(np.max(np.abs(fs[0]), initial=0.0)) + 1e-300
    vtol = 1e-9 * max(vscale, 1e-300)
    modes, stick = _modes_of(fs[0], u_c, mu, has_t, ftol, vtol)
    lam_b = (-red.Wb_pinv @ (A_b @ (v + np.linalg.solve(M_, R.T @ f_tot)))
             if A_b.shape[0] else np.zeros(0))
    return PointContactSolution(
        velocity_post=v_plus,
        impulse=f_tot.reshape(m, 3),
        bilateral_impulse=np.asarray(lam_b),
        modes=tuple(modes),
        stick_rows=stick,
        solutions=tuple(sols),
        exhaustive=exhaustive,
        active_sets=count,
        restitution_law=law,
        compression_velocity=vc0,
    )
