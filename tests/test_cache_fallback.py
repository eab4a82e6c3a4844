"""Caches that cannot be written run uncached with one line; damaged entries are rebuilt; numeric
warnings are one line (issue 36)."""

from __future__ import annotations

import importlib.util
import sys
import warnings

import pytest

from heelstrike import _caching
from heelstrike.cli._common import warnings_as_notes
from heelstrike.models._generated import CacheWarning, read_cached, write_cached


@pytest.fixture(autouse=True)
def _fresh_note(monkeypatch):
    monkeypatch.setattr(_caching, "_UNCACHED", [])


def test_an_entry_cut_at_a_line_boundary_fails_verification(tmp_path):
    path = tmp_path / "cache" / "entry.py"
    source = "def f(x):\n    return x\n\n\ndef g(x):\n    return 2 * x\n"
    assert write_cached(path, source) == path
    assert read_cached(path) == source
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines[:2]))  # still valid Python, one function short
    with pytest.warns(CacheWarning, match="incomplete or damaged"):
        assert read_cached(path) is None


def test_an_unwritable_model_cache_runs_uncached_with_one_line(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.warns(CacheWarning, match="running uncached") as seen:
        assert write_cached(blocker / "models" / "a.py", "x = 1\n") is None
        assert write_cached(blocker / "models" / "b.py", "x = 2\n") is None
    assert len([w for w in seen if issubclass(w.category, CacheWarning)]) == 1


def test_a_full_disk_for_numba_s_cache_runs_uncached(tmp_path, monkeypatch):
    pytest.importorskip("numba")
    from numba.core import caching

    _caching.tolerate_numba_cache_errors()
    (tmp_path / "hs_cached_mod.py").write_text(
        "from numba import njit\n\n@njit(cache=True)\ndef plus_one(x):\n    return x + 1\n")

    def full(self, key, data):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(caching.IndexDataCacheFile, "save", full)
    spec = importlib.util.spec_from_file_location("hs_cached_mod", tmp_path / "hs_cached_mod.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, "hs_cached_mod", module)
    spec.loader.exec_module(module)
    with pytest.warns(CacheWarning, match="No space left on device.*running uncached"):
        assert module.plus_one(1) == 2
    assert module.plus_one(2.5) == 3.5  # later compilations too, said once


def test_numeric_and_cache_warnings_are_one_line_each(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("HEELSTRIKE_CACHE_DIR", str(tmp_path))
    generated = tmp_path / "models" / "abc.py"
    with warnings_as_notes(RuntimeWarning, CacheWarning):
        for _ in range(3):
            warnings.warn_explicit("overflow encountered in scalar add", RuntimeWarning,
                                   str(generated), 181)
        warnings.warn("heelstrike: cannot write the model-code cache x; running uncached",
                      CacheWarning, stacklevel=2)
    err = capsys.readouterr().err.splitlines()
    assert err == [
        "heelstrike: note: numerical warning in the walker's generated model code: overflow "
        "encountered in scalar add (3 times)",
        "heelstrike: note: cannot write the model-code cache x; running uncached",
    ]
