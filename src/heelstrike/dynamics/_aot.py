"""Compiled kernels ahead of time: one numba source, an extension module that loads without numba.

The compiled backends' kernels are numba functions. Called through numba's JIT they cost every
new process the numba floor (importing numba, its typing registries and scipy.linalg, then
loading each kernel from numba's disk cache: about 0.5 s on the reference machine, more than the
whole of ``heelstrike impact --json``). For the serial entry points this module compiles the
*same* Python functions once, ahead of time, with numba's ``pycc`` into a CPython extension
module in heelstrike's cache, and later processes import that module directly: no numba, no
LLVM, no typing at run time. The arithmetic is numba's, so results are identical to the JIT
kernels' bit for bit (``tests/test_aot.py`` checks it walk by walk).

- A library (:class:`AotLibrary`) lists its exports with explicit numba signatures; the module
  name carries a digest of everything the machine code depends on (the kernel sources, the
  numba version, the Python ABI, the signatures, a caller key such as a generated walker's),
  so an edited kernel is rebuilt and never confused with an old one.
- Built modules live in ``<cache>/aot/`` (:func:`heelstrike.models._generated.cache_dir`). A
  module is machine code: it is loaded only if it and its folder are owned by the current user,
  not symbolic links and writable by nobody else (the rules of the generated-code cache).
  Builds write into a private temporary folder and move the result into place atomically.
- The generic x86-64 (or host-architecture baseline) target is used, not the build machine's
  CPU, so a cache shared between machines stays valid; on the reference machine the generic
  kernel runs at the JIT's speed.
- Every call checks the array arguments against the declared signature (dtype, dimensions,
  C order) before entering machine code that trusts them.
- ``HEELSTRIKE_AOT=0`` turns the tier off (numba's JIT is used); ``HEELSTRIKE_AOT=all`` also
  builds modules that are otherwise left to the JIT (a described walker of your own: see
  :mod:`heelstrike.dynamics.compiled_phased`). If a build fails (no C compiler, a numba
  without ``pycc``), a :class:`AotWarning` says so once and the JIT is used.

The parallel (``prange``) entry points stay on numba's JIT: ``pycc`` compiles serial code only.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.machinery
import importlib.util
import os
import re
import sys
import sysconfig
import tempfile
import threading
import time
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from heelstrike._firstuse import HEARTBEAT
from heelstrike.models._generated import _unsafe, cache_dir, numba_fingerprint

__all__ = [
    "AotExport",
    "AotLibrary",
    "AotWarning",
    "aot_enabled",
    "aot_mode",
    "compile_seconds",
    "load_library",
    "track_numba_compiles",
]

#: Bumped when the layout of built modules changes.
_FORMAT = "heelstrike-aot-1"
#: Environment variable: ``0`` (or ``false``, ``no``, ``off``) disables the ahead-of-time tier,
#: ``all`` builds every library asked for (default: the libraries their callers build).
ENV = "HEELSTRIKE_AOT"


class AotWarning(UserWarning):
    """The ahead-of-time kernels could not be built or loaded; numba's JIT is used instead."""


_DTYPES = {"f8": np.dtype(np.float64), "i8": np.dtype(np.int64), "b1": np.dtype(np.bool_)}


def _array_rank(spec: str) -> tuple[np.dtype[Any], int] | None:
    """``(dtype, ndim)`` of an array type string such as ``f8[:,::1]``; None for a scalar."""
    m = re.fullmatch(r"(f8|i8|b1)\[((?::,\s*)*)::1\]", spec.replace(" ", ""))
    if m is None:
        if re.fullmatch(r"f8|i8|b1", spec):
            return None
        raise ValueError(f"unsupported ahead-of-time argument type {spec!r} (use C-order arrays "
                         "such as f8[:,::1], or the scalars f8, i8, b1)")
    return _DTYPES[m.group(1)], m.group(2).count(":") + 1


