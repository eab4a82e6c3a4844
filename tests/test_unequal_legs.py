"""Walkers whose legs differ (issue #32, item 4): a walker file gives each leg its own
parameters and lists in ``[swap]`` the pairs the leg swap exchanges; its periodic gait is a
fixed point of the stride map (a step on each leg, :attr:`PlanarWalker.steps_per_period` 2)
with an energy book per step."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from heelstrike.analysis.gaits import Gait
from heelstrike.analysis.limit_cycle import PoincareMap, find_limit_cycle
from heelstrike.analysis.model_gaits import find_model_gaits
from heelstrike.dynamics.backends import simulator
from heelstrike.dynamics.hybrid import simulate
from heelstrike.dynamics.phased import PhasedWalker, load_phased_walker
from heelstrike.models.builder import load_walker
from heelstrike.models.description import ModelDescriptionError

AMPUTEE = Path(__file__).resolve().parents[1] / "examples" / "walkers" / "amputee.toml"
SLOPE = float(np.deg2rad(3.0))
EQUAL = {"m1": 5.0, "b1": 0.5}  # leg A given leg B's values: the compass walker


class _Alternating(PhasedWalker):
    """A walker that hands each step on to a *copy* of itself (a distinct object with the same
    parameter values): the stride machinery runs (two steps per period) on legs that are
    equal, so the stride must be two steps of the step map."""

    def after_swap(self) -> PhasedWalker:
        return PhasedWalker(self.description, **dict(self.parameters))


@pytest.fixture(scope="module")
def amputee_gait() -> Gait:
    return find_model_gaits(load_phased_walker(AMPUTEE), slope=SLOPE, backend="scipy")[0]


def test_swap_exchanges_the_declared_parameters() -> None:
    w = load_walker(AMPUTEE)
    assert w.description.swap == (("I1", "I2"), ("I2", "I1"), ("R1", "R2"), ("R2", "R1"),
                                  ("b1", "b2"), ("b2", "b1"), ("m1", "m2"), ("m2", "m1"))
    other = w.after_swap()
    assert other is not w and other.after_swap() is w
    assert w.steps_per_period == 2 and other.steps_per_period == 2
    assert other.parameters["m1"] == w.parameters["m2"] == 5.0
    assert other.parameters["b2"] == w.parameters["b1"] == 0.4
    # a stride walker runs on both backends (the kernel alternates the two parameter sets:
    # tests/test_stride_compiled.py)
    assert w.backends == ("scipy", "compiled") and w.compiled_kernel == "generated"
    # equal values: the swap is a symmetry again, one step per period, both backends
    same = w.replace(**EQUAL)
    assert same.after_swap() is same and same.steps_per_period == 1
    assert same.backends == ("scipy", "compiled")


def test_swap_maps_the_walker_onto_the_walker_after_it() -> None:
    """``M_P(q) = J^T M_P'(q') J`` and ``V_P(q) = V_P'(q')`` for the leg swap ``q -> q'``
    (``P'`` the swapped values); with the unswapped values instead it fails (the legs differ)."""
    w = load_walker(AMPUTEE)
    other = w.after_swap()
    rng = np.random.default_rng(3)
    q = rng.uniform(-0.6, 0.6, (5, 4))
    qd = rng.uniform(-2.0, 2.0, (5, 4))
    q2, qd2 = w.swap_legs(q, qd)
    np.testing.assert_allclose(other.kinetic_energy(q2, qd2), w.kinetic_energy(q, qd),
                               rtol=1e-12)
    np.testing.assert_allclose(other.potential_energy(q2, 0.1), w.potential_energy(q, 0.1),
                               rtol=1e-12, atol=1e-12)
    assert not np.allclose(w.kinetic_energy(q2, qd2), w.kinetic_energy(q, qd), rtol=1e-3)
    # the new stance foot is the old swing foot (and its leg B's radius after the swap)
    np.testing.assert_allclose(q2[:, :2], w.foot_centre(q, "left"), atol=1e-12)


def test_equal_legs_written_as_unequal_reproduce_the_compass_gait() -> None:
    """The amputee file with leg A given leg B's values is the compass walker: the same gait
    to 1e-8 (Newton from a perturbed start on each)."""
    w = load_phased_walker(AMPUTEE, **EQUAL)
    assert w.steps_per_period == 1
    compass = load_phased_walker("compass")
    start = np.array([-0.26, 1.08, -0.70])
    a = find_model_gaits(w, slope=SLOPE, backend="scipy", guess=start)[0]
    b = find_model_gaits(compass, slope=SLOPE, backend="scipy", guess=start)[0]
    np.testing.assert_allclose(a.fixed_point, b.fixed_point, atol=1e-8)
    np.testing.assert_allclose(np.abs(a.multipliers), np.abs(b.multipliers), atol=1e-6)


def test_stride_of_equal_legs_is_two_steps_of_the_step_map() -> None:
    """The stride map on equal legs: its fixed point is the step map's (1e-8), its period two
    steps, its Jacobian the square of the step map's (multipliers squared), and each step's
    energy book closes on its own."""
    step_walker = load_phased_walker(AMPUTEE, **EQUAL)
    stride_walker = _Alternating(step_walker.description, **dict(step_walker.parameters))
    assert stride_walker.steps_per_period == 2
    sim = simulator(step_walker, "scipy")
    start = np.array([-0.26, 1.08, -0.70])
    step = find_limit_cycle(step_walker, slope=SLOPE, guess=start, simulator=sim)
    stride = find_limit_cycle(stride_walker, slope=SLOPE, guess=start + 0.01,
                              simulator=simulator(stride_walker, "scipy"))
    np.testing.assert_allclose(stride.fixed_point, step.fixed_point, atol=1e-8)
    np.testing.assert_allclose(stride.period, 2.0 * step.period, rtol=1e-9)
    np.testing.assert_allclose(stride.step_length, 2.0 * step.step_length, rtol=1e-9)
    J1 = PoincareMap(walker=step_walker, slope=SLOPE, simulator=sim).jacobian(step.fixed_point)
    J2 = PoincareMap(walker=stride_walker, slope=SLOPE,
                     simulator=simulator(stride_walker, "scipy")).jacobian(step.fixed_point)
    np.testing.assert_allclose(J2, J1 @ J1, atol=1e-5)
    np.testing.assert_allclose(np.sort(np.abs(stride.multipliers)),
                               np.sort(np.abs(step.multipliers) ** 2), atol=1e-5)
    gait = find_model_gaits(stride_walker, slope=SLOPE, backend="scipy",
                            guess=stride.fixed_point)[0]
    assert [b.step for b in gait.steps] == [0, 1]
    for b in gait.steps:
        assert abs(b.kinetic_energy_gained) < 1e-7 * b.collision_loss
        np.testing.assert_allclose(b.collision_loss, gait.collision_loss / 2, rtol=1e-7)


def test_asymmetric_walker_has_a_stride_gait_whose_steps_differ(
        amputee_gait: Gait) -> None:
    """The shipped amputee: a stride-periodic gait whose two steps differ; the books close
    over the stride (sum of T_c = potential energy released, passive) though not per step
    (the kinetic energy one step gains the other loses); two steps from the fixed point
    return to it; and the mid-stride state is the gait of the walker after the swap."""
    g = amputee_gait
    assert len(g.steps) == 2 and g.leg_crossings == 1
    s0, s1 = g.steps
    assert g.stable  # the documented stable stride (0.74 s on leg A, 0.65 s on leg B)
    np.testing.assert_allclose([s0.duration, s1.duration], [0.74, 0.65], atol=0.005)
    assert abs(s0.step_length - s1.step_length) > 0.005
    assert abs(s0.collision_loss - s1.collision_loss) > 0.02
    total = s0.collision_loss + s1.collision_loss
    np.testing.assert_allclose(total, g.collision_loss, rtol=1e-14)
    released = s0.potential_energy_released + s1.potential_energy_released
    assert abs(total - released) < 1e-8 * total
    # per step the books do not close, and what one step gains the next loses
    assert abs(s0.kinetic_energy_gained) > 0.05
    np.testing.assert_allclose(s0.kinetic_energy_gained, -s1.kinetic_energy_gained, atol=1e-8)
    # over a stride the walker's posture repeats: the potential energy released is its weight
    # times the drop, the distance walked along the ground times sin(slope)
    w = load_phased_walker(AMPUTEE)
    mg = float(w.total_mass * w.scale.gravity)
    np.testing.assert_allclose(released, mg * np.sin(SLOPE) * (s0.step_length + s1.step_length),
                               rtol=1e-9)
    walk = simulate(w, g.q, g.q_dot, slope=SLOPE, steps=2)
    assert walk.ok and [r.step for r in walk.impacts] == [0, 1]
    z2 = w.state_to_section(walk.final_q, walk.final_q_dot)
    np.testing.assert_allclose(z2, g.fixed_point, atol=1e-8)
    np.testing.assert_allclose(g.period, s0.duration + s1.duration, rtol=1e-12)
    # each step's samples conserve the energy of the walker taking it
    for k in (0, 1):
        E = np.asarray(walk.mechanical_energy)[np.asarray(walk.step) == k]
        assert np.ptp(E) < 1e-8 * mg
    # the state after the first step is the gait of the walker after the swap
    other = w.after_swap()
    assert isinstance(other, PhasedWalker)
    mid_walk = simulate(w, g.q, g.q_dot, slope=SLOPE, steps=1)
    mid = other.state_to_section(mid_walk.final_q, mid_walk.final_q_dot)
    c = find_limit_cycle(other, slope=SLOPE, guess=mid + 0.005,
                         simulator=simulator(other, "scipy"))
    np.testing.assert_allclose(c.fixed_point, mid, atol=1e-8)
    np.testing.assert_allclose(c.period, g.period, rtol=1e-9)
    np.testing.assert_allclose(np.sort(np.abs(c.multipliers)),
                               np.sort(np.abs(g.multipliers)), rtol=1e-4)


def test_gait_json_lists_the_stride_books(amputee_gait: Gait) -> None:
    d = amputee_gait.to_dict()
    assert d["steps_per_period"] == 2
    assert [s["step"] for s in d["steps"]] == [0, 1]
    assert sorted({i["step"] for i in d["impacts"]}) == [0, 1]
    json.dumps(d)


def test_gait_json_energies_are_all_the_strides(capsys: pytest.CaptureFixture[str]) -> None:
    """Review finding: ``gait --model amputee --json`` gave the stride's ``collision_loss`` with
    the first step's ``T`` and ``T_a``. Every top-level energy is now the stride's (``"per":
    "stride"``): ``T_c`` the sum of the steps' (and of the impacts'), ``T = T_c + T_a``, each
    step's ``T``, ``T_c`` and ``T_a`` those of its heel strike, ``T`` recomputed as
    ``q_dot^T M q_dot / 2`` with the mass matrix of the walker taking that step and ``T_c`` as
    the kinetic energy the impact destroys."""
    from heelstrike.cli import main

    assert main(["gait", "--model", str(AMPUTEE), "--slope", "3deg", "--json",
                 "--guess=-0.2739,1.0878,-0.7221"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["per"] == "stride" and d["steps_per_period"] == 2
    T, Tc, Ta = (d[k] for k in ("kinetic_energy_pre", "kinetic_energy_constrained",
                                "kinetic_energy_admissible"))
    assert Tc == pytest.approx(d["collision_loss"], abs=1e-10)
    assert Tc == pytest.approx(sum(b["collision_loss"] for b in d["steps"]), abs=1e-10)
    assert Tc == pytest.approx(sum(i["T_c"] for i in d["impacts"]), abs=1e-10)
    assert T == pytest.approx(Tc + Ta, abs=1e-10)
    assert T == pytest.approx(sum(b["kinetic_energy_pre"] for b in d["steps"]), abs=1e-10)
    assert Ta == pytest.approx(sum(b["kinetic_energy_admissible"] for b in d["steps"]),
                               abs=1e-10)
    # each step's book against its heel strike, recomputed from the walk of the stride
    w = load_phased_walker(AMPUTEE)
    q, qd = w.section_to_state(list(d["fixed_point"].values()))
    walk = simulate(w, q, qd, slope=SLOPE, steps=2)
    walkers = (w, w.after_swap())
    for b, rec, wk in zip(d["steps"], walk.impacts, walkers, strict=True):
        M = wk.mass_matrix(rec.q)
        T_pre = 0.5 * rec.q_dot_minus @ M @ rec.q_dot_minus
        T_post = 0.5 * rec.q_dot_plus @ M @ rec.q_dot_plus
        assert b["kinetic_energy_pre"] == pytest.approx(T_pre, rel=1e-7)
        assert b["collision_loss"] == pytest.approx(T_pre - T_post, rel=1e-6)
        assert b["kinetic_energy_pre"] == pytest.approx(
            b["collision_loss"] + b["kinetic_energy_admissible"], abs=1e-10)
        assert b["impact_angle"] == pytest.approx(rec.impact_angle, abs=1e-7)
    # the steps differ, so a step's T is not the stride's (it was, for step 0)
    assert abs(T - d["steps"][0]["kinetic_energy_pre"]) > 1.0


def test_gait_json_of_equal_legs_is_per_step() -> None:
    """A walker whose swap is a symmetry: one step per period, the top level per step and equal
    to the step's book (and to the heel strike's ``T``, ``T_c``, ``T_a``)."""
    g = find_model_gaits(load_phased_walker(AMPUTEE, **EQUAL), slope=SLOPE,
                         guess=[-0.2739, 1.0878, -0.7221], backend="scipy")[0]
    d = g.to_dict()
    (b,), (imp,) = d["steps"], d["impacts"]
    assert d["per"] == "step"
    for top, key in (("kinetic_energy_pre", "T"), ("kinetic_energy_constrained", "T_c"),
                     ("kinetic_energy_admissible", "T_a")):
        assert d[top] == pytest.approx(imp[key], abs=1e-12)
    assert b["kinetic_energy_pre"] == pytest.approx(d["kinetic_energy_pre"], abs=1e-12)
    assert d["kinetic_energy_pre"] == pytest.approx(
        d["kinetic_energy_constrained"] + d["kinetic_energy_admissible"], abs=1e-10)


def test_cli_gait_model_walks_the_stride(capsys: pytest.CaptureFixture[str]) -> None:
    """``heelstrike gait --model FILE`` on a walker whose legs differ (the scipy reference
    here; the compiled backend, the default, in tests/test_stride_compiled.py): the stride's
    books in the JSON."""
    from heelstrike.cli import main

    assert main(["gait", "--model", str(AMPUTEE), "--slope", "3deg", "--json", "--backend",
                 "scipy", "--guess=-0.2739,1.0878,-0.7221"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["steps_per_period"] == 2 and len(d["steps"]) == 2
    assert abs(d["collision_loss"] - d["potential_energy_released"]) < 1e-7


# -- refused files ------------------------------------------------------------------------------
def _amputee_text() -> str:
    return AMPUTEE.read_text()


@pytest.mark.parametrize(("change", "message"), [
    (("[swap]\nm1 = \"m2\"\nb1 = \"b2\"\nI1 = \"I2\"\nR1 = \"R2\"\n", ""),
     r"^link\[0\]\.mass: link 'stance_leg' and its mirror 'swing_leg' differ \(4 vs 5\), "
     r"so .*\[swap\] table"),
    (("b1 = \"b2\"\n", ""), r"^link\[0\]\.com: after the leg swap the centre of mass of "
     r"'stance_leg' is not where 'swing_leg''s was.*\[swap\] table must exchange"),
    (("m1 = \"m2\"\n", "m1 = \"mass\"\n"), r"^swap\.m1: must name the parameter"),
    (("m1 = \"m2\"\n", "m1 = \"m2\"\nm2 = \"b1\"\n"),
     r"^swap\.m2: 'm2' is swapped with both 'm1' and 'b1'"),
    (("m1 = \"m2\"\n", "m1 = \"m2\"\ng = \"l\"\n"), r"^swap\.g: gravity 'g' belongs to no leg"),
    (("m1 = \"m2\"\n", "m1 = \"m2\"\nmX = \"mH\"\n"), r"^swap\.mX: unknown parameter"),
    # review finding: a self-pair was accepted and the file then refused for the mirror's mass;
    # a coordinate paired with itself was an "unknown parameter"
    (("m1 = \"m2\"\n", "m1 = \"m1\"\n"),
     r"^swap\.m1: pairs 'm1' with itself, which exchanges nothing: name the other leg's "
     r"parameter whose value 'm1' takes after the leg swap"),
    (("m1 = \"m2\"\n", "m1 = \"m2\"\nhip = \"hip\"\n"),
     r"^swap\.hip: 'hip' is a coordinate, not a parameter: \[swap\] pairs parameters"),
    (("m1 = \"m2\"\n", "m1 = \"m2\"\nstance_leg = \"stance_leg\"\n"),
     r"^swap\.stance_leg: 'stance_leg' is a coordinate, not a parameter"),
    (("m1 = \"m2\"\n", "m1 = \"hip\"\n"), r"^swap\.m1: 'hip' is a coordinate, not a parameter"),
])
def test_files_whose_swap_does_not_map_the_walker_are_refused(
        change: tuple[str, str], message: str, tmp_path: Path) -> None:
    text = _amputee_text()
    assert change[0] in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(change[0], change[1], 1))
    with pytest.raises(ModelDescriptionError, match=message):
        load_walker(path)


def test_swap_without_mirrors_is_refused(tmp_path: Path) -> None:
    text = _amputee_text().replace('mirror = "swing_leg"\n', "").replace(
        'mirror = "stance_leg"\n', "")
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ModelDescriptionError, match=r"^swap: the walker declares no link "
                       "mirrors"):
        load_walker(path)


def test_walk_tables_use_the_walker_of_each_step(amputee_gait: Gait) -> None:
    """The energy tables of a walk of a walker whose legs differ: each step's samples with the
    walker taking it, so the total is constant within every step and drops by ``T_c`` at every
    heel strike (with the first walker's energies throughout, the odd steps would not be)."""
    from heelstrike.analysis.walk_tables import walk_energy_table, walk_impact_table

    w = load_phased_walker(AMPUTEE)
    g = amputee_gait
    walk = simulate(w, g.q, g.q_dot, slope=SLOPE, steps=3)
    energy = walk_energy_table(w, walk)
    scale = float(w.total_mass * w.scale.gravity * w.scale.leg_length)
    for k in range(3):
        total = energy["total_J"][energy["step"] == k]
        assert np.ptp(total) < 1e-8 * scale
    impacts = walk_impact_table(w, walk)
    assert list(impacts["step"]) == [0, 1, 2]
    np.testing.assert_allclose(impacts["drop_J"], impacts["T_c_J"], rtol=1e-7)
    # the first walker's energy on an odd step is not conserved: the test can fail
    odd = np.asarray(walk.step) == 1
    wrong = w.mechanical_energy(walk.q[odd], walk.q_dot[odd], SLOPE)
    assert np.ptp(wrong) > 1e-3 * scale


def test_the_docs_page_shows_the_example_file(tmp_path: Path) -> None:
    """docs/walker_files.rst shows examples/walkers/amputee.toml (comments aside): the same
    parameters, links, feet, point masses and swap."""
    from heelstrike.models.description import read_description

    page = (AMPUTEE.parents[2] / "docs" / "walker_files.rst").read_text(encoding="utf-8")
    start = page.index('    name = "amputee"')
    block = page[start:page.index("\nWhat is refused", start)]
    shown = tmp_path / "amputee.toml"
    shown.write_text("\n".join(line[4:] for line in block.splitlines()), encoding="utf-8")
    a, b = read_description(shown), read_description(AMPUTEE)
    assert (a.params, a.links, a.feet, a.point_masses, a.swap, a.constraints) == \
        (b.params, b.links, b.feet, b.point_masses, b.swap, b.constraints)


def test_powered_gaits_of_a_stride_walker_are_refused() -> None:
    """The powered step map is one step of one walker: for a walker whose legs differ its
    fixed point would be no gait (the next step is another walker's), so it is refused."""
    from heelstrike.analysis.powered import powered_step

    w = load_phased_walker(AMPUTEE)
    with pytest.raises(ValueError, match=r"^powered gaits of a walker whose legs differ"):
        powered_step(w, [-0.27, 1.09, -0.72], None, None)
    same = load_phased_walker(AMPUTEE, **EQUAL)
    step = powered_step(same, [-0.27, 1.09, -0.72], None, None, slope=SLOPE)
    assert np.all(np.isfinite(step.z_next))


def test_basin_of_a_stride_walker_walks_strides(amputee_gait: Gait) -> None:
    """Each point of a stride walker's basin (scipy reference) has the fate of one long walk
    from it (:func:`simulate` alternates the legs): it converged exactly where that walk ends
    within the tolerance of the stride's fixed point (a basin that kept leg A in stance every
    step found no converging point and every walk ending 0.39 from z*)."""
    from heelstrike.analysis.basin import model_basin_of_attraction
    from heelstrike.dynamics.hybrid import WalkStatus

    w = load_phased_walker(AMPUTEE)
    zstar = amputee_gait.fixed_point
    steps, tol = 30, 1e-3
    basin = model_basin_of_attraction(
        w, SLOPE, grid=(3, 3), ranges=((-0.30, -0.25), (1.0, 1.15)), steps=steps, tol=tol,
        fixed_point=zstar, backend="scipy")
    outcome = np.asarray(basin.dataset["outcome"].values)
    a, b = (np.asarray(basin.dataset[d].values) for d in basin.dataset["outcome"].dims)
    converged = 0
    for i, ai in enumerate(a):
        for j, bj in enumerate(b):
            z = zstar.copy()
            z[list(basin.axes)] = ai, bj
            q, qd = w.section_to_state(z)
            r = simulate(w, q, qd, slope=SLOPE, steps=steps)
            arrived = r.ok and r.n_steps % 2 == 0 and float(np.linalg.norm(
                w.state_to_section(r.final_q, r.final_q_dot) - zstar)) < tol
            is_converged = outcome[i, j] == WalkStatus.CONVERGED.code
            converged += is_converged
            assert is_converged == arrived or (not r.ok and not is_converged)
    assert converged >= 3
