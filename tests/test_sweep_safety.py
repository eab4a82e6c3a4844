"""Data safety of sweep stores (issue 11, items 14-15): locking, identity, checksums, CLI resume."""

from __future__ import annotations

import dataclasses
import functools
import importlib
import re
import subprocess
import sys
import textwrap
import threading
import time
import types
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import xarray as xr

from heelstrike.analysis import sweep as sweep_module
from heelstrike.analysis.sweep import (
    SweepStoreLockedError,
    SweepStoreMismatchError,
    SweepStoreRepairWarning,
    sweep,
    sweep_progress,
)
from heelstrike.dynamics.hybrid import WalkStatus

pytestmark = pytest.mark.scale  # stores need zarr and filelock
zarr = pytest.importorskip("zarr")
pytest.importorskip("filelock")

A = np.linspace(0.0, 1.0, 7)
B = np.linspace(-1.0, 2.0, 5)
GRID = {"a": A, "b": B}
UNITS = {"a": "1", "b": "1", "y": "1", "positive": "1", "pair": "1"}
CHUNKS = {"a": 2, "b": 2}  # 4 x 3 = 12 chunks, ragged edges
N_CHUNKS = 12


class _Counter:
    """Chunk calls, thread-safe (not plain data: not part of a sweep's identity)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.calls: list[tuple[float, float]] = []
        self.gate: threading.Event | None = None

    def record(self, a: np.ndarray, b: np.ndarray) -> None:
        with self.lock:
            self.calls.append((float(a.flat[0]), float(b.flat[0])))
        if self.gate is not None:
            self.gate.wait(30.0)


COUNTER = _Counter()
SCALE = 1.0  # a module constant read by ``scaled``


def _values(a: np.ndarray, b: np.ndarray, scale: float) -> dict[str, np.ndarray]:
    y = scale * np.sin(3.0 * a) * np.exp(b) + a * b
    return {"y": y, "positive": y > 0.0, "pair": np.stack(np.broadcast_arrays(y, -y), axis=-1)}


def counted(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
    COUNTER.record(a, b)
    return _values(a, b, 1.0)


def scaled(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
    COUNTER.record(a, b)
    return _values(a, b, SCALE)


@dataclasses.dataclass(frozen=True, kw_only=True)
class _Scaling:
    """A model object read as a module global (as a walker would be)."""

    scale: float = 1.0


MODEL = _Scaling()


def modelled(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
    COUNTER.record(a, b)
    return _values(a, b, MODEL.scale)


#: A configuration module set at run time (``CONFIG.SCALE = x``), read as ``CONFIG.SCALE``.
CONFIG = types.ModuleType("sweep_test_config")
CONFIG.SCALE = 1.0  # type: ignore[attr-defined]

#: Walkers held in a list, as a script keeps several.
MODELS = [_Scaling()]


def configured(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
    COUNTER.record(a, b)
    return _values(a, b, CONFIG.SCALE)  # type: ignore[attr-defined]


def listed(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
    COUNTER.record(a, b)
    return _values(a, b, MODELS[0].scale)


def with_default(a: np.ndarray, b: np.ndarray, *, scale: float = 1.0) -> dict[str, np.ndarray]:
    COUNTER.record(a, b)
    return _values(a, b, scale)


def with_partial(a: np.ndarray, b: np.ndarray, *, scale: float) -> dict[str, np.ndarray]:
    COUNTER.record(a, b)
    return _values(a, b, scale)


def make_closure(scale: float) -> Any:
    def closure(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
        COUNTER.record(a, b)
        return _values(a, b, scale)

    return closure


def _helper(y: np.ndarray) -> np.ndarray:
    return y


def via_helper(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
    COUNTER.record(a, b)
    out = _values(a, b, 1.0)
    out["y"] = _helper(out["y"])
    return out


def _direct(scale: float = 1.0) -> dict[str, np.ndarray]:
    return _values(A[:, None], B[None, :], scale)


def _assert_values(ds: xr.Dataset, scale: float = 1.0) -> None:
    direct = _direct(scale)
    for name, value in direct.items():
        np.testing.assert_array_equal(ds[name].values, value)


@pytest.fixture
def counter() -> Any:
    COUNTER.calls = []
    COUNTER.gate = None
    yield COUNTER
    COUNTER.calls = []
    COUNTER.gate = None


def _run(func: Any, store: Path, **kw: Any) -> xr.Dataset:
    return sweep(func, GRID, chunks=CHUNKS, store=store, units=UNITS, progress=False,
                 scheduler="sync", **kw).load()


# -- 14a: one sweep at a time per store ----------------------------------------------------------
def test_second_sweep_on_a_busy_store_fails_fast(tmp_path: Path, counter: Any) -> None:
    store = tmp_path / "s.zarr"
    counter.gate = threading.Event()
    result: dict[str, Any] = {}

    def first() -> None:
        try:
            result["ds"] = _run(counted, store)
        except BaseException as exc:  # pragma: no cover - reported below
            result["error"] = exc

    t = threading.Thread(target=first)
    t.start()
    try:
        for _ in range(3000):  # the first sweep is inside its first chunk
            if counter.calls:
                break
            time.sleep(0.01)
        assert counter.calls, "first sweep did not start"
        with pytest.raises(SweepStoreLockedError, match="in use by another sweep"):
            _run(counted, store)
        with pytest.raises(SweepStoreLockedError):
            _run(counted, store, overwrite=True)  # nor may it delete the busy store
    finally:
        counter.gate.set()
        t.join(60)
    assert "error" not in result
    assert sweep_progress(store) == (N_CHUNKS, N_CHUNKS)
    _assert_values(result["ds"])
    counter.calls = []
    counter.gate = None
    _assert_values(_run(counted, store))  # the lock was released: reopened, nothing computed
    assert counter.calls == []


_SCRIPT = """
import sys, time
from pathlib import Path
import numpy as np
from heelstrike.analysis.sweep import SweepStoreLockedError, sweep

