"""One simulation entry point for every walker, with pluggable backends.

(The module is named ``backends`` so that it does not shadow the function
``heelstrike.dynamics.simulate``, which is :func:`simulate` here.)

:func:`simulate` is the walk of any :class:`~heelstrike.models.base.PlanarWalker`; the
``backend`` argument picks the implementation as scipy's ``solve_ivp(method=...)`` or PyDy's
``generator=`` do. Which implementations exist is the registry :data:`BACKENDS`, keyed by the
walker's *kernel kind* (:func:`kernel_kind`, read from the walker contract: its
:attr:`~heelstrike.models.base.PlanarWalker.description` and
:attr:`~heelstrike.models.base.PlanarWalker.compiled_kernel`, never its class) and the backend
name:

============  ==========  =================================================================
kind          backend     implementation
============  ==========  =================================================================
``planar``    ``scipy``   :func:`heelstrike.dynamics.hybrid.simulate` (any hand-written walker)
``compass``   ``scipy``   :func:`heelstrike.dynamics.hybrid.simulate`
``compass``   compiled    :func:`heelstrike.dynamics.compiled.simulate_compiled` (passive;
                          hip laws, push-off, friction, dense samples: the generated kernel
                          of :meth:`~heelstrike.models.base.PlanarWalker.as_described`)
described     ``scipy``   :func:`heelstrike.dynamics.hybrid.simulate`
described     compiled    :func:`heelstrike.dynamics.compiled_phased.simulate_phased_compiled`
============  ==========  =================================================================

The scipy backend is one loop for every walker: it runs the hybrid schedule the walker declares
(:meth:`~heelstrike.models.base.PlanarWalker.step_schedule`). The implementations are imported
when first used (numba and scipy.integrate stay unloaded until a walk needs them). Results are
:class:`~heelstrike.dynamics.hybrid.PhasedWalkResult` (scipy; every impact in ``events``) or
its base :class:`~heelstrike.dynamics.hybrid.WalkResult` (the compiled compass kernel).
"""

from __future__ import annotations

import importlib
import math
import numbers
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from heelstrike.dynamics.hybrid import WalkResult
from heelstrike.models.base import PlanarWalker

__all__ = [
    "BACKENDS",
    "BackendEntry",
    "BoundSimulator",
    "KernelKind",
    "backend_entry",
    "check_backend",
    "check_one_walker",
    "check_slope",
    "check_tolerances",
    "check_walk_arguments",
    "kernel_kind",
    "simulate",
    "simulator",
]

#: What simulates a walker: ``"planar"`` (a hand-written walker without a compiled kernel),
#: ``"compass"`` (the compass-gait kernel of :mod:`heelstrike.dynamics.compiled`) or
#: ``"described"`` (a walker built from a description; generated kernel).
KernelKind = Literal["planar", "compass", "described"]


@dataclass(frozen=True, kw_only=True)
class BackendEntry:
    """One implementation of the registry: where it lives, imported on first use.

    Attributes
    ----------
    module, function : str
        The simulator ``module.function`` (``simulate``'s arguments, returns a ``WalkResult``).
    check : callable or None
        ``check(walker, torque, push_off, friction, options)`` raises ``ValueError`` for
        actuation the implementation cannot run; None: it runs any.
    """

    module: str
    function: str
    check: Callable[[PlanarWalker, Any, Any, float | None, Mapping[str, Any]], None] | None = None

    def load(self) -> Callable[..., WalkResult]:
        """The simulator function (imports its module)."""
        fn: Callable[..., WalkResult] = getattr(importlib.import_module(self.module), self.function)
        return fn

    def check_actuation(
        self,
        walker: PlanarWalker,
        torque: Any,
        push_off: Any,
        friction: float | None,
        options: Mapping[str, Any],
    ) -> None:
        """Raise ``ValueError`` if the implementation cannot run this actuation."""
        if self.check is not None:
            self.check(walker, torque, push_off, friction, options)


def _check_compass_compiled(
    walker: PlanarWalker, torque: Any, push_off: Any, friction: float | None,
    options: Mapping[str, Any],
) -> None:
    from heelstrike.dynamics.compiled import check_compiled_compass

    check_compiled_compass(torque, push_off, friction, options.get("restitution", 0.0),
                           walker=walker, max_step=options.get("max_step", float("inf")))


def _check_described_compiled(
    walker: PlanarWalker, torque: Any, push_off: Any, friction: float | None,
    options: Mapping[str, Any],
) -> None:
    from heelstrike.dynamics.compiled_phased import check_compiled_actuation

    check_compiled_actuation(walker, torque, push_off)  # type: ignore[arg-type]


