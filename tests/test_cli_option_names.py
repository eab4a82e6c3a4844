"""Option names are a contract (issue 32): whole names only, one name and one range syntax for
the same thing in every command, old names kept as deprecated aliases that say so."""

from __future__ import annotations

import argparse
import math

import pytest

from heelstrike.cli import build_parser, main


def _parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """``parser`` and every subcommand's parser below it."""
    found = [parser]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in dict.fromkeys(action.choices.values()):
                found += _parsers(sub)
    return found


def test_no_parser_takes_an_abbreviated_option():
    parsers = _parsers(build_parser())
    assert len(parsers) > 12  # every command and subcommand (study cost, robot ...)
    assert [p.prog for p in parsers if p.allow_abbrev] == []


@pytest.mark.parametrize("argv", [
    ["bifurcation", "--slope-r", "1deg:2deg:3"],  # was read as --slope-range
    ["map", "--slo", "1deg:2deg:3"],  # was read as --slope
    ["gait", "--rad", "0.3"],  # was read as --radius
    ["powered", "--spe", "0.5"],  # was read as --speed
    ["study", "cost", "--step-len", "0.6"],  # was read as --step-length
])
def test_an_abbreviated_option_is_an_error(argv, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("heelstrike: error: unrecognized arguments"), err


@pytest.mark.parametrize(("command", "option"), [("bifurcation", "--slope"),
                                                 ("map", "--slope")])
def test_slopes_are_one_option_with_one_range_syntax(command, option):
    parser = build_parser()
    for text, want in [("1deg:6deg:21", (1.0, 6.0, 21)), ("1deg:6deg", (1.0, 6.0, None)),
                       ("3deg", (3.0, 3.0, 1))]:
        start, stop, count = parser.parse_args([command, option, text]).slope
        assert (math.degrees(start), math.degrees(stop), count) == pytest.approx(want)


def test_bifurcation_slope_is_a_slope_not_an_abbreviation(tmp_path, capsys):
    # issue 32: "bifurcation --slope 3deg" was taken as --slope-range and printed "3 to 3 deg"
    # with no word of it; --slope is now the option's own name, one slope is one point
    args = build_parser().parse_args(["bifurcation", "--slope", "3deg", "--out", str(tmp_path)])
    assert args.slope == pytest.approx((math.radians(3.0), math.radians(3.0), 1))
    assert not vars(args).get("deprecated")


def test_bifurcation_slope_range_still_works_with_a_deprecation_note(monkeypatch, capsys):
    import heelstrike.cli.gait as cli_gait

    seen = {}

    def run(args):
        seen["slope"] = args.slope
        print("ran")
        return 0

    monkeypatch.setattr(cli_gait, "_run_bifurcation", run)
    assert main(["bifurcation", "--slope-range", "2deg:3deg:5"]) == 0
    assert seen["slope"] == pytest.approx((math.radians(2.0), math.radians(3.0), 5))
    captured = capsys.readouterr()
    assert captured.out == "ran\n"
    err = captured.err.strip().splitlines()
    assert err == ["heelstrike: note: --slope-range is deprecated: it is now --slope (the same "
                   "values)"]
    # the new name: no note
    assert main(["bifurcation", "--slope", "2deg:3deg:5"]) == 0
    assert capsys.readouterr().err == ""


def test_bifurcation_refuses_both_slope_names(capsys):
    assert main(["bifurcation", "--slope", "2deg:3deg:3", "--slope-range", "2deg:3deg:3"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not allowed with argument --slope" in err[0], err


def test_a_failing_command_with_the_old_name_prints_its_one_error_line(capsys):
    assert main(["bifurcation", "--slope-range", "5deg:1deg"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["heelstrike: error: --slope needs 0 < START < STOP, or one slope > 0"]
