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
files together, saving them through :func:`save_figure`.

Every file is written whole or not at all: :func:`atomic_path` gives the writer a temporary name
in the file's own folder and renames it to the final name (:func:`os.replace`) only once it is
complete, so a run killed mid-write leaves no partial file under the final name (at most a
hidden ``.<name>.<token>.part<suffix>`` file beside it). :func:`claim_directory` makes an
output folder one run's at a time.
"""

from __future__ import annotations

import contextlib
import errno
import os
import uuid
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from heelstrike._optional import MissingExtraError, available, missing_extra_message

__all__ = [
    "FLOAT_FORMAT",
    "DirectoryInUseError",
    "atomic_path",
    "claim_directory",
    "save_figure",
    "write_csv",
    "write_netcdf",
    "write_text",
]

#: Float format of every CSV heelstrike writes: 17 significant digits, enough to read back the
#: exact ``float64`` (energy differences of 1e-10 relative survive the round trip).
FLOAT_FORMAT = "%.17g"


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Write a file under a temporary name and give it its final name only when complete.

    Parameters
    ----------
    path : str or Path
        The final file; its parent directories are created.

    Yields
    ------
    Path
        A fresh temporary path in the same folder, ``.<name>.<token>.part<suffix>`` (the final
        suffix kept, so that writers choosing a format by it, such as matplotlib's
        ``savefig``, choose the same one). The caller writes the whole file there.

    Notes
    -----
    When the block ends normally the temporary file is renamed to ``path`` with
    :func:`os.replace` (atomic within one file system: a reader sees the old file or the new
    one, never part of one); when it raises, the temporary file is removed and ``path`` is
    left as it was. A process killed mid-write leaves at most the hidden temporary file.
    """
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    tmp = p.with_name(f".{p.name}.{uuid.uuid4().hex[:12]}.part{p.suffix}")
    try:
        yield tmp
        os.replace(tmp, p)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def save_figure(fig: Any, path: str | Path, **kwargs: Any) -> Path:
    """Save a matplotlib figure to ``path`` whole or not at all (:func:`atomic_path`).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or Path
        Output file; its format is its suffix (``.png``, ``.pdf``, ...).
    **kwargs
        Passed to :meth:`~matplotlib.figure.Figure.savefig` (``dpi``, ``metadata``).

    Returns
    -------
    Path
        ``path``.
    """
    p = Path(path)
    kwargs.setdefault("format", p.suffix[1:] or None)
    with atomic_path(p) as tmp:
        fig.savefig(tmp, **kwargs)
    return p


class DirectoryInUseError(OSError):
    """An output folder is claimed by another running process (:func:`claim_directory`)."""


#: Name of the lock file :func:`claim_directory` keeps in a claimed folder.
CLAIM_FILE = ".heelstrike.lock"


def _pid_alive(pid: int) -> bool:
    """Whether a process ``pid`` exists (on this machine)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    except OSError:
        return False
    return True


class DirectoryClaim:
    """One process's claim on an output folder (from :func:`claim_directory`).

    Attributes
    ----------
    path : Path
        The folder.
    lock_file : Path
        Its lock file, holding the claiming process's PID.
    """

    def __init__(self, path: Path, lock_file: Path, fd: int) -> None:
        self.path = path
        self.lock_file = lock_file
        self._fd: int | None = fd

    def release(self) -> None:
        """Give the folder up (remove the lock file); a second call does nothing."""
        if self._fd is None:
            return
        with contextlib.suppress(OSError):
            self.lock_file.unlink()
        with contextlib.suppress(OSError):
            os.close(self._fd)
        self._fd = None

    def __enter__(self) -> DirectoryClaim:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def _try_lock(fd: int) -> bool:
    """An exclusive, non-blocking advisory lock on ``fd`` (released by the kernel when the
    process dies); True without ``fcntl`` (then the PID in the file decides)."""
    try:
        import fcntl
    except ImportError:  # pragma: no cover - not POSIX
        return True
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError as exc:
        if exc.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
            return False
        raise
    return True


def _read_pid(fd: int) -> int | None:
    try:
        os.lseek(fd, 0, os.SEEK_SET)
        return int(os.read(fd, 64).decode("ascii", "replace").split()[0])
    except (OSError, ValueError, IndexError):
        return None


def claim_directory(path: str | Path) -> DirectoryClaim:
    """Claim the folder ``path`` (created if needed) for this process until released.

    The claim is the lock file :data:`CLAIM_FILE` in the folder, holding this process's PID
    under an exclusive advisory lock. A lock left by a process that has died (killed with
    ``kill -9``) is taken over: the kernel released its lock, and its PID names no process.

    Parameters
    ----------
    path : str or Path
        The output folder.

    Returns
    -------
    DirectoryClaim
        Release it (or use it as a context manager) when the run's files are written.

    Raises
    ------
    DirectoryInUseError
        Another running process holds the folder; the message names the folder and its PID.
    """
    folder = Path(path)
    folder.mkdir(parents=True, exist_ok=True)
    lock_file = folder / CLAIM_FILE
    for _ in range(10):  # a released lock file may be unlinked under us: open it again
        fd = os.open(lock_file, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            locked = _try_lock(fd)
            other = _read_pid(fd)
            if not locked or (other not in (None, os.getpid()) and _pid_alive(other)
                              and not _has_flock()):
                who = f"process {other}" if other else "another process"
                raise DirectoryInUseError(
                    errno.EBUSY,
                    f"output folder {str(folder)!r} is in use by another heelstrike run "
                    f"({who}, lock file {str(lock_file)!r}); wait for it to finish or choose "
                    "another folder")
            if not _same_file(fd, lock_file):
                os.close(fd)
                continue
            os.ftruncate(fd, 0)
            os.lseek(fd, 0, os.SEEK_SET)
            os.write(fd, f"{os.getpid()}\n".encode("ascii"))
        except BaseException:
            with contextlib.suppress(OSError):
                os.close(fd)
            raise
        return DirectoryClaim(folder, lock_file, fd)
    raise DirectoryInUseError(errno.EBUSY, f"cannot claim output folder {str(folder)!r}: its "
                              f"lock file {str(lock_file)!r} keeps being replaced")


def _has_flock() -> bool:
    try:
        import fcntl  # noqa: F401
    except ImportError:  # pragma: no cover - not POSIX
        return False
    return True


def _same_file(fd: int, path: Path) -> bool:
    """Whether ``path`` still names the open file ``fd`` (not unlinked by a releasing run)."""
    try:
        a, b = os.fstat(fd), os.stat(path)
    except OSError:
        return False
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def write_text(text: str, path: str | Path) -> Path:
    """Write ``text`` (UTF-8) to ``path`` whole or not at all (:func:`atomic_path`); return
    the path."""
    p = Path(path)
    with atomic_path(p) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return p


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
    with atomic_path(p) as tmp:
        frame.to_csv(tmp, index=False, float_format=FLOAT_FORMAT)
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
    if available("netCDF4"):
        with atomic_path(p) as tmp:
            dataset.to_netcdf(tmp, engine="netcdf4")
        return p
    try:
        with atomic_path(p) as tmp:
            dataset.to_netcdf(tmp, engine="scipy", format="NETCDF3_64BIT")
    except (ValueError, TypeError, OverflowError) as exc:
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
