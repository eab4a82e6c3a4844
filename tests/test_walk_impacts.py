"""Every impact of a walk in ``impacts.csv`` (knee strikes too), marked in ``energy.png``; the
strobe of a described walker; the animation's progress on stderr (``heelstrike walk``).

Physics checks: the impact table's rows chain (the total after one impact is the total before
the next: the walk is conservative between impacts), each row's drop is the ``T_c`` its impact
destroys, and the drops account for all the energy the walk loses. The strobe's links are rigid
and joined, its stance foot rolls on the slope and its swing foot lands at the last frame.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from heelstrike.analysis.limit_cycle import PoincareMap, find_limit_cycle
from heelstrike.analysis.model_gaits import find_model_gait
from heelstrike.analysis.walk_tables import (
    model_strobe_table,
    walk_energy_table,
    walk_impact_table,
)
from heelstrike.cli import main
from heelstrike.core import impact
from heelstrike.dynamics import simulate
from heelstrike.dynamics.phased import PhasedWalker, load_phased_walker
from heelstrike.models.compass import CompassGait
from heelstrike.plots.gait import energy_figure, model_strobe_figure

SLOPE = math.radians(3.0)
COLUMNS = ["step", "kind", "time_s", "impact_angle_rad", "total_before_J", "total_after_J",
           "drop_J", "T_c_J"]


@pytest.fixture(scope="module")
def kneed() -> PhasedWalker:
    return load_phased_walker("kneed")


@pytest.fixture(scope="module")
def kneed_start(kneed: PhasedWalker) -> tuple[np.ndarray, np.ndarray]:
    """A post-impact state near (not on) the kneed walker's gait."""
    z = np.asarray(find_model_gait(kneed, slope=SLOPE).fixed_point)
    q, qd = kneed.section_to_state(list(z + np.array([0.01, 0.05, -0.05])))
    return np.asarray(q), np.asarray(qd)


def _check_chain(imp: pd.DataFrame, energy: pd.DataFrame, final_total: float) -> None:
    """The physics every impact table satisfies."""
    assert list(imp.columns) == COLUMNS
    t = imp["time_s"].to_numpy()
    assert np.all(np.diff(t) > 0), "rows are not in time order"
    # conservative between impacts: the total after one impact is the total before the next
    np.testing.assert_allclose(imp["total_after_J"].to_numpy()[:-1],
                               imp["total_before_J"].to_numpy()[1:], rtol=1e-9, atol=1e-7)
    # an inert impact destroys its constrained kinetic energy, and only that
    np.testing.assert_allclose(imp["drop_J"], imp["total_before_J"] - imp["total_after_J"],
                               rtol=1e-12)
    np.testing.assert_allclose(imp["drop_J"], imp["T_c_J"], rtol=1e-8, atol=1e-12)
    assert (imp["T_c_J"] > 0).all()
    # the drops are the whole loss of the walk
    E = energy["total_J"].to_numpy()
    lost = E[0] - final_total
    assert imp["drop_J"].sum() == pytest.approx(lost, rel=1e-6)
    # before and after are the walk's own samples at the impact time (the energy table)
    for r in imp.itertuples(index=False):
        at = energy[np.isclose(energy["t_s"], r.time_s, rtol=0, atol=1e-12)]["total_J"]
        assert np.any(np.isclose(at, r.total_before_J, rtol=1e-14, atol=0))


