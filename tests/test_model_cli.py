"""CLI for described walkers: --model, --param, impact-map, malformed files."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from heelstrike.cli import main
from heelstrike.models.builder import shipped_walkers


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


@pytest.mark.slow
def test_gait_model_kneed_json_keys(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = _run(capsys, "gait", "--model", "kneed", "--slope", "0.0504rad",
                      "--guess=-0.265,1.218,-1.096", "--json")
    assert rc == 0
    d = json.loads(out)
    for key in ("period", "step_length", "speed", "impact_angle", "multipliers", "stable",
                "collision_loss", "eta", "fixed_point", "impacts"):
        assert key in d
    assert [i["kind"] for i in d["impacts"]] == ["knee_strike", "heel_strike"]
    assert d["collision_loss"] == pytest.approx(sum(i["T_c"] for i in d["impacts"]), rel=1e-12)
    assert d["collision_loss"] == pytest.approx(d["potential_energy_released"], rel=1e-8)
    assert d["eta"] == pytest.approx(d["collision_loss"] / d["step_length"], rel=1e-12)
    assert set(d["fixed_point"]) == {"stance_shank", "stance_shank_dot", "hip_dot"}


def test_impact_model_matches_compass(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = _run(capsys, "impact", "--angle", "20deg", "--radius", "0.2", "--json")
    ref = json.loads(out)
    rc2, out2, _ = _run(capsys, "impact", "--model", "compass", "--param", "R=0.2",
                        "--angle", "20deg", "--json")
    d = json.loads(out2)
    assert rc == rc2 == 0
    for key in ("T", "T_c", "T_a", "eta", "step_length"):
        assert d[key] == pytest.approx(ref[key], rel=1e-10)
    assert d["trailing_foot_lifts"] == ref["trailing_foot_lifts"]
    # general state and velocity for a kneed walker
    rc3, out3, _ = _run(capsys, "impact", "--model", "kneed", "--state=0,0.1,0.2,0,-0.4,0",
                        "--velocity=-0.1,0,1,0,0,0", "--json")
    d3 = json.loads(out3)
    assert rc3 == 0
    assert d3["T"] == pytest.approx(d3["T_c"] + d3["T_a"], rel=1e-12)
    assert d3["T_c"] > 0


@pytest.mark.parametrize(
    ("text", "field"),
    [
        ("m = 5.0", "link[0].mass"),
        ("mass = \"m\"", "link[0].mass"),
    ],
)
def test_malformed_model_one_line_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, field: str
) -> None:
    src = (Path(__file__).parents[1] / "src/heelstrike/walkers/compass.toml").read_text()
    if text.startswith("m ="):
        bad = src.replace("m = 5.0", "m = -5.0", 1)
    else:
        bad = src.replace('mass = "m"', "", 1)
    assert bad != src
    path = tmp_path / "bad.toml"
    path.write_text(bad)
    rc, out, err = _run(capsys, "gait", "--model", str(path), "--json")
    assert rc == 2 and out == ""
    assert len(err.strip().splitlines()) == 1
    assert field in err


def test_bad_param_and_missing_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, _, err = _run(capsys, "impact", "--model", "compass", "--param", "R", "--angle", "0.2")
    assert rc == 2 and "--param" in err
    rc, _, err = _run(capsys, "impact", "--model", "compass", "--param", "nope=1",
                      "--angle", "0.2")
    assert rc == 2 and "nope" in err and len(err.strip().splitlines()) == 1
    rc, _, err = _run(capsys, "impact", "--model", str(tmp_path / "none.toml"), "--angle", "0.2")
    assert rc == 2 and len(err.strip().splitlines()) == 1


def test_impact_map_writes_png_and_csv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = _run(capsys, "impact-map", "--model", "kneed", "--x", "R:0:0.3:3",
                      "--y", "angle:10deg:30deg:2", "--out", str(tmp_path))
    assert rc == 0
    paths = [Path(p) for p in out.split()]
    assert {p.suffix for p in paths} == {".png", ".csv"}
    rows = (tmp_path / "impact_map.csv").read_text().strip().splitlines()
    assert len(rows) == 1 + 6
    # T_c falls with the foot radius at a fixed angle (the paper's trend, for the kneed walker)
    vals = [r.split(",") for r in rows[1:4]]
    tc = [float(v[3]) for v in vals]
    assert tc[0] > tc[1] > tc[2] > 0


def test_shipped_walkers_listed() -> None:
    assert {"compass", "kneed", "torso"} <= set(shipped_walkers())
