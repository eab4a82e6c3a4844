"""First use that tells the truth: every compile or derivation announces, shows and reports itself.

A walker's first use derives its equations with sympy, generates code and compiles kernels
with numba (ahead of time, :mod:`heelstrike.dynamics._aot`, or by its JIT); later uses load
the results from the caches. Every such build runs inside :func:`first_use`, one mechanism for
all of them:

- **before**, one line on stderr says what is built, an estimate of how long it takes and where
  the cache is;
- **during**, each stage is named as it starts (``stage 2 of 3``) with the time elapsed, and a
  heartbeat line every :data:`HEARTBEAT` seconds says what is being compiled, the time elapsed
  and the estimate;
- **after**, one line says what was built, how long it took (and what was estimated) and where
  the cache is.

The estimate is a model, not a guess::

    seconds = size * k[kind] * probe * load**LOAD_PERSISTENCE

``size`` measures the build (its :class:`BuildKind` says in what: lines of kernel source
compiled, or ``coordinates**3 * bodies`` of a derivation); ``probe`` is the processor time (s)
this machine takes for a small fixed Python workload (:func:`machine_probe`, timed once a
process: the speed of one core); ``load`` is how many times slower a build runs because other
work shares the cores (:func:`load_factor`: measured as each build starts, the inverse of the
share of a core this process gets over half a second, at least 1; only part of it is
expected to last through a long build, :data:`LOAD_PERSISTENCE`); ``k`` is seconds per unit
of size per second of probe. ``k`` is the median of the builds of that kind recorded on this
machine (:data:`RATES_FILE` in the cache folder, written after every build), else the reference
value of the kind (:data:`KINDS`, measured on a loaded 2-core machine). ``tests/test_firstuse.py``
checks the model and the messages; ``benchmarks/bench_first_use.py`` compares estimates with
measured times (``benchmarks/README.md``).

numba JIT compiles that no build announced (a kernel compiled on its first call) are announced
the same way by the listener on numba's ``numba:compile`` events
(:func:`heelstrike.dynamics._aot.track_numba_compiles` calls :func:`numba_compile_started`).
"""

from __future__ import annotations

import ast
import json
import math
import os
import statistics
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = [
    "HEARTBEAT",
    "KINDS",
    "RATES_FILE",
    "Build",
    "BuildKind",
    "Estimate",
    "coefficient",
    "current_load",
    "estimate",
    "first_use",
    "load_factor",
    "machine_probe",
    "numba_compile_ended",
    "numba_compile_started",
    "read_records",
    "record",
]

#: File of the build rates observed on this machine, in heelstrike's cache folder.
RATES_FILE = "build_rates.json"
#: Seconds between heartbeat lines during a build.
HEARTBEAT = 15.0
#: Builds estimated under this many seconds (s) are not announced (numba compiles of small
#: functions); they are still timed and recorded.
QUIET_BELOW = 1.0
#: Recorded builds kept per kind (the estimate uses their median).
KEEP = 7
#: Seconds of wall time over which :func:`load_factor` measures this process's share of a core.
LOAD_WINDOW = 0.5
#: Exponent of the load factor in the estimate: the load measured as a build starts on a shared
#: machine passes or grows during a build of minutes; half of its effect (in logarithm) is
#: assumed to last (fitted on ``benchmarks/bench_first_use.py``'s runs: the whole factor made
#: estimates 2-4x too long when a burst of other work ended soon after the build started).
LOAD_PERSISTENCE = 0.5
#: Seconds a measured load factor is reused (:func:`current_load`).
LOAD_REUSE = 10.0


@dataclass(frozen=True)
class BuildKind:
    """A kind of build and the reference value of its rate.

    Attributes
    ----------
    unit : str
        What its size counts.
    k : float
        Reference seconds per unit of size per second of :func:`machine_probe`.
    """

    unit: str
    k: float