#: The backend registry: ``(kernel kind, backend name) -> implementation`` (scipy's ``METHODS``
#: idea). A combination missing here is not supported.
BACKENDS: Mapping[tuple[KernelKind, str], BackendEntry] = MappingProxyType(
    {
        ("planar", "scipy"): BackendEntry(module="heelstrike.dynamics.hybrid",
                                          function="simulate"),
        ("compass", "scipy"): BackendEntry(module="heelstrike.dynamics.hybrid",
                                           function="simulate"),
        ("compass", "compiled"): BackendEntry(
            module="heelstrike.dynamics.compiled",
            function="simulate_compiled",
            check=_check_compass_compiled,
        ),
        ("described", "scipy"): BackendEntry(module="heelstrike.dynamics.hybrid",
                                             function="simulate"),
        ("described", "compiled"): BackendEntry(
            module="heelstrike.dynamics.compiled_phased",
            function="simulate_phased_compiled",
            check=_check_described_compiled,
        ),
    }
)


def kernel_kind(walker: PlanarWalker) -> KernelKind:
    """The walker's kernel kind, from its contract (:data:`KernelKind`).

    A walker with a :attr:`~heelstrike.models.base.PlanarWalker.description` is
    ``"described"``; otherwise its :attr:`~heelstrike.models.base.PlanarWalker.compiled_kernel`
    decides (``"compass"``, or ``"planar"`` for none).

    Raises
    ------
    ValueError
        If the walker declares the generated kernel but no description.
    """
    if walker.description is not None:
        return "described"
    kernel = walker.compiled_kernel
    if kernel is None:
        return "planar"
    if kernel == "compass":
        return "compass"
    raise ValueError(
        f"{type(walker).__name__} declares the {kernel!r} compiled kernel but no description"
    )


def backend_entry(walker: PlanarWalker, backend: str) -> BackendEntry:
    """The registry entry that simulates ``walker`` on ``backend``.

    Raises
    ------
    ValueError
        Unknown backend, or one the walker does not declare
        (:attr:`~heelstrike.models.base.PlanarWalker.backends`)
        or the registry does not implement for its kernel kind; the message names the walker's
        backends.
    """
    declared = tuple(walker.backends)
    entry = BACKENDS.get((kernel_kind(walker), backend))
    if not walker.supports(backend) or entry is None:
        known = sorted({name for _, name in BACKENDS})
        what = "unknown backend" if backend not in known else "unsupported backend"
        raise ValueError(
            f"{what} {backend!r} for this {type(walker).__name__}: it runs on "
            f"{', '.join(repr(b) for b in declared)} (walker.backends)"
        )
    return entry


def check_backend(
    walker: PlanarWalker,
    backend: str,
    *,
    torque: Any = None,
    push_off: Any = None,
    friction: float | None = None,
    **options: Any,
) -> None:
    """Raise ``ValueError`` unless ``simulate(walker, ..., backend=backend)`` can run this
    actuation (e.g. the compiled backends evaluate a fixed set of laws in the kernel).

    Parameters are those of :func:`simulate`; ``options`` are its extra keyword options.
    """
    backend_entry(walker, backend).check_actuation(walker, torque, push_off, friction, options)


def check_one_walker(walker: PlanarWalker) -> None:
    """Refuse a batch of walkers (array parameters) where one walker is walked.

    Raises
    ------
    ValueError
        Naming the parameters' shape (QA sweep 12: numpy's broadcasting errors, deep inside).
    """
    if walker.is_batched:
        raise ValueError(
            f"one walker is walked at a time, and this one has array parameters (a batch of "
            f"shape {walker.parameter_shape}): walk its members one by one "
            "(walker.replace(name=value) for each value)")


