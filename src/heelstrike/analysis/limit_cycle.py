"""Periodic gaits: Poincare map, Newton's method, Floquet multipliers, continuation.

The Poincare section is the state just after heel strike (after the legs are relabelled),
parametrised by the walker's section coordinates ``z`` (for the compass gait
``z = (q3, q3_dot, q4_dot)`` with ``q4 = -2 q3``). The map ``P`` integrates one step and applies
the impact; a period-one gait is a fixed point ``P(z*) = z*``. Its stability is given by the
eigenvalues (Floquet multipliers) of the Jacobian ``DP(z*)``: the gait is stable if all have
modulus < 1. For a passive walk on the scipy reference the Jacobian is exact (variational
equations and saltation matrices, :meth:`PoincareMap.exact_jacobian`); otherwise (compiled
maps, actuated walks) it is estimated by central differences. A real multiplier leaving the
unit circle through -1 while a parameter varies is a period-doubling bifurcation (Goswami,
Thuilot & Espiau 1998).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.analysis._defaults import BIFURCATION_RECORD, BIFURCATION_TRANSIENT
from heelstrike.analysis._gait_order import is_stable
from heelstrike.analysis.gaits import ENERGY_BOOKS_RTOL, Gait
from heelstrike.analysis.heel_strike import loss_per_metre
from heelstrike.analysis.newton import floquet_multipliers
from heelstrike.dynamics.backends import (
    BoundSimulator,
    check_one_walker,
    check_slope,
    check_tolerances,
)
from heelstrike.dynamics.hybrid import PushOff, WalkResult, simulate
from heelstrike.dynamics.single_support import TorqueLaw
from heelstrike.models.base import PlanarWalker, check_backend_name

if TYPE_CHECKING:
    from heelstrike.analysis.gait_map import NewtonGait
    from heelstrike.dynamics.variational import StepJacobian


__all__ = [
    "ENERGY_BOOKS_RTOL",
    "BifurcationDiagram",
    "Continuation",
    "GaitNotFoundError",
    "PoincareMap",
    "bifurcation_diagram",
    "continue_limit_cycle",
    "find_limit_cycle",
    "find_limit_cycles",
    "leg_crossings",
    "refine_period_doubling",
]


class GaitNotFoundError(RuntimeError):
    """No periodic gait was found (the message says why)."""


@dataclass(frozen=True, kw_only=True, eq=False)
class PoincareMap:
    """The step-to-step map on the post-impact section.

    Parameters
    ----------
    walker : PlanarWalker
        Must define :meth:`~PlanarWalker.section_to_state` and ``state_to_section``.
    slope : float
        Ground slope (rad).
    torque, push_off : optional
        Actuation (see :func:`heelstrike.dynamics.hybrid.simulate`).
    rtol, atol : float
        Integrator tolerances.
    max_step_duration : float
        Time bound of one step (s).
    method : {"scipy", "compiled"}
        ``"scipy"``: :func:`~heelstrike.dynamics.hybrid.simulate` (any walker, actuation);
        ``"compiled"``: :func:`~heelstrike.dynamics.compiled.step_map_compiled` for ``P(z)``
        (passive :class:`~heelstrike.models.CompassGait` only; ``walk`` still uses scipy).

    Notes
    -----
    ``P`` maps one period: :attr:`~heelstrike.models.base.PlanarWalker.steps_per_period`
    steps, one for a walker whose leg swap is a symmetry, two (the stride map: a step on each
    leg, the walker alternating with :meth:`~heelstrike.models.base.PlanarWalker.after_swap`)
    for a walker whose legs differ.
    """

    walker: PlanarWalker
    slope: float = 0.0
    torque: TorqueLaw | None = None
    push_off: PushOff | None = None
    rtol: float = 1e-11
    atol: float = 1e-11
    max_step_duration: float = 5.0
    max_step: float = np.inf
    method: str = "scipy"
    #: Step simulator with :func:`~heelstrike.dynamics.hybrid.simulate`'s signature (None: that
    #: function), e.g. :func:`heelstrike.dynamics.phased.simulate_phased` for described walkers.
    simulator: Callable[..., WalkResult] | None = None

    def __post_init__(self) -> None:
        check_backend_name(self.method, "method")
        check_one_walker(self.walker)
        if self.method == "compiled" and self.walker.steps_per_period != 1:
            raise ValueError(
                "method='compiled' maps one step of one walker; this walker's legs differ "
                "(steps_per_period 2: its map is the stride map): use method='scipy'")
        object.__setattr__(self, "slope", check_slope(self.slope))
        check_tolerances(self.rtol, self.atol)
        if self.method == "compiled" and (self.torque is not None or self.push_off is not None):
            raise ValueError("method='compiled' supports passive walkers only")

    def walk(self, z: ArrayLike, steps: int = 1) -> WalkResult:
        """Simulate ``steps`` steps from the section point ``z``."""
        q, q_dot = self.walker.section_to_state(np.asarray(z, dtype=float))
        sim = simulate if self.simulator is None else self.simulator
        return sim(
            self.walker,
            q,
            q_dot,
            slope=self.slope,
            steps=steps,
            torque=self.torque,
            push_off=self.push_off,
            rtol=self.rtol,
            atol=self.atol,
            max_step_duration=self.max_step_duration,
            max_step=self.max_step,
        )

    def __call__(self, z: ArrayLike) -> FloatArray:
        """``P(z)``; NaNs if the step fails (fall, no strike, trailing foot stays...)."""
        if self.method == "compiled":
            from heelstrike.dynamics.compiled import step_map_compiled

            return step_map_compiled(
                self.walker,  # type: ignore[arg-type]
                z,
                self.slope,
                rtol=self.rtol,
                atol=self.atol,
                max_step_duration=self.max_step_duration,
            ).z
        res = self.walk(z, self.walker.steps_per_period)
        if not res.ok:
            return np.full(np.shape(z), np.nan)
        return np.asarray(self.walker.state_to_section(res.final_q, res.final_q_dot))

    def many(self, Z: ArrayLike) -> FloatArray:
        """``P`` at every row of ``Z`` (shape (B, d)); rows of NaN where the step fails.

        One batched compiled call where a kernel runs the map: the compass map
        (``method="compiled"``, or the passive compass with the compiled backend as
        ``simulator``), or a described walker whose ``simulator`` is the compiled backend
        (:class:`~heelstrike.dynamics.backends.BoundSimulator`), the compass gait with a hip
        law or a push-off included (its description's kernel,
        :meth:`~heelstrike.models.base.PlanarWalker.as_described`); otherwise row by row.
        Each row equals ``self(Z[i])`` (the same kernel, walker by walker).
        """
        Z_ = np.atleast_2d(np.asarray(Z, dtype=float))
        compiled = isinstance(self.simulator, BoundSimulator) and \
            self.simulator.backend == "compiled"
        passive = self.torque is None and self.push_off is None
        kernel_walker = self.walker
        if compiled and self.walker.compiled_kernel == "compass" and not passive:
            # the compass kernel is passive: the compiled backend walks the described compass
        # (hip laws, push-off)
            kernel_walker = self.walker.as_described() or self.walker
        if self.method == "compiled" or (compiled and kernel_walker.compiled_kernel == "compass"
                                         and passive):
            from heelstrike.dynamics.compiled import COMPLETED, ensemble_walk

            ens = ensemble_walk(self.walker, Z_, self.slope, steps=1,  # type: ignore[arg-type]
                                rtol=self.rtol, atol=self.atol,
                                max_step_duration=self.max_step_duration, parallel=False)
            return np.where((ens.status == COMPLETED)[:, None], ens.z, np.nan)
        if compiled and kernel_walker.compiled_kernel == "generated":
            from heelstrike.dynamics.compiled_phased import ensemble_walk_phased

            ens_p = ensemble_walk_phased(  # one period: the stride of a walker whose legs differ
                kernel_walker, Z_, slope=self.slope,  # type: ignore[arg-type]
                steps=int(kernel_walker.steps_per_period),
                torque=cast(Any, self.torque), push_off=cast(Any, self.push_off),
                rtol=self.rtol, atol=self.atol, max_step_duration=self.max_step_duration,
                max_step=self.max_step, parallel=False,
            )
            return np.where(ens_p.ok[:, None], ens_p.z, np.nan)
        return np.stack([self(z) for z in Z_])

    def jacobian(self, z: ArrayLike, step: float = 1e-6, method: str = "central") -> FloatArray:
        """Jacobian ``DP(z)``, shape (d, d).

        Parameters
        ----------
        z : array_like, shape (d,)
            Section point.
        step : float
            Relative step of the central differences (``method="central"``).
        method : {"central", "exact"}
            ``"central"``: central differences of the map (one :meth:`many` call, ``2 d`` step
            maps, accurate to about :data:`MULTIPLIER_ACCURACY`). ``"exact"``: variational
            equations through every event with saltation matrices
            (:func:`heelstrike.dynamics.variational.step_jacobian`, exact to the integrator's
            tolerance), on the scipy reference (``method="scipy"`` and no ``simulator``).

        Raises
        ------
        ValueError
            For an unknown ``method``, or ``"exact"`` on a compiled map.
        heelstrike.dynamics.variational.ExactJacobianUnavailable
            If the walk cannot be differentiated exactly (see that function).
        """
        if method == "exact":
            return self.exact_jacobian(z).jacobian
        if method != "central":
            raise ValueError(f"jacobian method must be 'central' or 'exact', got {method!r}")
        z_ = np.asarray(z, dtype=float)
        d = z_.size
        dz = step * np.maximum(1.0, np.abs(z_))
        offsets = np.diag(dz)
        P = self.many(np.concatenate((z_ + offsets, z_ - offsets)))
        return (P[:d] - P[d:]).T / (2.0 * dz)


    def exact_jacobian(self, z: ArrayLike) -> StepJacobian:
        """The exact Jacobian of the step from ``z`` with its details (event times, the naive
        product without saltation terms): :func:`~heelstrike.dynamics.variational.step_jacobian`
        at this map's slope, actuation and tolerances (scipy reference only).

        Raises
        ------
        ValueError
            On a compiled map (``method="compiled"`` or a ``simulator``).
        heelstrike.dynamics.variational.ExactJacobianUnavailable
            For a walker whose legs differ (its map is the stride map, two steps; the exact
            Jacobian is of one step), and as
            :func:`~heelstrike.dynamics.variational.step_jacobian`.
        """
        from heelstrike.dynamics.variational import ExactJacobianUnavailable, step_jacobian

        sim = self.simulator
        reference = sim is None or sim is simulate or (
            isinstance(sim, BoundSimulator) and sim.backend == "scipy")
        if self.method != "scipy" or not reference:
            raise ValueError("the exact Jacobian runs on the scipy reference: a PoincareMap "
                             "with method='scipy' and no simulator")
        if self.walker.steps_per_period != 1:
            raise ExactJacobianUnavailable(
                "this walker's legs differ: its Poincare map is the stride map (two steps), "
                "the exact Jacobian is of one step; use central differences")
        return step_jacobian(self.walker, z, slope=self.slope, torque=self.torque,
                             push_off=self.push_off, rtol=self.rtol, atol=self.atol,
                             max_step_duration=self.max_step_duration, max_step=self.max_step)


@dataclass(frozen=True, kw_only=True)
class _OneStep:
    """``pmap.walk(z, steps_per_period)`` deferred (picklable, unlike a closure)."""

    pmap: PoincareMap
    z: FloatArray

    def __call__(self) -> WalkResult:
        return self.pmap.walk(self.z, self.pmap.walker.steps_per_period)


#: Fewest samples of a step's walk from which :func:`leg_crossings` counts. The samples are the
#: integrator's steps (15 on the scipy reference's ordinary compass step at 0.5 m/s, 75 on the
#: compiled kernel's); a crossing and back within one sample interval would be missed.
LEG_CROSSING_SAMPLES = 8


def leg_crossings(walker: PlanarWalker, walk: WalkResult) -> int | None:
    """How many times the swing leg crosses the stance leg in a simulated step.

    The sign changes of the hip angle ``q[hip_joint]`` (:attr:`PlanarWalker.hip_joint`, the
    swing leg relative to the stance leg) over the walk's samples: an ordinary step has one,
    from behind to ahead. A straight-legged swing foot is under the ground between the legs'
    crossing and the nearby instant where the stance leg's angle is half the hip angle, near
    mid-stance (the scuffing convention, README); with more crossings it is under the ground
    away from mid-stance too (QA sweep 6: 4.4 mm deep for 0.2 s, the legs 9 deg apart).

    Parameters
    ----------
    walker : PlanarWalker
    walk : WalkResult
        One step, sampled (``walk.q``, shape (N, n)); for a walk of several steps (the stride
        of a walker whose legs differ) the most crossings of any one step.

    Returns
    -------
    int or None
        The count; None with fewer than :data:`LEG_CROSSING_SAMPLES` samples.
    """
    q = np.asarray(walk.q, dtype=float)
    if q.ndim != 2:
        return None
    step = getattr(walk, "step", None)
    if step is None or np.size(step) != q.shape[0] or np.unique(step).size < 2:
        return _sign_changes(q[:, walker.hip_joint])
    # a stride (a walker whose legs differ): the most crossings of any of its steps
    counts = [_sign_changes(q[np.asarray(step) == k, walker.hip_joint])
              for k in np.unique(step)]
    return None if any(c is None for c in counts) else max(cast(list[int], counts))


def _sign_changes(hip_angles: ArrayLike) -> int | None:
    """:func:`leg_crossings` from the hip angles (rad) of a step's samples, shape (N,)."""
    a = np.asarray(hip_angles, dtype=float)
    if a.shape[0] < LEG_CROSSING_SAMPLES:
        return None
    sign = np.sign(a)
    sign = sign[sign != 0]
    return int(np.count_nonzero(sign[1:] != sign[:-1]))


