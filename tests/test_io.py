"""heelstrike.io, the one writer of CSV and netCDF files."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from heelstrike._optional import MissingExtraError
from heelstrike.io import write_csv, write_netcdf


def test_write_csv_round_trips_floats_exactly_and_creates_parents(tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    x = rng.normal(size=50) * 10.0 ** rng.integers(-12, 12, size=50)
    path = write_csv({"x_m": x, "n": np.arange(50), "ok": x > 0}, tmp_path / "a" / "b.csv")
    assert path == tmp_path / "a" / "b.csv" and path.is_file()
    back = pd.read_csv(path)
    assert list(back.columns) == ["x_m", "n", "ok"]
    np.testing.assert_array_equal(back["x_m"].to_numpy(), x)  # bit for bit
    assert back["n"].dtype.kind == "i" and back["ok"].dtype == bool
    np.testing.assert_array_equal(back["ok"].to_numpy(), x > 0)


def test_write_csv_writes_a_dataframe_without_its_index(tmp_path: Path) -> None:
    frame = pd.DataFrame({"t_s": [0.1, 0.2]}, index=[5, 9])
    text = write_csv(frame, tmp_path / "t.csv").read_text().splitlines()
    assert text == ["t_s", "0.10000000000000001", "0.20000000000000001"]
    assert float(text[1]) == 0.1


def test_write_csv_rejects_other_tables(tmp_path: Path) -> None:
    with pytest.raises(TypeError, match="DataFrame or a mapping"):
        write_csv([[1.0, 2.0]], tmp_path / "x.csv")
    assert not (tmp_path / "x.csv").exists()


def test_write_netcdf_classic_fallback_and_its_limit(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    xr = pytest.importorskip("xarray")
    monkeypatch.setitem(sys.modules, "netCDF4", None)  # as without the scale extra
    ds = xr.Dataset({"T_c": ("R", np.array([0.5, 0.25]), {"units": "J"})},
                    coords={"R": [0.0, 0.3]})
    path = write_netcdf(ds, tmp_path / "sub" / "d.nc")
    assert path.read_bytes()[:4] == b"CDF\x02"
    with xr.open_dataset(path, engine="scipy") as back:
        np.testing.assert_array_equal(back["T_c"].values, ds["T_c"].values)
        assert back["T_c"].attrs["units"] == "J"
    # int64 beyond the classic format's int32: refused with the extra named, no file left
    big = xr.Dataset({"n": ("k", np.array([2**40], dtype=np.int64))})
    with pytest.raises(MissingExtraError, match="scale"):
        write_netcdf(big, tmp_path / "big.nc")
    assert not (tmp_path / "big.nc").exists()
