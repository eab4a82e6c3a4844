"""Optional dependencies: import them on use, and name the extra that installs them.

``pip install heelstrike`` is the light install (everything ``reproduce``, ``impact``, ``gait``,
``walk``, ``powered``, ``basin`` and ``map`` need). The ``scale`` extra
(``pip install 'heelstrike[scale]'``) adds Dask process pools and clusters (``dask``,
``distributed``), resumable Zarr sweep stores (``zarr``) and netCDF-4 files (``netCDF4``).
Without ``netCDF4``, netCDF files are written in the classic 64-bit-offset format through
scipy (readable by every netCDF library and by :func:`xarray.open_dataset`).
"""

from __future__ import annotations

import importlib
import importlib.util
from pathlib import Path
from types import ModuleType
from typing import Any

__all__ = ["MissingExtraError", "require", "write_netcdf"]


class MissingExtraError(ImportError):
    """A package of an optional extra is missing; the message says how to install it."""


def missing_extra_message(what: str, extra: str = "scale") -> str:
    """``"<what> needs the '<extra>' extra: pip install 'heelstrike[<extra>]'"``."""
    return f"{what} needs the '{extra}' extra: pip install 'heelstrike[{extra}]'"


def require(module: str, what: str, extra: str = "scale") -> ModuleType:
    """Import ``module``, or raise :class:`MissingExtraError` naming ``extra``.

    Parameters
    ----------
    module : str
        Module to import, e.g. ``"zarr"`` or ``"dask.array"``.
    what : str
        The feature that needs it, as the start of the message (e.g. ``"a sweep store"``).
    extra : str
        The extra of heelstrike that installs it (default ``"scale"``).

    Returns
    -------
    module
        The imported module.
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise MissingExtraError(missing_extra_message(what, extra)) from exc


def available(module: str) -> bool:
    """Whether ``module`` can be imported (without importing it)."""
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


def write_netcdf(ds: Any, path: str | Path) -> Path:
    """Write an :class:`xarray.Dataset` to ``path`` as netCDF and return the path.

    netCDF-4 (HDF5) with the ``scale`` extra's ``netCDF4``; otherwise the classic 64-bit-offset
    format through scipy, which holds the same data for the datasets heelstrike writes
    (booleans are stored as ``int8`` by xarray in both). A dataset that the classic format
    cannot hold raises :class:`MissingExtraError`.
    """
    p = Path(path)
    if available("netCDF4"):
        ds.to_netcdf(p, engine="netcdf4")
        return p
    try:
        ds.to_netcdf(p, engine="scipy", format="NETCDF3_64BIT")
    except (ValueError, TypeError, OverflowError) as exc:
        p.unlink(missing_ok=True)
        raise MissingExtraError(
            missing_extra_message(f"netCDF-4 output ({exc})")
        ) from exc
    return p