@dataclass(frozen=True, kw_only=True)
class AotExport:
    """One exported function of an ahead-of-time library.

    Attributes
    ----------
    name : str
        Its name in the extension module (and on the loaded library).
    args : tuple of str
        numba types of the arguments: ``f8``, ``i8``, ``b1`` or C-order arrays of them
        (``f8[::1]``, ``f8[:,::1]``, ``i8[::1]``, ...).
    returns : str
        numba type of the result, e.g. ``void``, ``f8``, ``UniTuple(f8, 2)``,
        ``Tuple((i8, f8, f8))``.
    """

    name: str
    args: tuple[str, ...]
    returns: str

    @property
    def signature(self) -> str:
        """The numba signature string, ``returns(args...)``."""
        return f"{self.returns}({', '.join(self.args)})"


@dataclass(frozen=True, kw_only=True)
class AotLibrary:
    """A set of kernels compiled together into one extension module.

    Attributes
    ----------
    name : str
        Short name (letters, digits, underscores), part of the module name.
    exports : tuple of AotExport
        The exported functions and their signatures.
    functions : callable
        ``functions() -> {export name: numba dispatcher or Python function}``: the functions to
        compile. Called only to build (it may import numba); for a dispatcher its Python
        function is compiled.
    source_modules : tuple of str
        Modules whose source files define the compiled code (their bytes enter the digest).
    key : str
        Further digest input, e.g. the key of a walker's generated code.
    kind : str
        Kind of build for the first-use estimate (a key of :data:`heelstrike._firstuse.KINDS`).
    size : callable or None
        ``size() -> float``: the build's size in the kind's unit (None: the lines of the
        source modules).
    what : str
        What the build makes, in words (default: "the <name> kernels, compiled ahead of time").
    """

    name: str
    exports: tuple[AotExport, ...]
    functions: Callable[[], Mapping[str, Any]]
    source_modules: tuple[str, ...]
    key: str = ""
    kind: str = "aot-compass"
    size: Callable[[], float] | None = None
    what: str = ""


class _Checked:
    """A loaded library: each export behind a check of its array arguments."""

    def __init__(self, module: ModuleType, exports: tuple[AotExport, ...], path: Path) -> None:
        self.module = module
        self.path = path
        for e in exports:
            setattr(self, e.name, _checked(getattr(module, e.name), e))


def _checked(fn: Callable[..., Any], export: AotExport) -> Callable[..., Any]:
    arrays = [(i, spec) for i, spec in enumerate(_array_rank(a) for a in export.args)
              if spec is not None]
    n_args = len(export.args)

    def call(*args: Any) -> Any:
        if len(args) != n_args:
            raise TypeError(f"{export.name}() takes {n_args} arguments ({len(args)} given)")
        for i, (dtype, ndim) in arrays:
            a = args[i]
            if not (isinstance(a, np.ndarray) and a.dtype == dtype and a.ndim == ndim
                    and a.flags.c_contiguous and a.flags.aligned):
                raise TypeError(
                    f"{export.name}(): argument {i} must be a C-ordered {ndim}-d {dtype} array "
                    f"(got {type(a).__name__} {getattr(a, 'dtype', '')} "
                    f"{getattr(a, 'shape', '')})"
                )
        return fn(*args)

    call.__name__ = export.name
    call.__doc__ = f"Ahead-of-time kernel ``{export.signature}``."
    return call


def aot_mode() -> str:
    """``"off"`` (``HEELSTRIKE_AOT`` is 0, false, no or off), ``"all"`` or ``"on"`` (default)."""
    value = os.environ.get(ENV, "1").strip().lower()
    if value in ("0", "false", "no", "off"):
        return "off"
    return "all" if value == "all" else "on"


def aot_enabled() -> bool:
    """Whether the ahead-of-time tier is on (``HEELSTRIKE_AOT`` not set to 0/false/no/off)."""
    return aot_mode() != "off"


def _module_file(name: str) -> Path:
    spec = importlib.util.find_spec(name)
    if spec is None or spec.origin is None:
        raise ImportError(f"no source for module {name}")
    return Path(spec.origin)


def _digest(lib: AotLibrary) -> str:
    h = hashlib.sha256()
    for part in (_FORMAT, sys.implementation.cache_tag, str(sysconfig.get_config_var("EXT_SUFFIX")),
                 lib.name, lib.key):
        h.update(part.encode() + b"\0")
    h.update(numba_fingerprint().encode())
    for e in lib.exports:
        h.update(f"{e.name}:{e.signature}\0".encode())
    for mod in sorted(lib.source_modules):
        h.update(mod.encode() + b"\0")
        h.update(_module_file(mod).read_bytes())
    return h.hexdigest()


