"""``study cost`` prints a summary: the cheapest gait per actuation, then the files written."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from heelstrike.analysis.cost_study import cheapest_gaits
from heelstrike.cli import main


def _study(cot: list[list[float]], stable: list[list[float]]) -> xr.Dataset:
    """A two-radius, two-step-length study of one actuation with the given CoT and flags."""
    dims = ("actuation", "radius", "step_length")
    c = np.asarray([cot], dtype=float)
    ds = xr.Dataset(
        {"cost_of_transport": (dims, c), "eta": (dims, 10.0 * c),
         "parameter": (dims, 100.0 * c), "spectral_radius": (dims, 2.0 - np.asarray([stable])),
         "stable": (dims, np.asarray([stable], dtype=float)),
         "parameter_unit": (("actuation",), np.asarray(["N s"]))},
        coords={"actuation": ["pushoff"], "radius": [0.1, 0.2], "step_length": [0.3, 0.4]},
    )
    ds.attrs["target"] = "step_length"
    return ds


def test_cheapest_gait_is_the_minimum_and_the_stable_one_follows_when_it_differs() -> None:
    rows = cheapest_gaits(_study([[0.5, 0.2], [np.nan, 0.3]], [[1, 0], [np.nan, 1]]))
    assert [r["which"] for r in rows] == ["cheapest", "cheapest stable"]
    first, stable = rows
    assert (first["radius"], first["target_value"]) == (0.1, 0.4)
    assert first["cost_of_transport"] == 0.2 and first["eta"] == 2.0
    assert first["parameter"] == 20.0 and first["parameter_unit"] == "N s"
    assert first["stable"] is False and (first["found"], first["points"]) == (3, 4)
    assert (stable["radius"], stable["target_value"]) == (0.2, 0.4)
    assert stable["cost_of_transport"] == 0.3 and stable["stable"] is True


def test_a_stable_cheapest_gait_is_one_row_and_no_gait_is_none() -> None:
    rows = cheapest_gaits(_study([[0.5, 0.2], [0.4, 0.3]], [[0, 1], [0, 0]]))
    assert len(rows) == 1 and rows[0]["stable"] is True and rows[0]["cost_of_transport"] == 0.2
    assert cheapest_gaits(_study([[np.nan] * 2] * 2, [[np.nan] * 2] * 2)) == []
    undecided = cheapest_gaits(_study([[0.5, 0.2], [0.4, 0.3]], [[0, np.nan], [0, 0]]))
    assert undecided[0]["stable"] is None


def test_study_cost_prints_the_cheapest_gait_and_the_files(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "study"
    assert main(["study", "cost", "--radius", "0:0.3:2", "--step-length", "0.4:0.5:2",
                 "--out", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    with xr.open_dataset(out / "cost_study.nc") as f:
        ds = f.load()
    cot = ds["cost_of_transport"].sel(actuation="pushoff").values
    i, j = np.unravel_index(np.nanargmin(cot), cot.shape)
    start = lines.index(next(ln for ln in lines if ln.startswith("cheapest gait per actuation")))
    header = lines[start + 1].split()
    assert header[:2] == ["actuation", "gait"] and "CoT" in header and "stable" in header
    row = lines[start + 2].split()
    assert row[:2] == ["pushoff", "cheapest"]
    assert float(row[2]) == pytest.approx(float(ds["radius"][i]), rel=1e-3)
    assert float(row[3]) == pytest.approx(float(ds["step_length"][j]), rel=1e-3)
    assert float(row[4]) == pytest.approx(float(ds["parameter"].values[0, i, j]), rel=1e-3)
    assert row[5] == "N" and row[6] == "s"
    assert float(row[7]) == pytest.approx(float(cot[i, j]), rel=1e-3)
    assert float(row[8]) == pytest.approx(float(ds["eta"].values[0, i, j]), rel=1e-3)
    flag = float(ds["stable"].values[0, i, j])
    assert row[10] == ("yes" if flag == 1 else "no")
    assert row[11] == f"{int(np.isfinite(cot).sum())}/4"
    after = lines[lines.index("files written:") + 1:]
    files = [Path(ln.strip()) for ln in after[:next(k for k, ln in enumerate(after)
                                                   if not ln.startswith("  "))]]
    assert files[0].name == "cost_study.nc" and "cost_of_transport.png" in {f.name for f in files}
    assert all(f.is_file() and f.parent == out for f in files)
    assert {f.name for f in out.iterdir()} == {f.name for f in files}
