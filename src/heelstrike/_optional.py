"""Optional dependencies: import them on use, and name the extra that installs them.

heelstrike is installed from a clone of its repository (it is not on a package index):
``pip install .`` is the light install (everything ``reproduce``, ``impact``, ``gait``,
``walk``, ``powered``, ``basin`` and ``map`` need). The ``scale`` extra
(``pip install '.[scale]'``, in the clone) adds Dask process pools and clusters (``dask``,
``distributed``), resumable Zarr sweep stores (``zarr``) and netCDF-4 files (``netCDF4``).
Without ``netCDF4``, netCDF files are written in the classic 64-bit-offset format through
scipy (readable by every netCDF library and by :func:`xarray.open_dataset`); the writing is
:func:`heelstrike.io.write_netcdf`'s. This module holds the import helpers only.
"""

from __future__ import annotations

import importlib
import importlib.util
from types import ModuleType

__all__ = ["MissingExtraError", "available", "require"]


class MissingExtraError(ImportError):
    """A package of an optional extra is missing; the message says how to install it."""


def install_hint(extra: str) -> str:
    """``"pip install '.[<extra>]' in a clone of heelstrike"``: the install that works.

    heelstrike is not on a package index, so an install by the package's name would find
    nothing (or someone else's package); the extra is installed from the repository's clone.
    """
    return f"pip install '.[{extra}]' in a clone of heelstrike"


def missing_extra_message(what: str, extra: str = "scale") -> str:
    """``"<what> needs the '<extra>' extra: pip install '.[<extra>]' in a clone of heelstrike"``."""
    return f"{what} needs the '{extra}' extra: {install_hint(extra)}"


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

