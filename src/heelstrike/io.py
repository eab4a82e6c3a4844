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


class InputFileError(ValueError):
    """A file given to read that is not a regular file of a readable size (named in the
    message)."""


def read_regular_file(path: str | Path, *, what: str, max_bytes: int) -> bytes:
    """The bytes of ``path``, refusing anything but a regular file of at most ``max_bytes``.

    The file's type is checked before it is opened and again on the open descriptor (opened
    non-blocking, so a FIFO swapped in meanwhile cannot hang the open), and at most
    ``max_bytes + 1`` bytes are read: a FIFO, a device such as ``/dev/zero``, a socket or a
    directory is refused by type, never read.

    Parameters
    ----------
    path : str or Path
        The file.
    what : str
        What the file is, for messages (``"URDF file"``, ``"state file"``).
    max_bytes : int
        Largest size accepted (bytes).

    Returns
    -------
    bytes
        The file's contents.

    Raises
    ------
    InputFileError
        Naming the file: it does not exist, is not a regular file (saying what it is), is
        larger than ``max_bytes``, or cannot be read.
    """
    import os

    shown = repr(str(path))
    try:
        _require_regular(os.stat(path), what, shown, max_bytes)
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except FileNotFoundError:
        raise InputFileError(f"{what} {shown} does not exist") from None
    except OSError as exc:
        raise InputFileError(f"cannot read {what} {shown}: {exc.strerror or exc}") from None
    try:
        _require_regular(os.fstat(fd), what, shown, max_bytes)
        chunks: list[bytes] = []
        size = 0
        while size <= max_bytes:
            chunk = os.read(fd, min(1 << 20, max_bytes + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as exc:
        raise InputFileError(f"cannot read {what} {shown}: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    if size > max_bytes:  # it grew while being read
        raise InputFileError(f"{what} {shown} is larger than the {_size(max_bytes)} allowed")
    return b"".join(chunks)


def _require_regular(st: Any, what: str, shown: str, max_bytes: int) -> None:
    """Refuse a ``stat`` result that is not a regular file of at most ``max_bytes``."""
    import stat

    mode = st.st_mode
    if not stat.S_ISREG(mode):
        kind = ("a directory" if stat.S_ISDIR(mode) else "a FIFO (named pipe)"
                if stat.S_ISFIFO(mode) else "a character device" if stat.S_ISCHR(mode)
                else "a block device" if stat.S_ISBLK(mode) else "a socket"
                if stat.S_ISSOCK(mode) else "not a regular file")
        raise InputFileError(f"{what} {shown} is {kind}, not a regular file: give a file")
    if st.st_size > max_bytes:
        raise InputFileError(f"{what} {shown} has {st.st_size} bytes, more than the "
                             f"{_size(max_bytes)} allowed")


def _size(n: int) -> str:
    """``n`` bytes in MiB or KiB for messages."""
    return f"{n / (1 << 20):g} MiB" if n >= 1 << 20 else f"{n / 1024:g} KiB"
