"""Gradient-based design of a walker: optimise a gait's field over named parameters.

:func:`design` minimises a cost of the passive gait of a described walker (a gait field such as
``collision_loss``, or an expression of the fields, e.g. ``"eta/speed"``) over named walker
parameters (geometry, masses, foot-profile coefficients) and the slope, within bounds and
subject to constraints (spectral radius at most a value, speed and step-length ranges, the
trailing foot lifting), with
:func:`scipy.optimize.minimize` (SLSQP) and the gradients of
:func:`~heelstrike.analysis.design_gradients.gait_gradients` (implicit function theorem on the
periodicity condition). The gait is followed by continuation as the parameters move: each new
point starts Newton from the last converged fixed point moved by the first-order prediction
``dz*/dp dp``; if Newton fails, the segment is walked in smaller steps.

Every evaluation is appended to a record (JSON lines); a run given an existing record replays
the evaluations it holds without simulating (SLSQP's iterates are deterministic), so an
interrupted design resumes where it stopped.

On a passive gait the energy books close: the collision loss per step equals the potential
energy released, ``M g L sin(slope)``, so ``eta = M g sin(slope)`` for every design and the
cost of transport is ``sin(slope)``. Minimising the loss *per step* at a given slope trades
step length; minimising ``eta`` is only meaningful with the slope (or the masses) among the
varied parameters (the docs page :doc:`/design` states the formulations).
"""

from __future__ import annotations

import enum
import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._results import ResultDictMixin
from heelstrike._typing import FloatArray
from heelstrike.analysis.design_gradients import (
    GRADIENT_FIELDS,
    GaitGradients,
    GradientError,
    gait_gradients,
)
from heelstrike.analysis.limit_cycle import GaitNotFoundError
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.models.builder import BuiltWalker

__all__ = [
    "DESIGN_FIELDS",
    "DESIGN_TOL",
    "DesignError",
    "DesignIterate",
    "DesignResult",
    "DesignStatus",
    "design",
    "foot_outline",
]

#: Names a cost expression may use: the gait fields and the spectral radius.
DESIGN_FIELDS = (*GRADIENT_FIELDS, "spectral_radius")

#: Default stopping tolerance: SLSQP's ``ftol`` on the cost divided by its start value (the
#: gradients are accurate to about 1e-8 relative).
DESIGN_TOL = 1e-7

#: The scaled cost SLSQP sees at a point without a gait (its line search steps back).
LOST_PENALTY = 1e3

#: Newton iterations allowed from a continuation prediction (it converges in 2-4 when the
#: gait is there).
CONTINUATION_NEWTON = 8

#: Continuation sub-steps tried when Newton fails from the first-order prediction.
CONTINUATION_SUBSTEPS = (2, 4)


class DesignError(ValueError):
    """Bad design input: an unknown parameter, empty or reversed bounds, a bad cost expression
    (the message names it)."""


class DesignStatus(enum.Enum):
    """How a design ended."""

    CONVERGED = "converged"
    MAX_ITERATIONS = "max_iterations"
    GAIT_LOST = "gait_lost"
    STALLED = "stalled"
    FAILED = "failed"

    @property
    def message(self) -> str:
        """One line saying what the status means."""
        return {
            "converged": "the optimiser's KKT conditions hold to its tolerance",
            "max_iterations": "stopped at the iteration limit before convergence",
            "gait_lost": "the gait could not be followed to a point the optimiser asked for "
                         "(the result is the last feasible iterate)",
            "stalled": "the line search found no descent from the last iterate: an optimum to "
                       "the gradients' accuracy (about 1e-8; 1e-4 for the spectral radius's), "
                       "or inconsistent gradients",
            "failed": "the optimiser stopped without convergence (its message says why)",
        }[self.value]


@dataclass(frozen=True, kw_only=True)
class DesignIterate(ResultDictMixin):
    """One evaluated design point.

    Attributes
    ----------
    values : ndarray, shape (k,)
        Parameter values (SI; slope in rad).
    cost : float
        The cost (units of its field or expression).
    gradient : ndarray, shape (k,)
        ``d cost / d p``.
    fields : dict of str to float
        The gait's :data:`DESIGN_FIELDS` (SI).
    fixed_point : ndarray, shape (d,)
        The gait's fixed point.
    """

    values: FloatArray
    cost: float
    gradient: FloatArray
    fields: dict[str, float]
    fixed_point: FloatArray