def check_slope(slope: Any) -> float:
    """``slope`` (rad) as a float: one finite number, else a ValueError naming it."""
    if isinstance(slope, (str, bytes, bool, np.bool_)) or np.ndim(slope) != 0:
        raise ValueError(f"slope must be one number (rad), got {slope!r}")
    try:
        value = float(slope)
    except (TypeError, ValueError):
        raise ValueError(f"slope must be one number (rad), got {slope!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"slope must be finite (rad), got {value!r}")
    return value


def check_walk_arguments(
    walker: PlanarWalker, *, slope: Any, steps: Any, friction: Any, rtol: Any, atol: Any
) -> None:
    """The checks :func:`simulate` makes before running any backend: one walker, one finite
    slope below 90 degrees, a whole number of steps >= 1, a friction coefficient >= 0 (or
    None), positive finite tolerances (QA sweep 12: a NaN slope hung the compiled backend,
    ``atol=0`` hung scipy's first step, ``rtol=-1`` was taken).

    Raises
    ------
    ValueError
        The first argument that fails, named.
    """
    check_one_walker(walker)
    s = check_slope(slope)
    if not abs(s) < math.pi / 2:  # a bare 3 meant as degrees is 172 deg
        raise ValueError(f"slope {s:g} rad is {math.degrees(s):g} deg, no incline to walk on "
                         "(slopes are in radians, |slope| < pi/2)")
    if isinstance(steps, bool) or not isinstance(steps, numbers.Integral) or steps < 1:
        raise ValueError(f"steps must be >= 1 (a whole number), got {steps!r}")
    if friction is not None and not float(friction) >= 0.0:
        raise ValueError(f"friction must be a coefficient >= 0 (or None: no limit), got "
                         f"{friction!r}")
    check_tolerances(rtol, atol)


def check_tolerances(rtol: Any, atol: Any) -> None:
    """Refuse integrator tolerances that are not finite and > 0, naming the first."""
    for name, tol in (("rtol", rtol), ("atol", atol)):
        if isinstance(tol, bool) or not (math.isfinite(float(tol)) and float(tol) > 0.0):
            raise ValueError(f"{name} must be a finite tolerance > 0, got {tol!r}")


def simulate(
    walker: PlanarWalker,
    q0: ArrayLike,
    q_dot0: ArrayLike,
    *,
    backend: str = "scipy",
    slope: float = 0.0,
    steps: int = 1,
    torque: Any = None,
    push_off: Any = None,
    friction: float | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    **options: Any,
) -> WalkResult:
    """Simulate any walker for a number of steps on a chosen backend.

    Parameters
    ----------
    walker : PlanarWalker
        The walker; :attr:`~heelstrike.models.base.PlanarWalker.backends` lists where it runs.
    q0, q_dot0 : array_like, shape (n,)
        Initial state: stance foot on the ground and rolling (for described walkers, just after
        a heel strike with the lockable joints locked).
    backend : {"scipy", "compiled"}
        ``"scipy"``: the reference (DOP853, any walker, any actuation); ``"compiled"``: numba
        (the compass kernel or the kernel generated from the walker's description).
    slope : float
        Ground slope (rad), downhill towards ``-x``.
    steps : int
        Number of heel strikes to simulate.
    torque : callable, optional
        Actuator law ``(t since step start, q, q_dot) -> u`` (N m); the compiled backends take
        :class:`~heelstrike.dynamics.phased.TorsoPD` (a walker with a torso joint) and the hip
        laws :class:`~heelstrike.dynamics.actuation.SwingLegPD` (constant set point) and
        :class:`~heelstrike.dynamics.actuation.EnergyTracking` (the compass gait and its
        description), see
        :func:`~heelstrike.dynamics.compiled_phased.check_compiled_actuation`.
    push_off : callable, optional
        Impulsive actuation just before each heel strike: a
        :data:`~heelstrike.dynamics.hybrid.PushOff` callable (scipy), or the
        :class:`~heelstrike.dynamics.actuation.PushOff` impulse (every backend of a described
        walker).
    friction : float, optional
        Coulomb coefficient of the stance foot; more needed ends the walk (``slipped``).
    rtol, atol : float
        Integrator tolerances.
    **options
        Passed to the implementation (e.g. ``max_step_duration``, ``max_step``,
        ``restitution``, ``knee_flex_threshold``; see :data:`BACKENDS`).

    Returns
    -------
    WalkResult
        :class:`~heelstrike.dynamics.phased.PhasedWalkResult` for described walkers.

    Raises
    ------
    ValueError
        Unknown or unsupported backend (the message names ``walker.backends``), actuation the
        backend cannot run, an argument :func:`check_walk_arguments` refuses, or an invalid
        initial state.
    """
    check_walk_arguments(walker, slope=slope, steps=steps, friction=friction, rtol=rtol,
                         atol=atol)
    entry = backend_entry(walker, backend)
    entry.check_actuation(walker, torque, push_off, friction, options)
    return entry.load()(
        walker, q0, q_dot0, slope=slope, steps=steps, torque=torque, push_off=push_off,
        friction=friction, rtol=rtol, atol=atol, **options,
    )


@dataclass(frozen=True, kw_only=True)
class BoundSimulator:
    """:func:`simulate` bound to a backend: call it with :func:`simulate`'s arguments.

    Attributes
    ----------
    backend : str
        The backend every call runs on; code that can batch many walks on that backend (e.g.
        :meth:`heelstrike.analysis.limit_cycle.PoincareMap.many`) reads it.
    """

    backend: str

    def __call__(self, walker: PlanarWalker, q0: ArrayLike, q_dot0: ArrayLike,
                 **kwargs: Any) -> WalkResult:
        return simulate(walker, q0, q_dot0, backend=self.backend, **kwargs)


def simulator(
    walker: PlanarWalker,
    backend: str,
    *,
    torque: Any = None,
    push_off: Any = None,
    friction: float | None = None,
    **options: Any,
) -> BoundSimulator:
    """:func:`simulate` bound to a backend, checked up front for this walker and actuation.

    For code that takes a step simulator with :func:`simulate`'s signature (e.g.
    ``PoincareMap(simulator=...)``). ``torque``/``push_off``/``friction``/``options`` are only
    checked (:func:`check_backend`), not bound: pass them to the returned function's calls.

    Raises
    ------
    ValueError
        As :func:`check_backend`.
    """
    check_backend(walker, backend, torque=torque, push_off=push_off, friction=friction,
                  **options)
    return BoundSimulator(backend=backend)