def _default_guesses(walker: PlanarWalker) -> list[FloatArray]:
    """Candidate post-impact section states of a compass-like walker (coarse grid)."""
    out = []
    for a in (0.1, 0.17, 0.24, 0.31, 0.38, 0.45, 0.55):
        for w3 in (0.5, 0.8, 1.1, 1.4, 1.8, 2.3):
            for w4 in (-1.5, -0.9, -0.5, -0.2, 0.1):
                out.append(np.array([-a, w3, w4]))
    return out


def _automatic_guess(pmap: PoincareMap, progress: bool = False) -> FloatArray:
    """A starting point for Newton.

    A coarse grid of post-impact states is mapped once; from the most nearly periodic ones the
    map is iterated (a passive walker settles onto a stable gait). A state that converges under
    iteration (an attractor) is preferred; otherwise the most nearly periodic state is used.
    """
    coarse = replace(pmap, rtol=1e-7, atol=1e-8)
    scored: list[tuple[float, FloatArray]] = []
    guesses = _default_guesses(pmap.walker)
    for z in _progress(guesses, progress, "searching for a gait"):
        z1 = coarse(z)
        if np.all(np.isfinite(z1)):
            scored.append((float(np.linalg.norm(z1 - z)), z))
    if not scored:
        raise GaitNotFoundError(
            "no step could be completed from any of the automatic initial guesses"
        )
    scored.sort(key=lambda s: s[0])
    best, best_err = scored[0][1], scored[0][0]
    for _, z in scored[:6]:
        zi = z
        for _ in range(60):
            z1 = coarse(zi)
            if not np.all(np.isfinite(z1)):
                break
            err = float(np.linalg.norm(z1 - zi))
            zi = z1
            if err < 1e-6:
                return np.asarray(zi)  # an attracting gait
            if err < best_err:
                best, best_err = zi, err
    return np.asarray(best)


def _progress(items: Sequence[Any], enabled: bool, desc: str) -> Iterable[Any]:
    if not enabled:
        return items
    from heelstrike._progress import progress_bar

    return progress_bar(items, desc=desc)


