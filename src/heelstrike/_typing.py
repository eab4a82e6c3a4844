"""Array type aliases, defined once for the whole package."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["BoolArray", "FloatArray", "IntArray"]

#: An array of float64 values (units per use).
FloatArray = NDArray[np.float64]
#: An array of int64 values (indices, counts, status codes).
IntArray = NDArray[np.int64]
#: An array of booleans (flags, masks).
BoolArray = NDArray[np.bool_]
