"""Safe handling of generated model code: verification, sandboxed loading, the disk cache.

Walker files are data. The code generators (:mod:`heelstrike.models._codegen`) never paste a
string from a walker file into code: parameters appear as ``p_0, p_1, ...``, points and links
by index. Whatever sits in the cache is still treated as untrusted until checked:

- :func:`verify_source` parses the module and accepts only what the generators emit: function
  definitions (each name once) whose bodies assign arithmetic of local names, numbers,
  whitelisted ``numpy`` / ``math`` functions and a few injected helpers, tuple unpacking of
  arguments, subscripted stores into local arrays, and a return.
  No import, attribute other than the whitelisted ones, dunder name, builtin, comprehension,
  lambda, string (except docstrings) or any other statement passes.
- :func:`load_source` runs verified source in a namespace whose ``__builtins__`` is empty and
  which holds only the injected helpers, so even the functions' globals reach nothing else.
- :func:`read_cached` refuses cache files (and their folder) that are symlinks, not owned by
  the current user, or writable by group or others; :func:`write_cached` creates the folder
  with mode 0700 and writes files atomically with mode 0600.

Every entry ends with a trailer line holding the length and SHA-256 of what precedes it
(:func:`write_cached`), so an entry cut short, even at a line boundary where it still parses,
fails :func:`read_cached`'s check and is rebuilt. A cache that cannot be written (a full disk,
a read-only folder), this one or numba's (:func:`tolerate_numba_cache_errors`), makes the
code run uncached, with one :class:`CacheWarning` saying so.

A cache entry that fails any check is not run: the caller rebuilds it and warns
(:class:`CacheWarning`).
"""

from __future__ import annotations

import ast
import functools
import hashlib
import importlib.util
import os
import stat
import tempfile
import warnings
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from heelstrike._caching import CacheWarning, note_uncached, tolerate_numba_cache_errors

__all__ = [
    "CacheWarning",
    "IdentityCache",
    "UnsafeGeneratedCode",
    "cache_dir",
    "generator_fingerprint",
    "load_source",
    "numba_fingerprint",
    "read_cached",
    "tolerate_numba_cache_errors",
    "verify_source",
    "write_cached",
]


class UnsafeGeneratedCode(ValueError):
    """Generated (or cached) source contains something the generators never emit."""




class IdentityCache:
    """``compute(obj)`` once per object, by identity, for the ``maxsize`` objects used last
    (e.g. a walker description's cache key, which hashes its whole structure: about 0.8 ms).

    The cached objects are kept alive, so an ``id`` is never reused for another object while
    its entry exists; the size bound keeps a loop that reads a new description every time
    (``load_walker`` in a loop) from keeping them all. A cache is an object rather than a
    module-level dict (module-level dicts are data to
    :func:`heelstrike.analysis.sweep.sweep`'s identity).
    """

    def __init__(self, compute: Callable[[Any], str], maxsize: int = 128) -> None:
        self._compute = compute
        self._maxsize = maxsize
        self._by_id: dict[int, tuple[Any, str]] = {}  # insertion order = least recent first

    def __call__(self, obj: Any) -> str:
        key = id(obj)
        hit = self._by_id.get(key)
        if hit is not None and hit[0] is obj:
            self._by_id[key] = self._by_id.pop(key)  # most recently used last
            return hit[1]
        value = self._compute(obj)
        self._by_id[key] = (obj, value)
        while len(self._by_id) > self._maxsize:
            del self._by_id[next(iter(self._by_id))]
        return value

    def __len__(self) -> int:
        return len(self._by_id)


def cache_dir() -> Path:
    """Directory of the generated-code cache.

    ``$HEELSTRIKE_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/heelstrike`` or
    ``~/.cache/heelstrike``.
    """
    env = os.environ.get("HEELSTRIKE_CACHE_DIR")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "heelstrike"


_FINGERPRINT: dict[tuple[str, ...], str] = {}