GO = Path(sys.argv[2])
CALLS = []

def slow(a, b):
    while not GO.exists():  # the chunk runs until the test says go
        time.sleep(0.01)
    CALLS.append(1)
    return {"y": np.sin(3.0 * a) * np.exp(b) + a * b}

grid = {"a": np.linspace(0.0, 1.0, 7), "b": np.linspace(-1.0, 2.0, 5)}
timeout = None if sys.argv[3] == "wait" else 0.0
try:
    sweep(slow, grid, chunks={"a": 2, "b": 2}, store=sys.argv[1], units={"a": "1", "b": "1"},
          progress=False, scheduler="threads", num_workers=2, lock_timeout=timeout)
except SweepStoreLockedError as exc:
    print("LOCKED", exc, flush=True)
    sys.exit(3)
print("COMPUTED", len(CALLS), flush=True)
"""


@pytest.mark.slow  # three interpreters
def test_two_processes_on_one_store_keep_it_whole(tmp_path: Path) -> None:
    script = tmp_path / "two.py"
    script.write_text(_SCRIPT)
    store, go = tmp_path / "s.zarr", tmp_path / "go"

    def start(mode: str) -> subprocess.Popen[str]:
        return subprocess.Popen([sys.executable, str(script), str(store), str(go), mode],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    first = start("fail")
    try:
        for _ in range(6000):  # wait until the first sweep holds the lock
            if (tmp_path / "s.zarr.lock").exists() or first.poll() is not None:
                break
            time.sleep(0.01)
        time.sleep(0.2)
        refused = start("fail")
        out, err = refused.communicate(timeout=120)
        assert refused.returncode == 3, err
        assert out.startswith("LOCKED") and "s.zarr" in out
        waiting = start("wait")  # waits for the lock, then finds every chunk done
        time.sleep(0.5)
        assert waiting.poll() is None
    finally:
        go.touch()
    out1, err1 = first.communicate(timeout=120)
    assert first.returncode == 0, err1
    assert out1.split() == ["COMPUTED", str(N_CHUNKS)]
    out2, err2 = waiting.communicate(timeout=120)
    assert waiting.returncode == 0, err2
    assert out2.split() == ["COMPUTED", "0"]
    assert sweep_progress(store) == (N_CHUNKS, N_CHUNKS)
    ds = xr.open_zarr(store, consolidated=False)
    np.testing.assert_array_equal(ds["y"].values, _direct()["y"])


# -- 14b: the identity covers what the function computes -----------------------------------------
def test_changed_closure_value_is_not_resumed(tmp_path: Path, counter: Any) -> None:
    store = tmp_path / "s.zarr"
    _assert_values(_run(make_closure(1.0), store), 1.0)
    counter.calls = []
    _assert_values(_run(make_closure(1.0), store), 1.0)  # same closure value: reopened
    assert counter.calls == []
    with pytest.raises(SweepStoreMismatchError, match=r"function\.closure"):
        _run(make_closure(2.0), store)
    assert counter.calls == []
    _assert_values(_run(make_closure(2.0), store, overwrite=True), 2.0)
    assert len(counter.calls) == N_CHUNKS


def test_changed_module_constant_is_not_resumed(
    tmp_path: Path, counter: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    store = tmp_path / "s.zarr"
    _assert_values(_run(scaled, store), 1.0)
    monkeypatch.setattr(sys.modules[__name__], "SCALE", 3.0)
    with pytest.raises(SweepStoreMismatchError, match=r"function\.globals"):
        _run(scaled, store)
    counter.calls = []
    _assert_values(_run(scaled, store, overwrite=True), 3.0)
    assert len(counter.calls) == N_CHUNKS


def test_changed_dataclass_global_is_not_resumed(
    tmp_path: Path, counter: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    # QA sweep 5: a walker read from a module global counted by name only, so a resume after
    # changing it mixed chunks of two walkers in one store
    store = tmp_path / "s.zarr"
    _assert_values(_run(modelled, store), 1.0)
    monkeypatch.setattr(sys.modules[__name__], "MODEL", _Scaling(scale=2.0))
    with pytest.raises(SweepStoreMismatchError, match=r"function\.globals"):
        _run(modelled, store)
    counter.calls = []
    _assert_values(_run(modelled, store, overwrite=True), 2.0)
    assert len(counter.calls) == N_CHUNKS


@pytest.mark.parametrize(("func", "change"), [
    (configured, lambda mp: mp.setattr(CONFIG, "SCALE", 2.0)),
    (listed, lambda mp: mp.setattr(sys.modules[__name__], "MODELS", [_Scaling(scale=2.0)])),
])
def test_changed_module_attribute_or_list_of_walkers_is_not_resumed(
    tmp_path: Path, counter: Any, monkeypatch: pytest.MonkeyPatch, func: Any, change: Any
) -> None:
    # QA sweep 13: a module attribute read as ``CONFIG.SCALE`` and a list of dataclasses
    # counted by name only, so a store of the old values was resumed silently
    store = tmp_path / "s.zarr"
    _assert_values(_run(func, store), 1.0)
    change(monkeypatch)
    with pytest.raises(SweepStoreMismatchError, match=r"function\.globals"):
        _run(func, store)
    counter.calls = []
    _assert_values(_run(func, store, overwrite=True), 2.0)
    assert len(counter.calls) == N_CHUNKS


def test_overwrite_replaces_only_a_sweep_store(tmp_path: Path, counter: Any) -> None:
    # QA sweep 13: overwrite=True removed any folder given as the store, with what it held
    folder = tmp_path / "thesis"
    (folder / "chapters").mkdir(parents=True)
    (folder / "thesis.tex").write_text("years of work")
    with pytest.raises(sweep_module.SweepError, match="not a heelstrike sweep store"):
        _run(counted, folder, overwrite=True)
    assert (folder / "thesis.tex").read_text() == "years of work"
    assert sorted(p.name for p in folder.iterdir()) == ["chapters", "thesis.tex"]
    a_file = tmp_path / "notes.txt"
    a_file.write_text("keep")
    with pytest.raises(sweep_module.SweepError, match=r"\(a file\)"):
        _run(counted, a_file, overwrite=True)
    assert a_file.read_text() == "keep"
    assert counter.calls == []  # refused before computing anything
    store = tmp_path / "s.zarr"  # a sweep store is replaced
    _assert_values(_run(make_closure(1.0), store), 1.0)
    _assert_values(_run(make_closure(2.0), store, overwrite=True), 2.0)
    empty = tmp_path / "made_for_it"  # an empty folder is where the store is made
    empty.mkdir()
    _assert_values(_run(make_closure(1.0), empty), 1.0)
    assert sweep_progress(empty) == (N_CHUNKS, N_CHUNKS)


def uses_builtin_names(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
    COUNTER.record(a, b)
    assert isinstance(np.asarray(str(a.dtype)), object)  # ``np`` with ``str``, ``object``
    return _values(a, b, 1.0)


def test_the_identity_reads_no_attribute_of_a_library_module(
    tmp_path: Path, counter: Any
) -> None:
    # QA sweep 13: reading ``module.NAME`` values went through numpy too, where
    # ``getattr(np, "object")`` warns (two FutureWarnings on every basin and map run)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _assert_values(_run(uses_builtin_names, tmp_path / "s.zarr"), 1.0)


def test_a_failing_point_is_located_in_the_grid(counter: Any) -> None:
    # QA sweep 13: the caller's exception, unchanged in type, says which chunk and grid values
    def fails_at_large_a(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
        if np.any(a > 0.9):
            raise ValueError("a too large")
        return _values(a, b, 1.0)

    with pytest.raises(ValueError, match="a too large") as info:
        sweep(fails_at_large_a, GRID, chunks=CHUNKS, units=UNITS, progress=False,
              scheduler="sync")
    notes = getattr(info.value, "__notes__", [])
    assert len(notes) == 1
    m = re.fullmatch(r"in sweep chunk \(3, (\d)\): a 1, b (.+)", notes[0])
    assert m is not None, notes
    j = int(m.group(2 - 1))
    b = B[2 * j:2 * j + 2]  # the chunk's b values (chunks of 2, the last one ragged)
    assert m.group(2) == (f"{b[0]:g}" if b.size == 1 else f"{b[0]:g}..{b[-1]:g}")


def test_changed_default_is_not_resumed(
    tmp_path: Path, counter: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    store = tmp_path / "s.zarr"
    _assert_values(_run(with_default, store), 1.0)
    monkeypatch.setattr(with_default, "__kwdefaults__", {"scale": 0.5})
    with pytest.raises(SweepStoreMismatchError, match=r"function\.defaults"):
        _run(with_default, store)
    _assert_values(_run(with_default, store, overwrite=True), 0.5)


def test_changed_bound_argument_helper_or_version_is_not_resumed(
    tmp_path: Path, counter: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    store = tmp_path / "s.zarr"
    _run(functools.partial(with_partial, scale=1.0), store)
    with pytest.raises(SweepStoreMismatchError, match=r"function\.bound"):
        _run(functools.partial(with_partial, scale=2.0), store)

    store2 = tmp_path / "h.zarr"
    _assert_values(_run(via_helper, store2))
    monkeypatch.setattr(sys.modules[__name__], "_helper", lambda y: 2.0 * y)
    with pytest.raises(SweepStoreMismatchError, match=r"function\.code"):
        _run(via_helper, store2)
    monkeypatch.undo()

    _run(counted, store2, overwrite=True)
    monkeypatch.setattr(sweep_module, "_heelstrike_version", lambda: "0.0.0-other")
    with pytest.raises(SweepStoreMismatchError, match="heelstrike_version"):
        _run(counted, store2)


def test_edited_module_source_is_not_resumed(tmp_path: Path, counter: Any,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """A constant and a default edited in the file of the sweep function's module."""
    monkeypatch.syspath_prepend(str(tmp_path))
    src = tmp_path / "user_sweep_mod.py"
    template = textwrap.dedent("""
        import numpy as np
        GAIN = {gain}

        def f(a, b, offset={offset}):
            return {{"y": GAIN * np.sin(3.0 * a) * np.exp(b) + a * b + offset}}
    """)
    src.write_text(template.format(gain=1.0, offset=0.0))
    mod = importlib.import_module("user_sweep_mod")
    store = tmp_path / "s.zarr"
    first = _run(mod.f, store)
    np.testing.assert_array_equal(first["y"].values, _direct()["y"])
    for gain, offset, what in ((2.0, 0.0, "globals"), (1.0, 0.25, "defaults")):
        # a different size too, so that the import system does not reuse a stale .pyc
        src.write_text(template.format(gain=gain, offset=offset) + "\n" * int(4 * gain + offset))
        mod = importlib.reload(mod)
        with pytest.raises(SweepStoreMismatchError, match=rf"function\.({what}|modules)"):
            _run(mod.f, store)
        again = _run(mod.f, tmp_path / f"{what}.zarr")
        np.testing.assert_allclose(again["y"].values, gain * _direct()["y"]
                                   - (gain - 1) * (A[:, None] * B[None, :]) + offset, rtol=1e-14)


