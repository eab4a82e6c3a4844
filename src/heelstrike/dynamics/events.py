"""Typed events for the single-support integration.

scipy's ``solve_ivp`` reads ``terminal`` and ``direction`` attributes off plain callables. Here an
event is a frozen :class:`Event`; :func:`to_scipy` turns a tuple of them into what ``solve_ivp``
expects, so those attributes never leak into the rest of the package.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray

__all__ = ["Event", "to_scipy"]


@dataclass(frozen=True, kw_only=True)
class Event:
    """A zero crossing of ``function(t, x)`` that ends (or marks) an integration phase.

    Parameters
    ----------
    name : str
        What the crossing means (``"heel_strike"``, ``"fell_backward"`` ...).
    function : callable ``(t, x) -> float``
        Smooth scalar function of time (s) and the integrator state.
    direction : {-1, 0, 1}
        Only crossings from negative to positive (1), positive to negative (-1), or both (0).
    terminal : bool
        Whether the integration stops at the crossing.
    """

    name: str
    function: Callable[[float, NDArray[np.float64]], float]
    direction: Literal[-1, 0, 1] = 0
    terminal: bool = True


def to_scipy(events: Sequence[Event]) -> list[Callable[..., Any]]:
    """Wrap events as the callables with attributes that ``scipy.integrate.solve_ivp`` reads."""
    wrapped: list[Callable[..., Any]] = []
    for ev in events:

        def fn(t: float, x: NDArray[np.float64], *_args: Any, _f: Any = ev.function) -> float:
            return float(_f(t, x))

        fn.terminal = ev.terminal  # type: ignore[attr-defined]
        fn.direction = ev.direction  # type: ignore[attr-defined]
        wrapped.append(fn)
    return wrapped