#: Time bound (s) of the automatic search for gaits (seeding and Newton from every seed).
SEARCH_TIME_LIMIT = 300.0
#: Smallest sub-step of :func:`continue_limit_cycle`, as a fraction of its values' spacing.
_CONTINUATION_MIN_STEP = 1.0 / 1024.0

#: Two fixed points closer than this (Euclidean norm in section coordinates) are the same gait.
SAME_GAIT_TOL = 1e-6


#: Accuracy of the Floquet multipliers' moduli (central differences of the step map, passive
#: and powered gaits alike; a passive gait's exact Jacobian on the scipy reference agrees with
#: a 30-digit reference to about 1e-12): a largest ``|m|`` within this of 1 says the gait is
#: neutral to that accuracy, not stable or unstable (McGeer's wheel with push-off:
#: ``|m| = 1 - 3.5e-9``).
MULTIPLIER_ACCURACY = 1e-6


def _check_passive_slope(
    slope: float, *, torque: object = None, push_off: object = None,
    walker: PlanarWalker | None = None,
) -> None:
    """A passive walker cannot walk periodically on level or uphill ground: nothing supplies the
    energy lost at heel strike. Nor can McGeer's wheel, whose trailing foot neither lifts nor
    presses after a heel strike. Fail at once instead of searching.

    Parameters
    ----------
    slope : float
        Ground slope (rad), positive downhill.
    torque, push_off : optional
        The walk's actuation; with either, any slope may have a gait.
    walker : PlanarWalker, optional
        The walker (None: not checked for being McGeer's wheel).

    Raises
    ------
    GaitNotFoundError
        Passive (no torque, no push-off) and ``slope <= 0``, or ``|slope| >= pi/2``; a passive
        :attr:`~heelstrike.models.base.PlanarWalker.is_wheel` walker whose heel strike
        requires the trailing foot to lift (its passive step cannot end: the trailing foot
        grazes); one whose schedule accepts the grazing foot (``wheel.toml``) is searched.
    """
    if not abs(slope) < np.pi / 2:  # a bare 3 meant as degrees is 172 deg
        raise GaitNotFoundError(
            f"slope {slope:g} rad is {np.degrees(slope):g} deg: no walkable incline (slopes "
            f"are in radians, |slope| < pi/2; 3 deg is {np.deg2rad(3.0):.6g} rad)")
    if torque is None and push_off is None and not slope > 0.0:
        raise GaitNotFoundError(
            f"a passive walker has no periodic gait on a slope of "
            f"{np.degrees(slope):g} deg: the energy lost at every heel strike must come "
            f"from gravity, so the slope must be > 0 (downhill, e.g. 3 deg = "
            f"{np.deg2rad(3.0):.6g} rad)"
        )
    if torque is None and push_off is None and walker is not None and walker.is_wheel \
            and not _accepts_grazing(walker):
        raise GaitNotFoundError(
            "McGeer's wheel (foot radius R = leg length l): its two feet are arcs of one "
            "circle about the hip, so after every heel strike the trailing foot's contact "
            "point has exactly zero normal velocity (it neither lifts nor presses) and a "
            "passive step ends there ('trailing_foot_stays'): there is no passive step map "
            "to search (powered gaits accept this grazing contact, 'heelstrike powered "
            "--radius ...'; for passive gaits take R < l)"
        )


def _accepts_grazing(walker: PlanarWalker) -> bool:
    """Whether the walker's heel strike accepts a trailing foot leaving the ground with zero
    normal velocity: its declared schedule's ``"lift_or_graze"`` rule (a walker file's
    ``[events] trailing_foot = "lifts_or_grazes"``, e.g. ``wheel.toml``). Its passive steps
    then end at the strike, and passive gaits can be searched for. False for a walker that
    cannot walk at all (whose schedule raises)."""
    try:
        return walker.step_schedule().trailing_foot == "lift_or_graze"
    except ValueError:
        return False


def _compiled_ok(pmap: PoincareMap) -> bool:
    """Whether the batched compiled map can seed the search: a passive walker, not a batch,
    simulated by the compass-gait kernel (:mod:`heelstrike.dynamics.compiled`)."""
    w = pmap.walker
    return (
        w.compiled_kernel == "compass"
        and pmap.torque is None
        and pmap.push_off is None
        and pmap.simulator is None
        and not w.is_batched
    )


def _seed_grid() -> FloatArray:
    """Post-impact seeds ``(q3, q3_dot, q4_dot)`` (rad, rad/s) over step angles and rates,
    shape (864, 3)."""
    a = np.linspace(0.05, 0.6, 12)
    w3 = np.linspace(0.3, 2.5, 9)
    w4 = np.linspace(-1.8, 0.3, 8)
    return np.stack(np.meshgrid(-a, w3, w4, indexing="ij"), axis=-1).reshape(-1, 3)


def _add_distinct(found: list[FloatArray], z: FloatArray, tol: float = SAME_GAIT_TOL) -> bool:
    if all(float(np.linalg.norm(z - f)) > tol for f in found):
        found.append(np.asarray(z, dtype=float))
        return True
    return False


#: ``(tol, rtol = atol)`` of the first, coarse Newton stage of the compiled search.
_COARSE_NEWTON = (1e-7, 1e-9)


def _compiled_seeds(
    walker: Any, slope: float, rtol: float, atol: float, deadline: float, progress: bool,
    n_seeds: int = 40, tol: float = 1e-10, fd_step: float = 1e-6,
) -> list[NewtonGait]:
    """Distinct gaits of the compiled map found from a grid of seeds.

    The grid is mapped once in one batched call; the seeds that survive 80 steps give the
    attracting gaits, the most nearly periodic seeds (smallest ``|P(z) - z|``) the others. Newton
    runs on the compiled map in two stages: from every start on the map at rtol = atol = 1e-9 to
    ``|P(z) - z| < 1e-7`` (:data:`_COARSE_NEWTON`), then, from the distinct coarse fixed points
    only (closer than 1e-5: the same gait), at ``rtol``, ``atol``, ``tol`` and ``fd_step`` of
    :func:`find_limit_cycles`; duplicates are dropped. Every compiled call is serial (one numba
    kernel to load).
    """
    from heelstrike.analysis.gait_map import newton_gaits
    from heelstrike.dynamics.compiled import COMPLETED, ensemble_walk

    Z = _seed_grid()
    r1 = ensemble_walk(
        walker, Z, slope, steps=1, rtol=1e-7, atol=1e-8, record=False, parallel=False
    )
    ok = r1.status == COMPLETED
    if not np.any(ok):
        return []
    res = np.linalg.norm(r1.z - Z, axis=1)
    res[~ok] = np.inf
    rk = ensemble_walk(
        walker, Z[ok], slope, steps=80, rtol=1e-7, atol=1e-8, record=False, parallel=False
    )
    starts: list[FloatArray] = []
    for z in rk.z[rk.status == COMPLETED]:
        _add_distinct(starts, z, 1e-3)
    for i in np.argsort(res)[:n_seeds]:
        if np.isfinite(res[i]):
            starts.append(Z[i])
    found: list[NewtonGait] = []
    if not starts:
        return found
    c_tol, c_rtol = _COARSE_NEWTON
    coarse = newton_gaits(
        walker, slope, np.asarray(starts), tol=max(tol, c_tol), max_iter=15, fd_step=fd_step,
        rtol=max(rtol, c_rtol), atol=max(atol, c_rtol), deadline=deadline,
    )
    near: list[FloatArray] = []
    for g in coarse:
        if not isinstance(g, str):
            _add_distinct(near, g.z, 1e-5)
    if not near:
        return found
    results = newton_gaits(
        walker, slope, np.asarray(near), tol=tol, max_iter=15, fd_step=fd_step, rtol=rtol,
        atol=atol, deadline=deadline,
    )
    zs: list[FloatArray] = []
    for g in results:
        if not isinstance(g, str) and _add_distinct(zs, g.z):
            found.append(g)
    return found