@dataclass(frozen=True, kw_only=True)
class DesignResult(ResultDictMixin):
    """The outcome of :func:`design`.

    Attributes
    ----------
    parameters : tuple of str
        The varied parameters.
    lower, upper : ndarray, shape (k,)
        Their bounds.
    cost_name : str
        The cost (a field name or an expression of the fields).
    start, final : DesignIterate
        The first and the last accepted design points.
    history : tuple of DesignIterate
        The accepted iterates, the start first.
    status : DesignStatus
    message : str
        The optimiser's own message.
    evaluations : int
        Design points evaluated (gait + sensitivities).
    replayed : int
        Of those, the ones read back from the record instead of simulated.
    active_bounds : tuple of str
        ``"name=lower"`` or ``"name=upper"`` for every parameter on a bound at the end
        (relative tolerance 1e-9).
    constraints : dict of str to float
        Each constraint's value at the end (``>= 0`` is satisfied).
    foot_start, foot_final : ndarray, shape (N, 2) or None
        The stance foot's sole in the leg frame (m, hip at the origin, the leg along ``-y``)
        at the start and at the end (:func:`foot_outline`); None if the walker has no hip.
    """

    parameters: tuple[str, ...]
    lower: FloatArray
    upper: FloatArray
    cost_name: str
    start: DesignIterate
    final: DesignIterate
    history: tuple[DesignIterate, ...]
    status: DesignStatus
    message: str
    evaluations: int
    replayed: int
    active_bounds: tuple[str, ...]
    constraints: dict[str, float]
    foot_start: FloatArray | None
    foot_final: FloatArray | None

    @property
    def cost_history(self) -> FloatArray:
        """The cost of each accepted iterate, shape (len(history),)."""
        return np.array([it.cost for it in self.history])


def foot_outline(walker: BuiltWalker, *, angles: ArrayLike | None = None) -> FloatArray | None:
    """The stance foot's sole in the leg frame, from the walker's own contact point.

    The contact point ``c(theta)`` and the hip ``h(theta)`` at stance-leg angles ``theta``
    (``q = (0, 0, theta, 0, ...)``), rotated back by ``-theta``: ``Rot(-theta) (c - h)``.

    Parameters
    ----------
    walker : BuiltWalker
    angles : array_like, optional
        Stance-leg angles (rad); default 121 angles over [-0.6, 0.6].

    Returns
    -------
    ndarray, shape (N, 2) or None
        Points (m), hip at the origin; None if the walker has no ``hip`` point.
    """
    th = np.linspace(-0.6, 0.6, 121) if angles is None else np.asarray(angles, dtype=float)
    pts = []
    n = len(walker.coordinate_names)
    for t in th:
        q = np.zeros(n)
        q[2] = t
        pos = walker.positions(q)
        if "hip" not in pos or "stance_foot.contact" not in pos:
            return None
        v = np.asarray(pos["stance_foot.contact"]) - np.asarray(pos["hip"])
        c, s = math.cos(t), math.sin(t)
        pts.append((c * v[0] + s * v[1], -s * v[0] + c * v[1]))
    return np.array(pts)


def _cost_function(cost: str) -> tuple[Callable[[Mapping[str, float]], float],
                                       dict[str, Callable[[Mapping[str, float]], float]]]:
    """The cost and its partial derivatives with respect to the fields it uses."""
    import sympy

    from heelstrike.models.description import ModelDescriptionError, evaluate_expression

    syms = {f: sympy.Symbol(f) for f in DESIGN_FIELDS}
    try:
        expr = sympy.sympify(evaluate_expression(
            cost, syms, funcs={"sqrt": sympy.sqrt, "sin": sympy.sin, "cos": sympy.cos},
            pi=sympy.pi, path="cost"))
    except ModelDescriptionError as exc:
        raise DesignError(f"cost {cost!r}: {exc} (fields: {', '.join(DESIGN_FIELDS)})") from None
    used = sorted(str(s) for s in expr.free_symbols)
    if not used:
        raise DesignError(f"cost {cost!r} uses no gait field ({', '.join(DESIGN_FIELDS)})")
    args = [syms[u] for u in used]
    f = sympy.lambdify(args, expr, "math")
    partial = {u: sympy.lambdify(args, sympy.diff(expr, syms[u]), "math") for u in used}

    def value(fields: Mapping[str, float]) -> float:
        return float(f(*(fields[u] for u in used)))

    def wrap(g: Callable[..., Any]) -> Callable[[Mapping[str, float]], float]:
        return lambda fields: float(g(*(fields[u] for u in used)))

    return value, {u: wrap(g) for u, g in partial.items()}


