"""Parameter sensitivities of a passive gait (implicit function theorem on the periodicity
condition) against central differences of converged gaits and against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from heelstrike.analysis.gaits import Gait
from heelstrike.analysis.limit_cycle import find_limit_cycle
from heelstrike.analysis.sensitivity import GAIT_QUANTITY_UNITS, gait_sensitivity
from heelstrike.models import CompassGait

SLOPE = float(np.deg2rad(3.0))
TIGHT = {"tol": 1e-12, "rtol": 1e-12, "atol": 1e-12}
NAMES = ("foot_radius", "leg_com_from_hip", "hip_mass")


@pytest.fixture(scope="module")
def gait() -> tuple[CompassGait, Gait]:
    walker = CompassGait(foot_radius=0.3)
    return walker, find_limit_cycle(walker, slope=SLOPE, **TIGHT)


@pytest.mark.parametrize("k", range(len(NAMES)))
def test_sensitivities_match_central_differences_of_converged_gaits(
    gait: tuple[CompassGait, Gait], k: int
) -> None:
    walker, cycle = gait
    sens = gait_sensitivity(walker, cycle.fixed_point, NAMES, slope=SLOPE)
    name = NAMES[k]
    p = float(walker.parameters[name])
    h = 1e-4 * max(1.0, abs(p))
    plus = find_limit_cycle(walker.replace(**{name: p + h}), slope=SLOPE,
                            guess=cycle.fixed_point, **TIGHT)
    minus = find_limit_cycle(walker.replace(**{name: p - h}), slope=SLOPE,
                             guess=cycle.fixed_point, **TIGHT)
    dz = (plus.fixed_point - minus.fixed_point) / (2 * h)
    assert np.max(np.abs(sens.fixed_point[:, k] - dz)) <= 1e-6 * np.max(np.abs(dz))
    for q in GAIT_QUANTITY_UNITS:
        ref = (getattr(plus, q) - getattr(minus, q)) / (2 * h)
        # relative to the derivative, or where it vanishes (eta's in the geometry, see below)
        # to 1 % of the quantity per parameter unit
        scale = max(abs(ref), 1e-2 * abs(getattr(cycle, q)) / max(1.0, abs(p)))
        assert abs(sens.quantities[q][k] - ref) <= 1e-6 * scale, q
        assert sens.values[q] == pytest.approx(getattr(cycle, q), rel=1e-9)


def test_eta_sensitivity_closed_form(gait: tuple[CompassGait, Gait]) -> None:
    """A passive gait's collision loss is the potential energy released,
    ``(mH + 2 m) g L sin(slope)``, so ``eta = (mH + 2 m) g sin(slope)``: its derivative is
    ``g sin(slope)`` in each mass and 0 in the geometry."""
    walker, cycle = gait
    sens = gait_sensitivity(walker, cycle.fixed_point, ("hip_mass", "leg_mass", "foot_radius",
                                                        "leg_com_from_hip"), slope=SLOPE)
    g = float(walker.gravity)
    expected = [g * np.sin(SLOPE), 2 * g * np.sin(SLOPE), 0.0, 0.0]
    assert np.allclose(sens.quantities["eta"], expected, rtol=0, atol=1e-6)


def test_unknown_parameter(gait: tuple[CompassGait, Gait]) -> None:
    walker, cycle = gait
    with pytest.raises(ValueError, match="'R' is not a parameter of CompassGait"):
        gait_sensitivity(walker, cycle.fixed_point, ["R"], slope=SLOPE)


def test_cli_sensitivity_table_and_json(capsys: pytest.CaptureFixture[str]) -> None:
    """``gait --sensitivity R,b --json``: the library's derivatives, keyed by the walker file's
    parameter names, with units."""
    import json

    from heelstrike.cli import main

    argv = ["gait", "--radius", "0.3", "--slope", "3deg", "--backend", "scipy",
            "--guess=-0.386284,1.419327,-0.967944", "--sensitivity", "R,b"]
    assert main([*argv, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    sens = d["sensitivity"]
    assert sens["parameters"] == {"R": "m", "b": "m"}
    walker = CompassGait(foot_radius=0.3)
    z = np.array([d["fixed_point"][k] for k in ("q3", "q3_dot", "q4_dot")])
    lib = gait_sensitivity(walker, z, ("foot_radius", "leg_com_from_hip"), slope=SLOPE)
    for k, n in enumerate(("R", "b")):
        row = sens["derivatives"][n]
        assert [row[s] for s in ("q3", "q3_dot", "q4_dot")] == pytest.approx(
            lib.fixed_point[:, k], rel=1e-9)
        assert row["period"] == pytest.approx(lib.quantities["period"][k], rel=1e-9)
        assert row["multipliers"] == pytest.approx(lib.modulus_derivatives[:, k], rel=1e-6)
    units = sens["units"]["derivatives"]["R"]
    assert units["q3"] == "rad/m" and units["q3_dot"] == "(rad/s)/m"
    assert units["eta"] == "(J/m)/m" and units["period"] == "s/m"
    assert units["multipliers"] == "1/m"
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "d/dR (m):" in text and "(rad/s)/m" in text
    assert main([*argv[:-1], "R,mass"]) == 2
    assert "'mass' is not a walker parameter" in capsys.readouterr().err


def test_multiplier_sensitivities_match_converged_gaits(
    gait: tuple[CompassGait, Gait]
) -> None:
    """``d|lambda_i|/dp`` by eigenvalue perturbation against central differences of the
    converged gaits' multipliers (each the eigenvalues of an exact Jacobian)."""
    walker, cycle = gait
    sens = gait_sensitivity(walker, cycle.fixed_point, NAMES, slope=SLOPE)
    assert np.allclose(sens.multipliers, cycle.multipliers, atol=1e-9)
    for k, name in enumerate(NAMES):
        p = float(walker.parameters[name])
        h = 1e-4 * max(1.0, abs(p))
        plus = find_limit_cycle(walker.replace(**{name: p + h}), slope=SLOPE,
                                guess=cycle.fixed_point, **TIGHT)
        minus = find_limit_cycle(walker.replace(**{name: p - h}), slope=SLOPE,
                                 guess=cycle.fixed_point, **TIGHT)
        ref = (np.abs(plus.multipliers) - np.abs(minus.multipliers)) / (2 * h)
        got = sens.modulus_derivatives[:, k]
        assert np.max(np.abs(got - ref)) <= 1e-6 * max(np.max(np.abs(ref)), 1e-2), name