#: Kinds of build. Reference ``k`` measured on a loaded 2-core machine (builds of the shipped
#: walkers with empty caches, the probe timed beside them; ``benchmarks/README.md``, "first
#: use: estimate vs measured").
KINDS: dict[str, BuildKind] = {
    "aot-compass": BuildKind("lines of kernel source", 0.32),
    "aot-walker": BuildKind("lines of kernel and generated source", 0.9),
    "aot-robot": BuildKind("lines of kernel source", 1.4),
    "derive-numpy": BuildKind("coordinates^3 x bodies", 0.15),
    "derive-numba": BuildKind("coordinates^3 x bodies", 0.09),
    "jit": BuildKind("lines of compiled source", 0.45),
    "jit-kernel": BuildKind("lines of kernel source", 1.8),
    "jit-ensemble": BuildKind("lines of kernel source (its walk kernel compiled)", 0.17),
}


@dataclass(frozen=True)
class Estimate:
    """An estimated build time.

    Attributes
    ----------
    seconds : float
        Estimated wall time (s).
    basis : str
        Where ``k`` came from, in words (for the announcement).
    """

    seconds: float
    basis: str


# ---------------------------------------------------------------------------------------------
# the model
# ---------------------------------------------------------------------------------------------
def _probe_once() -> float:
    src = "\n".join(
        f"def f{i}(a, b):\n    c = a * {i} + b ** 2 - (a - b) / {i + 1}\n"
        "    return c if c > 0 else -c"
        for i in range(300)
    )
    t0 = time.process_time()
    ns: dict[str, Any] = {}
    exec(compile(ast.parse(src), "<probe>", "exec"), ns)
    total = 0.0
    for i in range(300):
        total += ns[f"f{i}"](1.5, 0.5)
    return time.process_time() - t0


class _Probe:
    """The probe's value, timed once a process, and the last load factor measured with the
    time it was measured (an object: a cache)."""

    def __init__(self) -> None:
        self.seconds: float | None = None
        self.load: float | None = None
        self.load_at = 0.0


_PROBE = _Probe()


def machine_probe() -> float:
    """Processor seconds this machine takes to parse, compile and run a fixed Python module.

    The fastest of three runs of a workload of about 20 ms, timed on the first call of a
    process and kept: a compile is mostly Python (numba's typing, sympy) and LLVM on one core,
    so its processor time scales with this one's. Processor time, not wall time: the share of
    the cores other work leaves is :func:`load_factor`'s (a probe this short is often given a
    whole core on a loaded machine, then its wall time says nothing of the load).
    """
    if _PROBE.seconds is None:
        _PROBE.seconds = min(_probe_once() for _ in range(3))
    return _PROBE.seconds


def load_factor(share: float | None = None, window: float = LOAD_WINDOW) -> float:
    """How many times slower than on an idle machine a one-core build runs now: ``1 / share``.

    ``share`` is the fraction of one core this process gets, measured: the probe's workload
    run over ``window`` seconds of wall time, its processor time divided by that wall time
    (other work on the cores lowers it; a window of half a second spans many of the
    scheduler's slices, where one 20 ms run is often given a whole core). At least 1.

    Parameters
    ----------
    share : float, optional
        The share (0 to 1) if already known (default: measured now).
    window : float
        Seconds of wall time measured.
    """
    if share is None:
        cpu0, wall0 = time.process_time(), time.perf_counter()
        while time.perf_counter() - wall0 < window:
            _probe_once()
        share = (time.process_time() - cpu0) / max(time.perf_counter() - wall0, 1e-9)
    return max(1.0, 1.0 / max(share, 1e-3))


def current_load() -> float:
    """:func:`load_factor`, measured at most once every :data:`LOAD_REUSE` seconds (a burst of
    small compiles does not pay half a second each)."""
    now = time.monotonic()
    if _PROBE.load is None or now - _PROBE.load_at > LOAD_REUSE:
        _PROBE.load, _PROBE.load_at = load_factor(), now
    return _PROBE.load


