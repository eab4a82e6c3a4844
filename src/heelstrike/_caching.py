"""Caches that may fail: one line when a cache cannot be written, and the code runs uncached.

Used by the generated-code cache (:mod:`heelstrike.models._generated`) and by every module
that compiles numba functions with ``cache=True`` (:func:`tolerate_numba_cache_errors`, called
before their decorators run). Importing this module imports nothing heavy.
"""

from __future__ import annotations

import warnings
from typing import Any

__all__ = ["CacheWarning", "note_uncached", "tolerate_numba_cache_errors"]


class CacheWarning(UserWarning):
    """A cache entry was refused (unsafe permissions, failed verification) and rebuilt, or a
    cache cannot be written and the code runs uncached."""


def note_uncached(what: str) -> None:
    """One :class:`CacheWarning` per process: a cache cannot be written, code runs uncached."""
    if _UNCACHED:  # said once: every later write fails the same way
        return
    _UNCACHED.append(what)
    warnings.warn(f"heelstrike: {what}; running uncached (compiled again on each run)",
                  CacheWarning, stacklevel=3)


_UNCACHED: list[str] = []


def tolerate_numba_cache_errors() -> None:
    """Make numba's disk cache optional: a cache that cannot be written (a full disk, a
    read-only or missing folder) disables caching of that function, with one
    :class:`CacheWarning` per process, instead of failing the computation.

    Installed once per process, before the ``cache=True`` functions are decorated (numba
    looks for a writable cache folder when a function is decorated, and writes the cache
    when it compiles).
    """
    from numba.core import caching, dispatcher

    if getattr(caching.Cache.save_overload, "_heelstrike", False):
        return
    save = caching.Cache.save_overload
    enable = dispatcher.Dispatcher.enable_caching

    def save_overload(self: Any, sig: Any, data: Any) -> None:
        try:
            save(self, sig, data)
        except OSError as exc:
            self.disable()
            where = getattr(self, "_cache_path", "its folder")
            note_uncached(f"cannot write numba's cache {where} ({exc.strerror or exc})")

    def enable_caching(self: Any) -> None:
        try:
            enable(self)
        except (RuntimeError, OSError) as exc:
            note_uncached(f"numba cannot cache {getattr(self, '__qualname__', 'a function')} "
                           f"({exc})")

    save_overload._heelstrike = True  # type: ignore[attr-defined]
    caching.Cache.save_overload = save_overload  # type: ignore[method-assign]
    dispatcher.Dispatcher.enable_caching = enable_caching  # type: ignore[method-assign]
