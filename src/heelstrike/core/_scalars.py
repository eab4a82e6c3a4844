"""Scalars from scalar inputs are Python scalars: 0-d results become ``float`` / ``bool``.

Batched results (any leading shape but ``()``) are left as arrays, so broadcasting code works
unchanged; code that needs the shape of a possibly scalar field uses :func:`numpy.shape`.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

import numpy as np

__all__ = ["python_scalars"]


def python_scalars(obj: Any, names: Iterable[str]) -> None:
    """Replace each 0-d field ``names`` of the frozen dataclass ``obj`` by a Python scalar.

    For use in ``__post_init__``: a 0-d boolean array becomes ``bool``, any other 0-d real
    array (or NumPy scalar) ``float``; fields with a batch shape are kept as they are.
    """
    for name in names:
        value = getattr(obj, name)
        if isinstance(value, bool | float) and type(value) in (bool, float):
            continue
        if np.ndim(value) != 0:
            continue
        arr = np.asarray(value)
        scalar: bool | float = bool(arr) if arr.dtype == np.bool_ else float(arr)
        object.__setattr__(obj, name, scalar)
