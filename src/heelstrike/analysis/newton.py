"""The one Newton engine: damped Newton on a batched residual, per-item outcomes.

Every gait search in heelstrike solves ``F(x) = 0`` for a residual evaluated by simulating
steps: the passive period-one gait ``P(z) - z = 0`` (:mod:`~heelstrike.analysis.limit_cycle`,
:mod:`~heelstrike.analysis.gait_map`) and the powered gait's augmented map
(:mod:`~heelstrike.analysis.powered`). They all run :func:`newton_solve`:

- the residual is *batched*: ``residual(X)`` takes ``(B, n)`` points and returns ``(B, m)``
  values, with a row of NaN where the walker fails to take a step. All pending iterates and
  their finite-difference neighbours go to the residual in one call per iteration, so a
  compiled ensemble evaluates them in one kernel launch;
- where the residual's Jacobian is known exactly (the passive step map on the scipy
  reference: :meth:`~heelstrike.analysis.limit_cycle.PoincareMap.exact_jacobian`),
  ``jacobian="exact"`` takes it with every evaluation instead of differences;
- failures are returned per start (diffrax's idea), never raised: a
  :class:`~heelstrike.status.SolveStatus` says what happened and carries its message.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.status import SolveStatus

__all__ = [
    "NewtonSolution", "SearchTimeLimitWarning", "floquet_multipliers", "newton_solve",
]

Residual = Callable[[FloatArray], FloatArray]
#: ``derivative(X) -> (F, J)``: the residual at ``(B, n)`` points and its Jacobians ``(B, m, n)``.
Derivative = Callable[[FloatArray], tuple[FloatArray, FloatArray]]


class SearchTimeLimitWarning(UserWarning):
    """A search reached its time limit: what it found by then is returned, and it may have
    missed solutions (e.g. :func:`heelstrike.analysis.limit_cycle.find_limit_cycles`)."""


@dataclass(frozen=True, kw_only=True)
class NewtonSolution(ResultDictMixin):
    """Per-start outcome of :func:`newton_solve` (``K`` starts, ``n`` unknowns, ``m`` equations).

    Attributes
    ----------
    x : ndarray, shape (K, n)
        The last iterate of each start (the root where ``status`` is ``CONVERGED``).
    residual : ndarray, shape (K, m)
        ``F(x)`` there (NaN where the walker failed).
    residual_norm : ndarray, shape (K,)
        ``|F(x)|`` (2-norm).
    jacobian : ndarray, shape (K, m, n)
        The Jacobian of ``F`` each start held when it ended (NaN if none was current: a
        central-difference Jacobian is dropped after each step). With ``jacobian="central"``
        and ``jacobian_at_root=True`` a converged start holds the central-difference Jacobian
        at ``x``: for a fixed point ``F = P - id`` the Floquet multipliers are the
        eigenvalues of ``jacobian + I``. With ``"broyden"`` it is the updated Broyden matrix;
        with ``"exact"`` the ``derivative``'s Jacobian at ``x`` (every start that has an
        iterate with a finite ``F``).
    iterations : ndarray of int, shape (K,)
        Residual evaluations at an iterate (1 when the start already solves ``F = 0``).
    status : tuple of SolveStatus, length K
        How each start ended.
    max_iter : int
        The iteration limit the solve ran with.
    method : str
        The ``jacobian`` option of the solve (``"central"``, ``"broyden"``, ``"chord"`` or
        ``"exact"``).
    """

    x: FloatArray
    residual: FloatArray
    residual_norm: FloatArray
    jacobian: FloatArray
    iterations: NDArray[np.int_]
    status: tuple[SolveStatus, ...]
    max_iter: int
    method: str = "central"

    def message(self, k: int, labels: Sequence[tuple[str, str]] | None = None) -> str:
        """One line on how start ``k`` ended, with its iterate or residual where they help.

        ``labels``: ``(name, unit)`` per unknown, to print the iterate as ``name = value unit``
        instead of a bare array.
        """
        s, r = self.status[k], float(self.residual_norm[k])
        if s is SolveStatus.STEP_FAILED:
            x = self.x[k]
            if labels is not None and len(labels) == x.size:
                pairs = ", ".join(f"{n} = {v:.6g} {u}"
                                  for (n, u), v in zip(labels, x, strict=True))
                return f"{s.message} ({pairs})"
            return f"{s.message} {np.round(x, 6)}"
        if s is SolveStatus.MAX_ITERATIONS:
            return f"Newton did not converge in {self.max_iter} iterations (residual {r:.2e})"
        if s in (SolveStatus.STALLED, SolveStatus.SLOW):
            return f"{s.message} (residual {r:.2e})"
        return s.message

    @property
    def converged(self) -> NDArray[np.bool_]:
        """``status is CONVERGED`` per start, shape (K,)."""
        return np.array([s is SolveStatus.CONVERGED for s in self.status], dtype=bool)


def floquet_multipliers(jacobian: ArrayLike) -> NDArray[np.complex128]:
    """The Floquet multipliers of a gait: the eigenvalues of its Poincare map's Jacobian.

    Parameters
    ----------
    jacobian : array_like, shape (d, d)
        ``DP`` at the fixed point (section coordinates).

    Returns
    -------
    ndarray of complex, shape (d,)
        Largest modulus first (ties in the eigensolver's order); NaN if ``DP`` is not finite.
    """
    DP = np.asarray(jacobian, dtype=float)
    if not np.all(np.isfinite(DP)):
        return np.full(DP.shape[-1], np.nan, dtype=complex)
    mult = np.linalg.eigvals(DP).astype(complex)
    return mult[np.argsort(-np.abs(mult), kind="stable")]


def _differences(x: FloatArray, fd_step: float, central: bool) -> tuple[FloatArray, FloatArray]:
    """Points ``x +- dx_i e_i`` for each row (``(A, 2n, n)`` or ``(A, n, n)``) and ``dx``."""
    n = x.shape[1]
    dx = fd_step * np.maximum(1.0, np.abs(x))  # (A, n)
    offset = np.eye(n)[None, :, :] * dx[:, None, :]  # (A, n, n): row i is dx_i e_i
    plus = x[:, None, :] + offset
    pts = np.concatenate((plus, x[:, None, :] - offset), axis=1) if central else plus
    return pts, dx


def _evaluate(residual: Residual, X: FloatArray, n: int) -> FloatArray:
    """``residual(X)`` as ``(B, n)`` floats; no call for an empty batch."""
    if X.shape[0] == 0:
        return np.empty((0, n))
    return np.asarray(residual(X), dtype=float).reshape(-1, n)


def _evaluate_pairs(derivative: Derivative, X: FloatArray, n: int
                    ) -> tuple[FloatArray, FloatArray]:
    """``derivative(X)`` as ``(B, n)`` and ``(B, n, n)`` floats; no call for an empty batch."""
    if X.shape[0] == 0:
        return np.empty((0, n)), np.empty((0, n, n))
    F, J = derivative(X)
    return (np.asarray(F, dtype=float).reshape(-1, n),
            np.asarray(J, dtype=float).reshape(-1, n, n))


def newton_solve(
    residual: Residual,
    x0: ArrayLike,
    *,
    tol: float,
    max_iter: int = 20,
    fd_step: float = 1e-6,
    jacobian: Literal["central", "broyden", "chord", "exact"] = "central",
    jacobian0: ArrayLike | None = None,
    derivative: Derivative | None = None,
    contraction: float = 0.2,
    jacobian_at_root: bool = True,
    line_search: Literal["finite", "decrease"] = "finite",
    min_step: float = 1e-3,
    accept: float | None = None,
    min_rate: float | None = None,
    project: Callable[[FloatArray], FloatArray] | None = None,
    deadline: float | None = None,
) -> NewtonSolution:
    """Damped Newton's method for ``F(x) = 0`` from ``K`` starts at once.

    Each iteration evaluates, in one call of ``residual``, every pending iterate together with
    its finite-difference neighbours (``x +- dx_i e_i`` with ``dx_i = fd_step max(1, |x_i|)``),
    solves ``J dx = -F`` per start and halves the step ``lam`` from 1 until the trial point is
    acceptable, all pending trials in one call per halving.

    Parameters
    ----------
    residual : callable
        ``residual(X)``, ``X`` of shape ``(B, n)``, returns ``F`` of shape ``(B, m)`` with
        ``m == n``; a row of NaN where the walker fails.
    x0 : array_like, shape (K, n) or (n,)
        Starts.
    tol : float
        Convergence bound on ``|F(x)|`` (same units as ``F``).
    max_iter : int
        Newton steps per start.
    fd_step : float
        Relative finite-difference step of the Jacobian.
    jacobian : {"central", "broyden", "chord", "exact"}
        ``central``: central differences at every iterate (``2n`` evaluations). ``exact``:
        every iterate and every trial of the line search is evaluated by ``derivative``,
        which gives ``F`` with its Jacobian (no differences; a trial that is taken brings its
        Jacobian, so an iteration costs one call, and a converged start holds the Jacobian at
        its root: Newton's quadratic convergence to the integrator's accuracy). ``broyden``:
        forward differences (``n`` evaluations) once, then Broyden's rank-one update after each
        step (recomputed once when the line search fails with a stale Jacobian). ``chord``: the
        same Jacobian at every iterate (``jacobian0``, else forward differences) and full steps
        ``x - J^-1 F(x)``, one evaluation each: a step is taken if it reduces ``|F|``; the
        Jacobian is kept while a step reduces ``|F|`` at least ``1 / contraction``-fold, else it
        is replaced once by forward differences; a second replacement ends the start
        :attr:`~heelstrike.status.SolveStatus.STALLED` (no line search; for a good Jacobian of
        a nearby point, e.g. a coarse stage's, on an expensive accurate residual).
    jacobian0 : array_like, shape (K, n, n), optional
        Initial Jacobians (``broyden``, ``chord``); a non-finite one is computed instead.
    derivative : callable, optional
        ``derivative(X)``, ``X`` of shape ``(B, n)``, returns ``(F, J)`` of shapes ``(B, m)``
        and ``(B, m, n)``: the residual (as ``residual``) and its Jacobian ``dF/dx`` at each
        point; rows of NaN where the walker fails. Required by, and only used with,
        ``jacobian="exact"``.
    contraction : float
        ``chord``: the fold reduction a step must reach for the Jacobian to be kept.
    jacobian_at_root : bool
        Evaluate the iterate and its neighbours in one call, so that a converged start also
        has its Jacobian (the Floquet multipliers of a fixed point). ``False``: the neighbours
        are evaluated only when a Newton step is needed (one call more per iteration, ``2n``
        evaluations fewer at the root).
    line_search : {"finite", "decrease"}
        ``finite``: the first ``lam`` at which the walker takes a step (the step is taken even
        if ``lam`` reaches ``min_step``). ``decrease``: the first ``lam >= min_step`` with
        ``|F(x + lam dx)| < (1 - lam / 4) |F(x)|``; none is
        :attr:`~heelstrike.status.SolveStatus.STALLED`.
    min_step : float
        Smallest ``lam``.
    accept : float, optional
        With ``line_search="decrease"``: a stall with ``|F| < accept`` (the integrator's noise
        floor) counts as converged. Default ``10 tol``.
    min_rate : float, optional
        With ``line_search="decrease"``: a step must reduce ``|F|`` at least ``1 / min_rate``
        fold while ``|F| >= accept`` (else :attr:`~heelstrike.status.SolveStatus.SLOW`).
    project : callable, optional
        Applied to each trial point ``(B, n) -> (B, n)`` (e.g. a bound on a parameter).
    deadline : float, optional
        ``time.monotonic()`` value after which pending starts end with ``TIME_LIMIT``.

    Returns
    -------
    NewtonSolution
        Per start: the iterate, ``F`` and its norm, the central-difference Jacobian at a
        converged iterate, iterations and status.

    Raises
    ------
    ValueError
        For ``jacobian="exact"`` without ``derivative``.
    """
    exact = jacobian == "exact"
    if exact and derivative is None:
        raise ValueError("jacobian='exact' needs derivative (the residual with its Jacobian)")
    X = np.atleast_2d(np.asarray(x0, dtype=float)).copy()
    K, n = X.shape
    floor = 10.0 * tol if accept is None else accept
    central = jacobian == "central"
    status: list[SolveStatus] = [SolveStatus.MAX_ITERATIONS] * K
    F_all = np.full((K, n), np.nan)
    J_all = np.full((K, n, n), np.nan)
    iters = np.zeros(K, dtype=int)
    # per-start state of the Broyden/forward variants
    J_cur: list[FloatArray | None] = [None] * K
    fresh = np.zeros(K, dtype=bool)
    F_cur = np.full((K, n), np.nan)
    have_F = np.zeros(K, dtype=bool)
    chord = jacobian == "chord"
    refreshed = np.zeros(K, dtype=bool)  # chord: its Jacobian was replaced once already
    if jacobian0 is not None:
        J0 = np.broadcast_to(np.asarray(jacobian0, dtype=float), (K, n, n))
        J_cur = [J0[k].copy() if np.all(np.isfinite(J0[k])) else None for k in range(K)]
    active = np.arange(K)
    it = 0
    while active.size:
        it += 1
        if deadline is not None and time.monotonic() > deadline:
            for k in active:
                status[k] = SolveStatus.TIME_LIMIT
            break
        x = X[active]
        if exact:  # F and its Jacobian together, where either is missing
            assert derivative is not None
            need = ~have_F[active] | np.array([J_cur[k] is None for k in active], dtype=bool)
            F_new, J_new = _evaluate_pairs(derivative, x[need], n)
            for j, k in enumerate(active[need]):
                F_cur[k], J_cur[k], have_F[k] = F_new[j], J_new[j], True
        new_F = ~have_F[active]
        need_jac = np.array([central or J_cur[k] is None for k in active], dtype=bool)
        if not jacobian_at_root:  # F first; neighbours only of the iterates not yet converged
            if np.any(new_F):
                F_cur[active[new_F]] = _evaluate(residual, x[new_F], n)
                have_F[active[new_F]] = True
            need_jac &= ~(np.linalg.norm(F_cur[active], axis=1) < tol)
            need_jac &= np.all(np.isfinite(F_cur[active]), axis=1)
            new_F[:] = False
        if chord:  # a chord Jacobian is replaced once at most
            need_jac &= ~refreshed[active]
        pts, dx = _differences(x[need_jac], fd_step, central)
        values = _evaluate(residual, np.concatenate((x[new_F], pts.reshape(-1, n))), n)
        nf = int(new_F.sum())
        F_cur[active[new_F]] = values[:nf]
        have_F[active[new_F]] = True
        nb = values[nf:].reshape(int(need_jac.sum()), 2 * n if central else n, n)
        F = F_cur[active]
        for j, row in enumerate(np.flatnonzero(need_jac)):
            if central:
                Jk = np.swapaxes((nb[j, :n] - nb[j, n:]) / (2.0 * dx[j][:, None]), 0, 1)
            else:
                Jk = np.swapaxes((nb[j] - F[row]) / dx[j][:, None], 0, 1)
            J_cur[active[row]] = Jk
            fresh[active[row]] = True
            refreshed[active[row]] = chord
        res = np.linalg.norm(F, axis=1)
        keep = np.ones(active.size, dtype=bool)
        step = np.zeros_like(x)
        retry = np.zeros(active.size, dtype=bool)  # chord: no step this time, Jacobian dropped
        for a, k in enumerate(active):
            iters[k] = it
            F_all[k] = F[a]
            Jk = J_cur[k]
            if not np.all(np.isfinite(F[a])):
                status[k], keep[a] = SolveStatus.STEP_FAILED, False
            elif res[a] < tol:
                status[k], keep[a] = SolveStatus.CONVERGED, False
            elif it > max_iter:
                keep[a] = False
            elif Jk is None:
                status[k], keep[a] = (SolveStatus.STALLED if chord else status[k]), False
            elif not np.all(np.isfinite(Jk)):
                status[k], keep[a] = SolveStatus.JACOBIAN_FAILED, False
            else:
                try:
                    step[a] = np.linalg.solve(Jk, -F[a])
                except np.linalg.LinAlgError:
                    if chord:
                        J_cur[k], retry[a] = None, True
                    else:
                        status[k], keep[a] = SolveStatus.SINGULAR, False
        lam = np.ones(active.size)
        pending = keep & ~retry
        ok = np.zeros(active.size, dtype=bool)
        F_try = np.full_like(x, np.nan)
        J_try = np.full((x.shape[0], n, n), np.nan)
        while np.any(pending):
            idx = np.flatnonzero(pending)
            trial = x[idx] + lam[idx, None] * step[idx]
            if project is not None:
                trial = project(trial)
            if exact:
                assert derivative is not None
                Ft, Jt = _evaluate_pairs(derivative, trial, n)
                J_try[idx] = Jt
            else:
                Ft = _evaluate(residual, trial, n)
            fine = np.all(np.isfinite(Ft), axis=1)
            if chord:  # full steps only: a failed or worse trial is judged below
                F_try[idx] = Ft
                ok[idx] = fine
                pending[:] = False
                break
            if line_search == "decrease":
                fine &= np.linalg.norm(Ft, axis=1) < (1.0 - 0.25 * lam[idx]) * res[idx]
            F_try[idx[fine]] = Ft[fine]
            ok[idx[fine]] = True
            pending[idx[fine]] = False
            lam[idx[~fine]] *= 0.5
            if line_search == "decrease":
                pending &= lam >= min_step
            else:
                pending &= lam > min_step
        for a, k in enumerate(active):
            if not keep[a] or retry[a]:
                continue
            if chord:
                new_res = float(np.linalg.norm(F_try[a])) if ok[a] else np.inf
                if new_res < res[a]:
                    X[k], F_cur[k] = x[a] + step[a], F_try[a]
                if not new_res <= contraction * res[a]:
                    J_cur[k] = None
                continue
            if line_search == "finite":  # the damped step is taken whatever lam became
                X[k] = x[a] + lam[a] * step[a]
                if project is not None:
                    X[k] = project(X[k][None, :])[0]
                # a trial that stepped is the new iterate: its F is known (not evaluated again)
                F_cur[k] = F_try[a]
                have_F[k] = bool(ok[a])
                J_cur[k] = J_try[a] if exact and ok[a] else None
                continue
            if not ok[a]:
                if jacobian == "broyden" and not fresh[k]:
                    J_cur[k] = None  # a stale Broyden Jacobian: recompute and retry
                    continue
                if res[a] < floor:
                    status[k], keep[a] = SolveStatus.CONVERGED, False
                else:
                    status[k], keep[a] = SolveStatus.STALLED, False
                continue
            new_res = float(np.linalg.norm(F_try[a]))
            if min_rate is not None and new_res > min_rate * res[a] and res[a] >= floor:
                status[k], keep[a] = SolveStatus.SLOW, False
                continue
            x_new = x[a] + lam[a] * step[a]
            if project is not None:
                x_new = project(x_new[None, :])[0]
            if jacobian == "broyden":
                Jk = J_cur[k]
                assert Jk is not None
                s = x_new - x[a]
                J_cur[k] = Jk + np.outer(F_try[a] - F[a] - Jk @ s, s) / float(s @ s)
                fresh[k] = False
            else:
                J_cur[k] = J_try[a] if exact else None
            X[k], F_cur[k] = x_new, F_try[a]
        active = active[keep]
    for i, J_end in enumerate(J_cur):
        if J_end is not None:
            J_all[i] = J_end
    return NewtonSolution(
        x=X,
        residual=F_all,
        residual_norm=np.linalg.norm(F_all, axis=1),
        jacobian=J_all,
        iterations=iters,
        status=tuple(status),
        max_iter=max_iter,
        method=str(jacobian),
    )
