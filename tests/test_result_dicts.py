"""Every public result offers ``to_dict()`` (issue 9, item 5): JSON-ready plain Python."""

from __future__ import annotations

import dataclasses
import enum
import importlib
import json
import math
from typing import Any

import numpy as np
import pytest

from heelstrike._results import ResultDictMixin, to_plain
from heelstrike.dynamics.hybrid import WalkStatus
from heelstrike.models import CompassGait, load_walker

SLOPE3 = np.deg2rad(3.0)
Z3 = np.array([-0.27102868, 1.09238359, -0.71500964])  # passive gait, R = 0, 3 deg
KNEED_SLOPE = 0.0504
KNEED_GAIT = [-0.2647694, 1.2181144, -1.0955048]

#: Every public result dataclass of the package, by module.
RESULTS: dict[str, tuple[str, ...]] = {
    "heelstrike.core.impact": ("ImpactResult",),
    "heelstrike.core.complementarity": ("MultiContactImpact",),
    "heelstrike.core.contact_laws": ("ContactImpact", "InertImpactBatch"),
    "heelstrike.dynamics.hybrid": ("ImpactRecord", "WalkResult", "GroundReaction", "Segment"),
    "heelstrike.dynamics.phased": ("PhasedImpact", "PhasedWalkResult"),
    "heelstrike.dynamics.compiled": ("EnsembleResult",),
    "heelstrike.dynamics.compiled_phased": ("PhasedEnsembleResult",),
    "heelstrike.analysis.heel_strike": ("HeelStrikeStudy",),
    "heelstrike.analysis.powered": ("PoweredStep",),
    "heelstrike.analysis.gaits": ("Actuation", "Gait", "StepBook"),
    "heelstrike.analysis.limit_cycle": ("Continuation", "BifurcationDiagram"),
    "heelstrike.analysis.model_gaits": ("ModelHeelStrike", "ImpactMap"),
    "heelstrike.analysis.paper": ("Figure3bData", "PaperFigureData"),
    "heelstrike.analysis.gait_map": ("NewtonGait", "GaitMap"),
    "heelstrike.analysis.basin": ("Basin",),
    "heelstrike.robots.study": ("RobotStudy",),
    "heelstrike.robots.contacts": ("RobotImpact",),
}
RESULT_NAMES = [f"{m}.{c}" for m, cs in RESULTS.items() for c in cs]


def _cls(qualified: str) -> type:
    module, name = qualified.rsplit(".", 1)
    if module.startswith("heelstrike.robots"):
        pytest.importorskip("pinocchio")
    return getattr(importlib.import_module(module), name)


@pytest.mark.parametrize("qualified", RESULT_NAMES)
def test_every_public_result_is_a_frozen_dataclass_with_to_dict(qualified: str) -> None:
    cls = _cls(qualified)
    assert dataclasses.is_dataclass(cls)
    assert cls.__dataclass_params__.frozen  # type: ignore[attr-defined]
    assert issubclass(cls, ResultDictMixin)
    assert callable(cls.to_dict)


def _json_round_trip(result: Any) -> dict[str, Any]:
    d = result.to_dict()
    assert isinstance(d, dict) and d
    text = json.dumps(d)
    return json.loads(text)


def _assert_plain(value: Any, path: str = "") -> None:
    """Only dict/list/str/int/float/bool/None below ``value`` (no numpy, no enums)."""
    if isinstance(value, dict):
        for k, v in value.items():
            assert isinstance(k, str), path
            _assert_plain(v, f"{path}.{k}")
    elif isinstance(value, list):
        for i, v in enumerate(value):
            _assert_plain(v, f"{path}[{i}]")
    else:
        assert value is None or type(value) in (str, int, float, bool), (path, type(value))


# -- real small results -----------------------------------------------------------------------
def test_impact_result() -> None:
    from heelstrike.core import impact

    M = np.diag([2.0, 1.0])
    r = impact(M, [[1.0, 0.0]], [1.0, 1.0])
    _assert_plain(r.to_dict())
    d = _json_round_trip(r)
    assert d["velocity_post"] == pytest.approx([0.0, 1.0], abs=1e-15)
    assert np.array(d["constrained_projector"]).shape == (2, 2)
    assert d["kinetic_energy_constrained"] == pytest.approx(1.0)  # 1/2 * 2 * 1^2