# -- 14c: checksums of finished chunks -----------------------------------------------------------
def _chunk_file(store: Path, var: str, index: tuple[int, ...]) -> Path:
    arr = zarr.open_array(str(store / var), mode="r")
    key = arr.metadata.encode_chunk_key(index)
    path = store / var / key
    assert path.is_file(), path
    return path


def test_deleted_or_overwritten_chunks_are_recomputed(tmp_path: Path, counter: Any) -> None:
    store = tmp_path / "s.zarr"
    _assert_values(_run(counted, store))
    # chunk (0, 1): a data file deleted (reads back as fill values: NaN / False)
    _chunk_file(store, "y", (0, 1)).unlink()
    _chunk_file(store, "positive", (0, 1)).unlink()
    # chunk (1, 0): overwritten with valid but wrong values
    root = zarr.open_group(str(store), mode="r+")
    root["y"][2:4, 0:2] = 42.0
    # chunk (3, 2): overwritten with garbage bytes
    _chunk_file(store, "pair", (3, 2, 0)).write_bytes(b"not a zarr chunk")
    # chunk (2, 1): the data file of a boolean output deleted
    _chunk_file(store, "positive", (2, 1)).unlink()
    counter.calls = []
    with pytest.warns(SweepStoreRepairWarning, match="4 finished chunk"):
        resumed = _run(counted, store)
    assert sorted(counter.calls) == sorted(
        [(A[0], B[2]), (A[2], B[0]), (A[6], B[4]), (A[4], B[2])]
    )
    _assert_values(resumed)
    counter.calls = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # repaired: no warning, nothing recomputed
        _assert_values(_run(counted, store))
    assert counter.calls == []


