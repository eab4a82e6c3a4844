"""Compiled inert impact of a kinematic tree: tree-sparse ``M = U D U^T``, Delassus, energy split.

One numba function per configuration, :func:`inert_item`, and its loop over a batch,
:func:`inert_batch`. The mass matrix is read from the upper triangle Pinocchio's ``crba``
fills; its factorisation is Pinocchio's own ``cholesky::decompose`` (Featherstone's
tree-sparse ``L^T D L``, written ``U D U^T`` with ``U`` unit upper triangular): entry
``U[i, j]`` is non-zero only when dof ``i`` is an ancestor of dof ``j`` (``parents`` walks
the ancestors, ``nvsub[j]`` is the number of dofs of ``j``'s subtree, ``j`` included, which
follow ``j`` contiguously). Then, with the rows ``A_p`` of the contacts in the nesting order
of the energy split (all normal rows, then all tangential rows):

- ``Y = U^-1 A_p^T`` (tree-sparse back substitution), ``W = Y^T D^-1 Y = A_p M^-1 A_p^T``
  (the Delassus matrix), ``W = L L^T`` (dense, ``k x k``);
- ``y = L^-1 A_p q_dot-``, ``lambda_p = -L^-T y``, ``q_dot+ = q_dot- + U^-T D^-1 Y lambda_p``;
- ``T_c = 1/2 |y|^2``, its nested shares the squares of ``y``'s segments;
  ``T = 1/2 q_dot-^T M q_dot-`` and ``T+ = 1/2 q_dot+^T M q_dot+`` from the tree-sparse ``M``.

The numbers are those of :func:`heelstrike.core.contact_laws.inert_contact_impact` (same
algebra, another factorisation of ``M``). Nothing here knows a robot: the tree is two integer
arrays.

Status codes: 0 solved; 1 ``M`` not positive definite (a pivot ``D[j] <= 0``); 2 ``W`` not
positive definite (rank-deficient rows); 3 solved, but the cheap full-rank certificate of
``A`` (``check``) did not hold, so the caller runs the reference rank test.
"""

from __future__ import annotations

import math

from numba import njit

from heelstrike._caching import tolerate_numba_cache_errors
from heelstrike._typing import FloatArray
from heelstrike.robots._inert_tree import (
    RANK_CERTIFICATE,
    IntArray,
    chain,
    out_size,
    tree_arrays,
    tree_layout,
    work_size,
)

tolerate_numba_cache_errors()  # numba's cache unwritable (full disk): run uncached

__all__ = ["RANK_CERTIFICATE", "chain", "inert_batch", "inert_item", "out_size", "tree_arrays",
           "tree_layout", "work_size"]


