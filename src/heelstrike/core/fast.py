"""Plumbing of the compiled, batched impact kernels: result type, twin compiles, batch runner.

The reference implementation :func:`heelstrike.core.impact.impact` handles any ``n`` and ``k``
with batched LAPACK calls on per-item ``(n, n)`` matrices. The compiled kernels (the compass
gait's closed-form heel strike, :func:`heelstrike.models.compass_fast.heel_strike_impact`, and
the walking kernels of :mod:`heelstrike.dynamics._compass_kernels`) share what is here: a batch
kernel is one Python function compiled twice, serial and ``prange``-parallel
(:func:`serial_and_parallel`); :func:`batched_impact` runs it on flat outputs and returns a
:class:`FastImpactResult`, raising :class:`~heelstrike.core.impact.ImpactInputError` for the first
item whose status is not 0 (:func:`raise_for_status`).

The parallel kernel runs when called from the main thread and the serial one from any other
thread (e.g. a Dask worker thread in :func:`heelstrike.analysis.sweep.sweep`), so that chunk-level
and item-level parallelism do not oversubscribe the cores.
"""

from __future__ import annotations

import types
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from heelstrike._caching import tolerate_numba_cache_errors
from heelstrike._results import tuple_dict
from heelstrike._typing import FloatArray
from heelstrike.core._parallel import use_parallel
from heelstrike.core.impact import ImpactInputError

tolerate_numba_cache_errors()  # numba's cache unwritable (full disk): run uncached

__all__ = ["FastImpactResult", "batched_impact", "raise_for_status", "serial_and_parallel",
           "use_parallel"]


class FastImpactResult(NamedTuple):
    """Result of a compiled impact kernel run by :func:`batched_impact`; field names follow
    :class:`~heelstrike.core.ImpactResult`.

    ``(...)`` is the broadcast batch shape of the inputs.

    Attributes
    ----------
    kinetic_energy : ndarray, shape (...)
        Pre-impact kinetic energy ``T`` (J), eq. (10).
    kinetic_energy_constrained : ndarray, shape (...)
        ``T_c = 1/2 (P_c q_dot-)^T M (P_c q_dot-)`` (J).
    kinetic_energy_admissible : ndarray, shape (...)
        ``T_a = 1/2 (P_a q_dot-)^T M (P_a q_dot-)`` (J).
    velocity_post : ndarray, shape (..., 4)
        ``q_dot+`` (m/s, rad/s).
    constraint_impulse : ndarray, shape (..., 2)
        ``lambda`` with ``M (q_dot+ - q_dot-) = A^T lambda`` (N s).
    energy_lost : ndarray, shape (...)
        ``(1 - e^2) T_c`` (J).
    """

    kinetic_energy: FloatArray
    kinetic_energy_constrained: FloatArray
    kinetic_energy_admissible: FloatArray
    velocity_post: FloatArray
    constraint_impulse: FloatArray
    energy_lost: FloatArray

    def to_dict(self) -> dict[str, Any]:
        """Every field as plain Python (:func:`~heelstrike._results.tuple_dict`)."""
        return tuple_dict(self)


def serial_and_parallel(py_func: Callable[..., None], **options: Any) -> tuple[Any, Any]:
    """Compile a batch kernel twice with numba: ``(serial, parallel)``.

    ``py_func`` loops over its items with ``numba.prange``, which is ``range`` in the serial
    compile and a parallel loop in the ``parallel=True`` one; ``options`` go to both ``njit``
    calls (``cache=True`` is added). Each compile gets its own copy of the function, named
    ``<name>_serial`` / ``<name>_parallel``: numba keys its disk cache by a function's name and
    bytecode but not by the compile options, so two compiles of one function would load each
    other's cached code (the parallel kernel running serially, or worse).
    """

    def named(suffix: str) -> Callable[..., None]:
        f = types.FunctionType(py_func.__code__, py_func.__globals__, py_func.__name__ + suffix,
                               py_func.__defaults__, py_func.__closure__)
        f.__qualname__ = py_func.__qualname__ + suffix
        f.__doc__ = py_func.__doc__
        return f

    serial = njit(cache=True, **options)(named("_serial"))
    parallel = njit(cache=True, parallel=True, **options)(named("_parallel"))
    return serial, parallel


def raise_for_status(status: NDArray[np.uint8], messages: dict[int, str]) -> None:
    """Raise :class:`ImpactInputError` for the first item whose status is not OK."""
    bad = np.flatnonzero(status)
    if bad.size:
        first = int(bad[0])
        code = int(status[first])
        raise ImpactInputError(
            f"{messages.get(code, f'status {code}')} (flat batch index {first}; "
            f"{bad.size} bad item(s) in total)"
        )


def batched_impact(
    kernels: tuple[Any, Any],
    args: tuple[Any, ...],
    batch: tuple[int, ...],
    e: float,
    parallel: bool | None,
    messages: Callable[[NDArray[np.uint8]], dict[int, str]],
) -> FastImpactResult:
    """Run a ``(serial, parallel)`` impact kernel pair (:func:`serial_and_parallel`) on a batch.

    The kernel is called as ``kernel(*args, e, T, Tc, Ta, q_dot+, lambda, status)`` on flat
    outputs of ``prod(batch)`` items; a status other than 0 raises :class:`ImpactInputError`
    with ``messages(status)[code]``.
    """
    n = int(np.prod(batch, dtype=np.int64))
    T = np.empty(n)
    Tc = np.empty(n)
    Ta = np.empty(n)
    qp = np.empty((n, 4))
    lam = np.empty((n, 2))
    status = np.zeros(n, dtype=np.uint8)
    kernel = kernels[1] if use_parallel(parallel) else kernels[0]
    kernel(*args, e, T, Tc, Ta, qp, lam, status)
    raise_for_status(status, messages(status))
    Tc_ = Tc.reshape(batch)
    return FastImpactResult(
        kinetic_energy=T.reshape(batch),
        kinetic_energy_constrained=Tc_,
        kinetic_energy_admissible=Ta.reshape(batch),
        velocity_post=qp.reshape((*batch, 4)),
        constraint_impulse=lam.reshape((*batch, 2)),
        energy_lost=(1.0 - e * e) * Tc_,
    )