def test_heel_strike_study_batch() -> None:
    from heelstrike.analysis.heel_strike import heel_strike_study

    s = heel_strike_study(CompassGait(foot_radius=0.25), np.deg2rad([10.0, 20.0]))
    d = _json_round_trip(s)
    assert d["eta"] == pytest.approx(np.asarray(s.eta).tolist())
    assert d["impact"]["energy_lost"] == pytest.approx(np.asarray(s.impact.energy_lost).tolist())
    assert all(isinstance(b, bool) for b in d["trailing_foot_lifts"])


def test_walk_result_with_records_and_ground_reaction() -> None:
    from heelstrike.dynamics.hybrid import ground_reaction, simulate

    w = CompassGait()
    q, qd = w.section_to_state(Z3)
    walk = simulate(w, q, qd, slope=SLOPE3, steps=2)
    plain = walk.to_dict()
    _assert_plain(plain)
    d = _json_round_trip(walk)
    assert d["status"] == WalkStatus.COMPLETED.value == walk.status.value
    assert len(d["impacts"]) == len(walk.impacts) == 2
    assert d["impacts"][1]["step_length"] == pytest.approx(walk.impacts[1].step_length)
    assert np.array(d["q"]).shape == walk.q.shape
    gr = ground_reaction(w, walk)
    g = _json_round_trip(gr)
    assert np.array(g["normal"]).shape == gr.normal.shape
    assert np.all(np.array(g["normal"]) > 0)  # the stance foot is pressed on the ground


def test_limit_cycle_keeps_its_summary() -> None:
    from heelstrike.analysis.limit_cycle import find_limit_cycle

    lc = find_limit_cycle(CompassGait(), slope=SLOPE3, guess=Z3, method="compiled")
    d = _json_round_trip(lc)
    assert d == json.loads(json.dumps(lc.to_dict()))
    assert d["fixed_point"]["q3"] == pytest.approx(Z3[0], abs=1e-6)
    assert d["stable"] is True


def test_ensemble_result() -> None:
    from heelstrike.dynamics.compiled import ensemble_walk

    e = ensemble_walk(CompassGait(), np.stack([Z3, [-0.5, 0.3, 0.0]]), SLOPE3, steps=3)
    d = _json_round_trip(e)
    assert d["status"] == e.status.tolist() and all(isinstance(s, int) for s in d["status"])
    assert np.array(d["z"]).shape == e.z.shape


def test_basin_and_gait_map_datasets() -> None:
    from heelstrike.analysis.basin import basin_of_attraction
    from heelstrike.analysis.gait_map import gait_map

    b = basin_of_attraction(CompassGait(), SLOPE3, grid=(5, 4),
                            ranges=((-0.5, -0.05), (0.3, 2.3)), steps=10, fixed_point=Z3)
    d = _json_round_trip(b)
    outcome = d["dataset"]["data_vars"]["outcome"]
    assert np.array(outcome["data"]).shape == (5, 4)
    assert d["converging_fraction"] == pytest.approx(b.converging_fraction)
    gm = gait_map(CompassGait(), [0.0, 0.3], np.deg2rad([2.9, 3.0]))
    g = _json_round_trip(gm)
    assert set(gm.dataset.data_vars) <= set(g["dataset"]["data_vars"])


def test_powered_step_and_gait() -> None:
    from heelstrike.analysis.powered import powered_step
    from heelstrike.dynamics.actuation import PushOff

    st = powered_step(CompassGait(foot_radius=0.3), [-0.2, 1.0, -0.5], None, PushOff(impulse=1.0))
    d = _json_round_trip(st)
    assert d["walk"]["status"] == st.walk.status.value
    assert d["energy_start"] == pytest.approx(st.energy_start)


def test_phased_walk_and_model_results() -> None:
    from heelstrike.analysis.model_gaits import (
        impact_map,
        model_heel_strike,
        symmetric_heel_strike_state,
    )
    from heelstrike.dynamics.phased import PhasedWalker, simulate_phased

    w = PhasedWalker.from_built(load_walker("kneed"))
    q, qd = w.section_to_state(KNEED_GAIT)
    walk = simulate_phased(w, q, qd, slope=KNEED_SLOPE, steps=1)
    d = _json_round_trip(walk)
    assert [e["kind"] for e in d["events"]] == [str(e.kind) for e in walk.events]
    assert d["phase"] == walk.phase.tolist()
    _json_round_trip(walk.events[0])
    kneed = load_walker("kneed")
    hs = model_heel_strike(kneed, *symmetric_heel_strike_state(kneed, 0.3))
    assert _json_round_trip(hs)["T_c"] == pytest.approx(hs.T_c)
    m = impact_map(kneed, ("R", [0.0, 0.1]), ("angle", [0.2, 0.3]))
    assert np.array(_json_round_trip(m)["T_c"]).shape == m.T_c.shape


