"""Sweep stores: identified by their real path, metadata verified and rebuilt, coordinates
checked, and every object a function reads part of its identity (issue 36)."""

from __future__ import annotations

import functools
import threading
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from heelstrike.analysis.sweep import (
    SweepError,
    SweepStoreLockedError,
    SweepStoreMismatchError,
    SweepStoreRepairWarning,
    sweep,
)

pytestmark = pytest.mark.scale
pytest.importorskip("zarr")
filelock = pytest.importorskip("filelock")

GRID = {"a": np.arange(6.0), "b": np.arange(4.0)}
UNITS = {"a": "1", "b": "1", "y": "1"}
CALLS: list[int] = []


def added(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
    CALLS.append(1)
    return {"y": a + 10.0 * b}


def _run(func: Any, store: Path, **kw: Any) -> Any:
    CALLS.clear()
    return sweep(func, GRID, chunks=2, store=store, units=UNITS, progress=False,
                 scheduler="sync", **kw)


def _check(ds: Any) -> None:
    np.testing.assert_array_equal(ds["a"].values, GRID["a"])
    np.testing.assert_array_equal(ds["b"].values, GRID["b"])
    np.testing.assert_array_equal(ds["y"].values, GRID["a"][:, None] + 10 * GRID["b"][None])


def _truncate(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])


def test_a_symlink_to_a_store_takes_the_store_s_own_lock(tmp_path):
    store = tmp_path / "s.zarr"
    _run(added, store)
    link = tmp_path / "link.zarr"
    link.symlink_to(store)
    with filelock.FileLock(str(tmp_path / "s.zarr.lock"), timeout=0):
        with pytest.raises(SweepStoreLockedError):
            _run(added, link)


@pytest.mark.parametrize("damaged", [
    "_heelstrike_sweep/done/c/0/0",          # the completion record
    "_heelstrike_sweep/checksum/c/0/0/0",    # the chunks' checksums
    "_heelstrike_sweep/done/zarr.json",      # metadata
    "y/zarr.json",
    "zarr.json",
])
def test_damaged_metadata_is_rebuilt_from_what_still_verifies(tmp_path, damaged):
    store = tmp_path / "s.zarr"
    _run(added, store)
    _truncate(store / damaged)
    with pytest.warns(SweepStoreRepairWarning):
        ds = _run(added, store)
    assert CALLS == []  # every finished chunk verified: nothing computed again
    _check(ds)
    with warnings.catch_warnings():
        warnings.simplefilter("error", SweepStoreRepairWarning)
        _check(_run(added, store))  # healed: a clean resume


def test_tampered_coordinates_are_detected_and_rewritten(tmp_path):
    import zarr

    store = tmp_path / "s.zarr"
    _run(added, store)
    root = zarr.open_group(str(store), mode="r+")
    coord: Any = root["a"]
    coord[...] = GRID["a"][::-1]
    with pytest.warns(SweepStoreRepairWarning, match="coordinate"):
        ds = _run(added, store)
    _check(ds)


class Cfg:
    def __init__(self, k: float) -> None:
        self.k = k


cfg = Cfg(1.0)


def reads_global_attribute(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
    return {"y": a * cfg.k + b}


def reads_argument_attribute(a: np.ndarray, b: np.ndarray, *, obj: Cfg) -> dict[str, Any]:
    return {"y": a * obj.k + b}


class Holder:
    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.k = 1.0


HOLDER = Holder()


def reads_a_lock(a: np.ndarray, b: np.ndarray) -> dict[str, np.ndarray]:
    with HOLDER.lock:
        return {"y": a * HOLDER.k + b}


def test_a_changed_global_attribute_is_not_resumed(tmp_path, monkeypatch):
    store = tmp_path / "s.zarr"
    _run(reads_global_attribute, store)
    monkeypatch.setattr(cfg, "k", 2.0)
    with pytest.raises(SweepStoreMismatchError, match=r"function\.globals"):
        _run(reads_global_attribute, store)


def test_a_changed_partial_object_is_not_resumed(tmp_path):
    store = tmp_path / "s.zarr"
    _run(functools.partial(reads_argument_attribute, obj=Cfg(1.0)), store)
    _run(functools.partial(reads_argument_attribute, obj=Cfg(1.0)), store)
    assert CALLS == []  # the same object's values: resumed
    with pytest.raises(SweepStoreMismatchError, match=r"function\.bound"):
        _run(functools.partial(reads_argument_attribute, obj=Cfg(2.0)), store)


def test_an_object_that_cannot_be_identified_refuses_the_resume_naming_it(tmp_path):
    store = tmp_path / "s.zarr"
    _run(reads_a_lock, store)
    with pytest.raises(SweepError, match=r"cannot be resumed.*HOLDER\.lock"):
        _run(reads_a_lock, store)
    _run(reads_a_lock, store, overwrite=True)  # computing afresh is allowed