class _GaitLost(RuntimeError):
    pass


def _key(x: FloatArray) -> str:
    return json.dumps([float(v) for v in x])


def design(
    walker: BuiltWalker,
    *,
    vary: Mapping[str, tuple[float, float]],
    cost: str = "collision_loss",
    slope: float,
    guess: ArrayLike | None = None,
    max_spectral_radius: float | None = None,
    speed: tuple[float, float] | None = None,
    step_length: tuple[float, float] | None = None,
    trailing_foot_lifts: bool = False,
    max_iter: int = 50,
    tol: float = DESIGN_TOL,
    record: str | Path | None = None,
    progress: Callable[[DesignIterate], None] | None = None,
) -> DesignResult:
    """Minimise a cost of the passive gait over named parameters (SLSQP, IFT gradients).

    Parameters
    ----------
    walker : BuiltWalker
        A described walker; its parameter values are the start.
    vary : mapping of str to (float, float)
        Parameter name (a walker parameter or ``"slope"``) -> ``(lower, upper)`` bounds (SI).
    cost : str
        A field of :data:`DESIGN_FIELDS` or an expression of them (``+ - * / **``, ``sqrt``,
        ``sin``, ``cos``), e.g. ``"collision_loss"``, ``"eta/speed"``.
    slope : float
        Ground slope (rad) (the start value if ``"slope"`` is varied).
    guess : array_like, shape (d,), optional
        Fixed point to start Newton from (default: the gait search of
        :func:`~heelstrike.analysis.model_gaits.find_model_gait`).
    max_spectral_radius : float, optional
        Constraint ``spectral_radius <= max_spectral_radius``.
    speed, step_length : (float, float), optional
        Constraints ``lo <= speed <= hi`` (m/s), ``lo <= step_length <= hi`` (m).
    trailing_foot_lifts : bool
        Constraint: the trailing foot's normal velocity just after the heel strike is not
        negative (``lift_velocity >= 0``: the impact leaves it free to lift).
    max_iter : int
        SLSQP iterations.
    tol : float
        SLSQP's ``ftol`` on the cost divided by its start value (:data:`DESIGN_TOL`).
    record : path, optional
        JSON-lines file of the evaluations: read back first (replayed), appended to.
    progress : callable, optional
        Called with each accepted iterate.

    Returns
    -------
    DesignResult

    Raises
    ------
    DesignError
        For an unknown parameter, bounds not ``lo < hi`` or a start outside them, a bad cost.
    GaitNotFoundError
        If no gait is found at the start.
    """
    from scipy.optimize import minimize

    names = tuple(vary)
    if not names:
        raise DesignError("vary: no parameter to vary")
    known = set(walker.parameters)
    lo = np.empty(len(names))
    hi = np.empty(len(names))
    x0 = np.empty(len(names))
    for j, n in enumerate(names):
        if n != "slope" and n not in known:
            raise DesignError(f"vary: unknown parameter {n!r} (the walker has "
                              f"{', '.join(sorted(known))}, and 'slope')")
        a, b = map(float, vary[n])
        if not (np.isfinite(a) and np.isfinite(b) and a < b):
            raise DesignError(f"vary: {n}={a:g}:{b:g} must have finite lower < upper")
        lo[j], hi[j] = a, b
        x0[j] = float(slope) if n == "slope" else float(np.asarray(walker.parameters[n]))
        if not a <= x0[j] <= b:
            raise DesignError(f"vary: the start {n} = {x0[j]:g} is outside [{a:g}, {b:g}]")
    value, partial = _cost_function(cost)
    use_rho = max_spectral_radius is not None or "spectral_radius" in partial
    use_lift = trailing_foot_lifts or "lift_velocity" in partial

    problem = json.dumps({
        "walker": walker.description.name,
        "parameters": {k: float(np.asarray(v)) for k, v in sorted(walker.parameters.items())},
        "vary": {n: [float(lo[j]), float(hi[j])] for j, n in enumerate(names)},
        "cost": cost, "slope": float(slope), "spectral_radius": use_rho}, sort_keys=True)
    cache: dict[str, dict[str, Any]] = {}
    path = None if record is None else Path(record)
    if path is not None and path.exists():
        for line in path.read_text(encoding="utf-8").splitlines():
            try:
                entry = json.loads(line)
            except json.JSONDecodeError:
                continue  # a line cut by an interruption
            if isinstance(entry, dict) and entry.get("problem") == problem:
                cache[_key(np.array(entry["values"]))] = entry
    counts = {"simulated": 0, "replayed": 0}
    state: dict[str, Any] = {"x": None, "z": None, "dz": None}

    def params_of(x: FloatArray) -> tuple[BuiltWalker, float]:
        vals = {n: float(v) for n, v in zip(names, x, strict=True)}
        sl = vals.pop("slope", float(slope))
        return (walker.replace(**vals) if vals else walker), sl

    def gait_at(x: FloatArray) -> FloatArray:
        w, sl = params_of(x)
        if state["x"] is None:
            return np.asarray(find_model_gait(w, slope=sl, guess=guess, backend="scipy")
                              .fixed_point, dtype=float)
        xp, zp, dzp = state["x"], state["z"], state["dz"]
        try:
            return np.asarray(find_model_gait(w, slope=sl, guess=zp + dzp @ (x - xp),
                                              backend="scipy", max_iter=CONTINUATION_NEWTON)
                              .fixed_point, dtype=float)
        except GaitNotFoundError:
            pass
        for m in CONTINUATION_SUBSTEPS:
            z = zp
            try:
                for i in range(1, m + 1):
                    xi = xp + (x - xp) * i / m
                    wi, si = params_of(xi)
                    z = np.asarray(find_model_gait(
                        wi, slope=si, guess=z + dzp @ ((x - xp) / m), backend="scipy",
                        max_iter=CONTINUATION_NEWTON)
                        .fixed_point, dtype=float)
                return z
            except GaitNotFoundError:
                continue
        raise _GaitLost(f"no gait at {dict(zip(names, map(float, x), strict=True))}")

    def evaluate(x: FloatArray) -> dict[str, Any]:
        k = _key(x)
        if k in cache:
            entry = cache[k]
            if not entry.get("_counted"):
                counts["replayed"] += 1
                entry["_counted"] = True
        else:
            try:
                z = gait_at(x)
                w, sl = params_of(x)
                s: GaitGradients = gait_gradients(w, z, names, slope=sl,
                                                  spectral_radius=use_rho, lift=use_lift)
            except (_GaitLost, GaitNotFoundError, GradientError, ValueError) as exc:
                if state["x"] is None:
                    raise
                # no gait here: a penalty the optimiser's line search steps back from
                lost = {"problem": problem, "values": [float(v) for v in x], "lost": str(exc)}
                cache[k] = dict(lost, _counted=True)
                counts["simulated"] += 1
                if path is not None:
                    with path.open("a", encoding="utf-8") as fh:
                        fh.write(json.dumps(lost) + "\n")
                return lost
            grad = np.zeros(len(names))
            for f, df in partial.items():
                grad += df(s.fields) * s.derivatives[f]
            counts["simulated"] += 1
            entry = {"problem": problem, "values": [float(v) for v in x],
                     "fixed_point": s.fixed_point.tolist(),
                     "fields": s.fields, "cost": value(s.fields), "gradient": grad.tolist(),
                     "derivatives": {f: v.tolist() for f, v in s.derivatives.items()},
                     "dz": s.fixed_point_derivative.tolist()}
            cache[k] = dict(entry, _counted=True)
            if path is not None:
                with path.open("a", encoding="utf-8") as fh:
                    fh.write(json.dumps(entry) + "\n")
        if "lost" in entry:
            return entry
        state["x"], state["z"] = np.array(x, dtype=float), np.array(entry["fixed_point"])
        state["dz"] = np.array(entry["dz"])
        return entry

    def iterate(entry: Mapping[str, Any]) -> DesignIterate:
        return DesignIterate(values=np.array(entry["values"]), cost=float(entry["cost"]),
                             gradient=np.array(entry["gradient"]), fields=dict(entry["fields"]),
                             fixed_point=np.array(entry["fixed_point"]))

    first = evaluate(x0)
    scale = abs(float(first["cost"])) or 1.0
    history = [iterate(first)]
    if progress is not None:
        progress(history[0])

    # SLSQP works on u = (x - lower) / (upper - lower) in [0, 1]: its first quasi-Newton step
    # (identity Hessian) is then a fraction of the box, not a jump to a corner
    width = hi - lo

    def phys(u: FloatArray) -> FloatArray:
        return np.clip(lo + np.asarray(u, dtype=float) * width, lo, hi)

    def fun(u: FloatArray) -> float:
        e = evaluate(phys(u))
        return LOST_PENALTY if "lost" in e else float(e["cost"]) / scale

    def jac(u: FloatArray) -> FloatArray:
        e = evaluate(phys(u))
        return np.zeros(len(names)) if "lost" in e else np.array(e["gradient"]) * width / scale

    def field_con(field: str, sign: float, bound: float) -> dict[str, Any]:
        ref = abs(bound) if bound else 1.0

        def con(u: FloatArray) -> float:
            e = evaluate(phys(u))
            return -1.0 if "lost" in e else sign * (e["fields"][field] - bound) / ref

        def con_jac(u: FloatArray) -> FloatArray:
            e = evaluate(phys(u))
            return np.zeros(len(names)) if "lost" in e else \
                sign * np.array(e["derivatives"][field]) * width / ref

        return {"type": "ineq", "fun": con, "jac": con_jac}

    cons: list[dict[str, Any]] = []
    labels: list[tuple[str, str, float, float]] = []
    if max_spectral_radius is not None:
        labels.append(("spectral_radius <= max", "spectral_radius", -1.0,
                       float(max_spectral_radius)))
    if trailing_foot_lifts:
        labels.append(("trailing foot lifts", "lift_velocity", 1.0, 0.0))
    for field, rng in (("speed", speed), ("step_length", step_length)):
        if rng is not None:
            a, b = map(float, rng)
            if not a < b:
                raise DesignError(f"{field}: range {a:g}:{b:g} must have lower < upper")
            labels += [(f"{field} >= lower", field, 1.0, a), (f"{field} <= upper", field, -1.0, b)]
    cons = [field_con(f, s, b) for _, f, s, b in labels]

    def callback(uk: FloatArray) -> None:
        e = evaluate(phys(uk))
        if "lost" in e:
            return
        it = iterate(e)
        history.append(it)
        if progress is not None:
            progress(it)

    status = DesignStatus.FAILED
    message = ""
    try:
        solver: Any = minimize
        res = solver(fun, (x0 - lo) / width, jac=jac, method="SLSQP",
                     bounds=[(0.0, 1.0)] * len(names),
                     constraints=cons, callback=callback,
                     options={"maxiter": int(max_iter), "ftol": float(tol)})
        message = str(res.message)
        if res.success:
            status = DesignStatus.CONVERGED
        elif res.status == 9:
            status = DesignStatus.MAX_ITERATIONS
        elif res.status == 8:  # "Positive directional derivative for linesearch"
            status = DesignStatus.STALLED
        final_entry = evaluate(phys(res.x))
        if "lost" in final_entry:
            status, message = DesignStatus.GAIT_LOST, str(final_entry["lost"])
            final = history[-1]
        else:
            final = iterate(final_entry)
            if not np.array_equal(final.values, history[-1].values):
                history.append(final)
    except _GaitLost as exc:
        status, message = DesignStatus.GAIT_LOST, str(exc)
        final = history[-1]
    active = tuple(
        f"{n}=lower" if math.isclose(v, a, rel_tol=1e-9, abs_tol=1e-12) else f"{n}=upper"
        for n, v, a, b in zip(names, final.values, lo, hi, strict=True)
        if math.isclose(v, a, rel_tol=1e-9, abs_tol=1e-12)
        or math.isclose(v, b, rel_tol=1e-9, abs_tol=1e-12))
    constraints = {lab: s * (final.fields[f] - b) for lab, f, s, b in labels}
    w_start, _ = params_of(x0)
    w_final, _ = params_of(final.values)
    return DesignResult(
        parameters=names, lower=lo, upper=hi, cost_name=cost, start=history[0], final=final,
        history=tuple(history), status=status, message=message,
        evaluations=counts["simulated"] + counts["replayed"], replayed=counts["replayed"],
        active_bounds=active, constraints=constraints,
        foot_start=foot_outline(w_start), foot_final=foot_outline(w_final))