def _radius_continuation_seeds(
    walker: Any, slope: float, rtol: float, atol: float, deadline: float, progress: bool,
    tol: float = 1e-10, fd_step: float = 1e-6,
) -> list[NewtonGait]:
    """Gaits of a round-footed walker continued in the foot radius from the point foot's (steps
    of at most 0.05 m), as :func:`heelstrike.analysis.gait_map.gait_map` does."""
    from heelstrike.analysis.gait_map import newton_gait

    R = float(walker.foot_radius)
    if R <= 0.0:
        return []
    out: list[NewtonGait] = []
    zs: list[FloatArray] = []
    base = _compiled_seeds(walker.replace(foot_radius=0.0), slope, rtol, atol, deadline, False)
    n_sub = max(1, int(np.ceil(R / 0.05)))
    for g in _progress(base, progress, "continuing gaits in the foot radius"):
        try:
            for Rs in np.linspace(0.0, R, n_sub + 1)[1:]:
                if time.monotonic() > deadline:
                    return out
                g = newton_gait(walker.replace(foot_radius=float(Rs)), slope, g.z, tol=tol,
                                fd_step=fd_step, rtol=rtol, atol=atol)
        except GaitNotFoundError:
            continue
        if _add_distinct(zs, g.z):
            out.append(g)
    return out


#: The Jacobians Newton's method may use on the Poincare map (``jacobian`` of
#: :func:`find_limit_cycle`): ``"exact"`` (variational equations and saltation matrices,
#: :meth:`PoincareMap.exact_jacobian`, where it applies) or ``"central"`` (differences).
NEWTON_JACOBIANS = ("exact", "central")


def _check_jacobian(jacobian: str) -> None:
    """Raise ValueError unless ``jacobian`` is one of :data:`NEWTON_JACOBIANS`."""
    if jacobian not in NEWTON_JACOBIANS:
        raise ValueError(f"jacobian must be one of {', '.join(map(repr, NEWTON_JACOBIANS))}, "
                         f"got {jacobian!r}")


def _exact_newton_ok(pmap: PoincareMap) -> bool:
    """Whether Newton can run on the exact Jacobian of ``pmap``: a passive walk, or one
    actuated by a push-off impulse and the built-in torque laws
    (:func:`~heelstrike.dynamics.variational.actuation_differentiable`: a user's law need not
    take complex states), on the scipy reference (``method="scipy"``, no simulator or the
    scipy one) of one walker whose period is one step
    (:func:`~heelstrike.dynamics.variational.step_jacobian` differentiates one step).
    Whether the walker's equations can be differentiated is found at the first iterate."""
    from heelstrike.dynamics.variational import actuation_differentiable

    sim = pmap.simulator
    reference = sim is None or sim is simulate or (
        isinstance(sim, BoundSimulator) and sim.backend == "scipy")
    return (pmap.method == "scipy" and reference
            and actuation_differentiable(pmap.torque, pmap.push_off)
            and pmap.walker.steps_per_period == 1 and not pmap.walker.is_batched)


def _exact_pairs(pmap: PoincareMap, fd_step: float, used: set[str]
                 ) -> Callable[[FloatArray], tuple[FloatArray, FloatArray]]:
    """``Z -> (P(Z) - Z, DP(Z) - I)`` row by row, shapes (B, d) and (B, d, d), for
    :func:`~heelstrike.analysis.newton.newton_solve`'s ``derivative``.

    ``DP`` is :meth:`PoincareMap.exact_jacobian` (one step and its variational equations give
    ``P(z)`` and ``DP(z)`` together); where it cannot be formed it is central differences with
    ``fd_step`` (:meth:`PoincareMap.jacobian`): at a grazing event or a step that skips a phase
    of its schedule for that row, and for every later row once the walker or its actuation
    cannot be differentiated at all. A row whose step fails is NaN. ``used`` collects the
    kinds used (``"exact"``, ``"central"``).
    """
    from heelstrike.core.saltation import GrazingEventError
    from heelstrike.dynamics.variational import (
        ExactJacobianUnavailable,
        StepFailedError,
        UnscheduledStepError,
    )

    exact = [True]

    def pairs(Z: FloatArray) -> tuple[FloatArray, FloatArray]:
        Z_ = np.atleast_2d(np.asarray(Z, dtype=float))
        B, d = Z_.shape
        F, J = np.full((B, d), np.nan), np.full((B, d, d), np.nan)
        for i, z in enumerate(Z_):
            if exact[0]:
                try:
                    sj = pmap.exact_jacobian(z)
                except ExactJacobianUnavailable:
                    exact[0] = False  # the walker's equations: not at any other point either
                except (GrazingEventError, UnscheduledStepError):
                    pass  # this point only: differences below
                except StepFailedError:
                    continue  # no step: a row of NaN
                else:
                    F[i], J[i] = sj.z_next - z, sj.jacobian - np.eye(d)
                    used.add("exact")
                    continue
            F[i] = pmap(z) - z
            if np.all(np.isfinite(F[i])):
                J[i] = pmap.jacobian(z, fd_step) - np.eye(d)
                used.add("central")
        return F, J

    return pairs


def _newton(
    pmap: PoincareMap, z: FloatArray, tol: float, max_iter: int, fd_step: float,
    jacobian: str = "central",
) -> tuple[FloatArray, float, int, str, FloatArray | None]:
    """Newton's method for ``P(z) = z`` on ``pmap`` (the one engine,
    :func:`~heelstrike.analysis.newton.newton_solve`).

    With ``jacobian="exact"`` where :func:`_exact_newton_ok` (else central differences),
    every iterate is evaluated with its exact Jacobian (:func:`_exact_pairs`).

    Returns
    -------
    tuple
        ``(z*, residual, iterations, kind, DP)``: ``kind`` the Jacobians Newton used
        (``"exact"``, ``"central"`` or ``"mixed"``), ``DP`` the map's Jacobian at ``z*``
        Newton evaluated there (exact runs; None otherwise).

    Raises
    ------
    GaitNotFoundError
        If a step fails, the system is singular or Newton does not converge.
    """
    from heelstrike.analysis.newton import newton_solve

    _check_jacobian(jacobian)
    if jacobian == "exact" and _exact_newton_ok(pmap):
        used: set[str] = set()
        sol = newton_solve(lambda Z: pmap.many(Z) - Z, z, tol=tol, max_iter=max_iter,
                           fd_step=fd_step, jacobian="exact",
                           derivative=_exact_pairs(pmap, fd_step, used))
        kind = "mixed" if len(used) > 1 else (used.pop() if used else "exact")
        J_root = sol.jacobian[0] + np.eye(z.size)
    else:
        sol = newton_solve(lambda Z: pmap.many(Z) - Z, z, tol=tol,
                           max_iter=max_iter, fd_step=fd_step, jacobian_at_root=False)
        kind, J_root = "central", None
    if not sol.converged[0]:
        raise GaitNotFoundError(sol.message(0, pmap.walker.section_labels))
    return sol.x[0], float(sol.residual_norm[0]), int(sol.iterations[0]), kind, J_root


def _preference(c: Gait) -> tuple[bool, bool, float, float]:
    """Sort key: the one order of gaits (:func:`~heelstrike.analysis._gait_order.gait_order`):
    ordinary steps before multi-swing gaits
    (:attr:`~heelstrike.analysis.gaits.Gait.multi_swing`), stable gaits first, the least
    actuator work (none for a passive gait), the most attracting first."""
    from heelstrike.analysis._gait_order import gait_order

    return gait_order(c)