@pytest.mark.parametrize("backend", ["compiled", "scipy"])
def test_kneed_table_lists_knee_strikes_between_heel_strikes(
    kneed: PhasedWalker, kneed_start: tuple[np.ndarray, np.ndarray], backend: str
) -> None:
    walk: Any = simulate(kneed, *kneed_start, backend=backend, slope=SLOPE, steps=3,
                         rtol=1e-10, atol=1e-10)
    assert walk.ok
    imp = walk_impact_table(kneed, walk)
    energy = walk_energy_table(kneed, walk)
    final = float(kneed.kinetic_energy(walk.final_q, walk.final_q_dot)
                  + kneed.potential_energy(walk.final_q, walk.slope))
    _check_chain(imp, energy, final)
    # each step: the swing knee locks, then the swing foot lands (the names the walk records)
    assert list(imp["kind"]) == [e.kind for e in walk.events] == ["knee_strike",
                                                                    "heel_strike"] * 3
    assert list(imp["step"]) == [0, 0, 1, 1, 2, 2]
    heel = imp[imp["kind"] == "heel_strike"]
    np.testing.assert_allclose(heel["time_s"], walk.impact_array("time"), rtol=0, atol=0)
    np.testing.assert_allclose(heel["impact_angle_rad"], walk.impact_array("impact_angle"))
    # the knee strike happens mid-swing, well before the heel strike of its step
    knee = imp[imp["kind"] == "knee_strike"]
    assert np.all(knee["time_s"].to_numpy() < heel["time_s"].to_numpy())
    assert np.all(knee["impact_angle_rad"].to_numpy() < heel["impact_angle_rad"].to_numpy())
    # T_c of a knee strike: the projector with the stance foot and the knee locks as the
    # constraints, applied to the walk's own pre-impact state; its drop is small but not 0
    for e, r in zip((e for e in walk.events if e.kind == "knee_strike"),
                    knee.itertuples(index=False), strict=True):
        res = impact(kneed.mass_matrix(e.q), e.rows, e.q_dot_minus)
        assert r.drop_J == pytest.approx(float(res.kinetic_energy_constrained), rel=1e-7)
        assert 1e-4 * r.total_before_J < r.drop_J < 0.2 * heel["drop_J"].max()


def test_walk_ending_at_an_impact_takes_the_final_state(kneed: PhasedWalker) -> None:
    # The trailing foot stays down at the first heel strike: no sample follows that impact
    q, qd = kneed.section_to_state([-0.4, 1.871, -2.0])
    walk: Any = simulate(kneed, q, qd, backend="compiled", slope=SLOPE, steps=3)
    assert walk.status.value == "trailing_foot_stays"
    imp = walk_impact_table(kneed, walk)
    assert list(imp["kind"]) == ["knee_strike", "heel_strike"]
    final = float(kneed.kinetic_energy(walk.final_q, walk.final_q_dot)
                  + kneed.potential_energy(walk.final_q, walk.slope))
    assert imp["total_after_J"].iloc[-1] == pytest.approx(final, rel=1e-14)
    _check_chain(imp, walk_energy_table(kneed, walk), final)


def test_compass_table_has_heel_strikes_only() -> None:
    w = CompassGait(foot_radius=0.3)
    cycle = find_limit_cycle(w, slope=SLOPE, method="compiled")
    walk = PoincareMap(walker=w, slope=SLOPE, rtol=1e-10, atol=1e-10).walk(
        np.asarray(cycle.fixed_point) + np.array([0.002, 0.0, 0.0]), 3)
    imp = walk_impact_table(w, walk)
    energy = walk_energy_table(w, walk)
    final = float(w.kinetic_energy(walk.final_q, walk.final_q_dot)
                  + w.potential_energy(walk.final_q, walk.slope))
    _check_chain(imp, energy, final)
    assert list(imp["kind"]) == ["heel_strike"] * 3
    assert list(imp["step"]) == [0, 1, 2]
    np.testing.assert_allclose(imp["T_c_J"], walk.impact_array("kinetic_energy_constrained"))


def _impact_lines(fig: Any) -> dict[str, list[Any]]:
    """The vertical impact lines of an energy figure, by legend label (every line of a kind
    drawn with the first's style)."""
    ax = fig.axes[0]
    handles, labels = ax.get_legend_handles_labels()
    return {lab: [ln for ln in ax.get_lines()
                  if ln.get_linestyle() == h.get_linestyle() and ln.get_color() == h.get_color()
                  and np.ptp(np.asarray(ln.get_xdata(), dtype=float)) == 0]
            for h, lab in zip(handles, labels, strict=True) if "strike" in lab}