def test_paper_data_newton_gait_and_phased_ensemble() -> None:
    from heelstrike.analysis.gait_map import newton_gait
    from heelstrike.analysis.limit_cycle import BifurcationDiagram, Continuation
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.analysis.paper import figure3b_data, paper_figure_data
    from heelstrike.dynamics.compiled_phased import ensemble_walk_phased
    from heelstrike.dynamics.phased import PhasedWalker

    f3 = figure3b_data(radii=[0.0, 0.5], impact_angles=[0.1, 0.2])
    assert np.array(_json_round_trip(f3)["eta"]).shape == f3.eta.shape
    paper = paper_figure_data()
    d = _json_round_trip(paper)
    assert set(d["figure2"]) == {str(c) for c in paper.figure2.columns}  # pandas: columns
    assert len(next(iter(d["figure2"].values()))) == len(paper.figure2)
    g = newton_gait(CompassGait(), SLOPE3, Z3)
    dg = _json_round_trip(g)
    assert dg["z"] == pytest.approx(Z3, abs=1e-6)
    assert len(dg["multipliers"]) == 3 and set(dg["multipliers"][0]) == {"real", "imag"}
    kneed = PhasedWalker.from_built(load_walker("kneed"))
    e = ensemble_walk_phased(kneed, np.array([KNEED_GAIT]), slope=KNEED_SLOPE, steps=1)
    de = _json_round_trip(e)
    assert de["section_names"] == list(kneed.section_names) and de["status"] == e.status.tolist()
    mg = find_model_gait(kneed, slope=KNEED_SLOPE, guess=KNEED_GAIT)
    assert len(_json_round_trip(mg)["impacts"]) == len(mg.impacts) >= 2  # knee + heel strike
    # containers of other results: the cycles nest as their own summaries
    from heelstrike.analysis.limit_cycle import find_limit_cycle

    lc = find_limit_cycle(CompassGait(), slope=SLOPE3, guess=Z3, method="compiled")
    c = Continuation(parameter="slope", values=np.array([SLOPE3]), cycles=(lc,),
                     period_doubling=np.array([]), stopped=None)
    dc = _json_round_trip(c)
    assert dc["cycles"] == [json.loads(json.dumps(lc.to_dict()))] and dc["stopped"] is None
    bd = BifurcationDiagram(slopes=np.array([0.05]), impact_angles=np.array([[0.2, np.nan]]),
                            periods=np.array([1]))
    assert json.loads(json.dumps(bd.to_dict()))["impact_angles"][0][0] == 0.2


def test_multi_contact_impact() -> None:
    from heelstrike.core.complementarity import CandidateContact, resolve_impact
    from heelstrike.models.compass import heel_strike_state

    cg = CompassGait(foot_radius=0.2)
    q, qd = heel_strike_state(cg, 0.3)
    r = resolve_impact(cg.mass_matrix(q), qd, cg.contact_jacobian(q, "left"),
                       [CandidateContact.from_jacobian(cg.contact_jacobian(q, "right"), "x")])
    d = _json_round_trip(r)
    assert d["modes"] == list(r.modes)
    assert d["impact"]["velocity_post"] == pytest.approx(r.impact.velocity_post.tolist())


@pytest.mark.robots
def test_robot_results() -> None:
    pytest.importorskip("pinocchio")
    from heelstrike.robots.contacts import ContactSpec, robot_impact
    from heelstrike.robots.loading import load_robot
    from heelstrike.robots.study import robot_heel_strike_study

    bolt = load_robot("bolt")
    q = np.array(bolt.reference_q)
    v = np.random.default_rng(0).standard_normal(bolt.nv)
    feet = [ContactSpec(frame=f, kind=bolt.foot_contact) for f in bolt.feet]  # type: ignore[arg-type]
    r = robot_impact(bolt, q, v, strike=[], keep=feet)
    assert _json_round_trip(r)["T_c"] == pytest.approx(r.result.T_c)
    assert _json_round_trip(r.result)["T_c"] == pytest.approx(r.result.T_c)
    s = robot_heel_strike_study(bolt, [0.1], [0.2, 0.3])
    assert np.array(_json_round_trip(s)["T_c"]).shape == s.T_c.shape


