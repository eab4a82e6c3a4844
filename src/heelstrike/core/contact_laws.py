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
      one), ``u_T+ = 0``, impulse inside the cone ``||w * lambda_T|| <= mu_i lambda_n``,
      ``lambda_n >= 0``;
    - ``"slip"``: same normal rows, ``lambda_T`` on the cone's boundary and opposite to the
      post-impact slip velocity (maximum dissipation): ``w * lambda_T = -mu_i lambda_n
      (u_T+ / w) / ||u_T+ / w||``.

    ``w`` are per-row tangential weights (1 for forces; ``1 / rho`` for a twisting moment with
    torsional radius ``rho``, the elliptic limit surface of a flat sole).

Solver (the choice stated): a **complementarity** formulation, *not* a convex QP relaxation (the
convex QP of Anitescu and of MuJoCo makes slipping contacts drift apart, ``u_n+ = mu ||u_T+||``;
here slipping contacts stay closed). Bilateral rows are eliminated exactly (Schur complement of
their Delassus block). Each striking contact's local problem is solved exactly: separation is
decided by the sign of the frictionless normal impulse, stick is tried first, and slip reduces
to one scalar secular equation in the multiplier ``beta`` of the disc constraint,
``||x(beta)|| = mu lambda_n(x(beta))`` with ``x(beta) = -(S + beta I)^-1 c``, solved by Brent's
method to machine precision. Several striking contacts are coupled by a block (non-smooth)
Gauss-Seidel iteration over contacts; with one striking contact it is exact in one sweep.
Uniqueness is not checked on this path (Painlevé-type configurations can have several
outcomes; the first root is returned: ``solutions`` is empty, ``unique`` None).
A contact with several normal rows (a flat sole held flat) is resolved all rows or none: where
holding it needs a pull yet releasing it leaves it moving into the ground (an edge or corner
landing), :func:`resolve_contact_impact` raises :class:`~heelstrike.core.impact.ImpactInputError`
rather than report a contact passing through the ground: give such a sole as its corners.

