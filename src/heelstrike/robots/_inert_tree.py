"""The integer layout of a kinematic tree and of contact rows for the inert impact kernel.

Numba-free, so that a process whose kernel comes from the ahead-of-time module
(:mod:`heelstrike.dynamics._aot`) never imports numba: the kernel itself is
:mod:`heelstrike.robots._inert_kernel`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["RANK_CERTIFICATE", "IntArray", "chain", "out_size", "tree_arrays", "tree_layout",
           "work_size"]

IntArray = NDArray[np.int64]

#: The full-rank certificate of :func:`heelstrike.core.contact_laws._certified_full_rank`:
#: ``||L_G^-1||_F^2 tr(G) * RANK_CERTIFICATE < 1`` with ``G = A A^T = L_G L_G^T``.
RANK_CERTIFICATE = 1e-10


def tree_arrays(parents_joint: list[int], idx_v: list[int], nv_joint: list[int],
                nv: int) -> tuple[IntArray, IntArray]:
    """Per dof: its parent dof (``-1`` at a root) and the size of its subtree (dofs).

    Parameters
    ----------
    parents_joint : list of int
        Parent joint of every joint (Pinocchio's ``model.parents``; joint 0 is the universe).
    idx_v, nv_joint : list of int
        First velocity index and number of velocity entries of every joint.
    nv : int
        Number of dofs.

    Returns
    -------
    parents : ndarray of int64, shape (nv,)
        Pinocchio's ``parents_fromRow``: the previous dof of the same joint, else the last
        dof of the nearest ancestor joint with dofs, else ``-1``.
    nvsub : ndarray of int64, shape (nv,)
        Pinocchio's ``nvSubtree_fromRow``.
    """
    nj = len(parents_joint)
    sub = [int(nv_joint[j]) for j in range(nj)]
    for j in range(nj - 1, 0, -1):
        sub[parents_joint[j]] += sub[j]
    parents = np.full(nv, -1, dtype=np.int64)
    nvsub = np.zeros(nv, dtype=np.int64)
    for j in range(1, nj):
        s, n = int(idx_v[j]), int(nv_joint[j])
        if n == 0:
            continue
        p = parents_joint[j]
        while p > 0 and nv_joint[p] == 0:
            p = parents_joint[p]
        parents[s] = int(idx_v[p]) + int(nv_joint[p]) - 1 if p > 0 else -1
        for i in range(n):
            if i:
                parents[s + i] = s + i - 1
            nvsub[s + i] = sub[j] - i
    return parents, nvsub



def chain(parents_joint: list[int], idx_v: list[int], nv_joint: list[int],
          joint: int) -> list[int]:
    """The dofs of ``joint`` and of its ancestors, ascending (those that move its body)."""
    dofs: list[int] = []
    while joint > 0:
        dofs += range(int(idx_v[joint]), int(idx_v[joint]) + int(nv_joint[joint]))
        joint = parents_joint[joint]
    return sorted(dofs)


def tree_layout(parents: IntArray, nvsub: IntArray, order: IntArray, bounds: IntArray,
                chains: list[list[int]]) -> IntArray:
    """The integer array :func:`inert_item` reads: ``n, k, groups``, then ``parents (n),
    nvsub (n), order (k), bounds (groups + 1)``, per row in nesting order the start and length
    of its chain, and the chains.

    Parameters
    ----------
    parents, nvsub : ndarray of int, shape (n,)
        :func:`tree_arrays`.
    order, bounds : ndarray of int
        :class:`~heelstrike.core.contact_laws.InertLayout`'s nesting order (k,) and group
        boundaries (groups + 1,).
    chains : list of list of int
        Per row in contact order, the dofs its row may be non-zero on, ascending: the dofs of
        the joints from the root to the joint that moves the contact (its ancestor path).
    """
    k = len(order)
    start: list[int] = []
    length: list[int] = []
    flat: list[int] = []
    for r in range(k):
        ch = chains[int(order[r])]
        start.append(len(flat))
        length.append(len(ch))
        flat += ch
    head = [len(parents), k, len(bounds) - 1]
    return np.concatenate([np.asarray(x, dtype=np.int64) for x in (
        head, parents, nvsub, order, bounds, start, length, flat)])


def work_size(n: int, k: int) -> int:
    """Length of the float work array of :func:`inert_item` for ``n`` dofs and ``k`` rows."""
    return n * n + k * n + 2 * k * k + 2 * n + 4 * k


def out_size(n: int, k: int, groups: int) -> int:
    """Length of one output row: ``q_dot+ (n), lambda (k), shares (groups), T, T+, T_c,
    T - T+, A q_dot- (k), A q_dot+ (k), A^T lambda (n)``."""
    return 2 * n + 3 * k + groups + 4
