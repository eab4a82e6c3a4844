"""Numba backend of the model builder: scalar kernels generated from the same sympy expressions.

:func:`heelstrike.models._codegen._derive` gives the walker's ``M``, ``h``, contact Jacobians,
their rates, the foot centres and the leg swap as sympy expressions; this module prints them
(``sympy.cse``) as three plain scalar Python functions and compiles them with numba:

``dynamics(q, u, p, slope, M, h)``
    writes ``M`` (n, n) and ``h`` (n,) and returns the potential energy ``V`` (J, zero at the
    ground frame origin; what an energy-tracking torque law needs, from the same CSE);
``contacts(q, u, p, A, rate, c)``
    writes the rolling-contact Jacobians ``A`` (2, 2, n) (stance, swing; tangential and normal
    rows), their rates ``A_dot q_dot`` ``rate`` (2, 2) and the arc centres ``c`` (2, 2) (m);
``swap(q, u, p, q_new, u_new)``
    writes the leg-swapped coordinates and velocities and returns 1.0 (0.0 and nothing written
    for a walker without mirrors);
``heel_strike_guard(q, p)``
    returns the walker file's declared heel-strike guard (``[events] heel_strike``, the same
    expression as the builder's ``heel_strike_guard``), 0.0 for a walker declaring none (its
    kernel's guard is the swing foot's clearance, from ``contacts``).

Every function returns a float (0.0 unless said otherwise) and has a fixed numba signature
(:func:`signatures`), so compiled simulation kernels take them as first-class function
arguments and are compiled (and disk-cached) once for all walkers. This module imports numba
only to compile: the key of a walker's code (:func:`numba_source_key`) needs no numba, so a
process that runs a walker's ahead-of-time kernels (:mod:`heelstrike.dynamics._aot`) never
loads it.

Security and caching
--------------------
The generated source contains only numbers and generated identifiers (``q_i``, ``u_i``, ``p_i``
for the i-th parameter of ``WalkerDescription.param_names``, ``slope``, ``t_i`` for common
subexpressions): every free symbol of the derived expressions is renamed before printing. The
source must pass the builder's verifier (:func:`heelstrike.models._generated.verify_source`,
``math`` the only free name) and a stricter whitelist of what this generator emits (function
definitions, assignments, arithmetic, ``math.sin/cos/sqrt/pi``, subscripts, ``return``), and is
executed with no builtins and only ``math`` injected, before numba compiles it. It is cached
(:func:`~heelstrike.models._generated.read_cached` / ``write_cached``: owner-only files,
re-verified on every load) in ``cache_dir() / "numba"`` as ``<key>.py``; the key hashes the
description's structure, the package, numba and the sources of the generators. numba's own
cache of the compiled functions (``cache=True``) lives beside it in ``__pycache__`` and is used
only while that folder and its files are owned by the user and writable by nobody else.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import math
import os
import stat
import sys
import types
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from heelstrike._version import __version__
from heelstrike.models._generated import (
    CacheWarning,
    IdentityCache,
    cache_dir,
    generator_fingerprint,
    numba_fingerprint,
    read_cached,
    tolerate_numba_cache_errors,
    verify_source,
    write_cached,
)
from heelstrike.models.builder import CODEGEN_VERSION
from heelstrike.models.description import WalkerDescription

__all__ = [
    "NumbaModel",
    "build_numba",
    "generate_numba_source",
    "numba_source_key",
    "signatures",
]

#: The four generated functions, in the order of :func:`signatures`.
FUNCTIONS = ("dynamics", "contacts", "swap", "heel_strike_guard")


@functools.cache
def signatures() -> dict[str, Any]:
    """The numba signatures of the generated functions (imports numba).

    - ``dynamics(q, u, p, slope, M, h) -> V`` (J);
    - ``contacts(q, u, p, A, rate, c) -> 0.0``; ``A`` (2, 2, n), ``rate`` and ``c`` (2, 2);
    - ``swap(q, u, p, q_new, u_new) -> 1.0`` (0.0: no swap declared);
    - ``heel_strike_guard(q, p) -> g`` (the declared guard; 0.0: none declared).
    """
    from numba import types as nbt

    v = nbt.float64[::1]
    m = nbt.float64[:, ::1]
    return {
        "dynamics": nbt.float64(v, v, v, nbt.float64, m, v),
        "contacts": nbt.float64(v, v, v, nbt.float64[:, :, ::1], m, m),
        "swap": nbt.float64(v, v, v, v, v),
        "heel_strike_guard": nbt.float64(v, v),
    }
#: ``heel_strike_guard`` of a walker declaring no guard (its kernel's is the clearance).
_GUARD_STUB = "def heel_strike_guard(q, p):\n    return 0.0\n"
#: The only name generated code uses without defining it (injected; no builtins).
_HELPERS: Mapping[str, Any] = types.MappingProxyType({"math": math})

_MEMORY: dict[str, NumbaModel] = {}  # one per walker structure (by its key)

_ALLOWED_NODES: tuple[type[ast.AST], ...] = (
    ast.Module, ast.FunctionDef, ast.arguments, ast.arg, ast.Assign, ast.Return, ast.Name,
    ast.Load, ast.Store, ast.Constant, ast.BinOp, ast.UnaryOp, ast.Add, ast.Sub, ast.Mult,
    ast.Div, ast.Pow, ast.USub, ast.UAdd, ast.Call, ast.Attribute, ast.Subscript, ast.Tuple,
)
_MATH_ATTRS = frozenset({"sin", "cos", "sqrt", "pi"})


def _key(desc: WalkerDescription) -> str:
    text = "\n".join(
        (
            "numba-kernels",
            CODEGEN_VERSION,
            __version__,
            numba_fingerprint(),
            generator_fingerprint("_codegen", "_codegen_numba", "description"),
            desc.structure_key(),
        )
    )
    return hashlib.sha256(text.encode()).hexdigest()


_KEYS = IdentityCache(_key)


def numba_source_key(desc: WalkerDescription) -> str:
    """The key of a walker structure's generated numba code (computed once a process per
    description; imports no numba). It names the cached source and the walker's ahead-of-time
    kernels."""
    return _KEYS(desc)


def _param_symbols(d: Mapping[str, Any], desc: WalkerDescription) -> list[Any]:
    """The parameter symbols of ``_derive``'s output in ``desc.param_names`` order."""
    P = d["P"]
    if isinstance(P, Mapping):
        if set(P) == set(desc.param_names):
            return [P[k] for k in desc.param_names]
        return list(P.values())
    return list(P)