@functools.cache
def module_name(lib: AotLibrary) -> str:
    """Name of the library's extension module (its digest included; computed once a process)."""
    return f"_heelstrike_aot_{lib.name}_{_digest(lib)[:24]}"


def _path(lib: AotLibrary) -> Path:
    suffix = importlib.machinery.EXTENSION_SUFFIXES[0]
    return cache_dir() / "aot" / f"{module_name(lib)}{suffix}"


def _safe(path: Path) -> str | None:
    """Why ``path`` (a built module) must not be loaded, or None if it may be."""
    for what, is_dir in ((path.parent, True), (path, False)):
        try:
            why = _unsafe(os.lstat(what), directory=is_dir)
        except OSError as exc:
            return f"{what}: {exc.strerror}"
        if why is not None:
            return f"{what} {why}"
    return None


def _import(name: str, path: Path) -> ModuleType:
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    spec = importlib.util.spec_from_file_location(name, str(path), loader=loader)
    if spec is None:  # pragma: no cover - only for a path importlib cannot describe
        raise ImportError(f"cannot load {path}")
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def build(lib: AotLibrary, *, quiet: bool = False) -> Path:
    """Compile ``lib`` with numba's ``pycc`` into the cache and return the module's path.

    The build is announced with an estimate from the library's size and this machine's speed,
    followed stage by stage (kernel k of n) and reported (:func:`heelstrike._firstuse.first_use`);
    ``quiet`` silences it.

    Raises
    ------
    RuntimeError
        If the build fails (the message says why), or the cache folder is unsafe.
    """
    from heelstrike._firstuse import first_use

    path = _path(lib)
    folder = path.parent
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    why = _unsafe(os.lstat(folder), directory=True)
    if why is not None:
        raise RuntimeError(f"not building into {folder}: it {why}")
    size = lib.size() if lib.size is not None else _source_lines(lib.source_modules)
    what = lib.what or f"the {lib.name} kernels, compiled ahead of time"
    with first_use(what, kind=lib.kind, size=size, cache=folder, built=path.name,
                   stages=2 + len(lib.exports), quiet=quiet, heartbeat=HEARTBEAT) as b:
        _CLOCK.start()
        try:
            _compile(lib, path, folder, b.stage)
        finally:
            _CLOCK.end()
    return path


def _source_lines(modules: tuple[str, ...]) -> int:
    """Lines of the source files of ``modules``."""
    return sum(_module_file(m).read_text().count("\n") for m in modules)