def find_limit_cycles(
    walker: PlanarWalker,
    *,
    slope: float = 0.0,
    torque: TorqueLaw | None = None,
    push_off: PushOff | None = None,
    tol: float = 1e-10,
    max_iter: int = 25,
    fd_step: float = 1e-6,
    rtol: float = 1e-11,
    atol: float = 1e-11,
    progress: bool = False,
    method: str = "scipy",
    simulator: Callable[..., WalkResult] | None = None,
    time_limit: float = SEARCH_TIME_LIMIT,
    jacobian: str = "exact",
) -> tuple[Gait, ...]:
    """Find every period-one gait the automatic search reaches, best first.

    For the passive :class:`~heelstrike.models.CompassGait` the seeds come from the batched
    compiled map (:func:`~heelstrike.dynamics.compiled.ensemble_walk`): a grid of 864
    post-impact states over step angle and rates is mapped once and walked 80 steps; the
    survivors (attracting gaits) and the 40 most nearly periodic seeds start Newton on the
    compiled map. If nothing is found for a round foot, the point foot's gaits are continued in
    the radius. Other walkers use a coarse grid, map iteration and Newton from the most nearly
    periodic seeds. Every distinct fixed point is then converged with ``method`` and
    characterised; with ``method="compiled"`` the compiled Newton solution (converged to ``tol``
    with the same ``fd_step``) is the gait, characterised on the compiled backend (see
    :func:`find_limit_cycle`).

    Parameters
    ----------
    walker, slope, torque, push_off, tol, max_iter, fd_step, rtol, atol, method, simulator
        As :func:`find_limit_cycle`.
    jacobian : {"exact", "central"}
        As :func:`find_limit_cycle` (the final Newton on ``method``'s map; the compiled
        seeding stage runs on differences).
    progress : bool
        Progress bar on stderr (shown after 2 s).
    time_limit : float
        Bound on the search (s); the gaits found by then are returned, with a
        :class:`~heelstrike.analysis.newton.SearchTimeLimitWarning` (others may exist).

    Returns
    -------
    tuple of Gait
        Distinct gaits, stable ones first, each group by increasing spectral radius (the most
        attracting gait first). Empty only if none was found (then
        :class:`GaitNotFoundError` is raised instead).

    Raises
    ------
    GaitNotFoundError
        A passive walker on a slope <= 0, no step possible, or no gait found.

    Warns
    -----
    SearchTimeLimitWarning
        The search ran past ``time_limit``: the gaits found by then are returned.
    """
    pmap = PoincareMap(
        walker=walker, slope=slope, torque=torque, push_off=push_off, rtol=rtol, atol=atol,
        method=method, simulator=simulator,
    )
    _check_passive_slope(pmap.slope, torque=pmap.torque, push_off=pmap.push_off,
                         walker=walker)
    _check_jacobian(jacobian)
    deadline = time.monotonic() + float(time_limit)
    if _compiled_ok(pmap):
        gaits = _compiled_seeds(
            walker, slope, rtol, atol, deadline, progress, tol=tol, fd_step=fd_step
        )
        if not gaits:
            gaits = _radius_continuation_seeds(
                walker, slope, rtol, atol, deadline, progress, tol=tol, fd_step=fd_step
            )
        starts = [g.z for g in gaits]
        if not starts and time.monotonic() > deadline:
            raise GaitNotFoundError(f"gave up after {time_limit:g} s (time limit of the search)")
        if not starts:
            raise GaitNotFoundError(
                "no period-one gait found from 864 seeds over step angles 3-34 deg (compiled "
                "map, 80 steps and Newton from the 40 most nearly periodic seeds"
                + ("; the search runs on the compiled map whatever the backend, the gaits it "
                   "finds are then converged on the scipy reference" if method != "compiled"
                   else "")
                + ")"
                + (", nor by continuation in the foot radius from the point foot"
                   if float(walker.foot_radius) > 0 else "")  # type: ignore[attr-defined]
            )
        if method == "compiled":  # already converged on this map: characterise them
            cycles = [
                _characterise_compiled(pmap, g.z, g.period, g.multipliers, g.residual,
                                       g.iterations)
                for g in gaits
            ]
            cycles = _closed_books(cycles, pmap)
            _warn_if_cut(deadline, time_limit, len(cycles))
            return tuple(sorted(cycles, key=_preference))
    else:
        starts = [_automatic_guess(pmap, progress)]
    cycles = []
    zs: list[FloatArray] = []
    last: Exception | None = None
    for z0 in starts:
        if time.monotonic() > deadline and cycles:
            break
        try:
            z, residual, it, kind, DP = _newton(pmap, np.asarray(z0, dtype=float), tol,
                                                max_iter, fd_step, jacobian)
        except GaitNotFoundError as exc:
            last = exc
            continue
        if _add_distinct(zs, z):
            cycles.append(_characterise(pmap, z, residual, it, fd_step, kind, DP))
    if not cycles:
        raise GaitNotFoundError(str(last) if last else "no period-one gait found")
    cycles = _closed_books(cycles, pmap)
    _warn_if_cut(deadline, time_limit, len(cycles))
    return tuple(sorted(cycles, key=_preference))


def _closed_books(cycles: list[Gait], pmap: PoincareMap) -> list[Gait]:
    """The passive gaits whose energy books close
    (:attr:`~heelstrike.analysis.gaits.Gait.energy_books_close`);
    actuated ones all, and those of a step simulator given to the map (a described walker's,
    whose step may hold knee strikes besides the heel strike of ``collision_loss``: its books
    are checked by :func:`~heelstrike.analysis.model_gaits.find_model_gaits`). Raise
    :class:`GaitNotFoundError` when none is left, saying why."""
    if pmap.torque is not None or pmap.push_off is not None or pmap.simulator is not None:
        return cycles
    kept = [c for c in cycles if c.energy_books_close]
    if kept:
        return kept
    c = cycles[0]
    raise GaitNotFoundError(
        f"the {len(cycles)} period-one solution{'s' if len(cycles) > 1 else ''} found at "
        f"slope {pmap.slope:g} rad do{'es' if len(cycles) == 1 else ''} not close the energy "
        f"books (collision loss {c.collision_loss:.3g} J, energy released "
        f"{c.potential_energy_released:.3g} J per step, which must agree within "
        f"{100 * ENERGY_BOOKS_RTOL:g} %): the step's energies are at the round-off of the "
        "walker's energy, so these are no gaits; give a larger slope")


def _warn_if_cut(deadline: float, time_limit: float, found: int) -> None:
    """Warn that the search ran past its deadline (its stages stop there, so gaits may have
    been missed)."""
    if time.monotonic() > deadline:
        from heelstrike.analysis.newton import SearchTimeLimitWarning

        warnings.warn(
            f"the gait search reached its time limit of {time_limit:g} s: the {found} "
            f"gait{'s' if found != 1 else ''} found by then {'are' if found != 1 else 'is'} "
            "returned, and others may exist",
            SearchTimeLimitWarning, stacklevel=3,
        )


