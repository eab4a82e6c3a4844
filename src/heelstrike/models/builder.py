"""Build a :class:`~heelstrike.models.base.PlanarWalker` from a description.

A new walker is a description (:mod:`heelstrike.models.description`, TOML or dataclasses), not a
derivation: :func:`build` derives the equations of motion with sympy, generates batched numpy
source (``sympy.cse``), caches it on disk and returns the compiled functions; :class:`BuiltWalker`
wraps them with parameter values. Parameters stay symbolic in the generated code, so changing a
value (``load_walker("compass", R=0.3)``) never re-derives anything.

Disk cache
----------
Generated modules live in ``$HEELSTRIKE_CACHE_DIR`` (default ``$XDG_CACHE_HOME/heelstrike`` or
``~/.cache/heelstrike``) under ``models/<sha256>.py``, keyed by the description's structure
(everything except parameter values), the package version, :data:`CODEGEN_VERSION` and a hash
of the generator's own source. A cache hit needs neither sympy nor any derivation.

The cache holds data, not trusted code (:mod:`heelstrike.models._generated`): a cached module
is used only if it and its folder belong to the current user and nobody else can write them,
and only after its syntax tree has been checked against what the generator emits; it then runs
with no builtins. An entry failing either check is rebuilt, with a :class:`CacheWarning`.

Knee locks
----------
Joints declared ``lockable`` (e.g. knees) are listed by :attr:`BuiltWalker.lockable_joints`
(coordinate indices, all ``>= 3``) with their lock angles :attr:`BuiltWalker.lock_angles`.
A lock is the holonomic constraint ``q[j] = lock_angle``; its Jacobian (constant rows ``e_j``)
is :meth:`BuiltWalker.lock_jacobian`. A knee strike is an inert impact with ``A`` = that row
(:func:`heelstrike.core.impact`); a locked phase is simulated by removing ``j`` from the free
coordinates (``SingleSupport(locked=(j, ...))``).
"""

from __future__ import annotations

import contextvars
import functools
import hashlib
import importlib.resources
import os
import warnings
from abc import ABCMeta
from collections.abc import Callable, Mapping
from dataclasses import FrozenInstanceError, dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from heelstrike._typing import FloatArray
from heelstrike._version import __version__
from heelstrike.models._contact import CONTACT_TOLERANCE
from heelstrike.models._generated import (
    CacheWarning,
    IdentityCache,
    UnsafeGeneratedCode,
    cache_dir,
    generator_fingerprint,
    load_source,
    read_cached,
    write_cached,
)
from heelstrike.models.base import (
    CompiledKernel,
    Foot,
    ParameterValue,
    PlanarWalker,
    WalkerScale,
)
from heelstrike.models.description import (
    ModelDescriptionError,
    WalkerDescription,
    evaluate_expression,
    read_description,
    rolling_radius,
)
from heelstrike.models.schedule import (
    Guard,
    Phase,
    Stage,
    StepSchedule,
    TrailingFootRule,
    fell_forward,
)

__all__ = [
    "CODEGEN_VERSION",
    "BuiltWalker",
    "CacheWarning",
    "GeneratedModel",
    "build",
    "cache_dir",
    "load_walker",
    "shipped_walkers",
    "walker_description",
]

#: Bumped whenever the generated code changes meaning; part of the cache key.
CODEGEN_VERSION = "3"

#: Functions a generated walker module may define.
GENERATED_FUNCTIONS = frozenset(
    {
        "mass_matrix",
        "bias_forces",
        "dynamics_terms",
        "potential_energy",
        "points",
        "swap_coordinates",
        "swap_jacobian",
        "heel_strike_guard",
        *(
            f"{kind}_{foot}"
            for kind in ("contact_jacobian", "contact_jacobian_rate", "foot_centre")
            for foot in ("stance", "swing")
        ),
    }
)


def _lead(q: Any, *args: Any) -> tuple[int, ...]:
    """Broadcast leading shape of a state batch ``q`` (..., n) and parameter arrays."""
    lead: tuple[int, ...] = np.shape(q)[:-1]
    # scalars (Python floats, the usual parameter values) never change the shape: skip them,
    # numpy.broadcast_shapes costs ~1 us per argument
    shapes = [s for a in args if type(a) is not float and (s := np.shape(a))]
    return np.broadcast_shapes(lead, *shapes) if shapes else lead


#: What generated walker modules may use by name (the only names their source does not define).
_HELPERS: Mapping[str, Any] = MappingProxyType({"numpy": np, "zeros": np.zeros, "_lead": _lead})

_MEMORY: dict[str, GeneratedModel] = {}

#: Set while a walker builds the walker after its leg swap: that one's swap is the inverse of
#: the one being checked, so it is not checked again (no endless pair of constructions).
_BUILDING_AFTER_SWAP: contextvars.ContextVar[bool] = contextvars.ContextVar(
    "heelstrike_building_after_swap", default=False)


@dataclass(frozen=True, kw_only=True, eq=False)
class GeneratedModel:
    """The compiled functions of one walker structure.

    Attributes
    ----------
    key : str
        sha256 cache key.
    source : str
        Generated Python source.
    namespace : mapping
        The module's globals (functions ``mass_matrix``, ``bias_forces``, ...).
    path : Path or None
        Cache file the source was read from or written to.
    from_cache : bool
        True if the source came from the disk cache (no sympy derivation).
    """

    key: str
    source: str
    namespace: Mapping[str, Any]
    path: Path | None
    from_cache: bool

    def fn(self, name: str) -> Callable[..., Any]:
        """A generated function by name."""
        f = self.namespace[name]
        assert callable(f)
        return f


def _compute_key(desc: WalkerDescription) -> str:
    text = "\n".join(
        (
            CODEGEN_VERSION,
            __version__,
            generator_fingerprint("_codegen", "description"),
            desc.structure_key(),
        )
    )
    return hashlib.sha256(text.encode()).hexdigest()


#: The cache key of a walker structure's generated numpy code, once a process per description.
_key = IdentityCache(_compute_key)


def _compile(source: str, path: Path | str) -> dict[str, Any]:
    """Verify generated source and run it with no builtins (see the module docstring)."""
    return load_source(source, str(path), helpers=_HELPERS, functions=GENERATED_FUNCTIONS)


def derivation_size(desc: WalkerDescription) -> float:
    """The size of a walker's derivation for its first-use estimate: ``coordinates**3 * bodies``
    (:mod:`heelstrike._firstuse`; sympy's work grows with the mass matrix's entries times the
    terms each body adds to them)."""
    n = 2 + len(desc.links)
    return float(n**3 * (len(desc.links) + len(desc.point_masses)))


