"""Chunked, resumable parameter sweeps over the outer product of 1-D grids.

:func:`sweep` evaluates a pure, vectorized function on the full outer product of named 1-D grids
(walker parameters, initial states, slopes, ...), chunk by chunk, with Dask: local threads or
processes, or a ``dask.distributed`` cluster. With a ``store`` every finished chunk is written to
Zarr at once and recorded, so an interrupted sweep resumes where it stopped and never recomputes
a finished chunk.

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

import functools
import hashlib
import itertools
import json
import os
import shutil
import types
import uuid
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "KNOWN_UNITS",
    "SweepError",
    "SweepFunction",
    "SweepStoreMismatchError",
    "sweep",
    "sweep_progress",
]

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
_LOCAL_SCHEDULERS = ("threads", "threading", "processes", "multiprocessing", "sync",
                     "synchronous", "single-threaded")


class SweepError(RuntimeError):
    """A sweep cannot run: bad grid, bad function output or unusable store."""


class SweepStoreMismatchError(SweepError):
    """The store holds a sweep of a different grid, chunking or function."""


# -- identity ------------------------------------------------------------------------------------
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


def _token(obj: Any) -> str:
    """Deterministic (across processes) description of a bound argument."""
    if isinstance(obj, np.ndarray):
        return f"ndarray({obj.dtype},{obj.shape},{hashlib.sha256(obj.tobytes()).hexdigest()})"
    if isinstance(obj, list | tuple):
        return f"{type(obj).__name__}({','.join(_token(x) for x in obj)})"
    if isinstance(obj, dict):
        return "dict(" + ",".join(f"{k!r}:{_token(v)}" for k, v in sorted(obj.items())) + ")"
    if callable(obj) and hasattr(obj, "__qualname__"):
        return _func_name(obj)
    text = repr(obj)
    if " at 0x" in text:  # repr with a memory address is not reproducible
        return type(obj).__qualname__
    return text


def _func_name(func: Any) -> str:
    if isinstance(func, functools.partial):
        return f"functools.partial({_func_name(func.func)})"
    module = getattr(func, "__module__", None) or type(func).__module__
    name = getattr(func, "__qualname__", None) or type(func).__qualname__
    return f"{module}.{name}"


def _func_identity(func: Any) -> dict[str, str]:
    h = hashlib.sha256()
    inner = func
    bound: list[str] = []
    while isinstance(inner, functools.partial):
        bound.append(_token(inner.args) + _token(inner.keywords))
        inner = inner.func
    code = getattr(inner, "__code__", None)
    if code is None:
        code = getattr(getattr(inner, "__call__", None), "__code__", None)  # noqa: B004
    if isinstance(code, types.CodeType):
        _code_digest(code, h)
    return {"name": _func_name(func), "code_sha256": h.hexdigest(), "bound": "|".join(bound)}


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
    out = func(**kwargs)
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
        self.template: dict[str, tuple[np.dtype[Any], tuple[int, ...]]] | None = None

    def open_existing(self) -> NDArray[np.bool_] | None:
        """Validate an existing store; return its completion record (None: start afresh)."""
        import zarr

        root = zarr.open_group(str(self.path), mode="r+")
        stored = json.loads(str(root.attrs[_IDENTITY_ATTR]))
        mine = json.loads(self.attrs[_IDENTITY_ATTR])
        if stored != mine:
            diff = sorted(k for k in set(stored) | set(mine) if stored.get(k) != mine.get(k))
            raise SweepStoreMismatchError(
                f"store {str(self.path)!r} holds a different sweep (differs in: "
                f"{', '.join(diff)}); pass overwrite=True or use another store"
            )
        if _STATE_GROUP not in root:
            return None
        self._bind(root)
        return np.asarray(self.done_array[...], dtype=bool)

    def _bind(self, root: Any) -> None:
        self.done_array = root[f"{_STATE_GROUP}/done"]
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
        self._bind(root)

    def write(self, index: tuple[int, ...], result: Mapping[str, NDArray[Any]]) -> None:
        assert self.arrays is not None
        region = self.plan.chunk_slices(index)
        for name, arr in result.items():
            self.arrays[name][region] = arr
        self.done_array[index] = 1  # after the data: a half-written chunk is recomputed


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
    import dask
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
    with Callback(posttask=posttask):
        dask.compute(*sinks, **kwargs)


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
    from distributed import Client

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
    progress: bool = True,
    units: Mapping[str, str] | None = None,
    output_dims: Mapping[str, Sequence[str]] | None = None,
    num_workers: int | None = None,
    overwrite: bool = False,
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
        Zarr directory. Each chunk is written as soon as it finishes and recorded as done; if the
        store holds an unfinished run of the same sweep (same grid, chunks, function name, code
        and bound arguments) only the missing chunks are computed. A store of a different sweep
        raises :class:`SweepStoreMismatchError` unless ``overwrite=True``.
    scheduler : str, distributed.Client or cluster, optional
        ``None`` or ``"threads"`` (default): Dask's local thread pool; ``"processes"``: local
        process pool; ``"sync"``: in the calling thread. A scheduler address
        (``"tcp://host:8786"``), a :class:`distributed.Client` or a cluster object (e.g.
        :class:`distributed.LocalCluster`) runs the chunks on that cluster; results are written
        by the calling process, so workers need no access to ``store``.
    progress : bool
        Show a tqdm progress bar over chunks (default True).
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
    """
    plan = _plan(grid, chunks, dict(units or {}))
    ident = {
        "function": _func_identity(func),
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
        if path.exists() and overwrite:
            shutil.rmtree(path)
        elif path.exists():
            if not _is_sweep_store(path):
                raise SweepError(
                    f"{str(path)!r} exists and is not a heelstrike sweep store; remove it or "
                    "pass overwrite=True"
                )
            record = st.open_existing()
            if record is not None:
                done = record
    pending = [i for i in all_chunks if not done[i]]

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

    from tqdm.auto import tqdm

    bar = tqdm(
        total=len(all_chunks),
        initial=len(all_chunks) - len(pending),
        disable=not progress,
        desc=f"sweep {_func_name(func)}",
        unit="chunk",
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
    import zarr

    path = Path(os.fspath(store))
    if not _is_sweep_store(path):
        raise SweepError(f"{str(path)!r} is not a heelstrike sweep store")
    root = zarr.open_group(str(path), mode="r")
    if _STATE_GROUP not in root:
        return 0, 0
    done_array: Any = root[f"{_STATE_GROUP}/done"]
    done = np.asarray(done_array[...])
    return int(done.sum()), int(done.size)


def _describe(t: Mapping[str, tuple[np.dtype[Any], tuple[int, ...]]]) -> str:
    return ", ".join(f"{n}: {dt} trailing {sh}" for n, (dt, sh) in sorted(t.items()))