def read_records(path: Path) -> dict[str, list[float]]:
    """The recorded values of ``k`` by kind in ``path`` (empty if missing or unreadable)."""
    try:
        data = json.loads(path.read_text())
        kinds = data["k"]
        return {str(kind): [float(v) for v in values if math.isfinite(float(v)) and v > 0]
                for kind, values in kinds.items()}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return {}


def coefficient(kind: str, records: dict[str, list[float]]) -> tuple[float, str]:
    """``k`` of a kind (s per unit per probe second) and where it came from.

    The median of the builds of that kind recorded on this machine, else :data:`KINDS`'
    reference value.
    """
    seen = records.get(kind, [])
    if seen:
        n = len(seen)
        return statistics.median(seen), f"the rate of {n} earlier build{'s' * (n > 1)} here"
    return KINDS[kind].k, "the reference rate"


def estimate(kind: str, size: float, probe: float,
             records: dict[str, list[float]], load: float = 1.0) -> Estimate:
    """The estimated time of a build: ``size * k[kind] * probe * load**LOAD_PERSISTENCE``
    (:func:`coefficient`).

    Parameters
    ----------
    kind : str
        A key of :data:`KINDS`.
    size : float
        The build's size, in the kind's unit.
    probe : float
        :func:`machine_probe` (s).
    records : dict
        :func:`read_records` of this machine.
    load : float
        :func:`load_factor` (1: an idle machine).
    """
    k, basis = coefficient(kind, records)
    return Estimate(seconds=size * k * probe * load**LOAD_PERSISTENCE,
                    basis=f"{size:g} {KINDS[kind].unit} at {basis}, "
                          f"machine probe {probe * 1e3:.0f} ms, load factor {load:.1f}")


def record(path: Path, kind: str, size: float, seconds: float, probe: float,
           load: float = 1.0) -> None:
    """Add a finished build's ``k = seconds / (size * probe * load**LOAD_PERSISTENCE)`` to
    ``path`` (atomic rewrite; ``load`` the :func:`load_factor` over the build).

    Unwritable caches are ignored: the record only improves later estimates.
    """
    if not (size > 0 and probe > 0 and seconds > 0 and load > 0):
        return
    records = read_records(path)
    values = records.setdefault(kind, [])
    values.append(seconds / (size * probe * load**LOAD_PERSISTENCE))
    del values[:-KEEP]
    try:
        path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".rates-", suffix=".json")
        with os.fdopen(fd, "w") as f:
            json.dump({"format": "heelstrike-build-rates-1", "k": records}, f, indent=1)
        os.replace(tmp, path)
    except OSError:
        pass


# ---------------------------------------------------------------------------------------------
# the messages
# ---------------------------------------------------------------------------------------------
def _seconds(s: float) -> str:
    """``'42 s'`` or ``'3 min 05 s'``."""
    if s < 100:
        return f"{s:.0f} s" if s >= 10 else f"{s:.1f} s"
    m, r = divmod(round(s), 60)
    return f"{m} min {r:02d} s"


def announce_text(what: str, est: Estimate, cache: str) -> str:
    """The line said before a build."""
    return (f"heelstrike: first use: {what}; estimated {_seconds(est.seconds)} on this machine "
            f"({est.basis}); cached afterwards in {cache}")


def stage_text(index: int, total: int, name: str, elapsed: float) -> str:
    """The line said as a stage starts."""
    of = f" of {total}" if total else ""
    return f"heelstrike:   [{_seconds(elapsed)}] stage {index}{of}: {name}"


def heartbeat_text(doing: str, elapsed: float, est: Estimate) -> str:
    """The line said every :data:`HEARTBEAT` seconds."""
    return (f"heelstrike:   [{_seconds(elapsed)}] still {doing} "
            f"(estimated {_seconds(est.seconds)} in all)")


def finish_text(what: str, built: str, seconds: float, est: Estimate, cache: str) -> str:
    """The line said after a build."""
    return (f"heelstrike: built {built} ({what}) in {_seconds(seconds)} (estimated "
            f"{_seconds(est.seconds)}); cache: {cache}")


