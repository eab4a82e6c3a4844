"""The front door (issue 12): light imports, optional extras, version, units in JSON, scalars.

- ``heelstrike impact --json`` and ``heelstrike --help`` load neither ``scipy.integrate`` nor
  ``numba`` nor ``matplotlib`` (issue 9, item 6);
- without the ``scale`` extra (dask, distributed, zarr, netCDF4) the light commands still work
  and what needs the extra fails with one line naming it;
- ``heelstrike --version`` / ``python -m heelstrike``; CITATION.cff matches the package;
- every ``--json`` object carries a ``units`` map for its keys;
- one impact (scalar inputs) gives Python floats, a batch gives arrays.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
import tomllib
from importlib.metadata import version
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from heelstrike._optional import MissingExtraError
from heelstrike.cli import main

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("scipy.integrate", "numba", "matplotlib")
SCALE_MODULES = ("dask", "dask.array", "distributed", "zarr", "netCDF4", "h5netcdf", "filelock")


def _loaded_after(argv: list[str]) -> list[str]:
    """Heavy modules loaded by a fresh interpreter that runs ``heelstrike <argv>``."""
    code = (
        "import sys\n"
        "from heelstrike.cli import main\n"
        "try:\n"
        f"    main({argv!r})\n"
        "except SystemExit:\n"
        "    pass\n"
        f"heavy = [m for m in {HEAVY!r} if m in sys.modules]\n"
        "sys.stderr.write('HEAVY=' + ','.join(heavy) + '\\n')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True)
    line = [s for s in out.stderr.splitlines() if s.startswith("HEAVY=")][-1]
    return [m for m in line[len("HEAVY="):].split(",") if m]


@pytest.mark.parametrize(
    "argv",
    [["impact", "--radius", "0.25", "--angle", "20deg", "--json"], ["--help"]],
    ids=["impact-json", "help"],
)
def test_light_commands_do_not_import_integrators_jit_or_plotting(argv: list[str]) -> None:
    assert _loaded_after(argv) == []


def test_heavy_module_detection_can_fail() -> None:
    """The probe's criterion can fail: integrating a step does load scipy.integrate (lazily,
    when ``heelstrike.simulate`` first integrates)."""
    code = ("import sys, numpy as np, heelstrike\n"
            "w = heelstrike.CompassGait()\n"
            "q, qd = heelstrike.heel_strike_state(w, 0.2)\n"
            "before = 'scipy.integrate' in sys.modules\n"
            "heelstrike.simulate(w, q, np.array([0.0, 0.0, -1.0, 0.0]), slope=0.05, steps=1)\n"
            "print(before, 'scipy.integrate' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True)
    assert out.stdout.strip() == "False True"


# -- the scale extra ----------------------------------------------------------------------
@pytest.fixture
def without_scale(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make the scale extra's packages unimportable (as in the light install, ``pip install .``)."""
    for name in SCALE_MODULES:
        monkeypatch.setitem(sys.modules, name, None)


def _energies(impact_angle: np.ndarray, foot_radius: np.ndarray) -> dict[str, Any]:
    from heelstrike.analysis.heel_strike import heel_strike_study
    from heelstrike.models.compass import CompassGait

    s = heel_strike_study(CompassGait(foot_radius=foot_radius), impact_angle)
    return {"T_c": s.kinetic_energy_constrained, "lifts": s.trailing_foot_lifts}


GRID = {"impact_angle": np.linspace(0.05, 0.7, 7), "foot_radius": np.linspace(0.0, 1.0, 5)}


@pytest.mark.parametrize("scheduler", [None, "threads", "sync"])
def test_sweep_without_dask_runs_on_threads_with_same_result(
    scheduler: str | None, monkeypatch: pytest.MonkeyPatch
) -> None:
    import xarray as xr

    from heelstrike.analysis.sweep import sweep

    reference = sweep(_energies, GRID, chunks=3, progress=False, scheduler="sync")
    for name in SCALE_MODULES:
        monkeypatch.setitem(sys.modules, name, None)
    light = sweep(_energies, GRID, chunks=3, progress=False, scheduler=scheduler,
                  num_workers=2)
    xr.testing.assert_identical(light, reference)