def generate_numba_source(desc: WalkerDescription) -> str:
    """Derive the walker with sympy and return the source of its four scalar functions.

    See the module docstring for the functions and the naming of the generated identifiers.
    """
    import sympy as sp
    from sympy.printing.pycode import PythonCodePrinter

    from heelstrike.models._codegen import _derive

    d = _derive(desc)
    n = int(d["n"])
    rename: dict[Any, Any] = {}
    for i in range(n):
        rename[d["q"][i]] = sp.Symbol(f"q_{i}", real=True)
        rename[d["u"][i]] = sp.Symbol(f"u_{i}", real=True)
    rename[d["slope"]] = sp.Symbol("slope", real=True)
    psyms = _param_symbols(d, desc)
    for i, s in enumerate(psyms):
        rename[s] = sp.Symbol(f"p_{i}", real=True)
    allowed = set(rename.values())
    printer = PythonCodePrinter({"fully_qualified_modules": True, "standard": "python3"})

    def fn(name: str, args: str, unpack_u: bool, outputs: list[tuple[str, Any]],
           returns: str = "0.0") -> str:
        exprs = [sp.sympify(ex).xreplace(rename) for _, ex in outputs]
        for ex in exprs:
            extra = ex.free_symbols - allowed
            if extra:
                raise ValueError(f"unexpected symbols in the derived expressions: {extra}")
        repl, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("t_"), optimizations="basic")
        lines = [f"def {name}({args}):"]
        lines += [f"    q_{i} = q[{i}]" for i in range(n)]
        if unpack_u:
            lines += [f"    u_{i} = u[{i}]" for i in range(n)]
        lines += [f"    p_{i} = p[{i}]" for i in range(len(psyms))]
        for sym, ex in repl:
            lines.append(f"    {sym} = {printer.doprint(ex)}")
        for (target, _), ex in zip(outputs, reduced, strict=True):
            lines.append(f"    {target} = {printer.doprint(ex) if ex != 0 else '0.0'}")
        lines.append(f"    return {returns}")
        return "\n".join(lines) + "\n"

    M, h = d["M"], d["h"]
    dyn = [(f"M[{i}, {j}]", M[i, j]) for i in range(n) for j in range(n)]
    dyn += [(f"h[{i}]", h[i]) for i in range(n)]
    dyn += [("V", d["V"])]
    con: list[tuple[str, Any]] = []
    for f, foot in enumerate(("stance", "swing")):
        c, _R, A, rate = d["feet"][foot]
        con += [(f"A[{f}, {r}, {j}]", A[r, j]) for r in range(2) for j in range(n)]
        con += [(f"rate[{f}, {r}]", rate[r]) for r in range(2)]
        con += [(f"c[{f}, {r}]", c[r]) for r in range(2)]
    parts = [
        f"# Generated by heelstrike.models._codegen_numba (n = {n}). Do not edit.\n",
        fn("dynamics", "q, u, p, slope, M, h", True, dyn, returns="V"),
        fn("contacts", "q, u, p, A, rate, c", True, con),
    ]
    if d["swap_q"] is not None:
        sq, sJ = d["swap_q"], d["swap_J"]
        sw = [(f"q_new[{i}]", sq[i]) for i in range(n)]
        sw += [
            (f"u_new[{i}]", sum((sJ[i, j] * d["u"][j] for j in range(n)), sp.Integer(0)))
            for i in range(n)
        ]
        parts.append(fn("swap", "q, u, p, q_new, u_new", True, sw, returns="1.0"))
    else:
        parts.append("def swap(q, u, p, q_new, u_new):\n    return 0.0\n")
    if d["guard"] is not None:
        parts.append(fn("heel_strike_guard", "q, p", False, [("g", d["guard"])], returns="g"))
    else:
        parts.append(_GUARD_STUB)
    source = "\n\n".join(parts)
    check_source(source)
    return source