def test_energy_figure_marks_knee_strikes_apart(
    kneed: PhasedWalker, kneed_start: tuple[np.ndarray, np.ndarray]
) -> None:
    walk = simulate(kneed, *kneed_start, backend="compiled", slope=SLOPE, steps=2)
    imp = walk_impact_table(kneed, walk)
    lines = _impact_lines(energy_figure(walk_energy_table(kneed, walk), imp))
    assert set(lines) == {"knee strike", "heel strike"}
    for label, kind in (("knee strike", "knee_strike"), ("heel strike", "heel_strike")):
        at = sorted(float(ln.get_xdata()[0]) for ln in lines[label])
        np.testing.assert_allclose(at, imp[imp["kind"] == kind]["time_s"], rtol=0, atol=0)
    knee, heel = lines["knee strike"][0], lines["heel strike"][0]
    assert (knee.get_linestyle(), knee.get_color()) != (heel.get_linestyle(), heel.get_color())

    # the compass gait's figure: heel strikes only, no knee-strike entry
    w = CompassGait(foot_radius=0.3)
    cw = PoincareMap(walker=w, slope=SLOPE).walk([-0.386284, 1.419327, -0.967944], 2)
    cl = _impact_lines(energy_figure(walk_energy_table(w, cw), walk_impact_table(w, cw)))
    assert set(cl) == {"heel strike"} and len(cl["heel strike"]) == 2


