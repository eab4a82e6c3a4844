"""CLI contracts of ``heelstrike impact`` and ``heelstrike reproduce`` (issue 2)."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from heelstrike.analysis.heel_strike import heel_strike_study
from heelstrike.cli import main
from heelstrike.models import heel_strike_state
from heelstrike.models.compass import CompassGait

IMPACT_KEYS = {"T", "T_c", "T_a", "eta", "step_length", "qdot_plus", "impulse",
               "trailing_foot_lifts"}


def _impact_json(argv: list[str], capsys: pytest.CaptureFixture[str]) -> dict:
    assert main(argv) == 0
    captured = capsys.readouterr()
    lines = captured.out.strip().splitlines()
    assert len(lines) == 1, captured.out
    d = json.loads(lines[0])
    assert isinstance(d, dict)
    return d


@pytest.mark.parametrize(
    ("argv", "R", "q3", "kwargs", "walker_kw"),
    [
        (["--radius", "0.25", "--angle", "20deg"], 0.25, np.deg2rad(20), {}, {}),
        (["--radius", "0", "--angle", "0.5rad"], 0.0, 0.5, {}, {}),
        (["--radius", "0.6", "--angle", "0.3", "--q3dot", "1.7", "--q4dot", "-0.4",
          "--restitution", "0.3", "--leg-inertia", "0.2", "--hip-mass", "4"],
         0.6, 0.3, {"q3_dot": 1.7, "q4_dot": -0.4, "restitution": 0.3},
         {"leg_inertia": 0.2, "hip_mass": 4.0}),
    ],
)
def test_impact_json_matches_library(argv, R, q3, kwargs, walker_kw, capsys):
    d = _impact_json(["impact", *argv, "--json"], capsys)
    assert IMPACT_KEYS <= d.keys()
    s = heel_strike_study(CompassGait(foot_radius=R, **walker_kw), q3, **kwargs)
    assert d["T"] == pytest.approx(float(s.kinetic_energy), rel=1e-12)
    assert d["T_c"] == pytest.approx(float(s.kinetic_energy_constrained), rel=1e-12)
    assert d["T_a"] == pytest.approx(float(s.kinetic_energy_admissible), rel=1e-12)
    assert d["eta"] == pytest.approx(float(s.eta), rel=1e-12)
    assert d["step_length"] == pytest.approx(float(s.step_length), rel=1e-12)
    assert d["qdot_plus"] == pytest.approx(list(s.velocity_post), rel=1e-12, abs=1e-15)
    assert d["impulse"] == pytest.approx(list(s.constraint_impulse), rel=1e-12, abs=1e-15)
    assert d["trailing_foot_lifts"] is bool(s.trailing_foot_lifts)
    assert len(d["qdot_plus"]) == 4 and len(d["impulse"]) == 2
    # physics through the CLI: energy balance
    assert d["T_c"] + d["T_a"] == pytest.approx(d["T"], rel=1e-12)


def test_impact_json_lift_flag_follows_the_physics(capsys):
    lifts = _impact_json(["impact", "--radius", "0", "--angle", "10deg", "--json"], capsys)
    stays = _impact_json(["impact", "--radius", "0", "--angle", "40deg", "--json"], capsys)
    wheel = _impact_json(["impact", "--radius", "1", "--angle", "20deg", "--json"], capsys)
    assert lifts["trailing_foot_lifts"] is True and lifts["qdot_plus"][1] > 0
    assert stays["trailing_foot_lifts"] is False and stays["qdot_plus"][1] < 0
    assert wheel["trailing_foot_lifts"] is False and wheel["T_c"] == pytest.approx(0, abs=1e-12)


@pytest.mark.parametrize("argv", [
    ["impact", "--radius", "0.25", "--angle", "20deg", "--q3dot", "-1"],
    ["impact", "--radius", "0.25", "--angle", "20deg", "--q3dot", "0.5", "--q4dot", "-3",
     "--json"],
    ["impact", "--model", "compass", "--angle", "20deg", "--q3dot", "-1", "--json"],
])
def test_impact_refuses_a_striking_foot_that_leaves_the_ground(argv, capsys):
    # Walking backwards (or closing the legs fast) lifts the leading foot: there is no heel
    # strike, and the bilateral impact law would report a loss with a pulling (negative)
    # normal impulse. The physics: the foot's pre-impact normal velocity is positive.
    walker = CompassGait(foot_radius=0.25)
    q3dot = float(argv[argv.index("--q3dot") + 1])
    q4dot = float(argv[argv.index("--q4dot") + 1]) if "--q4dot" in argv else 0.0
    q, qd = heel_strike_state(walker, np.deg2rad(20.0), q3_dot=q3dot, q4_dot=q4dot)
    assert (walker.contact_jacobian(q, "left") @ qd)[1] > 0
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("heelstrike: error: the striking foot moves away")
    assert len(captured.err.strip().splitlines()) == 1


@pytest.mark.parametrize(("argv", "needle"), [
    (["impact", "--angle", "-20deg"], "--angle must satisfy 0 < q3 < 90deg"),
    (["gait", "--slope", "-3deg"], "downhill slope > 0"),
    (["map", "--radius", "-0.1:0.3:3"], "--radius needs 0 <= START"),
])
def test_negative_value_with_a_unit_is_judged_as_a_value(argv, needle, capsys):
    # "-20deg" is the value of --angle, not an option: the error must say what is wrong with
    # it, not "expected one argument" (which is what argparse says on its own).
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("heelstrike: error:")
    assert needle in lines[0] and "expected one argument" not in lines[0]


@pytest.mark.parametrize(("argv", "needle"), [
    (["gait", "--radius=-0.1"], "foot_radius must satisfy 0 <= R <= leg_length (m); got "),
    (["gait", "--model", "kneed", "--param", "R=abc"], "'abc' is not a number"),
    (["gait", "--model", "kneed", "--param", "R"], "use NAME=VALUE"),
])
def test_bad_values_are_echoed(argv, needle, capsys):
    # the message names the offending value (a QA finding: it did not)
    assert main(argv) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0]
    if "--radius=-0.1" in argv:
        assert "foot_radius = -0.1" in lines[0]
        assert lines[0].endswith("(--radius sets foot_radius, --leg-length sets leg_length)")


def test_compass_rule_names_the_options_that_set_it(capsys):
    # QA sweep 5 (P3): the error named the model's fields only; --leg-length 0.4 leaves the
    # default b = 0.5 m outside the leg
    assert main(["gait", "--leg-length", "0.4"]) == 2
    line = capsys.readouterr().err.strip()
    assert line.startswith("heelstrike: error: leg_com_from_hip must satisfy 0 < b < leg_length")
    assert "leg_com_from_hip = 0.5" in line and "leg_length = 0.4" in line
    assert line.endswith("(--leg-length sets leg_length, --com-from-hip sets leg_com_from_hip)")


def test_every_failed_compass_rule_is_named_with_its_values_only(capsys):
    # QA sweep 9: --leg-length 0.2 --radius 0.25 named only the centre-of-mass rule, and every
    # message listed all seven parameter values
    assert main(["impact", "--radius", "0.25", "--angle", "20deg", "--leg-length", "0.2"]) == 2
    line = capsys.readouterr().err.strip()
    assert line.startswith("heelstrike: error: leg_com_from_hip must satisfy 0 < b < leg_length "
                           "(m); foot_radius must satisfy 0 <= R <= leg_length (m); got "
                           "leg_length = 0.2, leg_com_from_hip = 0.5, foot_radius = 0.25 (")
    assert "hip_mass" not in line and "gravity" not in line
    assert main(["impact", "--radius", "-0.1", "--angle", "20deg"]) == 2
    line = capsys.readouterr().err.strip()
    assert "got leg_length = 1, foot_radius = -0.1 (" in line and "hip_mass" not in line
    # QA sweep 10: R just above l was refused as "foot_radius = 1", hiding why
    assert main(["impact", "--radius", "1.0000001", "--angle", "20deg"]) == 2
    assert "got leg_length = 1, foot_radius = 1.0000001 (" in capsys.readouterr().err


@pytest.mark.parametrize("argv", [
    ["impact", "--model", "torso", "--angle", "20deg", "--json"],
    ["impact", "--radius", "0", "--angle", "20deg", "--json"],
])
def test_json_has_no_negative_zero(argv, capsys):
    # QA sweep 9: R = 0 printed "qdot_minus": [-0.0, ...] (-R q3_dot with R = 0)
    assert main(argv) == 0
    raw = json.loads(capsys.readouterr().out, parse_float=str)  # numbers as printed

    def numbers(x):
        if isinstance(x, dict):
            return [n for v in x.values() for n in numbers(v)]
        if isinstance(x, list):
            return [n for v in x for n in numbers(v)]
        return [x] if isinstance(x, str) else []

    printed = numbers(raw)
    assert "0.0" in printed and "-0.0" not in printed


def test_impact_table_is_readable(capsys):
    assert main(["impact", "--radius", "0.25", "--angle", "20deg"]) == 0
    out = capsys.readouterr().out
    s = heel_strike_study(CompassGait(foot_radius=0.25), np.deg2rad(20.0))
    assert f"{float(s.kinetic_energy_constrained):.6f}" in out
    assert f"{float(s.eta):.6f}" in out
    for word in ("T_c", "T_a", "eta", "J/m", "lifts"):
        assert word in out


BAD = [
    ["impact", "--radius", "2", "--angle", "20deg"],
    ["impact", "--radius", "-1", "--angle", "20deg"],
    ["impact", "--radius", "0.2", "--angle", "abc"],
    ["impact", "--radius", "0.2"],
    ["impact", "--angle", "0deg"],
    ["impact", "--angle", "-10deg"],
    ["impact", "--angle", "20deg", "--restitution", "1.5"],
    ["impact", "--angle", "20deg", "--q3dot", "nan"],
    ["impact", "--angle", "20deg", "--com-from-hip", "1"],
    ["impact", "--angle", "20deg", "--json", "--radius", "x"],
    ["impact", "--model", "kneed", "--angle", "20deg", "--backend", "compiled"],
    ["impact", "--angle", "20deg", "--backend", "numba"],
    ["reproduce", "--bogus"],
]


@pytest.mark.parametrize("argv", BAD)
def test_bad_input_gives_one_line_error(argv, capsys):
    assert main(argv) != 0
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1
    assert lines[0].startswith("heelstrike: error:")
    assert "Traceback" not in captured.err


def _entry_point() -> list[str]:
    exe = shutil.which("heelstrike", path=str(Path(sys.executable).parent))
    return [exe] if exe else [sys.executable, "-m", "heelstrike.cli"]


def test_installed_entry_point_json_and_errors():
    ok = subprocess.run([*_entry_point(), "impact", "--radius", "0.25", "--angle", "20deg",
                         "--json"], capture_output=True, text=True, timeout=120)
    assert ok.returncode == 0, ok.stderr
    d = json.loads(ok.stdout)
    assert IMPACT_KEYS <= d.keys()
    s = heel_strike_study(CompassGait(foot_radius=0.25), np.deg2rad(20.0))
    assert d["T_c"] == pytest.approx(float(s.kinetic_energy_constrained), rel=1e-12)
    for argv in (["--radius", "2", "--angle", "20deg"], ["--angle", "abc"]):
        bad = subprocess.run([*_entry_point(), "impact", *argv], capture_output=True, text=True,
                             timeout=120)
        assert bad.returncode != 0
        assert bad.stdout == ""
        lines = bad.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("heelstrike: error:")
        assert "Traceback" not in bad.stderr


def test_reproduce_writes_figures_and_data(tmp_path, capsys):
    out = tmp_path / "figs"
    assert main(["reproduce", "--out", str(out)]) == 0
    printed = [Path(p) for p in capsys.readouterr().out.strip().splitlines()]
    expected = {out / f"{fig}.{ext}" for fig in ("fig2", "fig3a", "fig3b")
                for ext in ("png", "pdf", "csv")}
    assert set(printed) == expected and len(printed) == 9
    for p in expected:
        assert p.stat().st_size > 0
    assert (out / "fig3b.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "fig2.pdf").read_bytes()[:5] == b"%PDF-"
    # the CSVs hold the physics: spot-check against the library
    fig2 = pd.read_csv(out / "fig2.csv")
    row = fig2[(fig2["R_m"] == 0.25)].iloc[10]
    s = heel_strike_study(CompassGait(foot_radius=0.25), row["q3_rad"])
    assert row["T_c_J"] == pytest.approx(float(s.kinetic_energy_constrained), rel=1e-10)
    assert row["T_a_J"] == pytest.approx(float(s.kinetic_energy_admissible), rel=1e-10)
    fig3a = pd.read_csv(out / "fig3a.csv")
    assert (fig3a.loc[fig3a["R_m"] == 1.0, "eta_J_per_m"].abs() < 1e-12).all()
    fig3b = pd.read_csv(out / "fig3b.csv")
    big_R = fig3b[fig3b["R_m"] > 0.4]
    assert big_R["shown"].all() and big_R["eta_J_per_m"].notna().all()
    assert fig3b.loc[~fig3b["shown"], "eta_J_per_m"].isna().all()
    # QA sweep 9: McGeer's wheel is drawn (shown) but its impacts are not admissible
    # (q2_dot+ = 0): 'admissible' means the trailing foot lifts, in every figure's CSV
    for table in (fig2, fig3a, fig3b):
        wheel = table["degenerate_wheel"]
        assert wheel.any() and "admissible" not in table
        assert not table.loc[wheel, "trailing_foot_lifts"].any()
        np.testing.assert_array_equal(table.loc[~wheel, "trailing_foot_lifts"],
                                      table.loc[~wheel, "q2_dot_plus_m_per_s"] > 0)
    assert fig3b.loc[fig3b["degenerate_wheel"], "shown"].all()


def test_reproduce_into_unwritable_place_fails_cleanly(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["reproduce", "--out", str(blocker / "sub")]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("heelstrike: error:")


@pytest.mark.parametrize("command", [["reproduce"], ["basin", "--grid", "3x3"]])
def test_out_that_is_an_existing_file_is_named_as_such(command, tmp_path, capsys):
    # mkdir on an existing file answers "File exists", which reads as if the directory were
    # there: the message must say the path is not a directory.
    blocker = tmp_path / "figures"
    blocker.write_text("x")
    assert main([*command, "--out", str(blocker)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("heelstrike: error: cannot write")
    assert "not a directory" in lines[0]
    assert blocker.read_text() == "x"


def test_impact_backend_compiled_gives_the_reference_numbers(capsys):
    """``impact --backend compiled`` (the numba compass kernel) reports the reference's JSON
    (the same keys, values to round-off) for a non-paper walker with restitution."""
    argv = ["impact", "--radius", "0.3", "--angle", "25deg", "--q3dot", "1.3", "--q4dot", "-0.5",
            "--restitution", "0.2", "--leg-inertia", "0.05", "--json"]
    ref = _impact_json(argv, capsys)
    fast = _impact_json([*argv, "--backend", "compiled"], capsys)
    assert fast.keys() == ref.keys()
    for key, value in ref.items():
        if isinstance(value, (bool, dict)) or value is None:
            assert fast[key] == value, key
        else:
            np.testing.assert_allclose(fast[key], value, rtol=1e-12, atol=1e-12, err_msg=key)


def test_wheel_impact_text_has_no_negative_zero(capsys):
    # QA sweep 4: at R = l the round-off (1e-17) printed as "-0.000000" next to "exactly 0"
    assert main(["impact", "--radius", "1", "--angle", "20deg"]) == 0
    out = capsys.readouterr().out
    assert "-0.000000" not in out and "0.000000, 0.000000 N s" in out


@pytest.mark.parametrize("argv", [
    ["map", "--radius", "0.2:0.2:3", "--slope", "2deg:3deg:2"],
    ["study", "cost", "--radius", "0.3:0.3:3", "--step-length", "0.3:0.5:2"],
    ["impact-map", "--x", "R:0.2:0.2:2", "--y", "angle:10deg:20deg:2"],
    ["basin", "--q3-range=-0.2:-0.2", "--grid", "3x3"],
])
def test_a_range_that_repeats_one_value_is_refused(argv, capsys, tmp_path):
    # QA sweep 7 (P2): map --radius 0.2:0.2:3 reached sweep() and failed as an "unexpected
    # SweepError" naming foot_radius; study cost and impact-map computed the repeats
    assert main([*argv, "--out", str(tmp_path / "o")]) == 2
    captured = capsys.readouterr()
    line = captured.err.strip()
    assert captured.out == "" and len(line.splitlines()) == 1
    assert "START = STOP is one value" in line and "unexpected" not in line
