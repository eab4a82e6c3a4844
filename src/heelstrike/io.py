"""Writing data files: the one place heelstrike writes CSV and netCDF.

Every table and dataset heelstrike saves goes through :func:`write_csv` or
:func:`write_netcdf`, so all its files share one layout: CSV with a header row, no index column,
floats as ``%.17g`` (:data:`FLOAT_FORMAT`, which round-trips every ``float64`` exactly), booleans
as ``True``/``False`` (except where a table is all numbers and writes its flags as ``1``/``0``,
so that ``numpy.loadtxt`` reads it whole: ``impact_map.csv``); netCDF-4 when the ``scale``
extra's ``netCDF4`` is installed, otherwise the classic 64-bit-offset format. Units are part
of the column names (``T_c_J``, ``t_s``) or of the dataset's ``units`` attributes; these
functions write the values as given (SI units).

Figures are drawn by :mod:`heelstrike.plots`; :mod:`heelstrike.outputs` puts figures and data
files together.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from heelstrike._optional import MissingExtraError, available, missing_extra_message

__all__ = ["FLOAT_FORMAT", "write_csv", "write_netcdf"]

#: Float format of every CSV heelstrike writes: 17 significant digits, enough to read back the
#: exact ``float64`` (energy differences of 1e-10 relative survive the round trip).
FLOAT_FORMAT = "%.17g"


def write_csv(table: Any, path: str | Path) -> Path:
    """Write a table to ``path`` as CSV and return the path.

    Parameters
    ----------
    table : pandas.DataFrame or mapping of str to array_like
        The table: a DataFrame, or columns by name (each 1-D, all of the same length ``n``).
        Column names carry the units (``t_s``, ``T_c_J``); values are written as given.
    path : str or Path
        Output file; its parent directories are created.

    Returns
    -------
    Path
        The written file: a header row, then one row per table row, no index column; floats
        formatted with :data:`FLOAT_FORMAT`, integers as integers, booleans as ``True`` /
        ``False``.

    Raises
    ------
    TypeError
        If ``table`` is neither a DataFrame nor a mapping.
    """
    import pandas as pd

    if isinstance(table, pd.DataFrame):
        frame = table
    elif isinstance(table, Mapping):
        frame = pd.DataFrame({str(k): v for k, v in table.items()})
    else:
        raise TypeError(f"write_csv needs a DataFrame or a mapping of columns, got "
                        f"{type(table).__name__}")
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    frame.to_csv(p, index=False, float_format=FLOAT_FORMAT)
    return p


def write_netcdf(dataset: Any, path: str | Path) -> Path:
    """Write an :class:`xarray.Dataset` to ``path`` as netCDF and return the path.

    Parameters
    ----------
    dataset : xarray.Dataset
        The data, with its units in the variables' ``units`` attributes.
    path : str or Path
        Output file; its parent directories are created.

    Returns
    -------
    Path
        The written file: netCDF-4 (HDF5) with the ``scale`` extra's ``netCDF4``; otherwise the
        classic 64-bit-offset format through scipy, which holds the same data for the datasets
        heelstrike writes (booleans are stored as ``int8`` by xarray in both).

    Raises
    ------
    heelstrike._optional.MissingExtraError
        If ``netCDF4`` is missing and the classic format cannot hold the dataset (no partial
        file is left behind).
    """
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    if available("netCDF4"):
        dataset.to_netcdf(p, engine="netcdf4")
        return p
    try:
        dataset.to_netcdf(p, engine="scipy", format="NETCDF3_64BIT")
    except (ValueError, TypeError, OverflowError) as exc:
        p.unlink(missing_ok=True)
        raise MissingExtraError(missing_extra_message(f"netCDF-4 output ({exc})")) from exc
    return p
