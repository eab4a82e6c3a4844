"""Chunked, resumable parameter sweeps over the outer product of 1-D grids.

:func:`sweep` evaluates a pure, vectorized function on the full outer product of named 1-D grids
(walker parameters, initial states, slopes, ...), chunk by chunk, with Dask: local threads or
processes, or a ``dask.distributed`` cluster. With a ``store`` every finished chunk is written to
Zarr at once and recorded, so an interrupted sweep resumes where it stopped and never recomputes
a finished chunk. A store is safe to reuse: a running sweep locks it, it is resumed only by the
same computation (grid, chunks, function identity including closures, defaults, plain-data
globals and module sources, heelstrike version), and every finished chunk carries a checksum,
so a deleted or overwritten chunk is computed again (see :func:`sweep`). Local threads work in
the light install (a plain thread pool when Dask is absent); processes, clusters and stores
need the ``scale`` extra (``pip install '.[scale]'`` in a clone of heelstrike).

The function contract
---------------------
``func(**kwargs) -> Mapping[str, array_like]``.

- It is called once per chunk with one keyword per grid name, in grid order. For a grid with
  ``d`` names, ``kwargs[name]`` is a float (or the grid's dtype) ndarray with ``d`` dimensions,
  of length ``c_j`` (the chunk's extent along that name's axis ``j``) along axis ``j`` and 1
  along every other axis; the arguments therefore broadcast against each other to the chunk
  shape ``(c_0, ..., c_{d-1})`` (an open mesh, as from ``numpy.ix_``).
- It returns a mapping of output name to array. The first ``d`` dimensions of every output must
  broadcast to the chunk shape; any further (trailing) dimensions are extra output dimensions,
  e.g. ``(..., 2)`` for a pair of multipliers, and must have the same size in every chunk. Each
  output keeps the same dtype in every chunk. Output names must differ from the grid names.
- It must be pure and deterministic (same inputs, same outputs); it is never called twice for a
  chunk that finished. For process or distributed execution it must be picklable (a module-level
  function or a :func:`functools.partial` of one; cloudpickle also handles closures).

Results are identical whatever the scheduler or chunking: each value depends only on its inputs.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import hashlib
import itertools
import json
import logging
import os
import shutil
import sys
import sysconfig
import types
import uuid
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray

from heelstrike._optional import available, require
from heelstrike.io import write_text

__all__ = [
    "KNOWN_UNITS",
    "SweepError",
    "SweepFunction",
    "SweepStoreLockedError",
    "SweepStoreMismatchError",
    "SweepStoreRepairWarning",
    "sweep",
    "sweep_progress",
]

def _attribute_units(attrs: Mapping[str, Any],
                     units: Mapping[str, str] | None = None) -> dict[str, str]:
    """``<name>_units`` attributes for the numeric attributes of a result dataset whose unit is
    known: from ``units`` (name to unit), else from :data:`KNOWN_UNITS` by the name, or by the
    name without a ``fixed_point_``, ``walker_`` or ``param_`` prefix. Names that already have
    a ``_units`` attribute, and names of unknown unit, get none."""
    known = {**KNOWN_UNITS, **(units or {})}
    out: dict[str, str] = {}
    for key, value in attrs.items():
        if key.endswith("_units") or f"{key}_units" in attrs or isinstance(value, bool | str):
            continue
        if not isinstance(value, int | float | np.integer | np.floating):
            continue
        base = key
        for prefix in ("fixed_point_", "walker_", "param_"):
            if key.startswith(prefix):
                base = key[len(prefix):]
        unit = known.get(key, known.get(base))
        if unit is not None:
            out[f"{key}_units"] = unit
    return out


#: ``func(**chunk_kwargs) -> {output name: array}``; see the module docstring.
SweepFunction = Callable[..., Mapping[str, ArrayLike]]

#: Units (UDUNITS strings) of heelstrike's parameter, state and output names. Used for names the
#: caller gives no units for.
KNOWN_UNITS: dict[str, str] = {
    "impact_angle": "rad",
    "q3": "rad",
    "q4": "rad",
    "slope": "rad",
    "foot_radius": "m",
    "leg_length": "m",
    "leg_com_from_hip": "m",
    "step_length": "m",
    "hip_mass": "kg",
    "leg_mass": "kg",
    "leg_inertia": "kg m2",
    "gravity": "m s-2",
    "q1_dot": "m s-1",
    "q2_dot": "m s-1",
    "q2_dot_post": "m s-1",
    "q3_dot": "rad s-1",
    "q4_dot": "rad s-1",
    "restitution": "1",
    "kinetic_energy": "J",
    "kinetic_energy_constrained": "J",
    "kinetic_energy_admissible": "J",
    "kinetic_energy_post": "J",
    "energy_lost": "J",
    "T": "J",
    "T_c": "J",
    "T_a": "J",
    "eta": "J m-1",
    "constraint_impulse": "N s",
}

_STATE_GROUP = "_heelstrike_sweep"
_IDENTITY_ATTR = "sweep_identity"
#: Per-chunk completion records (a file of the chunk's SHA-256 each), in the state group's
#: folder: a damaged ``done`` or ``checksum`` array is rebuilt from them.
_RECORDS = "records"
#: The store's metadata manifest: every ``zarr.json`` of the store with its SHA-256 and text,
#: and the manifest's own checksum; a damaged metadata file is restored from it.
_MANIFEST = f"{_STATE_GROUP}/manifest.json"
_LOCAL_SCHEDULERS = ("threads", "threading", "processes", "multiprocessing", "sync",
                     "synchronous", "single-threaded")


class SweepError(RuntimeError):
    """A sweep cannot run: bad grid, bad function output or unusable store."""


class SweepStoreMismatchError(SweepError):
    """The store holds a sweep of a different grid, chunking or function.

    Attributes
    ----------
    differs : tuple of str
        The parts of the sweep identity that differ, e.g. ``("function.closure",)``.
    """

    def __init__(self, message: str, differs: Sequence[str] = ()) -> None:
        super().__init__(message)
        self.differs = tuple(differs)


class SweepStoreLockedError(SweepError):
    """Another sweep is writing to the same store (its lock file is held)."""


class SweepStoreRepairWarning(UserWarning):
    """Finished chunks of a store failed checksum verification and are computed again."""


_log = logging.getLogger(__name__)

# -- identity ------------------------------------------------------------------------------------
# The identity of a sweep function covers what it computes: the bytecode of the function and of
# every Python function it reaches (through globals, closures, defaults, partials and the methods
# of classes it uses) that is defined outside the standard library and site-packages (or in
# heelstrike), the values of the closure cells, defaults and bound arguments, the values of the
# referenced globals (and ``module.NAME`` attributes) that are plain data or dataclasses, and the
# source text of every module reached; plus the heelstrike version. Third-party code is
# identified by name only.
_PLAIN_SCALARS = (bool, int, float, complex, str, bytes, type(None), np.generic)
_MAX_DEPTH = 16


def _code_digest(code: types.CodeType, h: Any) -> None:
    h.update(code.co_code)
    h.update(repr(code.co_names).encode())
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            _code_digest(const, h)
        elif isinstance(const, frozenset):
            h.update(repr(sorted(map(repr, const))).encode())
        else:
            h.update(repr(const).encode())


def _code_names(code: types.CodeType) -> set[str]:
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, types.CodeType):
            names |= _code_names(const)
    return names


def _array_token(obj: NDArray[Any]) -> str:
    data = np.ascontiguousarray(obj)
    return f"ndarray({obj.dtype},{obj.shape},{hashlib.sha256(data.tobytes()).hexdigest()})"


def _plain_token(obj: Any, depth: int = 0) -> str | None:
    """Token of plain data (numbers, strings, numeric arrays, containers of them), else None."""
    if depth > _MAX_DEPTH:
        return None
    if isinstance(obj, np.generic):
        return f"{type(obj).__name__}({obj!r})"
    if isinstance(obj, _PLAIN_SCALARS):
        return repr(obj)
    if isinstance(obj, np.ndarray):
        return None if obj.dtype.hasobject else _array_token(obj)
    if isinstance(obj, list | tuple | set | frozenset):
        items = [_plain_token(x, depth + 1) for x in obj]
        parts = [t for t in items if t is not None]
        if len(parts) != len(items):
            return None
        if isinstance(obj, set | frozenset):
            parts.sort()
        return f"{type(obj).__name__}({','.join(parts)})"
    if isinstance(obj, dict):
        pairs = []
        for k, v in obj.items():
            tk, tv = _plain_token(k, depth + 1), _plain_token(v, depth + 1)
            if tk is None or tv is None:
                return None
            pairs.append(f"{tk}:{tv}")
        return "dict(" + ",".join(sorted(pairs)) + ")"
    return None


def _user_module(name: str | None) -> bool:
    """Whether code of module ``name`` is followed (heelstrike and the user's own modules)."""
    if not name:
        return False
    if name.split(".")[0] == "heelstrike":
        return True
    module = sys.modules.get(name)
    path = getattr(module, "__file__", None)
    if path is None:
        return name == "__main__"
    if name.split(".")[0] in sys.stdlib_module_names:
        return False
    real = os.path.realpath(path)
    return not any(real.startswith(root) for root in _library_roots())


def _library_module(module: types.ModuleType) -> bool:
    """Whether a module is the standard library's or an installed package's (not heelstrike,
    not the user's own file, not one made at run time)."""
    name = module.__name__
    if name.split(".")[0] == "heelstrike":
        return False
    if name.split(".")[0] in sys.stdlib_module_names or name in sys.builtin_module_names:
        return True
    path = getattr(module, "__file__", None)
    if path is None:
        return False
    real = os.path.realpath(path)
    return any(real.startswith(root) for root in _library_roots())


@functools.lru_cache(maxsize=1)
def _library_roots() -> tuple[str, ...]:
    """Directories of the standard library and installed third-party packages."""
    paths = sysconfig.get_paths()
    keys = ("stdlib", "platstdlib", "purelib", "platlib")
    return tuple(sorted({os.path.realpath(paths[k]) + os.sep for k in keys if k in paths}))


#: module name -> (the module's spec when read, digest of its source file)
_MODULE_DIGESTS: dict[str, tuple[Any, str]] = {}


def _module_digest(name: str) -> str:
    """SHA-256 of a module's source file, read once per import of the module.

    The file is read the first time a sweep reaches the module and again only after the module
    is re-imported (``importlib.reload``): the digest stands for the code that runs, and edits
    of the file after import (which do not change that code) do not change it.
    """
    module = sys.modules.get(name)
    spec = getattr(module, "__spec__", None)
    cached = _MODULE_DIGESTS.get(name)
    if cached is not None and cached[0] is spec:
        return cached[1]
    path = getattr(module, "__file__", None)
    digest = "no source"
    if path and str(path).endswith(".py"):
        try:
            with open(path, "rb") as f:
                digest = hashlib.sha256(f.read()).hexdigest()
        except OSError:
            pass
    _MODULE_DIGESTS[name] = (spec, digest)
    return digest


class _Identity:
    """Collects the identity of a callable (see the comment above)."""

    def __init__(self) -> None:
        self.parts: dict[str, list[str]] = {
            k: [] for k in ("code", "defaults", "closure", "globals", "bound")
        }
        self.modules: set[str] = set()
        self.seen: set[int] = set()
        #: objects read whose values cannot be identified (``module.var.attr (type)``)
        self.unidentified: set[str] = set()

    def value(self, obj: Any, depth: int = 0) -> str:
        """Deterministic token of a bound value; follows callables and classes."""
        plain = _plain_token(obj)
        if plain is not None:
            return plain
        if depth > _MAX_DEPTH:
            return type(obj).__qualname__
        if isinstance(obj, np.ndarray):  # object arrays
            return "ndarray(" + ",".join(self.value(x, depth + 1) for x in obj.ravel()) + ")"
        if isinstance(obj, list | tuple):
            return f"{type(obj).__name__}({','.join(self.value(x, depth + 1) for x in obj)})"
        if isinstance(obj, dict):
            return "dict(" + ",".join(
                sorted(f"{self.value(k, depth + 1)}:{self.value(v, depth + 1)}"
                       for k, v in obj.items())
            ) + ")"
        if isinstance(obj, type):
            self.klass(obj)
            return f"class {obj.__module__}.{obj.__qualname__}"
        if dataclasses.is_dataclass(obj):  # field by field (a repr may abbreviate arrays)
            self.klass(type(obj))
            fields = ",".join(f"{f.name}={self.value(getattr(obj, f.name), depth + 1)}"
                              for f in dataclasses.fields(obj))
            return f"{type(obj).__module__}.{type(obj).__qualname__}({fields})"
        if isinstance(obj, types.ModuleType):
            if _user_module(obj.__name__):
                self.modules.add(obj.__name__)
            return f"module {obj.__name__}"
        if callable(obj) and (
            isinstance(obj, functools.partial | types.FunctionType | types.MethodType)
            or hasattr(obj, "py_func")
        ):
            self.callable(obj)
            return _func_name(obj)
        if _object_with_state(obj):  # e.g. functools.partial(g, obj=Cfg(k)): its fields
            return self._object_token(obj, f"an argument of type {type(obj).__qualname__}",
                                      depth)
        if not isinstance(obj, type) and _user_module(type(obj).__module__):
            self.klass(type(obj))
        text = repr(obj)
        if " at 0x" in text:  # repr with a memory address is not reproducible
            return type(obj).__qualname__
        return text

    def callable(self, func: Any) -> None:
        while isinstance(func, functools.partial):
            self.parts["bound"].append(self.value(func.args) + self.value(func.keywords))
            func = func.func
        if isinstance(func, types.MethodType):
            self.parts["bound"].append(self.value(func.__self__))
            func = func.__func__
        py_func = getattr(func, "py_func", None)  # numba dispatchers
        if isinstance(py_func, types.FunctionType):
            func = py_func
        if isinstance(func, types.FunctionType):
            self.function(func)
            return
        call = getattr(type(func), "__call__", None)  # noqa: B004
        if isinstance(call, types.FunctionType):  # a callable instance
            self.parts["bound"].append(self.value(func))
            self.function(call)
        else:  # builtins, ufuncs, ...
            self.parts["code"].append(_func_name(func))

    def klass(self, cls: type) -> None:
        if id(cls) in self.seen or not _user_module(cls.__module__):
            return
        self.seen.add(id(cls))
        self.modules.add(cls.__module__)
        for attr in vars(cls).values():
            for f in (attr, getattr(attr, "__func__", None), getattr(attr, "fget", None)):
                if isinstance(f, types.FunctionType):
                    self.function(f)

    def function(self, func: types.FunctionType) -> None:
        if id(func) in self.seen:
            return
        self.seen.add(id(func))
        if not _user_module(func.__module__):
            self.parts["code"].append(_func_name(func))
            return
        self.modules.add(func.__module__)
        h = hashlib.sha256()
        _code_digest(func.__code__, h)
        self.parts["code"].append(f"{_func_name(func)}:{h.hexdigest()}")
        name = func.__qualname__
        self.parts["defaults"].append(
            f"{name}:{self.value(func.__defaults__)}:{self.value(func.__kwdefaults__)}"
        )
        for var, cell in zip(func.__code__.co_freevars, func.__closure__ or (), strict=True):
            try:
                content = cell.cell_contents
            except ValueError:  # empty cell
                content = "<empty>"
            self.parts["closure"].append(f"{name}.{var}={self.value(content)}")
        glb = func.__globals__
        names = sorted(_code_names(func.__code__))
        for var in names:
            if var not in glb:
                continue
            obj = glb[var]
            plain = _plain_token(obj)
            if plain is not None:
                self.parts["globals"].append(f"{func.__module__}.{var}={plain}")
            elif isinstance(obj, types.ModuleType):
                self.value(obj)
                if _library_module(obj):  # numpy, math...: their attributes are code
                    continue
                # ``module.NAME`` read by the code: the name is in the bytecode, its value is
                # not (a config module set at run time, ``helper.SCALE = x``: QA sweep 13)
                for attr in names:
                    token = self._data_token(getattr(obj, attr, None))
                    if token is not None:
                        self.parts["globals"].append(f"{func.__module__}.{var}.{attr}={token}")
            elif isinstance(obj, type) or callable(obj):
                self.value(obj)  # follows code; its name is in the bytecode already
            elif (token := self._data_token(obj)) is not None:
                # e.g. a walker, or a list of walkers: field by field, as an argument
                self.parts["globals"].append(f"{func.__module__}.{var}={token}")
            elif _object_with_state(obj):
                # ``cfg.k`` of a global ``cfg``: the attributes the code reads by name
                token = self._object_token(obj, f"{func.__module__}.{var}", 0, set(names))
                self.parts["globals"].append(f"{func.__module__}.{var}={token}")
            # other objects (heelstrike's models, third-party objects): by name, i.e. through
            # the bytecode only

    def _object_token(
        self, obj: Any, where: str, depth: int, attrs: set[str] | None = None
    ) -> str:
        """Token of an object's instance state (``vars``), or of the attributes ``attrs`` of
        it the code reads; what cannot be identified (a lock, a third-party object) is
        recorded in :attr:`unidentified` under ``where``."""
        cls = type(obj)
        self.klass(cls)
        state = dict(vars(obj))
        if attrs is not None:
            state = {k: v for k, v in state.items() if k in attrs}
        parts = []
        for key in sorted(state):
            v = state[key]
            token = self._data_token(v)
            if token is None and depth < _MAX_DEPTH:
                if isinstance(v, type | types.ModuleType) or callable(v):
                    token = self.value(v, depth + 1)
                elif _object_with_state(v):
                    token = self._object_token(v, f"{where}.{key}", depth + 1)
            if token is None:
                self.unidentified.add(f"{where}.{key} ({type(v).__qualname__})")
                token = type(v).__qualname__
            parts.append(f"{key}={token}")
        return f"{cls.__module__}.{cls.__qualname__}({','.join(parts)})"

    def _data_token(self, obj: Any, depth: int = 0) -> str | None:
        """Token of data: plain data, dataclass instances, and lists, tuples and dicts of
        them; None for anything else (a container holding a lock or a function: state, not
        data, counted by name)."""
        plain = _plain_token(obj)
        if plain is not None:
            return plain
        if depth > _MAX_DEPTH:
            return None
        if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
            return self.value(obj)
        if isinstance(obj, list | tuple):
            items = [self._data_token(x, depth + 1) for x in obj]
            if any(t is None for t in items):
                return None
            return f"{type(obj).__name__}({','.join(items)})"  # type: ignore[arg-type]
        if isinstance(obj, dict):
            pairs = [(self._data_token(k, depth + 1), self._data_token(v, depth + 1))
                     for k, v in obj.items()]
            if any(k is None or v is None for k, v in pairs):
                return None
            return "dict(" + ",".join(sorted(f"{k}:{v}" for k, v in pairs)) + ")"
        return None

    def digest(self) -> dict[str, str]:
        out = {
            k: hashlib.sha256("\n".join(v).encode()).hexdigest() for k, v in self.parts.items()
        }
        if self.unidentified:  # said when a store of this function would be resumed
            out["unidentified"] = "; ".join(sorted(self.unidentified))
        out["modules"] = hashlib.sha256(
            "\n".join(f"{m}:{_module_digest(m)}" for m in sorted(self.modules)).encode()
        ).hexdigest()
        return out


def _object_with_state(obj: Any) -> bool:
    """Whether ``obj`` is an instance whose state (``vars``) the identity reads: an object of
    a class defined outside heelstrike (the user's ``Cfg``, a ``SimpleNamespace``), not a
    class, module, function or dataclass, and not one of heelstrike's own models (identified
    by their code and the data they are built from)."""
    if isinstance(obj, type | types.ModuleType) or dataclasses.is_dataclass(obj):
        return False
    if isinstance(obj, functools.partial | types.FunctionType | types.MethodType):
        return False
    module = type(obj).__module__ or ""
    if module.split(".")[0] in ("heelstrike", "builtins"):
        return False
    try:
        state = vars(obj)
    except TypeError:
        return False
    return isinstance(state, dict)


def _func_name(func: Any) -> str:
    if isinstance(func, functools.partial):
        return f"functools.partial({_func_name(func.func)})"
    module = getattr(func, "__module__", None) or type(func).__module__
    name = getattr(func, "__qualname__", None) or type(func).__qualname__
    return f"{module}.{name}"


def _func_identity(func: Any) -> dict[str, str]:
    """Name and digests (code, defaults, closure, globals, bound arguments, module sources)."""
    ident = _Identity()
    ident.callable(func)
    return {"name": _func_name(func), **ident.digest()}


# -- grid and chunks -----------------------------------------------------------------------------
@dataclass(frozen=True)
class _Plan:
    names: tuple[str, ...]
    values: tuple[NDArray[Any], ...]
    units: dict[str, str]
    coord_attrs: dict[str, dict[str, Any]]
    chunk_sizes: tuple[int, ...]
    n_chunks: tuple[int, ...]

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(v.size for v in self.values)

    def chunk_slices(self, index: tuple[int, ...]) -> tuple[slice, ...]:
        return tuple(
            slice(i * c, min((i + 1) * c, n))
            for i, c, n in zip(index, self.chunk_sizes, self.shape, strict=True)
        )

    def chunk_indices(self) -> Iterator[tuple[int, ...]]:
        return itertools.product(*(range(n) for n in self.n_chunks))

    def chunk_kwargs(self, index: tuple[int, ...]) -> dict[str, NDArray[Any]]:
        d = len(self.names)
        out = {}
        for j, (name, vals, sl) in enumerate(
            zip(self.names, self.values, self.chunk_slices(index), strict=True)
        ):
            shape = [1] * d
            shape[j] = -1
            out[name] = np.array(vals[sl]).reshape(shape)
        return out

    def grid_digest(self) -> str:
        h = hashlib.sha256()
        for name, vals in zip(self.names, self.values, strict=True):
            h.update(name.encode())
            h.update(str(vals.dtype).encode())
            h.update(np.ascontiguousarray(vals).tobytes())
        return h.hexdigest()


def _plan(
    grid: Mapping[str, ArrayLike],
    chunks: int | Mapping[str, int] | None,
    units: Mapping[str, str],
) -> _Plan:
    if not grid:
        raise SweepError("grid is empty: give at least one name -> 1-D array")
    names: list[str] = []
    values: list[NDArray[Any]] = []
    unit_map: dict[str, str] = {str(k): str(v) for k, v in units.items()}
    attrs: dict[str, dict[str, Any]] = {}
    for name, raw in grid.items():
        if not isinstance(name, str) or not name.isidentifier():
            raise SweepError(f"grid names must be Python identifiers, got {name!r}")
        raw_attrs = dict(getattr(raw, "attrs", {}) or {})
        vals = np.asarray(raw)
        if vals.ndim != 1 or vals.size == 0:
            raise SweepError(f"grid[{name!r}] must be a non-empty 1-D array, got {vals.shape}")
        if vals.dtype.kind not in "biuf":
            raise SweepError(f"grid[{name!r}] must be numeric, got dtype {vals.dtype}")
        bad = np.flatnonzero(~np.isfinite(vals))
        if bad.size:
            more = f" (and {bad.size - 1} more)" if bad.size > 1 else ""
            raise SweepError(f"grid[{name!r}] must be finite, got {vals[bad[0]].item()} at "
                             f"index {int(bad[0])}{more}")
        distinct, counts = np.unique(vals, return_counts=True)
        if np.any(counts > 1):
            twice = distinct[counts > 1]
            more = (f" (and {twice.size - 1} more value{'s' if twice.size > 2 else ''})"
                    if twice.size > 1 else "")
            raise SweepError(
                f"grid[{name!r}] repeats {twice[0].item()!r}{more}: every value must be distinct "
                "(a repeated one is computed twice, and selecting it by value is ambiguous)")
        unit = units.get(name, raw_attrs.get("units", KNOWN_UNITS.get(name)))
        if unit is None:
            raise SweepError(
                f"no units for grid coordinate {name!r}: pass units={{{name!r}: ...}} "
                "(use '1' for dimensionless)"
            )
        names.append(name)
        values.append(vals.copy())
        unit_map[name] = str(unit)
        attrs[name] = {**raw_attrs, "units": str(unit)}
    shape = tuple(v.size for v in values)
    if chunks is None:
        # About 2**16 points per chunk: trailing names whole while they fit, then split.
        sizes = [1] * len(shape)
        room = 1 << 16
        for j in reversed(range(len(shape))):
            sizes[j] = max(1, min(shape[j], room))
            room = max(1, room // shape[j])
        chunk_sizes = tuple(sizes)
    elif isinstance(chunks, int | np.integer):
        chunk_sizes = tuple(min(int(chunks), n) for n in shape)
    else:
        unknown = set(chunks) - set(names)
        if unknown:
            raise SweepError(f"chunks names {sorted(unknown)} are not in the grid {names}")
        chunk_sizes = tuple(
            min(int(chunks.get(n, s)), s) for n, s in zip(names, shape, strict=True)
        )
    if any(c < 1 for c in chunk_sizes):
        raise SweepError(f"chunk sizes must be >= 1, got {chunk_sizes}")
    n_chunks = tuple(-(-n // c) for n, c in zip(shape, chunk_sizes, strict=True))
    return _Plan(tuple(names), tuple(values), unit_map, attrs, chunk_sizes, n_chunks)


# -- running one chunk (on a worker) -------------------------------------------------------------
def _run_chunk(
    func: SweepFunction,
    kwargs: dict[str, NDArray[Any]],
    chunk_shape: tuple[int, ...],
    index: tuple[int, ...],
) -> dict[str, NDArray[Any]]:
    try:
        out = func(**kwargs)
    except Exception as exc:  # the caller's own exception, told where in the grid it arose
        exc.add_note(f"in sweep chunk {index}: {_chunk_span(kwargs)}")
        raise
    if not isinstance(out, Mapping):
        raise SweepError(f"sweep function returned {type(out).__name__}, expected a mapping")
    d = len(chunk_shape)
    result: dict[str, NDArray[Any]] = {}
    for name, value in out.items():
        arr = np.asarray(value)
        if arr.ndim < d:
            raise SweepError(
                f"output {name!r} of chunk {index} has {arr.ndim} dims, needs >= {d} "
                f"(chunk shape {chunk_shape})"
            )
        try:
            full = np.broadcast_to(arr, (*chunk_shape, *arr.shape[d:]))
        except ValueError as exc:
            raise SweepError(
                f"output {name!r} of chunk {index} has shape {arr.shape}; its first {d} dims "
                f"must broadcast to the chunk shape {chunk_shape}"
            ) from exc
        result[str(name)] = np.ascontiguousarray(full)
    return result


def _chunk_span(kwargs: dict[str, NDArray[Any]]) -> str:
    """The grid values a chunk covers, ``name lo..hi`` per numeric grid name."""
    parts = []
    for name, value in kwargs.items():
        arr = np.asarray(value)
        if arr.size and np.issubdtype(arr.dtype, np.number):
            lo, hi = float(np.min(arr)), float(np.max(arr))
            parts.append(f"{name} {lo:g}" if lo == hi else f"{name} {lo:g}..{hi:g}")
    return ", ".join(parts) or "(no numeric grid values)"


def _drop(_: object) -> None:
    return None


# -- store ---------------------------------------------------------------------------------------
def _is_sweep_store(path: Path) -> bool:
    if not path.exists():
        return False
    try:
        import zarr

        root = zarr.open_group(str(path), mode="r")
    except Exception:
        return False
    return _IDENTITY_ATTR in root.attrs


class _Store:
    """Zarr store of one sweep: the dataset at the root, the completion record in a subgroup."""

    def __init__(self, path: Path, plan: _Plan, attrs: dict[str, Any]) -> None:
        self.path = path
        self.plan = plan
        self.attrs = attrs
        self.arrays: dict[str, Any] | None = None
        self.done_array: Any = None
        self.checksum_array: Any = None
        self.template: dict[str, tuple[np.dtype[Any], tuple[int, ...]]] | None = None

    def open_existing(self) -> NDArray[np.bool_] | None:
        """Validate an existing store; return its completion record (None: start afresh).

        Metadata restored from the manifest (:func:`_restore_metadata`, by the caller),
        coordinates checked against the grid (rewritten when tampered with), the completion
        record read from the per-chunk records (or the ``done``/``checksum`` arrays of a store
        without them) and every finished chunk verified against its checksum.
        """
        import zarr

        root = zarr.open_group(str(self.path), mode="r+")
        stored = _flatten(json.loads(str(root.attrs[_IDENTITY_ATTR])))
        mine = _flatten(json.loads(self.attrs[_IDENTITY_ATTR]))
        if stored != mine:
            diff = sorted(k for k in set(stored) | set(mine) if stored.get(k) != mine.get(k))
            raise SweepStoreMismatchError(
                f"store {str(self.path)!r} holds a different sweep (differs in: "
                f"{', '.join(diff)}); its results are not what this sweep computes: pass "
                "overwrite=True to compute them again, or use another store",
                differs=diff,
            )
        if _STATE_GROUP not in root:
            return None
        try:
            self._bind(root)
        except Exception as exc:  # metadata damaged and no manifest to restore it from
            raise SweepError(
                f"store {str(self.path)!r}: its metadata is damaged ({type(exc).__name__}: "
                f"{exc}) and it has no intact manifest to restore it from; pass "
                "overwrite=True to compute afresh, or remove the store") from exc
        self._check_coordinates(root)
        records = self._read_records()
        try:
            done = np.asarray(self.done_array[...], dtype=bool)
            sums = np.asarray(self.checksum_array[...], dtype=np.uint8)
            arrays_ok = done.shape == self.plan.n_chunks
        except Exception:  # a truncated or undecodable record array
            arrays_ok = False
        if records or not arrays_ok:
            if not arrays_ok:
                warnings.warn(
                    f"store {str(self.path)!r}: its completion record is damaged; " + (
                        "rebuilt from the per-chunk records of the chunks that verify"
                        if records else
                        "it keeps no per-chunk records: computing every chunk again"),
                    SweepStoreRepairWarning, stacklevel=4)
            done = np.zeros(self.plan.n_chunks, dtype=bool)
            sums = np.zeros((*self.plan.n_chunks, 32), dtype=np.uint8)
            for index, digest in records.items():
                done[index] = True
                sums[index] = np.frombuffer(digest, dtype=np.uint8)
        done = self._verify(done, sums)
        try:  # heal the arrays from what verified (a truncated chunk file is rewritten)
            self.done_array[...] = done.astype(np.uint8)
            self.checksum_array[...] = np.where(done[..., None], sums, 0).astype(np.uint8)
        except Exception as exc:
            raise SweepError(f"store {str(self.path)!r}: cannot rewrite its completion record: "
                             f"{exc}") from exc
        return done

    def _check_coordinates(self, root: Any) -> None:
        """Rewrite coordinate arrays that differ from the grid (the identity's grid digest
        says which values the store holds), with a :class:`SweepStoreRepairWarning`."""
        fixed = []
        for name, vals in zip(self.plan.names, self.plan.values, strict=True):
            arr: Any = None
            try:
                arr = root[name]
                ok = np.array_equal(np.asarray(arr[...]), vals)
            except Exception:  # missing, or a chunk file that does not decode
                ok = False
            if ok:
                continue
            fixed.append(name)
            if arr is None or tuple(arr.shape) != vals.shape:
                raise SweepError(
                    f"store {str(self.path)!r}: coordinate {name!r} is damaged beyond repair "
                    "(its array is missing or of another length); pass overwrite=True to "
                    "compute afresh, or remove the store")
            arr[...] = vals
        if fixed:
            warnings.warn(
                f"store {str(self.path)!r}: coordinate(s) {', '.join(fixed)} did not match the "
                "sweep's grid (edited or damaged); rewritten from the grid",
                SweepStoreRepairWarning, stacklevel=5)

    def _record_dir(self) -> Path:
        return self.path / _STATE_GROUP / _RECORDS

    def _read_records(self) -> dict[tuple[int, ...], bytes]:
        """The per-chunk records that parse (a damaged one: that chunk is computed again)."""
        out: dict[tuple[int, ...], bytes] = {}
        folder = self._record_dir()
        if not folder.is_dir():
            return out
        d = len(self.plan.names)
        for f in folder.iterdir():
            try:
                index = tuple(int(i) for i in f.name.split("_"))
                digest = bytes.fromhex(f.read_text(encoding="ascii").strip())
            except (OSError, ValueError, UnicodeDecodeError):
                continue
            if (len(index) == d and len(digest) == 32 and all(
                    0 <= i < n for i, n in zip(index, self.plan.n_chunks, strict=True))):
                out[index] = digest
        return out

    def _verify(self, done: NDArray[np.bool_], sums: NDArray[np.uint8]) -> NDArray[np.bool_]:
        """Clear the finished chunks whose data do not match their recorded checksum."""
        assert self.arrays is not None
        bad = []
        for index in zip(*np.nonzero(done), strict=True):
            index = tuple(int(i) for i in index)
            region = self.plan.chunk_slices(index)
            try:
                data = {n: np.asarray(a[region]) for n, a in self.arrays.items()}
                ok = _chunk_digest(data) == bytes(sums[index])
            except Exception:  # undecodable chunk file
                ok = False
            if not ok:
                done[index] = False
                bad.append(index)
        if bad:
            shown = ", ".join(map(str, bad[:5])) + (", ..." if len(bad) > 5 else "")
            warnings.warn(
                f"store {str(self.path)!r}: {len(bad)} finished chunk(s) failed checksum "
                f"verification (data deleted or overwritten: {shown}); computing them again",
                SweepStoreRepairWarning,
                stacklevel=5,
            )
            for index in bad:
                with contextlib.suppress(OSError):
                    (self._record_dir() / "_".join(map(str, index))).unlink()
        return done

    def _bind(self, root: Any) -> None:
        self.done_array = root[f"{_STATE_GROUP}/done"]
        self.checksum_array = root[f"{_STATE_GROUP}/checksum"]
        names = [n for n in root.array_keys() if n not in self.plan.names]
        self.arrays = {n: root[n] for n in names}
        self.template = {
            n: (np.dtype(a.dtype), tuple(a.shape[len(self.plan.names):]))
            for n, a in self.arrays.items()
        }

    def create(self, first: Mapping[str, NDArray[Any]], dims: Mapping[str, Sequence[str]]) -> None:
        """Write the template (metadata and coordinates) from the first finished chunk."""
        import dask.array as da
        import zarr

        plan = self.plan
        d = len(plan.names)
        data_vars = {}
        encoding = {}
        for name, arr in first.items():
            trailing = arr.shape[d:]
            var_dims = (*plan.names, *dims[name])
            data_vars[name] = xr.Variable(
                var_dims,
                da.zeros((*plan.shape, *trailing), dtype=arr.dtype,
                         chunks=(*plan.chunk_sizes, *trailing)),
                attrs=_output_attrs(name, plan),
            )
            encoding[name] = {"chunks": (*plan.chunk_sizes, *trailing)}
        ds = xr.Dataset(data_vars, coords=_coords(plan), attrs=self.attrs)
        if self.path.exists():
            shutil.rmtree(self.path)
        ds.to_zarr(str(self.path), mode="w", compute=False, consolidated=False,
                   encoding=encoding)
        root = zarr.open_group(str(self.path), mode="r+")
        state = root.require_group(_STATE_GROUP)
        state.create_array("done", shape=plan.n_chunks, dtype="uint8", chunks=plan.n_chunks,
                           fill_value=0)
        state.create_array("checksum", shape=(*plan.n_chunks, 32), dtype="uint8",
                           chunks=(*plan.n_chunks, 32), fill_value=0)
        self._bind(root)
        self._record_dir().mkdir(parents=True, exist_ok=True)
        _write_manifest(self.path)

    def write(self, index: tuple[int, ...], result: Mapping[str, NDArray[Any]]) -> None:
        assert self.arrays is not None
        region = self.plan.chunk_slices(index)
        stored = {}
        for name, arr in result.items():
            self.arrays[name][region] = arr
            stored[name] = np.asarray(arr).astype(self.arrays[name].dtype, copy=False)
        # the record after the data: a half-written chunk is recomputed
        digest = _chunk_digest(stored)
        write_text(digest.hex() + "\n", self._record_dir() / "_".join(map(str, index)))
        self.checksum_array[index] = np.frombuffer(digest, dtype=np.uint8)
        self.done_array[index] = 1


def _metadata_files(path: Path) -> list[Path]:
    """The store's metadata files (every ``zarr.json``), sorted."""
    return sorted(path.rglob("zarr.json"))


def _manifest_digest(files: Mapping[str, Any]) -> str:
    return hashlib.sha256(json.dumps(files, sort_keys=True).encode()).hexdigest()


def _write_manifest(path: Path) -> None:
    """Write the store's manifest (:data:`_MANIFEST`) of its current metadata files."""
    files = {}
    for f in _metadata_files(path):
        text = f.read_text(encoding="utf-8")
        files[f.relative_to(path).as_posix()] = {
            "sha256": hashlib.sha256(text.encode()).hexdigest(), "text": text}
    write_text(json.dumps({"files": files, "sha256": _manifest_digest(files)}, sort_keys=True),
               path / _MANIFEST)


def _read_manifest(path: Path) -> dict[str, Any] | None:
    """The store's manifest if it is intact (its checksum verifies), else None."""
    try:
        data = json.loads((path / _MANIFEST).read_text(encoding="utf-8"))
        files = data["files"]
        if not isinstance(files, dict) or data["sha256"] != _manifest_digest(files):
            return None
        return files
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _restore_metadata(path: Path) -> None:
    """Restore the store's damaged or missing metadata files from its intact manifest (with a
    :class:`SweepStoreRepairWarning`); write a manifest for a store without an intact one
    whose metadata all parse."""
    files = _read_manifest(path)
    if files is None:
        try:
            for f in _metadata_files(path):
                json.loads(f.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return  # damaged and nothing to restore it from: said when the store is opened
        if (path / "zarr.json").is_file() and (path / _STATE_GROUP).is_dir():
            _write_manifest(path)
        return
    restored = []
    for rel, entry in files.items():
        f = path / rel
        if ".." in Path(rel).parts or Path(rel).name != "zarr.json":
            continue  # a manifest names the store's own metadata files only
        try:
            ok = hashlib.sha256(f.read_bytes()).hexdigest() == entry["sha256"]
        except OSError:
            ok = False
        if not ok:
            write_text(str(entry["text"]), f)
            restored.append(rel)
    if restored:
        warnings.warn(
            f"store {str(path)!r}: metadata file(s) {', '.join(restored)} were damaged or "
            "missing; restored from the store's manifest", SweepStoreRepairWarning,
            stacklevel=4)


def _chunk_digest(data: Mapping[str, NDArray[Any]]) -> bytes:
    """SHA-256 of a chunk's outputs (names, dtypes, shapes and bytes) as stored."""
    h = hashlib.sha256()
    for name in sorted(data):
        arr = np.ascontiguousarray(data[name])
        h.update(f"{name}|{arr.dtype.str}|{arr.shape}|".encode())
        h.update(arr.tobytes())
    return h.digest()


def _lock_path(path: Path) -> Path:
    """The lock file of a store: a sibling ``<store>.lock`` (it outlives a replaced store)."""
    return path.with_name(path.name + ".lock")


def _lock_store(path: Path, timeout: float | None) -> Any:
    """Acquire the exclusive lock of store ``path`` (a :class:`filelock.FileLock`)."""
    filelock = require("filelock", "a sweep store (store=...)")
    lock_file = _lock_path(path)
    try:
        lock_file.parent.mkdir(parents=True, exist_ok=True)
        with open(lock_file, "a"):  # fails here (not as a timeout) where we cannot write
            pass
        lock = filelock.FileLock(str(lock_file), timeout=-1 if timeout is None else timeout)
        lock.acquire()
    except filelock.Timeout:
        raise SweepStoreLockedError(
            f"store {str(path)!r} is in use by another sweep (lock file {str(lock_file)!r} is "
            "held); wait for it to finish, or pass lock_timeout to wait for it"
        ) from None
    except OSError as exc:
        raise SweepError(
            f"cannot lock store {str(path)!r} ({str(lock_file)!r}): {exc.strerror or exc}"
        ) from exc
    return lock


def _flatten(obj: Any, prefix: str = "") -> dict[str, Any]:
    """``{"a": {"b": 1}}`` -> ``{"a.b": 1}``."""
    if not isinstance(obj, dict):
        return {prefix: obj}
    out: dict[str, Any] = {}
    for k, v in obj.items():
        out.update(_flatten(v, f"{prefix}.{k}" if prefix else str(k)))
    return out


def _coords(plan: _Plan) -> dict[str, xr.Variable]:
    return {
        n: xr.Variable((n,), v, attrs=plan.coord_attrs[n])
        for n, v in zip(plan.names, plan.values, strict=True)
    }


def _output_attrs(name: str, plan: _Plan) -> dict[str, str]:
    unit = plan.units.get(name, KNOWN_UNITS.get(name))
    return {} if unit is None else {"units": unit}


def _heelstrike_version() -> str:
    try:
        from importlib.metadata import version

        return version("heelstrike")
    except Exception:  # pragma: no cover - not installed
        return "unknown"


# -- schedulers ----------------------------------------------------------------------------------
def _run_local(
    func: SweepFunction,
    plan: _Plan,
    pending: list[tuple[int, ...]],
    scheduler: str,
    num_workers: int | None,
    on_result: Callable[[tuple[int, ...], dict[str, NDArray[Any]]], None],
    token: str,
) -> None:
    if scheduler not in ("processes", "multiprocessing") and not available("dask"):
        _run_plain(func, plan, pending, scheduler, num_workers, on_result)
        return
    dask = require("dask", f"the {scheduler!r} Dask scheduler")
    from dask.callbacks import Callback

    keys: dict[str, tuple[int, ...]] = {}
    sinks = []
    for index in pending:
        key = f"heelstrike-sweep-{token}-" + "-".join(map(str, index))
        keys[key] = index
        shape = tuple(s.stop - s.start for s in plan.chunk_slices(index))
        task = dask.delayed(_run_chunk, pure=True)(
            func, plan.chunk_kwargs(index), shape, index, dask_key_name=key
        )
        sinks.append(dask.delayed(_drop, pure=True)(task, dask_key_name=key + "-sink"))

    def posttask(key: Any, result: Any, dsk: Any, state: Any, worker_id: Any) -> None:
        index = keys.get(key if isinstance(key, str) else str(key))
        if index is not None:
            on_result(index, result)

    kwargs: dict[str, Any] = {"scheduler": scheduler, "optimize_graph": False}
    if num_workers is not None:
        kwargs["num_workers"] = num_workers
    if scheduler in ("processes", "multiprocessing"):  # workers end when this process dies
        kwargs["initializer"] = functools.partial(_end_with_parent, os.getpid())
    with Callback(posttask=posttask):
        dask.compute(*sinks, **kwargs)


#: Seconds between a process-pool worker's checks that its parent is alive.
_PARENT_POLL = 0.5


def _end_with_parent(parent: int) -> None:
    """Initializer of a sweep's process-pool workers: end the worker when its parent dies.

    A parent killed with SIGKILL cannot stop its pool, and its workers (and with them
    multiprocessing's resource tracker, which waits for them) would run on. A daemon thread
    polls :func:`os.getppid` every :data:`_PARENT_POLL` s and ends the worker with
    :func:`os._exit` once the parent is gone (the worker is re-parented).
    """
    import threading
    import time

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(_PARENT_POLL)
        os._exit(1)

    if os.getppid() != parent:
        os._exit(1)
    threading.Thread(target=watch, name="heelstrike-parent-watch", daemon=True).start()


def _run_plain(
    func: SweepFunction,
    plan: _Plan,
    pending: list[tuple[int, ...]],
    scheduler: str,
    num_workers: int | None,
    on_result: Callable[[tuple[int, ...], dict[str, NDArray[Any]]], None],
) -> None:
    """Local threads (or the calling thread for ``"sync"``) without Dask (light install)."""
    from concurrent.futures import ThreadPoolExecutor, as_completed

    def args(index: tuple[int, ...]) -> tuple[Any, ...]:
        shape = tuple(s.stop - s.start for s in plan.chunk_slices(index))
        return func, plan.chunk_kwargs(index), shape, index

    if scheduler in ("sync", "synchronous", "single-threaded"):
        for index in pending:
            on_result(index, _run_chunk(*args(index)))
        return
    with ThreadPoolExecutor(max_workers=num_workers or os.cpu_count()) as pool:
        futures = {pool.submit(_run_chunk, *args(index)): index for index in pending}
        try:
            for fut in as_completed(futures):
                on_result(futures[fut], fut.result())
        finally:
            for fut in futures:  # interrupted: start no further chunk
                fut.cancel()


def _run_distributed(
    func: SweepFunction,
    plan: _Plan,
    pending: list[tuple[int, ...]],
    client: Any,
    on_result: Callable[[tuple[int, ...], dict[str, NDArray[Any]]], None],
    token: str,
) -> None:
    import uuid

    from distributed import as_completed

    # Keys are unique per run: a previous run's keys may still be being forgotten by the
    # scheduler (released or cancelled), and reusing them could leave a future that never ends.
    run_id = uuid.uuid4().hex
    futures = {}
    for index in pending:
        key = f"heelstrike-sweep-{token}-{run_id}-" + "-".join(map(str, index))
        shape = tuple(s.stop - s.start for s in plan.chunk_slices(index))
        fut = client.submit(_run_chunk, func, plan.chunk_kwargs(index), shape, index,
                            key=key, pure=False)
        futures[fut.key] = (fut, index)
    try:
        for fut, result in as_completed([f for f, _ in futures.values()], with_results=True):
            on_result(futures[fut.key][1], result)
            fut.release()
    finally:
        unfinished = [f for f, _ in futures.values() if not f.done()]
        if unfinished:  # interrupted: do not leave work running on the cluster
            client.cancel(unfinished)


def _resolve_client(scheduler: Any) -> tuple[Any, bool] | None:
    """``(client, owned)`` for a distributed scheduler, None for a local one."""
    if scheduler is None or (isinstance(scheduler, str) and scheduler in _LOCAL_SCHEDULERS):
        return None
    Client = require("distributed", "a Dask cluster scheduler").Client

    if isinstance(scheduler, Client):
        return scheduler, False
    if isinstance(scheduler, str):
        if "://" not in scheduler:
            raise SweepError(
                f"scheduler {scheduler!r} is neither a local scheduler "
                f"{_LOCAL_SCHEDULERS} nor an address like 'tcp://host:8786'"
            )
        return Client(scheduler), True
    if hasattr(scheduler, "scheduler_address"):  # e.g. distributed.LocalCluster
        return Client(scheduler), True
    raise SweepError(f"unsupported scheduler {scheduler!r}")


# -- public --------------------------------------------------------------------------------------
def sweep(
    func: SweepFunction,
    grid: Mapping[str, ArrayLike],
    *,
    chunks: int | Mapping[str, int] | None = None,
    store: str | os.PathLike[str] | None = None,
    scheduler: str | Any | None = None,
    progress: bool | str = True,
    units: Mapping[str, str] | None = None,
    output_dims: Mapping[str, Sequence[str]] | None = None,
    num_workers: int | None = None,
    overwrite: bool = False,
    lock_timeout: float | None = 0.0,
) -> xr.Dataset:
    """Evaluate ``func`` on the outer product of ``grid``, chunked, with Dask; optionally resumable.

    Parameters
    ----------
    func : callable
        Pure vectorized function ``func(**kwargs) -> {output name: array}``; the exact contract
        is in the module docstring (open-mesh keyword arrays broadcasting to the chunk shape;
        outputs of the chunk shape plus optional trailing dimensions).
    grid : mapping of str to 1-D array_like
        Grid name -> values, in axis order; the sweep covers the full outer product, shape
        ``(len(v_0), ..., len(v_{d-1}))``. Values may be :class:`xarray.DataArray` whose
        ``attrs`` (e.g. ``units``) are kept on the coordinate.
    chunks : int or mapping of str to int, optional
        Chunk length per grid name (names left out are not split), or one length for all.
        Default: about 65536 points per chunk, split along the leading names.
    store : path, optional
        Zarr directory. Each chunk is written as soon as it finishes and recorded as done, with
        a SHA-256 checksum of its data; if the store holds a run of the same sweep, only the
        missing chunks are computed, and finished chunks whose data fail their checksum (deleted
        or overwritten files) are computed again, with a :class:`SweepStoreRepairWarning`.
        "The same sweep" means the same grid, chunks, heelstrike version and function identity:
        the function's name and bytecode and those of every Python function it reaches outside
        the standard library and site-packages (and in heelstrike), through globals, closures,
        defaults, partials and the methods of classes it uses; the values of its closure cells,
        defaults and bound arguments; the referenced module globals that are plain data
        (numbers, strings, numeric arrays and containers of them), dataclasses (a
        ``CompassGait``, field by field) or lists, tuples and dicts of them, and the values
        of module attributes the code reads as ``module.NAME`` when they are plain data or
        dataclasses (``config.SCALE`` set at run time); and the source text of every module
        reached. Objects of the user's own classes (and other objects with instance state,
        such as a ``SimpleNamespace``) count by their state: all of it when bound (a
        ``functools.partial`` argument, a closure cell), the attributes the code reads by name
        when global (``cfg.k``); state that cannot be identified (a lock, a third-party object)
        is named in ``function.unidentified``, and a store of such a function is not resumed
        (:class:`SweepError` naming it; ``overwrite=True`` computes afresh). Other objects
        (third-party functions, heelstrike's models) count by name only. A store of a
        different sweep raises :class:`SweepStoreMismatchError` naming what differs (e.g.
        ``function.closure``), unless ``overwrite=True`` (compute afresh).
        The store is identified by its real path (a symlink to a store is that store). While
        the sweep runs it holds an exclusive lock, the file ``<store>.lock`` beside the real
        store (:mod:`filelock`), so a second sweep on the same store cannot interleave with it.
        Its metadata are verifiable: a checksummed manifest of every ``zarr.json`` restores a
        damaged or missing one, a record file per finished chunk (its checksum) rebuilds a
        damaged completion record from the chunks that still verify, and coordinates that no
        longer match the grid are rewritten from it, each with a
        :class:`SweepStoreRepairWarning`.
    scheduler : str, distributed.Client or cluster, optional
        ``None`` or ``"threads"`` (default): Dask's local thread pool; ``"processes"``: local
        process pool; ``"sync"``: in the calling thread. A scheduler address
        (``"tcp://host:8786"``), a :class:`distributed.Client` or a cluster object (e.g.
        :class:`distributed.LocalCluster`) runs the chunks on that cluster; results are written
        by the calling process, so workers need no access to ``store``. Without Dask (the light
        install) ``"threads"`` and ``"sync"`` run on a :mod:`concurrent.futures` thread pool
        with the same results; ``"processes"``, clusters and ``store`` need the ``scale`` extra
        (``pip install '.[scale]'`` in a clone of heelstrike).
    progress : bool or str
        Show a tqdm progress bar over chunks (default True), labelled ``sweep <function>``;
        a string shows it with that label (e.g. ``"basin of attraction"``).
    units : mapping of str to str, optional
        Units of grid names and outputs (UDUNITS strings, ``"1"`` for dimensionless). Defaults
        come from :data:`KNOWN_UNITS`; every grid coordinate must end up with units.
    output_dims : mapping of str to sequence of str, optional
        Names of the trailing dimensions of outputs that have them (default
        ``"<output>_dim<j>"``).
    num_workers : int, optional
        Worker count of the local thread or process pool (Dask's default: the CPU count).
    overwrite : bool
        Replace an existing store instead of resuming or refusing it.
    lock_timeout : float or None
        Seconds to wait for another sweep holding ``store``'s lock: 0 (default) fails at once
        with :class:`SweepStoreLockedError`, ``None`` waits as long as it takes.

    Returns
    -------
    xarray.Dataset
        Dimensions are the grid names (coordinates with ``units`` attrs) plus any trailing
        output dimensions; one variable per output. ``attrs`` hold ``heelstrike_version``,
        ``sweep_function`` and ``sweep_identity`` (JSON: function, code digest, grid digest,
        chunks). With ``store`` the dataset is opened lazily from the store.

    Raises
    ------
    SweepError
        Invalid grid, chunks or function output; a non-sweep directory at ``store``.
    SweepStoreMismatchError
        ``store`` holds a different sweep.
    SweepStoreLockedError
        Another sweep holds ``store``'s lock (for longer than ``lock_timeout``).
    heelstrike._optional.MissingExtraError
        ``store``, ``"processes"`` or a cluster without the ``scale`` extra installed.
    """
    lock = None
    if store is not None:
        require("zarr", "a sweep store (store=...)")
        require("dask.array", "a sweep store (store=...)")
        # the store's real path: a symlink to a store takes the store's own lock
        store = Path(os.path.realpath(os.fspath(store)))
        lock = _lock_store(store, lock_timeout)
    try:
        return _sweep(func, grid, chunks=chunks, store=store, scheduler=scheduler,
                      progress=progress, units=units, output_dims=output_dims,
                      num_workers=num_workers, overwrite=overwrite)
    finally:
        if lock is not None:
            lock.release()


def _sweep(
    func: SweepFunction,
    grid: Mapping[str, ArrayLike],
    *,
    chunks: int | Mapping[str, int] | None,
    store: str | os.PathLike[str] | None,
    scheduler: str | Any | None,
    progress: bool | str,
    units: Mapping[str, str] | None,
    output_dims: Mapping[str, Sequence[str]] | None,
    num_workers: int | None,
    overwrite: bool,
) -> xr.Dataset:
    """:func:`sweep` with the store (if any) locked by the caller."""
    plan = _plan(grid, chunks, dict(units or {}))
    function = _func_identity(func)
    ident = {
        "format": 2,
        "heelstrike_version": _heelstrike_version(),
        "function": function,
        "grid": {"names": list(plan.names), "sha256": plan.grid_digest()},
        "chunks": list(plan.chunk_sizes),
    }
    ident_json = json.dumps(ident, sort_keys=True)
    token = hashlib.sha256(ident_json.encode()).hexdigest()[:12] + "-" + uuid.uuid4().hex[:8]
    attrs = {
        "heelstrike_version": _heelstrike_version(),
        "sweep_function": _func_name(func),
        _IDENTITY_ATTR: ident_json,
    }
    dims = dict(output_dims or {})
    all_chunks = list(plan.chunk_indices())
    done = np.zeros(plan.n_chunks, dtype=bool)

    st: _Store | None = None
    if store is not None:
        path = Path(os.fspath(store))
        st = _Store(path, plan, attrs)
        # only a sweep store is ever removed: overwrite=True once deleted any folder given as
        # the store, with whatever it held (QA sweep 13)
        if path.is_dir() and not any(path.iterdir()):
            path.rmdir()  # an empty folder made for the store: the store is made there
        if path.is_dir() and not overwrite:
            _restore_metadata(path)
        if path.exists() and not _is_sweep_store(path):
            raise SweepError(
                f"{str(path)!r} exists and is not a heelstrike sweep store "
                f"({'a file' if not path.is_dir() else 'a folder'}): "
                "remove it or choose another store (overwriting replaces only a sweep store)"
            )
        if path.exists() and overwrite:
            shutil.rmtree(path)
        elif path.exists():
            record = st.open_existing()
            if record is not None:
                done = record
            unknown = function.get("unidentified")
            if unknown and done.any():
                raise SweepError(
                    f"store {str(path)!r} cannot be resumed: the sweep function reads objects "
                    f"whose values cannot be identified ({unknown}), so a change to them would "
                    "resume stale results; pass overwrite=True to compute afresh, or give the "
                    "function those values as plain data (numbers, arrays, dataclasses)")
    pending = [i for i in all_chunks if not done[i]]
    if st is not None:
        _log.info("store %s: %d of %d chunks already done, computing %d", st.path,
                  len(all_chunks) - len(pending), len(all_chunks), len(pending))

    memory: dict[str, NDArray[Any]] = {}
    d = len(plan.names)
    template: dict[str, tuple[np.dtype[Any], tuple[int, ...]]] | None = (
        None if st is None else st.template
    )

    def check(index: tuple[int, ...], result: Mapping[str, NDArray[Any]]) -> None:
        nonlocal template
        clash = set(result) & set(plan.names)
        if clash:
            raise SweepError(f"output names {sorted(clash)} clash with grid names")
        got = {n: (a.dtype, a.shape[d:]) for n, a in result.items()}
        if template is None:
            template = got
            for name, (_, trailing) in got.items():
                given = tuple(dims.get(name, ()))
                if given and len(given) != len(trailing):
                    raise SweepError(
                        f"output_dims[{name!r}] names {len(given)} dims, the output has "
                        f"{len(trailing)} trailing dims"
                    )
                dims[name] = given or tuple(f"{name}_dim{j}" for j in range(len(trailing)))
            return
        if set(got) != set(template) or any(
            got[n][1] != template[n][1] or got[n][0] != template[n][0] for n in got
        ):
            raise SweepError(
                f"chunk {index} returned outputs {_describe(got)}, earlier chunks "
                f"{_describe(template)}: names, dtypes and trailing shapes must not vary"
            )

    def on_result(index: tuple[int, ...], result: dict[str, NDArray[Any]]) -> None:
        check(index, result)
        if st is not None:
            if st.arrays is None:
                st.create(result, dims)
            st.write(index, result)
        else:
            if not memory:
                for name, arr in result.items():
                    memory[name] = np.empty((*plan.shape, *arr.shape[d:]), dtype=arr.dtype)
            region = plan.chunk_slices(index)
            for name, arr in result.items():
                memory[name][region] = arr
        bar.update(1)

    from heelstrike._progress import progress_bar

    bar = progress_bar(
        total=len(all_chunks),
        initial=len(all_chunks) - len(pending),
        enabled=bool(progress),
        desc=progress if isinstance(progress, str) else f"sweep {_func_name(func)}",
        unit="chunk",
        delay=0.0,
        leave=True,
    )
    try:
        if pending:
            resolved = _resolve_client(scheduler)
            if resolved is None:
                _run_local(func, plan, pending, scheduler or "threads", num_workers, on_result,
                           token)
            else:
                client, owned = resolved
                try:
                    _run_distributed(func, plan, pending, client, on_result, token)
                finally:
                    if owned:
                        client.close()
    finally:
        bar.close()

    if st is not None:
        return xr.open_zarr(str(st.path), consolidated=False)
    assert template is not None
    data_vars = {
        name: xr.Variable((*plan.names, *dims[name]), arr, attrs=_output_attrs(name, plan))
        for name, arr in memory.items()
    }
    return xr.Dataset(data_vars, coords=_coords(plan), attrs=attrs)


def sweep_progress(store: str | os.PathLike[str]) -> tuple[int, int]:
    """``(finished, total)`` chunk counts recorded in a sweep store.

    Raises
    ------
    SweepError
        If ``store`` is not a heelstrike sweep store.
    """
    zarr = require("zarr", "a sweep store")

    path = Path(os.fspath(store))
    if not _is_sweep_store(path):
        raise SweepError(f"{str(path)!r} is not a heelstrike sweep store")
    root = zarr.open_group(str(path), mode="r")
    if _STATE_GROUP not in root:
        return 0, 0
    done_array: Any = root[f"{_STATE_GROUP}/done"]
    records = path / _STATE_GROUP / _RECORDS
    if records.is_dir():  # the per-chunk records (the array may be damaged)
        return sum(1 for _ in records.iterdir()), int(np.prod(done_array.shape))
    done = np.asarray(done_array[...])
    return int(done.sum()), int(done.size)


def _describe(t: Mapping[str, tuple[np.dtype[Any], tuple[int, ...]]]) -> str:
    return ", ".join(f"{n}: {dt} trailing {sh}" for n, (dt, sh) in sorted(t.items()))