@pytest.mark.parametrize(
    ("kwargs", "feature"),
    [({"store": "s.zarr"}, "a sweep store"), ({"scheduler": "processes"}, "'processes'"),
     ({"scheduler": "tcp://127.0.0.1:1"}, "cluster")],
)
def test_sweep_features_of_the_extra_name_it(
    kwargs: dict[str, Any], feature: str, tmp_path: Path, without_scale: None
) -> None:
    from heelstrike.analysis.sweep import sweep

    if "store" in kwargs:
        kwargs = {"store": tmp_path / kwargs["store"]}
    with pytest.raises(MissingExtraError) as info:
        sweep(_energies, GRID, chunks=3, progress=False, **kwargs)
    message = str(info.value)
    assert feature in message
    assert message.endswith(
        "needs the 'scale' extra: pip install '.[scale]' in a clone of heelstrike")
    assert "\n" not in message
    assert not (tmp_path / "s.zarr").exists()


def test_cli_reports_a_missing_extra_in_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A command that needs the extra exits 2 with one line naming it (simulated by a command
    whose library call raises, as a sweep store does without zarr)."""
    import heelstrike.analysis.heel_strike as hs

    def needs_extra(*args: Any, **kwargs: Any) -> Any:
        from heelstrike._optional import require

        return require("heelstrike_no_such_module", "netCDF output")

    monkeypatch.setattr(hs, "heel_strike_study", needs_extra)
    assert main(["impact", "--angle", "20deg", "--json"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err == (
        "heelstrike: error: netCDF output needs the 'scale' extra: "
        "pip install '.[scale]' in a clone of heelstrike\n"
    )


def _basin_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> dict[str, Any]:
    assert main(["basin", "--grid", "6x5", "--steps", "10", "--out", str(tmp_path),
                 "--json"]) == 0
    return dict(json.loads(capsys.readouterr().out))


def test_basin_without_netcdf4_writes_classic_netcdf(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], without_scale: None
) -> None:
    import xarray as xr

    d = _basin_json(tmp_path, capsys)
    nc = Path(d["data"])
    assert nc.read_bytes()[:4] == b"CDF\x02"  # netCDF classic, 64-bit offset
    with xr.open_dataset(nc, engine="scipy") as ds:
        from heelstrike.analysis.basin import OUTCOMES

        outcome = ds["outcome"].values
        assert outcome.shape == (6, 5)
        for s in OUTCOMES:  # the file holds what the command reported (walk-status codes)
            assert np.mean(outcome == s.code) == pytest.approx(d["fractions"][s.value])
        assert len(set(outcome.ravel().tolist())) > 1
        assert ds.attrs["max_steps"] == 10
    _check_units(d)


def test_basin_with_netcdf4_writes_netcdf4(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("netCDF4")
    d = _basin_json(tmp_path, capsys)
    assert Path(d["data"]).read_bytes()[:4] == b"\x89HDF"
    _check_units(d)


# -- version, python -m, citation ----------------------------------------------------------
def test_version_and_python_m() -> None:
    import heelstrike

    # the version is written once (heelstrike/_version.py); the installed metadata reads it
    assert heelstrike.__version__ == version("heelstrike")
    expected = f"heelstrike {version('heelstrike')}"
    for cmd in ([sys.executable, "-m", "heelstrike", "--version"],):
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=120, check=True)
        assert out.stdout.strip() == expected
    out = subprocess.run(
        [sys.executable, "-m", "heelstrike", "impact", "--radius", "0.25", "--angle", "20deg",
         "--json"], capture_output=True, text=True, timeout=120, check=True)
    d = json.loads(out.stdout)
    assert d["T"] == pytest.approx(d["T_c"] + d["T_a"], rel=1e-12)
    bad = subprocess.run([sys.executable, "-m", "heelstrike", "impact", "--angle", "95deg"],
                         capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and bad.stderr.startswith("heelstrike: error:")


def test_version_matches_pyproject_and_citation() -> None:
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    # the version is written once, in heelstrike/_version.py, which pyproject reads
    assert pyproject["project"]["dynamic"] == ["version"]
    attr = pyproject["tool"]["setuptools"]["dynamic"]["version"]["attr"]
    assert attr == "heelstrike._version.__version__"
    declared = re.search(r'^__version__ = "([^"]+)"$',
                         (ROOT / "src/heelstrike/_version.py").read_text(), re.M)
    assert declared is not None
    meta = {"version": declared.group(1)}
    assert version("heelstrike") == meta["version"]
    cff = (ROOT / "CITATION.cff").read_text(encoding="utf-8")
    assert re.search(rf"^version: \"?{re.escape(meta['version'])}\"?$", cff, re.M)
    assert "Dynamics of Heel Strike in Bipedal Systems with Circular Feet" in cff
    assert "BSD-3-Clause" in cff
    license_text = (ROOT / "LICENSE").read_text(encoding="utf-8")
    assert "BSD 3-Clause" in license_text and "heelstrike developers" in license_text
    changelog = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert f"## [{meta['version']}]" in changelog


# -- units in every --json object -----------------------------------------------------------
_UNIT = re.compile(r"^(1|[A-Za-z]+(\^?-?\d)?( [A-Za-z]+(\^?-?\d)?)*(/[A-Za-z]+(\^?\d)?)?)$")


def _check_units(d: dict[str, Any]) -> dict[str, Any]:
    """Every key of ``d`` (but ``units``) has a unit entry shaped like its value."""
    units = d["units"]
    assert set(units) == set(d) - {"units"}, set(d) ^ set(units)

    def check(value: Any, unit: Any, where: str) -> None:
        if isinstance(value, dict):
            assert isinstance(unit, dict) and set(unit) == set(value), where
            for k in value:
                check(value[k], unit[k], f"{where}.{k}")
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            assert isinstance(unit, dict), where
            for item in value:
                check(item, {k: unit[k] for k in item}, f"{where}[]")
        elif isinstance(value, list) and not value and isinstance(unit, dict):
            assert unit == {}, where  # an empty list of objects (e.g. other_gaits)
        elif isinstance(unit, list):
            assert isinstance(value, list) and len(unit) == len(value), where
            for u in unit:
                assert isinstance(u, str) and _UNIT.match(u), (where, u)
        elif unit is not None:
            assert isinstance(unit, str) and _UNIT.match(unit), (where, unit)
            assert not isinstance(value, bool | str), (where, value)

    for key in units:
        check(d[key], units[key], key)
    return dict(units)


def _json(argv: list[str], capsys: pytest.CaptureFixture[str]) -> dict[str, Any]:
    assert main(argv) == 0
    return dict(json.loads(capsys.readouterr().out))


def test_impact_json_units(capsys: pytest.CaptureFixture[str]) -> None:
    d = _json(["impact", "--radius", "0.25", "--angle", "20deg", "--json"], capsys)
    u = _check_units(d)
    assert u["T"] == u["T_c"] == u["T_a"] == u["energy_lost"] == "J"
    assert u["eta"] == "J/m" and u["step_length"] == "m" and u["impact_angle"] == "rad"
    assert u["qdot_plus"] == ["m/s", "m/s", "rad/s", "rad/s"]
    assert u["impulse"] == ["N s", "N s"]
    # the values are in the units said: eta = T_c / L_S, the angle given as 20deg is in rad
    assert d["eta"] == pytest.approx(d["T_c"] / d["step_length"], rel=1e-12)
    assert d["impact_angle"] == pytest.approx(np.deg2rad(20.0), rel=1e-15)


def test_model_impact_json_units(capsys: pytest.CaptureFixture[str]) -> None:
    d = _json(["impact", "--model", "kneed", "--angle", "15deg", "--json"], capsys)
    u = _check_units(d)
    n = len(d["coordinates"])
    assert u["q"] == ["m", "m"] + ["rad"] * (n - 2)
    assert u["qdot_plus"] == ["m/s", "m/s"] + ["rad/s"] * (n - 2)
    # striking foot (x, y) in N s, then the two knee locks in N m s; the trailing foot lifts
    assert d["trailing_foot_lifts"] is True
    assert u["impulse"] == ["N s", "N s", "N m s", "N m s"]


def test_gait_json_units(capsys: pytest.CaptureFixture[str]) -> None:
    d = _json(["gait", "--radius", "0.3", "--slope", "3deg", "--json"], capsys)
    u = _check_units(d)
    assert u["fixed_point"] == {"q3": "rad", "q3_dot": "rad/s", "q4_dot": "rad/s"}
    assert u["period"] == "s" and u["speed"] == "m/s" and u["collision_loss"] == "J"
    assert d["speed"] == pytest.approx(d["step_length"] / d["period"], rel=1e-9)


def test_map_json_units(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    d = _json(["map", "--radius", "0:0.1:2", "--slope", "3deg:3.5deg:2", "--out",
               str(tmp_path), "--json"], capsys)
    u = _check_units(d)
    assert u["slope"] == "rad" and u["foot_radius"] == "m"
    assert d["slope"][0] == pytest.approx(np.deg2rad(3.0))


@pytest.mark.slow
def test_powered_json_units(capsys: pytest.CaptureFixture[str]) -> None:
    d = _json(["powered", "--radius", "0.3", "--speed", "0.5", "--json"], capsys)
    u = _check_units(d)
    assert u["parameter"] == d["parameter_unit"] == "N s"
    assert u["cost_of_transport"] == "1" and u["actuator_work"] == "J"
    # two gaits meet 0.3 m/s with point feet: the other one's units too
    two = _json(["powered", "--radius", "0", "--speed", "0.3", "--json"], capsys)
    assert two["gaits_found"] == 2
    assert _check_units(two)["other_gaits"]["actuator_work"] == "J"
    pd = _json(["powered", "--radius", "0.3", "--actuation", "hip-pd", "--json"], capsys)
    assert _check_units(pd)["gains"]["kp"] == "N m/rad"


# -- Python scalars from scalar inputs ------------------------------------------------------
def test_scalar_inputs_give_python_floats_and_batches_arrays() -> None:
    from heelstrike.analysis.heel_strike import heel_strike_study
    from heelstrike.core import impact
    from heelstrike.models import CompassGait

    r = impact(np.diag([2.0, 1.0]), np.array([[1.0, 1.0]]), [1.0, 0.0])
    for name in ("kinetic_energy", "kinetic_energy_constrained", "kinetic_energy_admissible",
                 "kinetic_energy_post", "energy_lost"):
        assert type(getattr(r, name)) is float, name
    assert r.kinetic_energy_constrained == pytest.approx(1.0 / 3.0, rel=1e-14)
    batch = impact(np.diag([2.0, 1.0]), np.array([[1.0, 1.0]]), [[1.0, 0.0], [0.0, 1.0]])
    assert isinstance(batch.kinetic_energy_constrained, np.ndarray)
    assert batch.kinetic_energy_constrained.shape == (2,)
    np.testing.assert_allclose(batch.kinetic_energy_constrained[0], 1.0 / 3.0, rtol=1e-14)

    s = heel_strike_study(CompassGait(foot_radius=0.25), np.deg2rad(20.0))
    assert type(s.eta) is float and type(s.kinetic_energy_constrained) is float
    assert type(s.trailing_foot_lifts) is bool and s.trailing_foot_lifts
    assert type(s.degenerate_wheel) is bool and not s.degenerate_wheel
    assert s.eta == pytest.approx(s.energy_lost / s.step_length, rel=1e-14)
    grid = heel_strike_study(CompassGait(foot_radius=np.array([0.0, 0.25])), np.deg2rad(20.0))
    assert grid.eta.shape == (2,) and grid.trailing_foot_lifts.dtype == bool
    assert grid.eta[1] == s.eta


def test_limit_cycle_scalars_are_python_floats() -> None:
    from heelstrike.analysis.limit_cycle import find_limit_cycle
    from heelstrike.models import CompassGait

    c = find_limit_cycle(CompassGait(foot_radius=0.3), slope=np.deg2rad(3.0), method="compiled")
    for name in ("period", "step_length", "speed", "collision_loss", "eta", "slope",
                 "potential_energy_released", "impact_angle"):
        assert type(getattr(c, name)) is float, name
    assert type(c.stable) is bool


def test_no_test_depends_on_machine_speed() -> None:
    """Issue 35: a per-example hypothesis deadline or an assertion on elapsed time fails on a
    loaded machine. Tests set no deadline but None (conftest's profile has none) and assert no
    wall-clock duration."""
    timed = re.compile(r"assert[^\n#]*(perf_counter|monotonic|time\.time)\(\)\s*-")
    for path in sorted((ROOT / "tests").glob("*.py")):
        text = path.read_text()
        for m in re.finditer(r"(settings|register_profile)\([^)]*deadline\s*=\s*([^,)\s]+)",
                             text):
            line = text[: m.start()].count("\n") + 1
            if m.group(2) != "None":
                raise AssertionError(f"{path.name}:{line}: hypothesis deadline {m.group(2)}")
        assert not timed.search(text), f"{path.name}: an assertion on elapsed time"