def _compile(lib: AotLibrary, path: Path, folder: Path, stage: Callable[[str], None]) -> None:
    """The ``pycc`` build of :func:`build` (into a private folder, moved into ``path``);
    ``stage(name)`` is called as each stage starts."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pycc's pending-deprecation notice is ours to handle
        from numba.pycc import CC
        from numba.pycc import compiler as pycc_compiler

        stage("preparing the functions to compile")
        functions = lib.functions()
        with tempfile.TemporaryDirectory(dir=folder, prefix=".build-") as tmp:
            cc = CC(module_name(lib))
            cc.output_dir = tmp
            cc.verbose = False
            for e in lib.exports:
                fn = functions[e.name]
                cc.export(e.name, e.signature)(getattr(fn, "py_func", fn))
            n = len(lib.exports)
            original = pycc_compiler.compile_extra
            done = [0]

            def compile_extra(*args: Any, **kwargs: Any) -> Any:
                done[0] += 1
                name = getattr(args[2] if len(args) > 2 else None, "__name__", "?")
                stage(f"compiling kernel {done[0]} of {n}, {name} (numba typing and LLVM)")
                result = original(*args, **kwargs)
                if done[0] == n:
                    stage("writing the native object and linking the extension module")
                return result

            pycc_compiler.compile_extra = compile_extra
            try:
                cc.compile()
            except Exception as exc:  # compiler missing, pycc failure: reported by the caller
                raise RuntimeError(f"numba.pycc could not build {lib.name}: {exc}") from exc
            finally:
                pycc_compiler.compile_extra = original
            built = [p for p in Path(tmp).iterdir() if p.name.endswith(path.suffix)]
            if len(built) != 1:
                raise RuntimeError(f"numba.pycc built {[p.name for p in built]}, expected one "
                                   f"module ending in {path.suffix}")
            os.chmod(built[0], 0o700)
            os.replace(built[0], path)  # atomic: concurrent builders never see partial files


class _CompileClock:
    """Wall time this process has spent compiling kernels: ``pycc`` builds and numba JIT
    compiles (nested compiles count once). An object, like :class:`_LoadedLibraries`."""

    def __init__(self) -> None:
        self.seconds = 0.0
        self.depth = 0
        self.started = 0.0
        self.listening = False
        self.lock = threading.Lock()

    def start(self) -> None:
        with self.lock:
            if self.depth == 0:
                self.started = time.monotonic()
            self.depth += 1

    def end(self) -> None:
        with self.lock:
            self.depth -= 1
            if self.depth == 0:
                self.seconds += time.monotonic() - self.started


_CLOCK = _CompileClock()


def compile_seconds() -> float:
    """Seconds (wall, :func:`time.monotonic`) this process has spent compiling kernels so far.

    One-time costs of a first run (building an ahead-of-time module, numba compiling a kernel
    into its disk cache) that a search's time limit should not count
    (:func:`heelstrike.analysis.powered.find_powered_gait`). A compile in progress counts up
    to now.
    """
    with _CLOCK.lock:
        running = time.monotonic() - _CLOCK.started if _CLOCK.depth > 0 else 0.0
        return _CLOCK.seconds + running


def track_numba_compiles() -> None:
    """Count numba's JIT compiles (its ``numba:compile`` events) in :func:`compile_seconds`,
    and announce them (:func:`heelstrike._firstuse.numba_compile_started`).

    Called by the kernel modules when they import numba; idempotent.
    """
    from heelstrike._firstuse import numba_compile_ended, numba_compile_started

    with _CLOCK.lock:
        if _CLOCK.listening:
            return
        _CLOCK.listening = True
    from numba.core import event

    class _Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            _CLOCK.start()
            numba_compile_started(ev.data)

        def on_end(self, ev: Any) -> None:
            _CLOCK.end()
            details = getattr(ev, "_exc_details", None)
            numba_compile_ended(details[1] if details else None)

    event.register("numba:compile", _Listener())


class _LoadedLibraries:
    """What this process loaded (or failed to build), by module name: a cache, so an object
    (module-level dicts are data to :func:`heelstrike.analysis.sweep.sweep`'s identity)."""

    def __init__(self) -> None:
        self.by_name: dict[str, _Checked | None] = {}


_LOCK = threading.Lock()
_LOADED = _LoadedLibraries()


def load_library(lib: AotLibrary, *, build_missing: bool = True) -> Any | None:
    """The library's ahead-of-time module, built on first use; None to use numba's JIT.

    None when the tier is off (``HEELSTRIKE_AOT=0``), when the module is missing and
    ``build_missing`` is false, or when it cannot be built or loaded (with an
    :class:`AotWarning`, once per library and process).

    Returns
    -------
    object or None
        An object with one attribute per export: the compiled function behind a check of its
        array arguments (dtype, ``ndim``, C order); ``.path`` is the module file.
    """
    if not aot_enabled():
        return None
    name = module_name(lib)
    with _LOCK:
        if name in _LOADED.by_name:
            return _LOADED.by_name[name]
        path = _path(lib)
        result: _Checked | None = None
        try:
            if path.exists():
                why = _safe(path)
                if why is not None:
                    raise RuntimeError(f"not loading {path.name}: {why}")
            elif build_missing:
                build(lib)
            if path.exists():
                result = _Checked(_import(name, path), lib.exports, path)
        except (OSError, ImportError, RuntimeError) as exc:
            warnings.warn(f"heelstrike: ahead-of-time kernels unavailable ({exc}); using "
                          "numba's JIT", AotWarning, stacklevel=3)
            result = None
        if result is not None or build_missing:  # a module merely missing is looked for again
            _LOADED.by_name[name] = result
        return result