# -- 15: basin, map and study cost resume from --store -------------------------------------------
def _interrupt_after(monkeypatch: pytest.MonkeyPatch, n: int) -> list[int]:
    """Ctrl-C (KeyboardInterrupt) as the sweep is about to record its ``n+1``-th chunk."""
    written: list[int] = []
    real = sweep_module._Store.write

    def write(self: Any, index: tuple[int, ...], result: Any) -> None:
        if len(written) >= n:
            raise KeyboardInterrupt
        real(self, index, result)
        written.append(1)

    monkeypatch.setattr(sweep_module._Store, "write", write)
    return written


def _computed(err: str) -> list[tuple[int, int, int]]:
    """``(done, total, computing)`` of every store log line on stderr."""
    import re

    return [tuple(map(int, m)) for m in re.findall(  # type: ignore[misc]
        r"(\d+) of (\d+) chunks already done, computing (\d+)", err)]


def _resume_check(
    argv: list[str], out_name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str], interrupt_after: int, data: str,
) -> tuple[list[tuple[int, int, int]], xr.Dataset, xr.Dataset]:
    from heelstrike.cli import main

    store = str(tmp_path / "store")
    _interrupt_after(monkeypatch, interrupt_after)
    assert main([*argv, "--out", str(tmp_path / "a"), "--store", store]) == 130
    err = capsys.readouterr().err
    assert "run the same command again to resume" in err
    monkeypatch.undo()
    assert main([*argv, "--out", str(tmp_path / "a"), "--store", store]) == 0
    resumed = _computed(capsys.readouterr().err)
    assert main([*argv, "--out", str(tmp_path / "b")]) == 0  # uninterrupted, no store
    capsys.readouterr()
    return (resumed, xr.load_dataset(tmp_path / "a" / data),
            xr.load_dataset(tmp_path / "b" / data))