def generator_fingerprint(*modules: str) -> str:
    """sha256 of the source files of the given ``heelstrike.models`` modules.

    Part of every cache key, so that a change to a generator invalidates what it generated.
    """
    if modules not in _FINGERPRINT:
        h = hashlib.sha256()
        here = Path(__file__).parent
        for name in (*modules, "_generated"):
            h.update((here / f"{name}.py").read_bytes())
        _FINGERPRINT[modules] = h.hexdigest()
    return _FINGERPRINT[modules]


@functools.cache
def numba_fingerprint() -> str:
    """sha256 of the installed numba's version file, without importing numba.

    Part of the keys of what numba compiles (generated walker code, ahead-of-time kernels), so
    a numba upgrade invalidates them. Reading one file costs far less than importing numba or
    its distribution metadata.
    """
    spec = importlib.util.find_spec("numba")
    h = hashlib.sha256(b"numba\0")
    if spec is None or not spec.submodule_search_locations:
        h.update(b"not installed")
        return h.hexdigest()
    path = Path(next(iter(spec.submodule_search_locations))) / "_version.py"
    try:
        h.update(path.read_bytes())
    except OSError:
        h.update(b"version unknown")
    return h.hexdigest()


# -- verification --------------------------------------------------------------------------------

#: Attributes the generators may use, per module name.
ALLOWED_ATTRIBUTES: Mapping[str, frozenset[str]] = {
    "numpy": frozenset(
        {"sin", "cos", "tan", "sqrt", "pi", "exp", "log", "abs", "sign", "arctan2", "power"}
    ),
    "math": frozenset({"sin", "cos", "tan", "sqrt", "pi", "exp", "log", "fabs", "atan2"}),
}
_BINOPS = (ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow)
_UNARY = (ast.USub, ast.UAdd)


def _fail(node: ast.AST, what: str) -> UnsafeGeneratedCode:
    line = getattr(node, "lineno", "?")
    return UnsafeGeneratedCode(f"line {line}: {what} is not allowed in generated code")


