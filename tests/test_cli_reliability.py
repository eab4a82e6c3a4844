"""Never a confident wrong answer (issue 11, items 5, 6, 9, 10, 13) and the two bugs of issue 9.

- no option is silently ignored (compass options with ``--model`` map to the model's parameter
  or are refused);
- states that are not heel strikes, parameters outside the walker file's constraints and
  invalid sweeps are refused;
- non-finite results are refused and stdout holds one whole JSON object or nothing;
- outputs, frame rates, ffmpeg and memory are checked before computing, and every failure ends
  in one line with exit status 2;
- the impact-map figure masks the non-lifting region and its boundary agrees with the data;
- ``continue_limit_cycle`` works for described walkers and every walker has one ``scale``.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from heelstrike.analysis import basin as basin_module
from heelstrike.analysis import limit_cycle as limit_cycle_module
from heelstrike.analysis.model_gaits import ImpactMap, symmetric_heel_strike_state
from heelstrike.cli import main
from heelstrike.dynamics.phased import PhasedWalker, load_phased_walker, simulate_phased
from heelstrike.models import CompassGait, load_walker

Capsys = pytest.CaptureFixture[str]


def _run(capsys: Capsys, *argv: str) -> tuple[int, str, str]:
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def _one_line_error(rc: int, out: str, err: str) -> str:
    assert rc == 2
    assert out == ""
    lines = [ln for ln in err.splitlines() if ln.startswith("heelstrike: error:")]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


def _entry_point() -> list[str]:
    exe = shutil.which("heelstrike", path=str(Path(sys.executable).parent))
    return [exe] if exe else [sys.executable, "-m", "heelstrike.cli"]


def _forbid(monkeypatch: pytest.MonkeyPatch, module: Any, name: str) -> None:
    """Make ``module.name`` fail the test if it is called (the check must come first)."""

    def called(*args: Any, **kwargs: Any) -> Any:
        raise AssertionError(f"{name} was called before the arguments were checked")

    monkeypatch.setattr(module, name, called)


# -- 11.5: no option silently ignored ------------------------------------------------------------
def test_radius_with_model_sets_R(capsys: Capsys) -> None:
    rc, out, _ = _run(capsys, "impact", "--model", "compass", "--radius", "0.5",
                      "--angle", "20deg", "--json")
    assert rc == 0
    model = json.loads(out)
    rc, out, _ = _run(capsys, "impact", "--radius", "0.5", "--angle", "20deg", "--json")
    compass = json.loads(out)
    rc, out, _ = _run(capsys, "impact", "--radius", "0", "--angle", "20deg", "--json")
    point_foot = json.loads(out)
    assert model["T_c"] == pytest.approx(compass["T_c"], rel=1e-9)
    assert abs(model["T_c"] - point_foot["T_c"]) > 0.1 * point_foot["T_c"]


def test_every_compass_option_maps_with_model(capsys: Capsys) -> None:
    options = ["--radius", "0.3", "--hip-mass", "7", "--leg-mass", "3", "--leg-length", "1.2",
               "--com-from-hip", "0.4", "--leg-inertia", "0.05", "--gravity", "3.7"]
    rc, out, _ = _run(capsys, "impact", "--model", "compass", *options, "--angle", "15deg",
                      "--json")
    assert rc == 0
    rc2, out2, _ = _run(capsys, "impact", *options, "--angle", "15deg", "--json")
    assert rc2 == 0
    a, b = json.loads(out), json.loads(out2)
    for key in ("T", "T_c", "T_a", "step_length"):
        assert a[key] == pytest.approx(b[key], rel=1e-9)


def test_q4dot_with_model_is_the_hip_rate(capsys: Capsys) -> None:
    rc, out, _ = _run(capsys, "impact", "--model", "compass", "--angle", "20deg",
                      "--q4dot", "0.5", "--json")
    assert rc == 0
    model = json.loads(out)
    _, out, _ = _run(capsys, "impact", "--angle", "20deg", "--q4dot", "0.5", "--json")
    compass = json.loads(out)
    assert model["T"] == pytest.approx(compass["T"], rel=1e-9)
    assert model["T_c"] == pytest.approx(compass["T_c"], rel=1e-9)


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["impact", "--model", "kneed", "--leg-length", "2", "--angle", "20deg"],
         "--leg-length"),
        (["impact", "--model", "compass", "--radius", "0.3", "--param", "R=0.2",
          "--angle", "20deg"], "give it once"),
        (["impact", "--model", "compass", "--angle", "20deg", "--restitution", "0.5"],
         "--restitution"),
        (["impact", "--model", "compass", "--angle", "20deg", "--state=0,0,0.3,-0.6"],
         "not both"),
        (["impact", "--model", "compass", "--state=0,0,0.3,-0.6",
          "--velocity=0,0,1,0", "--q3dot", "2"], "--velocity"),
        (["impact", "--angle", "20deg", "--state=0,0,0.3,-0.6"], "--state needs --model"),
        (["impact", "--angle", "20deg", "--velocity=0,0,1,0"], "--velocity needs --model"),
        (["impact", "--angle", "20deg", "--param", "R=0.2"], "--param needs --model"),
        (["gait", "--model", "kneed", "--com-from-hip", "0.3"], "--com-from-hip"),
        (["impact", "--angle", "20deg", "--friction", "0.5"], "only for a robot"),
        (["impact", "--robot", "talos", "--state", "s.json", "--radius", "0.3"],
         "does not take --radius"),
    ],
)
def test_ignored_options_are_refused(capsys: Capsys, argv: list[str], needle: str) -> None:
    line = _one_line_error(*_run(capsys, *argv))
    assert needle in line


# -- 11.6: constraints, heel-strike states, sweeps -----------------------------------------------
@pytest.mark.parametrize(
    ("model", "param", "needle"),
    [("compass", "R=2", "R <= l"), ("compass", "b=1.5", "b < l"),
     ("torso", "R=1.5", "R <= l"), ("kneed", "R=0.6", "R <= a1 + b1")],
)
def test_parameters_outside_the_walker_constraints(
    capsys: Capsys, model: str, param: str, needle: str
) -> None:
    line = _one_line_error(*_run(capsys, "impact", "--model", model, "--param", param,
                                 "--angle", "20deg"))
    assert needle in line


def test_hovering_state_is_not_a_heel_strike(capsys: Capsys) -> None:
    line = _one_line_error(*_run(capsys, "impact", "--model", "compass",
                                 "--state=0,5,0.3,-0.6"))
    assert "not a heel strike" in line


def test_a_true_heel_strike_state_is_accepted(capsys: Capsys) -> None:
    w = load_phased_walker("kneed")
    q, _ = symmetric_heel_strike_state(w, 0.3)
    state = ",".join(repr(float(v)) for v in q)
    rc, out, err = _run(capsys, "impact", "--model", "kneed", f"--state={state}", "--json")
    assert rc == 0, err
    d = json.loads(out)
    rc, out, _ = _run(capsys, "impact", "--model", "kneed", "--angle", "0.3rad", "--json")
    assert d["T_c"] == pytest.approx(json.loads(out)["T_c"], rel=1e-9)


@pytest.mark.parametrize("model", ["compass", "kneed"])
def test_check_heel_strike_state(model: str) -> None:
    from heelstrike.analysis.heel_strike import NotAHeelStrikeError, check_heel_strike_state

    w = load_phased_walker(model)
    q, _ = symmetric_heel_strike_state(w, 0.25)
    check_heel_strike_state(w, q)
    for i in (1, 2):  # lift the walker, or open the legs: a foot leaves the ground
        bad = np.array(q, dtype=float)
        bad[i] += 1e-3
        with pytest.raises(NotAHeelStrikeError, match="not a heel strike"):
            check_heel_strike_state(w, bad)


def test_impact_map_refuses_invalid_sweeps(capsys: Capsys, tmp_path: Path) -> None:
    out = tmp_path / "m"
    line = _one_line_error(*_run(capsys, "impact-map", "--model", "compass",
                                 "--x", "m:-1:1:3", "--y", "R:0:0.5:3", "--out", str(out)))
    assert "m = -1" in line
    assert not (out / "impact_map.csv").exists()
    # valid one by one, invalid together (R <= a1 + b1): no NaN rows with exit 0
    line = _one_line_error(*_run(capsys, "impact-map", "--model", "kneed",
                                 "--x", "R:0:0.5:6", "--y", "b1:0.05:0.3:3", "--out", str(out)))
    assert "R <= a1 + b1" in line
    assert not (out / "impact_map.csv").exists()
    line = _one_line_error(*_run(capsys, "impact-map", "--model", "compass",
                                 "--x", "angle:0deg:100deg:3", "--y", "R:0:0.5:3",
                                 "--out", str(out)))
    assert "angle" in line


# -- 11.10: non-finite results, whole JSON ---------------------------------------------------------
@pytest.mark.parametrize("json_flag", [[], ["--json"]])
def test_overflow_is_an_error_with_empty_stdout(json_flag: list[str]) -> None:
    res = subprocess.run([*_entry_point(), "impact", "--angle", "20deg", "--q3dot", "1e200",
                          *json_flag], capture_output=True, text=True, timeout=120)
    assert res.returncode == 2
    assert res.stdout == ""
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("heelstrike: error:"), res.stderr
    assert "not finite" in lines[0]


def test_json_stdout_is_one_whole_object() -> None:
    res = subprocess.run([*_entry_point(), "impact", "--angle", "20deg", "--q3dot", "1e100",
                          "--json"], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.count("\n") == 1
    d = json.loads(res.stdout)
    assert all(np.isfinite(d[k]) for k in ("T", "T_c", "T_a", "eta"))


@pytest.mark.parametrize("argv", [["--q3dot", "inf"], ["--q4dot", "nan"]])
def test_non_finite_rates_are_refused(capsys: Capsys, argv: list[str]) -> None:
    _one_line_error(*_run(capsys, "impact", "--angle", "20deg", *argv))


# -- 11.13: check before computing; every failure is one line --------------------------------------
def test_basin_unwritable_out_fails_before_computing(
    capsys: Capsys, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    _forbid(monkeypatch, basin_module, "basin_of_attraction")
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    line = _one_line_error(*_run(capsys, "basin", "--grid", "3x3", "--out",
                                 str(blocker / "x")))
    assert "cannot write" in line


@pytest.mark.parametrize(
    ("command", "module", "function"),
    [(["bifurcation"], "heelstrike.analysis.gait_map", "compass_bifurcation"),
     (["map"], "heelstrike.analysis.gait_map", "gait_map"),
     (["study", "cost"], "heelstrike.analysis.cost_study", "cost_study")],
)
def test_unwritable_out_fails_before_computing(
    capsys: Capsys, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, command: list[str],
    module: str, function: str,
) -> None:
    import importlib

    _forbid(monkeypatch, importlib.import_module(module), function)
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    line = _one_line_error(*_run(capsys, *command, "--out", str(blocker / "x")))
    assert "cannot write" in line


def test_basin_memory_estimate_refuses_before_computing(
    capsys: Capsys, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    _forbid(monkeypatch, basin_module, "find_limit_cycle")
    from heelstrike.analysis import _memory

    monkeypatch.setattr(_memory, "available_memory", lambda: 2 * 1024**3)
    line = _one_line_error(*_run(capsys, "basin", "--grid", "30000x30000",
                                 "--out", str(tmp_path / "b")))
    assert "GiB" in line and "30000x30000" in line
    need = basin_module.basin_memory_estimate((30000, 30000))
    assert need >= 30000 * 30000 * 100  # at least the ~120 B per point of the state arrays
    with pytest.raises(MemoryError, match="GiB"):
        basin_module.basin_of_attraction(CompassGait(), 0.05, grid=(30000, 30000))


@pytest.mark.parametrize(("argv", "needle"), [
    # QA sweep 3: accepted, then silent (4e10 and 1e10 points)
    (["impact-map", "--model", "compass", "--x", "R:0:0.5:200000", "--y",
      "angle:10deg:20deg:200000"], "a 200000x200000 impact map needs about"),
    (["study", "cost", "--radius", "0:0.9:100000", "--step-length", "0.3:0.6:100000"],
     "a 1x100000x100000 cost study needs about"),
])
def test_huge_grids_are_refused_before_computing(argv: list[str], needle: str, capsys: Capsys,
                                                 tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    from heelstrike.analysis import cost_study as study_module
    from heelstrike.analysis import model_gaits

    # nothing is built or searched: the refusal comes first
    _forbid(monkeypatch, model_gaits, "impact_map")
    _forbid(monkeypatch, study_module, "cost_study")
    line = _one_line_error(*_run(capsys, *argv, "--out", str(tmp_path / "o")))
    assert "out of memory" in line and needle in line and "GiB" in line
    assert not (tmp_path / "o").exists()


def test_long_impact_map_says_what_it_costs(capsys: Capsys, tmp_path: Path,
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    from heelstrike.analysis import model_gaits

    monkeypatch.setattr(model_gaits, "IMPACT_MAP_SECONDS_PER_POINT", 100.0)  # 4 points: 400 s
    rc, out, err = _run(capsys, "impact-map", "--model", "compass", "--x", "R:0:0.3:2",
                        "--y", "angle:10deg:20deg:2", "--out", str(tmp_path / "m"))
    assert rc == 0
    assert "impact-map: 4 points, about 6.67 min (about 100000 ms a point)" in err
    assert "impact-map:" not in out
    capsys.readouterr()
    monkeypatch.setattr(model_gaits, "IMPACT_MAP_SECONDS_PER_POINT", 2e-3)
    rc, _, err = _run(capsys, "impact-map", "--model", "compass", "--x", "R:0:0.3:2",
                      "--y", "angle:10deg:20deg:2", "--out", str(tmp_path / "m"))
    assert rc == 0 and "impact-map:" not in err  # a short map says nothing


@pytest.mark.parametrize(
    ("argv", "needle"),
    [(["--fps", "0"], "--fps"), (["--fps", "nan"], "--fps"),
     (["--out", "{tmp}/file/w.gif"], "cannot write")],
)
def test_walk_checks_before_computing(
    capsys: Capsys, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, argv: list[str],
    needle: str,
) -> None:
    _forbid(monkeypatch, limit_cycle_module, "find_limit_cycle")
    (tmp_path / "file").write_text("")
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    if "--out" not in argv:
        argv += ["--out", str(tmp_path / "w.gif")]
    line = _one_line_error(*_run(capsys, "walk", *argv))
    assert needle in line


def test_walk_mp4_without_ffmpeg_fails_before_computing(
    capsys: Capsys, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    _forbid(monkeypatch, limit_cycle_module, "find_limit_cycle")
    monkeypatch.setenv("PATH", str(tmp_path))
    line = _one_line_error(*_run(capsys, "walk", "--out", str(tmp_path / "w.mp4")))
    assert "ffmpeg" in line


def test_model_that_is_not_a_file_is_refused_before_reading() -> None:
    # /dev/zero never ends: reading it would exhaust memory (the address space is capped so
    # that a regression fails instead of swapping)
    def cap() -> None:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (2 * 1024**3, 2 * 1024**3))

    res = subprocess.run([*_entry_point(), "impact", "--model", "/dev/zero", "--angle", "20deg"],
                         capture_output=True, text=True, timeout=120, preexec_fn=cap)
    assert res.returncode == 2
    assert res.stdout == ""
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "not a regular file" in lines[0], res.stderr


@pytest.mark.parametrize("error", [RuntimeError("boom\nsecond line"), MemoryError(),
                                   KeyError("x"), PermissionError(13, "Permission denied")])
def test_unexpected_errors_end_in_one_line(
    capsys: Capsys, monkeypatch: pytest.MonkeyPatch, error: BaseException
) -> None:
    import heelstrike.analysis.heel_strike as hs

    def fail(*args: Any, **kwargs: Any) -> Any:
        raise error

    monkeypatch.setattr(hs, "heel_strike_study", fail)
    monkeypatch.delenv("HEELSTRIKE_DEBUG", raising=False)
    line = _one_line_error(*_run(capsys, "impact", "--angle", "20deg"))
    if isinstance(error, MemoryError):
        assert "out of memory" in line
    monkeypatch.setenv("HEELSTRIKE_DEBUG", "1")
    rc, _, err = _run(capsys, "impact", "--angle", "20deg")
    assert rc == 2
    assert "Traceback" in err and err.strip().splitlines()[-1].startswith("heelstrike: error:")


# -- 11.9: impact-map figure -------------------------------------------------------------------
def _synthetic_map() -> ImpactMap:
    """Lifts for R < 0.45 m; the trailing-foot velocity crosses zero far inside the
    non-lifting region (at 0.8 m), as round-off or a tolerance can make it."""
    x = np.linspace(0.0, 1.0, 11)
    y = np.linspace(0.1, 0.6, 6)
    X, _ = np.meshgrid(x, y)
    lifts = X < 0.45
    T = 1.0 + X
    return ImpactMap(
        x_name="R", y_name="angle", x=x, y=y, T=T, T_c=0.3 * T, T_a=0.7 * T, eta=0.5 * T,
        step_length=np.ones_like(T), trailing_normal_velocity=0.8 - X, lifts=lifts,
        held=~lifts, angle=0.3, stance_rate=1.0, walker_name="synthetic",
    )


def test_impact_map_boundary_between_lifting_and_non_lifting_cells() -> None:
    from matplotlib.collections import QuadMesh

    from heelstrike.plots.models import LIFT_BOUNDARY_GID, impact_map_figure

    m = _synthetic_map()
    fig = impact_map_figure(m, {"R": "m"})
    panels = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"][:3]
    for ax in panels:
        bounds = [c for c in ax.collections if c.get_gid() == LIFT_BOUNDARY_GID]
        assert len(bounds) == 1
        xs = np.concatenate([np.asarray(p.vertices)[:, 0] for p in bounds[0].get_paths()])
        assert xs.size > 0
        assert np.all((xs >= 0.4 - 1e-12) & (xs <= 0.5 + 1e-12))  # between the cells
        coloured = [c for c in ax.collections if isinstance(c, QuadMesh)
                    and c.get_cmap().name == "viridis"]
        assert len(coloured) == 1
        mask = np.ma.getmaskarray(np.ma.asarray(coloured[0].get_array())).reshape(m.lifts.shape)
        np.testing.assert_array_equal(mask, ~m.lifts)  # the non-lifting region is masked


def test_impact_map_axes_have_units() -> None:
    from heelstrike.models.description import parameter_units
    from heelstrike.plots.models import impact_map_figure

    for name in ("compass", "kneed", "torso"):
        w = load_walker(name)
        units = parameter_units(w.description)
        assert set(w.parameters) <= set(units), name
    compass = parameter_units(load_walker("compass").description)
    assert (compass["R"], compass["m"], compass["I"], compass["g"]) == (
        "m", "kg", "kg m^2", "m/s^2")
    fig = impact_map_figure(_synthetic_map(), compass)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "R (m)" and ax.get_ylabel() == "impact angle (deg)"
    # the axes span the computed grid, R from 0 m (QA sweep 13: from -0.05 m, half a cell
    # past it), impact angles 0.1-0.6 rad in degrees
    assert ax.get_xlim() == pytest.approx((0.0, 1.0))
    assert ax.get_ylim() == pytest.approx(tuple(np.degrees([0.1, 0.6])))


# -- issue 9: continuation of described walkers, one scale ---------------------------------------
def test_continuation_of_a_described_walker() -> None:
    w = PhasedWalker.from_built(load_walker("compass", R=0.2))
    guess = (-0.3328, 1.2752, -0.8238)  # near the gait at 0.05 rad
    cont = limit_cycle_module.continue_limit_cycle(
        w, "R", [0.2, 0.21], slope=0.05, guess=guess, simulator=simulate_phased
    )
    assert cont.stopped is None
    np.testing.assert_array_equal(cont.values, [0.2, 0.21])
    z0, z1 = (c.fixed_point for c in cont.cycles)
    assert np.linalg.norm(z1 - z0) > 1e-4  # the parameter really changed


@pytest.mark.slow
def test_continuation_of_the_kneed_walker_in_its_foot_radius() -> None:
    w = PhasedWalker.from_built(load_walker("kneed"))
    cont = limit_cycle_module.continue_limit_cycle(
        w, "R", [0.1, 0.105], slope=0.0504, guess=(-0.265, 1.218, -1.096),
        simulator=simulate_phased,
    )
    assert cont.stopped is None
    np.testing.assert_array_equal(cont.values, [0.1, 0.105])
    z0, z1 = (c.fixed_point for c in cont.cycles)
    assert np.linalg.norm(z1 - z0) > 1e-4


def test_continuation_errors_are_clear() -> None:
    with pytest.raises(ValueError, match="Poincare section"):
        limit_cycle_module.continue_limit_cycle(load_walker("kneed"), "R", [0.1, 0.11])
    with pytest.raises(ValueError, match="not a parameter"):
        limit_cycle_module.continue_limit_cycle(CompassGait(), "R", [0.1], slope=0.05)


def test_every_walker_has_one_scale() -> None:
    from heelstrike.analysis.powered import _scale

    for walker in (load_walker("compass", g=3.7), PhasedWalker.from_built(
            load_walker("compass", g=3.7)), CompassGait(gravity=3.7)):
        s = walker.scale
        assert float(s.gravity) == pytest.approx(3.7, rel=1e-12)
        assert float(s.total_mass) == pytest.approx(float(walker.total_mass), rel=1e-12)
        assert float(s.leg_length) == pytest.approx(1.0, rel=1e-12)
        assert _scale(walker) == pytest.approx((20.0, 3.7, 1.0), rel=1e-12)
    kneed = load_walker("kneed", g=1.62, R=0.2)
    p = kneed.parameters
    s = kneed.scale
    assert float(s.gravity) == pytest.approx(1.62, rel=1e-12)
    assert float(s.leg_length) == pytest.approx(p["a1"] + p["b1"] + p["a2"] + p["b2"], rel=1e-12)
    assert float(s.total_mass) == pytest.approx(p["mH"] + 2 * p["mt"] + 2 * p["ms"], rel=1e-12)
    long_legs = CompassGait(leg_length=1.3, foot_radius=0.4)
    assert float(long_legs.scale.leg_length) == 1.3
    assert float(load_walker("compass", l=1.3, R=0.4).scale.leg_length) == pytest.approx(1.3)


if os.name != "posix":  # pragma: no cover - the /dev/zero and rlimit test is POSIX only
    test_model_that_is_not_a_file_is_refused_before_reading = pytest.mark.skip(
        reason="POSIX only")(test_model_that_is_not_a_file_is_refused_before_reading)


def test_impact_map_csv_names_the_swept_columns_with_their_units(tmp_path: Path) -> None:
    # Every CSV column carries its unit: the swept foot radius is in metres and the impact
    # angle in radians (0.1 ... 0.6 here, not degrees), like T_J or step_length_m.
    from heelstrike.outputs import write_impact_map

    m = _synthetic_map()
    csv = next(p for p in write_impact_map(m, tmp_path, units={"R": "m"}) if p.suffix == ".csv")
    header = csv.read_text().splitlines()[0].split(",")
    assert header[:2] == ["R_m", "angle_rad"]
    assert {"T_J", "T_c_J", "eta_J_per_m", "step_length_m"} <= set(header)
    rows = np.loadtxt(csv, delimiter=",", skiprows=1)
    np.testing.assert_allclose(np.unique(rows[:, 1]), m.y)


def test_impact_map_refuses_a_backward_stance_rate(capsys: Capsys, tmp_path: Path) -> None:
    # With --q3dot < 0 (joints at rest) the leading foot rises: no heel strike, yet the
    # bilateral impact would report T_c = T (everything "lost") at every grid point.
    from heelstrike.analysis.model_gaits import symmetric_heel_strike_state
    from heelstrike.dynamics.phased import load_phased_walker

    walker = load_phased_walker("compass")
    q, qd = symmetric_heel_strike_state(walker, 0.2, stance_rate=-1.0)
    assert (walker.contact_jacobian(np.asarray(q), "left") @ np.asarray(qd))[1] > 0
    line = _one_line_error(*_run(capsys, "impact-map", "--model", "compass", "--x",
                                 "R:0:0.3:2", "--y", "angle:10deg:20deg:2", "--q3dot", "-1",
                                 "--out", str(tmp_path / "m")))
    assert "--q3dot must be > 0" in line and "no heel strike" in line
    assert not (tmp_path / "m" / "impact_map.csv").exists()
    # at rest (q3dot = 0) nothing strikes either: it wrote rows of zeros
    line = _one_line_error(*_run(capsys, "impact-map", "--model", "compass", "--x",
                                 "R:0:0.3:2", "--y", "angle:10deg:20deg:2", "--q3dot", "0",
                                 "--out", str(tmp_path / "m")))
    assert "--q3dot must be > 0, got 0" in line
    assert not (tmp_path / "m" / "impact_map.csv").exists()


@pytest.mark.parametrize(("argv", "needle"), [
    # an option the command would ignore is refused, not dropped (QA sweep 3)
    (["impact-map", "--model", "compass", "--x", "R:0:0.5:2", "--y", "angle:10deg:20deg:2",
      "--param", "R=0.3"], "--param R=... is swept by --x/--y"),
    (["impact-map", "--model", "compass", "--x", "R:0:0.5:2", "--y", "angle:10deg:20deg:2",
      "--angle", "15deg"], "--angle sets the impact angle when it is not swept"),
    (["impact-map", "--model", "compass", "--x", "R:0:1:1", "--y", "angle:10deg:20deg:2"],
     "COUNT 1 is one point, START, so STOP must equal START"),
    (["powered", "--gain", "5"], "--gain not used by --actuation pushoff"),
    (["powered", "--actuation", "hip-energy", "--kp", "10"],
     "--kp not used by --actuation hip-energy"),
    (["study", "cost", "--kd", "1"], "--kd not used by --actuation pushoff"),
    (["powered", "--actuation", "hip-pd", "--kd", "nan"], "--kd must be finite and >= 0"),
])
def test_ignored_or_meaningless_options_are_refused(argv: list[str], needle: str,
                                                    capsys: Capsys, tmp_path: Path) -> None:
    out = tmp_path / "out"
    line = _one_line_error(*_run(capsys, *argv, "--out", str(out)))
    assert needle in line
    assert not out.exists() or not any(out.iterdir())


def test_error_lines_escape_control_characters(tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    # issue 36: a path holding an ANSI escape was printed raw in the error line
    from heelstrike.cli._render import fail

    assert fail("cannot read /tmp/a\x1b[31m.json") == 2
    err = capsys.readouterr().err
    assert "\x1b" not in err and "\\x1b[31m" in err
    pytest.importorskip("pinocchio")  # a command that names the path as it is given
    bad = tmp_path / "log\x1b[31m.txt"
    bad.write_text("t,q_0,v_0\n")
    assert main(["robot", "replay", str(bad), "--model", "talos", "--contact", "a:point"]) == 2
    err = capsys.readouterr().err
    assert "\x1b" not in err and "\\x1b[31m" in err
    assert err.startswith("heelstrike: error:") and err.count("\n") == 1