def check_source(source: str) -> None:
    """Reject generated source that is not plain arithmetic on generated identifiers.

    Both :func:`heelstrike.models._generated.verify_source` (the builder's policy) and a
    stricter whitelist of the nodes this generator emits must accept it.

    Raises
    ------
    ValueError
        (:class:`~heelstrike.models._generated.UnsafeGeneratedCode` from the builder's
        verifier) on any syntax outside the whitelist (see the module docstring), a string
        constant, or an attribute other than ``math.sin/cos/sqrt/pi``.
    """
    verify_source(source, helpers=set(_HELPERS), functions=set(FUNCTIONS))
    tree = ast.parse(source)
    for node in ast.walk(tree):
        if not isinstance(node, _ALLOWED_NODES):
            raise ValueError(f"generated code: {type(node).__name__} not allowed")
        if isinstance(node, ast.Constant) and not isinstance(node.value, (int, float)):
            raise ValueError("generated code: only numeric constants are allowed")
        if isinstance(node, ast.FunctionDef) and (node.decorator_list or node.returns):
            raise ValueError("generated code: decorators and annotations are not allowed")
        if isinstance(node, ast.Attribute) and not (
            isinstance(node.value, ast.Name)
            and node.value.id == "math"
            and node.attr in _MATH_ATTRS
        ):
            raise ValueError("generated code: only math.sin/cos/sqrt/pi attributes are allowed")
        if isinstance(node, ast.Call) and not isinstance(node.func, ast.Attribute):
            raise ValueError("generated code: only math functions may be called")
        if isinstance(node, ast.Name) and node.id.startswith("__"):
            raise ValueError("generated code: dunder names are not allowed")


@dataclass(frozen=True, kw_only=True, eq=False)
class NumbaModel:
    """The numba-compiled functions of one walker structure.

    Attributes
    ----------
    key : str
        sha256 cache key.
    n : int
        Number of coordinates.
    dynamics, contacts, swap, heel_strike_guard : numba dispatcher
        See the module docstring; each compiled for its one signature.
    has_swap : bool
        The walker declares mirrors (``swap`` is not the stub).
    has_guard : bool
        The walker declares its heel-strike guard (``heel_strike_guard`` is not the stub).
    path : Path or None
        Cache file of the source (None if it could not be written).
    from_cache : bool
        The source came from the disk cache (no sympy derivation).
    """

    key: str
    n: int
    dynamics: Callable[..., float]
    contacts: Callable[..., float]
    swap: Callable[..., float]
    heel_strike_guard: Callable[..., float]
    has_swap: bool
    has_guard: bool
    path: Path | None
    from_cache: bool


