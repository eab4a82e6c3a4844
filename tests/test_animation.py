"""Walk animations: blitted frames written straight to the file (content, not timing)."""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from PIL import Image, ImageChops

from heelstrike.plots import gait as plots_gait
from heelstrike.plots.gait import animate_walk


def _frames(n: int) -> pd.DataFrame:
    """A compass walk's frames: the hip moves forward and the swing leg swings (m, rad)."""
    t = np.arange(n) / 10.0
    hip_x = 0.1 * np.arange(n)
    swing = np.linspace(-0.3, 0.3, n)
    return pd.DataFrame({
        "t_s": t, "step": np.zeros(n, dtype=int), "stance_leg": np.zeros(n, dtype=int),
        "hip_x_m": hip_x, "hip_y_m": np.full(n, 0.95),
        "stance_foot_x_m": np.zeros(n), "stance_foot_y_m": np.zeros(n), "stance_rad": -hip_x,
        "swing_foot_x_m": hip_x + np.sin(swing), "swing_foot_y_m": 0.95 - np.cos(swing),
        "swing_rad": swing,
    })


def test_gif_has_one_frame_per_row_and_the_frames_differ(tmp_path: Path) -> None:
    out = animate_walk(_frames(7), tmp_path / "walk.gif", foot_radius=0.2, slope=0.05,
                       title="test", fps=10.0)
    with Image.open(out) as im:
        assert im.n_frames == 7
        assert im.info["duration"] == 100  # ms a frame at 10 frames/s
        pictures = []
        for k in range(im.n_frames):
            im.seek(k)
            pictures.append(im.convert("RGB"))
    for a, b in itertools.pairwise(pictures):
        assert ImageChops.difference(a, b).getbbox() is not None  # the walker moved
    first = np.asarray(pictures[0])
    # the legs are drawn in their colours (tab:blue and tab:red) over the static scene
    blue = np.all(np.abs(first.astype(int) - (31, 119, 180)) < 30, axis=-1)
    red = np.all(np.abs(first.astype(int) - (214, 39, 40)) < 30, axis=-1)
    assert blue.sum() > 50 and red.sum() > 50
    # the background (axes, ground) is the same in every frame: the top-left corner
    assert all(np.array_equal(np.asarray(p)[:5, :5], first[:5, :5]) for p in pictures)


def test_blitted_frame_equals_a_full_draw(tmp_path: Path) -> None:
    # blitting must not lose or leave anything: frame k equals a figure drawn whole at frame k
    captured: dict[str, object] = {}

    def grab(fig, draw, n, fps, out, progress=False):  # type: ignore[no-untyped-def]
        captured.update(fig=fig, draw=draw, n=n)
        return out

    real = plots_gait._save_animation
    plots_gait._save_animation = grab
    try:
        animate_walk(_frames(5), tmp_path / "w.gif", foot_radius=0.2, slope=0.05, fps=10.0)
    finally:
        plots_gait._save_animation = real
    fig, draw = captured["fig"], captured["draw"]
    blitted = list(plots_gait._frames_rgb(fig, draw, 5))  # type: ignore[arg-type]
    for a in draw(3):  # type: ignore[operator]
        a.set_animated(False)
    fig.canvas.draw()  # type: ignore[attr-defined]
    whole = np.asarray(fig.canvas.buffer_rgba())[..., :3]  # type: ignore[attr-defined]
    assert np.mean(np.any(blitted[3] != whole, axis=-1)) < 1e-3
    assert not np.array_equal(blitted[3], blitted[4])


def test_mp4_without_ffmpeg_names_ffmpeg(tmp_path: Path,
                                         monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(plots_gait.shutil, "which", lambda name: None)
    with pytest.raises(ValueError, match="ffmpeg"):
        animate_walk(_frames(3), tmp_path / "walk.mp4", foot_radius=0.2, slope=0.05)
    assert not (tmp_path / "walk.mp4").exists()


@pytest.mark.skipif(plots_gait.shutil.which("ffmpeg") is None
                    or plots_gait.shutil.which("ffprobe") is None,
                    reason="MP4 needs ffmpeg (and ffprobe to read it back)")
def test_mp4_has_one_frame_per_row(tmp_path: Path) -> None:
    import subprocess

    out = animate_walk(_frames(7), tmp_path / "walk.mp4", foot_radius=0.2, slope=0.05, fps=10.0)
    probe = subprocess.run(
        ["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
         "stream=nb_read_frames,codec_name,r_frame_rate", "-of", "csv=p=0", str(out)],
        capture_output=True, text=True, check=True).stdout.strip()
    assert probe.split(",") == ["h264", "10/1", "7"]
