"""Parameter sensitivities of a gait and ``heelstrike design`` (issue 33, items 2, 4, 5).

The sensitivities (implicit function theorem on the periodicity condition) are checked against
central differences of *converged* gaits (Newton re-solved at p +- h, an independent route) to
1e-6 relative, and against closed forms: on a passive gait the energy books close, so
``eta = M g sin(slope)`` for every design, whence ``d eta / d slope = M g cos(slope)``,
``d eta / d m = 2 g sin(slope)`` (two legs of mass m) and ``d eta / d R = 0``.

The design problem with a known answer: minimising ``eta`` over the foot radius and the slope
within bounds; ``eta = M g sin(slope)`` increases with the slope and does not depend on ``R``,
so the optimum is the slope's lower bound with ``eta = M g sin(lower)`` exactly (a bound-active
KKT point: the multiplier of the bound is ``d eta / d slope > 0``, the free gradient is zero).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.design import DesignError, DesignStatus, design, foot_outline
from heelstrike.analysis.design_gradients import GradientError, gait_gradients
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.cli import main
from heelstrike.models.builder import load_walker

SLOPE = 0.05
FOOT6 = Path(__file__).resolve().parents[1] / "examples" / "walkers" / "compass_foot6.toml"


@pytest.fixture(scope="module")
def compass_gait():  # type: ignore[no-untyped-def]
    w = load_walker("compass", R=0.3)
    g = find_model_gait(w, slope=SLOPE, backend="scipy")
    s = gait_gradients(w, g.fixed_point, ["R", "slope", "m"], slope=SLOPE,
                         spectral_radius=False)
    return w, g, s


def _converged(walker, z0, values: dict[str, float]) -> np.ndarray:  # type: ignore[no-untyped-def]
    params = {k: v for k, v in values.items() if k != "slope"}
    sl = values.get("slope", SLOPE)
    g = find_model_gait(walker.replace(**params) if params else walker, slope=sl,
                        backend="scipy", guess=z0, tol=1e-13)
    lift = g.impacts[-1].trailing_normal_velocity
    return np.concatenate((g.fixed_point, [g.step_length, g.period, g.speed, g.collision_loss,
                                           g.eta, lift]))


@pytest.mark.parametrize("j", [0, 1, 2], ids=["R", "slope", "m"])
def test_sensitivities_agree_with_central_differences_of_converged_gaits(
        compass_gait, j: int) -> None:  # type: ignore[no-untyped-def]
    w, g, s = compass_gait
    name = s.parameters[j]
    v0 = float(s.values[j])
    # steps within the central difference's plateau (truncation h^2, round-off tol/h)
    h = {"R": 1e-4, "slope": 1e-5, "m": 1e-3}[name]
    plus = _converged(w, g.fixed_point, {name: v0 + h})
    minus = _converged(w, g.fixed_point, {name: v0 - h})
    fd = (plus - minus) / (2 * h)
    fields = ("step_length", "period", "speed", "collision_loss", "eta", "lift_velocity")
    ift = np.concatenate((s.fixed_point_derivative[:, j], [s.derivatives[f][j] for f in fields]))
    for i, label in enumerate((*s.section_names, *fields)):
        if label == "eta" and name == "R":
            continue  # zero (closed form below): no relative comparison
        assert abs(ift[i] - fd[i]) <= 1e-6 * abs(fd[i]), (name, label, ift[i], fd[i])


def test_eta_sensitivities_are_the_energy_books_closed_form(compass_gait) -> None:  # type: ignore[no-untyped-def]
    w, _, s = compass_gait
    Mg = float(w.total_mass) * 9.81
    assert s.fields["eta"] == pytest.approx(Mg * math.sin(SLOPE), rel=1e-9)
    d = dict(zip(s.parameters, s.derivatives["eta"], strict=True))
    assert d["slope"] == pytest.approx(Mg * math.cos(SLOPE), rel=1e-7)
    assert d["m"] == pytest.approx(2 * 9.81 * math.sin(SLOPE), rel=1e-7)
    assert abs(d["R"]) <= 1e-7 * s.fields["eta"]
    cot = dict(zip(s.parameters, s.derivatives["cost_of_transport"], strict=True))
    assert cot["slope"] == pytest.approx(math.cos(SLOPE), rel=1e-7)


def test_unknown_parameter_is_named() -> None:
    w = load_walker("compass", R=0.3)
    with pytest.raises(GradientError, match="unknown parameter 'Rx'"):
        gait_gradients(w, np.zeros(3), ["Rx"], slope=SLOPE)
    with pytest.raises(DesignError, match="unknown parameter 'Rx'"):
        design(w, vary={"Rx": (0.1, 0.5)}, slope=SLOPE)
    with pytest.raises(DesignError, match=r"R=0\.5:0\.1 must have finite lower < upper"):
        design(w, vary={"R": (0.5, 0.1)}, slope=SLOPE)
    with pytest.raises(DesignError, match="outside"):
        design(w, vary={"R": (0.4, 0.5)}, slope=SLOPE)
    with pytest.raises(DesignError, match="cost 'speedy'"):
        design(w, vary={"R": (0.1, 0.5)}, slope=SLOPE, cost="speedy")


def test_design_finds_the_bound_active_optimum_and_replays_its_record(tmp_path: Path) -> None:
    w = load_walker("compass", R=0.3)
    record = tmp_path / "record.jsonl"
    vary = {"R": (0.1, 0.5), "slope": (0.02, 0.06)}
    res = design(w, vary=vary, cost="eta", slope=SLOPE, record=record)
    Mg = float(w.total_mass) * 9.81
    assert res.status is DesignStatus.CONVERGED
    assert res.active_bounds == ("slope=lower",)
    j = res.parameters.index("slope")
    assert res.final.values[j] == pytest.approx(0.02, abs=1e-12)
    assert res.final.cost == pytest.approx(Mg * math.sin(0.02), rel=1e-9)
    # KKT: the bound's multiplier d eta / d slope = M g cos(slope) > 0, the free gradient ~ 0
    assert res.final.gradient[j] == pytest.approx(Mg * math.cos(0.02), rel=1e-7)
    assert abs(res.final.gradient[1 - j]) <= 1e-7 * res.final.cost
    assert res.replayed == 0 and res.evaluations >= 2
    lines = record.read_text().splitlines()
    assert len(lines) == res.evaluations
    # a rerun replays the whole record: the same iterates, no gait simulated
    again = design(w, vary=vary, cost="eta", slope=SLOPE, record=record)
    assert again.replayed == again.evaluations == res.evaluations
    np.testing.assert_array_equal(again.final.values, res.final.values)
    assert len(record.read_text().splitlines()) == len(lines)
    # an interrupted run (the record cut after its first entry, mid-line) resumes to the same end
    record.write_text(lines[0] + "\n" + lines[1][: len(lines[1]) // 2])
    resumed = design(w, vary=vary, cost="eta", slope=SLOPE, record=record)
    assert resumed.replayed == 1
    np.testing.assert_array_equal(resumed.final.values, res.final.values)
    # a record of another problem is not replayed
    other = design(w, vary=vary, cost="eta + 0", slope=SLOPE, record=record)
    assert other.replayed == 0


def test_foot_outline_of_the_arc_is_the_circle_about_its_centre() -> None:
    R, l = 0.3, 1.0
    pts = foot_outline(load_walker("compass", R=R))
    assert pts is not None
    # hip at the origin, the arc centre l - R below it on the leg
    np.testing.assert_allclose(np.hypot(pts[:, 0], pts[:, 1] + (l - R)), R, rtol=0, atol=1e-12)
    assert np.ptp(pts[:, 0]) > 0.3  # the sweep covers the sole, not one point


@pytest.mark.slow
def test_profile_parameter_sensitivities_agree_with_converged_gaits() -> None:
    w = load_walker(FOOT6)
    g = find_model_gait(w, slope=SLOPE, backend="scipy")
    s = gait_gradients(w, g.fixed_point, ["k2", "d"], slope=SLOPE,
                         spectral_radius=False)
    z0 = g.fixed_point

    def central(name: str, h: float) -> np.ndarray:
        return (_converged(w, z0, {name: h}) - _converged(w, z0, {name: -h})) / (2 * h)

    for j, name in enumerate(s.parameters):
        # the sole's offset d has a small natural scale (third derivatives ~ 1e3 / m^2): the
        # central differences of the converged gaits at h and h/2, Richardson-extrapolated
        h = 1e-4
        fd = (4 * central(name, h / 2) - central(name, h)) / 3
        ift = np.concatenate((s.fixed_point_derivative[:, j],
                              [s.derivatives[f][j] for f in ("step_length", "period", "speed",
                                                             "collision_loss")]))
        np.testing.assert_allclose(ift, fd[:-2], rtol=1e-6, err_msg=name)


def test_cli_design_json_figures_and_record(tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "out"
    argv = ["design", "--model", "compass", "--param", "R=0.3", "--slope", "0.05",
            "--vary", "slope=0.02:0.06", "--vary", "R=0.1:0.5", "--cost", "eta", "--json",
            "--out", str(out)]
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["status"] == "converged"
    assert d["final"]["values"][0] == pytest.approx(0.02, abs=1e-12)
    Mg = 20.0 * 9.81
    assert d["final"]["cost"] == pytest.approx(Mg * math.sin(0.02), rel=1e-9)
    assert d["units"]["fields"]["eta"] == "J/m"
    for name in ("design_cost.png", "design_foot.png", "design_record.jsonl"):
        assert (out / name).is_file(), name
    # the rerun replays the record
    assert main(argv) == 0
    d2 = json.loads(capsys.readouterr().out)
    assert d2["replayed"] == d2["evaluations"] == d["evaluations"]
    # the table without --json; a bad --vary is refused before computing
    # (the trailing foot lifts at 0.49 m/s: the constraint is inactive, the answer the same)
    assert main([*argv[:-3], "--trailing-foot-lifts"]) == 0
    text = capsys.readouterr().out
    assert "slope=lower" in text and "converged" in text
    assert "lift_velocity" in text
    assert main(["design", "--model", "compass", "--slope", "0.05", "--vary", "R"]) == 2
    assert "NAME=LO:HI" in capsys.readouterr().err


def test_cli_default_tolerance_is_the_analysis_default() -> None:
    from heelstrike.analysis.design import DESIGN_TOL
    from heelstrike.cli import design as cli_design

    assert cli_design.DESIGN_TOL == DESIGN_TOL


def test_a_point_without_gait_is_stepped_back_from(tmp_path: Path) -> None:
    # the known-answer design's first trial point (its optimum) marked in the record as a point
    # without a gait: the line search must step back, and the design must end on a point that
    # has a gait, better than the start, never on the marked one
    w = load_walker("compass", R=0.3)
    record = tmp_path / "record.jsonl"
    vary = {"R": (0.1, 0.5), "slope": (0.02, 0.06)}
    first = design(w, vary=vary, cost="eta", slope=SLOPE, record=record)
    lines = [json.loads(x) for x in record.read_text().splitlines()]
    marked = lines[1]
    assert marked["values"] == list(first.final.values)
    lost = {"problem": marked["problem"], "values": marked["values"], "lost": "marked"}
    record.write_text(json.dumps(lines[0]) + "\n" + json.dumps(lost) + "\n")
    res = design(w, vary=vary, cost="eta", slope=SLOPE, record=record, max_iter=6)
    assert list(res.final.values) != marked["values"]
    assert res.final.cost < res.start.cost
    assert all(it.values.tolist() != marked["values"] for it in res.history)


def test_design_gradients_are_the_sensitivities_checked_by_converged_gaits(compass_gait) -> None:  # type: ignore[no-untyped-def]
    """The design's fixed-point derivatives and its step length / period / loss derivatives are
    :func:`gait_sensitivity`'s (one implicit-function solve, which the design calls; their
    numbers against central differences of converged gaits: the test above), and its spectral
    radius's derivative (the largest multiplier's modulus derivative) is the central
    difference of the spectral radii of *re-converged* gaits (Newton at p +- h, each gait's
    multipliers from the exact Jacobian at its root): an independent route, to 1e-6."""
    from heelstrike.analysis.sensitivity import gait_sensitivity
    from heelstrike.dynamics.phased import PhasedWalker

    w, g, s = compass_gait
    ref = gait_sensitivity(PhasedWalker.from_built(w), g.fixed_point, list(s.parameters),
                           slope=SLOPE, rtol=1e-11, atol=1e-11, multipliers=False)
    assert all(ref.exact)
    assert np.all(np.isnan(ref.multiplier_derivatives))  # not asked for
    assert np.allclose(s.fixed_point_derivative, ref.fixed_point, rtol=1e-12, atol=0.0)
    for field in ("step_length", "period", "speed", "collision_loss", "eta"):
        scale = float(np.max(np.abs(ref.quantities[field])))  # d eta/dR is 0: noise at 1e-10
        assert np.allclose(s.derivatives[field], ref.quantities[field], rtol=1e-9,
                           atol=1e-11 * scale)
    z0 = g.fixed_point
    rho = gait_gradients(w, z0, ["R", "slope", "m"], slope=SLOPE, lift=False)
    assert rho.fields["spectral_radius"] == pytest.approx(g.spectral_radius, rel=1e-12)

    def radius(values: dict[str, float]) -> float:
        params = {k: v for k, v in values.items() if k != "slope"}
        again = find_model_gait(w.replace(**params) if params else w,
                                slope=values.get("slope", SLOPE), backend="scipy", guess=z0,
                                tol=1e-13)
        assert again.newton_jacobian == "exact"
        return again.spectral_radius

    for j, name in enumerate(rho.parameters):
        v0 = float(rho.values[j])
        h = {"R": 1e-4, "slope": 5e-6, "m": 1e-3}[name]
        fd = (radius({name: v0 + h}) - radius({name: v0 - h})) / (2 * h)
        assert abs(rho.derivatives["spectral_radius"][j] - fd) <= 1e-6 * abs(fd), (name, fd)


@pytest.mark.slow
def test_kneed_gradients_with_the_knee_strikes_loss_agree_with_converged_gaits() -> None:
    """A step with a knee strike: the collision loss sums both impacts (the knee strike's share
    by the chain rule on gait_sensitivity's ``dz*/dp``), checked with the lift velocity and the
    spectral radius against central differences of re-converged gaits, to 1e-6."""
    w = load_walker("kneed")
    slope = 0.0504
    g = find_model_gait(w, slope=slope, backend="scipy", guess=[-0.2647694, 1.2181144,
                                                                -1.0955048])
    z0 = g.fixed_point
    assert len(g.impacts) == 2  # the knee strike, then the heel strike
    s = gait_gradients(w, z0, ["mH"], slope=slope)

    def fields(mH: float) -> np.ndarray:
        again = find_model_gait(w.replace(mH=mH), slope=slope, backend="scipy", guess=z0,
                                tol=1e-13)
        return np.array([again.collision_loss, again.impacts[-1].trailing_normal_velocity,
                         again.spectral_radius])

    mH, h = float(w.parameters["mH"]), 1e-4
    fd = (fields(mH + h) - fields(mH - h)) / (2 * h)
    ift = [s.derivatives[f][0] for f in ("collision_loss", "lift_velocity", "spectral_radius")]
    np.testing.assert_allclose(ift, fd, rtol=1e-6)
    assert s.fields["collision_loss"] == pytest.approx(g.collision_loss, rel=1e-9)