def _numba_cache_safe(path: Path) -> bool:
    """numba's cache beside ``path`` (``__pycache__``, pickles) is ours and only ours.

    The folder and every cache file of this source must be owned by the current user, not
    symbolic links and not writable by group or others (else the functions are compiled
    without numba's disk cache).
    """
    folder = path.parent / "__pycache__"
    try:
        entries = [folder, *(e for e in folder.iterdir() if e.name.startswith(path.stem))]
    except FileNotFoundError:
        return True  # numba creates it (with this process's umask)
    except OSError:
        return False
    for entry in entries:
        try:
            st = os.lstat(entry)
        except OSError:
            return False
        if stat.S_ISLNK(st.st_mode) or st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
            return False
        if hasattr(os, "getuid") and st.st_uid != os.getuid():
            return False
    return True


def _numba_cached(path: Path) -> bool:
    """Whether numba's disk cache holds an index for the generated module at ``path``."""
    folder = path.parent / "__pycache__"
    try:
        return any(e.name.startswith(path.stem) and e.suffix == ".nbi" for e in folder.iterdir())
    except OSError:
        return False


def _load(source: str, path: Path, key: str, cache: bool) -> dict[str, Any]:
    """Verify, execute with no builtins (``math`` injected) and jit the four functions."""
    check_source(source)
    name = f"heelstrike_numba_{key[:16]}"
    mod = types.ModuleType(name)
    ns = mod.__dict__
    ns.update({"__builtins__": {}, **_HELPERS})
    exec(compile(source, str(path), "exec"), ns)
    # numba rebuilds a cached function's environment by importing its module by name
    sys.modules[name] = mod
    import numba

    tolerate_numba_cache_errors()  # a cache that cannot be written: compiled uncached
    return {
        fname: numba.njit(sig, cache=cache, nogil=True)(ns[fname])
        for fname, sig in signatures().items()
    }


def build_numba(desc: WalkerDescription, *, use_cache: bool = True) -> NumbaModel:
    """Generate (or fetch from the caches) and compile the numba functions of a walker.

    Parameters
    ----------
    desc : WalkerDescription
        The walker.
    use_cache : bool
        Use the in-process cache, the source cache and numba's disk cache (default True).

    Returns
    -------
    NumbaModel
    """
    # the key is computed once per description (numba_source_key), not per call
    key = numba_source_key(desc) if use_cache else _key(desc)
    if use_cache and key in _MEMORY:
        return _MEMORY[key]
    path = cache_dir() / "numba" / f"{key}.py"
    source: str | None = read_cached(path) if use_cache else None
    from_cache = source is not None
    if source is not None:
        try:
            check_source(source)
        except (ValueError, SyntaxError) as exc:
            warnings.warn(
                f"heelstrike: cached numba model code {path} failed verification ({exc}); "
                "rebuilding it",
                CacheWarning,
                stacklevel=2,
            )
            source, from_cache = None, False
    written: Path | None = path if from_cache else None
    from heelstrike._firstuse import first_use

    if source is None:
        from heelstrike.models.builder import derivation_size

        with first_use(f"the {desc.name!r} walker's equations derived with sympy, numba code "
                       "generated", kind="derive-numba", size=derivation_size(desc),
                       cache=path.parent, built=path.name):
            source = generate_numba_source(desc)
            written = write_cached(path, source) if use_cache else None
    # numba's disk cache needs the source file on disk (and a folder only we can write)
    numba_cache = written is not None and _numba_cache_safe(path)
    if numba_cache and _numba_cached(path):
        fns = _load(source, path, key, cache=numba_cache)
    else:
        with first_use(f"the {desc.name!r} walker's {len(signatures())} generated functions "
                       "compiled by numba", kind="jit", size=source.count("\n"),
                       cache=path.parent / "__pycache__" if numba_cache else
                       "nowhere (compiled in every process)", built=path.name):
            fns = _load(source, path, key, cache=numba_cache)
    model = NumbaModel(
        key=key,
        n=len(desc.coordinate_names),
        dynamics=fns["dynamics"],
        contacts=fns["contacts"],
        swap=fns["swap"],
        heel_strike_guard=fns["heel_strike_guard"],
        has_swap="q_new[" in source,
        has_guard=_GUARD_STUB not in source,
        path=written,
        from_cache=from_cache,
    )
    if use_cache:
        _MEMORY[key] = model
    return model