def test_basin_command_resumes_from_store(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["basin", "--grid", "6x5", "--steps", "15", "--json", "--q3-range=-0.3:-0.24",
            "--q3dot-range", "1.0:1.2"]
    resumed, a, b = _resume_check(argv, "a", tmp_path, monkeypatch, capsys, 2, "basin.nc")
    assert resumed == [(2, 6, 4)]  # one chunk per q3 row; two were kept
    xr.testing.assert_identical(a, b)
    assert (a["outcome"] == WalkStatus.CONVERGED.code).any()  # some converge: a real basin


def test_map_command_resumes_from_store(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["map", "--radius", "0:0.1:3", "--slope", "3deg:3.5deg:2", "--json"]
    resumed, a, b = _resume_check(argv, "a", tmp_path, monkeypatch, capsys, 1, "gait_map.nc")
    assert resumed == [(1, 3, 2)]  # one chunk per radius
    xr.testing.assert_identical(a.drop_attrs(), b.drop_attrs())
    assert bool(a["stable"].all())


@pytest.mark.slow  # powered gaits: three study runs of two gaits each
def test_study_cost_command_resumes_from_store(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["study", "cost", "--radius", "0.5:0.6:2", "--step-length", "0.4:0.4:1"]
    resumed, a, b = _resume_check(argv, "a", tmp_path, monkeypatch, capsys, 1, "cost_study.nc")
    assert resumed == [(1, 1, 0), (0, 1, 1)]  # row 0 kept, row 1 computed
    xr.testing.assert_identical(a, b)
    assert np.isfinite(a["cost_of_transport"].values).all()


def test_study_cost_refuses_a_folder_that_is_not_its_store(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # QA sweep 13: the study wrote its rows into any folder given as --store, next to what it
    # held, where basin and map refuse a folder that is not a sweep store
    from heelstrike.cli import main

    folder = tmp_path / "notastore"
    folder.mkdir()
    (folder / "x.txt").write_text("data")
    argv = ["study", "cost", "--radius", "0:0.2:2", "--step-length", "0.3:0.4:2",
            "--out", str(tmp_path / "c")]
    assert main([*argv, "--store", str(folder)]) == 2
    err = capsys.readouterr().err
    assert "is not a heelstrike cost-study store (it holds 'x.txt')" in err
    assert sorted(p.name for p in folder.iterdir()) == ["x.txt"]
    (tmp_path / "afile").write_text("keep")
    assert main([*argv, "--store", str(tmp_path / "afile")]) == 2
    assert "is a file, not a heelstrike cost-study store" in capsys.readouterr().err
    assert (tmp_path / "afile").read_text() == "keep"


def test_store_of_other_arguments_is_refused_by_the_command(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from heelstrike.cli import main

    store = str(tmp_path / "store")
    argv = ["basin", "--grid", "4x3", "--steps", "10", "--json", "--out", str(tmp_path / "o")]
    assert main([*argv, "--store", store]) == 0
    capsys.readouterr()
    assert main([*argv, "--tol", "2e-3", "--store", store]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("heelstrike: error: --store")
    assert "different computation" in err[-1] and "function.bound" in err[-1]


def test_store_messages_speak_the_commands_terms(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # QA sweep 5 (P3): "differs in: function.bound" named no option; --out == --store failed
    # with "exists and is not a heelstrike sweep store"; a repaired store printed a raw Python
    # warning with its source line
    from heelstrike.cli import main

    store, out = tmp_path / "store", str(tmp_path / "o")
    argv = ["basin", "--grid", "4x3", "--steps", "10", "--json", "--out", out]
    assert main([*argv, "--store", str(store)]) == 0
    capsys.readouterr()
    assert main([*argv, "--tol", "2e-3", "--store", str(store)]) == 2
    assert "the command's options (walker, slope, steps, tol" in capsys.readouterr().err
    assert main([*argv, "--store", out]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--store and --out are both" in err[0]
    chunk = next(p for p in sorted((store / "status" / "c").rglob("*")) if p.is_file())
    chunk.unlink()  # a finished chunk's data deleted: recomputed, with a one-line note
    assert main([*argv, "--store", str(store)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    notes = [ln for ln in err if "failed checksum verification" in ln]
    assert len(notes) == 1 and notes[0].startswith("heelstrike: note: store")
    assert not any("Warning" in ln for ln in err)


_SIGINT_DRIVER = """
import os, signal, sys
from heelstrike.analysis import sweep
from heelstrike.cli import main

real, written = sweep._Store.write, []

def write(self, index, result):  # Ctrl-C from the terminal after two recorded chunks
    real(self, index, result)
    written.append(1)
    if len(written) == 2:
        os.kill(os.getpid(), signal.SIGINT)

sweep._Store.write = write
sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.slow  # three interpreters
def test_basin_command_resumes_after_sigint(tmp_path: Path) -> None:
    driver = tmp_path / "driver.py"
    driver.write_text(_SIGINT_DRIVER)
    argv = ["basin", "--grid", "6x5", "--steps", "15", "--json", "--store",
            str(tmp_path / "store")]

    def run(*cmd: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, *cmd], capture_output=True, text=True,
                              timeout=300)

    first = run(str(driver), *argv, "--out", str(tmp_path / "a"))
    assert first.returncode == 130, first.stderr
    assert first.stdout == ""
    done, total = sweep_progress(tmp_path / "store")
    assert 2 <= done < total == 6
    second = run("-m", "heelstrike.cli", *argv, "--out", str(tmp_path / "a"))
    assert second.returncode == 0, second.stderr
    assert _computed(second.stderr) == [(done, 6, 6 - done)]
    plain = run("-m", "heelstrike.cli", *argv[:-2], "--out", str(tmp_path / "b"))
    assert plain.returncode == 0, plain.stderr
    xr.testing.assert_identical(xr.load_dataset(tmp_path / "a" / "basin.nc"),
                                xr.load_dataset(tmp_path / "b" / "basin.nc"))
