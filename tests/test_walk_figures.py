"""`heelstrike walk --out DIR`: the walk's figures and their CSVs (issue 12, item 4)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from heelstrike.analysis.limit_cycle import PoincareMap
from heelstrike.analysis.walk_tables import strobe_table, walk_energy_table, walk_impact_table
from heelstrike.cli import main
from heelstrike.models.compass import CompassGait
from heelstrike.plots.gait import model_diagram

# Post-impact state of the R = 0.3 m gait on a 3 deg slope (rounded: close to, not on, the cycle).
GUESS = "--guess=-0.386284,1.419327,-0.967944"
SLOPE = np.deg2rad(3.0)
STEMS = ("strobe", "phase_portrait", "step", "energy")


@pytest.fixture(scope="module")
def walk_dir(tmp_path_factory: pytest.TempPathFactory):
    out = tmp_path_factory.mktemp("walk") / "figures"
    status = main(["walk", "--radius", "0.3", "--slope", "3deg", "--steps", "3", "--fps", "10",
                   GUESS, "--out", str(out)])
    assert status == 0
    return out


@pytest.mark.slow  # shares a ~10 s CLI run (GIF + four figures)
def test_walk_dir_writes_every_figure_and_csv(walk_dir):
    from PIL import Image

    assert (walk_dir / "walk.gif").is_file()
    for stem in STEMS:
        png, csv = walk_dir / f"{stem}.png", walk_dir / f"{stem}.csv"
        with Image.open(png) as im:
            assert im.format == "PNG"
            w, h = im.size
            assert w >= 400 and h >= 300
            # not a blank canvas: many distinct colours were drawn
            assert len(im.convert("RGB").getcolors(maxcolors=1 << 20) or []) > 50
        assert len(pd.read_csv(csv)) >= 7
    assert len(pd.read_csv(walk_dir / "impacts.csv")) == 3


@pytest.mark.slow  # shares a ~10 s CLI run (GIF + four figures)
def test_energy_csv_constant_between_impacts_and_drops_by_tc(walk_dir):
    e = pd.read_csv(walk_dir / "energy.csv")
    imp = pd.read_csv(walk_dir / "impacts.csv")
    np.testing.assert_allclose(e["total_J"], e["kinetic_J"] + e["potential_J"], rtol=1e-12)
    for k, d in e.groupby("step"):
        total = d["total_J"].to_numpy()
        assert np.ptp(total) <= 1e-8 * np.abs(total).max(), f"energy drifts in step {k}"
    # the drop between the last sample of a step and the first of the next is T_c
    for r in imp.itertuples(index=False):
        nxt = e[e["step"] == r.step + 1]
        if len(nxt) == 0:
            continue
        before = e[e["step"] == r.step]["total_J"].iloc[-1]
        drop = before - nxt["total_J"].iloc[0]
        assert drop == pytest.approx(r.T_c_J, rel=1e-8)
        assert drop == pytest.approx(r.drop_J, rel=1e-10)
        assert e[e["step"] == r.step]["t_s"].iloc[-1] == pytest.approx(r.time_s)
    # T_c agrees with the paper's projector applied to the gait's own impact, and is lost
    w = CompassGait(foot_radius=0.3)
    walk = PoincareMap(walker=w, slope=SLOPE, rtol=1e-9, atol=1e-9).walk(
        [-0.386284, 1.419327, -0.967944], 1)
    rec = walk.impacts[0]
    from heelstrike.core import impact

    res = impact(w.mass_matrix(rec.q), w.contact_jacobian(rec.q, "left"), rec.q_dot_minus)
    assert imp["T_c_J"].iloc[0] == pytest.approx(float(res.kinetic_energy_constrained), rel=1e-6)
    assert (imp["T_c_J"] > 0).all()


@pytest.mark.slow  # shares a ~10 s CLI run (GIF + four figures)
def test_step_csv_ground_reaction_is_physical(walk_dir):
    s = pd.read_csv(walk_dir / "step.csv")
    assert (s["normal_N"] > 0).all()
    np.testing.assert_allclose(
        s["required_friction"], np.abs(s["tangential_N"]) / s["normal_N"], rtol=1e-12
    )
    # the stance leg swings forward through the vertical; the hip angle is q4 = swing - stance
    assert s["q3_rad"].iloc[0] < 0 < s["q3_rad"].iloc[-1]
    np.testing.assert_allclose(s["swing_rad"], s["q3_rad"] + s["q4_rad"], atol=1e-15)
    # heel strike ends the step at the symmetric configuration q4 = -2 q3
    assert s["q4_rad"].iloc[-1] == pytest.approx(-2.0 * s["q3_rad"].iloc[-1], abs=1e-8)
    # weight support: over a step the normal force averages roughly to the weight (20 kg * g)
    t, n = s["t_s"].to_numpy(), s["normal_N"].to_numpy()
    mean = np.sum(0.5 * (n[1:] + n[:-1]) * np.diff(t)) / (t[-1] - t[0])
    assert 0.6 * 20 * 9.81 < mean < 1.4 * 20 * 9.81


@pytest.mark.slow  # shares a ~10 s CLI run (GIF + four figures)
def test_strobe_feet_roll_on_the_slope(walk_dir):
    st = pd.read_csv(walk_dir / "strobe.csv")
    R = 0.3
    # world frame: the stance foot's arc centre stays R above the sloped ground (rolling)
    height = st["stance_foot_y_m"] - st["stance_foot_x_m"] * np.tan(SLOPE)
    np.testing.assert_allclose(height * np.cos(SLOPE), R, atol=1e-9)
    # the hip stays l - R from the stance foot's centre
    d = np.hypot(st["hip_x_m"] - st["stance_foot_x_m"], st["hip_y_m"] - st["stance_foot_y_m"])
    np.testing.assert_allclose(d, 1.0 - R, atol=1e-12)
    # the last frame is the heel strike: the swing foot's centre is R above the ground too
    last = st.iloc[-1]
    h = (last["swing_foot_y_m"] - last["swing_foot_x_m"] * np.tan(SLOPE)) * np.cos(SLOPE)
    assert h == pytest.approx(R, abs=1e-7)


@pytest.mark.slow  # shares a ~10 s CLI run (GIF + four figures)
def test_phase_portrait_is_a_limit_cycle(walk_dir):
    p = pd.read_csv(walk_dir / "phase_portrait.csv")
    first = [d.iloc[0] for _, d in p.groupby("step")]
    # every step starts (just after heel strike) from nearly the same state
    for a in first[1:]:
        assert a["q3_rad"] == pytest.approx(first[0]["q3_rad"], abs=1e-5)
        assert a["q3_dot_rad_s"] == pytest.approx(first[0]["q3_dot_rad_s"], abs=1e-5)


def test_energy_table_library_matches_walk_records():
    w = CompassGait(foot_radius=0.0)
    from heelstrike.analysis.limit_cycle import find_limit_cycle

    cycle = find_limit_cycle(w, slope=SLOPE, method="compiled")
    walk = PoincareMap(walker=w, slope=SLOPE, rtol=1e-10, atol=1e-10).walk(cycle.fixed_point, 2)
    e = walk_energy_table(w, walk)
    imp = walk_impact_table(w, walk)
    assert list(imp["step"]) == [0, 1]
    # a passive periodic gait: each heel strike destroys what the slope gave (eq. 14)
    np.testing.assert_allclose(imp["T_c_J"], cycle.collision_loss, rtol=1e-6)
    np.testing.assert_allclose(imp["drop_J"], imp["T_c_J"], rtol=1e-8)
    assert e["total_J"].iloc[0] - imp["total_after_J"].iloc[-1] == pytest.approx(
        2 * cycle.collision_loss, rel=1e-6
    )
    with pytest.raises(ValueError, match="no samples in step"):
        strobe_table(w, walk, step=7)


def test_model_diagram_labels_coordinates_and_parameters():
    fig = model_diagram(CompassGait(foot_radius=0.25))
    assert isinstance(fig, Figure)
    texts = {t.get_text() for t in fig.axes[0].texts}
    for label in ("$q_1$", "$q_2$", "$q_3$", "$q_4$", "$l$", "$a$", "$b$", "$R$", "$m_H$",
                  "$m$"):
        assert label in texts, label
    assert "R$ = 0.25 m" in fig.axes[0].get_title()


def test_walk_out_rejects_file_that_is_not_animation(tmp_path, capsys):
    f = tmp_path / "notadir"
    f.write_text("x")
    assert main(["walk", "--steps", "1", "--out", str(f)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a directory" in err[0]


def test_bifurcation_branch_pieces_meet_at_the_period_doubling() -> None:
    """The stable (solid) and unstable (dotted) pieces of the period-one branch are drawn to the
    period-doubling slope between two continuation points and meet there (no gap)."""
    import numpy as np

    from heelstrike.plots.gait import _branch_piece

    x = np.array([3.0, 4.0, 5.0, 6.0])
    y = np.array([10.0, 12.0, 16.0, 18.0])
    stable = np.array([True, True, False, False])
    xs, ys = _branch_piece(x, y, stable, True, np.array([4.4]))
    xu, yu = _branch_piece(x, y, stable, False, np.array([4.4]))
    np.testing.assert_allclose(xs[:3], [3.0, 4.0, 4.4])
    np.testing.assert_allclose(ys[:3], [10.0, 12.0, 13.6])
    assert np.isnan(xs[3])
    np.testing.assert_allclose(xu, [4.4, 5.0, 6.0])
    np.testing.assert_allclose(yu, [13.6, 16.0, 18.0])
    # without a crossing between them, the pieces meet half-way
    xm, _ = _branch_piece(x, y, stable, False, np.array([]))
    assert xm[0] == 4.5


def test_bifurcation_figure_shades_the_slopes_where_the_walker_falls():
    # QA sweep 4: above 5.2 deg the diagram was blank, with nothing saying the walker falls
    from heelstrike.analysis.limit_cycle import BifurcationDiagram
    from heelstrike.plots.gait import bifurcation_figure

    slopes = np.deg2rad([4.0, 4.5, 5.0, 5.5, 6.0])
    angles = np.tile(np.deg2rad([17.0, 18.0]), (5, 1))
    angles[3:] = np.nan  # the walker fell at 5.5 and 6 deg
    periods = np.where(np.isnan(angles), np.nan, 0.75)
    fig = bifurcation_figure(BifurcationDiagram(slopes=slopes, impact_angles=angles,
                                                periods=periods))
    ax = fig.axes[0]
    spans = sorted((round(float(p.get_x()), 6), round(float(p.get_x() + p.get_width()), 6))
                   for p in ax.patches)
    # QA sweep 10: the last band ended half a grid step past the range, at 6.25 deg
    assert spans == [(5.25, 5.75), (5.75, 6.0)]
    assert "no steady state (the simulated walk fell)" in [t.get_text()
                                                    for t in ax.get_legend().get_texts()]
    # slopes below a walker's first gait are not walked (status ""): no band says it fell there
    statuses = ("", "completed", "completed", "lost_contact", "lost_contact")
    angles[0] = np.nan
    fig = bifurcation_figure(BifurcationDiagram(slopes=slopes, impact_angles=angles,
                                                periods=periods, statuses=statuses))
    spans = sorted((round(float(p.get_x()), 6), round(float(p.get_x() + p.get_width()), 6))
                   for p in fig.axes[0].patches)
    assert spans == [(5.25, 5.75), (5.75, 6.0)]


def test_animation_frames_follow_the_walk_on_a_uniform_clock() -> None:
    """The animation's frames (``walk_frames``, ``model_walk_frames``): one per tick of the
    frame clock, each the sample at or just after its tick; the compass gait's stance foot rolls
    (its centre R above the slope) and its legs keep their length; every link of the kneed
    walker keeps its length from frame to frame."""
    from heelstrike.analysis.model_gaits import find_model_gait
    from heelstrike.analysis.walk_tables import model_walk_frames, resample_walk, walk_frames
    from heelstrike.dynamics.phased import load_phased_walker, simulate_phased

    w = CompassGait(foot_radius=0.3)
    walk = PoincareMap(walker=w, slope=SLOPE, rtol=1e-9, atol=1e-9, max_step=0.02).walk(
        [-0.386284, 1.419327, -0.967944], 2)
    fps = 12.0
    times, idx = resample_walk(walk, fps)
    np.testing.assert_allclose(np.diff(times), 1.0 / fps, rtol=1e-9)
    inside = times <= walk.t[-1]  # the last tick may pass the walk's end by half a frame
    assert np.all(walk.t[idx[inside]] >= times[inside]) and np.all(np.diff(idx) >= 0)
    assert np.all(idx[~inside] == walk.t.size - 1) and np.sum(~inside) <= 1
    # the sample at or after each tick is the first such: the one before lies before the tick
    assert np.all(walk.t[np.maximum(idx[inside] - 1, 0)] <= times[inside])
    frames = walk_frames(w, walk, fps)
    assert len(frames) == times.size
    np.testing.assert_array_equal(frames["t_s"], walk.t[idx])
    np.testing.assert_array_equal(frames["step"], walk.step[idx])
    height = (frames["stance_foot_y_m"] - frames["stance_foot_x_m"] * np.tan(SLOPE)) * np.cos(SLOPE)
    np.testing.assert_allclose(height, 0.3, atol=1e-9)
    for side in ("stance", "swing"):
        leg = np.hypot(frames["hip_x_m"] - frames[f"{side}_foot_x_m"],
                       frames["hip_y_m"] - frames[f"{side}_foot_y_m"])
        np.testing.assert_allclose(leg, 1.0 - 0.3, atol=1e-12)
    with pytest.raises(ValueError, match="fps"):
        walk_frames(w, walk, 0.0)

    kneed = load_phased_walker("kneed")
    gait = find_model_gait(kneed, slope=SLOPE)
    q, qd = kneed.section_to_state(gait.fixed_point)
    mwalk = simulate_phased(kneed, q, qd, slope=SLOPE, steps=1, max_step=0.02)
    mframes = model_walk_frames(kneed, mwalk, fps)
    _, midx = resample_walk(mwalk, fps)
    assert mframes["frame"].nunique() == midx.size
    links = mframes[mframes["element"] == "link"]
    for _, one in links.groupby("name"):
        length = np.hypot(one["x1_m"] - one["x0_m"], one["y1_m"] - one["y0_m"])
        np.testing.assert_allclose(length, length.iloc[0], rtol=1e-12)
    firsts = mframes.groupby("frame").first()
    np.testing.assert_array_equal(firsts["t_s"], mwalk.t[midx])
    np.testing.assert_array_equal(firsts["step"], mwalk.step[midx])
