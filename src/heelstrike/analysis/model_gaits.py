"""Gaits, energy books and heel-strike maps of described walkers (TOML models).

- :func:`find_model_gaits` / :func:`find_model_gait`: the period-one gaits (the stable one
  first) / a period-one gait of a :class:`~heelstrike.models.builder.BuiltWalker`
  through :func:`~heelstrike.analysis.limit_cycle.find_limit_cycle` with the compiled
  :func:`~heelstrike.dynamics.compiled_phased.simulate_phased_compiled` (default) or the scipy
  reference :func:`~heelstrike.dynamics.phased.simulate_phased` (knee strikes and heel
  strikes), and its energy book: per step, ``actuator work + potential energy released = sum
  of T_c`` over the step's impacts (Font & Kövecses 2008, eqs. 14-15) on the periodic gait.
- :func:`model_heel_strike`: the impact decomposition of a heel strike of any described walker.
- :func:`impact_map`: ``T_c``, ``T_a`` and ``eta`` at heel strike over a grid of two swept
  description parameters (or a parameter and the impact angle): the paper's Figs. 2-3 for any
  walker.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.analysis._continuation import PARAMETER_STEP, SLOPE_STEP, Point, follow
from heelstrike.analysis._memory import require_budget
from heelstrike.analysis.gaits import Gait, StepBook
from heelstrike.analysis.heel_strike import loss_per_metre, trailing_foot_lifts
from heelstrike.analysis.limit_cycle import (
    GaitNotFoundError,
    PoincareMap,
    _add_distinct,
    _check_passive_slope,
    _preference,
    _progress,
    find_limit_cycle,
)
from heelstrike.core.complementarity import CandidateContact, resolve_impact
from heelstrike.dynamics.backends import simulator as backend_simulator
from heelstrike.dynamics.hybrid import PushOff
from heelstrike.dynamics.phased import (
    PhasedWalker,
    PhasedWalkResult,
)
from heelstrike.dynamics.single_support import TorqueLaw
from heelstrike.models.base import PlanarWalker, gravity_vector
from heelstrike.models.builder import BuiltWalker

__all__ = [
    "ANGLE",
    "IMPACT_MAP_BYTES_PER_POINT",
    "IMPACT_MAP_SECONDS_PER_POINT",
    "LOCK_TORQUE_SAMPLES",
    "REFERENCE_SLOPE",
    "TWO_SIDED_FLOOR",
    "GaitLocks",
    "ImpactMap",
    "ModelHeelStrike",
    "check_impact_map_memory",
    "find_model_gait",
    "find_model_gaits",
    "follows_reference",
    "gait_locks",
    "hanging_links",
    "impact_map",
    "lock_torque_ranges",
    "model_heel_strike",
    "symmetric_heel_strike_state",
    "two_sided_locks",
    "upright_links",
]

#: Name of the impact angle as a swept quantity of :func:`impact_map`.
ANGLE = "angle"


# -- gaits --------------------------------------------------------------------------------------
def _grid_guesses(walker: PhasedWalker, *, fine: bool = False) -> list[FloatArray]:
    """Seeds on the walker's section: stance angles, stance and swing rates
    (:meth:`~heelstrike.models.base.PlanarWalker.section_point`), the rates scaled by the
    walker's ``sqrt(g / l)`` (those of the paper's walker for ``g = 9.81``, ``l = 1``).

    The coarse grid (120 seeds, step angles 5.7-17 deg) starts the search on both backends;
    ``fine``: the compass search's grid (:func:`~heelstrike.analysis.limit_cycle._seed_grid`,
    864 seeds over step angles of 3-34 deg), the compiled backend's second stage
    (:func:`find_model_gaits`).
    """
    from heelstrike.analysis.limit_cycle import _seed_grid

    _, g, l = walker.scale
    k = float(np.sqrt(float(g) / float(l) / 9.81))
    if fine:
        rows = _seed_grid()
    else:
        rows = np.array(list(itertools.product(
            (-0.1, -0.15, -0.2, -0.25, -0.3), (0.6, 0.8, 1.0, 1.2, 1.4, 1.6),
            (-1.0, -0.6, -0.3, 0.0))))
    return [walker.section_point(a, k * w, k * h) for a, w, h in rows]


#: The compiled search's attractor pass: the most nearly periodic seeds walked this many steps
#: (a stable gait attracts them; :func:`find_model_gaits`).
ATTRACTOR_SEEDS, ATTRACTOR_STEPS = 40, 50


#: Slope (rad) of the reference gait that :func:`find_model_gaits` follows to the walker when the
#: automatic search finds no stable gait: the walker file's own parameters at 3 deg (the slope at
#: which ``map`` anchors its branches).
REFERENCE_SLOPE = float(np.deg2rad(3.0))


def _energy_book(cycle: Gait, walker: PlanarWalker, *, backend: str | None = None) -> Gait:
    """The gait ``cycle`` (its ``collision_loss`` the heel strikes') with the energy book of
    its one-period walk (every impact of the period), the ``walker``'s links it carries
    hanging and its lock torques (:func:`gait_locks` on ``backend``, computed on first access
    of :attr:`~heelstrike.analysis.gaits.Gait.locks`; None without locked joints, or with
    ``backend`` None: an actuated gait, whose step :func:`gait_locks` cannot walk again):
    ``collision_loss``, ``eta``, ``actuator_work`` and ``potential_energy_released`` become the
    period's totals over every impact."""
    walk = cycle.walk
    assert isinstance(walk, PhasedWalkResult)
    impacts = walk.events
    books = []
    for rec in walk.impacts:
        mine = [e for e in impacts if e.step == rec.step]
        lost = float(sum(e.kinetic_energy_constrained for e in mine))
        books.append(StepBook(
            step=int(rec.step), duration=float(rec.step_duration),
            step_length=float(rec.step_length), collision_loss=lost,
            potential_energy_released=float(rec.potential_energy_released),
            actuator_work=float(rec.actuator_work),
            kinetic_energy_gained=float(rec.actuator_work + rec.potential_energy_released
                                        - lost),
            kinetic_energy_pre=float(sum(e.kinetic_energy for e in mine)),
            kinetic_energy_admissible=float(sum(e.kinetic_energy_admissible for e in mine)),
            impact_angle=float(rec.impact_angle)))
    loss = float(sum(b.collision_loss for b in books))
    work = float(sum(b.actuator_work for b in books))
    released = float(sum(b.potential_energy_released for b in books))
    return replace(
        cycle,
        impacts=impacts,
        collision_loss=loss,
        eta=float(loss_per_metre(loss, cycle.step_length)),
        actuator_work=work,
        potential_energy_released=released,
        energy_residual=work + released - loss,
        kinetic_energy_pre=float(sum(b.kinetic_energy_pre for b in books)),
        kinetic_energy_admissible=float(sum(b.kinetic_energy_admissible for b in books)),
        hanging_links=hanging_links(walker, cycle.q, cycle.slope),
        steps=tuple(books),
        locks=(_lazy_locks(walker, cycle, backend)
               if backend is not None and walker.step_schedule().lock_angles else None),
    )


def _lazy_locks(walker: PlanarWalker, cycle: Gait, backend: str) -> Callable[[], GaitLocks]:
    """:func:`gait_locks` of ``cycle``, deferred (one dense walk of its step; a partial of a
    module function, picklable where the walker and gait are)."""
    return functools.partial(gait_locks, walker, cycle, backend=backend)


def _coarse_ensemble(w: PhasedWalker, Z: FloatArray, kw: dict[str, Any], steps: int) -> Any:
    """``steps`` compiled steps from every seed of ``Z`` (S, d) at the search's coarse
    tolerance, serially, with the actuation of ``kw`` (checked for the compiled backend by
    ``backend_simulator``)."""
    from heelstrike.dynamics.compiled_phased import ensemble_walk_phased

    return ensemble_walk_phased(w, Z, steps=steps, slope=kw["slope"],
                                torque=cast(Any, kw["torque"]),
                                push_off=cast(Any, kw["push_off"]), rtol=1e-7, atol=1e-8,
                                parallel=False)


def _nearly_periodic(w: PhasedWalker, Z: FloatArray, backend: str,
                     kw: dict[str, Any]) -> list[FloatArray]:
    """The seeds ``Z`` (S, d) that take a step, most nearly periodic first (``|P(z) - z|`` at
    a coarse tolerance: one batched compiled call, or step by step on the scipy reference).

    Raises
    ------
    GaitNotFoundError
        No seed takes a step.
    """
    if backend == "compiled":
        ens = _coarse_ensemble(w, Z, kw, steps=int(w.steps_per_period))  # one period
        Z1 = np.where(ens.ok[:, None], ens.z, np.nan)
    else:
        coarse = PoincareMap(walker=w, rtol=1e-7, atol=1e-8, **kw)
        Z1 = np.array([coarse(z) for z in Z])
    err = np.linalg.norm(Z1 - Z, axis=1)
    mapped = np.flatnonzero(np.all(np.isfinite(Z1), axis=1))
    if mapped.size == 0:
        raise GaitNotFoundError("no step could be completed from any automatic guess")
    return [Z[i] for i in mapped[np.argsort(err[mapped], kind="stable")]]


def _attractors(w: PhasedWalker, Z: FloatArray, kw: dict[str, Any]) -> list[FloatArray]:
    """Where the seeds ``Z`` settle in :data:`ATTRACTOR_STEPS` compiled steps (a stable
    gait attracts the seeds near it), distinct to 1e-3."""
    walked = _coarse_ensemble(w, Z, kw, steps=ATTRACTOR_STEPS)
    out: list[FloatArray] = []
    for z in walked.z[walked.ok]:
        _add_distinct(out, np.asarray(z, dtype=float), 1e-3)
    return out


def find_model_gaits(
    walker: BuiltWalker,
    *,
    slope: float = 0.0,
    guess: ArrayLike | None = None,
    torque: TorqueLaw | None = None,
    push_off: PushOff | None = None,
    tol: float = 1e-10,
    max_iter: int = 20,
    rtol: float = 1e-11,
    atol: float = 1e-11,
    backend: str = "compiled",
    from_reference: bool = True,
    every_start: bool = False,
) -> tuple[Gait, ...]:
    """Find the period-one gaits of a described walker, the stable one first, with energy books.

    Without ``guess`` the search has two stages:

    1. A coarse grid of post-impact states (:func:`_grid_guesses`, 120 seeds, rates scaled
       by the walker's ``sqrt(g / l)``) is mapped once; Newton starts from the 5 most nearly
       periodic ones, until one converges to a stable gait. If none does, on the compiled
       backend, the compass search's finer grid (864 seeds, step angles 3-34 deg) is mapped
       too, its :data:`ATTRACTOR_SEEDS` most nearly periodic seeds are walked
       :data:`ATTRACTOR_STEPS` steps, and Newton starts from where they settle (a stable
       gait attracts them), then from the finer grid's 5 best. (The scipy reference, whose
       steps cost about a thousand times more, stops at the coarse grid.)
    2. If no stable gait was found and ``from_reference``: the stable gait of the walker file's
       own parameters at :data:`REFERENCE_SLOPE` (found by stage 1) is followed by
       natural-parameter continuation with step control (the one ``map`` uses) along the
       straight line from those parameters and that slope to the walker's, so that ``gait``
       finds the gait ``map`` reaches. Intermediate walkers the description rejects end the
       continuation.

    Parameters
    ----------
    walker : BuiltWalker
        Any described walker (wrapped in :class:`PhasedWalker` for its section).
    slope : float
        Ground slope (rad), positive downhill.
    guess : array_like, optional
        Section coordinates (``PhasedWalker.section_names``) to start Newton from; if given, the
        one gait Newton converges to is returned.
    torque, push_off : optional
        Actuation (see :func:`~heelstrike.dynamics.phased.simulate_phased`).
    tol, max_iter, rtol, atol
        Newton tolerance and iterations; integrator tolerances.
    backend : {"compiled", "scipy"}
        Step simulator: :func:`~heelstrike.dynamics.compiled_phased.simulate_phased_compiled`
        (numba, generated from the walker's equations; passive or
        :class:`~heelstrike.dynamics.phased.TorsoPD` torque, optionally
        :class:`~heelstrike.dynamics.actuation.PushOff`) or the scipy reference
        :func:`~heelstrike.dynamics.phased.simulate_phased` (any actuation).
    from_reference : bool
        Allow stage 2.
    every_start : bool
        Run Newton from every coarse start of stage 1, not only until a stable gait is found,
        so that the gaits returned are all those the starts reach (``heelstrike gait`` lists
        them on the compiled backend, as the compass gait's search does). Costs a few more
        Newton solves: on the scipy reference, seconds each.

    Returns
    -------
    tuple of Gait
        The distinct gaits found (fixed points further apart than ``SAME_GAIT_TOL``): stable
        before unstable, then by increasing spectral radius.

    Raises
    ------
    GaitNotFoundError
        No gait found, or a passive walker (no torque, no push-off) on a slope <= 0.
    ValueError
        Unknown backend, or actuation the compiled backend does not support.
    """
    w = PhasedWalker.from_built(walker)
    _check_passive_slope(slope, torque=torque, push_off=push_off, walker=w)
    # the one entry point, checked for this walker and actuation (ValueError if unsupported)
    simulator = backend_simulator(w, backend, torque=torque, push_off=push_off)
    kw: dict[str, Any] = dict(slope=slope, torque=torque, push_off=push_off, simulator=simulator)
    if guess is not None:
        starts = [np.asarray(guess, dtype=float)]
    else:
        # the grid mapped once at a coarse tolerance: one batched compiled call, or step by
        # step on the scipy reference; Newton starts from the most nearly periodic points
        Z = np.array(_grid_guesses(w))
        starts = _nearly_periodic(w, Z, backend, kw)[:5]
    # stage 1: Newton from each start until a stable gait is found (on the compiled backend
    # then from the finer grid's attractors and most nearly periodic seeds)
    last: Exception | None = None
    found: list[Gait] = []
    points: list[FloatArray] = []
    finer = ""

    def add(cycle: Gait) -> None:
        if _add_distinct(points, np.asarray(cycle.fixed_point, dtype=float)):
            found.append(cycle)

    def newton_from(zs: list[FloatArray]) -> None:
        nonlocal last
        for z0 in zs:
            try:
                add(find_limit_cycle(
                    w, guess=z0, tol=tol, max_iter=max_iter, rtol=rtol, atol=atol, **kw
                ))
            except GaitNotFoundError as exc:
                last = exc
                continue
            if not every_start and any(c.stable for c in found):
                break

    newton_from(starts)
    if guess is None and backend == "compiled" and not any(c.stable for c in found):
        fine = np.array(_grid_guesses(w, fine=True))
        try:
            best = _nearly_periodic(w, fine, backend, kw)
        except GaitNotFoundError:
            best = []
        attractors = _attractors(w, np.array(best[:ATTRACTOR_SEEDS]), kw) if best else []
        newton_from(attractors + best[:5])
        finer = (f"; nor from the {len(attractors)} states that the {ATTRACTOR_SEEDS} most "
                 f"nearly periodic of {len(fine)} finer seeds settle to in {ATTRACTOR_STEPS} "
                 "steps, nor from the 5 best of those seeds")
    # stage 2: the reference gait followed to this walker and slope
    if guess is None and from_reference and not any(c.stable for c in found):
        z_end = _follow_reference(w, slope, torque=torque, push_off=push_off,
                                  backend=backend, rtol=rtol, atol=atol)
        if z_end is not None:
            try:
                add(find_limit_cycle(
                    w, guess=z_end, tol=tol, max_iter=max_iter, rtol=rtol, atol=atol, **kw
                ))
            except GaitNotFoundError as exc:
                last = exc
    if not found:
        if guess is not None:
            raise GaitNotFoundError(str(last))
        tried = (f"; nor did the walker file's own stable gait at {np.degrees(REFERENCE_SLOPE):g}"
                 " deg continue to these parameters and slope" if from_reference else "")
        raise GaitNotFoundError(
            f"Newton converged from none of the {len(starts)} most nearly periodic of "
            f"{len(Z)} automatic starts (the last: {last}){finer}{tried}")
    passive = torque is None and push_off is None
    gaits = tuple(_energy_book(c, walker, backend=backend if passive else None)
                  for c in sorted(found, key=_preference))
    if passive:
        return _closed_model_books(gaits, slope)
    return gaits


def _closed_model_books(gaits: tuple[Gait, ...], slope: float) -> tuple[Gait, ...]:
    """The passive gaits whose energy books close: the step's collision losses (every
    impact's) equal the potential energy released, both positive, to within
    :data:`~heelstrike.analysis.limit_cycle.ENERGY_BOOKS_RTOL` of the larger; raise
    :class:`GaitNotFoundError` when none does (solutions at the round-off of the walker's
    energies on a slope too small to resolve)."""
    from heelstrike.analysis.limit_cycle import ENERGY_BOOKS_RTOL

    def closes(g: Gait) -> bool:
        loss, supplied = g.collision_loss, g.potential_energy_released + g.actuator_work
        return bool(np.isfinite(loss) and np.isfinite(supplied) and loss > 0 and supplied > 0
                    and abs(loss - supplied) <= ENERGY_BOOKS_RTOL * max(loss, supplied))

    kept = tuple(g for g in gaits if closes(g))
    if kept or not gaits:
        return kept
    g = gaits[0]
    raise GaitNotFoundError(
        f"the {len(gaits)} period-one solution(s) found at slope {slope:g} rad do not close "
        f"the energy books (collision loss {g.collision_loss:.3g} J, energy released "
        f"{g.potential_energy_released:.3g} J per step, which must agree within "
        f"{100 * ENERGY_BOOKS_RTOL:g} %): the step's energies are at the round-off of the "
        "walker's energy, so these are no gaits; give a larger slope")


def follows_reference(walker: BuiltWalker, slope: float) -> bool:
    """Whether stage 2 of :func:`find_model_gaits` has anything to follow for ``walker`` at
    ``slope``: its parameters or the slope differ from the walker file's own at
    :data:`REFERENCE_SLOPE` (there, stage 1 has searched the reference itself).

    Parameters
    ----------
    walker : BuiltWalker
        A described walker.
    slope : float
        Ground slope (rad).

    Returns
    -------
    bool
    """
    desc = walker.description
    same = abs(float(slope) - REFERENCE_SLOPE) <= 1e-12 and all(
        np.array_equal(np.asarray(v, dtype=float), np.asarray(desc.default_params[k], dtype=float))
        for k, v in walker.parameters.items())
    return not same


def _follow_reference(
    w: PhasedWalker,
    slope: float,
    *,
    torque: TorqueLaw | None,
    push_off: PushOff | None,
    backend: str,
    rtol: float,
    atol: float,
) -> FloatArray | None:
    """Stage 2 of :func:`find_model_gaits`: the reference walker's stable gait at
    :data:`REFERENCE_SLOPE`, continued along ``lam`` in [0, 1] (parameters and slope linear in
    ``lam``) to ``w`` at ``slope``. Returns the fixed point at ``lam = 1``, or None if there is
    no stable reference gait, nothing to continue, or the branch ends before ``lam = 1``."""

    ref_values = w.description.default_params
    changed = {
        k: (np.asarray(ref_values[k], dtype=float), np.asarray(v, dtype=float))
        for k, v in w.parameters.items()
        if not np.array_equal(np.asarray(ref_values[k], dtype=float), np.asarray(v, dtype=float))
    }
    s0 = REFERENCE_SLOPE
    if not changed and abs(slope - s0) <= 1e-12:
        return None  # the reference itself: stage 1 has searched it
    try:
        ref = w.replace(**{k: a for k, (a, _) in changed.items()})
        start = find_model_gaits(ref, slope=s0, torque=torque, push_off=push_off, rtol=rtol,
                                 atol=atol, backend=backend, from_reference=False)[0]
    except (GaitNotFoundError, ValueError):
        return None
    if not start.stable:
        return None
    # the sub-step bound: at most SLOPE_STEP of slope and PARAMETER_STEP (relative) of each
    # changed parameter per sub-step, as in map
    h = 1.0
    if slope != s0:
        h = min(h, SLOPE_STEP / abs(slope - s0))
    for a, b in changed.values():
        span = float(np.max(np.abs(b - a)))
        scale = max(1.0, float(np.max(np.abs(a))), float(np.max(np.abs(b))))
        h = min(h, PARAMETER_STEP * scale / span)

    def solve(lam: float, z: FloatArray, it: int) -> tuple[Any, FloatArray, int, float]:
        at_end = lam == 1.0
        params = {k: b if at_end else a + lam * (b - a) for k, (a, b) in changed.items()}
        try:
            wl = w.replace(**params) if params else w
        except ValueError as exc:  # an intermediate walker the description rejects
            raise GaitNotFoundError(str(exc)) from exc
        s = slope if at_end else s0 + lam * (slope - s0)
        c = find_limit_cycle(wl, guess=z, max_iter=it, rtol=rtol, atol=atol, slope=s,
                             torque=torque, push_off=push_off,
                             simulator=backend_simulator(wl, backend, torque=torque,
                                                         push_off=push_off))
        return c, np.asarray(c.fixed_point, dtype=float), int(c.iterations), float("nan")

    z0 = np.asarray(start.fixed_point, dtype=float)
    (end,), _ = follow(solve, Point(value=0.0, z=z0, mnr=float("nan"), gait=start),
                        [1.0], h)
    return None if end is None else end.z


def find_model_gait(
    walker: BuiltWalker,
    *,
    slope: float = 0.0,
    guess: ArrayLike | None = None,
    torque: TorqueLaw | None = None,
    push_off: PushOff | None = None,
    tol: float = 1e-10,
    max_iter: int = 20,
    rtol: float = 1e-11,
    atol: float = 1e-11,
    backend: str = "compiled",
) -> Gait:
    """Find a period-one gait of a described walker and its energy book: the first (preferred)
    gait of :func:`find_model_gaits` (a stable one when one is found).

    Parameters
    ----------
    walker : BuiltWalker
    slope, guess, torque, push_off, tol, max_iter, rtol, atol, backend
        As :func:`find_model_gaits`.

    Returns
    -------
    Gait

    Raises
    ------
    GaitNotFoundError
    ValueError
        Unknown backend, or actuation the compiled backend does not support.
    """
    return find_model_gaits(walker, slope=slope, guess=guess, torque=torque, push_off=push_off,
                            tol=tol, max_iter=max_iter, rtol=rtol, atol=atol,
                            backend=backend)[0]


# -- single heel strike -------------------------------------------------------------------------
def upright_links(walker: PlanarWalker) -> tuple[str, ...]:
    """The links of a described walker meant to stand above a joint that lets them turn over
    (``direction = "up"``, on a joint that does not lock: a torso; not the root's stance leg,
    nor a kneed walker's stance thigh, held by its knee lock): those :func:`hanging_links`
    looks at."""
    desc = walker.description
    if desc is None:
        return ()
    return tuple(link.name for link in desc.links
                 if link.direction == "up" and link.parent is not None
                 and link.joint is not None and not link.joint.lockable)


def hanging_links(walker: PlanarWalker, q: ArrayLike, slope: float) -> tuple[str, ...]:
    """Links described upright that hang at the configuration ``q``.

    A link of :func:`upright_links` (a torso: ``direction = "up"`` on a joint that does not
    lock) is meant to stand above its proximal joint; a passive gait can instead carry it
    hanging, its centre of mass below the joint along gravity (the torso walker's stable
    passive gaits on 1-2 deg carry the torso through the legs, 179 deg from upright, while its
    upright gaits are unstable: QA sweep 13). Reports say so, since a gait of the hanging link
    is another gait.

    Parameters
    ----------
    walker : PlanarWalker
        A described walker (others have no such links: ``()``).
    q : array_like, shape (n,)
        Configuration (m, rad).
    slope : float
        Ground slope (rad).

    Returns
    -------
    tuple of str
        Names of the upright links whose centre of mass is below their proximal joint.
    """
    upright = upright_links(walker)
    if not upright:
        return ()
    down = gravity_vector(1.0, float(slope))  # unit vector along gravity
    points = cast(BuiltWalker, walker).positions(np.asarray(q, dtype=float))  # described
    return tuple(
        name for name in upright
        if float((points[f"{name}.com"] - points[f"{name}.proximal"]) @ down) > 0.0)


#: Samples per step of the walk :func:`lock_torque_ranges` measures on (the integrator's
#: largest step is the period over this).
LOCK_TORQUE_SAMPLES = 200


def lock_torque_ranges(
    walker: PlanarWalker, cycle: Gait, *, backend: str = "compiled"
) -> dict[str, tuple[float, float]]:
    """The smallest and largest torque each lock exerts over one step of a gait.

    The step is walked again from the gait's fixed point, sampled densely (at least
    :data:`LOCK_TORQUE_SAMPLES` samples), and
    :func:`~heelstrike.dynamics.hybrid.lock_torques` evaluated along it. A range that spans
    both signs is a lock that must pull as well as push: a one-sided knee stop could not hold
    it (QA sweep 13: the kneed walker's stance knee at 3 deg, -0.18 to +0.22 N m).

    Parameters
    ----------
    walker : PlanarWalker
        A described walker with lockable joints (others: an empty dict).
    cycle : Gait
        Its gait (``q``, ``q_dot``, ``period``, ``slope``).
    backend : {"compiled", "scipy"}
        Where to walk the step.

    Returns
    -------
    dict of str to (float, float)
        Per lockable joint (coordinate name): ``(min, max)`` of its holding torque (N m) while
        locked.
    """
    from heelstrike.dynamics import simulate
    from heelstrike.dynamics.hybrid import lock_torques

    if not walker.step_schedule().lock_angles:
        return {}
    walk = simulate(walker, cycle.q, cycle.q_dot, slope=cycle.slope, steps=1, backend=backend,
                    max_step=cycle.period / LOCK_TORQUE_SAMPLES)
    out = {}
    for name, torque in lock_torques(walker, walk).items():
        held = torque[np.isfinite(torque)]
        if held.size:
            out[name] = (float(held.min()), float(held.max()))
    return out


#: A lock's torque counts as of both signs when it passes this fraction of the walker's
#: ``m g l`` (N m) either way (round-off of a torque that keeps one sign stays far below).
TWO_SIDED_FLOOR = 1e-6


def two_sided_locks(
    walker: PlanarWalker, ranges: dict[str, tuple[float, float]]
) -> dict[str, tuple[float, float]]:
    """The locks of :func:`lock_torque_ranges` that must pull as well as push: a one-sided
    stop could not hold them (their ``(min, max)`` torques, N m)."""
    sc = walker.scale
    floor = TWO_SIDED_FLOOR * float(sc.total_mass * sc.gravity * sc.leg_length)
    return {k: v for k, v in ranges.items() if v[0] < -floor and v[1] > floor}


@dataclass(frozen=True, kw_only=True)
class GaitLocks(ResultDictMixin):
    """The torques a gait's locks exert over one step (:func:`gait_locks`).

    Attributes
    ----------
    ranges : dict of str to (float, float)
        Per lockable joint (coordinate name): ``(min, max)`` of its holding torque (N m) while
        locked (:func:`lock_torque_ranges`); empty for a walker without locks.
    two_sided : dict of str to (float, float)
        The locks among them that must pull as well as push (:func:`two_sided_locks`): a
        one-sided stop could not hold them.
    """

    ranges: dict[str, tuple[float, float]]
    two_sided: dict[str, tuple[float, float]]


def gait_locks(walker: PlanarWalker, cycle: Gait, *, backend: str = "compiled") -> GaitLocks:
    """The torques the locks of ``walker`` exert over one step of its gait ``cycle``, and which
    of them are two-sided (:func:`lock_torque_ranges`, :func:`two_sided_locks`).

    Parameters
    ----------
    walker : PlanarWalker
        A described walker (without lockable joints: no ranges).
    cycle : Gait
        Its gait.
    backend : {"compiled", "scipy"}
        Where to walk the step.

    Returns
    -------
    GaitLocks
    """
    ranges = lock_torque_ranges(walker, cycle, backend=backend)
    return GaitLocks(ranges=ranges, two_sided=two_sided_locks(walker, ranges))


def symmetric_heel_strike_state(
    walker: BuiltWalker, angle: float, *, stance_rate: float = 1.0
) -> tuple[FloatArray, FloatArray]:
    """Pre-impact state of the paper's heel-strike study for a described walker.

    Stance angle ``angle`` (rad); lockable joints at their lock angles; a joint named ``torso``
    held upright (relative angle ``-angle``); other joints 0, except the hip, which solves zero
    swing-foot clearance (the symmetric configuration for straight symmetric legs).
    Velocities: stance rate ``stance_rate`` (rad/s), all joint rates
    0, stance foot rolling.

    Returns
    -------
    q, q_dot : ndarray, shape (n,)
    """
    w = PhasedWalker.from_built(walker)
    n = w.n_coordinates
    R = float(np.asarray(w.foot_radii[0]))
    q = np.zeros(n)
    q[1] = R
    q[2] = angle
    for j, a in zip(w.lockable_joints, w.lock_angles, strict=True):
        q[j] = float(a)
    if "torso" in w.coordinate_names:
        q[w.joint_index("torso")] = -angle
    q = w.touchdown_configuration(q)
    qd = np.zeros(n)
    qd[2] = stance_rate
    qd[0] = -R * stance_rate
    return q, qd


@dataclass(frozen=True, kw_only=True)
class ModelHeelStrike(ResultDictMixin):
    """Decomposition of one heel strike of a described walker (all energies in J).

    Attributes
    ----------
    T, T_c, T_a, T_plus : float
        Kinetic energy before, its constrained (lost) and admissible parts, after.
    q, q_dot_minus, q_dot_plus : ndarray, shape (n,)
    impulse : ndarray, shape (k,)
        Impulses of the active rows (N s).
    step_length : float
        Length of the symmetric step ending in this impact (m): stance contact to striking
        contact along the ground plus the stance foot's rolling ``2 R q[2]``; the paper's
        ``L_S = 2 (l - R) sin q3 + 2 R q3`` for the compass gait.
    eta : float
        ``T_c / step_length`` (J/m).
    trailing_foot_lifts : bool
        Complementarity decision (``resolve_impact``) for the trailing foot.
    trailing_foot_held : bool
        The ground holds the trailing foot (a frictionless contact, its normal impulse the last
        entry of ``impulse``): ``T_c`` then includes what that contact destroys too, and is
        larger than the paper's ``T_c`` of the striking foot's constraints alone (eq. 10), which
        describes an inadmissible impact there (QA sweep 10).
    trailing_normal_velocity : float
        Its normal velocity after impact (m/s).
    """

    T: float
    T_c: float
    T_a: float
    T_plus: float
    q: FloatArray
    q_dot_minus: FloatArray
    q_dot_plus: FloatArray
    impulse: FloatArray
    step_length: float
    eta: float
    trailing_foot_lifts: bool
    trailing_foot_held: bool
    trailing_normal_velocity: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dictionary."""
        return {
            "T": self.T,
            "T_c": self.T_c,
            "T_a": self.T_a,
            "T_plus": self.T_plus,
            "energy_lost": self.T_c,
            "eta": self.eta,
            "step_length": self.step_length,
            "q": [float(v) for v in self.q],
            "qdot_minus": [float(v) for v in self.q_dot_minus],
            "qdot_plus": [float(v) for v in self.q_dot_plus],
            "impulse": [float(v) for v in self.impulse],
            "trailing_foot_lifts": self.trailing_foot_lifts,
            "trailing_foot_held": self.trailing_foot_held,
            "trailing_normal_velocity": self.trailing_normal_velocity,
        }


def model_heel_strike(walker: BuiltWalker, q: ArrayLike, q_dot: ArrayLike) -> ModelHeelStrike:
    """Heel strike of a described walker at ``(q, q_dot)`` (swing foot striking).

    The striking foot's rows and the locks of the lockable joints at their lock angle
    (:meth:`~heelstrike.models.builder.BuiltWalker.joints_at_lock`: a bent knee is free) are
    bilateral, the trailing foot a unilateral candidate decided by
    :func:`~heelstrike.core.complementarity.resolve_impact`.

    Parameters
    ----------
    walker : BuiltWalker
    q, q_dot : array_like, shape (n,)
        Pre-impact state (rad, m, rad/s, m/s).
    """
    q_ = np.asarray(q, dtype=float)
    qd = np.asarray(q_dot, dtype=float)
    n = walker.n_coordinates
    if q_.shape != (n,) or qd.shape != (n,):
        raise ValueError(
            f"state and velocity need {n} values each ({', '.join(walker.coordinate_names)})"
        )
    locked = walker.joints_at_lock(q_)  # a lockable joint away from its lock angle is free
    A_lock = walker.lock_jacobian(locked) if locked else np.zeros((0, n))
    M = walker.mass_matrix(q_)
    bil = np.vstack((walker.contact_jacobian(q_, "left"), A_lock))
    mc = resolve_impact(
        M, qd, bil, [CandidateContact.from_jacobian(walker.contact_jacobian(q_, "right"))]
    )
    R = float(np.asarray(walker.foot_radii[0]))
    L = float(walker.contact_point(q_, "right")[0] - walker.contact_point(q_, "left")[0])
    L += 2.0 * R * float(q_[2])  # rolling of the stance foot over a symmetric step
    T_c = mc.kinetic_energy_constrained
    return ModelHeelStrike(
        T=mc.kinetic_energy,
        T_c=T_c,
        T_a=mc.kinetic_energy_admissible,
        T_plus=float(mc.impact.kinetic_energy_post),
        q=q_,
        q_dot_minus=qd,
        q_dot_plus=np.asarray(mc.velocity_post),
        impulse=np.asarray(mc.impact.constraint_impulse),
        step_length=L,
        eta=float(loss_per_metre(T_c, L)),
        trailing_foot_lifts=mc.modes[0] == "separate"
        and bool(
            trailing_foot_lifts(
                float(mc.normal_velocity[0]),
                float(walker.scale.leg_length) * float(np.sum(np.abs(qd[2:]))),
            )
        ),
        trailing_foot_held=mc.modes[0] != "separate",
        trailing_normal_velocity=float(mc.normal_velocity[0]),
    )


# -- maps over two swept quantities -------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class ImpactMap(ResultDictMixin):
    """Heel-strike energetics over a grid of two swept quantities.

    Attributes
    ----------
    x_name, y_name : str
        Swept description parameters, or :data:`ANGLE` (the stance angle at impact, rad).
    x, y : ndarray, shape (nx,), (ny,)
        Values (SI units).
    T, T_c, T_a, eta, step_length, trailing_normal_velocity : ndarray, shape (ny, nx)
        At each grid point (J, J, J, J/m, m, m/s); NaN where the walker is invalid.
    lifts : ndarray of bool, shape (ny, nx)
        The trailing foot lifts (the impact is admissible).
    held : ndarray of bool, shape (ny, nx)
        The ground holds the trailing foot (:attr:`ModelHeelStrike.trailing_foot_held`: the
        energies include its contact's loss).
    angle : float
        Impact angle (rad) when it is not swept.
    stance_rate : float
        Pre-impact stance-leg rate (rad/s).
    walker_name : str
    """

    x_name: str
    y_name: str
    x: FloatArray
    y: FloatArray
    T: FloatArray
    T_c: FloatArray
    T_a: FloatArray
    eta: FloatArray
    step_length: FloatArray
    trailing_normal_velocity: FloatArray
    lifts: NDArray[np.bool_]
    held: NDArray[np.bool_]
    angle: float
    stance_rate: float
    walker_name: str


#: Time (s) an impact-map point takes, about: building and checking its walker dominates.
IMPACT_MAP_SECONDS_PER_POINT = 2e-3

#: Memory (bytes) an impact-map point needs, an upper estimate: seven result arrays (56 B), its
#: CSV row (about 200 B of text) and the figure's image of it.
IMPACT_MAP_BYTES_PER_POINT = 512


def check_impact_map_memory(nx: int, ny: int) -> None:
    """Raise ``MemoryError`` if an ``nx`` x ``ny`` impact map would not fit in the available
    memory (:data:`IMPACT_MAP_BYTES_PER_POINT` a point); :func:`impact_map` checks it first."""
    require_budget(f"a {nx}x{ny} impact map", nx * ny,
                   bytes_per_point=IMPACT_MAP_BYTES_PER_POINT,
                   seconds_per_point=IMPACT_MAP_SECONDS_PER_POINT,
                   hint="give fewer --x or --y values (COUNT)")


def impact_map(
    walker: BuiltWalker,
    x: tuple[str, Sequence[float] | FloatArray],
    y: tuple[str, Sequence[float] | FloatArray],
    *,
    angle: float = 0.3,
    stance_rate: float = 1.0,
    progress: bool = False,
) -> ImpactMap:
    """Map ``T_c``, ``T_a``, ``eta`` at heel strike over two swept quantities.

    Each grid point is one walker (about 2 ms to build and check,
    :data:`IMPACT_MAP_SECONDS_PER_POINT`) and one complementarity heel strike: a 100 x 100
    map takes about 20 s. A grid whose arrays, file and figure would not fit in the available
    memory (:data:`IMPACT_MAP_BYTES_PER_POINT` a point) is refused before any computing.

    Parameters
    ----------
    walker : BuiltWalker
        Base walker (its parameter values are used for everything not swept).
    x, y : (name, values)
        A description parameter name or :data:`ANGLE` and its values (SI units, rad).
    angle : float
        Impact angle (rad) when :data:`ANGLE` is not swept.
    stance_rate : float
        Pre-impact stance-leg rate (rad/s), the paper's ``q3_dot = 1``.
    progress : bool
        Show a progress bar over the rows (on stderr, after 2 s).

    Returns
    -------
    ImpactMap

    Raises
    ------
    ValueError
        Unknown parameter name, or the same quantity on both axes.
    MemoryError
        The grid would not fit in the available memory.
    """
    (xn, xv), (yn, yv) = x, y
    if xn == yn:
        raise ValueError(f"x and y must differ, both are {xn!r}")
    for name in (xn, yn):
        if name != ANGLE and name not in walker.parameters:
            raise ValueError(
                f"unknown parameter {name!r}; known: {sorted(walker.parameters)} or {ANGLE!r}"
            )
    xa, ya = np.asarray(xv, dtype=float), np.asarray(yv, dtype=float)
    shape = (ya.size, xa.size)
    check_impact_map_memory(xa.size, ya.size)
    # the section walker: replace() keeps it, so each point builds one walker, not two
    walker = PhasedWalker.from_built(walker)
    out = {k: np.full(shape, np.nan) for k in ("T", "T_c", "T_a", "eta", "L", "v")}
    lifts, held = np.zeros(shape, dtype=bool), np.zeros(shape, dtype=bool)
    for i, yy in _progress(list(enumerate(ya)), progress, "impact map"):
        for j, xx in enumerate(xa):
            vals = {xn: float(xx), yn: float(yy)}
            ang = vals.pop(ANGLE, angle)
            try:
                w = walker.replace(**vals) if vals else walker
                q, qd = symmetric_heel_strike_state(w, ang, stance_rate=stance_rate)
                hs = model_heel_strike(w, q, qd)
            except ValueError:
                continue
            out["T"][i, j], out["T_c"][i, j], out["T_a"][i, j] = hs.T, hs.T_c, hs.T_a
            out["eta"][i, j], out["L"][i, j] = hs.eta, hs.step_length
            out["v"][i, j] = hs.trailing_normal_velocity
            lifts[i, j], held[i, j] = hs.trailing_foot_lifts, hs.trailing_foot_held
    return ImpactMap(
        x_name=xn, y_name=yn, x=xa, y=ya, T=out["T"], T_c=out["T_c"], T_a=out["T_a"],
        eta=out["eta"], step_length=out["L"], trailing_normal_velocity=out["v"], lifts=lifts,
        held=held, angle=float(angle), stance_rate=float(stance_rate),
        walker_name=walker.description.name,
    )