def test_walk_model_cli_writes_every_impact_and_shows_progress(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    import tqdm.auto

    real = tqdm.auto.tqdm

    def eager(*args: Any, **kwargs: Any) -> Any:  # show the bar at once, not after 2 s
        return real(*args, **{**kwargs, "delay": 0.0, "mininterval": 0.0})

    monkeypatch.setattr(tqdm.auto, "tqdm", eager)
    monkeypatch.setenv("HEELSTRIKE_PROGRESS", "1")  # captured stderr is no terminal
    assert main(["walk", "--model", "kneed", "--steps", "2", "--fps", "10", "--out",
                 str(tmp_path)]) == 0
    out, err = capsys.readouterr()
    # progress on stderr only: the frames of the animation counted, then the encoding
    frames = len(np.arange(0.0, pd.read_csv(tmp_path / "energy.csv")["t_s"].iloc[-1] + 0.05,
                           0.1))
    assert "rendering walk.gif" in err and f"{frames}/{frames}" in err
    assert "encoding walk.gif" in err
    assert out.splitlines() == [
        "2 steps, status: completed (all requested steps were taken)",
        *(str(tmp_path / n) for n in ("walk.gif", "strobe.png", "strobe.csv",
                                      "phase_portrait.png", "phase_portrait.csv", "step.png",
                                      "step.csv", "energy.png", "energy.csv", "impacts.csv")),
    ]
    imp = pd.read_csv(tmp_path / "impacts.csv")
    energy = pd.read_csv(tmp_path / "energy.csv")
    assert list(imp["kind"]) == ["knee_strike", "heel_strike"] * 2
    strobe = pd.read_csv(tmp_path / "strobe.csv")
    assert set(strobe["name"]) == {"stance_shank", "stance_thigh", "swing_thigh", "swing_shank",
                                   "stance_foot", "swing_foot", "hip"}
    walker = load_phased_walker("kneed")
    walk: Any = simulate(walker, *walker.section_to_state(
        list(find_model_gait(walker, slope=SLOPE).fixed_point)), backend="compiled",
        slope=SLOPE, steps=2, rtol=1e-9, atol=1e-9, max_step=0.05)
    final = float(walker.kinetic_energy(walk.final_q, walk.final_q_dot)
                  + walker.potential_energy(walk.final_q, walk.slope))
    _check_chain(imp, energy, final)


def test_walk_compass_cli_impacts_have_a_kind(tmp_path: Path) -> None:
    assert main(["walk", "--radius", "0.3", "--steps", "2", "--fps", "8",
                 "--guess=-0.386284,1.419327,-0.967944", "--out", str(tmp_path)]) == 0
    imp = pd.read_csv(tmp_path / "impacts.csv")
    energy = pd.read_csv(tmp_path / "energy.csv")
    assert list(imp["kind"]) == ["heel_strike"] * 2
    assert list(imp.columns) == COLUMNS
    np.testing.assert_allclose(imp["total_after_J"].iloc[0], imp["total_before_J"].iloc[1],
                               rtol=1e-9)
    np.testing.assert_allclose(imp["drop_J"], imp["T_c_J"], rtol=1e-8)
    assert energy["total_J"].iloc[0] == pytest.approx(imp["total_before_J"].iloc[0], rel=1e-9)


def _height(x: Any, y: Any) -> Any:
    """Height (m) of world points above the slope, along its normal."""
    return (np.asarray(y) - np.asarray(x) * np.tan(SLOPE)) * np.cos(SLOPE)


def _element(strobe: pd.DataFrame, name: str) -> pd.DataFrame:
    return strobe[strobe["name"] == name].sort_values("frame").reset_index(drop=True)


def test_model_strobe_is_the_walker_s_own_geometry(
    kneed: PhasedWalker, kneed_start: tuple[np.ndarray, np.ndarray]
) -> None:
    walk: Any = simulate(kneed, *kneed_start, backend="compiled", slope=SLOPE, steps=2,
                         rtol=1e-10, atol=1e-10)
    frames = 6
    s0 = model_strobe_table(kneed, walk, 0, frames=frames)
    s1 = model_strobe_table(kneed, walk, 1, frames=frames)
    p = kneed.parameters
    R = p["R"]
    lengths = {"stance_shank": p["a1"] + p["b1"], "swing_shank": p["a1"] + p["b1"],
               "stance_thigh": p["a2"] + p["b2"], "swing_thigh": p["a2"] + p["b2"]}
    for s in (s0, s1):
        assert len(s) == frames * (4 + 2 + 1)
        # rigid links of the walker file's lengths, joined knee to thigh to hip to thigh to knee
        for name, length in lengths.items():
            d = _element(s, name)
            np.testing.assert_allclose(np.hypot(d["x1_m"] - d["x0_m"], d["y1_m"] - d["y0_m"]),
                                       length, rtol=1e-12)
        for parent, child in (("stance_shank", "stance_thigh"), ("stance_thigh", "swing_thigh"),
                              ("swing_thigh", "swing_shank")):
            a, b = _element(s, parent), _element(s, child)
            np.testing.assert_allclose(a[["x1_m", "y1_m"]].to_numpy(),
                                       b[["x0_m", "y0_m"]].to_numpy(), atol=1e-12)
        hip = _element(s, "hip")
        np.testing.assert_allclose(hip[["x0_m", "y0_m"]].to_numpy(),
                                   _element(s, "stance_thigh")[["x1_m", "y1_m"]].to_numpy(),
                                   atol=1e-12)
        # the stance foot rolls: its centre stays R above the slope; the swing foot lands last
        st, sw = _element(s, "stance_foot"), _element(s, "swing_foot")
        np.testing.assert_allclose(_height(st["x0_m"], st["y0_m"]), R, atol=1e-9)
        h_swing = _height(sw["x0_m"], sw["y0_m"])
        assert h_swing[-1] == pytest.approx(R, abs=1e-7)
        assert (h_swing[1:-1] > R).all()  # clear of the ground in between
        # each foot's arc is centred on its shank's free end: R from the centre along the shank
        np.testing.assert_allclose(np.hypot(st["x1_m"] - st["x0_m"], st["y1_m"] - st["y0_m"]), R,
                                   rtol=1e-12)
        shank = _element(s, "stance_shank")
        np.testing.assert_allclose(st[["x1_m", "y1_m"]].to_numpy(),
                                   shank[["x0_m", "y0_m"]].to_numpy(), atol=1e-12)
        shank = _element(s, "swing_shank")
        np.testing.assert_allclose(sw[["x1_m", "y1_m"]].to_numpy(),
                                   shank[["x1_m", "y1_m"]].to_numpy(), atol=1e-12)
    # frames evenly spaced over the step, the last at its heel strike
    t = _element(s0, "hip")["t_s"].to_numpy()
    heel0 = walk.impacts[0].time
    assert t[0] == 0.0 and t[-1] == pytest.approx(heel0, abs=1e-12)
    np.testing.assert_allclose(np.diff(t), heel0 / (frames - 1), atol=0.06)
    # the legs swap roles at heel strike: the foot that landed is the next step's stance foot
    for s, stance in ((s0, 0), (s1, 1)):
        legs = s.groupby("name")["leg"].unique()
        for name in ("stance_shank", "stance_thigh", "stance_foot"):
            assert list(legs[name]) == [stance]
        for name in ("swing_shank", "swing_thigh", "swing_foot"):
            assert list(legs[name]) == [1 - stance]
        assert list(legs["hip"]) == [-1]
    landed = _element(s0, "swing_foot").iloc[-1]
    stands = _element(s1, "stance_foot").iloc[0]
    assert stands["x0_m"] == pytest.approx(landed["x0_m"], abs=1e-9)
    assert stands["y0_m"] == pytest.approx(landed["y0_m"], abs=1e-9)

    fig = model_strobe_figure(s0, slope=SLOPE)
    ax = fig.axes[0]
    links = [ln for ln in ax.get_lines() if len(ln.get_xdata()) == 2
             and ln.get_color() in ("tab:blue", "tab:red")]
    assert len(links) == frames * 4
    assert "hip path" in ax.get_legend_handles_labels()[1]


def test_model_strobe_torso_belongs_to_neither_leg() -> None:
    torso = load_phased_walker("torso")
    z = find_model_gait(torso, slope=SLOPE).fixed_point
    walk = simulate(torso, *torso.section_to_state(list(z)), backend="compiled", slope=SLOPE,
                    steps=1)
    s = model_strobe_table(torso, walk, 0, frames=3)
    legs = s.groupby("name")["leg"].unique()
    assert list(legs["torso"]) == [-1]
    assert list(legs["stance_leg"]) == [0] and list(legs["swing_leg"]) == [1]
    with pytest.raises(ValueError, match="frames must be >= 2"):
        model_strobe_table(torso, walk, 0, frames=1)


@pytest.mark.parametrize("backend", ["compiled", "scipy"])
def test_model_tables_list_each_sample_once(
    kneed: PhasedWalker, kneed_start: tuple[np.ndarray, np.ndarray], backend: str
) -> None:
    """QA sweep 11: ``energy.csv`` and ``phase_portrait.csv`` of ``walk --model kneed`` held one
    fully duplicated row per step (the swing knee's unlocking ends one integration segment and
    starts the next at the same state). Each sample is listed once; an impact's two rows (the
    same time, steps k and k + 1) are both kept."""
    from heelstrike.analysis.walk_tables import model_phase_portrait_table, walk_energy_table

    walk: Any = simulate(kneed, *kneed_start, backend=backend, slope=SLOPE, steps=2,
                         rtol=1e-10, atol=1e-10)
    raw = np.column_stack([walk.t, walk.step, walk.q, walk.q_dot])
    repeats = int(np.sum(np.all(raw[1:] == raw[:-1], axis=1)))
    for table in (walk_energy_table(kneed, walk), model_phase_portrait_table(kneed, walk)):
        assert not table.duplicated().any()
        assert len(table) == len(walk.t) - repeats
        # the heel strike's two rows: one time, two steps
        at = table[table["t_s"] == walk.impacts[0].time]
        assert list(at["step"]) == [0, 1]
    energy = walk_energy_table(kneed, walk)
    # passive walk: within a step the energy changes only by the knee strike's loss
    for k, rows in energy.groupby("step"):
        knee = sum(e.kinetic_energy_constrained for e in walk.events
                   if e.kind == "knee_strike" and e.step == k)
        assert abs(np.ptp(rows["total_J"]) - knee) < 1e-8