def find_limit_cycle(
    walker: PlanarWalker,
    *,
    slope: float = 0.0,
    guess: ArrayLike | None = None,
    torque: TorqueLaw | None = None,
    push_off: PushOff | None = None,
    tol: float = 1e-10,
    max_iter: int = 25,
    fd_step: float = 1e-6,
    rtol: float = 1e-11,
    atol: float = 1e-11,
    progress: bool = False,
    method: str = "scipy",
    simulator: Callable[..., WalkResult] | None = None,
    jacobian: str = "exact",
) -> Gait:
    """Find a period-one gait with Newton's method on the Poincare map.

    Parameters
    ----------
    walker : PlanarWalker
        Walker with a Poincare section (e.g. :class:`~heelstrike.models.CompassGait`).
    slope : float
        Ground slope (rad).
    guess : array_like, optional
        Section coordinates to start from. If None, every gait the automatic search of
        :func:`find_limit_cycles` finds is computed and the preferred one returned: the stable
        gait with the smallest spectral radius (the most attracting), else the least unstable.
    torque, push_off : optional
        Actuation laws.
    tol : float
        Convergence tolerance on ``|P(z) - z|``.
    max_iter : int
        Maximum Newton iterations.
    fd_step : float
        Relative finite-difference step for the Jacobian (Newton's; the multipliers' too where
        the exact Jacobian is not used: compiled maps, actuated walks).
    rtol, atol : float
        Integrator tolerances.
    progress : bool
        Show a progress bar (stderr, after 2 s) during the automatic search.
    method : {"scipy", "compiled"}
        Poincare map used by Newton (see :class:`PoincareMap`). With ``"compiled"`` the gait
        is also characterised on the compiled backend (period, step length, energies at the
        compiled pre-impact state, multipliers of the compiled map; equal to the scipy
        reference's to about the integration tolerances) and the returned cycle's ``walk`` is
        the scipy reference's, simulated on first access.
    simulator : callable, optional
        Step simulator (see :class:`PoincareMap`), e.g.
        :func:`heelstrike.dynamics.phased.simulate_phased` for described walkers.
    jacobian : {"exact", "central"}
        Newton's Jacobian (:data:`NEWTON_JACOBIANS`). ``"exact"`` (default): the exact
        Jacobian of the map at every iterate (:meth:`PoincareMap.exact_jacobian`; one step
        with its variational equations gives ``P(z)`` and ``DP(z)`` together, quadratic
        convergence, and the gait's multipliers from the Jacobian at the root) where it
        applies: a passive walk on the scipy reference, a walker whose period is one step and
        whose equations can be differentiated; central differences (``2 d`` step maps per
        iterate) elsewhere,
        and at a point where the exact one cannot be formed (a grazing event). ``"central"``:
        differences everywhere. The choice is recorded in the cycle's ``newton_jacobian``.

    Returns
    -------
    Gait

    Raises
    ------
    GaitNotFoundError
        If no step can be taken, Newton diverges, or the iteration does not converge; at once
        for a passive walker on a slope <= 0.
    """
    kw: dict[str, Any] = dict(
        slope=slope, torque=torque, push_off=push_off, tol=tol, max_iter=max_iter,
        fd_step=fd_step, rtol=rtol, atol=atol, method=method, simulator=simulator,
        jacobian=jacobian,
    )
    if guess is None:
        return find_limit_cycles(walker, progress=progress, **kw)[0]
    pmap = PoincareMap(
        walker=walker, slope=slope, torque=torque, push_off=push_off, rtol=rtol, atol=atol,
        method=method, simulator=simulator,
    )
    z, residual, it, kind, DP = _newton(pmap, np.asarray(guess, dtype=float), tol, max_iter,
                                        fd_step, jacobian)
    return _closed_books([_characterise(pmap, z, residual, it, fd_step, kind, DP)], pmap)[0]


def _multiplier_jacobian(pmap: PoincareMap, z: FloatArray, fd_step: float) -> FloatArray:
    """The Jacobian whose eigenvalues are a gait's Floquet multipliers.

    Exact (:meth:`PoincareMap.exact_jacobian`: variational equations and saltation matrices)
    for a passive walk on the scipy reference whose walker has generated equations; central
    differences with ``fd_step`` otherwise (compiled maps, actuated walks: a torque law need not
    take the complex states of the complex-step derivatives) or where the exact Jacobian is
    unavailable (a grazing event, a step that does not complete).
    """
    from heelstrike.core.saltation import GrazingEventError
    from heelstrike.dynamics.variational import ExactJacobianUnavailable, StepFailedError

    sim = pmap.simulator
    passive = pmap.torque is None and pmap.push_off is None
    if pmap.method == "scipy" and passive and (sim is None or sim is simulate):
        try:
            return pmap.exact_jacobian(z).jacobian
        except (ExactJacobianUnavailable, GrazingEventError, StepFailedError):
            pass  # central differences say what they can (NaN where the step fails)
    return pmap.jacobian(z, fd_step)


def _characterise(
    pmap: PoincareMap, z: FloatArray, residual: float, iterations: int, fd_step: float,
    newton_jacobian: str = "central", jacobian: FloatArray | None = None,
) -> Gait:
    """The gait at Newton's root ``z``; its multipliers from ``jacobian`` (``DP(z)``, the
    Jacobian Newton evaluated at ``z``) if given and finite, else
    :func:`_multiplier_jacobian`."""
    walker = pmap.walker
    if jacobian is not None and np.all(np.isfinite(jacobian)):
        Jac = jacobian
    else:
        Jac = _multiplier_jacobian(pmap, z, fd_step)
    mult = floquet_multipliers(Jac)
    if pmap.method == "compiled":
        from heelstrike.dynamics.compiled import step_map_compiled

        step = step_map_compiled(
            walker,  # type: ignore[arg-type]
            z, pmap.slope, rtol=pmap.rtol, atol=pmap.atol,
            max_step_duration=pmap.max_step_duration,
        )
        return _characterise_compiled(pmap, z, step.step_time, mult, residual, iterations)
    walk = pmap.walk(z, walker.steps_per_period)
    if not walk.ok:  # converged on a batched map that does not check everything the walk does
        raise GaitNotFoundError(f"the walk of a period from the converged point "
                                f"{np.round(z, 6)} fails: {walk.status.value} ({walk.message})")
    recs = walk.impacts
    rec = recs[0]
    return _cycle(
        pmap, z, mult, period=sum(r.step_duration for r in recs),
        step_length=sum(r.step_length for r in recs),
        impact_angle=rec.impact_angle, collision_loss=sum(r.energy_lost for r in recs),
        kinetic_energy_pre=rec.kinetic_energy,
        kinetic_energy_admissible=rec.kinetic_energy_admissible,
        potential_energy_released=sum(r.potential_energy_released for r in recs),
        actuator_work=sum(r.actuator_work for r in recs), residual=residual,
        iterations=iterations, walk=walk, leg_crossings=leg_crossings(walker, walk),
        newton_jacobian=newton_jacobian,
    )


def _cycle(
    pmap: PoincareMap, z: FloatArray, multipliers: NDArray[np.complex128], *, period: float,
    step_length: float, collision_loss: float, iterations: int, walk: Any,
    leg_crossings: int | None, newton_jacobian: str = "central", **values: float,
) -> Gait:
    """The :class:`~heelstrike.analysis.gaits.Gait` at the fixed point ``z`` of ``pmap``: its
    speed, stability and ``eta`` from the step's ``period`` (s), ``step_length`` (m),
    ``collision_loss`` (J) and ``multipliers``; ``values`` are the other float fields (the
    step's energies, ``impact_angle``, the Newton ``residual``)."""
    q, q_dot = pmap.walker.section_to_state(z)
    mult = np.asarray(multipliers, dtype=complex)
    return Gait(
        fixed_point=np.array(z, dtype=float), section_names=pmap.walker.section_names, q=q,
        q_dot=q_dot, period=float(period), step_length=float(step_length),
        speed=float(step_length) / float(period), multipliers=mult,
        stable=is_stable(mult), collision_loss=float(collision_loss),
        eta=float(loss_per_metre(collision_loss, step_length)), slope=float(pmap.slope),
        iterations=int(iterations), walk=walk, leg_crossings=leg_crossings,
        newton_jacobian=newton_jacobian,
        **cast(dict[str, Any], {k: float(v) for k, v in values.items()}),
    )


def _characterise_compiled(
    pmap: PoincareMap,
    z: FloatArray,
    period: float,
    multipliers: NDArray[np.complex128],
    residual: float,
    iterations: int,
) -> Gait:
    """A gait of the compiled map characterised on the compiled backend.

    The pre-impact state is the compiled integration of single support from the fixed point
    over the step's duration ``period`` (the compiled map's heel-strike time), at the map's
    tolerances; the impact decomposition (``T``, ``T_c``, ``T_a``), the step length and the
    potential energy released are then computed there exactly as
    :func:`~heelstrike.dynamics.hybrid.simulate` computes them. ``multipliers`` are those of the
    compiled map's Jacobian. The ``walk`` (trajectory samples) is the scipy reference's,
    simulated on first access.
    """
    from heelstrike.dynamics.compiled import single_support_compiled
    from heelstrike.dynamics.hybrid import heel_strike
    from heelstrike.dynamics.single_support import SingleSupport

    walker, slope = pmap.walker, float(pmap.slope)
    z = np.asarray(z, dtype=float)
    if not (np.isfinite(period) and period > 0.0):
        raise GaitNotFoundError(f"the walker fails to take a step from {np.round(z, 6)}")
    q0, qd0 = walker.section_to_state(z)
    support = SingleSupport(walker=walker, slope=slope)
    path = single_support_compiled(
        walker,  # type: ignore[arg-type]
        support.pack(q0, qd0), slope, float(period), rtol=pmap.rtol, atol=pmap.atol,
    )
    q, q_dot = support.unpack(path[-1], q0)
    # the hip angle at the start and after every accepted integrator step
    hip = [q0[walker.hip_joint], *(support.unpack(row, q0)[0][walker.hip_joint] for row in path)]
    impact, _ = heel_strike(walker, q, q_dot)
    return _cycle(
        pmap, z, multipliers, period=period, step_length=float(walker.step_length(q0, q)),
        impact_angle=float(q[2]), collision_loss=float(impact.energy_lost),
        kinetic_energy_pre=float(impact.kinetic_energy),
        kinetic_energy_admissible=float(impact.kinetic_energy_admissible),
        potential_energy_released=float(
            walker.potential_energy(q0, slope) - walker.potential_energy(q, slope)
        ),
        actuator_work=0.0, residual=residual, iterations=iterations,
        walk=_OneStep(pmap=pmap, z=z.copy()), leg_crossings=_sign_changes(hip),
    )