def build(desc: WalkerDescription, *, use_cache: bool = True) -> GeneratedModel:
    """Derive (or fetch from the caches) the numeric functions of a walker structure.

    Parameters
    ----------
    desc : WalkerDescription
        The walker.
    use_cache : bool
        Read and write the in-process and disk caches (default True).

    Returns
    -------
    GeneratedModel
    """
    key = _key(desc)
    if use_cache and key in _MEMORY:
        return _MEMORY[key]
    path = cache_dir() / "models" / f"{key}.py"
    cached = read_cached(path) if use_cache else None
    if cached is not None:
        try:
            ns = _compile(cached, path)
            _check_generated(ns, desc)
        except (UnsafeGeneratedCode, ModelDescriptionError) as exc:
            warnings.warn(
                f"heelstrike: cached model code {path} failed verification ({exc}); "
                "rebuilding it",
                CacheWarning,
                stacklevel=2,
            )
        else:
            model = GeneratedModel(
                key=key, source=cached, namespace=MappingProxyType(ns), path=path, from_cache=True
            )
            _MEMORY[key] = model
            return model
    from heelstrike._firstuse import first_use

    with first_use(f"the {desc.name!r} walker's equations of motion derived with sympy, numpy "
                   "code generated", kind="derive-numpy", size=derivation_size(desc),
                   cache=path.parent, built=path.name, stages=2) as b:
        b.stage("deriving and generating (sympy)")
        from heelstrike.models._codegen import generate_source  # sympy only on a miss

        source = generate_source(desc, key)
        b.stage("checking and loading the generated code")
        ns = _compile(source, path)
        _check_generated(ns, desc)
        written = write_cached(path, source) if use_cache else None
    model = GeneratedModel(
        key=key, source=source, namespace=MappingProxyType(ns), path=written, from_cache=False
    )
    if use_cache:
        _MEMORY[key] = model
    return model


def _check_generated(ns: Mapping[str, Any], desc: WalkerDescription) -> None:
    """The sizes a generated module declares must be those of the description."""
    expected = {
        "N": 2 + len(desc.links),
        "N_PARAMS": len(desc.param_names),
        "N_POINTS": len(desc.point_names),
    }
    for name, value in expected.items():
        if ns.get(name) != value:
            raise ModelDescriptionError(f"generated module declares {name}={ns.get(name)!r}")
    required = GENERATED_FUNCTIONS - {"swap_coordinates", "swap_jacobian", "heel_strike_guard"}
    if desc.events is not None:
        required = required | {"heel_strike_guard"}
    missing = sorted(required - set(ns))
    if missing:
        raise ModelDescriptionError(f"generated module lacks {missing}")


def _arr(x: ArrayLike, n: int, name: str) -> FloatArray:
    a = np.asarray(x, dtype=float)
    if a.ndim < 1 or a.shape[-1] != n:
        raise ValueError(f"{name} must have shape (..., {n}), got {a.shape}")
    return a


def _read_only(a: FloatArray) -> FloatArray:
    """``a`` made read-only (a cached property of a frozen walker must not be changed)."""
    a.setflags(write=False)
    return a


def _first(a: FloatArray) -> FloatArray:
    """View of a state batch (..., n) with the coordinate axis first, shape (n, ...)."""
    return a if a.ndim == 1 else a.transpose(a.ndim - 1, *range(a.ndim - 1))


def _sparse_null_basis(basis: FloatArray) -> list[FloatArray]:
    """A basis of the span of the columns of ``basis`` (n, k) in reduced row-echelon form,
    pivoting on the last coordinates first (the joints before ``x``, ``y``): a joint that moves
    nothing alone comes out as a unit vector, a combined motion with its pivot scaled to 1.
    Entries below 1e-12 are set to zero."""
    B = np.array(basis, dtype=float).T.copy()  # (k, n)
    k, n = B.shape
    rows: list[int] = []
    for col in range(n - 1, -1, -1):
        free = [r for r in range(k) if r not in rows]
        if not free:
            break
        r = max(free, key=lambda i: abs(B[i, col]))
        if abs(B[r, col]) < 1e-9:
            continue
        B[r] /= B[r, col]
        for i in range(k):
            if i != r:
                B[i] -= B[i, col] * B[r]
        rows.append(r)
    B[np.abs(B) < 1e-12] = 0.0
    return [B[r] for r in rows]


class _FrozenAfterInit(ABCMeta):
    """Metaclass freezing an instance once its (sub)class ``__init__`` has returned."""

    def __call__(cls, *args: Any, **kwargs: Any) -> Any:
        obj = super().__call__(*args, **kwargs)
        object.__setattr__(obj, "_frozen", True)
        return obj


