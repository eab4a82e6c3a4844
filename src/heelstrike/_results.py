"""JSON-ready dictionaries of result dataclasses: :class:`ResultDictMixin`.

Every public result of heelstrike (impacts, walks, limit cycles, powered gaits, ensembles,
basins, gait maps, robot impacts, ...) is a frozen dataclass deriving from
:class:`ResultDictMixin`, so that ``json.dumps(result.to_dict())`` works for all of them; the
compiled paths' few small results are :class:`typing.NamedTuple` (unpackable, cheap to build
per call) whose ``to_dict()`` is :func:`tuple_dict`.
Results that define their own summary (e.g. :meth:`~heelstrike.analysis.Gait.to_dict`,
whose keys the CLI's ``--json`` output promises) keep it.
"""

from __future__ import annotations

import dataclasses
import enum
import os
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["ResultDictMixin", "to_plain", "tuple_dict"]

#: numpy dtype kinds whose ``tolist()`` is already plain Python (bool, int, float, str).
_PLAIN_KINDS = frozenset("biufU")


def _complex(z: complex) -> dict[str, float]:
    return {"real": float(z.real), "imag": float(z.imag)}


def to_plain(value: Any) -> Any:
    """A value turned into plain Python that :func:`json.dumps` accepts.

    Parameters
    ----------
    value : object
        A result's field value.

    Returns
    -------
    object
        - None, bool, int, float and str are kept (``float('nan')`` and infinities too:
          :func:`json.dumps` writes them as ``NaN`` / ``Infinity``, which strict JSON parsers
          reject; pass ``allow_nan=False`` to find them);
        - enums (e.g. :class:`~heelstrike.dynamics.WalkStatus`) become their ``.value``;
        - numpy scalars become bool/int/float/str, numpy arrays nested lists of them;
        - complex numbers become ``{"real": x, "imag": y}``;
        - results (:class:`ResultDictMixin`) become their :meth:`~ResultDictMixin.to_dict`,
          other dataclasses (e.g. a :class:`~heelstrike.models.CompassGait`: its parameters) a
          dict of their public fields, mappings dicts with string keys, tuples, lists and sets
          lists, paths strings;
        - xarray datasets become ``Dataset.to_dict()`` (``dims``, ``coords``, ``data_vars``,
          ``attrs``), pandas frames ``{column: [values]}``.

    Raises
    ------
    TypeError
        For any other object (a described walker, a callable, ...).
    """
    if value is None or isinstance(value, bool):
        return value
    if isinstance(value, enum.Enum):
        return to_plain(value.value)
    if isinstance(value, float):  # numpy.float64 too
        return float(value)
    if isinstance(value, int):
        return int(value)
    if isinstance(value, str):  # numpy.str_ too
        return str(value)
    if isinstance(value, complex | np.complexfloating):
        return _complex(complex(value))
    if isinstance(value, np.generic):
        return to_plain(value.item())
    if isinstance(value, np.ndarray):
        if value.dtype.kind in _PLAIN_KINDS:
            return value.tolist()
        if value.dtype.kind in "mM":
            return value.astype(str).tolist()
        return [to_plain(v) for v in value.tolist()] if value.ndim else to_plain(value.item())
    if isinstance(value, ResultDictMixin):
        return value.to_dict()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return _fields_dict(value)
    module = type(value).__module__.split(".")[0]
    if module == "xarray" and hasattr(value, "to_dict"):  # before Mapping: a Dataset is one
        return to_plain(value.to_dict(data="list"))
    if module == "pandas" and hasattr(value, "to_dict"):
        return to_plain(value.to_dict(orient="list"))
    if isinstance(value, Mapping):
        return {str(k): to_plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple | set | frozenset):
        return [to_plain(v) for v in value]
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    raise TypeError(f"cannot turn a {type(value).__name__} into JSON-ready data")


def _fields_dict(obj: Any) -> dict[str, Any]:
    """``{field name: plain value}`` of a dataclass instance (private fields left out)."""
    return {
        f.name: to_plain(getattr(obj, f.name))
        for f in dataclasses.fields(obj)
        if not f.name.startswith("_")
    }


class ResultDictMixin:
    """Gives a frozen result dataclass :meth:`to_dict`: its fields as JSON-ready plain Python.

    Examples
    --------
    >>> import json
    >>> from heelstrike.core import impact
    >>> r = impact([[2.0, 0.0], [0.0, 1.0]], [[1.0, 0.0]], [1.0, 1.0])
    >>> json.loads(json.dumps(r.to_dict()))["velocity_post"]
    [0.0, 1.0]
    """

    __slots__ = ()

    def to_dict(self) -> dict[str, Any]:
        """Every public field of the result, as plain Python (see :func:`to_plain`).

        Returns
        -------
        dict
            ``{field name: value}``; arrays are nested lists (SI units, angles in rad), enums
            their value, nested results their own ``to_dict()``, None kept and NaN kept as
            ``float('nan')``.
        """
        return _fields_dict(self)


def tuple_dict(result: Any) -> dict[str, Any]:
    """The ``to_dict()`` of a result that is a :class:`typing.NamedTuple` (the compiled paths'
    results: :class:`~heelstrike.core.fast.FastImpactResult`,
    :class:`~heelstrike.dynamics.compiled.CompiledStep`, ...).

    Parameters
    ----------
    result : NamedTuple

    Returns
    -------
    dict
        ``{field name: value}`` as plain Python (:func:`to_plain`).
    """
    return {str(k): to_plain(v) for k, v in result._asdict().items()}
