"""Basin of attraction of a passive gait (Schwab & Wisse 2001), with the compiled ensemble.

**Section.** Initial states are post-impact section points ``z = (q3, q3_dot, q4_dot)`` (just
after heel strike and the leg swap, ``q4 = -2 q3``, stance foot rolling). The basin is drawn on
the 2-D slice through the gait's fixed point ``z*`` spanned by the stance angle ``q3`` (rad) and
the stance angular velocity ``q3_dot`` (rad/s), with the swing velocity held at its fixed-point
value ``q4_dot = q4_dot*``. (Schwab & Wisse's simplest walker has a 2-D section; the compass gait's
is 3-D, so a slice is shown.)

**Classification.** A grid point whose trailing foot is on the ground and moving into it
(:meth:`~heelstrike.models.base.PlanarWalker.trailing_foot_presses`) is the state after no heel
strike: it is not walked, its outcome is ``inadmissible_start``. Every other grid point is walked
with
:func:`~heelstrike.dynamics.compiled.ensemble_walk` for up to ``steps`` steps. It *converges* when
its post-impact state comes within ``tol`` (Euclidean norm in section coordinates) of ``z*`` within
those steps (the walk is stopped there); it *keeps walking* if it completes every step without
doing so (another attractor, or slow convergence); otherwise it failed, with the
:class:`~heelstrike.dynamics.hybrid.WalkStatus` of the failure. The gait's stability is recorded
with the fixed point (:attr:`Basin.gait_stable`, :attr:`Basin.spectral_radius`): the basin of an
unstable gait is empty, no initial state converges to it.

**Described walkers** (TOML models): :func:`model_basin_of_attraction` draws the same
classification on the slice of the walker's post-heel-strike section
(:class:`~heelstrike.dynamics.phased.PhasedWalker`) spanned by the stance angle ``q[2]`` and its
rate, the other section coordinates held at the fixed point, walked with
:func:`~heelstrike.dynamics.compiled_phased.ensemble_walk_phased` (or the scipy reference).
"""

from __future__ import annotations

import functools
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.analysis._defaults import BASIN_STEPS, BASIN_TOLERANCE
from heelstrike.analysis._memory import available_memory, require_budget
from heelstrike.analysis.limit_cycle import Gait, find_limit_cycle
from heelstrike.dynamics.backends import check_one_walker
from heelstrike.dynamics.compiled import ensemble_walk
from heelstrike.dynamics.hybrid import WalkStatus
from heelstrike.models.base import PlanarWalker, check_backend_name
from heelstrike.models.compass import CompassGait

if TYPE_CHECKING:
    from heelstrike.models.builder import BuiltWalker
    from heelstrike.models.description import WalkerDescription


__all__ = [
    "BYTES_PER_POINT",
    "OUTCOMES",
    "Basin",
    "available_memory",
    "basin_memory_estimate",
    "basin_of_attraction",
    "default_ranges",
    "model_basin_of_attraction",
    "model_slice_axes",
]

#: The outcomes of a basin, in report order: members of
#: :class:`~heelstrike.dynamics.hybrid.WalkStatus`, the one walk vocabulary. A walk that took
#: every step is ``CONVERGED`` (within the tolerance of the gait) or ``KEEPS_WALKING``; any other
#: ends with the status of its failure; a start that is not walked is ``INADMISSIBLE_START``. The
#: dataset's ``outcome`` holds the members' codes (``flag_values`` / ``flag_meanings``), so code 0
#: (``completed``, which a basin never reports) means what it means for every walk.
OUTCOMES: tuple[WalkStatus, ...] = (
    WalkStatus.CONVERGED,
    WalkStatus.KEEPS_WALKING,
    WalkStatus.FELL_FORWARD,
    WalkStatus.FELL_BACKWARD,
    WalkStatus.TRAILING_FOOT_STAYS,
    WalkStatus.LOST_CONTACT,
    WalkStatus.NO_HEEL_STRIKE,
    WalkStatus.INTEGRATION_FAILED,
    WalkStatus.SLIPPED,
    WalkStatus.NO_CONSISTENT_ASSIGNMENT,
    WalkStatus.NO_LEG_SWAP,
    WalkStatus.INADMISSIBLE_START,
    WalkStatus.OFF_PROFILE,
)

