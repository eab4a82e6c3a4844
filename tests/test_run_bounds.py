"""Every grid, run and expression is bounded before evaluation (issue 36)."""

from __future__ import annotations

import math

import pytest

from heelstrike.analysis._memory import MAX_RUN_SECONDS, RunTooLongError, require_budget
from heelstrike.cli import main
from heelstrike.models.description import ModelDescriptionError, evaluate_expression

_HUGE = [
    ["map", "--model", "compass", "--x", "R:0:0.2:1000000000"],
    ["map", "--radius", "0:0.2:1000000000"],
    ["bifurcation", "--slope-range", "1deg:6deg:100000000"],
    ["bifurcation", "--transient", "1000000000"],
    ["walk", "--steps", "1000000000"],
    ["basin", "--steps", "1000000000"],
    ["basin", "--grid", "100000x100000"],
    ["impact-map", "--model", "compass", "--x", "R:0:0.2:100000", "--y", "m:1:2:100000"],
]


@pytest.mark.parametrize("argv", _HUGE, ids=lambda a: " ".join(a[:2]))
def test_huge_runs_are_refused_before_computing(argv, tmp_path, capsys):
    assert main([*argv, "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "memory" in err or "hours" in err, err
    assert "--" in err.split("heelstrike: error:")[-1]  # names the options to change
    assert not (tmp_path / "out").exists()  # refused before the output folder is made


def test_the_budget_refuses_by_stated_estimates_not_timings():
    require_budget("a small run", 10, bytes_per_point=8, seconds_per_point=1.0)
    with pytest.raises(RunTooLongError, match="--steps"):
        require_budget("a long run", 10**6, bytes_per_point=8,
                       seconds_per_point=MAX_RUN_SECONDS / 10**5, hint="give fewer --steps")
    with pytest.raises(MemoryError, match="a vast run"):
        require_budget("a vast run", 10**30, bytes_per_point=8)


def test_basin_tol_must_be_finite(tmp_path, capsys):
    assert main(["basin", "--tol", "inf", "--out", str(tmp_path / "b")]) == 2
    assert "--tol must be finite" in capsys.readouterr().err


@pytest.mark.parametrize("text", [
    "((9**16)**16)**16",
    "(((((((9**16)**16)**16)**16)**16)**16)**16)",
    "(m * (l**4)**8)",
    "sqrt((l**16)**2)",
])
def test_nested_powers_are_bounded_before_evaluation(text):
    # refused by the exponent bound, before anything is raised to a power
    with pytest.raises(ModelDescriptionError, match="total exponent"):
        evaluate_expression(text, {"m": 1.0, "l": 2.0}, path="link[0].mass")


def test_huge_integer_products_are_floats_or_refused():
    v = evaluate_expression("9**16 * 9**16", {}, path="x")
    assert isinstance(v, float) and math.isclose(v, 9.0**32)
    with pytest.raises(ModelDescriptionError, match=r"link\[0\]\.mass: .*cannot be evaluated"):
        evaluate_expression("1e200 * 1e200", {}, path="link[0].mass")
    with pytest.raises(ModelDescriptionError, match=r"link\[0\]\.mass: .*cannot be evaluated"):
        evaluate_expression("9007199254740992**16 * 9007199254740992**16", {},
                            path="link[0].mass")


def _walker_file(tmp_path, old, new):
    from importlib.resources import files

    text = (files("heelstrike") / "walkers" / "compass.toml").read_text()
    assert old in text
    path = tmp_path / "w.toml"
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize(("old", "new", "said"), [
    ("m = 5.0", "m = 1e308", "params.m: 1e+308 is beyond"),
    ('mass = "mH"', 'mass = "mH + ((9**16)**16)**16"', "point_mass[0].mass: nested powers"),
    ('"R <= l"]', '"R <= l", "R < ((9**16)**16)**16"]', "constraints[2]: nested powers"),
])
def test_walker_file_values_out_of_range_name_file_and_field(tmp_path, capsys, old, new, said):
    path = _walker_file(tmp_path, old, new)
    assert main(["gait", "--model", str(path)]) == 2
    err = capsys.readouterr().err
    assert said in err and str(path) in err, err