@dataclass(frozen=True, kw_only=True)
class Continuation(ResultDictMixin):
    """A branch of period-one gaits along a parameter.

    Attributes
    ----------
    parameter : str
        Name of the varied parameter (``"slope"`` or a walker field).
    values : ndarray, shape (K,)
        Parameter values where a gait was found (SI units; rad for the slope).
    cycles : tuple of Gait
        The gait at each value.
    period_doubling : ndarray, shape (P,)
        Parameter values (linearly interpolated) where a real multiplier crosses -1.
    stopped : str or None
        Why the branch ended early, if it did.
    """

    parameter: str
    values: FloatArray
    cycles: tuple[Gait, ...]
    period_doubling: FloatArray
    stopped: str | None

    @property
    def spectral_radius(self) -> FloatArray:
        return np.asarray([c.spectral_radius for c in self.cycles])


def continue_limit_cycle(
    walker: PlanarWalker,
    parameter: str,
    values: ArrayLike,
    *,
    slope: float = 0.0,
    guess: ArrayLike | None = None,
    progress: bool = False,
    **kwargs: Any,
) -> Continuation:
    """Natural-parameter continuation of a period-one gait.

    Each gait is found by Newton's method from the secant prediction of the previous ones, with
    step control (the one continuation, ``heelstrike.analysis._continuation.follow``): where
    Newton fails, is slow or lands far from the prediction (another gait family), the step to
    the next value is halved, so the branch does not depend on how finely ``values`` sample
    it; the continuation stops where the sub-step would fall below 1/1024 of the values'
    largest spacing (a fold, or the end of the walker's gaits). Period doubling is
    detected where the smallest real multiplier crosses -1 between consecutive values,
    and located by :func:`refine_period_doubling` (bisection, 12 halvings of the bracket).

    Parameters
    ----------
    walker : PlanarWalker
        Walker with a Poincare section; other parameters than the slope are changed with its
        ``replace(**params)``.
    parameter : str
        ``"slope"`` or the name of a walker parameter (e.g. ``"foot_radius"``, ``"hip_mass"``
        for :class:`~heelstrike.models.CompassGait`, ``"R"`` for a described walker).
    values : array_like, shape (K,)
        Parameter values, in order.
    slope : float
        Slope (rad) when ``parameter`` is not the slope.
    guess : array_like, optional
        Section coordinates near the first gait.
    **kwargs
        Passed to :func:`find_limit_cycle`.

    Raises
    ------
    ValueError
        The walker has no Poincare section or no parameter ``parameter``, or a value is
        outside the walker's parameter constraints.
    """
    vals = np.asarray(values, dtype=float)
    try:
        _ = walker.section_names
    except NotImplementedError as exc:
        raise ValueError(
            f"cannot continue a gait of {walker!r}: {exc} (for a described walker use "
            "heelstrike.dynamics.phased.PhasedWalker.from_built(walker))"
        ) from None
    from heelstrike.analysis._continuation import Point, follow

    def at(v: float) -> tuple[PlanarWalker, float]:
        if parameter == "slope":
            return walker, float(v)
        try:
            return walker.replace(**{parameter: float(v)}), slope
        except TypeError as exc:  # a dataclass walker without that field
            raise ValueError(f"{parameter!r} is not a parameter of {walker!r}: {exc}") from None

    def where(v: float) -> str:
        return f"slope {np.rad2deg(v):.4g} deg" if parameter == "slope" else f"{parameter} = {v:g}"

    last_error: list[GaitNotFoundError] = []

    def correct(v: float, z: FloatArray, it: int) -> tuple[Gait, FloatArray, int, float]:
        w, s = at(v)
        try:
            c = find_limit_cycle(w, slope=s, guess=z, **{**kwargs, "max_iter": it})
        except GaitNotFoundError as exc:
            last_error[:] = [exc]
            raise
        return c, c.fixed_point, c.iterations, float("nan")

    cycles: list[Gait] = []
    found: list[float] = []
    stopped = None
    max_iter = int(kwargs.get("max_iter", 20))
    # sub-steps of at most the values' largest spacing: on a well-resolved grid one per value,
    # halved where Newton fails, is slow or jumps (the branch does not depend on the grid),
    # down to 1/1024 of it (a coarse grid's first sub-step, predicted without a secant, may
    # need many halvings)
    h_max = float(np.max(np.abs(np.diff(vals)))) if vals.size > 1 else 1.0
    point: Point | None = None
    for v in _progress(list(vals), progress, f"continuation in {parameter}"):
        if point is None:
            w, s = at(v)
            try:
                c = find_limit_cycle(w, slope=s, guess=guess, **kwargs)
            except GaitNotFoundError as exc:
                stopped = f"no gait at {where(v)}: {exc}"
                break
            point = Point(value=float(v), z=c.fixed_point, mnr=float("nan"), gait=c)
        else:
            (got,), path = follow(correct, point, [float(v)], h_max, max_iter=max_iter,
                                  h_min=h_max * _CONTINUATION_MIN_STEP)
            if got is None:
                why = f": {last_error[0]}" if last_error else ""
                stopped = (f"no gait at {where(v)}: the branch ends after {where(path[-1].value)} "
                           f"(Newton failed, was slow or jumped to another gait on every "
                           f"shorter sub-step{why})")
                break
            point = got
        cycles.append(point.gait)
        found.append(float(v))
    pd: list[float] = []
    for a, b, ca, cb in zip(found[:-1], found[1:], cycles[:-1], cycles[1:], strict=True):
        ma, mb = _smallest_real(ca.multipliers), _smallest_real(cb.multipliers)
        if ma is not None and mb is not None and (ma + 1.0) * (mb + 1.0) < 0:

            def solve(v: float, z0: FloatArray) -> tuple[float, FloatArray]:
                w, s = at(v)
                c = find_limit_cycle(w, slope=s, guess=z0, **kwargs)
                m = _smallest_real(c.multipliers)
                return (np.nan if m is None else m), c.fixed_point

            pd.append(refine_period_doubling(solve, a, b, ma, ca.fixed_point))
    return Continuation(
        parameter=parameter,
        values=np.asarray(found),
        cycles=tuple(cycles),
        period_doubling=np.asarray(pd),
        stopped=stopped,
    )


def refine_period_doubling(
    solve: Callable[[float, FloatArray], tuple[float, FloatArray]],
    lo: float,
    hi: float,
    m_lo: float,
    z_lo: FloatArray,
    *,
    iterations: int = 12,
) -> float:
    """The parameter value where the smallest real multiplier crosses -1 (period
    doubling): the one definition, used by continuation and by the gait maps.

    Bisection on ``[lo, hi]`` (the crossing is bracketed: ``m(lo) + 1`` and ``m(hi) + 1`` have
    opposite signs), each gait found by ``solve(value, z)`` from the fixed point ``z`` of the
    last gait on the ``lo`` side; ``iterations`` halvings (12: the bracket shrinks 4096-fold).
    If a gait is not found the midpoint of the current bracket is returned.

    Parameters
    ----------
    solve : callable
        ``solve(value, z0) -> (smallest real multiplier, fixed point)``; may raise
        :class:`GaitNotFoundError`.
    lo, hi : float
        The bracket (parameter units).
    m_lo : float
        Smallest real multiplier at ``lo``.
    z_lo : ndarray
        Fixed point at ``lo``.
    """
    f_lo, z = m_lo + 1.0, z_lo
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        try:
            m, z_mid = solve(mid, z)
        except GaitNotFoundError:
            break
        f = m + 1.0
        if not np.isfinite(f):
            break
        if f * f_lo > 0.0:
            lo, f_lo, z = mid, f, z_mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _smallest_real(mult: NDArray[np.complex128]) -> float | None:
    real = [m.real for m in mult if abs(m.imag) < 1e-9 * max(1.0, abs(m))]
    return min(real) if real else None