def test_sensitivity_at_a_bound_of_the_parameter() -> None:
    """At ``R = 0`` (the point foot; ``R < 0`` is no walker) the derivatives exist one-sided:
    the multipliers' moduli move as a one-sided difference of re-converged gaits says (the
    central difference asked for ``R = -1e-5`` and ``gait --sensitivity R`` failed at its
    default foot)."""
    from heelstrike.analysis.limit_cycle import find_limit_cycle
    from heelstrike.analysis.sensitivity import gait_sensitivity
    from heelstrike.models import CompassGait

    slope = float(np.deg2rad(3.0))
    tight = {"rtol": 1e-12, "atol": 1e-12}

    def rho(R: float) -> np.ndarray:
        c = find_limit_cycle(CompassGait(foot_radius=R), slope=slope, tol=1e-12, **tight)
        return np.sort(np.abs(c.multipliers))[::-1]

    z = find_limit_cycle(CompassGait(), slope=slope, tol=1e-12, **tight).fixed_point
    s = gait_sensitivity(CompassGait(), z, ["foot_radius"], slope=slope)
    h = 1e-4
    ref = (-3.0 * rho(0.0) + 4.0 * rho(h) - rho(2 * h)) / (2 * h)
    got = np.sort(s.modulus_derivatives[:, 0])[::-1]
    assert np.all(np.isfinite(got))
    assert np.allclose(np.sort(got), np.sort(ref), rtol=1e-3, atol=1e-4 * np.max(np.abs(ref)))