class _Verifier:
    def __init__(self, helpers: frozenset[str], functions: frozenset[str] | None) -> None:
        self.helpers = helpers  # injected callables/modules reachable by name
        self.functions = functions  # allowed top-level function names (None: any identifier)
        self.defined: set[str] = set()

    # expressions
    def expr(self, node: ast.expr, local: set[str]) -> None:
        if isinstance(node, ast.Constant):
            if node.value is Ellipsis or (
                isinstance(node.value, int | float) and not isinstance(node.value, bool)
            ):
                return
            raise _fail(node, f"constant {type(node.value).__name__}")
        if isinstance(node, ast.Name):
            if (
                node.id not in local
                and node.id not in self.helpers
                and (node.id not in self.defined)
            ):
                raise _fail(node, f"name {node.id!r}")
            return
        if isinstance(node, ast.BinOp) and isinstance(node.op, _BINOPS):
            self.expr(node.left, local)
            self.expr(node.right, local)
            return
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, _UNARY):
            self.expr(node.operand, local)
            return
        if isinstance(node, ast.Attribute):
            self.attribute(node)
            return
        if isinstance(node, ast.Call):
            if node.keywords:
                raise _fail(node, "a keyword argument")
            f = node.func
            if isinstance(f, ast.Attribute):
                self.attribute(f)
            elif not (isinstance(f, ast.Name) and (f.id in self.helpers or f.id in self.defined)):
                raise _fail(node, "this call")
            for a in node.args:
                self.expr(a.value if isinstance(a, ast.Starred) else a, local)
            return
        if isinstance(node, ast.Tuple) and isinstance(node.ctx, ast.Load):
            for e in node.elts:
                self.expr(e.value if isinstance(e, ast.Starred) else e, local)
            return
        if isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Load):
            self.expr(node.value, local)
            self.index(node.slice, local)
            return
        raise _fail(node, type(node).__name__)

    def attribute(self, node: ast.Attribute) -> None:
        v = node.value
        if not (
            isinstance(v, ast.Name)
            and v.id in ALLOWED_ATTRIBUTES
            and v.id in self.helpers
            and node.attr in ALLOWED_ATTRIBUTES[v.id]
        ):
            raise _fail(node, f"attribute {ast.unparse(node)!r}")

    def index(self, node: ast.expr, local: set[str]) -> None:
        if isinstance(node, ast.Tuple):
            for e in node.elts:
                self.index(e, local)
        elif isinstance(node, ast.Slice):
            for part in (node.lower, node.upper, node.step):
                if part is not None:
                    self.expr(part, local)
        else:
            self.expr(node, local)

    # statements
    def function(self, fn: ast.FunctionDef) -> None:
        if self.functions is not None and fn.name not in self.functions:
            raise _fail(fn, f"function {fn.name!r}")
        if fn.name in self.defined:  # a second definition would shadow the generated one
            raise _fail(fn, f"a second definition of {fn.name!r}")
        if (
            fn.name.startswith("__")
            or fn.decorator_list
            or fn.returns
            or getattr(fn, "type_params", None)
        ):
            raise _fail(fn, "this function definition")
        a = fn.args
        if a.posonlyargs or a.kwonlyargs or a.kwarg or a.defaults or a.kw_defaults:
            raise _fail(fn, "this signature")
        local = {arg.arg for arg in a.args}
        if a.vararg is not None:
            local.add(a.vararg.arg)
        if any(arg.annotation is not None for arg in a.args):
            raise _fail(fn, "an annotation")
        body = list(fn.body)
        if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
            if not isinstance(body[0].value.value, str):
                raise _fail(body[0], "this expression statement")
            body = body[1:]
        for st in body:
            if isinstance(st, ast.Assign):
                self.expr(st.value, local)
                for t in st.targets:
                    self.target(t, local)
            elif isinstance(st, ast.Return) and st.value is not None:
                self.expr(st.value, local)
            else:
                raise _fail(st, type(st).__name__)
        self.defined.add(fn.name)

    def target(self, t: ast.expr, local: set[str]) -> None:
        if isinstance(t, ast.Name):
            if t.id.startswith("__") or t.id in self.helpers:
                raise _fail(t, f"assigning {t.id!r}")
            local.add(t.id)
        elif isinstance(t, ast.Tuple):
            for e in t.elts:
                self.target(e, local)
        elif isinstance(t, ast.Subscript) and isinstance(t.value, ast.Name):
            if t.value.id not in local:
                raise _fail(t, f"storing into {t.value.id!r}")
            self.index(t.slice, local)
        else:
            raise _fail(t, "this assignment target")

    def module(self, tree: ast.Module) -> None:
        body = list(tree.body)
        if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
            if not isinstance(body[0].value.value, str):
                raise _fail(body[0], "this expression statement")
            body = body[1:]
        for st in body:
            if isinstance(st, ast.FunctionDef):
                self.function(st)
            elif (
                isinstance(st, ast.Assign)
                and len(st.targets) == 1
                and isinstance(st.targets[0], ast.Name)
                and st.targets[0].id.isupper()
                and isinstance(st.value, ast.Constant)
                and isinstance(st.value.value, int)
                and not isinstance(st.value.value, bool)
            ):
                self.defined.add(st.targets[0].id)
            else:
                raise _fail(st, type(st).__name__)


def verify_source(
    source: str,
    *,
    helpers: frozenset[str] | set[str],
    functions: frozenset[str] | set[str] | None = None,
) -> None:
    """Raise :class:`UnsafeGeneratedCode` unless ``source`` is of the form the generators emit.

    Parameters
    ----------
    source : str
        Python source of a generated module.
    helpers : set of str
        Names that :func:`load_source` will inject (e.g. ``{"numpy", "zeros", "_lead"}``);
        the only free names the code may use besides its own functions and constants.
    functions : set of str, optional
        The only top-level function names allowed (default: any non-dunder name).
    """
    try:
        tree = ast.parse(source)
    except (SyntaxError, ValueError, RecursionError, MemoryError) as exc:
        raise UnsafeGeneratedCode(f"does not parse: {exc}") from None
    _Verifier(frozenset(helpers), None if functions is None else frozenset(functions)).module(tree)


