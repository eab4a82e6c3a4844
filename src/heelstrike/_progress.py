"""Progress bars on stderr: one place that decides when they are shown.

A bar is drawn on an interactive terminal only (tqdm's ``disable=None``: a log file, a pipe or a
captured stream never receives the carriage-return frames of a bar, so what a command prints to
a file does not depend on how fast the machine ran it). ``HEELSTRIKE_PROGRESS=1`` shows bars on
any stream, ``HEELSTRIKE_PROGRESS=0`` hides them everywhere.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable
from typing import Any

#: Seconds a task must run before its bar appears (short tasks stay silent).
PROGRESS_DELAY = 2.0


def progress_disabled() -> bool | None:
    """tqdm's ``disable`` argument from ``HEELSTRIKE_PROGRESS``.

    Returns
    -------
    bool or None
        ``False`` (always shown) for ``1``/``true``/``yes``/``always``, ``True`` (never shown)
        for ``0``/``false``/``no``/``never``, otherwise ``None``: shown on a terminal only.
    """
    value = os.environ.get("HEELSTRIKE_PROGRESS", "").strip().lower()
    if value in ("1", "true", "yes", "always"):
        return False
    if value in ("0", "false", "no", "never"):
        return True
    return None


def progress_bar(iterable: Iterable[Any] | None = None, *, desc: str, total: int | None = None,
                 unit: str = "it", delay: float = PROGRESS_DELAY, leave: bool = False,
                 enabled: bool = True, **kwargs: Any) -> Any:
    """A tqdm bar on stderr, shown as :func:`progress_disabled` says.

    Parameters
    ----------
    iterable : iterable, optional
        Items to wrap (as ``tqdm(iterable)``); omit it and call ``update`` yourself.
    desc : str
        What is being done, e.g. ``"heelstrike: basin"``.
    total : int, optional
        Number of units of work.
    unit : str
        Name of one unit of work.
    delay : float
        Seconds (s) before the bar appears.
    leave : bool
        Keep the finished bar on screen.
    enabled : bool
        ``False`` never shows it (the caller asked for no progress).
    **kwargs
        Passed to tqdm.

    Returns
    -------
    tqdm.tqdm
        The bar (a context manager and an iterable when ``iterable`` is given).
    """
    import tqdm.auto

    disable = True if not enabled else progress_disabled()
    return tqdm.auto.tqdm(iterable, desc=desc, total=total, unit=unit, delay=delay, leave=leave,
                          file=sys.stderr, disable=disable, **kwargs)