# ---------------------------------------------------------------------------------------------
# a build
# ---------------------------------------------------------------------------------------------
@dataclass
class Build:
    """One announced build (see :func:`first_use`); nested builds are stages of the outer one.

    Attributes
    ----------
    what : str
        What is built, in words.
    estimate : Estimate
        Its estimated time.
    cache : str
        Where the result is cached.
    stages : int
        Number of stages announced (0: not known).
    quiet : bool
        Say nothing (a build estimated under :data:`QUIET_BELOW`, or nested in another).
    built : str
        What to name in the final line (a file name, say); default ``what``.
    """

    what: str
    estimate: Estimate
    cache: str
    stages: int = 0
    quiet: bool = False
    built: str = ""
    started: float = field(default_factory=time.monotonic)
    stage_index: int = 0
    doing: str = ""
    compiled: list[str] = field(default_factory=list)

    def say(self, line: str) -> None:
        """Print ``line`` on stderr (unless quiet)."""
        if not self.quiet:
            print(line, file=sys.stderr, flush=True)

    def elapsed(self) -> float:
        """Seconds (wall) since the build started."""
        return time.monotonic() - self.started

    def stage(self, name: str) -> None:
        """Announce the next stage, ``name``."""
        self.stage_index += 1
        self.doing = name
        self.say(stage_text(self.stage_index, self.stages, name, self.elapsed()))

    def compiling(self, name: str) -> None:
        """Note a function being compiled inside the build (shown by the heartbeat)."""
        self.compiled.append(name)
        self.doing = f"{self.doing.split(' (now:')[0]} (now: {name}, function " \
                     f"{len(self.compiled)} compiled)"

    def beat(self) -> None:
        """One heartbeat line."""
        self.say(heartbeat_text(self.doing or self.what, self.elapsed(), self.estimate))


class _Active:
    """The builds in progress, outermost first (an object: state of the process)."""

    def __init__(self) -> None:
        self.stack: list[Build] = []
        self.lock = threading.RLock()


_ACTIVE = _Active()


def _heartbeat(build: Build, stop: threading.Event, interval: float) -> None:
    while not stop.wait(interval):
        build.beat()


@contextmanager
def first_use(what: str, *, kind: str, size: float, cache: Path | str,
              stages: int = 0, built: str = "", quiet: bool = False,
              heartbeat: float | None = HEARTBEAT) -> Iterator[Build]:
    """Announce, follow and report one build (a derivation or a compile).

    Parameters
    ----------
    what : str
        What is built, in words ("the kneed walker's kernels, ahead of time").
    kind : str
        A key of :data:`KINDS` (the rate used for the estimate, and recorded).
    size : float
        The build's size in the kind's unit.
    cache : path or str
        Where the result is cached (named before and after).
    stages : int
        How many stages the caller will announce with :meth:`Build.stage` (0: not counted).
    built : str
        What the final line names as built (default ``what``).
    quiet : bool
        Say nothing (the build is still timed and recorded).
    heartbeat : float or None
        Seconds between heartbeat lines (None: none).

    Yields
    ------
    Build
        Call ``stage(name)`` as each stage starts. Inside another build, this one is said as a
        stage of it (no heartbeat of its own).

    Notes
    -----
    The rate of a build that completes is recorded beside the cache (:func:`record`); a build
    that raises is reported as failed and not recorded.
    """
    from heelstrike.models._generated import cache_dir

    rates = cache_dir() / RATES_FILE
    probe = machine_probe()
    load = current_load()
    est = estimate(kind, size, probe, read_records(rates), load)
    with _ACTIVE.lock:
        outer = _ACTIVE.stack[-1] if _ACTIVE.stack else None
        b = Build(what=what, estimate=est, cache=str(cache), stages=stages, built=built or what,
                  quiet=quiet or outer is not None or est.seconds < QUIET_BELOW)
        _ACTIVE.stack.append(b)
    if outer is not None and not quiet:
        outer.stage(f"{what} (estimated {_seconds(est.seconds)})")
    b.say(announce_text(what, est, str(cache)))
    stop = threading.Event()
    beat = None
    if heartbeat is not None and outer is None and not b.quiet:
        beat = threading.Thread(target=_heartbeat, args=(b, stop, heartbeat), daemon=True)
        beat.start()
    ok = False
    try:
        yield b
        ok = True
    finally:
        stop.set()
        if beat is not None:
            beat.join()
        with _ACTIVE.lock:
            _ACTIVE.stack.remove(b)
        took = b.elapsed()
        if ok:
            if took >= QUIET_BELOW:  # a tiny compile's overhead says little about a rate
                # the load over the build: the mean of the factors at its start and end
                record(rates, kind, size, took, probe, 0.5 * (load + current_load()))
            b.say(finish_text(what, b.built, took, est, str(cache)))
        else:
            b.say(f"heelstrike: {what}: failed after {_seconds(took)}")