#: Default window of the slice: ``q3`` (rad) and ``q3_dot`` (rad/s) ranges (widened where
#: needed to hold the fixed point with :data:`DEFAULT_MARGINS` to spare).
DEFAULT_RANGES: tuple[tuple[float, float], tuple[float, float]] = ((-0.5, -0.05), (0.3, 2.3))

#: Least distance (rad, rad/s) from the fixed point to the edges of the default window.
DEFAULT_MARGINS: tuple[float, float] = (0.1, 0.3)


def default_ranges(fixed_point: ArrayLike) -> tuple[tuple[float, float], tuple[float, float]]:
    """The compass basin's default window: :data:`DEFAULT_RANGES`, each edge moved out as far
    as needed to keep the fixed point ``(q3, q3_dot, ...)`` :data:`DEFAULT_MARGINS` inside it
    (large feet walk with ``|q3| > 0.5`` rad: ``R = 0.5 m`` at 3 deg has ``q3 = -0.547``)."""
    z = np.asarray(fixed_point, dtype=float)
    return tuple(  # type: ignore[return-value]
        (min(lo, float(z[i]) - m), max(hi, float(z[i]) + m))
        for i, ((lo, hi), m) in enumerate(zip(DEFAULT_RANGES, DEFAULT_MARGINS, strict=True))
    )


#: Memory (bytes) a basin needs per grid point, an upper estimate: the initial states, final
#: states, statuses and step counts (about 120 B), the dataset, and the figure and netCDF file
#: written from it.
BYTES_PER_POINT = 256


def basin_memory_estimate(grid: tuple[int, int]) -> int:
    """Estimated peak memory (bytes) of a basin over ``grid`` points, figure and file included.

    Parameters
    ----------
    grid : (int, int)
        Number of ``q3`` and ``q3_dot`` values.
    """
    n3, nd = (int(v) for v in grid)
    return n3 * nd * BYTES_PER_POINT


def _check_memory(grid: tuple[int, int]) -> None:
    require_budget(f"a {grid[0]}x{grid[1]} basin", int(grid[0]) * int(grid[1]),
                   bytes_per_point=BYTES_PER_POINT)


@dataclass(frozen=True, kw_only=True)
class Basin(ResultDictMixin):
    """A computed basin of attraction.

    Attributes
    ----------
    dataset : xarray.Dataset
        ``outcome`` (int8 :class:`~heelstrike.dynamics.hybrid.WalkStatus` codes, one of
        :data:`OUTCOMES` each), ``steps`` (heel strikes taken) and
        ``distance`` (final distance to the fixed point) over coordinates ``q3`` (rad) and
        ``q3_dot`` (rad/s); the fixed point, slope and walker parameters as attributes.
    fixed_point : ndarray, shape (3,)
        ``z* = (q3, q3_dot, q4_dot)`` of the passive gait (rad, rad/s).
    converging_fraction : float
        Fraction of the grid's initial states that converge to the gait.
    elapsed : float
        Wall time of the ensemble run (s).
    axes : (int, int)
        Indices in ``fixed_point`` of the slice's two coordinates (the dataset's two dims).
    walker_steps : int
        Heel strikes taken by all initial states together (the ensemble's work).
    gait_stable : bool or None
        Whether the period-one gait the basin is built around is stable (all Floquet
        multipliers inside the unit circle); None if unknown (the fixed point was given). An
        unstable gait attracts no initial state: its basin is empty (0 % converging).
    spectral_radius : float or None
        Largest ``|multiplier|`` of that gait (1), None if unknown.
    hanging_links : tuple of str
        The links described upright that the gait carries hanging at the fixed point
        (:func:`~heelstrike.analysis.model_gaits.hanging_links`): the basin is then that of a
        gait of the hanging link. Empty for the compass gait and walkers without such links.
    """

    dataset: xr.Dataset
    fixed_point: FloatArray
    converging_fraction: float
    elapsed: float
    axes: tuple[int, int] = (0, 1)
    walker_steps: int = 0
    gait_stable: bool | None = None
    spectral_radius: float | None = None
    hanging_links: tuple[str, ...] = ()

    def fractions(self) -> dict[str, float]:
        """Fraction of the grid in every outcome (keys: the :data:`OUTCOMES`, in order)."""
        codes = self.dataset["outcome"].values.ravel()
        return {s.value: float(np.mean(codes == s.code)) for s in OUTCOMES}