Active-set path (issue #34): striking *point* contacts (one normal row, up to two tangential
rows: a sole's corners, points, arcs) can instead be solved exactly by
:func:`heelstrike.core.complementarity.solve_point_contacts` (``method="active-set"``; taken
automatically for rank-deficient rows and for the energetic restitution law): friction is the
pyramid ``|lambda_t| <= mu lambda_n`` per tangential row, every active set is enumerated (up
to :data:`~heelstrike.core.complementarity.ENUMERATION_BUDGET`; above it Lemke's method gives
one outcome), the outcomes found are ``solutions`` (``unique``, ``exhaustive``,
``active_sets``), and redundant rows (two heel corners, a four-corner sole) give the unique
``q_dot+`` with the impulses of the smallest consistent active set (Carathéodory) and the kept
rows' least-norm impulses. Its energy split is the nested one below with pseudo-inverses
(:func:`energy_split` with ``redundant=True``): rows that repeat earlier ones add nothing, so
their energy goes to the contacts before them in the stated order.

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
import scipy.optimize
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.core.complementarity import RestitutionLaw, _pinv_psd, solve_point_contacts
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
SolverMethod = Literal["auto", "gauss-seidel", "active-set"]


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
    iterations : int
        Gauss-Seidel sweeps used (0 for the exact active-set solver).
    solutions : tuple of ndarray
        ``q_dot+`` (n,) of every distinct outcome the law admits, the returned one first, when
        the active sets were examined (:func:`heelstrike.core.complementarity.
        solve_point_contacts`); empty when they were not (the Gauss-Seidel path).
    exhaustive : bool
        Whether every active set was examined (``solutions`` is then complete).
    active_sets : int
        Number of active sets of the law (a bound on the number of outcomes; 0 if unknown).
    restitution_law : str
        ``"newton"`` or ``"energetic"``.
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
    iterations: int
    solutions: tuple[FloatArray, ...] = ()
    exhaustive: bool = False
    active_sets: int = 0
    restitution_law: str = "newton"

    @property
    def outcomes(self) -> int:
        """Number of distinct outcomes found (1 when the active sets were not examined)."""
        return max(len(self.solutions), 1)

    @property
    def unique(self) -> bool | None:
        """Whether the law has one outcome: None when the active sets were not all examined."""
        return len(self.solutions) == 1 if self.exhaustive else None


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


def _solve_local(
    G: FloatArray,
    u0: FloatArray,
    target_n: FloatArray,
    c: ContactRows,
) -> tuple[FloatArray, ImpactMode]:
    """Exact impulse of one unilateral contact given its free velocity ``u0`` (see module doc)."""
    N, T = list(c.normal), list(c.tangential)
    lam = np.zeros(c.rows)
    G_NN = G[np.ix_(N, N)]
    lam_N0 = np.linalg.solve(G_NN, target_n - u0[N])
    if lam_N0[0] <= 0.0:
        return lam, "separate"
    mu = c.law.friction
    if not T or mu == 0.0:
        lam[N] = lam_N0
        return lam, "slip" if T else "stick"
    # Stick.
    rhs = -u0.copy()
    rhs[N] += target_n
    lam_st: FloatArray = np.asarray(np.linalg.solve(G, rhs), dtype=float)
    w = np.asarray(c.tangential_weights, dtype=float)
    if lam_st[N[0]] > 0.0 and np.linalg.norm(w * lam_st[T]) <= mu * lam_st[N[0]]:
        return lam_st, "stick"
    # Slip: reduce to the tangential rows, scaled x = w * lambda_T. An infinite coefficient
    # reaches here only when sticking would pull (Painlevé-like); take the large-mu limit.
    mu = min(mu, 1e12)
    G_NT, G_TN, G_TT = G[np.ix_(N, T)], G[np.ix_(T, N)], G[np.ix_(T, T)]
    H = np.linalg.solve(G_NN, G_NT)  # lambda_N = lambda_N0 - H lambda_T
    S = G_TT - G_TN @ H
    S = 0.5 * (S + S.T)
    cvec = u0[T] + G_TN @ lam_N0  # u_T+ = c + S lambda_T
    Dinv = 1.0 / w
    Sx = Dinv[:, None] * S * Dinv[None, :]
    cx = Dinv * cvec
    hx = Dinv * H[0]
    evals, Q = np.linalg.eigh(Sx)
    cq = Q.T @ cx

    def x_of(beta: float) -> FloatArray:
        return np.asarray(-(Q @ (cq / (evals + beta))))

    def F(beta: float) -> float:
        x = x_of(beta)
        return float(np.linalg.norm(x) - mu * (lam_N0[0] - hx @ x))

    hi = max(float(evals.max()), 1e-300)
    while F(hi) >= 0.0:
        hi *= 4.0
        if hi > 1e300:  # pragma: no cover - cannot happen for lam_N0[0] > 0
            raise ImpactInputError(f"contact {c.name!r}: slip equation has no root")
    beta = 0.0 if F(0.0) <= 0.0 else scipy.optimize.brentq(F, 0.0, hi, xtol=1e-300, rtol=1e-15)
    lam_T = x_of(beta) / w
    lam[T] = lam_T
    lam[N] = lam_N0 - H @ lam_T
    if lam[N[0]] <= 0.0:
        return np.zeros(c.rows), "separate"
    return lam, "slip"


#: Relative tolerance (of the largest striking-contact velocity) on the separation condition
#: ``u_n+ >= -e min(u_n-, 0)`` of a contact reported as separating: it absorbs round-off.
SEPARATION_TOLERANCE = 1e-9


def _check_separations(
    contacts: Sequence[ContactRows],
    uni: list[int],
    modes: list[ImpactMode],
    targets: list[FloatArray],
    u_post: FloatArray,
    offs: list[slice],
    u_pre: FloatArray,
) -> None:
    """Raise unless every contact reported as separating really separates.

    A contact with several normal rows (a flat sole: the normal force and the moments
    that hold it flat) is resolved as all of them active or none. When holding it needs a pull
    and releasing it lets it move on into the ground, neither is consistent: the sole lands on
    an edge or a corner, which these laws do not model. Such a result is refused, not reported.
    """
    scale = max(float(np.max(np.abs(u_pre), initial=0.0)),
                float(np.max(np.abs(u_post), initial=0.0)), 1e-300)
    for j, i in enumerate(uni):
        if modes[j] != "separate":
            continue
        c = contacts[i]
        u_n = float(u_post[offs[j]][c.normal[0]])
        if u_n < float(targets[j][0]) - SEPARATION_TOLERANCE * scale:
            raise ImpactInputError(
                f"contact {c.name!r}: no consistent impact: holding its {len(c.normal)} normal "
                "rows (the sole flat on the ground) needs a pull, and releasing it leaves it "
                f"moving into the ground at {u_n:.4g} m/s; the sole lands on an edge or a "
                "corner, which this contact law does not model (give it as a point contact)"
            )


def resolve_contact_impact(
    M: ArrayLike,
    q_dot: ArrayLike,
    contacts: Sequence[ContactRows],
    *,
    max_sweeps: int = 500,
    tol: float = 1e-13,
    restitution_law: RestitutionLaw = "newton",
    method: SolverMethod = "auto",
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
    max_sweeps : int
        Maximum Gauss-Seidel sweeps over the unilateral contacts.
    tol : float
        Relative convergence tolerance on the impulses.
    restitution_law : {"newton", "energetic"}
        Newton's kinematic law (can gain energy with sticking friction: Kane's paradox) or
        the energetic two-phase law of :func:`heelstrike.core.complementarity.
        solve_point_contacts`, which cannot (it uses the active-set solver).
    method : {"auto", "gauss-seidel", "active-set"}
        ``"gauss-seidel"``: the block Gauss-Seidel over contacts with round friction cones
        (full-rank rows only). ``"active-set"``: exact active-set enumeration with pyramid
        cones (:func:`~heelstrike.core.complementarity.solve_point_contacts`; every striking
        contact a point: one normal row, at most two tangential rows; any rank; reports every
        outcome). ``"auto"`` (default): active-set when the rows are rank deficient or the law
        is energetic, else Gauss-Seidel.

    Returns
    -------
    ContactImpact

    Raises
    ------
    ImpactInputError
        On malformed input, rank-deficient rows that the active-set solver cannot take (only
        bilateral contacts, or a striking contact with several normal rows), or no
        convergence.
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
    bil = [i for i, c in enumerate(contacts) if c.bilateral]
    uni = [i for i, c in enumerate(contacts) if not c.bilateral]
    A_all = np.vstack([c.jacobian for c in contacts])
    sv = np.linalg.svd(A_all, compute_uv=False)
    deficient = A_all.shape[0] > n or sv[-1] <= 1e-12 * max(A_all.shape) * sv[0]
    if method not in ("auto", "gauss-seidel", "active-set"):
        raise ImpactInputError(f"method must be auto, gauss-seidel or active-set, got {method!r}")
    if uni and (method == "active-set" or (method == "auto" and (
            deficient or restitution_law == "energetic"))):
        return _resolve_active_set(M_, v, contacts, restitution_law)
    if restitution_law != "newton":
        raise ImpactInputError("the energetic restitution law needs the active-set solver")
    if A_all.shape[0] > n:
        raise ImpactInputError(f"{A_all.shape[0]} contact rows exceed the {n} coordinates")
    if deficient:
        raise ImpactInputError("contact rows are rank deficient (redundant contacts?)")

    A_b = (
        np.vstack([contacts[i].jacobian for i in bil]) if bil else np.zeros((0, n))
    )
    A_s = (
        np.vstack([contacts[i].jacobian for i in uni]) if uni else np.zeros((0, n))
    )
    X_b = scipy.linalg.cho_solve(cho, A_b.T) if bil else np.zeros((n, 0))
    X_s = scipy.linalg.cho_solve(cho, A_s.T) if uni else np.zeros((n, 0))
    if bil:
        W_bb = A_b @ X_b
        W_bb = 0.5 * (W_bb + W_bb.T)
        cho_b = scipy.linalg.cho_factor(W_bb)
        v0 = v - X_b @ scipy.linalg.cho_solve(cho_b, A_b @ v)
        Y = X_s - X_b @ scipy.linalg.cho_solve(cho_b, A_b @ X_s) if uni else X_s
    else:
        v0 = v.copy()
        Y = X_s
    G = A_s @ Y
    G = 0.5 * (G + G.T)
    # Offsets of each unilateral contact within A_s.
    offs: list[slice] = []
    start = 0
    for i in uni:
        offs.append(slice(start, start + contacts[i].rows))
        start += contacts[i].rows
    u_pre_s = A_s @ v
    u_free = A_s @ v0
    targets: list[FloatArray] = []
    for j, i in enumerate(uni):
        c = contacts[i]
        un = u_pre_s[offs[j]][list(c.normal)]
        tgt = -c.law.restitution * un
        tgt[0] = -c.law.restitution * min(un[0], 0.0)
        targets.append(tgt)
    lam_s = np.zeros(A_s.shape[0])
    modes_s: list[ImpactMode] = ["separate"] * len(uni)
    sweeps = 0
    for sweeps in range(1, max_sweeps + 1):  # noqa: B007
        change = 0.0
        for j, i in enumerate(uni):
            sl = offs[j]
            u0 = u_free[sl] + G[sl, :] @ lam_s - G[sl, sl] @ lam_s[sl]
            new, modes_s[j] = _solve_local(G[sl, sl], u0, targets[j], contacts[i])
            change = max(change, float(np.max(np.abs(new - lam_s[sl]), initial=0.0)))
            lam_s[sl] = new
        scale = max(float(np.max(np.abs(lam_s), initial=0.0)), 1e-300)
        if len(uni) <= 1 or change <= tol * scale:
            break
    else:
        raise ImpactInputError(f"Gauss-Seidel over contacts did not converge in {max_sweeps}")
    v_plus = v0 + Y @ lam_s
    _check_separations(contacts, uni, modes_s, targets, A_s @ v_plus, offs, u_pre_s)
    if bil:
        lam_b = -scipy.linalg.cho_solve(cho_b, A_b @ v + A_b @ X_s @ lam_s)
    else:
        lam_b = np.zeros(0)
    # Assemble impulses and modes in contact order.
    modes: list[ImpactMode] = []
    lam_parts: list[FloatArray] = []
    bpos, spos = 0, 0
    j = 0
    for c in contacts:
        if c.bilateral:
            lam_parts.append(lam_b[bpos : bpos + c.rows])
            bpos += c.rows
            modes.append("stick")
        else:
            lam_parts.append(lam_s[spos : spos + c.rows])
            spos += c.rows
            modes.append(modes_s[j])
            j += 1
    lam = np.concatenate(lam_parts)
    f = A_all.T @ lam
    # Energy split over the active rows: normal groups first, then tangential groups.
    normal_groups: list[FloatArray] = []
    tangential_groups: list[FloatArray] = []
    for c, mode in zip(contacts, modes, strict=True):
        Jn = c.jacobian[list(c.normal)]
        Jt = c.jacobian[list(c.tangential)]
        if mode == "separate":
            Jn, Jt = Jn[:0], Jt[:0]
        elif mode == "slip":
            Jt = Jt[:0]
        normal_groups.append(Jn)
        tangential_groups.append(Jt)
    _, shares = energy_split(M_, v, normal_groups + tangential_groups, check=False)
    m = len(contacts)
    A_act = np.vstack(normal_groups + tangential_groups)
    if A_act.shape[0]:
        split = impact(M_, A_act, v, check=False)  # the paper's projectors, eqs. (6)-(10)
        T, T_c = float(split.kinetic_energy), float(split.kinetic_energy_constrained)
        T_a = float(split.kinetic_energy_admissible)
    else:
        T = 0.5 * float(v @ M_ @ v)
        T_c, T_a = 0.0, T
    T_post = 0.5 * float(v_plus @ M_ @ v_plus)
    return ContactImpact(
        velocity_pre=v,
        velocity_post=v_plus,
        impulse=lam,
        generalized_impulse=f,
        modes=tuple(modes),
        contact_velocity_pre=tuple(c.jacobian @ v for c in contacts),
        contact_velocity_post=tuple(c.jacobian @ v_plus for c in contacts),
        T=T,
        T_c=T_c,
        T_a=T_a,
        T_post=T_post,
        energy_lost=T - T_post,
        T_c_normal=shares[:m],
        T_c_tangential=shares[m:],
        iterations=sweeps,
    )


def _resolve_active_set(M: FloatArray, v: FloatArray, contacts: Sequence[ContactRows],
                        law: RestitutionLaw) -> ContactImpact:
    """:func:`resolve_contact_impact` by exact active sets (pyramid cones, any rank)."""
    n = M.shape[0]
    uni = [c for c in contacts if not c.bilateral]
    for c in uni:
        if len(c.normal) != 1 or len(c.tangential) > 2:
            raise ImpactInputError(
                f"contact {c.name!r}: the active-set solver takes striking point contacts (one "
                "normal row, at most two tangential rows): give a sole as its corners")
    m = len(uni)
    N = np.array([c.jacobian[c.normal[0]] for c in uni])
    Tt = np.zeros((m, 2, n))
    for j, c in enumerate(uni):
        for a, t in enumerate(c.tangential):
            Tt[j, a] = c.jacobian[t]
    mu = np.array([c.law.friction if c.tangential else 0.0 for c in uni])
    e = np.array([c.law.restitution for c in uni])
    bil = [c.jacobian for c in contacts if c.bilateral]
    sol = solve_point_contacts(M, v, N, tangential=Tt, bilateral=np.vstack(bil) if bil else None,
                               friction=mu, restitution=e, law=law)
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
            lam = np.zeros(c.rows)
            lam[c.normal[0]] = sol.impulse[j, 0]
            for a, t in enumerate(c.tangential):
                lam[t] = sol.impulse[j, 1 + a]
            lam_parts.append(lam)
            modes.append(sol.modes[j])
            if sol.modes[j] == "separate":
                Jn = Jn[:0]
            Jt = Jt[[a for a in range(len(c.tangential)) if sol.stick_rows[j, a]]]
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
        iterations=0,
        solutions=sol.solutions,
        exhaustive=sol.exhaustive,
        active_sets=sol.active_sets,
        restitution_law=law,
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
        Every contact in mode ``"stick"``, ``iterations = 1`` (as the reference path reports).

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
        iterations=1,
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