@njit(cache=True)
def inert_item(M: FloatArray, A: FloatArray, v: FloatArray, tree: IntArray,
               work: FloatArray, out: FloatArray, check: bool,
               upto: int = 5) -> int:  # pragma: no cover
    """Inert impact of one configuration (module doc); returns the status code.

    Parameters
    ----------
    M : ndarray, shape (n, n)
        Mass matrix; only the entries ``M[i, j]``, ``i`` an ancestor of ``j`` or ``i = j``,
        are read (the upper triangle ``crba`` fills).
    A : ndarray, shape (k, n)
        Contact rows in contact order, each zero outside its chain (the dofs that move the
        contact's body: :func:`tree_layout`).
    v : ndarray, shape (n,)
        ``q_dot-``.
    tree : ndarray of int64
        :func:`tree_layout`.
    work : ndarray, shape (work_size(n, k),)
    out : ndarray, shape (out_size(n, k, groups),)
        ``q_dot+``, ``lambda`` (contact order), nested shares of ``T_c`` (normal groups, then
        tangential), ``T``, ``T+``, ``T_c``, ``T - T+``, ``A q_dot-``, ``A q_dot+``,
        ``A^T lambda``.
    check : bool
        Test the full-rank certificate of ``A`` (status 3 when it does not hold).
    upto : int
        Stop after a stage (for timing the stages; ``out`` is then incomplete): 0 the
        certificate, 1 ``U D U^T``, 2 ``Y``, 3 ``W = L L^T``, 4 ``lambda`` and ``q_dot+``,
        5 everything (default).
    """
    # No array views inside the loops: each costs numba two atomic reference-count updates.
    n = tree[0]
    k = tree[1]
    ng = tree[2]
    P = 3  # parents
    NV = P + n  # subtree sizes
    OR = NV + n  # nesting order
    BD = OR + k  # group bounds
    CS = BD + ng + 1  # chain start per row (nesting order)
    CL = CS + k  # chain length
    CH = CL + k  # chains
    U = work[:n * n].reshape((n, n))
    Y = work[n * n:n * n + k * n].reshape((k, n))
    w0 = n * n + k * n
    L = work[w0:w0 + k * k].reshape((k, k))
    Gi = work[w0 + k * k:w0 + 2 * k * k].reshape((k, k))
    x = work[w0 + 2 * k * k:]  # D: 0, tmp: n, y: 2n, lambda: 2n + k, b: 2n + 2k, col: 2n + 3k
    TM = n
    YY = 2 * n
    LA = 2 * n + k
    BB = 2 * n + 2 * k
    CO = 2 * n + 3 * k
    SH = n + k
    SC = n + k + ng
    UP = SC + 4
    UQ = UP + k
    GE = UQ + k
    status = 0
    if check:  # full-rank certificate of A: ||L_G^-1||_F^2 tr(G) * c < 1, G = A A^T
        trace = 0.0
        ok = True
        for r in range(k):
            ar = tree[OR + r]
            sr = tree[CS + r]
            lr_ = tree[CL + r]
            for c in range(r + 1):
                ac = tree[OR + c]
                sc = tree[CS + c]
                s = 0.0
                for i in range(min(lr_, tree[CL + c])):  # chains share a prefix from the root
                    j = tree[CH + sr + i]
                    if j != tree[CH + sc + i]:
                        break
                    s += A[ar, j] * A[ac, j]
                if r == c:
                    trace += s
                for m in range(c):
                    s -= Gi[r, m] * Gi[c, m]
                if r == c:
                    if not s > 0.0:
                        ok = False
                        break
                    Gi[r, r] = math.sqrt(s)
                else:
                    Gi[r, c] = s / Gi[c, c]
            if not ok:
                break
        if ok:  # ||L_G^-1||_F^2 column by column (L x = e_c)
            fro = 0.0
            for c in range(k):
                for r in range(c, k):
                    s = 1.0 if r == c else 0.0
                    for m in range(c, r):
                        s -= Gi[r, m] * x[CO + m]
                    x[CO + r] = s / Gi[r, r]
                    fro += x[CO + r] * x[CO + r]
            denom = fro * trace
            ok = math.isfinite(denom) and denom * RANK_CERTIFICATE < 1.0
        if not ok:
            status = 3
    if upto == 0:
        return status
    # M = U D U^T on the tree (pinocchio::cholesky::decompose); x[:n] holds 1 / D afterwards
    for j in range(n):
        x[j] = M[j, j]
        i = tree[P + j]
        while i >= 0:
            U[i, j] = M[i, j]
            i = tree[P + i]
    for j in range(n - 1, -1, -1):
        e = j + tree[NV + j]
        s = x[j]
        for c in range(j + 1, e):
            t = U[j, c] * x[c]
            x[TM + c] = t
            s -= U[j, c] * t
        if not s > 0.0:
            return 1
        x[j] = s
        inv = 1.0 / s
        i = tree[P + j]
        while i >= 0:
            s = U[i, j]
            for c in range(j + 1, e):
                s -= U[i, c] * x[TM + c]
            U[i, j] = s * inv
            i = tree[P + i]
    for j in range(n):
        x[j] = 1.0 / x[j]
    if upto == 1:
        return status
    # Y = U^-1 A_p^T (row r nonzero on its chain only), b = A_p v
    for r in range(k):
        ar = tree[OR + r]
        sr = CH + tree[CS + r]
        lr_ = tree[CL + r]
        s = 0.0
        for i in range(lr_):
            j = tree[sr + i]
            s += A[ar, j] * v[j]
        x[BB + r] = s
        for i in range(lr_ - 1, -1, -1):
            j = tree[sr + i]
            s = A[ar, j]
            for m in range(i + 1, lr_):
                c = tree[sr + m]
                s -= U[j, c] * Y[r, c]
            Y[r, j] = s
    if upto == 2:
        return status
    # W = Y D^-1 Y^T = L L^T (the chains of two rows share a prefix from the root)
    for r in range(k):
        sr = CH + tree[CS + r]
        lr_ = tree[CL + r]
        for c in range(r + 1):
            sc = CH + tree[CS + c]
            s = 0.0
            for i in range(min(lr_, tree[CL + c])):
                j = tree[sr + i]
                if j != tree[sc + i]:
                    break
                s += Y[r, j] * Y[c, j] * x[j]
            for m in range(c):
                s -= L[r, m] * L[c, m]
            if r == c:
                if not s > 0.0:
                    return 2
                L[r, r] = math.sqrt(s)
            else:
                L[r, c] = s / L[c, c]
    if upto == 3:
        return status
    # y = L^-1 b, lambda_p = -L^-T y
    for r in range(k):
        s = x[BB + r]
        for m in range(r):
            s -= L[r, m] * x[YY + m]
        x[YY + r] = s / L[r, r]
    for r in range(k - 1, -1, -1):
        s = -x[YY + r]
        for m in range(r + 1, k):
            s -= L[m, r] * x[LA + m]
        x[LA + r] = s / L[r, r]
    # q_dot+ = v + U^-T D^-1 Y^T lambda_p
    for j in range(n):
        x[TM + j] = 0.0
    for r in range(k):
        sr = CH + tree[CS + r]
        lr = x[LA + r]
        for i in range(tree[CL + r]):
            j = tree[sr + i]
            x[TM + j] += Y[r, j] * lr
    for j in range(n):
        s = x[TM + j] * x[j]
        i = tree[P + j]
        while i >= 0:
            s -= U[i, j] * out[i]
            i = tree[P + i]
        out[j] = s
    for j in range(n):
        out[j] += v[j]
    if upto == 4:
        return status
    # outputs in contact order, energies
    t_c = 0.0
    for g in range(ng):
        s = 0.0
        for r in range(tree[BD + g], tree[BD + g + 1]):
            s += x[YY + r] * x[YY + r]
        out[SH + g] = 0.5 * s
        t_c += 0.5 * s
    t0 = 0.0
    t1 = 0.0
    for j in range(n):
        s0 = 0.5 * M[j, j] * v[j]
        s1 = 0.5 * M[j, j] * out[j]
        i = tree[P + j]
        while i >= 0:
            s0 += M[i, j] * v[i]
            s1 += M[i, j] * out[i]
            i = tree[P + i]
        t0 += s0 * v[j]
        t1 += s1 * out[j]
    out[SC] = t0
    out[SC + 1] = t1
    out[SC + 2] = t_c
    out[SC + 3] = t0 - t1
    for j in range(n):
        out[GE + j] = 0.0
    for r in range(k):
        ar = tree[OR + r]
        sr = CH + tree[CS + r]
        lr = x[LA + r]
        s0 = 0.0
        s1 = 0.0
        for i in range(tree[CL + r]):
            j = tree[sr + i]
            s0 += A[ar, j] * v[j]
            s1 += A[ar, j] * out[j]
            out[GE + j] += A[ar, j] * lr
        out[n + ar] = lr
        out[UP + ar] = s0
        out[UQ + ar] = s1
    return status


@njit(cache=True)
def inert_batch(Ms: FloatArray, As: FloatArray, vs: FloatArray, tree: IntArray,
                work: FloatArray, out: FloatArray, status: IntArray,
                check: bool) -> None:  # pragma: no cover
    """:func:`inert_item` for every configuration ``b < len(status)`` of the stacks
    ``Ms`` (B, n, n), ``As`` (B, k, n), ``vs`` (B, n) into ``out[b]`` and ``status[b]``."""
    for b_ in range(status.shape[0]):
        status[b_] = inert_item(Ms[b_], As[b_], vs[b_], tree, work, out[b_], check)