def active() -> Build | None:
    """The innermost build in progress, or None."""
    with _ACTIVE.lock:
        return _ACTIVE.stack[-1] if _ACTIVE.stack else None


# ---------------------------------------------------------------------------------------------
# numba's JIT compiles
# ---------------------------------------------------------------------------------------------
def _source_lines(fn: Any) -> int:
    code = getattr(getattr(fn, "py_func", fn), "__code__", None)
    if code is None:
        return 1
    lines = [ln for _, _, ln in code.co_lines() if ln is not None]
    return max(1, max(lines) - code.co_firstlineno + 1) if lines else 1


def _numba_cache(dispatcher: Any) -> str:
    path = getattr(getattr(dispatcher, "_cache", None), "_cache_path", None)
    return str(path) if path else "nowhere (compiled in every process)"


class _NumbaBuilds:
    """The JIT compiles announced by the listener (an object: state of the process)."""

    def __init__(self) -> None:
        self.depth = 0
        self.contexts: list[Any] = []


_NUMBA = _NumbaBuilds()


def numba_compile_started(data: Any) -> None:
    """Announce a numba JIT compile (the start of a ``numba:compile`` event, ``data`` its
    details) as a build of kind ``jit`` sized by the lines of the function, or, inside an
    announced build, name it in that build's heartbeat. Never raises (a report must not break
    a compile)."""
    try:
        _numba_started(data)
    except Exception:  # pragma: no cover - defensive
        pass


def numba_compile_ended(exc: BaseException | None) -> None:
    """Close what :func:`numba_compile_started` opened (``exc``: the compile's error, if
    any). Never raises."""
    try:
        _numba_ended(exc)
    except Exception:  # pragma: no cover - defensive
        pass


def _numba_started(data: Any) -> None:
    disp = (data or {}).get("dispatcher")
    name = getattr(getattr(disp, "py_func", None), "__qualname__", "a function")
    with _ACTIVE.lock:
        _NUMBA.depth += 1
        _NUMBA.contexts.append(None)  # one entry per event, whatever happens below
        slot = len(_NUMBA.contexts) - 1
        outer = _ACTIVE.stack[-1] if _ACTIVE.stack else None
        if outer is not None:  # a function of an announced build (or of a JIT compile)
            outer.compiling(name)
            return
    ctx = first_use(f"numba JIT compile of {name}", kind="jit", size=_source_lines(disp),
                    cache=_numba_cache(disp), built=name)
    ctx.__enter__()
    _NUMBA.contexts[slot] = ctx


def _numba_ended(exc: BaseException | None) -> None:
    with _ACTIVE.lock:
        _NUMBA.depth -= 1
        ctx = _NUMBA.contexts.pop() if _NUMBA.contexts else None
    if ctx is not None:
        if exc is None:
            ctx.__exit__(None, None, None)
        else:
            ctx.__exit__(type(exc), exc, exc.__traceback__)
