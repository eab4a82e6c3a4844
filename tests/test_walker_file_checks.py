"""Walker files written by users (QA sweep 12): what would have given a silently wrong or
unexplained answer is refused or said, in one line naming the cause.

1. a shipped name means the shipped walker even with a file or folder of that name in the
   working directory (a file ``compass`` there replaced it, silently);
2. a declared parameter that no field uses: setting it changed nothing, silently;
3. a mass matrix singular at every configuration ("division by zero" from the kernels);
4. a walker without mirrors reported an "unexpected NotImplementedError";
5. symmetry errors name what does not mirror (they all blamed ``link[0].mirror``);
6. units in expressions and reserved coordinate names are explained;
7. ``gait --model`` prints the impact angle, as the compass report does.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import heelstrike
from heelstrike.cli import main
from heelstrike.models.builder import BuiltWalker, load_walker, walker_description
from heelstrike.models.description import ModelDescriptionError, parse_description

WALKERS = Path(heelstrike.__file__).parent / "walkers"


def _compass_text() -> str:
    return (WALKERS / "compass.toml").read_text()


def _data(text: str | None = None) -> dict[str, Any]:
    return tomllib.loads(_compass_text() if text is None else text)


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    rc = main(list(argv))
    out, err = capsys.readouterr()
    return rc, out, err


def test_a_shipped_name_is_the_shipped_walker_whatever_the_folder_holds(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.chdir(tmp_path)
    heavy_hip = _compass_text().replace("mH = 10.0", "mH = 2.0")
    (tmp_path / "compass").write_text(heavy_hip)
    (tmp_path / "kneed").mkdir()  # e.g. the --out folder of an earlier run
    shipped = walker_description(WALKERS / "compass.toml")
    assert walker_description("compass") == shipped
    assert walker_description("./compass").default_params["mH"] == 2.0
    assert walker_description(Path("compass")).default_params["mH"] == 2.0
    args = ("impact", "--angle", "20deg", "--json")
    rc, out, err = _run(capsys, *args, "--model", "compass")
    assert rc == 0 and "the file 'compass' in the working directory is not read" in err
    t_shipped = json.loads(out)["T"]
    rc, out, _ = _run(capsys, *args, "--model", "./compass")
    assert rc == 0 and json.loads(out)["T"] < t_shipped  # the lighter hip: the file's walker
    rc, out, err = _run(capsys, *args, "--model", "kneed")
    # no note for the folder (stderr may show the walker's derivation on a cold cache)
    assert rc == 0 and "note" not in err and json.loads(out)["model"] == "kneed"


def test_a_failed_walk_leaves_no_output_folder(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "walk_out"
    rc, _, err = _run(capsys, "walk", "--model", str(tmp_path / "missing.toml"), "--out",
                      str(out))
    assert rc == 2 and "cannot read model" in err
    assert not out.exists()


def test_setting_a_parameter_that_no_field_uses_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = (_compass_text().replace('com = "l - b"', 'com = "l - 0.6"')
            .replace('com = "b"', 'com = "0.6"').replace('constraints = ["0 < b < l", ',
                                                         'constraints = ['))
    desc = parse_description(_data(text))
    assert desc.unused_params == {"b"}
    assert walker_description("kneed").unused_params == frozenset()
    assert all(walker_description(n).unused_params == frozenset() for n in ("compass", "torso"))
    with pytest.raises(ModelDescriptionError, match=r"^params\.b: walker 'compass' uses it "
                       "nowhere .* so setting it changes nothing"):
        BuiltWalker(desc, b=0.3)
    # its own value (what a copy of the walker passes) is no change
    w = BuiltWalker(desc, **desc.default_params)
    assert w.parameters["b"] == 0.5
    path = tmp_path / "fixed_com.toml"
    path.write_text(text.replace('name = "compass"', 'name = "fixed_com"'))
    rc, _, err = _run(capsys, "impact", "--model", str(path), "--angle", "15deg", "--param",
                      "b=0.3")
    assert rc == 2 and "params.b: walker 'fixed_com' uses it nowhere" in err
    rc, _, err = _run(capsys, "impact", "--model", str(path), "--angle", "15deg")
    assert rc == 0
    assert "declares parameter(s) b that no field uses: their values change nothing" in err


def test_a_singular_mass_matrix_is_refused_naming_the_coordinate(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # without the file's constraints, b = 0 puts the swing leg's mass on the hip axis
    # (I = 0): the hip coordinate moves nothing and M is singular at every configuration
    text = _compass_text().replace('constraints = ["0 < b < l", "R <= l"]', "")
    desc = parse_description(_data(text))
    w = BuiltWalker(desc, b=1e-3)
    assert np.linalg.eigvalsh(w.mass_matrix(np.array([0.0, 0.0, 0.2, -0.4])))[0] > 0
    with pytest.raises(ModelDescriptionError,
                       match=r"mass matrix is singular .* coordinate 'hip' moves no mass"):
        BuiltWalker(desc, b=0.0)
    # with a leg inertia the same mass placement is fine
    assert BuiltWalker(desc, b=0.0, I=0.1).parameters["b"] == 0.0
    # a batch of walkers: refused if any member is singular
    with pytest.raises(ModelDescriptionError, match="coordinate 'hip'"):
        BuiltWalker(desc, b=np.array([0.5, 0.0]))
    path = tmp_path / "free_b.toml"
    path.write_text(text.replace('name = "compass"', 'name = "free_b"'))
    rc, _, err = _run(capsys, "gait", "--model", str(path), "--param", "b=0")
    assert rc == 2 and "coordinate 'hip' moves no mass and no inertia" in err
    assert "division by zero" not in err


@pytest.mark.slow
def test_a_walker_without_mirrors_is_one_plain_error_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text = "\n".join(ln for ln in _compass_text().splitlines() if not ln.startswith("mirror"))
    path = tmp_path / "nomirror.toml"
    path.write_text(text.replace('name = "compass"', 'name = "nomirror"'))
    rc, out, err = _run(capsys, "gait", "--model", str(path))
    assert rc == 2 and out == ""
    line = err.strip().splitlines()[-1]
    assert line.startswith("heelstrike: error: walker 'nomirror': no leg swap")
    assert "link.mirror" in line and "unexpected" not in line and "HEELSTRIKE_DEBUG" not in line


def _link(data: dict[str, Any], name: str) -> dict[str, Any]:
    return next(lk for lk in data["link"] if lk["name"] == name)


def test_symmetry_errors_name_what_does_not_mirror() -> None:
    data = _data()
    data["params"]["m2"] = 4.0
    _link(data, "swing_leg")["mass"] = "m2"
    with pytest.raises(ModelDescriptionError, match=r"^link\[0\]\.mass: link 'stance_leg' and "
                       r"its mirror 'swing_leg' differ \(5 vs 4\).*legs differ names each leg's "
                       r"parameters by role and lists the pairs the leg swap exchanges in a "
                       r"\[swap\] table"):
        BuiltWalker(parse_description(data))
    data = _data()
    _link(data, "swing_leg")["com"] = "0.4"  # the stance leg's COM is l - b = 0.5 from its foot
    with pytest.raises(ModelDescriptionError, match=r"^link\[0\]\.com: after the leg swap the "
                       "centre of mass of 'stance_leg' is not where 'swing_leg''s was"):
        BuiltWalker(parse_description(data))
    data = _data()
    data["point_mass"].append({"name": "bag", "link": "swing_leg", "at": "0.5", "mass": "1.0"})
    with pytest.raises(ModelDescriptionError, match=r"^point_mass: the leg swap maps the links "
                       "but not the mass distribution"):
        BuiltWalker(parse_description(data))
    # the shipped walkers are symmetric
    for name in ("compass", "kneed", "torso"):
        load_walker(name).check_swap_symmetry()


def test_units_in_expressions_and_reserved_names_are_explained() -> None:
    data = _data()
    data["foot"][0]["radius"] = "0.3 m"
    with pytest.raises(ModelDescriptionError, match=r"^foot\[0\]\.radius: invalid expression "
                       r"'0\.3 m': values in a walker file are plain numbers in SI units "
                       r"\(angles in radians\), without a unit such as 'm'"):
        parse_description(data)
    data = _data()
    _link(data, "swing_leg")["joint"]["name"] = "x"
    with pytest.raises(ModelDescriptionError, match=r"^link\[1\]\.joint\.name: duplicate "
                       r"coordinate name 'x': it is a base coordinate's name \(x, y\)"):
        parse_description(data)
    data = _data()
    _link(data, "swing_leg")["joint"]["name"] = "stance_leg"
    with pytest.raises(ModelDescriptionError, match="it is the root link's name"):
        parse_description(data)


@pytest.mark.slow
def test_gait_model_reports_the_impact_angle(capsys: pytest.CaptureFixture[str]) -> None:
    rc, out, _ = _run(capsys, "gait", "--model", "compass", "--param", "R=0.3", "--json")
    assert rc == 0
    angle = json.loads(out)["impact_angle"]
    rc, out, _ = _run(capsys, "gait", "--model", "compass", "--param", "R=0.3")
    assert rc == 0
    line = next(ln for ln in out.splitlines() if ln.strip().startswith("impact angle"))
    assert f"{angle:10.5f} rad" in line and f"({np.degrees(angle):.3f} deg)" in line
    # the compass shorthand's report has the same line, and the same angle (one walker)
    rc, out, _ = _run(capsys, "gait", "--radius", "0.3")
    assert rc == 0 and line in out.splitlines()