def load_source(
    source: str,
    filename: str,
    *,
    helpers: Mapping[str, Any],
    functions: frozenset[str] | set[str] | None = None,
) -> dict[str, Any]:
    """Verify ``source`` and execute it with no builtins; return its namespace.

    Parameters
    ----------
    source : str
        Generated module source.
    filename : str
        Name shown in tracebacks.
    helpers : mapping
        The objects the module may use by name (modules such as ``numpy``, helper functions).
    functions : set of str, optional
        Allowed top-level function names.

    Raises
    ------
    UnsafeGeneratedCode
        If verification fails (the source is not run).
    """
    verify_source(source, helpers=set(helpers), functions=functions)
    ns: dict[str, Any] = {"__builtins__": {}, "__name__": "heelstrike_generated", **helpers}
    exec(compile(source, filename, "exec"), ns)
    return ns


# -- the disk cache ------------------------------------------------------------------------------


def _unsafe(st: os.stat_result, *, directory: bool) -> str | None:
    if stat.S_ISLNK(st.st_mode):
        return "is a symbolic link"
    if directory and not stat.S_ISDIR(st.st_mode):
        return "is not a directory"
    if not directory and not stat.S_ISREG(st.st_mode):
        return "is not a regular file"
    if hasattr(os, "getuid") and st.st_uid != os.getuid():
        return f"is owned by uid {st.st_uid}, not by this user ({os.getuid()})"
    if st.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return "is writable by group or others"
    return None


def read_cached(path: Path) -> str | None:
    """Text of a cache file, or None if absent; warn and return None if it is unsafe.

    The file and its folder must be owned by the current user, not symlinks, and writable by
    nobody else; the file must be a regular file of at most 64 MiB.
    """
    try:
        st_dir = os.lstat(path.parent)
        st = os.lstat(path)
    except FileNotFoundError:
        return None
    for what, s, is_dir in ((path.parent, st_dir, True), (path, st, False)):
        why = _unsafe(s, directory=is_dir)
        if why is not None:
            warnings.warn(
                f"heelstrike: not using cached model code: {what} {why}; rebuilding it in memory",
                CacheWarning,
                stacklevel=3,
            )
            return None
    if st.st_size > 64 << 20:
        return None
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        text = ""
    body = _checked_body(text)
    if body is None:
        warnings.warn(
            f"heelstrike: cached model code {path} failed verification (incomplete or damaged: "
            "its length and checksum do not match its trailer); rebuilding it", CacheWarning,
            stacklevel=3)
    return body


#: The first characters of a cache entry's trailer line (its last line).
_TRAILER = "# heelstrike-cache-entry "


def _trailer(body: str) -> str:
    data = body.encode("utf-8")
    return f"{_TRAILER}length={len(data)} sha256={hashlib.sha256(data).hexdigest()}\n"


def _checked_body(text: str) -> str | None:
    """The entry's text before its trailer if the trailer's length and checksum match."""
    body, sep, last = text.rstrip("\n").rpartition("\n")
    if not sep or not last.startswith(_TRAILER):
        return None
    body += "\n"
    return body if _trailer(body) == last + "\n" else None




def write_cached(path: Path, text: str) -> Path | None:
    """Write ``text`` to ``path`` atomically (mode 0600, folder 0700); None if it cannot."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        if _unsafe(os.lstat(path.parent), directory=True) is not None:
            return None
        fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
        try:
            body = text if text.endswith("\n") else text + "\n"
            with os.fdopen(fd, "w", encoding="utf-8") as fh:
                fh.write(body + _trailer(body))
            os.replace(tmp, path)  # atomic: concurrent builders never see partial files
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        return path
    except OSError as exc:  # full disk, read-only home etc.: still usable, just not cached
        note_uncached(f"cannot write the model-code cache {path.parent} "
                       f"({exc.strerror or exc})")
        return None