#: A period-``p`` cycle (``p > 1``) of :meth:`BifurcationDiagram.period_steps` must be this many
#: times wider (step to step) than its angles ``p`` steps apart disagree.
CYCLE_CONTRAST = 100.0


@dataclass(frozen=True, kw_only=True)
class BifurcationDiagram(ResultDictMixin):
    """Steady-state step-to-step values along the slope (brute force, as Goswami et al. 1998).

    Attributes
    ----------
    slopes : ndarray, shape (K,)
        Slopes (rad).
    impact_angles, periods : ndarray, shape (K, N)
        The last ``N`` impact angles (rad) and step durations (s) after the transient; NaN
        where the walker fell.
    statuses : tuple of str, length K or 0
        How each slope's walk ended (a :class:`~heelstrike.dynamics.hybrid.WalkStatus` value,
        e.g. ``"completed"`` or ``"fell_backward"``); ``""`` for a slope that was not walked
        (below the first gait of the range). Empty when not recorded (a diagram built by
        hand).
    """

    slopes: FloatArray
    impact_angles: FloatArray
    periods: FloatArray
    statuses: tuple[str, ...] = ()

    def period_steps(self, tol: float = 1e-6) -> NDArray[np.int_]:
        """The period (in steps) each slope's walk settled into, from its recorded steps.

        Parameters
        ----------
        tol : float
            Largest difference (rad) between impact angles ``p`` steps apart.

        Returns
        -------
        ndarray of int, shape (K,)
            The smallest ``p <= N // 2`` with ``|impact_angles[k, i + p] - impact_angles[k, i]|
            <= tol`` over every recorded step (1: the period-one gait, 2: after its period
            doubling, ...) and, for ``p > 1``, a cycle at least :data:`CYCLE_CONTRAST` times
            wider than that (its largest step-to-step difference): a walk still converging
            to the period-one gait through a multiplier near -1 alternates with an amplitude
            that shrinks, and its angles two steps apart agree ~10x better than one step
            apart (QA sweep 7: "settled on period 2" on the stable branch). 0 where no such
            ``p`` exists (a longer period, chaos, or a walk still in its transient, as near a
            period doubling, where it settles slowly), where a recorded step is missing (the
            walk fell), or with fewer than 2 recorded steps. A cycle's width must also hold
            to ``tol`` over the record (its first ``p`` steps against its last ``p``): with
            a multiplier of -0.998, just below the period doubling, the alternation on the way
            to the period-one gait shrinks only 3 % over 16 steps and passed the contrast test
            (QA sweep 13: "period 2" where a 20,000-step walk settles on period one).
        """
        angles = np.asarray(self.impact_angles, dtype=float)
        out = np.zeros(angles.shape[0], dtype=int)
        n = angles.shape[1]
        for k, row in enumerate(angles):
            if n < 2 or not np.all(np.isfinite(row)):
                continue
            width = float(np.max(np.abs(np.diff(row))))
            for p in range(1, n // 2 + 1):
                residual = float(np.max(np.abs(row[p:] - row[:-p])))
                if residual > tol:
                    continue
                if p == 1:
                    out[k] = p
                    break
                first = float(np.ptp(row[:p + 1]))
                last = float(np.ptp(row[-p - 1:]))
                if width >= CYCLE_CONTRAST * residual and abs(first - last) <= tol:
                    out[k] = p
                    break
        return out

    def settling(self, branch: Continuation, tol: float = 1e-6) -> NDArray[np.bool_]:
        """Walks still on their way to the stable period-one gait when recorded.

        A walk that completed without settling into a period (:meth:`period_steps` 0) at a
        slope where the period-one gait is stable (``branch``, the continuation over these
        slopes) is a transient, not a steady state: with a multiplier near 1 (large feet)
        or near -1 (near the period doubling) the transient outlasts the walk (QA sweep 13:
        at R = 0.9 m, 50 transient steps left the walk 8 deg from the gait, and one such walk
        fell at step 232). Past the period doubling a walk without a period may be chaotic,
        and is not counted here.

        Returns
        -------
        ndarray of bool, shape (K,)
        """
        period = self.period_steps(tol)
        values = np.asarray(branch.values, dtype=float)
        stable = np.asarray([c.stable for c in branch.cycles], dtype=bool)
        out = np.zeros(self.slopes.shape[0], dtype=bool)
        if len(self.statuses) != out.size or branch.parameter != "slope" or not values.size:
            return out
        for k, (slope, status) in enumerate(zip(self.slopes, self.statuses, strict=True)):
            if status != "completed" or period[k]:
                continue
            at = np.isclose(values, slope, rtol=1e-9, atol=1e-12)
            out[k] = bool(np.any(stable[at]))
        return out


def bifurcation_diagram(
    walker: PlanarWalker,
    slopes: ArrayLike,
    *,
    guess: ArrayLike | None = None,
    transient: int = BIFURCATION_TRANSIENT,
    record: int = BIFURCATION_RECORD,
    rtol: float = 1e-9,
    atol: float = 1e-10,
    progress: bool = False,
    callback: Callable[[int], None] | None = None,
    simulator: Callable[..., WalkResult] | None = None,
    restart: Callable[[float, FloatArray], ArrayLike] | None = None,
) -> BifurcationDiagram:
    """Brute-force bifurcation diagram over increasing slopes.

    For each slope the walker is released from the previous slope's last post-impact state
    (the first from ``guess`` or an automatically found gait), walks ``transient`` steps, and
    the next ``record`` impact angles and step durations are stored. ``simulator`` is the
    step simulator of :class:`PoincareMap` (default: the scipy reference).

    A walk that falls is walked once more from ``restart(slope, z)`` (e.g. the period-one gait
    at that slope by Newton from ``z``, the last state that walked; None: no second walk;
    nothing if ``restart`` raises :class:`GaitNotFoundError`), and the longer of the two walks
    is kept. Without it a coarse grid's step in the slope can throw the walker off a stable
    gait, and every later slope starts from the same stale state (QA sweep 7: 11 slopes of a
    stable branch "lost contact").
    """
    sl = np.asarray(slopes, dtype=float)
    K = sl.size
    angles = np.full((K, record), np.nan)
    periods = np.full((K, record), np.nan)
    statuses = [""] * K
    if guess is None:
        z = find_limit_cycle(walker, slope=float(sl[0]), rtol=rtol, atol=atol).fixed_point
    else:
        z = np.asarray(guess, dtype=float)
    for i in _progress(list(range(K)), progress, "bifurcation diagram"):
        pmap = PoincareMap(walker=walker, slope=float(sl[i]), rtol=rtol, atol=atol,
                           simulator=simulator)
        res = pmap.walk(z, transient + record)
        if not res.ok and restart is not None:
            try:
                again = pmap.walk(np.asarray(restart(float(sl[i]), z), dtype=float),
                                  transient + record)
            except GaitNotFoundError:
                again = None
            if again is not None and len(again.impacts) > len(res.impacts):
                res = again
        rec = res.impacts[transient:]
        angles[i, : len(rec)] = [r.impact_angle for r in rec]
        periods[i, : len(rec)] = [r.step_duration for r in rec]
        statuses[i] = str(res.status.value)
        if res.ok:
            z = walker.state_to_section(res.final_q, res.final_q_dot)
        if callback is not None:
            callback(i)
    return BifurcationDiagram(slopes=sl, impact_angles=angles, periods=periods,
                              statuses=tuple(statuses))