def _check_grid(grid: tuple[int, int], steps: int) -> tuple[int, int]:
    """The grid sizes, after the checks every basin makes before computing."""
    if any(isinstance(v, bool) or int(v) != v for v in grid):
        raise ValueError(f"grid must be two whole numbers, got {grid}")
    n1, n2 = (int(v) for v in grid)
    if n1 < 1 or n2 < 1:
        raise ValueError(f"grid must be positive, got {grid}")
    _check_memory((n1, n2))
    if steps < 1:
        raise ValueError("steps must be >= 1")
    return n1, n2


def _walk_slice(
    func: Any, coords: dict[str, FloatArray], units: tuple[str, str], zstar: FloatArray,
    tol: float, chunks: int, store: str | os.PathLike[str] | None, progress: bool,
) -> tuple[NDArray[np.int8], NDArray[np.int64], FloatArray, float]:
    """Walk every point of the slice grid ``coords`` (two 1-D axes) with the sweep function
    ``func``, in blocks of whole rows of the first axis; returns the outcome codes, heel
    strikes taken, final distances to ``zstar`` (flattened) and the wall time (s)."""
    from heelstrike.analysis.sweep import sweep

    (first, values), (second, _) = coords.items()
    rows = -(-values.size // max(1, min(int(chunks), values.size)))  # rows per ensemble call
    t0 = time.perf_counter()
    res = sweep(
        func, coords, chunks={first: rows}, store=store, scheduler="sync",
        progress="basin of attraction" if progress else False,
        units={first: units[0], second: units[1], "status": "1", "steps": "1", "z": "1"},
    )
    status = np.asarray(res["status"].values).ravel()
    taken = np.asarray(res["steps"].values).ravel()
    zf = np.asarray(res["z"].values).reshape(-1, zstar.size)
    elapsed = time.perf_counter() - t0
    dist = np.linalg.norm(zf - zstar, axis=1)
    return _classify(status, dist, tol), taken, dist, elapsed


def _make_basin(
    coords: dict[str, Any], attrs: dict[str, Any], outcome: NDArray[np.int8],
    taken: NDArray[np.int64], dist: FloatArray, zstar: FloatArray, elapsed: float,
    axes: tuple[int, int] = (0, 1), gait: Gait | None = None,
    hanging: tuple[str, ...] = (),
) -> Basin:
    """The :class:`Basin` of a walked slice (compass and described walkers alike); ``gait``:
    the period-one gait found at ``zstar`` (its stability goes into the result and the
    dataset's ``gait_stable`` (0/1) and ``gait_spectral_radius`` attributes), None if the
    fixed point was given; ``hanging``: :attr:`Basin.hanging_links`."""
    dims = tuple(coords)
    shape = tuple(len(coords[d][1]) for d in dims)
    from heelstrike.analysis.sweep import _attribute_units

    attrs = {**attrs, **_attribute_units(attrs, {
        "max_steps": "1", "tol": "rad, rad s-1 (mixed)", "rtol": "1", "atol": "1"})}
    ds = xr.Dataset(
        {
            "outcome": (dims, np.asarray(outcome).reshape(shape), {
                "long_name": "fate of the initial state",
                "flag_values": np.array([s.code for s in OUTCOMES], dtype=np.int8),
                "flag_meanings": " ".join(OUTCOMES),
            }),
            "steps": (dims, np.asarray(taken).reshape(shape).astype(np.int32), {
                "long_name": "heel strikes taken (a converged walk stops on arrival)",
                "units": "1",
            }),
            "distance": (dims, np.asarray(dist).reshape(shape), {
                "long_name": "final distance to the fixed point in section coordinates "
                             "(Euclidean norm of rad and rad/s components, as the convergence "
                             "test --tol)",
                "units": "rad, rad s-1 (mixed)",
            }),
        },
        coords=coords,
        attrs=attrs,
    )
    frac = float(np.mean(outcome == WalkStatus.CONVERGED.code))
    ds.attrs["converging_fraction"] = frac
    ds.attrs["converging_fraction_units"] = "1"
    stable = rho = None
    if gait is not None:
        stable, rho = bool(gait.stable), float(gait.spectral_radius)
        ds.attrs["gait_stable"] = np.int8(stable)  # netCDF attributes have no booleans
        ds.attrs["gait_spectral_radius"] = rho
        ds.attrs.update(gait_stable_units="1", gait_spectral_radius_units="1")
    return Basin(dataset=ds, fixed_point=zstar, converging_fraction=frac, elapsed=elapsed,
                 axes=axes, walker_steps=int(taken.sum()), gait_stable=stable,
                 spectral_radius=rho, hanging_links=hanging)


def _walk_chunk(
    a: FloatArray, b: FloatArray, zstar: tuple[float, ...], axes: tuple[int, int],
    walk: Callable[[FloatArray], tuple[ArrayLike, ArrayLike, ArrayLike]],
    walker: PlanarWalker, states: Callable[[FloatArray], tuple[FloatArray, FloatArray]],
) -> dict[str, NDArray[np.generic]]:
    """Sweep-function body: ``walk`` the section points ``zstar`` with coordinates ``axes`` set
    to the chunk's broadcast ``(a, b)`` grid (``walk(Z)``, ``Z`` of shape ``(n, d)``, returns
    the status codes, heel strikes taken and final section points); returns ``status`` and
    ``steps`` (int64, shape ``(n_a, n_b)``) and ``z`` (shape ``(n_a, n_b, d)``).

    Points whose state (``states(Z)``: ``(q, q_dot)``, each ``(n, n_q)``) has the ``walker``'s
    trailing foot pressing into the ground are not walked: status ``INADMISSIBLE_START``,
    no steps, final point the start."""
    A, B = np.broadcast_arrays(np.asarray(a, dtype=float), np.asarray(b, dtype=float))
    Z = np.tile(np.asarray(zstar), (A.size, 1))
    Z[:, axes[0]] = A.ravel()
    Z[:, axes[1]] = B.ravel()
    inadmissible = walker.trailing_foot_presses(*states(Z))
    status = np.full(A.size, WalkStatus.INADMISSIBLE_START.code, dtype=np.int64)
    taken = np.zeros(A.size, dtype=np.int64)
    zf = Z.copy()
    if not np.all(inadmissible):
        ok = ~inadmissible
        status[ok], taken[ok], zf[ok] = walk(Z[ok])
    return {
        "status": status.reshape(A.shape),
        "steps": taken.reshape(A.shape),
        "z": zf.reshape(*A.shape, len(zstar)),
    }


def basin_of_attraction(
    walker: CompassGait,
    slope: float,
    grid: tuple[int, int] = (400, 400),
    ranges: tuple[tuple[float, float] | None, tuple[float, float] | None] | None = None,
    steps: int = BASIN_STEPS,
    *,
    tol: float = BASIN_TOLERANCE,
    fixed_point: ArrayLike | None = None,
    rtol: float = 1e-8,
    atol: float = 1e-9,
    chunks: int = 16,
    parallel: bool | None = None,
    progress: bool = False,
    store: str | os.PathLike[str] | None = None,
    backend: str = "compiled",
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
    ranges : ((float, float), (float, float)), optional
        ``(q3_min, q3_max)`` (rad) and ``(q3_dot_min, q3_dot_max)`` (rad/s), inclusive;
        default (or for an axis given as None) :func:`default_ranges`
        (:data:`DEFAULT_RANGES`, widened to hold the fixed point).
    steps : int
        Largest number of steps walked from every initial state.
    tol : float
        Convergence radius around the fixed point (section norm, rad and rad/s mixed).
    fixed_point : array_like, shape (3,), optional
        The gait's section point; found with Newton (compiled map) from the automatic search if
        omitted (and then its stability is recorded: :attr:`Basin.gait_stable`).
    rtol, atol : float
        Integrator tolerances of the ensemble.
    chunks : int
        Number of ensemble calls the grid is split into (blocks of whole ``q3`` rows, at most
        one per row): the unit of the progress bar and of resuming.
    parallel : bool, optional
        See :func:`~heelstrike.dynamics.compiled.ensemble_walk`.
    progress : bool
        Show a progress bar.
    store : path, optional
        Zarr store of the ensemble run (:func:`~heelstrike.analysis.sweep.sweep`): every
        finished block is kept, and an interrupted run with the same arguments resumes there.
    backend : {"compiled", "scipy"}
        The compiled ensemble (default; :func:`~heelstrike.dynamics.compiled.ensemble_walk`)
        or the scipy reference, walker by walker and step by step (slow: hours for the
        default grid).

    Returns
    -------
    Basin

    Raises
    ------
    MemoryError
        Before any computing, if :func:`basin_memory_estimate` exceeds
        :func:`~heelstrike.analysis._memory.available_memory`; the message gives both.
    ValueError
        Unknown backend, or decreasing ranges.
    """
    check_backend_name(backend)
    check_one_walker(walker)
    n3, nd = _check_grid(grid, steps)
    given = (None, None) if ranges is None else ranges
    if any(r is not None and not r[0] < r[1] for r in given):
        raise ValueError(f"ranges must be increasing (min < max), got {ranges}")
    gait = None
    if fixed_point is None:
        gait = find_limit_cycle(walker, slope=slope, method=backend)
        zstar = gait.fixed_point
    else:
        zstar = np.asarray(fixed_point, dtype=float).reshape(3)
    (a0, a1), (b0, b1) = (r if r is not None else d
                          for r, d in zip(given, default_ranges(zstar), strict=True))
    q3 = np.linspace(a0, a1, n3)
    q3d = np.linspace(b0, b1, nd)
    func = functools.partial(
        _basin_chunk, walker=walker, slope=float(slope), zstar=tuple(map(float, zstar)),
        steps=int(steps), tol=float(tol), rtol=float(rtol), atol=float(atol), parallel=parallel,
        backend=backend,
    )
    outcome, taken, dist, elapsed = _walk_slice(
        func, {"q3": q3, "q3_dot": q3d}, ("rad", "rad s-1"), zstar, tol, chunks, store, progress)
    from heelstrike.analysis.gait_map import _walker_kwargs

    return _make_basin(
        {
            "q3": ("q3", q3, {"units": "rad", "long_name": "post-impact stance angle q3",
                              "label": r"post-impact stance angle $q_3$ (rad)"}),
            "q3_dot": ("q3_dot", q3d, {
                "units": "rad s-1", "long_name": "post-impact stance angular velocity q3_dot",
                "label": r"post-impact stance velocity $\dot q_3$ (rad/s)",
            }),
        },
        {
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
            **_walker_kwargs(walker),
            "max_steps": int(steps),
            "tol": float(tol),
            "rtol": float(rtol),
            "atol": float(atol),
            "backend": backend,
        },
        outcome, taken, dist, zstar, elapsed, gait=gait,
    )


def _classify(status: NDArray[np.int64], dist: FloatArray, tol: float) -> NDArray[np.int8]:
    """Outcome codes (:data:`OUTCOMES`' :class:`~heelstrike.dynamics.hybrid.WalkStatus` codes)
    from walk status codes and final distances: a completed walk is ``CONVERGED`` if it ended
    within ``tol`` of the fixed point, else ``KEEPS_WALKING``; every other status is itself."""
    completed = status == WalkStatus.COMPLETED.code
    outcome = status.astype(np.int8)
    outcome[completed] = WalkStatus.KEEPS_WALKING.code
    outcome[completed & (dist < tol)] = WalkStatus.CONVERGED.code
    return outcome


def _basin_chunk(
    q3: FloatArray,
    q3_dot: FloatArray,
    *,
    walker: CompassGait,
    slope: float,
    zstar: tuple[float, ...],
    steps: int,
    tol: float,
    rtol: float,
    atol: float,
    parallel: bool | None,
    backend: str = "compiled",
) -> dict[str, NDArray[np.generic]]:
    """Sweep function: walk every ``(q3, q3_dot)`` point of the chunk (see the sweep contract
    and :func:`_walk_chunk`)."""

    def walk(z0: FloatArray) -> tuple[Any, Any, Any]:
        if backend != "compiled":
            return _walk_points_scipy(walker, z0, slope, steps, np.asarray(zstar), tol, rtol,
                                      atol)
        res = ensemble_walk(walker, z0, slope, steps=steps, rtol=rtol, atol=atol, record=False,
                            stop_near=(np.asarray(zstar), tol), parallel=parallel)
        return res.status, res.steps, res.z

    return _walk_chunk(q3, q3_dot, zstar, (0, 1), walk, walker, walker.section_to_state)


# -- described walkers (TOML models) -------------------------------------------------------------
def model_slice_axes(walker: BuiltWalker) -> tuple[int, int]:
    """Section indices of a described walker's basin slice: the stance angle and its rate.

    The first section coordinate is the stance (root) link's angle ``q[2]`` and the first rate
    is its rate ``q_dot[2]`` (:class:`~heelstrike.dynamics.phased.PhasedWalker`'s section).
    """
    from heelstrike.dynamics.phased import PhasedWalker

    w = PhasedWalker.from_built(walker)
    return 0, len(w.section_names) - len(w._section_v)


def model_basin_of_attraction(
    walker: BuiltWalker,
    slope: float,
    grid: tuple[int, int] = (100, 100),
    ranges: tuple[tuple[float, float], tuple[float, float]] | None = None,
    steps: int = BASIN_STEPS,
    *,
    tol: float = BASIN_TOLERANCE,
    fixed_point: ArrayLike | None = None,
    backend: str = "compiled",
    rtol: float = 1e-8,
    atol: float = 1e-9,
    chunks: int = 16,
    parallel: bool | None = None,
    progress: bool = False,
    store: str | os.PathLike[str] | None = None,
) -> Basin:
    """Basin of attraction of a described walker's passive gait on a 2-D section slice.

    The slice passes through the gait's fixed point ``z*`` (post-heel-strike section,
    :attr:`~heelstrike.dynamics.phased.PhasedWalker.section_names`) and is spanned by the
    stance angle ``q[2]`` (rad) and its rate (rad/s) (:func:`model_slice_axes`); every other
    section coordinate is held at its fixed-point value. Initial states are classified as in
    :func:`basin_of_attraction`.

    Parameters
    ----------
    walker : BuiltWalker
        Any described walker with scalar parameters.
    slope : float
        Slope (rad).
    grid : (int, int)
        Number of stance angles and stance rates.
    ranges : ((float, float), (float, float)), optional
        Stance angle (rad) and rate (rad/s) windows, inclusive; default: ``[-0.25, +0.2]`` rad
        and ``[-0.9, +1.1]`` rad/s about the fixed point.
    steps : int
        Largest number of steps walked from every initial state.
    tol : float
        Convergence radius around the fixed point (section norm, rad and rad/s mixed).
    fixed_point : array_like, shape (d,), optional
        The gait's section point; found with
        :func:`~heelstrike.analysis.model_gaits.find_model_gait` if omitted (and then its
        stability is recorded: :attr:`Basin.gait_stable`).
    backend : {"compiled", "scipy"}
        :func:`~heelstrike.dynamics.compiled_phased.ensemble_walk_phased` (default) or a loop
        of the scipy reference :func:`~heelstrike.dynamics.phased.simulate_phased`.
    rtol, atol : float
        Integrator tolerances.
    chunks, parallel, progress, store
        As :func:`basin_of_attraction`.

    Returns
    -------
    Basin
        Dataset dims are the two section names (e.g. ``stance_shank``, ``stance_shank_dot``).

    Raises
    ------
    MemoryError, ValueError, GaitNotFoundError
    """
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.dynamics.phased import PhasedWalker

    check_backend_name(backend)
    w = PhasedWalker.from_built(walker)
    n1, n2 = _check_grid(grid, steps)
    names = w.section_names
    d = len(names)
    gait = None
    if fixed_point is None:
        gait = find_model_gait(w, slope=slope, backend=backend)
        zstar = np.asarray(gait.fixed_point)
    else:
        zstar = np.asarray(fixed_point, dtype=float).reshape(d)
    ia, ib = model_slice_axes(w)
    if ranges is None:
        ranges = ((zstar[ia] - 0.25, zstar[ia] + 0.2), (zstar[ib] - 0.9, zstar[ib] + 1.1))
    (a0, a1), (b0, b1) = ranges
    if not (a0 < a1 and b0 < b1):
        raise ValueError(f"ranges must be increasing (min < max), got {ranges}")
    xa = np.linspace(a0, a1, n1)
    xb = np.linspace(b0, b1, n2)
    xn, yn = names[ia], names[ib]
    func = functools.partial(
        _model_basin_chunk, description=w.description, params=dict(w.parameters),
        slope=float(slope), zstar=tuple(map(float, zstar)), axes=(ia, ib), steps=int(steps),
        tol=float(tol), rtol=float(rtol), atol=float(atol), backend=backend, parallel=parallel,
    )
    outcome, taken, dist, elapsed = _walk_slice(
        func, {"a": xa, "b": xb}, ("rad", "rad s-1"), zstar, tol, chunks, store, progress)
    held = [i for i in range(d) if i not in (ia, ib)]
    unit = ["rad" if i < ib else "rad/s" for i in range(d)]
    attrs: dict[str, Any] = {
        "title": f"basin of attraction of the passive gait of {w.description.name!r}",
        "model": w.description.name,
        "section": f"post-heel-strike ({', '.join(names)}); slice ({xn}, {yn}) through the "
        "fixed point, the others held at their fixed-point values",
        "held": ", ".join(f"{names[i]} = {zstar[i]:.4f} {unit[i]}" for i in held),
        "slope": float(slope),
        "slope_units": "rad",
        "backend": backend,
        "max_steps": int(steps),
        "tol": float(tol),
        "rtol": float(rtol),
        "atol": float(atol),
    }
    from heelstrike.models.base import section_unit
    from heelstrike.models.description import parameter_units

    for i, name in enumerate(names):
        attrs[f"fixed_point_{name}"] = float(zstar[i])
        attrs[f"fixed_point_{name}_units"] = section_unit(name).replace("/s", " s-1")
    units = parameter_units(w.description)
    for name, value in w.parameters.items():
        attrs[f"param_{name}"] = float(np.asarray(value))
        if name in units:
            attrs[f"param_{name}_units"] = units[name]
    coords = {
        xn: (xn, xa, {"units": "rad", "long_name": f"post-heel-strike stance angle {xn}",
                      "label": f"post-impact stance angle {xn} (rad)"}),
        yn: (yn, xb, {"units": "rad s-1",
                      "long_name": f"post-heel-strike stance angular velocity {yn}",
                      "label": f"post-impact stance velocity {yn} (rad/s)"}),
    }
    from heelstrike.analysis.model_gaits import hanging_links

    hanging = hanging_links(w, w.section_to_state(zstar)[0], float(slope))
    return _make_basin(coords, attrs, outcome, taken, dist, zstar, elapsed, axes=(ia, ib),
                       gait=gait, hanging=hanging)


def _model_basin_chunk(
    a: FloatArray,
    b: FloatArray,
    *,
    description: WalkerDescription,
    params: dict[str, Any],
    slope: float,
    zstar: tuple[float, ...],
    axes: tuple[int, int],
    steps: int,
    tol: float,
    rtol: float,
    atol: float,
    backend: str,
    parallel: bool | None,
) -> dict[str, NDArray[np.generic]]:
    """Sweep function of :func:`model_basin_of_attraction` over the slice coordinates (see
    :func:`_walk_chunk`)."""
    from heelstrike.dynamics.phased import PhasedWalker

    w = PhasedWalker(description, **params)

    def walk(Z: FloatArray) -> tuple[Any, Any, Any]:
        if backend != "compiled":
            return _walk_points_scipy(w, Z, slope, steps, np.asarray(zstar), tol, rtol, atol)
        from heelstrike.dynamics.compiled_phased import ensemble_walk_phased

        res = ensemble_walk_phased(w, Z, slope=slope, steps=steps, rtol=rtol, atol=atol,
                                   stop_near=(np.asarray(zstar), tol), parallel=parallel)
        return res.status, res.steps, res.z

    from heelstrike.dynamics.compiled_phased import section_states

    return _walk_chunk(a, b, zstar, axes, walk, w, functools.partial(section_states, w))


def _walk_points_scipy(
    walker: PlanarWalker, Z: FloatArray, slope: float, steps: int, zstar: FloatArray,
    tol: float, rtol: float, atol: float,
) -> tuple[NDArray[np.int64], NDArray[np.int64], FloatArray]:
    """The ensemble with the scipy reference, one period at a time (stops on arrival); any
    walker with a Poincare section. A period is
    :attr:`~heelstrike.models.base.PlanarWalker.steps_per_period` steps (a walker whose legs
    differ walks a stride, its steps taken by the walker and by the walker after its swap, as
    :func:`~heelstrike.dynamics.hybrid.simulate` does), and arrival is tested at the section
    where ``zstar`` lies: after whole periods."""
    from heelstrike.dynamics.hybrid import simulate

    n = Z.shape[0]
    status = np.zeros(n, dtype=np.int64)
    taken = np.zeros(n, dtype=np.int64)
    zf = np.zeros_like(Z)
    period = int(walker.steps_per_period)
    for i in range(n):
        q, qd = walker.section_to_state(Z[i])
        k = 0
        code = WalkStatus.COMPLETED.code
        while k < steps:
            r = simulate(walker, q, qd, slope=slope, steps=min(period, steps - k), rtol=rtol,
                         atol=atol)
            k += r.n_steps
            q, qd = r.final_q, r.final_q_dot
            if not r.ok:
                code = r.status.code
                break
            if k % period == 0 and float(np.linalg.norm(
                    walker.state_to_section(q, qd) - zstar)) < tol:
                break
        status[i], taken[i], zf[i] = code, k, walker.state_to_section(q, qd)
    return status, taken, zf