class BuiltWalker(PlanarWalker, metaclass=_FrozenAfterInit):
    """A walker whose equations were derived from a :class:`WalkerDescription`.

    Frozen like :class:`~heelstrike.models.CompassGait`: attributes cannot be set once the walker
    is constructed (:class:`dataclasses.FrozenInstanceError`); :meth:`replace` makes a new one.

    Parameters
    ----------
    description : WalkerDescription
        The walker.
    use_cache : bool
        Use the generated-code caches (default True).
    **params : float or array_like
        Parameter values overriding the description's defaults; arrays broadcast against the
        leading axes of states (e.g. a grid of foot radii).

    Notes
    -----
    Coordinates: ``q = (x, y, theta_root, joint angles...)`` (:attr:`coordinate_names`);
    ``x, y`` is the stance foot's arc centre (for a profile foot, the centre of its rolling
    disc: ``docs/walker_files.rst``). All methods broadcast over leading axes.
    """

    def __init__(
        self, description: WalkerDescription, *, use_cache: bool = True, **params: ArrayLike
    ) -> None:
        unknown = sorted(set(params) - set(description.param_names))
        if unknown:
            raise ModelDescriptionError(
                f"params.{unknown[0]}: unknown parameter (known: {list(description.param_names)})"
            )
        values: dict[str, Any] = description.default_params
        idle = sorted(k for k in set(params) & description.unused_params
                      if np.any(np.asarray(params[k], dtype=float) != values[k]))
        if idle:  # setting it would change nothing, and nothing would say so (QA sweep 12)
            raise ModelDescriptionError(
                f"params.{idle[0]}: walker {description.name!r} uses it nowhere (no link, "
                "foot, point mass or posture law), so setting it changes nothing")
        for k, v in params.items():
            a = np.asarray(v, dtype=float)
            values[k] = float(a) if a.ndim == 0 else a
        description.check_values(values)
        self._description = description
        self.coordinate_names = description.coordinate_names
        self.model = build(description, use_cache=use_cache)
        self._values: dict[str, Any] = values
        self._p = tuple(values[k] for k in description.param_names)
        self._dynamics_terms = self.model.fn("dynamics_terms")
        n = len(self.coordinate_names)
        self._n = n
        links = description.links
        self.lockable_joints: tuple[int, ...] = tuple(
            j for j, lk in enumerate(links[1:], start=3) if lk.joint and lk.joint.lockable
        )
        self.actuated_joints: tuple[int, ...] = tuple(
            j for j, lk in enumerate(links[1:], start=3) if lk.joint and lk.joint.actuated
        )
        self.lock_angles: tuple[Any, ...] = tuple(
            self._eval(links[j - 2].joint.lock_angle)  # type: ignore[union-attr]
            for j in self.lockable_joints
        )
        if self.hip_joint in self.lockable_joints:  # the section needs the swing leg free
            hip = self.coordinate_names[self.hip_joint]
            raise ModelDescriptionError(
                f"link[{self.hip_joint - 2}].joint.lockable: the hip ({hip!r}) cannot be "
                "lockable: the swing leg swings about it (lock knees, not the hip)")
        self.point_names: tuple[str, ...] = description.point_names
        # a batch of walkers does not walk (its parameters broadcast against states instead)
        self._feet_one_circle = not self.is_batched and self._feet_are_one_circle()
        self._check_mass_matrix()
        if description.events is not None:
            self._check_guard_depends_on_state()
        if "swap_coordinates" in self.model.namespace and all(
            np.ndim(v) == 0 for v in values.values()
        ) and not _BUILDING_AFTER_SWAP.get():
            self.check_swap_symmetry()

    # -- walkers whose legs differ --------------------------------------------------------------
    @property
    def swapped_parameters(self) -> dict[str, ParameterValue]:
        """The parameter values of the walker that takes the next step: the description's
        ``[swap]`` pairs exchanged (``new[k] = old[j]`` for each pair ``(k, j)``); the values
        themselves when the description has no ``[swap]`` table."""
        out: dict[str, Any] = dict(self._values)
        for k, j in self.description.swap:
            out[k] = self._values[j]
        return out

    @functools.cached_property
    def _after_swap(self) -> BuiltWalker:
        swapped = self.swapped_parameters
        if all(np.array_equal(np.asarray(swapped[k]), np.asarray(v))
               for k, v in self._values.items()):
            return self
        token = _BUILDING_AFTER_SWAP.set(True)
        try:
            other = self.replace(**swapped)
        finally:
            _BUILDING_AFTER_SWAP.reset(token)
        other.__dict__["_after_swap"] = self  # the stride's two walkers know each other
        return other

    def after_swap(self) -> BuiltWalker:
        """The walker after the leg swap (:meth:`PlanarWalker.after_swap`): the same
        description with the ``[swap]`` parameters exchanged, or this walker itself when they
        are equal (the swap is then a symmetry: :attr:`steps_per_period` is 1). Calling it on
        the result returns this walker (the same object)."""
        return self._after_swap

    @property
    def generated_model(self) -> GeneratedModel:
        """The equations generated from :attr:`description` (:class:`GeneratedModel`)."""
        return self.model

    @property
    def compiled_kernel(self) -> CompiledKernel | None:
        """``"generated"``: the kernel generated from the description
        (:mod:`heelstrike.dynamics.compiled_phased`).

        None for a subclass that declares another :meth:`step_schedule` (the kernel runs the
        described walkers' schedule only): such walkers run on the scipy reference only. A
        description declaring its heel-strike guard (``[events]``, e.g. McGeer's wheel) runs
        it on both backends, and so does a walker whose legs differ (:attr:`steps_per_period`
        2): the kernel alternates its parameter values with those of :meth:`after_swap` at
        every heel strike.
        """
        if type(self).step_schedule is not BuiltWalker.step_schedule:
            return None
        return "generated"

    def __setattr__(self, name: str, value: Any) -> None:
        if self.__dict__.get("_frozen", False):
            raise FrozenInstanceError(f"cannot assign to field {name!r} of a frozen walker")
        super().__setattr__(name, value)

    def __delattr__(self, name: str) -> None:
        if self.__dict__.get("_frozen", False):
            raise FrozenInstanceError(f"cannot delete field {name!r} of a frozen walker")
        super().__delattr__(name)

    def _check_mass_matrix(self) -> None:
        """Refuse parameter values whose mass matrix is singular, naming the coordinates of
        its null vector (a massless link without inertia at the end of a chain, or a massless
        rod carrying nothing: no acceleration, walk or impact is defined; QA sweep 12 met
        "division by zero"). Massless links are otherwise accepted.

        Checked at a configuration without symmetries (every joint bent), where a walker's
        mass matrix is singular only if it is singular everywhere: ``M`` is refused when its
        smallest eigenvalue is below ``1e-12`` times its largest, and the message lists the
        coordinates that M's null space moves (with the null vector when it is one), e.g.
        ``torso`` for a massless torso rod carrying no point mass.
        """
        k = np.arange(self._n - 2)
        q = np.zeros(self._n)
        q[2:] = 0.3 * (1.0 + 0.37 * k) * (-1.0) ** k
        M = self.mass_matrix(q)
        w, v = np.linalg.eigh(M)
        bad = ~(w[..., 0] > 1e-12 * np.abs(w[..., -1]))
        if not np.any(bad):
            return
        at = tuple(np.argwhere(bad)[0]) if bad.ndim else ()
        small = w[at] <= 1e-12 * np.abs(w[at][-1])
        basis = v[at][:, small]  # orthonormal basis of M's null space, shape (n, k)
        motions = _sparse_null_basis(basis)
        said = []
        for vec in motions:
            moved = [int(j) for j in np.flatnonzero(np.abs(vec) > 1e-9)]
            if len(moved) == 1:
                said.append(f"coordinate {self.coordinate_names[moved[0]]!r} moves no mass and "
                            "no inertia")
            else:
                said.append("the motion " + ", ".join(
                    f"{self.coordinate_names[j]}: {vec[j]:.3g}" for j in moved)
                    + " moves no mass and no inertia")
        raise ModelDescriptionError(
            f"walker {self.description.name!r}: its mass matrix is singular with these "
            f"parameter values: {'; '.join(said)} (M's null space, dimension {len(motions)}; "
            "give the links they move a mass away from the joint, an inertia or a point mass)")

    def _check_guard_depends_on_state(self) -> None:
        """Refuse a declared guard that takes one value at every state (``"hip - hip"``): it
        can never cross zero. Checked at three generic states (one walker; a batch is
        checked member by member when one is built)."""
        if self.is_batched:
            return
        q, _ = _sample_states(3, self._n, 1)
        values = np.asarray(self.heel_strike_function(q), dtype=float)
        if float(np.ptp(values)) == 0.0:
            guard = self.description.events.heel_strike  # type: ignore[union-attr]
            raise ModelDescriptionError(
                f"events.heel_strike: {guard!r} does not depend on the state (it takes one "
                "value in every configuration), so it can never cross zero")

    # -- parameters ---------------------------------------------------------------------------
    def _eval(self, v: Any) -> Any:
        return evaluate_expression(v, self._values)

    @property
    def description(self) -> WalkerDescription:
        """The description the walker was built from."""
        return self._description

    @property
    def parameters(self) -> Mapping[str, ParameterValue]:
        """The named parameter vector (read-only), in the description's parameter order."""
        return MappingProxyType({k: self._values[k] for k in self.description.param_names})

    @property
    def powered_speed(self) -> float | None:
        """The walker file's ``[powered] speed`` (m/s), or None if it declares none."""
        powered = self.description.powered
        return None if powered is None else powered.speed

    def largest_admissible(self, name: str, upper: float) -> float:
        """The largest value of parameter ``name`` up to ``upper`` that the description admits.

        The other parameters keep their values; the admitted values are taken to form an
        interval that contains the current one (true of the bounds and linear constraints of
        the shipped files, e.g. the kneed walker's ``R <= a1 + b1``). Bisection to 1e-12
        relative on :meth:`WalkerDescription.check_values`.

        Parameters
        ----------
        name : str
            A scalar parameter, e.g. ``"R"`` (SI units).
        upper : float
            Largest value of interest (same units).

        Returns
        -------
        float
            ``upper`` if admitted, else the end of the admitted interval (just inside it).
        """
        if name not in self._values:
            raise ValueError(f"{name!r} is not a parameter of {self.description.name!r}")

        def admitted(v: float) -> bool:
            try:
                self.description.check_values({**self._values, name: v})
            except ModelDescriptionError:
                return False
            return True

        lo, hi = float(self._values[name]), float(upper)
        if admitted(hi):
            return hi
        while hi - lo > 1e-12 * max(abs(hi), 1.0):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if admitted(mid) else (lo, mid)
        return lo

    def replace(self, **params: ArrayLike) -> BuiltWalker:
        """A copy with some parameter values changed (no re-derivation)."""
        merged: dict[str, Any] = dict(self._values)
        merged.update(params)
        return BuiltWalker(self.description, use_cache=True, **merged)

    def __repr__(self) -> str:
        vals = ", ".join(f"{k}={v!r}" for k, v in self._values.items())
        return f"BuiltWalker({self.description.name!r}, {vals})"

    # -- PlanarWalker ---------------------------------------------------------------------------
    # total_mass, scale and foot_radii depend on the (frozen) parameter values only: computed
    # once per walker (each evaluates description expressions), returned read-only.
    @functools.cached_property
    def total_mass(self) -> FloatArray:
        d = self.description
        masses = [self._eval(lk.mass) for lk in d.links] + [
            self._eval(pm.mass) for pm in d.point_masses
        ]
        return _read_only(np.asarray(sum(masses), dtype=float))

    @functools.cached_property
    def scale(self) -> WalkerScale:
        """``(total mass, gravity, leg length)`` (kg, m/s^2, m).

        Gravity is the walker's ``g`` parameter; the leg length is measured on the model (see
        :attr:`PlanarWalker.scale`), e.g. ``a1 + b1 + a2 + b2`` for the kneed walker.
        """
        measured = super().scale
        if any(ft.profile is not None for ft in self.description.feet):
            # the base class extrapolates the swing foot to the hip turned by pi, beyond a
            # profile's range: measure the hip's height above the swing foot's contact point
            # with every coordinate zero instead (the same l for an arc foot)
            hip = self.description.links[self.hip_joint - 2].name
            q0 = np.zeros(self._n)
            pos = self.positions(q0)
            leg = pos[f"{hip}.proximal"][..., 1] - pos["swing_foot.contact"][..., 1]
            measured = WalkerScale(total_mass=measured.total_mass, gravity=measured.gravity,
                                   leg_length=np.asarray(leg, dtype=float))
        g = np.asarray(self._values["g"], dtype=float)
        return WalkerScale(
            total_mass=_read_only(np.array(measured.total_mass, dtype=float)),
            gravity=_read_only(np.broadcast_to(g, np.shape(measured.gravity)).copy()),
            leg_length=_read_only(np.array(measured.leg_length, dtype=float)),
        )

    @functools.cached_property
    def foot_radii(self) -> tuple[FloatArray, FloatArray]:
        """Rolling radii ``R0`` (m) of the stance and swing foot: an arc foot's radius, a
        profile foot's radius of curvature at ``phi = 0``
        (:func:`~heelstrike.models.description.rolling_radius`)."""
        st, sw = self.description.feet
        return (_read_only(np.array(rolling_radius(st, self._values), dtype=float)),
                _read_only(np.array(rolling_radius(sw, self._values), dtype=float)))

    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """Mass matrix ``M(q)`` (kg, kg m, kg m^2), shape (..., n, n)."""
        return np.asarray(self.model.fn("mass_matrix")(_arr(q, self._n, "q"), self._p))

    def bias_forces(self, q: ArrayLike, q_dot: ArrayLike, slope: ArrayLike = 0.0) -> FloatArray:
        """``h`` in ``M q_ddot + h = B u + A^T lambda`` (N, N m), shape (..., n).

        Coriolis, centrifugal and gravity terms; gravity ``g (-sin slope, -cos slope)``.
        """
        return np.asarray(
            self.model.fn("bias_forces")(
                _arr(q, self._n, "q"),
                _arr(q_dot, self._n, "q_dot"),
                self._p,
                np.asarray(slope, dtype=float),
            )
        )

    def dynamics_terms(
        self, q: ArrayLike, q_dot: ArrayLike, slope: ArrayLike = 0.0
    ) -> tuple[FloatArray, FloatArray]:
        """``(M(q), h(q, q_dot))`` from one generated function, shapes (..., n, n), (..., n).

        Equal to ``(mass_matrix(q), bias_forces(q, q_dot, slope))`` (to rounding), but the
        trigonometry and the subexpressions the two share are evaluated once (one ``sympy.cse``
        over both), and a single state is evaluated on Python floats (numpy scalars where
        Python would raise, e.g. on overflow): what the scipy backend's right-hand side calls
        once per evaluation. ``M`` has the leading shape of ``q`` and the
        parameters, ``h`` that broadcast with ``q_dot`` and ``slope``.
        """
        q_ = _arr(q, self._n, "q")
        qd = _arr(q_dot, self._n, "q_dot")
        s = np.asarray(slope, dtype=float)
        lead_m = _lead(q_, *self._p)
        if q_.ndim == 1 and qd.ndim == 1 and s.ndim == 0:
            # one state (the integrator's case): Python floats, several times faster than
            # numpy scalars; where Python raises instead of returning inf, numpy scalars below
            try:
                return self._dynamics_terms(
                    q_.tolist(), qd.tolist(), self._p, float(s), lead_m, lead_m
                )
            except (OverflowError, ZeroDivisionError):
                pass
        lead_h = lead_m
        if qd.ndim > 1 or s.ndim:
            lead_h = np.broadcast_shapes(lead_m, qd.shape[:-1], s.shape)
        # the generated function takes the states coordinate-first, shape (n, ...)
        return self._dynamics_terms(_first(q_), _first(qd), self._p, s[()], lead_m, lead_h)

    def potential_energy(self, q: ArrayLike, slope: ArrayLike = 0.0) -> FloatArray:
        """Gravitational potential energy (J), zero at the frame origin, shape (...)."""
        return np.asarray(
            self.model.fn("potential_energy")(
                _arr(q, self._n, "q"), self._p, np.asarray(slope, dtype=float)
            )
        )

    @staticmethod
    def _foot(foot: str) -> str:
        if foot == "right":
            return "stance"
        if foot == "left":
            return "swing"
        raise ValueError(f"foot must be 'right' or 'left', got {foot!r}")

    def contact_jacobian(self, q: ArrayLike, foot: Foot) -> FloatArray:
        """Rolling-contact Jacobian (tangential, normal rows), shape (..., 2, n).

        ``foot = "right"`` is the stance foot, ``"left"`` the swing foot.
        """
        f = self.model.fn(f"contact_jacobian_{self._foot(foot)}")
        return np.asarray(f(_arr(q, self._n, "q"), self._p))

    def contact_jacobian_rate(self, q: ArrayLike, q_dot: ArrayLike, foot: Foot) -> FloatArray:
        """``A_dot q_dot`` of a foot's rolling contact (m/s^2), shape (..., 2)."""
        f = self.model.fn(f"contact_jacobian_rate_{self._foot(foot)}")
        return np.asarray(f(_arr(q, self._n, "q"), _arr(q_dot, self._n, "q_dot"), self._p))

    def foot_centre(self, q: ArrayLike, foot: Foot) -> FloatArray:
        """Arc centre of a foot (m), shape (..., 2): the point ``R0`` (:attr:`foot_radii`)
        above its contact point (for a profile foot, the centre of the circle of that radius
        touching the ground where the foot would)."""
        f = self.model.fn(f"foot_centre_{self._foot(foot)}")
        return np.asarray(f(_arr(q, self._n, "q"), self._p))

    def contact_point(self, q: ArrayLike, foot: Foot) -> FloatArray:
        """Ground point ``R`` below the foot's arc centre (m), shape (..., 2): the point of
        the foot whose outward normal points down (for a profile foot ``O + (-h', -h)``)."""
        c = self.foot_centre(q, foot)
        R = self.foot_radii[0 if self._foot(foot) == "stance" else 1]
        return np.asarray(c - np.stack(np.broadcast_arrays(np.zeros_like(R), R), axis=-1))

    def foot_clearance(self, q: ArrayLike, foot: Foot) -> FloatArray:
        """Height of the foot arc's lowest point above the ground (m), shape (...)."""
        return np.asarray(self.contact_point(q, foot)[..., 1])

    def swap_legs(self, q: ArrayLike, q_dot: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Relabel so that the swing foot becomes the stance foot (links swap with their mirrors).

        ``q' = (c_swing, theta_{mirror(root)}, theta'_child - theta'_parent, ...)`` with
        ``theta'_k = theta_{mirror(k)}`` (unmirrored links such as a torso keep their absolute
        angle); ``q_dot' = (dq'/dq) q_dot``.

        Raises
        ------
        NotImplementedError
            If the description declares no mirrors.
        """
        if "swap_coordinates" not in self.model.namespace:
            raise NotImplementedError(
                f"walker {self.description.name!r} declares no link mirrors: no leg swap"
            )
        q_ = _arr(q, self._n, "q")
        qd = _arr(q_dot, self._n, "q_dot")
        q_new = np.asarray(self.model.fn("swap_coordinates")(q_, self._p))
        J = self.model.fn("swap_jacobian")(q_, self._p)
        return q_new, np.asarray(np.einsum("...ij,...j->...i", J, qd))

    def actuation_matrix(self) -> FloatArray:
        """``B`` (n, n_u): column ``e_j`` for each actuated joint (torque across the joint)."""
        B = np.zeros((self._n, len(self.actuated_joints)))
        for col, j in enumerate(self.actuated_joints):
            B[j, col] = 1.0
        return B

    # -- extras -------------------------------------------------------------------------------
    def lock_jacobian(self, joints: tuple[int, ...] | None = None) -> FloatArray:
        """Jacobian of joint-lock constraints ``q[j] = lock_angle``, shape (k, n).

        Parameters
        ----------
        joints : tuple of int, optional
            Coordinate indices to lock (default: all :attr:`lockable_joints`).
        """
        js = self.lockable_joints if joints is None else tuple(joints)
        for j in js:
            if j not in self.lockable_joints:
                raise ValueError(
                    f"coordinate {j} ({self.coordinate_names[j]}) is not a lockable joint"
                )
        A = np.zeros((len(js), self._n))
        for r, j in enumerate(js):
            A[r, j] = 1.0
        return A

    def joints_at_lock(self, q: ArrayLike, tol: float = 1e-6) -> tuple[int, ...]:
        """The lockable joints at their lock angle in the configuration ``q`` (within ``tol``
        rad): the ones an impact at ``q`` holds locked; a bent knee is free.

        Parameters
        ----------
        q : array_like, shape (n,)
        tol : float
            Accepted ``|q[j] - lock_angle|`` (rad).
        """
        q_ = np.asarray(q, dtype=float)
        return tuple(j for j, a in zip(self.lockable_joints, self.lock_angles, strict=True)
                     if abs(float(q_[j]) - float(a)) <= tol)

    def stance_and_swing_locks(self) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """Split the lockable joints into stance-leg and swing-leg ones.

        Along the kinematic chain from the stance foot's link to the swing foot's link, a joint
        is on the stance side if its link's mirror comes later in the chain (e.g. the stance
        knee's ``stance_thigh`` before ``swing_thigh``), else on the swing side. Lockable joints
        off that chain count as swing-side.

        Returns
        -------
        stance, swing : tuple of int
            Coordinate indices.
        """
        desc = self.description
        links = {lk.name: lk for lk in desc.links}
        chain: list[str] = []
        name: str | None = desc.feet[1].link
        while name is not None:
            chain.append(name)
            name = links[name].parent
        chain.reverse()
        index = {lk.name: 3 + k for k, lk in enumerate(desc.links[1:])}
        stance: list[int] = []
        swing: list[int] = []
        for j in self.lockable_joints:
            lk = next(lk for lk in desc.links[1:] if index[lk.name] == j)
            if (
                lk.name in chain
                and lk.mirror in chain
                and chain.index(lk.mirror) > chain.index(lk.name)
            ):
                stance.append(j)
            else:
                swing.append(j)
        return tuple(stance), tuple(swing)

    def _feet_are_one_circle(self) -> bool:
        """Whether the two feet are one circle in every posture (equal radii, the same arc
        centre; checked at two generic postures; one walker)."""
        q = np.zeros((2, self._n))
        q[:, 2:] = np.linspace(0.3, 0.7, self._n - 2) * np.array([[1.0], [-1.3]])
        R_st, R_sw = (np.asarray(r, dtype=float) for r in self.foot_radii)
        gap = np.linalg.norm(self.foot_centre(q, "left") - self.foot_centre(q, "right"),
                             axis=-1)
        tol = 1e-9 * float(self.scale.leg_length)
        return bool(np.all(gap < tol) and abs(float(R_st) - float(R_sw)) < tol)

    def check_heel_strike_detectable(self) -> None:
        """Raise ``ValueError`` if the walker's heel-strike guard cannot detect its heel strike.

        That is so when the guard is the swing foot's clearance (no ``[events]`` table) and the
        two feet are one circle in every posture: equal radii and the
        same arc centre, e.g. McGeer's wheel ``R = l`` of the compass and torso walkers (both
        arcs about the hip). The clearance is then zero to round-off throughout the step, and
        a walk would strike anywhere (the compass walker struck at 0.39 s with its legs nearly
        upright). Decided once, when the walker is built (two generic postures); the
        equations of motion and the impact algebra stay valid there, only walking is refused.
        A walker file that declares its guard (``[events] heel_strike``, e.g. the shipped
        ``wheel.toml``) walks whatever its feet.
        """
        if self._feet_one_circle and self.description.events is None:
            raise ValueError(
                f"model {self.description.name!r} cannot walk with these parameter values: its "
                "two feet are one circle in every posture (the same radius and arc centre, e.g. "
                "McGeer's wheel R = l), so the swing foot's clearance is zero throughout a step "
                "and cannot detect its heel strike (the compass gait without --model, "
                "--radius 1, walks the wheel: its heel strike is 2 q3 + q4 = 0; so does "
                "--model wheel, whose walker file declares that guard in its [events] table)"
            )

    def heel_strike_function(self, q: ArrayLike) -> FloatArray:
        """The heel-strike guard, rising through zero at the strike, shape (...).

        The walker file's declared guard (``[events] heel_strike``, generated from the
        expression), else minus the swing foot's clearance (the default of
        :meth:`~heelstrike.models.base.PlanarWalker.heel_strike_function`).

        Parameters
        ----------
        q : array_like, shape (..., n)
        """
        if self.description.events is None:
            return np.asarray(-self.foot_clearance(q, "left"))
        return np.asarray(self.model.fn("heel_strike_guard")(_arr(q, self._n, "q"), self._p))

    def step_schedule(self, *, knee_flex_threshold: float = 1e-6) -> StepSchedule:
        """The hybrid schedule of one step of a described walker.

        *Knee swing* (only with lockable joints; McGeer 1990): the stance-side locks held, the
        swing knee free; first until it has flexed past ``knee_flex_threshold`` (rad) beyond
        its lock angle, then until it straightens back to it: the **knee strike** (an inert
        impact with ``A = [A_R; lock rows]``). *Locked swing*: every lock held; first until the
        heel strike is *armed* (stance angle > 0, swing foot ahead of the stance foot and above
        the ground; skipped if armed at its start), then until the swing foot's clearance falls
        through zero with the foot ahead of the stance foot (a touch level with it or behind it
        is no heel strike: :meth:`strike_not_ahead`, and the strike is armed anew). This
        excludes the mid-stance scuffing root of the clearance (during the knee swing, ground
        penetration of the swing foot is ignored too); for the compass gait it is the same
        event as :meth:`heelstrike.models.CompassGait.heel_strike_function`. A walker file
        declaring its guard (``[events]``) runs it instead: the locked swing is then the
        compass gait's (midstance, then the declared guard), and the trailing foot is decided by
        the declared rule (``"lifts"``: complementarity; ``"lifts_or_grazes"``: the
        ``"lift_or_graze"`` rule of :data:`~heelstrike.models.schedule.TrailingFootRule`).
        Every stage can end in a fall: forward (stance angle reaching ``pi/2``) or backward
        (the stance leg stopping before the vertical, or rolling back through it), and for a
        profile foot (``[[foot]] profile``) in ``off_profile``: the stance foot's contact angle
        leaving its ``phi_range`` (every stage; checked at each stage's start too), or the
        swing foot's in the stage that ends in the heel strike (:meth:`profile_margin`). The
        heel strike decides the trailing foot by complementarity.

        Parameters
        ----------
        knee_flex_threshold : float
            How far (rad) the swing knee must flex before its strike is looked for.

        Raises
        ------
        ValueError
            If the heel strike cannot be detected (:meth:`check_heel_strike_detectable`).
        """
        self.check_heel_strike_detectable()
        stance_locks, swing_locks = self.stance_and_swing_locks()
        angle = {j: float(a) for j, a in zip(self.lockable_joints, self.lock_angles,
                                              strict=True)}
        stance_range, swing_range = self._profile_guards()
        falls = (
            fell_forward(),
            Guard(
                name="fell_backward",
                function=lambda q, qd: float(qd[2]) if q[2] < 0.0 else 1.0 + float(q[2]),
                direction=-1,
            ),
            *stance_range,
        )

        def flex(q: FloatArray, qd: FloatArray) -> float:
            return float(min(q[j] - angle[j] for j in swing_locks))

        def armed(q: FloatArray, qd: FloatArray) -> float:
            clearance = float(self.foot_clearance(q, "left"))
            return float(min(q[2], self.swing_foot_ahead(q), clearance))

        threshold = float(knee_flex_threshold)
        phases: list[Phase] = []
        if swing_locks:
            flexed = Guard(name="knee_flexed", function=lambda q, qd: flex(q, qd) - threshold,
                           direction=1)
            knee = Guard(name="knee_strike", function=flex, direction=-1)
            phases.append(Phase(
                name="knee_swing", locked=stance_locks, reset="knee_strike",
                strike_joints=swing_locks,
                stages=(Stage(until=flexed, failures=falls), Stage(until=knee, failures=falls)),
            ))
        events = self.description.events
        if events is not None:
            phases.append(self._declared_strike_phase(stance_locks + swing_locks, falls,
                                                      swing_range))
            rule: TrailingFootRule = ("lift_or_graze" if events.trailing_foot == "lifts_or_grazes"
                                      else "complementarity")
            return StepSchedule(phases=tuple(phases), lock_angles=tuple(angle.items()),
                                trailing_foot=rule)
        strike = Guard(name="heel_strike",
                       function=lambda q, qd: float(-self.foot_clearance(q, "left")), direction=1)
        phases.append(Phase(
            name="locked_swing", locked=stance_locks + swing_locks, reset="heel_strike",
            stages=(
                Stage(until=Guard(name="armed", function=armed, direction=1), failures=falls,
                      skip=lambda q, qd: armed(q, qd) > 0.0),
                Stage(until=strike, failures=(*falls, *swing_range),
                      reject=self.strike_not_ahead),
            ),
        ))
        return StepSchedule(phases=tuple(phases), lock_angles=tuple(angle.items()),
                            trailing_foot="complementarity")

    def _declared_strike_phase(self, locked: tuple[int, ...], falls: tuple[Guard, ...],
                               swing_range: tuple[Guard, ...] = ()) -> Phase:
        """The locked swing of a walker declaring its heel-strike guard (``[events]``).

        As the compass gait's step (:meth:`PlanarWalker.step_schedule`): first until the
        stance leg passes the vertical (skipped if it has), then until the declared guard
        rises through zero. A crossing with the swing foot off the ground
        (``|clearance| > CONTACT_TOLERANCE l``) is no heel strike: the strike is armed anew.
        """
        leg = float(np.asarray(self.scale.leg_length))

        def off_ground(q: FloatArray, qd: FloatArray) -> bool:
            return bool(abs(float(self.foot_clearance(q, "left"))) > CONTACT_TOLERANCE * leg)

        midstance = Stage(
            until=Guard(name="midstance", function=lambda q, qd: float(q[2]), direction=1),
            failures=falls, skip=lambda q, qd: bool(q[2] >= 0.0),
        )
        strike = Stage(
            until=Guard(name="heel_strike",
                        function=lambda q, qd: float(self.heel_strike_function(q)),
                        direction=1),
            failures=(*falls, *swing_range), reject=off_ground,
        )
        return Phase(name="locked_swing", locked=locked, reset="heel_strike",
                     stages=(midstance, strike))

    @functools.cached_property
    def profile_ranges(self) -> tuple[tuple[float, float] | None, tuple[float, float] | None]:
        """``(phi_min, phi_max)`` (rad) of the stance and the swing foot's profile
        (``[[foot]] phi_range`` at this walker's values), None for an arc foot (whose support
        function ``h = R`` holds at every angle). Of a single walker (not a batch)."""
        out: list[tuple[float, float] | None] = []
        for ft in self.description.feet:
            if ft.profile is None:
                out.append(None)
                continue
            lo, hi = (float(self._eval(v)) for v in ft.phi_range)
            out.append((lo, hi))
        return out[0], out[1]

    def contact_angle(self, q: ArrayLike, foot: Foot) -> FloatArray:
        """The profile angle ``phi`` (rad) at a foot's contact with the ground, shape (...).

        The contact normal is the ground's, so ``phi`` is the absolute angle of the foot's
        link (:meth:`link_angles`; ``docs/walker_files.rst``): the support function is
        evaluated at it. ``foot = "right"`` is the stance foot, ``"left"`` the swing foot.
        """
        ft = self.description.feet[0 if self._foot(foot) == "stance" else 1]
        return self.link_angles(q)[ft.link]

    def profile_margin(self, q: ArrayLike, foot: Foot) -> FloatArray:
        """How far (rad) a foot's contact angle is inside its profile's ``phi_range``,
        ``min(phi - phi_min, phi_max - phi)`` (:meth:`contact_angle`), shape (...): negative
        where the support function would be extrapolated beyond the shape the walker file
        gives; ``+inf`` for an arc foot."""
        rng = self.profile_ranges[0 if self._foot(foot) == "stance" else 1]
        phi = self.contact_angle(q, foot)
        if rng is None:
            return np.full(np.shape(phi), np.inf)
        lo, hi = rng
        return np.asarray(np.minimum(phi - lo, hi - phi))

    def profile_excursion(self, q: ArrayLike, tol: float = 1e-9) -> str | None:
        """Which foot's contact angle is at or beyond its profile's ``phi_range`` at ``q``
        (shape (n,)), said in words (the foot, its link, the angle and the range), or None
        if both are inside by more than ``tol`` (rad). The message of a walk ending in
        ``off_profile``."""
        feet: tuple[Foot, Foot] = ("right", "left")
        margin, foot = min((float(self.profile_margin(q, f)), f) for f in feet)
        if margin > tol:
            return None
        i = 0 if foot == "right" else 1
        ft = self.description.feet[i]
        rng = self.profile_ranges[i]
        assert rng is not None
        role = "stance" if i == 0 else "swing (striking)"
        return (f"the {role} foot {ft.name!r} (link {ft.link!r}) is at contact angle "
                f"phi = {float(self.contact_angle(q, foot)):.6g} rad, at or beyond the end of "
                f"its phi_range [{rng[0]:.6g}, {rng[1]:.6g}] rad")

    def _profile_guards(self) -> tuple[tuple[Guard, ...], tuple[Guard, ...]]:
        """The ``off_profile`` guards of the stance and the swing foot (each empty for an arc
        foot or a batch of walkers): :meth:`profile_margin` falling through zero."""
        if self.is_batched:
            return (), ()

        def guard(foot: Foot) -> tuple[Guard, ...]:
            if self.profile_ranges[0 if foot == "right" else 1] is None:
                return ()
            return (Guard(name="off_profile",
                          function=lambda q, qd: float(self.profile_margin(q, foot)),
                          direction=-1),)

        return guard("right"), guard("left")

    def swing_foot_ahead(self, q: ArrayLike) -> float:
        """How far (m) the swing ("left") foot's contact point is ahead of the stance foot's,
        along the walking direction ``-x``."""
        return float(self.contact_point(q, "right")[0] - self.contact_point(q, "left")[0])

    def strike_not_ahead(self, q: ArrayLike, q_dot: ArrayLike) -> bool:
        """Whether a swing foot touching the ground at ``q`` is no heel strike: it is not ahead
        of the stance foot by more than ``CONTACT_TOLERANCE (l - R)`` (legs parallel, or the
        foot arriving from behind: a step of zero or negative length; QA sweep 11, #4). ``R``
        is the swing foot's radius: the feet's contact points at a heel strike are
        ``~2 (l - R) sin q3`` apart, which vanishes towards McGeer's wheel (``R = l``). The
        compiled kernels test the same (``_phased_kernels``)."""
        span = float(self.scale.leg_length) - float(np.asarray(self.foot_radii[1]))
        return self.swing_foot_ahead(q) <= CONTACT_TOLERANCE * span

    def joint_index(self, name: str) -> int:
        """Coordinate index of a coordinate/joint name."""
        return self.coordinate_names.index(name)

    def positions(self, q: ArrayLike) -> dict[str, FloatArray]:
        """Named points (m): each link's ``.proximal``, ``.distal``, ``.com``; point masses;
        ``stance_foot.centre/.contact``, ``swing_foot.centre/.contact``. Each (..., 2)."""
        P = self.model.fn("points")(_arr(q, self._n, "q"), self._p)
        return {name: np.asarray(P[..., k, :]) for k, name in enumerate(self.point_names)}

    @property
    def segments(self) -> tuple[tuple[str, str], ...]:
        """Point-name pairs to draw as line segments (one per link)."""
        return tuple((f"{lk.name}.proximal", f"{lk.name}.distal") for lk in self.description.links)

    def swing_leg_angle(self, q: ArrayLike) -> FloatArray:
        """Absolute angle (rad) of the link hanging from the hip joint (see
        :meth:`~heelstrike.models.base.PlanarWalker.swing_leg_angle`), shape (...)."""
        return self.link_angles(q)[self.description.links[self.hip_joint - 2].name]

    def link_angles(self, q: ArrayLike) -> dict[str, FloatArray]:
        """Absolute angle (rad) of every link, shape (...)."""
        q_ = _arr(q, self._n, "q")
        out: dict[str, FloatArray] = {}
        for j, lk in enumerate(self.description.links, start=2):
            base = out[lk.parent] if lk.parent is not None else 0.0
            out[lk.name] = np.asarray(base + q_[..., j])
        return out

    def check_swap_symmetry(self, n_samples: int = 3, seed: int = 0, rtol: float = 1e-9) -> None:
        """Check numerically that the leg swap maps this walker onto :meth:`after_swap`.

        With ``P`` this walker's parameter values and ``P'`` the swapped ones
        (:attr:`swapped_parameters`; ``P' = P`` without a ``[swap]`` table, where the swap is a
        symmetry), at random states: each link's ``length``, ``mass`` and ``inertia`` at ``P``
        equal its mirror's at ``P'``; ``M_P(q) = J_s^T M_{P'}(q') J_s``,
        ``V_P(q) = V_{P'}(q')`` at two slopes; the new swing foot's contact point is the old stance
        foot's, and every link's COM maps onto its mirror's.

        Raises
        ------
        ModelDescriptionError
            When the mirrors do not describe the swap, naming the first thing that does not
            map (``link[i].mass: ...``, a link's centre of mass, the feet, the masses).
        """
        links = self.description.links
        index = {lk.name: i for i, lk in enumerate(links)}
        swapped = self.swapped_parameters
        if self.description.swap:
            why = ("; the [swap] table must exchange every parameter in which the legs differ "
                   "(the walker after the swap is the same file with those values exchanged)")
        else:
            why = ("; a walker whose legs differ names each leg's parameters by role and lists "
                   "the pairs the leg swap exchanges in a [swap] table (e.g. m1 = \"m2\")")

        def after(v: Any) -> Any:
            return evaluate_expression(v, swapped)

        for i, lk in enumerate(links):  # the plainest cause first: the mirrors' own fields
            if lk.mirror is None:
                continue
            other = links[index[lk.mirror]]
            for key in ("length", "mass", "inertia"):
                a, b = self._eval(getattr(lk, key)), after(getattr(other, key))
                if not np.allclose(a, b, rtol=rtol, atol=0.0):
                    swapped_note = " after the [swap]" if self.description.swap else ""
                    raise ModelDescriptionError(
                        f"link[{i}].{key}: link {lk.name!r} and its mirror {other.name!r} "
                        f"differ ({float(a):g} vs {float(b):g}{swapped_note}), so the leg "
                        f"swap does not map the walker onto itself{why}")
        other_walker = self.after_swap()
        q, qd = _sample_states(n_samples, self._n, seed)
        q2, _ = self.swap_legs(q, qd)
        pos1, pos2 = self.positions(q), other_walker.positions(q2)
        for lk in links:
            if not np.allclose(pos2[f"{lk.name}.com"], pos1[f"{lk.mirror or lk.name}.com"],
                               atol=1e-9):
                raise ModelDescriptionError(
                    f"link[{index[lk.name]}].com: after the leg swap the centre of mass of "
                    f"{lk.name!r} is not where {lk.mirror or lk.name!r}'s was (its com, "
                    f"com_offset, attach or direction do not mirror){why}")
        if not np.allclose(other_walker.contact_point(q2, "left"),
                           self.contact_point(q, "right"), atol=1e-9):
            raise ModelDescriptionError(
                "foot: after the leg swap the new swing foot's contact point is not where the "
                "old stance foot's was (the feet's radius, profile, centre or centre_offset do "
                f"not mirror){why}")
        J = self.model.fn("swap_jacobian")(q, self._p)
        M1 = self.mass_matrix(q)
        M2 = np.swapaxes(J, -1, -2) @ other_walker.mass_matrix(q2) @ J
        ok = np.allclose(M1, M2, rtol=rtol, atol=rtol * np.max(np.abs(M1)))
        for slope in (0.0, 0.3):
            V1 = self.potential_energy(q, slope)
            V2 = other_walker.potential_energy(q2, slope)
            ok &= np.allclose(V1, V2, rtol=rtol, atol=rtol * np.max(np.abs(V1)) + 1e-12)
        if not ok:
            raise ModelDescriptionError(
                "point_mass: the leg swap maps the links but not the mass distribution (mass "
                "matrix or potential energy): a point mass without a mirror image on the "
                f"other leg, or one off the legs' line (offset){why}")


def _sample_states(n_samples: int, n: int, seed: int) -> tuple[FloatArray, FloatArray]:
    """Deterministic well-spread test states: angles in [-0.6, 0.6] rad, rates in [-2, 2] rad/s.

    A Weyl (golden-ratio) sequence shifted by ``seed``; used instead of :mod:`numpy.random`,
    whose import costs every walker-loading process about 5 ms.
    """
    k = np.arange(1, 2 * n_samples * n + 1, dtype=float) + seed * np.sqrt(2.0)
    u = np.modf(k * 0.6180339887498949)[0].reshape(2, n_samples, n)
    return 1.2 * u[0] - 0.6, 4.0 * u[1] - 2.0


def shipped_walkers() -> tuple[str, ...]:
    """Names of the descriptions shipped in ``heelstrike/walkers``."""
    root = importlib.resources.files("heelstrike") / "walkers"
    return tuple(sorted(p.name[:-5] for p in root.iterdir() if p.name.endswith(".toml")))


def load_walker(
    name_or_path: str | os.PathLike[str], *, use_cache: bool = True, **param_overrides: ArrayLike
) -> BuiltWalker:
    """Load a shipped walker by name (``"compass"``, ``"kneed"``, ``"torso"``) or a TOML file.

    Parameters
    ----------
    name_or_path : str or path
        Shipped name or path to a ``.toml`` description.
    use_cache : bool
        Use the generated-code caches.
    **param_overrides : float or array_like
        Parameter values, e.g. ``R=0.3``.

    Examples
    --------
    >>> w = load_walker("compass", R=0.2)
    >>> w.mass_matrix([0.0, 0.2, 0.1, -0.2]).shape
    (4, 4)
    """
    return BuiltWalker(walker_description(name_or_path), use_cache=use_cache, **param_overrides)


def walker_description(name_or_path: str | os.PathLike[str]) -> WalkerDescription:
    """The description of a shipped walker (by name) or of a TOML file (see :func:`load_walker`).

    A string that is a shipped name (:func:`shipped_walkers`) means the shipped walker even if
    a file or folder of that name is in the working directory: give such a file as a path
    (``./compass`` or a ``pathlib.Path``).

    Raises
    ------
    ValueError
        An unknown shipped name.
    ModelDescriptionError
        A file that is not a valid description.
    """
    s = os.fspath(name_or_path)
    shipped = isinstance(name_or_path, str) and s in shipped_walkers()
    if not shipped and (s.endswith(".toml") or os.sep in s or Path(s).is_file()):
        return read_description(s)
    res = importlib.resources.files("heelstrike") / "walkers" / f"{s}.toml"
    if not res.is_file():
        raise ValueError(f"unknown walker {s!r}; shipped: {shipped_walkers()}")
    with importlib.resources.as_file(res) as p:
        return read_description(p)