# -- the conversion rules ---------------------------------------------------------------------
class _Colour(enum.Enum):
    RED = "red"


@dataclasses.dataclass(frozen=True, kw_only=True)
class _Demo(ResultDictMixin):
    a: Any
    b: Any = None
    _hidden: int = 0


def test_conversion_rules() -> None:
    inner = _Demo(a=np.float32(1.5))
    d = _Demo(
        a={
            "arr": np.arange(6, dtype=np.int64).reshape(2, 3),
            "nan": np.nan,
            "np_nan": np.float64("nan"),
            "z": np.array([1 + 2j]),
            "enum": _Colour.RED,
            "status": WalkStatus.COMPLETED,
            "bools": np.array([True, False]),
            "tuple": (np.int32(3), "x"),
            "inner": inner,
            1: None,
        },
    ).to_dict()
    assert set(d) == {"a", "b"}  # private fields left out
    a = d["a"]
    _assert_plain(d)
    assert a["arr"] == [[0, 1, 2], [3, 4, 5]]
    assert math.isnan(a["nan"]) and math.isnan(a["np_nan"]) and type(a["np_nan"]) is float
    assert a["z"] == [{"real": 1.0, "imag": 2.0}]
    assert a["enum"] == "red" and a["status"] == WalkStatus.COMPLETED.value
    assert a["bools"] == [True, False] and a["tuple"] == [3, "x"]
    assert a["inner"] == {"a": 1.5, "b": None}
    assert a["1"] is None and d["b"] is None
    # NaN is kept: json writes it as NaN, and strict JSON refuses it
    assert "NaN" in json.dumps(d)
    with pytest.raises(ValueError):
        json.dumps(d, allow_nan=False)


def test_unconvertible_objects_are_refused() -> None:
    with pytest.raises(TypeError, match="BuiltWalker"):
        to_plain(load_walker("compass"))
    # a hand-written walker is a frozen dataclass of its parameters
    assert to_plain(CompassGait(foot_radius=0.2))["foot_radius"] == 0.2
    with pytest.raises(TypeError, match="function"):
        _Demo(a=lambda: 0).to_dict()


def test_compiled_paths_named_tuples_offer_to_dict_too() -> None:
    # QA sweep 6 (layout audit): the compiled paths' results are NamedTuples (numba-friendly,
    # unpackable) and had no to_dict(); their dicts are JSON-ready and carry the same numbers
    from heelstrike.core.fast import FastImpactResult
    from heelstrike.dynamics.compiled import CompiledStep, step_map_compiled
    from heelstrike.models.compass import CompassPositions, heel_strike_state
    from heelstrike.models.compass_fast import HeelStrikeImpact, heel_strike_impact

    w = CompassGait(foot_radius=0.3)
    q, qd = heel_strike_state(w, np.deg2rad(20.0))
    closed = heel_strike_impact(np.deg2rad(20.0), walker=w)
    assert isinstance(closed, FastImpactResult)  # HeelStrikeImpact is one
    step = step_map_compiled(CompassGait(), Z3, SLOPE3)
    pos = w.positions(q)
    for result, cls in ((closed, HeelStrikeImpact),
                        (step, CompiledStep), (pos, CompassPositions)):
        assert isinstance(result, cls)
        d = result.to_dict()
        assert list(d) == list(result._fields)
        json.dumps(d, allow_nan=False)
    # the same T, T_c as the reference algebra (T = T_c + T_a, eq. 10)
    d = closed.to_dict()
    assert d["kinetic_energy"] == pytest.approx(
        d["kinetic_energy_constrained"] + d["kinetic_energy_admissible"], rel=1e-12)
    from heelstrike.core.impact import impact

    ref = impact(w.mass_matrix(q), w.contact_jacobian(q, "left"), qd)
    assert float(ref.kinetic_energy_constrained) == pytest.approx(
        d["kinetic_energy_constrained"], rel=1e-12)
    assert step.to_dict()["status"] == "completed"
    assert pos.to_dict()["hip"] == pytest.approx(np.asarray(pos.hip).tolist())
