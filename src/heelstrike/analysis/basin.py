"""Basin of attraction of a passive gait (Schwab & Wisse 2001), with the compiled ensemble.

**Section.** Initial states are post-impact section points ``z = (q3, q3_dot, q4_dot)`` (just
after heel strike and the leg swap, ``q4 = -2 q3``, stance foot rolling). The basin is drawn on
the 2-D slice through the gait's fixed point ``z*`` spanned by the stance angle ``q3`` (rad) and
the stance angular velocity ``q3_dot`` (rad/s), with the swing velocity held at its fixed-point
value ``q4_dot = q4_dot*``. (Schwab & Wisse's simplest walker has a 2-D section; the compass gait's
is 3-D, so a slice is shown.)

**Classification.** Every grid point is walked with
:func:`~heelstrike.dynamics.compiled.ensemble_walk` for up to ``steps`` steps. It *converges* when
its post-impact state comes within ``tol`` (Euclidean norm in section coordinates) of ``z*`` within
those steps (the walk is stopped there); it *keeps walking* if it completes every step without
doing so (another attractor, or slow convergence); otherwise it failed, with the
:class:`~heelstrike.dynamics.hybrid.WalkStatus` of the failure.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray

from heelstrike.analysis.limit_cycle import find_limit_cycle
from heelstrike.dynamics.compiled import STATUS_NAMES, ensemble_walk
from heelstrike.models.compass import CompassGait

FloatArray = NDArray[np.float64]

__all__ = ["OUTCOMES", "Basin", "basin_of_attraction"]

#: Outcome codes of the basin (``flag_values`` / ``flag_meanings`` of the dataset).
OUTCOMES: tuple[str, ...] = (
    "converged",
    "keeps_walking",
    "fell_forward",
    "fell_backward",
    "trailing_foot_stays",
    "lost_contact",
    "no_heel_strike",
    "integration_failed",
)

#: Default window of the slice: ``q3`` (rad) and ``q3_dot`` (rad/s) ranges.
DEFAULT_RANGES: tuple[tuple[float, float], tuple[float, float]] = ((-0.5, -0.05), (0.3, 2.3))


@dataclass(frozen=True, kw_only=True)
class Basin:
    """A computed basin of attraction.

    Attributes
    ----------
    dataset : xarray.Dataset
        ``outcome`` (int8 codes of :data:`OUTCOMES`), ``steps`` (heel strikes taken) and
        ``distance`` (final distance to the fixed point) over coordinates ``q3`` (rad) and
        ``q3_dot`` (rad/s); the fixed point, slope and walker parameters as attributes.
    fixed_point : ndarray, shape (3,)
        ``z* = (q3, q3_dot, q4_dot)`` of the passive gait (rad, rad/s).
    converging_fraction : float
        Fraction of the grid's initial states that converge to the gait.
    elapsed : float
        Wall time of the ensemble run (s).
    """

    dataset: xr.Dataset
    fixed_point: FloatArray
    converging_fraction: float
    elapsed: float

    def fractions(self) -> dict[str, float]:
        """Fraction of the grid in every outcome."""
        codes = self.dataset["outcome"].values.ravel()
        return {name: float(np.mean(codes == i)) for i, name in enumerate(OUTCOMES)}


def basin_of_attraction(
    walker: CompassGait,
    slope: float,
    grid: tuple[int, int] = (400, 400),
    ranges: tuple[tuple[float, float], tuple[float, float]] = DEFAULT_RANGES,
    steps: int = 60,
    *,
    tol: float = 1e-3,
    fixed_point: ArrayLike | None = None,
    rtol: float = 1e-8,
    atol: float = 1e-9,
    chunks: int = 16,
    parallel: bool | None = None,
    progress: bool = False,
) -> Basin:
    """Basin of attraction of the passive period-one gait on the ``(q3, q3_dot)`` slice.

    Parameters
    ----------
    walker : CompassGait
        Scalar-parameter walker.
    slope : float
        Slope (rad).
    grid : (int, int)
        Number of ``q3`` and ``q3_dot`` values.
    ranges : ((float, float), (float, float))
        ``(q3_min, q3_max)`` (rad) and ``(q3_dot_min, q3_dot_max)`` (rad/s), inclusive.
    steps : int
        Largest number of steps walked from every initial state.
    tol : float
        Convergence radius around the fixed point (section norm, rad and rad/s mixed).
    fixed_point : array_like, shape (3,), optional
        The gait's section point; found with Newton (compiled map) from the automatic search if
        omitted.
    rtol, atol : float
        Integrator tolerances of the ensemble.
    chunks : int
        Number of ensemble calls the grid is split into (for the progress bar).
    parallel : bool, optional
        See :func:`~heelstrike.dynamics.compiled.ensemble_walk`.
    progress : bool
        Show a progress bar.

    Returns
    -------
    Basin
    """
    n3, nd = (int(v) for v in grid)
    if n3 < 1 or nd < 1:
        raise ValueError(f"grid must be positive, got {grid}")
    if steps < 1:
        raise ValueError("steps must be >= 1")
    (a0, a1), (b0, b1) = ranges
    if not (a0 < a1 and b0 < b1):
        raise ValueError(f"ranges must be increasing (min < max), got {ranges}")
    if fixed_point is None:
        zstar = find_limit_cycle(walker, slope=slope, method="compiled").fixed_point
    else:
        zstar = np.asarray(fixed_point, dtype=float).reshape(3)
    q3 = np.linspace(a0, a1, n3)
    q3d = np.linspace(b0, b1, nd)
    A, B = np.meshgrid(q3, q3d, indexing="ij")
    Z = np.column_stack((A.ravel(), B.ravel(), np.full(A.size, zstar[2])))
    status = np.empty(A.size, dtype=np.int64)
    taken = np.empty(A.size, dtype=np.int64)
    zf = np.empty((A.size, 3))
    parts = np.array_split(np.arange(A.size), max(1, min(int(chunks), A.size)))
    bar: Any = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=A.size, desc="basin of attraction", unit="walker", leave=False)
    t0 = time.perf_counter()
    for idx in parts:
        res = ensemble_walk(
            walker, Z[idx], slope, steps=steps, rtol=rtol, atol=atol, record=False,
            stop_near=(zstar, tol), parallel=parallel,
        )
        status[idx], taken[idx], zf[idx] = res.status, res.steps, res.z
        if bar is not None:
            bar.update(len(idx))
    elapsed = time.perf_counter() - t0
    if bar is not None:
        bar.close()
    dist = np.linalg.norm(zf - zstar, axis=1)
    completed = status == STATUS_NAMES.index("completed")
    outcome = np.empty(A.size, dtype=np.int8)
    for code, name in enumerate(STATUS_NAMES):
        if name in OUTCOMES:
            outcome[status == code] = OUTCOMES.index(name)
    outcome[completed] = OUTCOMES.index("keeps_walking")
    outcome[completed & (dist < tol)] = OUTCOMES.index("converged")
    shape = (n3, nd)
    dims = ("q3", "q3_dot")
    ds = xr.Dataset(
        {
            "outcome": (dims, outcome.reshape(shape), {
                "long_name": "fate of the initial state",
                "flag_values": np.arange(len(OUTCOMES), dtype=np.int8),
                "flag_meanings": " ".join(OUTCOMES),
            }),
            "steps": (dims, taken.reshape(shape).astype(np.int32), {
                "long_name": "heel strikes taken (a converged walk stops on arrival)",
                "units": "1",
            }),
            "distance": (dims, dist.reshape(shape), {
                "long_name": "final distance to the fixed point in section coordinates",
            }),
        },
        coords={
            "q3": ("q3", q3, {"units": "rad", "long_name": "post-impact stance angle q3"}),
            "q3_dot": ("q3_dot", q3d, {
                "units": "rad s-1", "long_name": "post-impact stance angular velocity q3_dot",
            }),
        },
        attrs={
            "title": "basin of attraction of the passive compass gait",
            "section": "post-impact (q3, q3_dot) with q4 = -2 q3 and q4_dot = q4_dot*",
            "q4_dot": float(zstar[2]),
            "q4_dot_units": "rad s-1",
            "fixed_point_q3": float(zstar[0]),
            "fixed_point_q3_dot": float(zstar[1]),
            "fixed_point_q4_dot": float(zstar[2]),
            "slope": float(slope),
            "slope_units": "rad",
            "foot_radius": float(walker.foot_radius),
            "hip_mass": float(walker.hip_mass),
            "leg_mass": float(walker.leg_mass),
            "leg_length": float(walker.leg_length),
            "leg_com_from_hip": float(walker.leg_com_from_hip),
            "leg_inertia": float(walker.leg_inertia),
            "gravity": float(walker.gravity),
            "max_steps": int(steps),
            "tol": float(tol),
            "rtol": float(rtol),
            "atol": float(atol),
        },
    )
    frac = float(np.mean(outcome == 0))
    ds.attrs["converging_fraction"] = frac
    return Basin(dataset=ds, fixed_point=zstar, converging_fraction=frac, elapsed=elapsed)
